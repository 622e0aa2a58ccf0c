//! Per-pixel blur fields of video frames (`cargo bench --bench maps`): the
//! maps of one 1920x1080 rolling-shutter frame (`series::maps::frame_maps`,
//! what `mmbm frames --maps` computes before writing each EXR), pinhole and
//! through a wide-angle lens, on one thread and on all cores, and the
//! throughput for a minute of 60 fps video; then the GPU path
//! (`series::maps::gpu`, `src/series/maps/maps.wgsl`) where an adapter exists, with
//! its largest difference per pixel from its CPU twin and from the f64
//! maps at full size. The motion is the shared
//! running log's (`../shared/data/running_phone`, its blurriest frames) when
//! present beside the checkout, else a synthetic log of similar rates.
//! Times are printed, never asserted.

mod common;

use glam::DVec3;
use mmbm::camera::{Camera, Distortion};
use mmbm::error::{Error, Result};
use mmbm::io::frames::VideoFrame;
use mmbm::io::gyro::{read_log, GyroOptions, GyroSample};
use mmbm::model::log::ImuLog;
use mmbm::series::maps::gpu::MapsRunner;
use mmbm::series::maps::kernel::frame_maps_twin;
use mmbm::series::maps::{frame_maps, FrameMaps, MapRays, MapsJob};
use mmbm::series::SeriesOptions;
use mmbm::{Method, Scene};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    common::main(run)
}

fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::invalid("bench thread pool", e.to_string()))
}

/// The running log and a few of its frames, or a synthetic log.
fn motion() -> Result<(ImuLog, Vec<VideoFrame>, &'static str)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/running_phone");
    if dir.join("gyro.csv").exists() {
        let log = read_log(&dir.join("gyro.csv"), GyroOptions::default())?;
        let frames = mmbm::io::frames::read_frames(&dir.join("frames.csv"))?;
        // Its blurriest frames (docs/cli.md) and a sharp one.
        let pick = [263, 311, 432, 433, 472, 5];
        return Ok((
            log,
            pick.iter().map(|&k| frames[k]).collect(),
            "running_phone",
        ));
    }
    let samples = (0..2000)
        .map(|i| {
            let t = i as f64 / 200.0;
            GyroSample {
                t,
                omega: DVec3::new(2.0 * (7.0 * t).sin(), 1.5 * (4.0 * t).cos(), 0.5),
                velocity: None,
                depth: None,
            }
        })
        .collect();
    let frames = (0..6)
        .map(|k| VideoFrame {
            t_start: 1.0 + k as f64,
            exposure_s: 0.0013,
            readout_s: Some(0.016),
        })
        .collect();
    Ok((ImuLog::new(samples)?, frames, "synthetic"))
}

fn run() -> Result<()> {
    let (log, frames, source) = motion()?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let base = Camera::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/cameras/running_phone.toml"),
    )?;
    println!(
        "blur fields of 1920x1080 rolling-shutter frames ({} ms readout), {source} log, {} frames; {cores} core(s)",
        base.shutter.readout_s * 1e3,
        frames.len()
    );
    println!("| lens | threads | rays (once per video) | per frame (wall) | per frame (CPU, all threads) | Mpx/s (wall) | a 60 fps minute (3600 frames, wall) |");
    println!("|---|---|---|---|---|---|---|");
    let lens = Camera {
        distortion: Distortion::WIDE_ANGLE,
        ..base
    };
    for (name, cam) in [("pinhole", base), ("wide-angle", lens)] {
        let opts = rotation_only(cam);
        for threads in [1, cores] {
            let p = pool(threads)?;
            let t0 = Instant::now();
            let rays = p.install(|| MapRays::new(&cam))?;
            let t_rays = t0.elapsed().as_secs_f64();
            // One warm-up, then every frame twice.
            p.install(|| frame_maps(&log, &opts, &rays, 0, &frames[0], None))?;
            let (per, cpu) = timed(&frames, 2, |k, f| {
                p.install(|| frame_maps(&log, &opts, &rays, k, f, None))
            })?;
            println!(
                "| {name} | {threads} | {:.3} s | {:.3} s | {cpu} | {:.1} | {:.0} s |",
                t_rays,
                per,
                1920.0 * 1080.0 / per / 1e6,
                t_rays + 3600.0 * per
            );
        }
    }
    gpu(&log, &frames, base, lens)
}

