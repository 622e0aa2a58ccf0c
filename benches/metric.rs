//! The metric rules' throughput (`cargo bench --bench metric`): ns per
//! sample on one thread, thesis camera, random rotations; the exact method's
//! hard case; and `riemann:8x6` with the flow expansion included. Printed,
//! never asserted.

mod common;

use common::{time_per_call, twists};
use mmbm::error::Result;
use mmbm::metric::{Evaluator, Method};
use mmbm::{Scene, Twist};
use std::hint::black_box;
use std::process::ExitCode;

fn main() -> ExitCode {
    common::main(metric)
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
