//! One lens strategy for the maps kernel (`frames --maps --backend gpu`):
//! the lens models without a formula in the lens module (Gyroflow's
//! `poly3`, `poly5`, 12-coefficient `opencv_standard`, digital lenses...)
//! run in table mode (`series::maps::table`) instead of being refused. The
//! twin against the f64 maps, the kernel against the twin, and the CLI's
//! GPU against its CPU path on a real Gyroflow profile.
//!
//! Tolerances: the maps kernel's (`cli/tests/frames/maps_gpu.rs`): twin vs f64,
//! |difference| <= 2e-4 x (1 + path px) for the displacement and path and
//! 1e-5 x (1 + |flow|) for the flow (px/s); kernel vs twin 2e-5 x (1 + path)
//! and 1e-6 x (1 + |flow|).

use crate::common;
use crate::maps_fixture;

use maps_fixture::*;
use mmbm::camera::{Distortion, Readout, Shutter};
use mmbm::io::frames::VideoFrame;
use mmbm::series::maps::gpu::MapsRunner;
use mmbm::series::maps::kernel::frame_maps_twin;
use mmbm::series::maps::{frame_maps, MapRays};
use mmbm::Camera;
use std::path::PathBuf;

/// A Gyroflow profile of the fixtures whose lens (a GoPro SuperView
/// digital lens over the fisheye) has no formula in the lens module.
fn profile() -> PathBuf {
    common::repo_root().join(
        "tests/fixtures/lens_profiles/p02_GoPro_HERO5_Black_Superview_NO_EIS_1080p_16by9_1920x1080_59.json",
    )
}

/// Lenses in table mode on a 160 x 120 sensor: three Gyroflow models and
/// the real profile, scaled.
fn table_lenses() -> Vec<(String, Camera)> {
    let base = Camera {
        shutter: Shutter {
            readout_s: 0.02,
            direction: Readout::TopToBottom,
        },
        ..Camera::thesis().scaled_to(160, 120)
    };
    let mut k = [0.0; 12];
    k[..5].copy_from_slice(&[-0.25, 0.06, 0.001, -0.0015, -0.005]);
    k[5] = 0.02; // k4: the rational term, so not the five-coefficient model
    let mut out: Vec<(String, Camera)> = [
        Distortion::Poly3 { k1: -0.08 },
        Distortion::Poly5 {
            k1: -0.05,
            k2: 0.004,
        },
        Distortion::OpencvStandard { k },
    ]
    .into_iter()
    .map(|d| {
        (
            d.name().to_string(),
            Camera {
                distortion: d,
                ..base
            },
        )
    })
    .collect();
    let p = Camera::load(&profile()).unwrap();
    out.push(("p02 superview".into(), p.scaled_to(160, 90)));
    for (name, c) in &out {
        assert!(
            c.distortion.coefficients().is_none(),
            "{name}: the lens module has a formula for it"
        );
    }
    out
}

/// The twin in table mode agrees with the f64 maps (rotation, and
/// translation on a plane), and the kernel with the twin per pixel.
#[test]
fn table_mode_matches_f64_and_kernel_matches_twin() {
    let log = synthetic_log(None);
    let frame = VideoFrame {
        t_start: 0.7,
        exposure_s: 0.01,
        readout_s: Some(0.02),
    };
    let plane = mmbm::Plane {
        normal: glam::DVec3::new(0.2, -0.1, 1.0).normalize(),
        d: 1.5,
    };
    let mut runner = common::gpu().map(|_| MapsRunner::new().unwrap());
    let (mut wt, mut wf, mut gt, mut gf) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (name, cam) in table_lenses() {
        let rays = MapRays::new(&cam).unwrap();
        for o in [opts(cam, None, false), opts(cam, Some(plane), true)] {
            let cpu = frame_maps(&log, &o, &rays, 0, &frame, None)
                .unwrap()
                .unwrap();
            let twin = frame_maps_twin(&job(&log, &o, &rays, 0, &frame))
                .unwrap()
                .unwrap();
            assert!(cpu.mean_path_px().1 > 0.5, "{name}: a blur to measure");
            let (t, fl) = worst(&twin, &cpu);
            assert!(
                t < 2e-4 && fl < 1e-5,
                "{name}: twin vs f64 {t:.2e} {fl:.2e}"
            );
            (wt, wf) = (wt.max(t), wf.max(fl));
            if let Some(r) = runner.as_mut() {
                let gpu = r
                    .frame_maps(&job(&log, &o, &rays, 0, &frame))
                    .unwrap()
                    .unwrap();
                let (t, fl) = worst(&gpu, &twin);
                assert!(
                    t < 2e-5 && fl < 1e-6,
                    "{name}: kernel vs twin {t:.2e} {fl:.2e}"
                );
                (gt, gf) = (gt.max(t), gf.max(fl));
            }
        }
    }
    eprintln!(
        "table mode: twin vs f64 track {wt:.2e} x (1 + path), flow {wf:.2e} x (1 + |flow|); \
         kernel vs twin {gt:.2e}, {gf:.2e}"
    );
}

