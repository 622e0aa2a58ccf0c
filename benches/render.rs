//! Renderer cost (`cargo bench --bench render`; printed, never asserted): ms per 640x480 frame at the
//! `default` preset for the two scenes of the render-speed goal (the full-view
//! `checker:0.02` at 1 m, the blob board at 5 m), at three blur lengths, on
//! the GPU (whatever adapter is in use, e.g. lavapipe) and the CPU twin (all
//! threads), with both area integrators; and the equivalent throughput in
//! pixel-samples (pixels x instants, or x samples for the lattice) per second.

mod common;

use mmbm::camera::Camera;
use mmbm::error::Result;
use mmbm::model::motion::Twist;
use mmbm::render::{
    maps, render_frame, Backend, Integrator, Quality, RenderJob, Target, Trajectory,
};
use std::process::ExitCode;
use std::time::Instant;

/// The goal's motion: w = (0.3, -0.2, 0.5) rad/s, exposure scaled so that the
/// largest image path over the sensor is `path_px`.
fn job(target: &Target, path_px: f64) -> Result<RenderJob> {
    let cam = Camera::thesis().with_resolution(640, 480);
    let tw = Twist::rotation(0.3, -0.2, 0.5);
    let probe = Trajectory::from_twist(tw, 0.05)?;
    let l0 = maps::max_path_px(&cam, target, &probe);
    let te = 0.05 * path_px / l0;
    let mut j = RenderJob::new(cam, te, Trajectory::from_twist(tw, te)?, target.clone());
    j.quality = Quality::Default;
    j.with_maps = false;
    Ok(j)
}

/// Best of `reps` wall times (s) and the samples per pixel.
fn time(j: &RenderJob, reps: usize) -> Result<(f64, u32)> {
    let mut best = f64::INFINITY;
    let mut n = 0;
    for _ in 0..reps {
        let t0 = Instant::now();
        let o = render_frame(j)?;
        best = best.min(t0.elapsed().as_secs_f64());
        n = o.samples_per_pixel;
    }
    Ok((best, n))
}

fn main() -> ExitCode {
    common::main(bench)
}

/// Prints the renderer benchmarks.
fn bench() -> Result<()> {
    let gpu = mmbm::gpu::gpu();
    match &gpu {
        Ok(c) => println!("render bench, GPU: {}", c.description),
        Err(e) => println!("render bench, no GPU ({e})"),
    }
    println!("  640x480, default preset, best of 2; ms per frame (M pixel-samples/s)");
    println!(
        "  {:<22} {:<9} {:>7} {:>6} {:>18} {:>18}",
        "scene", "integr.", "path px", "N", "gpu", "cpu twin"
    );
    let scenes = [
        ("checker:0.02 at 1 m", Target::checker(0.02, 1.0)),
        ("blob board at 5 m", Target::blobs(1.0, 5.0)),
    ];
    for (name, target) in &scenes {
        for integrator in [Integrator::Analytic, Integrator::Lattice] {
            for path in [2.0, 20.0, 80.0] {
                let mut j = job(target, path)?;
                j.integrator = integrator;
                let cell = |b: Backend, ok: bool| -> Result<(String, u32)> {
                    if !ok {
                        return Ok((format!("{:>18}", "-"), 0));
                    }
                    let jb = RenderJob {
                        backend: b,
                        ..j.clone()
                    };
                    let (t, n) = time(&jb, 2)?;
                    let mps = 640.0 * 480.0 * n as f64 / t * 1e-6;
                    Ok((format!("{:>9.0} ({:>6.0})", t * 1e3, mps), n))
                };
                let (g, _) = cell(Backend::Gpu, gpu.is_ok())?;
                let (c, n) = cell(Backend::Cpu { threads: None }, true)?;
                println!(
                    "  {:<22} {:<9} {:>7.0} {:>6} {} {}",
                    name,
                    integrator.to_string(),
                    path,
                    n,
                    g,
                    c
                );
            }
        }
    }
    Ok(())
}
