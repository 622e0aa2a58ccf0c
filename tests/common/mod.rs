//! Helpers shared by the integration tests (`mod common;` in each binary of
//! `tests/`; `cli/tests/common` includes this file and adds the CLI runners):
//! the repository's root, and the getters of the resources a test may lack (a
//! GPU adapter, the real logs of `../shared/data`, ffmpeg).
//!
//! A missing resource is a failure under `MMBM_REQUIRE_GPU=1` /
//! `MMBM_REQUIRE_DATA=1` (as in CI). Without them the test returns early and
//! passes, and says so on stderr as `SKIPPED: <test name>: <reason>`, written
//! to the process's stderr directly: libtest captures `println!`/`eprintln!`
//! of passing tests, so a line printed with those would never be seen.

// Each test binary uses some of these helpers, not all of them.
#![allow(dead_code)]

use mmbm::gpu::GpuContext;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The repository's root (the workspace's folder, which holds `Cargo.lock`),
/// whichever crate's tests include this file (`tests/` or `cli/tests/`).
pub fn repo_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.ancestors()
        .find(|d| d.join("Cargo.lock").is_file())
        .unwrap_or(here)
        .to_path_buf()
}

/// The running test's name (libtest names each test's thread after it).
pub fn test_name() -> String {
    std::thread::current()
        .name()
        .unwrap_or("<unnamed test>")
        .to_string()
}

/// True when `VAR=1`: the resource it names is required.
fn required(var: &str) -> bool {
    std::env::var(var).is_ok_and(|v| v == "1")
}

/// Reports that the running test is skipped, past libtest's capture.
pub fn skip(reason: &str) {
    let line = format!("SKIPPED: {}: {reason}\n", test_name());
    std::io::stderr()
        .write_all(line.as_bytes())
        .expect("write the SKIPPED line to stderr");
}

/// A resource the running test lacks: a failure when `var=1`, else a skip.
fn missing(var: &str, reason: &str) {
    if required(var) {
        panic!("{}: {var}=1 but {reason}", test_name());
    }
    skip(reason);
}

/// `../shared/data/NAME/gyro.csv` when it is beside the checkout, else `None`
/// (skipped; a failure under `MMBM_REQUIRE_DATA=1`).
pub fn shared_log(name: &str) -> Option<PathBuf> {
    let p = repo_root()
        .join("../shared/data")
        .join(name)
        .join("gyro.csv");
    if p.exists() {
        return Some(p);
    }
    missing("MMBM_REQUIRE_DATA", &format!("{} is missing", p.display()));
    None
}

/// The shared GPU device when an adapter exists, else `None` (skipped, with
/// the adapter error as the reason; a failure under `MMBM_REQUIRE_GPU=1`).
pub fn gpu() -> Option<&'static GpuContext> {
    match mmbm::gpu::gpu() {
        Ok(c) => Some(c),
        Err(e) => {
            missing("MMBM_REQUIRE_GPU", &e.to_string());
            None
        }
    }
}

/// A PNG file whose header claims `w` x `h` RGB pixels (no image data).
pub fn png_header(w: u32, h: u32) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 == 1 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let mut chunk = b"IHDR".to_vec();
    chunk.extend_from_slice(&w.to_be_bytes());
    chunk.extend_from_slice(&h.to_be_bytes());
    chunk.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend_from_slice(&13u32.to_be_bytes());
    png.extend_from_slice(&chunk);
    png.extend_from_slice(&crc32(&chunk).to_be_bytes());
    // An empty data chunk: a decoder has the header once it reaches it.
    png.extend_from_slice(&0u32.to_be_bytes());
    png.extend_from_slice(b"IDAT");
    png.extend_from_slice(&crc32(b"IDAT").to_be_bytes());
    png
}

/// Every file under `dir` (relative path -> bytes).
pub fn tree(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// A gyro log of `n + 1` samples `dt` apart of one constant rotation `w`
/// (rad/s): the flow does not change in time.
pub fn steady_rotation(w: glam::DVec3, n: usize, dt: f64) -> Vec<mmbm::io::gyro::GyroSample> {
    (0..=n)
        .map(|k| mmbm::io::gyro::GyroSample {
            t: k as f64 * dt,
            omega: w,
            velocity: None,
            depth: None,
        })
        .collect()
}

/// A fisheye whose polynomial turns back at 1.2 (`theta + theta^3 - 0.8
/// theta^5`), f = 26 px on 64 x 48: the corners (about 10 % of the sensor)
/// lie beyond its radial distortion limit.
pub fn turning_fisheye() -> mmbm::Camera {
    mmbm::Camera {
        distortion: mmbm::camera::Distortion::Fisheye {
            k1: 1.0,
            k2: -0.8,
            k3: 0.0,
            k4: 0.0,
        },
        ..mmbm::Camera::new(0.26, 0.01, 64, 48)
    }
}

/// The largest and the mean `|a - b|` of two images (GPU against its twin).
pub fn abs_diff_max_mean(a: &[f32], b: &[f32]) -> (f32, f32) {
    let diffs: Vec<f32> = a.iter().zip(b).map(|(x, y)| (x - y).abs()).collect();
    let max = diffs.iter().cloned().fold(0.0, f32::max);
    (max, diffs.iter().sum::<f32>() / diffs.len() as f32)
}

/// True when `ffmpeg` and `ffprobe` run (`mmbm sync` and the clip tests need
/// them); else skipped, a failure under `MMBM_REQUIRE_FFMPEG=1` (as in CI).
pub fn ffmpeg() -> bool {
    let runs = |p: &str| {
        Command::new(p)
            .arg("-version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    if runs("ffmpeg") && runs("ffprobe") {
        return true;
    }
    missing("MMBM_REQUIRE_FFMPEG", "ffmpeg or ffprobe is not on PATH");
    false
}
