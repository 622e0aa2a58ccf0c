//! Light a user can state: from the scene's illuminance (lux), the lens's
//! f-number, the pixel pitch and the quantum efficiency to the electrons per
//! second a white pixel collects (`phi`, the light of docs/spec.md sections 9-10 and
//! of the benefit map's rows).
//!
//! `phi = E * R * tau / (4 N^2) * PHOTONS_PER_LUX_S_M2 * (p * 1e-6)^2 * QE`
//!
//! with `E` the illuminance on the scene (lux), `R` the white's reflectance,
//! `tau` the lens's transmission, `N` the f-number, `p` the pixel pitch (um)
//! and `QE` the quantum efficiency (electrons per photon, fill factor
//! included). Assumptions (docs/light.md): a Lambertian white (`R = 1`; the
//! renderer's white), a lossless lens (`tau = 1`), the image on the optical
//! axis (no `cos^4` fall-off) of a distant scene (magnification << 1: the
//! image-plane illuminance is `E R tau / (4 N^2)`), and every photon counted
//! as one at 555 nm (683 lm/W): a broadband white delivers more photons per
//! lux (about 2x for daylight), so read the result as a lower bound.

use crate::error::{Error, Result};
use crate::limits::{LIGHT_MAX_F_NUMBER, LIGHT_MAX_LUX, LIGHT_MAX_PIXEL_UM, LIGHT_MIN_F_NUMBER};

/// Photons per second per square metre in one lux at 555 nm:
/// `1 / (683 lm/W * h c / 555 nm)`, photons/(s m^2 lx).
pub const PHOTONS_PER_LUX_S_M2: f64 = 1.0 / (683.0 * 6.626_070_15e-34 * 299_792_458.0 / 555e-9);

/// A camera looking at a lit white scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneLight {
    /// Illuminance on the scene, lux.
    pub lux: f64,
    /// The lens's f-number (focal length over aperture diameter).
    pub f_number: f64,
    /// Pixel pitch, um.
    pub pixel_um: f64,
    /// Quantum efficiency, electrons per photon (0, 1].
    pub qe: f64,
}

impl SceneLight {
    /// Checks every input against its range (naming the flag), then the result
    /// against [`crate::limits::MAX_LIGHT_E_PER_S`].
    pub fn electrons_per_s(&self) -> Result<f64> {
        let range = |what: &str, x: f64, lo: f64, hi: f64, open_lo: bool| -> Result<()> {
            let ok = x.is_finite() && x <= hi && if open_lo { x > lo } else { x >= lo };
            if ok {
                Ok(())
            } else {
                let l = if open_lo { "(" } else { "[" };
                Err(Error::invalid(
                    what,
                    format!("must be in {l}{lo}, {hi}], got {x}"),
                ))
            }
        };
        range("--lux", self.lux, 0.0, LIGHT_MAX_LUX, true)?;
        range(
            "--f-number",
            self.f_number,
            LIGHT_MIN_F_NUMBER,
            LIGHT_MAX_F_NUMBER,
            false,
        )?;
        range("--pixel-um", self.pixel_um, 0.0, LIGHT_MAX_PIXEL_UM, true)?;
        range("--qe", self.qe, 0.0, 1.0, true)?;
        let image_lux = self.lux / (4.0 * self.f_number * self.f_number);
        let area_m2 = (self.pixel_um * 1e-6).powi(2);
        let phi = image_lux * PHOTONS_PER_LUX_S_M2 * area_m2 * self.qe;
        crate::limits::check_light("light (e-/s)", phi)
    }
}

/// Common scenes and their illuminance, lux (orders of magnitude; the
/// docs' table is computed from these).
pub const SCENES: [(&str, f64); 8] = [
    ("full moon, clear night", 0.25),
    ("street at night", 10.0),
    ("living room", 50.0),
    ("corridor, warehouse aisle", 100.0),
    ("office", 500.0),
    ("overcast day, outside", 2_000.0),
    ("daylight, shade", 20_000.0),
    ("direct sun", 100_000.0),
];

/// The camera of the docs' table: f/2, 4.65 um pixels (the thesis's Flea2),
/// quantum efficiency 0.5.
pub const TABLE_CAMERA: (f64, f64, f64) = (2.0, 4.65, 0.5);

/// The docs' table of [`SCENES`] for the camera `(f-number, pixel um, QE)`:
/// e-/s and electrons in the thesis's 70 ms exposure, Markdown.
pub fn scene_table_md(camera: (f64, f64, f64)) -> Result<String> {
    let (f_number, pixel_um, qe) = camera;
    let mut s = format!(
        "| scene | lux | e-/s (f/{f_number}, {pixel_um} um, QE {qe}) | e- in 70 ms |\n|---|---|---|---|\n"
    );
    for (name, lux) in SCENES {
        let phi = SceneLight {
            lux,
            f_number,
            pixel_um,
            qe,
        }
        .electrons_per_s()?;
        s += &format!(
            "| {name} | {lux} | {} | {} |\n",
            sig3(phi),
            sig3(phi * 0.07)
        );
    }
    Ok(s)
}

/// `x` to three significant figures, without exponent (e.g. 1380000, 2.76).
pub fn sig3(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = 2 - x.abs().log10().floor() as i32;
    let scale = 10f64.powi(digits);
    let r = (x * scale).round() / scale;
    if digits > 0 {
        format!("{r:.0$}", digits as usize)
    } else {
        format!("{r:.0}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_hand() {
        // 1 lx at 555 nm: a photon is h c / 555 nm = 3.5793e-19 J, a lux
        // 1/683 W/m^2: 4.0906e15 photons/(s m^2).
        assert!((PHOTONS_PER_LUX_S_M2 / 4.0906e15 - 1.0).abs() < 1e-4);
        // 500 lx at f/2 on 4.65 um, QE 0.5: 31.25 lx on the sensor x 4.0906e15
        // x 2.16225e-11 m^2 x 0.5 = 1.382e6 e-/s.
        let phi = SceneLight {
            lux: 500.0,
            f_number: 2.0,
            pixel_um: 4.65,
            qe: 0.5,
        }
        .electrons_per_s()
        .unwrap();
        let want = 31.25 * 4.0906e15 * 4.65e-6 * 4.65e-6 * 0.5;
        assert!((phi / want - 1.0).abs() < 1e-4, "{phi} vs {want}");
        assert_eq!(sig3(1_382_123.0), "1380000");
        assert_eq!(sig3(2.7649), "2.76");
        assert_eq!(sig3(0.012345), "0.0123");
    }

    #[test]
    fn bad_inputs_name_their_flag() {
        let ok = SceneLight {
            lux: 100.0,
            f_number: 2.0,
            pixel_um: 3.0,
            qe: 0.6,
        };
        for (l, flag) in [
            (SceneLight { lux: 0.0, ..ok }, "--lux"),
            (
                SceneLight {
                    lux: f64::NAN,
                    ..ok
                },
                "--lux",
            ),
            (SceneLight { lux: 1e9, ..ok }, "--lux"),
            (
                SceneLight {
                    f_number: 0.3,
                    ..ok
                },
                "--f-number",
            ),
            (
                SceneLight {
                    pixel_um: -1.0,
                    ..ok
                },
                "--pixel-um",
            ),
            (SceneLight { qe: 1.5, ..ok }, "--qe"),
        ] {
            let e = l.electrons_per_s().unwrap_err().to_string();
            assert!(e.contains(flag), "{e}");
        }
    }
}
