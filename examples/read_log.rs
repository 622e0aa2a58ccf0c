//! Reads a gyro log (CSV, Gyroflow `.gcsv` or ROS 2 MCAP, told apart by the
//! file) and prints its span, its rate and the MMBM of its first samples.
//!
//! `cargo run --release --example read_log -- [LOG]` (default: the walk in
//! `tests/fixtures/gcsv/walk.gcsv`).

use mmbm::prelude::*;
use mmbm::series::mmbm_series;
use std::path::PathBuf;

fn main() -> Result<()> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/gcsv/walk.gcsv")
        });
    // Units, axes and time offset default to the documented ones (rad/s, s,
    // the camera's axes); `GyroOptions` changes them.
    let log: ImuLog = read_log(&path, GyroOptions::default())?;
    let (first, last) = (log[0].t, log[log.len() - 1].t);
    let dt = log.median_interval().unwrap_or(f64::NAN);
    println!(
        "{}: {} samples over {:.3} s (median interval {:.2} ms)",
        path.display(),
        log.len(),
        last - first,
        dt * 1e3
    );
    if let Some(r) = log.readout() {
        println!("  the log states a rolling-shutter readout: {r:?}");
    }
    // The thesis camera, with the log's readout when it states one.
    let (camera, _) = log.apply_readout(Camera::thesis())?;
    let scene = Scene {
        camera,
        plane: None,
    };
    let n = log.len().min(5);
    let values = mmbm_series(&log[..n], &scene, Method::default())?;
    for (s, m) in log[..n].iter().zip(&values) {
        println!("  t = {:.4} s: MMBM {m:.4} mm/s", s.t);
    }
    Ok(())
}
