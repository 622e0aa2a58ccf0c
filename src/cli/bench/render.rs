//! Renderer throughput (printed, never asserted): pixel-samples per second
//! on the GPU (whatever adapter is in use, e.g. lavapipe) and on the CPU twin
//! with one thread and with all threads, at 320x240, 640x480 and 1920x1080;
//! then the cost of a default-quality frame against blur length.

use glam::DVec3;
use mmbm::error::Result;
use mmbm::model::camera::Camera;
use mmbm::model::motion::Twist;
use mmbm::render::{maps, render_frame, Backend, Quality, RenderJob, Target, Trajectory};
use std::time::Instant;

fn job(w: u32, h: u32, scale: f64, quality: Quality, backend: Backend) -> Result<RenderJob> {
    let cam = Camera::thesis().with_resolution(w, h);
    let tw = Twist::new(
        DVec3::new(0.4, -0.6, 0.3) * scale,
        DVec3::new(0.05, 0.0, 0.1) * scale,
    );
    let mut j = RenderJob::new(
        cam,
        Trajectory::from_twist(tw, 0.05)?,
        Target::checker(0.05, 2.0),
    );
    j.quality = quality;
    j.backend = backend;
    j.with_maps = false;
    Ok(j)
}

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

/// Prints the renderer benchmarks.
pub fn bench() -> Result<()> {
    let gpu = mmbm::gpu::gpu();
    match &gpu {
        Ok(c) => println!("render bench, GPU: {}", c.description),
        Err(e) => println!("render bench, no GPU ({e})"),
    }
    println!("  64 samples/pixel, checker, best of 2 (M pixel-samples/s):");
    println!(
        "  {:>10} {:>10} {:>10} {:>10}",
        "size", "gpu", "cpu x1", "cpu all"
    );
    let q = Quality::Custom {
        min_samples: 64,
        max_spacing_px: 1e9,
    };
    for (w, h) in [(320, 240), (640, 480), (1920, 1080)] {
        let mut row = format!("  {:>10}", format!("{w}x{h}"));
        let samples = (w * h) as f64 * 64.0;
        let backends = [
            (gpu.is_ok(), Backend::Gpu),
            (true, Backend::Cpu { threads: Some(1) }),
            (true, Backend::Cpu { threads: None }),
        ];
        for (ok, b) in backends {
            if !ok {
                row += &format!(" {:>10}", "-");
                continue;
            }
            let (t, _) = time(&job(w, h, 1.0, q, b)?, 2)?;
            row += &format!(" {:>10.1}", samples / t * 1e-6);
        }
        println!("{row}");
    }
    println!("  cost vs blur length, 320x240, default quality:");
    println!(
        "  {:>10} {:>8} {:>10} {:>10}",
        "max px", "N", "gpu ms", "cpu ms"
    );
    for scale in [0.25, 1.0, 4.0, 16.0] {
        let j = job(
            320,
            240,
            scale,
            Quality::Default,
            Backend::Cpu { threads: None },
        )?;
        let l = maps::max_path_px(&j.camera, &j.target, &j.trajectory);
        let g = if gpu.is_ok() {
            let jg = RenderJob {
                backend: Backend::Gpu,
                ..j.clone()
            };
            format!("{:>10.1}", time(&jg, 1)?.0 * 1e3)
        } else {
            format!("{:>10}", "-")
        };
        let (tc, n) = time(&j, 1)?;
        println!("  {:>10.1} {:>8} {} {:>10.1}", l, n, g, tc * 1e3);
    }
    Ok(())
}
