//! `mmbm bench`: throughput measurements (printed, never asserted): the
//! metric rules here, the flow-field kernels ([`field`]), the renderer
//! ([`render`]) and the trigger policies ([`trigger`]).

mod camera;
mod field;
mod render;
mod trigger;

use clap::Args;
use mmbm::error::Result;
use mmbm::metric::{Evaluator, Method};
use mmbm::{Scene, Twist};
use std::hint::black_box;
use std::time::Instant;

/// Measure throughput.
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm bench
  mmbm bench --what metric
  mmbm bench --what gpu
  mmbm bench --what trigger
  mmbm bench --what render
  mmbm bench --what camera")]
pub struct BenchArgs {
    /// metric, gpu, trigger, render or all.
    #[arg(long, default_value = "all")]
    pub what: String,
}

/// Runs `f` repeatedly for about `secs` seconds, returning seconds per call.
pub fn time_per_call(secs: f64, mut f: impl FnMut()) -> f64 {
    f();
    let mut n = 1u64;
    let t0 = Instant::now();
    loop {
        for _ in 0..n {
            f();
        }
        let el = t0.elapsed().as_secs_f64();
        if el > secs {
            let total: u64 = (1..=n).filter(|k| k.is_power_of_two()).sum();
            return el / total as f64;
        }
        n *= 2;
    }
}

pub(crate) fn twists(n: usize) -> Vec<Twist> {
    let mut s = 1u64;
    (0..n)
        .map(|_| {
            let mut r = || {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
            };
            Twist::rotation(r(), r(), r() * 0.3)
        })
        .collect()
}

fn metric() -> Result<()> {
    let s = Scene::thesis();
    let tws = twists(4096);
    let polys: Vec<_> = tws.iter().map(|t| s.flow_poly(t)).collect();
    println!("metric, one thread, thesis camera, random rotations:");
    for m in [
        Method::Riemann { nu: 8, nv: 6 },
        Method::Gauss { nu: 4, nv: 3 },
        Method::Gauss { nu: 8, nv: 6 },
        Method::Exact { tol: 1e-8 },
    ] {
        let n = if matches!(m, Method::Exact { .. }) {
            256
        } else {
            polys.len()
        };
        let ev = Evaluator::new(&s.camera, m)?;
        let per = time_per_call(1.0, || {
            for p in &polys[..n] {
                black_box(ev.mean_speed(black_box(p)));
            }
        }) / n as f64;
        // Flow expansion included (what series does per sample).
        println!(
            "  {:<14} {:>10.1} ns/sample  {:>8.2} M samples/s",
            m.to_string(),
            per * 1e9,
            1e-6 / per
        );
    }
    // The hard case for the exact method: the flow vanishes inside the
    // sensor (roll-dominated motion puts a cone-shaped kink there).
    let kinks: Vec<_> = twists(256)
        .iter()
        .map(|t| s.flow_poly(&Twist::rotation(0.05 * t.omega.x, 0.05 * t.omega.y, 1.0)))
        .collect();
    let ev = Evaluator::new(&s.camera, Method::Exact { tol: 1e-8 })?;
    let per = time_per_call(1.0, || {
        for p in &kinks {
            black_box(ev.mean_speed(black_box(p)));
        }
    }) / kinks.len() as f64;
    println!(
        "  exact:1e-8, flow zero inside the sensor (roll-dominated): {:.1} us/sample",
        per * 1e6
    );
    let ev = Evaluator::new(&s.camera, Method::default())?;
    let per = time_per_call(1.0, || {
        for t in &tws {
            black_box(ev.mean_speed(&s.flow_poly(black_box(t))));
        }
    }) / tws.len() as f64;
    println!(
        "  riemann:8x6 incl. flow expansion {:.1} ns/sample",
        per * 1e9
    );
    Ok(())
}

pub fn run(a: BenchArgs) -> Result<()> {
    match a.what.as_str() {
        "metric" => metric(),
        "gpu" => field::run(),
        "trigger" => trigger::bench(),
        "render" => render::bench(),
        "camera" => camera::bench(),
        "all" => {
            metric()?;
            field::run()?;
            trigger::bench()?;
            render::bench()?;
            camera::bench()
        }
        w => Err(mmbm::Error::invalid(
            "--what",
            format!("'{w}': expected metric, gpu, trigger, render, camera or all"),
        )),
    }
}
