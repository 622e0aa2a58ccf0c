//! Renders one motion-blurred frame: the thesis camera pitching at 2 rad/s
//! for a 30 ms exposure in front of a checkerboard 1 m away, on the CPU
//! twin (the GPU kernel gives the same image), written as a PNG.
//!
//! `cargo run --release --example render_frame -- [OUT.png]` (default:
//! `render_frame.png` in the system's temporary folder).

use mmbm::prelude::*;
use mmbm::render::Target;
use std::path::PathBuf;

fn main() -> Result<()> {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("render_frame.png"));
    let camera = Camera::thesis(); // global shutter: the motion spans the exposure alone
    let exposure_s = 0.03;
    // The motion covers the camera's busy time: readout (0 here) + exposure.
    let span = camera.shutter.busy_s(exposure_s);
    let trajectory = Trajectory::from_twist(Twist::rotation(2.0, 0.0, 0.0), span)?;
    let target = Target::checker(0.05, 1.0); // 5 cm squares at 1 m
    let mut job = RenderJob::new(camera, exposure_s, trajectory, target);
    job.quality = Quality::Fast;
    job.backend = Backend::Cpu { threads: None };
    let frame = render_frame(&job)?;
    frame.write_image(&out)?;
    println!(
        "{}: {} x {} px, {} samples per pixel, longest path {:.1} px ({})",
        out.display(),
        frame.width,
        frame.height,
        frame.samples_per_pixel,
        frame.max_path_px,
        frame.backend_used
    );
    if let Some(maps) = &frame.maps {
        println!("blur maps: {:?}", maps.means());
    }
    Ok(())
}
