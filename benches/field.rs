//! The flow-field kernels (`cargo bench --bench field`): the GPU against
//! their CPU twins on one thread and on all cores. Times are printed, never
//! asserted; without a GPU adapter it stops with the adapter error (exit 1).

mod common;

use mmbm::camera::Camera;
use mmbm::error::{Error, Result};
use mmbm::field::cpu as flow_cpu;
use mmbm::field::{FlowRunner, Grid, TwistGpu};
use mmbm::model::motion::Twist;
use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

/// Seconds per call of `f`: after one warm-up call, repeats until `secs`
/// have passed (at least 3 calls).
fn per_call(secs: f64, mut f: impl FnMut() -> Result<()>) -> Result<f64> {
    f()?;
    let t0 = Instant::now();
    let mut n = 0u32;
    while n < 3 || t0.elapsed().as_secs_f64() < secs {
        f()?;
        n += 1;
    }
    Ok(t0.elapsed().as_secs_f64() / n as f64)
}

fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::invalid("bench thread pool", e.to_string()))
}

/// Deterministic pseudo-random rotations (rad/s), up to about 1 rad/s per axis.
fn bench_twists(n: usize, f: f64) -> Vec<TwistGpu> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut r = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| TwistGpu::new(f, &Twist::rotation(r(), r(), 0.3 * r()), None))
        .collect()
}

fn main() -> ExitCode {
    common::main(run)
}

/// Runs the benchmark and prints the table.
fn run() -> Result<()> {
    let mut gpu = FlowRunner::new()?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let one = pool(1)?;
    let all = pool(cores)?;
    let base = Camera::thesis();
    let tw = bench_twists(1, base.focal_mm)[0];
    println!(
        "GPU flow kernels on {}; CPU twin (f32) on 1 and {cores} threads",
        gpu.adapter()
    );
    println!(
        "times in ms per field (mean speed reduced; GPU: kernel + readback of the partial sums)"
    );
    println!(
        "{:<11} {:>10} {:>14} {:>12} {:>12} {:>12}",
        "resolution", "GPU field", "GPU +readback", "GPU mean", "CPU 1 thr", "CPU all"
    );
    for (w, h) in [(640u32, 480u32), (1920, 1080), (4096, 3072)] {
        let cam = base.with_resolution(w, h);
        let grid = Grid::new(&cam, 0, 0)?;
        let secs = 1.0;
        let g_field = per_call(secs, || {
            black_box(gpu.tiles_ext(&grid, &[tw], true, false)?);
            Ok(())
        })?;
        let g_read = per_call(secs, || {
            black_box(gpu.tiles(&grid, &[tw], true)?);
            Ok(())
        })?;
        let g_mean = per_call(secs, || {
            black_box(gpu.tiles(&grid, &[tw], false)?);
            Ok(())
        })?;
        let c1 = one.install(|| {
            per_call(secs, || {
                black_box(flow_cpu::flow_tiles(&grid, &tw, true)?);
                Ok(())
            })
        })?;
        let cn = all.install(|| {
            per_call(secs, || {
                black_box(flow_cpu::flow_tiles(&grid, &tw, true)?);
                Ok(())
            })
        })?;
        println!(
            "{:<11} {:>10.2} {:>14.2} {:>12.2} {:>12.2} {:>12.2}",
            format!("{w}x{h}"),
            g_field * 1e3,
            g_read * 1e3,
            g_mean * 1e3,
            c1 * 1e3,
            cn * 1e3
        );
    }
    println!("batched MMBM, thesis camera, 16384 twists per dispatch (twists/s):");
    println!(
        "{:<11} {:>14} {:>14} {:>14}",
        "grid", "GPU", "CPU 1 thr", "CPU all"
    );
    let twists = bench_twists(16_384, base.focal_mm);
    for (w, h) in [(8u32, 6u32), (64, 48), (640, 480)] {
        let grid = Grid::new(&base, w, h)?;
        // Fewer twists at full resolution to keep the run short.
        let n = if w * h > 10_000 { 256 } else { twists.len() };
        let t = &twists[..n];
        let g = per_call(1.0, || {
            black_box(gpu.batch_means(&grid, t)?);
            Ok(())
        })?;
        let c1 = one.install(|| {
            per_call(1.0, || {
                black_box(flow_cpu::batch_means(&grid, t)?);
                Ok(())
            })
        })?;
        let cn = all.install(|| {
            per_call(1.0, || {
                black_box(flow_cpu::batch_means(&grid, t)?);
                Ok(())
            })
        })?;
        println!(
            "{:<11} {:>14.0} {:>14.0} {:>14.0}",
            format!("{w}x{h}"),
            n as f64 / g,
            n as f64 / c1,
            n as f64 / cn
        );
    }
    Ok(())
}
