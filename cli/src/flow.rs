//! `mmbm flow`: the per-pixel flow field at sensor resolution on the GPU,
//! written as a float EXR (`flow.u`, `flow.v`, `flow.speed` in px/s), with an
//! optional quiver PNG. Pixels beyond a lens's radial distortion limit are
//! NaN in the EXR and out of the mean.

use super::args::{parse_vec3, CameraArgs, SceneArgs};
use clap::Args;
use glam::DVec3;
use mmbm::check::positive;
use mmbm::error::Result;
use mmbm::{Scene, Twist};
use std::path::PathBuf;

/// Per-pixel flow field on the GPU: EXR with flow.u, flow.v, flow.speed (px/s).
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm flow --omega 1,0,0 --out flow.exr --quiver flow.png
  mmbm flow --omega 0.5,0.5,1 --velocity 0.5,0.25,-2 --depth 0.5 --out f.exr --quiver f.png --exposure 0.05
  mmbm flow --omega 0,0,0 --velocity 0,0,1 --plane 0,-0.3,1,2 --sensor 1920x1080 --out f.exr

+u is right, +v is down (px/s). Arrows in the quiver plot are the image
displacement over the exposure, magnified by the factor printed in its title.")]
pub struct FlowArgs {
    /// Angular velocity WX,WY,WZ, rad/s (camera frame: x right, y down, z forward).
    #[arg(long, value_name = "WX,WY,WZ", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub omega: DVec3,
    /// Linear velocity VX,VY,VZ, m/s (needs --depth or --plane).
    #[arg(long, value_name = "VX,VY,VZ", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub velocity: Option<DVec3>,
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output float EXR (channels flow.u, flow.v, flow.speed in px/s).
    #[arg(long, value_name = "FILE.exr")]
    pub out: PathBuf,
    /// Also write a quiver plot (PNG).
    #[arg(long, value_name = "FILE.png")]
    pub quiver: Option<PathBuf>,
    /// Exposure for the quiver arrows, s (arrow = displacement over it).
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        default_value_t = mmbm::trigger::CameraTiming::DEFAULT_EXPOSURE_S
    )]
    pub exposure: f64,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn run(a: FlowArgs) -> Result<()> {
    positive("--exposure (s)", a.exposure)?;
    // Every output checked before any work.
    super::args::check_ext(&a.out, &["exr"], "--out")?;
    let mut outputs = vec![("--out", a.out.as_path())];
    if let Some(q) = &a.quiver {
        super::args::check_ext(q, &["png"], "--quiver")?;
        outputs.push(("--quiver", q.as_path()));
    }
    let mut guard = mmbm::io::guard::OutputGuard::new();
    for (flag, p) in outputs {
        guard = guard.output(flag, Some(p));
    }
    guard
        .input("--camera", a.camera.camera.as_deref())
        .check()?;
    let scene = Scene {
        camera: a.camera.camera()?,
        plane: a.scene.plane()?,
    };
    let tw = Twist::new(a.omega, a.velocity.unwrap_or(DVec3::ZERO));
    scene.validate_for(&tw)?;
    let f = mmbm::field::flow_field_gpu(&scene, &tw, 0, 0)?;
    let speed = f.speed();
    mmbm::io::atomic::all_or_nothing(|| {
        mmbm::io::images::write_exr(
            &a.out,
            f.width as usize,
            f.height as usize,
            &[("flow.u", &f.u), ("flow.v", &f.v), ("flow.speed", &speed)],
        )?;
        if let Some(q) = &a.quiver {
            mmbm_lab::plot::quiver::quiver_png(&scene.camera, &f.u, &f.v, a.exposure, q)?;
        }
        Ok(())
    })?;
    let desc = mmbm::gpu::gpu()
        .map(|c| c.description.clone())
        .unwrap_or_default();
    println!(
        "MMBM = {:.10} mm/s = {:.6} px/s ({}x{} pixels on {desc})",
        f.mmbm.mm_s, f.mmbm.px_s, f.width, f.height
    );
    if f.masked > 0.0 {
        println!(
            "masked: {:.4} % of the pixels (beyond the lens's radial distortion limit: NaN in \
             the field, out of the mean)",
            100.0 * f.masked
        );
    }
    println!("wrote {}", a.out.display());
    if let Some(q) = &a.quiver {
        println!("wrote {}", q.display());
    }
    Ok(())
}
