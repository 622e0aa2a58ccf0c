//! One video frame's blur from a gyro log: its exposure MMBM (the mean
//! image-plane speed over the exposure, mm/s and px/s), its blur length in
//! pixels, and its per-pixel blur maps (displacement, path length and flow of
//! every pixel over its line's exposure).
//!
//! `cargo run --release --example frame_blur -- [LOG]` (default: the walk in
//! `tests/fixtures/gcsv/walk.gcsv`).

use mmbm::io::frames::VideoFrame;
use mmbm::prelude::*;
use mmbm::series::frames::frame_mmbm;
use mmbm::series::maps::{frame_maps, MapRays};
use mmbm::series::SeriesOptions;
use std::path::PathBuf;

fn main() -> Result<()> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/gcsv/walk.gcsv")
        });
    let log = read_log(&path, GyroOptions::default())?;
    // A small camera (the thesis optics on 160 x 120 pixels of 18.6 um) keeps
    // the maps quick; the log's rolling-shutter readout applies when it states one.
    let (camera, _) = log.apply_readout(Camera::new(4.2548, 0.0186, 160, 120))?;
    let opts = SeriesOptions {
        scene: Scene {
            camera,
            plane: None,
        },
        method: Method::default(),
        use_velocity: false,
    };
    // One frame of 20 ms exposure starting in the middle of the log.
    let (first, last) = (log[0].t, log[log.len() - 1].t);
    let frame = VideoFrame {
        t_start: 0.5 * (first + last),
        exposure_s: 0.02,
        readout_s: None, // the camera's
    };
    let (mmbm, outside) = frame_mmbm(&log, &opts, &[frame])?;
    if !outside.is_empty() {
        println!("the frame is not inside the log");
        return Ok(());
    }
    let m = mmbm[0];
    println!(
        "frame at {:.3} s, {:.0} ms exposure, {:.2} ms readout: exposure MMBM {:.4} mm/s ({:.1} px/s), blur {:.2} px",
        m.t_start,
        m.exposure_s * 1e3,
        m.readout_s * 1e3,
        m.exposure_mm_s.unwrap_or(f64::NAN),
        m.exposure_px_s.unwrap_or(f64::NAN),
        m.blur_px().unwrap_or(f64::NAN)
    );
    let rays = MapRays::new(&camera)?;
    if let Some(maps) = frame_maps(&log, &opts, &rays, 0, &frame, None)? {
        let (mean_path, _) = maps.mean_path_px();
        let longest = maps.path_px.iter().copied().fold(0.0f32, f32::max);
        println!(
            "maps: {} x {} px, {} chords per line, mean path {mean_path:.2} px, longest {longest:.2} px",
            maps.width, maps.height, maps.steps
        );
    }
    Ok(())
}
