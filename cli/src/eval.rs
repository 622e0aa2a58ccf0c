//! `mmbm eval`: MMBM of one twist.

use super::args::{parse_vec3, CameraArgs, SceneArgs};
use clap::Args;
use glam::DVec3;
use mmbm::camera::checked_blur_of_px_s;
use mmbm::error::Result;
use mmbm::{AnyMethod, Scene, Twist};

/// MMBM of one twist.
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm eval --omega 1,1,1
  mmbm eval --omega 1,1,1 --method exact:1e-10 --json
  mmbm eval --omega 0,0,0 --velocity 1,0,0 --depth 0.5 --method gauss:8
  mmbm eval --omega 0.2,0.1,0 --velocity 0,0,1 --plane 0,-0.3,1,2 --method gpu")]
pub struct EvalArgs {
    /// Angular velocity WX,WY,WZ, rad/s (camera frame: x right, y down, z forward).
    #[arg(long, value_name = "WX,WY,WZ", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub omega: DVec3,
    /// Linear velocity VX,VY,VZ, m/s (needs --depth or --plane).
    #[arg(long, value_name = "VX,VY,VZ", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub velocity: Option<DVec3>,
    #[command(flatten)]
    pub scene: SceneArgs,
    /// riemann[:NUxNV] (default 8x6), gauss[:N|:NUxNV], exact[:TOL] (default 1e-9), gpu[:WxH].
    /// Limits: 1,048,576 grid points, 1024 Gauss nodes per side.
    #[arg(long, default_value = "riemann:8x6")]
    pub method: AnyMethod,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also give the expected blur length over an exposure of S seconds, px
    /// (MMBM x S / pixel pitch, docs/spec.md section 3).
    #[arg(long, value_name = "S")]
    pub exposure: Option<f64>,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn run(a: EvalArgs) -> Result<()> {
    let method = a.method;
    let scene = Scene {
        camera: a.camera.camera()?,
        plane: a.scene.plane()?,
    };
    if let Some(te) = a.exposure {
        mmbm::check::positive("--exposure (s)", te)?;
    }
    let tw = Twist::new(a.omega, a.velocity.unwrap_or(DVec3::ZERO));
    let m = match method {
        AnyMethod::Gpu { width, height } => {
            scene.validate_for(&tw)?;
            mmbm::field::mmbm_gpu(&scene, &tw, width, height)?
        }
        AnyMethod::Cpu(method) => mmbm::mmbm(&scene, &tw, method)?,
    };
    // Checked before anything is printed: a blur that is not a finite
    // number is an error, not "inf" or a JSON null.
    let blur = match a.exposure {
        Some(te) => Some((te, checked_blur_of_px_s(m.px_s, te)?)),
        None => None,
    };
    // The share of the sensor beyond the lens's radial distortion limit,
    // excluded from the mean (given only where there is one).
    let masked = scene.camera.masked_fraction();
    if a.json {
        let mut o = serde_json::json!({
            "mmbm_mm_s": m.mm_s,
            "mmbm_px_s": m.px_s,
            "method": method.to_string(),
            "evaluations": m.evaluations,
        });
        if let Some(e) = m.error_estimate {
            o["error_estimate"] = serde_json::json!(e);
        }
        if masked > 0.0 {
            o["masked_fraction"] = serde_json::json!(masked);
        }
        if let Some((te, b)) = blur {
            o["exposure_s"] = serde_json::json!(te);
            o["blur_px"] = serde_json::json!(b);
        }
        println!("{o}");
    } else {
        print!("MMBM = {:.10} mm/s = {:.6} px/s  ({method}", m.mm_s, m.px_s);
        if let Some(e) = m.error_estimate {
            print!(", error estimate {e:.2e} mm/s");
        }
        println!(")");
        if masked > 0.0 {
            println!(
                "masked: {:.4} % of the sensor (beyond the lens's radial distortion limit)",
                100.0 * masked
            );
        }
        if let Some((te, b)) = blur {
            println!("blur over {te} s: {b:.4} px");
        }
    }
    Ok(())
}
