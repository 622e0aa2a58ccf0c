//! The real camera's cost (`cargo bench --bench camera`; printed, never
//! asserted): the metric per sample through lens distortion, and the
//! renderer's ms per 640x480 frame with each effect of docs/spec.md section 9 alone (the
//! render goal's checker at 1 m, 20 px of blur, `default` preset), GPU and
//! CPU twin.

mod common;

use common::{time_per_call, twists};
use mmbm::camera::{Camera, Distortion, Lens, Noise, Readout, Shutter};
use mmbm::error::Result;
use mmbm::metric::{Evaluator, Method};
use mmbm::model::motion::Twist;
use mmbm::render::{maps, render_frame, Backend, RenderJob, Target, Trajectory};
use mmbm::Scene;
use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

fn metric() -> Result<()> {
    let polys: Vec<_> = twists(4096)
        .iter()
        .map(|t| Scene::thesis().flow_poly(t))
        .collect();
    println!("metric through lens distortion (OpenCV k1..k3, p1, p2), one thread, ns/sample:");
    println!("  {:<14} {:>10} {:>12}", "method", "pinhole", "distorted");
    for m in [
        Method::Riemann { nu: 8, nv: 6 },
        Method::Gauss { nu: 4, nv: 3 },
        Method::Exact { tol: 1e-8 },
    ] {
        let n = if matches!(m, Method::Exact { .. }) {
            64
        } else {
            polys.len()
        };
        let mut per = [0.0; 2];
        for (k, cam) in [
            Camera::thesis(),
            Camera {
                distortion: Distortion::WIDE_ANGLE,
                ..Camera::thesis()
            },
        ]
        .iter()
        .enumerate()
        {
            let ev = Evaluator::new(cam, m)?;
            per[k] = time_per_call(1.0, || {
                for p in &polys[..n] {
                    black_box(ev.mean_speed(black_box(p)));
                }
            }) / n as f64;
        }
        println!(
            "  {:<14} {:>10.1} {:>12.1}",
            m.to_string(),
            per[0] * 1e9,
            per[1] * 1e9
        );
    }
    Ok(())
}

fn render() -> Result<()> {
    let base = Camera::thesis().with_resolution(640, 480);
    let target = Target::checker(0.02, 1.0);
    let tw = Twist::rotation(0.3, -0.2, 0.5);
    let probe = Trajectory::from_twist(tw, 0.05)?;
    let te = 0.05 * 20.0 / maps::max_path_px(&base, &target, &probe);
    let effects: [(&str, Camera); 5] = [
        ("pinhole (today)", base),
        (
            "rolling shutter 16 ms",
            Camera {
                shutter: Shutter {
                    readout_s: 0.016,
                    direction: Readout::TopToBottom,
                },
                ..base
            },
        ),
        (
            "distortion (OpenCV)",
            Camera {
                distortion: Distortion::WIDE_ANGLE,
                ..base
            },
        ),
        (
            "noise (EMVA 1288)",
            Camera {
                noise: Some(Noise::at_light(50_000.0)),
                ..base
            },
        ),
        (
            "defocus f/2 at 0.5 m",
            Camera {
                lens: Some(Lens {
                    f_number: 2.0,
                    focus_m: 0.5,
                }),
                ..base
            },
        ),
    ];
    println!("render, 640x480 checker:0.02 at 1 m, 20 px of blur, default preset, best of 2, ms per frame:");
    println!(
        "  {:<24} {:>6} {:>10} {:>10}",
        "camera", "N", "gpu", "cpu twin"
    );
    for (name, cam) in effects {
        let span = te + cam.shutter.readout_s;
        let mut ms = [f64::NAN; 2];
        let mut n = 0;
        for (k, backend) in [Backend::Gpu, Backend::Cpu { threads: None }]
            .into_iter()
            .enumerate()
        {
            let mut j = RenderJob::new(cam, te, Trajectory::from_twist(tw, span)?, target.clone());
            j.with_maps = false;
            j.backend = backend;
            let mut best = f64::INFINITY;
            for _ in 0..2 {
                let t0 = Instant::now();
                match render_frame(&j) {
                    Ok(o) => {
                        n = o.samples_per_pixel;
                        best = best.min(t0.elapsed().as_secs_f64());
                    }
                    Err(e) => {
                        println!("  {name}: {e}");
                        break;
                    }
                }
            }
            ms[k] = best * 1e3;
        }
        println!("  {:<24} {:>6} {:>10.0} {:>10.0}", name, n, ms[0], ms[1]);
    }
    Ok(())
}

fn main() -> ExitCode {
    common::main(bench)
}

/// Prints the camera benchmarks.
fn bench() -> Result<()> {
    metric()?;
    render()
}