/// The GPU path on the same frames, and its agreement at full size.
fn gpu(log: &ImuLog, frames: &[VideoFrame], base: Camera, lens: Camera) -> Result<()> {
    let mut runner = match MapsRunner::new() {
        Ok(r) => r,
        Err(e) => {
            println!("GPU path: not measured ({e})");
            return Ok(());
        }
    };
    println!(
        "\nGPU path on {} (host side on rayon's pool)",
        runner.adapter()
    );
    println!("| lens | per frame (wall) | per frame (CPU, all threads) | a 60 fps minute (wall) | max GPU - twin | max GPU - f64 |");
    println!("|---|---|---|---|---|---|");
    for (name, cam) in [("pinhole", base), ("wide-angle", lens)] {
        let opts = rotation_only(cam);
        let rays = MapRays::new(&cam)?;
        let job = |index: usize, frame| MapsJob {
            log,
            opts: &opts,
            rays: &rays,
            index,
            frame,
            steps: None,
        };
        let some = |m: Option<FrameMaps>| {
            m.ok_or_else(|| Error::invalid("bench", "frame outside the log"))
        };
        // Warm-up (shader build, rays upload) and the agreement on the first frame.
        let g = some(runner.frame_maps(&job(0, &frames[0]))?)?;
        let twin = some(frame_maps_twin(&job(0, &frames[0]))?)?;
        let cpu = some(frame_maps(log, &opts, &rays, 0, &frames[0], None)?)?;
        let (per, cpu_t) = timed(frames, 1, |k, f| runner.frame_maps(&job(k, f)))?;
        println!(
            "| {name} | {per:.3} s | {cpu_t} | {:.0} s | {:.1e} px | {:.1e} px |",
            3600.0 * per,
            max_diff(&g, &twin),
            max_diff(&g, &cpu)
        );
    }
    Ok(())
}

/// Options for the maps of `cam`, rotation only (the method is not used).
fn rotation_only(cam: Camera) -> SeriesOptions {
    SeriesOptions {
        scene: Scene {
            camera: cam,
            plane: None,
        },
        method: Method::Riemann { nu: 8, nv: 6 },
        use_velocity: false,
    }
}

/// Computes every frame's maps `reps` times with `one`: wall seconds per
/// frame and the CPU time per frame (all threads), printed.
fn timed<'f>(
    frames: &'f [VideoFrame],
    reps: usize,
    mut one: impl FnMut(usize, &'f VideoFrame) -> Result<Option<FrameMaps>>,
) -> Result<(f64, String)> {
    let (t0, c0) = (Instant::now(), cpu_s());
    let mut n = 0;
    for _ in 0..reps {
        for (k, f) in frames.iter().enumerate() {
            let m = one(k, f)?;
            std::hint::black_box(
                m.ok_or_else(|| Error::invalid("bench", "frame outside the log"))?,
            );
            n += 1;
        }
    }
    let per = t0.elapsed().as_secs_f64() / n as f64;
    let cpu = match (c0, cpu_s()) {
        (Some(a), Some(b)) => format!("{:.3} s", (b - a) / n as f64),
        _ => "?".into(),
    };
    Ok((per, cpu))
}

/// The largest |a - b| over the displacement and path channels (px).
fn max_diff(a: &FrameMaps, b: &FrameMaps) -> f64 {
    let mut w: f64 = 0.0;
    for (x, y) in a.channels().iter().zip(b.channels()).take(3) {
        for (p, q) in x.1.iter().zip(y.1) {
            if p.is_finite() && q.is_finite() {
                w = w.max((p - q).abs() as f64);
            }
        }
    }
    w
}

/// CPU time of this process so far (user + system, all threads), s, from
/// `/proc/self/stat` (Linux; `None` elsewhere): on a machine shared with
/// other jobs, wall time overstates the work.
fn cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // Fields 14 and 15 of stat (utime, stime), counted from the state (field 3).
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
