//! The synthetic clip of `cli/tests/frames/frames_choose.rs` and `cli/tests/frames/frames_video.rs`.
//!
//! The synthetic clip: a narrow camera (focal 100 mm, pitch 0.01 mm,
//! 64 x 48: half a field of view of 0.0032 rad) turning about its y axis at
//! a rate held constant over each frame's exposure (0.01 s, global shutter),
//! so every pixel moves f/pitch x w = 10^4 w px/s to a relative 1e-5, and a
//! frame's blur is 100 w px: the rate of frame k is b_k / 100 rad/s for a
//! blur of b_k px chosen by the test.

#![allow(dead_code)]

use super::common::mmbm_in;
use std::path::{Path, PathBuf};
use std::process::Output;

/// A fresh folder for the running test.
pub fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-frames-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes cam.toml, gyro.csv (1 kHz, from -0.1 s to past the last frame)
/// and frames.csv (frame k at `t0 + 0.1 k` s) for frame blurs `blur` px.
pub fn clip(d: &Path, blur: &[f64], t0: f64) {
    std::fs::write(
        d.join("cam.toml"),
        "focal_mm = 100\npitch_mm = 0.01\nwidth = 64\nheight = 48\nreadout_s = 0\n",
    )
    .unwrap();
    let n = blur.len();
    let mut g = String::from("t,wx,wy,wz\n");
    let samples = (n as f64 * 100.0) as usize + 200;
    for i in 0..=samples {
        let t = -0.1 + i as f64 * 0.001;
        let k = ((t / 0.1).round().max(0.0) as usize).min(n - 1);
        g += &format!("{t:.6},0,{},0\n", blur[k] / 100.0);
    }
    std::fs::write(d.join("gyro.csv"), g).unwrap();
    let mut f = String::from("t_start,exposure_s\n");
    for k in 0..n {
        f += &format!("{:.6},0.01\n", t0 + 0.1 * k as f64);
    }
    std::fs::write(d.join("frames.csv"), f).unwrap();
}

/// Blurs, px, of `n` frames: distinct, 1 to 10 px, no two within 0.05 px.
pub fn blurs(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 1.0 + ((k * 37 + 11) % 91) as f64 * 0.1)
        .collect()
}

pub const BASE: &[&str] = &[
    "frames",
    "--gyro",
    "gyro.csv",
    "--frames",
    "frames.csv",
    "--camera",
    "cam.toml",
];

pub fn run(d: &Path, extra: &[&str]) -> Output {
    let args: Vec<&str> = BASE.iter().chain(extra).copied().collect();
    mmbm_in(d, &args)
}

pub fn ok(d: &Path, extra: &[&str]) -> String {
    let o = run(d, extra);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{extra:?}: {err}");
    err
}

/// The rows of an image list of the default names (frame_%06d.png from 1).
pub fn listed(p: &Path) -> Vec<usize> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .map(|l| {
            let n: usize = l
                .strip_prefix("frame_")
                .and_then(|r| r.strip_suffix(".png"))
                .unwrap()
                .parse()
                .unwrap();
            n - 1
        })
        .collect()
}

/// The row of least blur in `r` (blurs are distinct).
pub fn argmin(b: &[f64], r: std::ops::Range<usize>) -> usize {
    r.min_by(|&x, &y| b[x].total_cmp(&b[y])).unwrap()
}
