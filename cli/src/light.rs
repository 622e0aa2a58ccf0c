//! `mmbm light`: the light a user can state (lux, f-number, pixel pitch,
//! quantum efficiency) as the electrons per second a white pixel collects,
//! the unit of `--light`, `[camera.noise] phi_e_per_s` and the benefit map's
//! rows (docs/light.md).

use clap::Args;
use mmbm::camera::SceneLight;
use mmbm::error::{Error, Result};

/// Electrons per second in a white pixel from lux, f-number, pixel pitch and QE.
#[derive(Args, Debug)]
#[command(
    after_help = "phi = lux / (4 N^2) x 4.09e15 photons/(s m^2 lx) x (pitch)^2 x QE: a Lambertian white
scene (reflectance 1), a lossless lens, on the optical axis of a distant scene, photons counted at 555 nm
(a broadband white gives about 2x more: read it as a lower bound). docs/light.md has a table of scenes.

Examples:
  mmbm light --lux 500 --f-number 2 --pixel-um 4.65 --qe 0.5
  mmbm light --lux 10 --f-number 1.4 --pixel-um 3 --qe 0.7 --exposure 0.02"
)]
pub struct LightArgs {
    /// Illuminance on the scene, lux (> 0, at most 1e7).
    #[arg(allow_negative_numbers = true, long)]
    pub lux: f64,
    /// The lens's f-number (0.5 to 1000).
    #[arg(allow_negative_numbers = true, long)]
    pub f_number: f64,
    /// Pixel pitch, um (> 0, at most 1000).
    #[arg(allow_negative_numbers = true, long)]
    pub pixel_um: f64,
    /// Quantum efficiency, electrons per photon (0, 1], fill factor included.
    #[arg(allow_negative_numbers = true, long)]
    pub qe: f64,
    /// Also the electrons collected in this exposure, s (> 0).
    #[arg(allow_negative_numbers = true, long)]
    pub exposure: Option<f64>,
}

pub fn run(a: LightArgs) -> Result<()> {
    let phi = SceneLight {
        lux: a.lux,
        f_number: a.f_number,
        pixel_um: a.pixel_um,
        qe: a.qe,
    }
    .electrons_per_s()?;
    if let Some(t) = a.exposure {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::invalid(
                "--exposure",
                format!("must be > 0 s, got {t}"),
            ));
        }
    }
    println!("{phi:.6e} e-/s  (use as --light {phi:.0})");
    if let Some(t) = a.exposure {
        println!("{:.6e} e- in {t} s", phi * t);
    }
    Ok(())
}
