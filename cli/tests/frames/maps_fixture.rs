//! Helpers of the frame-maps tests, shared by `cli/tests/frames/frame_maps.rs`,
//! `cli/tests/frames/maps_gpu.rs` and `maps_gpu_lens.rs`: the options, the example
//! cameras, the shared logs with their frame tables, a frame's maps job and the
//! largest difference of two maps.
#![allow(dead_code)]

use glam::DVec3;
use mmbm::io::frames::{read_frames, VideoFrame};
use mmbm::io::gyro::{read_log, GyroOptions, GyroSample};
use mmbm::model::log::ImuLog;
use mmbm::series::maps::{FrameMaps, MapRays, MapsJob};
use mmbm::series::SeriesOptions;
use mmbm::{Camera, Method, Plane, Scene};
use std::path::{Path, PathBuf};

pub fn opts(camera: Camera, plane: Option<Plane>, use_velocity: bool) -> SeriesOptions {
    SeriesOptions {
        scene: Scene { camera, plane },
        method: Method::Riemann { nu: 8, nv: 6 },
        use_velocity,
    }
}

/// `examples/cameras/NAME.toml`.
pub fn example_camera(name: &str) -> Camera {
    let p = crate::common::repo_root().join(format!("examples/cameras/{name}.toml"));
    Camera::load(&p).unwrap()
}

/// The shared log `name` and its frame table, or `None` (skipped: see `common::shared_log`).
pub fn shared(name: &str) -> Option<(ImuLog, Vec<VideoFrame>)> {
    let gyro = super::common::shared_log(name)?;
    let frames = read_frames(&gyro.with_file_name("frames.csv")).unwrap();
    Some((read_log(&gyro, GyroOptions::default()).unwrap(), frames))
}

pub fn path(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// The running phone's camera file.
pub fn running_phone_camera() -> PathBuf {
    crate::common::repo_root().join("examples/cameras/running_phone.toml")
}

/// `mmbm frames --gyro GYRO --frames TABLE --camera CAMERA --scale-to
/// 192x108 --maps DIR --maps-format float --out OUT` and `extra` (float
/// maps: the tests compare them to f32 rounding; the maps of row k are
/// `frame_{k+1:06}.exr`, as the image list names the frame).
pub fn frames_maps(
    gyro: &Path,
    table: &Path,
    camera: &Path,
    dir: &Path,
    out: &Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "frames",
        "--gyro",
        path(gyro),
        "--frames",
        path(table),
        "--camera",
        path(camera),
        "--scale-to",
        "192x108",
        "--maps",
        path(dir),
        "--maps-format",
        "float",
        "--out",
        path(out),
    ];
    args.extend_from_slice(extra);
    super::common::mmbm(&args)
}

/// A synthetic log at 200 Hz for 2 s: turning rotation, forward-and-sideways
/// velocity, and `depth` on every sample.
pub fn synthetic_log(depth: Option<f64>) -> ImuLog {
    let samples: Vec<GyroSample> = (0..400)
        .map(|i| {
            let t = i as f64 * 0.005;
            GyroSample {
                t,
                omega: DVec3::new(0.8 * (9.0 * t).sin(), 0.5 * (5.0 * t).cos(), 0.3),
                velocity: Some(DVec3::new(0.6, -0.2, 1.2 * (3.0 * t).cos())),
                depth,
            }
        })
        .collect();
    ImuLog::new(samples).unwrap()
}

/// The job of frame `index` with automatic chords.
pub fn job<'a>(
    log: &'a ImuLog,
    opts: &'a SeriesOptions,
    rays: &'a MapRays,
    index: usize,
    frame: &'a VideoFrame,
) -> MapsJob<'a> {
    MapsJob {
        log,
        opts,
        rays,
        index,
        frame,
        steps: None,
    }
}

/// The largest |a - b| per channel relative to `(1 + path)` (channels 0..3)
/// and `(1 + |flow|)` (3..5), of `b`; NaN must be in the same pixels.
pub fn worst(a: &FrameMaps, b: &FrameMaps) -> (f64, f64) {
    let (ca, cb) = (a.channels(), b.channels());
    let (mut track, mut flow): (f64, f64) = (0.0, 0.0);
    for i in 0..b.path_px.len() {
        let path = b.path_px[i] as f64;
        let speed = (b.flow_u[i] as f64).hypot(b.flow_v[i] as f64);
        for c in 0..5 {
            let (x, y) = (ca[c].1[i], cb[c].1[i]);
            assert_eq!(x.is_nan(), y.is_nan(), "pixel {i} channel {c}: {x} vs {y}");
            if x.is_nan() {
                continue;
            }
            let e = (x - y).abs() as f64;
            if c < 3 {
                track = track.max(e / (1.0 + path));
            } else {
                flow = flow.max(e / (1.0 + speed));
            }
        }
    }
    (track, flow)
}