/// `frames --maps --backend gpu` takes a real Gyroflow profile (a digital
/// lens, once refused by name) and agrees with `--backend cpu` within the
/// maps kernel's tolerance.
#[test]
fn cli_gyroflow_profile_gpu_matches_cpu() {
    let Some(gyro) = common::shared_log("running_phone") else {
        return;
    };
    if common::gpu().is_none() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let table = tmp.path().join("frames.csv");
    // Long exposures: the profile's wide lens at 192 x 108 blurs these
    // frames by about 0.2 px at their own 4 ms.
    std::fs::write(&table, "t_start,exposure_s\n2.0,0.02\n5.258,0.01\n").unwrap();
    let run = |backend: &str| {
        let dir = tmp.path().join(backend);
        let f = tmp.path().join(format!("{backend}.csv"));
        let out = frames_maps(&gyro, &table, &profile(), &dir, &f, &["--backend", backend]);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{backend}: {err}");
        (dir, err)
    };
    let (cpu, err) = run("cpu");
    assert!(err.contains("on the CPU"), "{err}");
    let (gpu, err) = run("gpu");
    assert!(
        err.contains("maps: 2 frame(s)") && !err.contains("on the CPU"),
        "{err}"
    );
    let (mut wt, mut wf, mut mean) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..2 {
        let name = format!("frame_{:06}.exr", k + 1);
        let (_, _, a) = mmbm::io::images::read_exr(&gpu.join(&name)).unwrap();
        let (_, _, b) = mmbm::io::images::read_exr(&cpu.join(&name)).unwrap();
        let get =
            |ch: &[(String, Vec<f32>)], n: &str| ch.iter().find(|c| c.0 == n).unwrap().1.clone();
        let path = get(&b, "path_px");
        let (fu, fv) = (get(&b, "flow.u"), get(&b, "flow.v"));
        let valid: Vec<f64> = path
            .iter()
            .filter(|p| p.is_finite())
            .map(|&p| p as f64)
            .collect();
        assert!(
            valid.len() > path.len() / 2,
            "{name}: {} pixels with maps",
            valid.len()
        );
        mean = mean.max(valid.iter().sum::<f64>() / valid.len() as f64);
        for n in ["disp.u", "disp.v", "path_px", "flow.u", "flow.v"] {
            let (x, y) = (get(&a, n), get(&b, n));
            for i in 0..y.len() {
                assert_eq!(x[i].is_nan(), y[i].is_nan(), "{name} {n} pixel {i}");
                let e = (x[i] - y[i]).abs() as f64;
                if n.starts_with("flow") {
                    let e = e / (1.0 + (fu[i] as f64).hypot(fv[i] as f64));
                    assert!(e < 1e-5, "{name} {n} pixel {i}: {} vs {}", x[i], y[i]);
                    wf = wf.max(e);
                } else {
                    let e = e / (1.0 + path[i] as f64);
                    assert!(e < 2e-4, "{name} {n} pixel {i}: {} vs {}", x[i], y[i]);
                    wt = wt.max(e);
                }
            }
        }
    }
    assert!(mean > 0.5, "mean path {mean} px: a blur to compare");
    eprintln!("p02 GPU vs CPU: track {wt:.2e} x (1 + path), flow {wf:.2e} x (1 + |flow|)");
}
