//! The GPU path of `frames --maps` (`src/series/maps.wgsl`): its CPU twin
//! against the f64 maps (`series::maps::frame_maps`) on both shared logs and
//! a synthetic log with translation, the kernel against the twin per pixel
//! (lavapipe or any adapter), every lens model taken (table mode:
//! `tests/maps_gpu_lens.rs`), and the CLI's `--backend`.
//!
//! Tolerances: twin vs f64, |difference| <= 2e-4 x (1 + path px) for the
//! displacement and path and 1e-5 x (1 + |flow|) for the flow (px/s): a
//! distorted track's positions are f32 (about 6e-8 x their size in px, a
//! few 1e-5 px at these sizes; measured up to 3.6e-5) and the path sums
//! them; the pinhole track is kept as an offset from the start (measured
//! 5e-8). Kernel vs twin: 2e-5 x (1 + path) and 1e-6 x (1 + |flow|) (the
//! same f32 operations; the GPU may fuse and reorder them; measured 6.8e-6
//! and 0 on lavapipe).

use crate::common;
use crate::maps_fixture;

use glam::DVec3;
use maps_fixture::*;
use mmbm::camera::{Distortion, Readout, Shutter};
use mmbm::gpu::Backend;
use mmbm::io::frames::VideoFrame;
use mmbm::model::log::ImuLog;
use mmbm::series::maps::gpu::{resolve, MapsRunner};
use mmbm::series::maps::kernel::frame_maps_twin;
use mmbm::series::maps::{frame_maps, MapRays};
use mmbm::series::SeriesOptions;
use mmbm::{Camera, Plane};

/// The pinhole, an OpenCV lens, a fisheye, and a fisheye whose radial limit
/// lies inside the sensor (pixels beyond it have no ray: NaN) on `base`.
fn lenses(base: Camera) -> [(&'static str, Camera); 4] {
    let masked = Camera {
        distortion: Distortion::Fisheye {
            k1: -0.35,
            k2: 0.0,
            k3: 0.0,
            k4: 0.0,
        },
        ..base
    };
    let rays = MapRays::new(&masked).unwrap();
    let none = rays.rays().iter().filter(|r| r.0.is_nan()).count();
    assert!(
        none > rays.rays().len() / 100,
        "{none} pixels without a ray"
    );
    [
        ("masked", masked),
        ("pinhole", base),
        (
            "opencv",
            Camera {
                distortion: Distortion::WIDE_ANGLE,
                ..base
            },
        ),
        (
            "fisheye",
            Camera {
                distortion: Distortion::Fisheye {
                    k1: 0.05,
                    k2: -0.01,
                    k3: 0.002,
                    k4: 0.0,
                },
                ..base
            },
        ),
    ]
}

/// The frames of a shared log's tests: its blurriest (largest mean path at
/// a coarse scale) and a few spread over the log.
fn picks(frames: &[VideoFrame]) -> Vec<usize> {
    let n = frames.len();
    vec![5, n / 3, n / 2, 2 * n / 3, n - 5]
}

/// The twin (f32, the kernel's operations) agrees with the f64 maps on both
/// shared logs, three lenses, rolling shutter, auto chord counts.
#[test]
fn twin_matches_f64_maps_on_shared_logs() {
    for (name, (w, h)) in [("running_phone", (192, 108)), ("dashboard_car", (160, 120))] {
        let Some((log, frames)) = shared(name) else {
            continue;
        };
        for (lens, cam) in lenses(example_camera(name).scaled_to(w, h)) {
            let o = opts(cam, None, false);
            let rays = MapRays::new(&cam).unwrap();
            let (mut wt, mut wf, mut n) = (0.0f64, 0.0f64, 0);
            for k in picks(&frames) {
                let f = &frames[k];
                let Some(cpu) = frame_maps(&log, &o, &rays, k, f, None).unwrap() else {
                    continue;
                };
                let twin = frame_maps_twin(&job(&log, &o, &rays, k, f))
                    .unwrap()
                    .unwrap();
                assert_eq!(twin.steps, cpu.steps);
                let (t, fl) = worst(&twin, &cpu);
                assert!(
                    t < 2e-3 && fl < 1e-4,
                    "{name} {lens} frame {k}: {t:.2e} {fl:.2e}"
                );
                (wt, wf, n) = (wt.max(t), wf.max(fl), n + 1);
            }
            assert!(n >= 3, "{name}: {n} frames with maps");
            eprintln!("{name} {lens}: twin vs f64 over {n} frames: track {wt:.2e} x (1 + path), flow {wf:.2e} x (1 + |flow|)");
        }
    }
}

/// A synthetic log with velocity on a tilted plane, column readout: the
/// twin against the f64 maps (translation and the plane's inverse depth).
fn synthetic() -> (ImuLog, VideoFrame, Camera, Plane) {
    let log = synthetic_log(None);
    let cam = Camera {
        shutter: Shutter {
            readout_s: 0.02,
            direction: Readout::RightToLeft,
        },
        distortion: Distortion::WIDE_ANGLE,
        ..Camera::thesis().scaled_to(160, 120)
    };
    let f = VideoFrame {
        t_start: 0.7,
        exposure_s: 0.01,
        readout_s: Some(0.02),
    };
    let plane = Plane {
        normal: DVec3::new(0.2, -0.1, 1.0).normalize(),
        d: 1.5,
    };
    (log, f, cam, plane)
}

#[test]
fn twin_matches_f64_maps_with_translation_and_column_readout() {
    let (log, f, cam, plane) = synthetic();
    for c in [
        cam,
        Camera {
            distortion: Distortion::None,
            ..cam
        },
    ] {
        let o = opts(c, Some(plane), true);
        let rays = MapRays::new(&c).unwrap();
        let cpu = frame_maps(&log, &o, &rays, 0, &f, None).unwrap().unwrap();
        let twin = frame_maps_twin(&job(&log, &o, &rays, 0, &f))
            .unwrap()
            .unwrap();
        let (t, fl) = worst(&twin, &cpu);
        eprintln!(
            "synthetic, translation, {:?}: twin vs f64 track {t:.2e}, flow {fl:.2e}",
            c.distortion.name()
        );
        assert!(t < 2e-4 && fl < 1e-5, "{t:.2e} {fl:.2e}");
        // Translation matters: without it the maps differ.
        let rot = frame_maps_twin(&job(&log, &opts(c, None, false), &rays, 0, &f))
            .unwrap()
            .unwrap();
        assert!((rot.mean_path_px().0 - twin.mean_path_px().0).abs() > 0.1);
    }
}

/// The kernel agrees with its twin per pixel: both shared logs, three
/// lenses, and the synthetic log with translation and column readout, its
/// lines split over many dispatches.
#[test]
fn gpu_matches_twin_per_pixel() {
    if common::gpu().is_none() {
        return;
    }
    let mut runner = MapsRunner::new().unwrap();
    eprintln!("adapter: {}", runner.adapter());
    let (mut wt, mut wf) = (0.0f64, 0.0f64);
    let mut check =
        |runner: &mut MapsRunner, log: &ImuLog, o: &SeriesOptions, f: &VideoFrame, what: &str| {
            let rays = MapRays::new(&o.scene.camera).unwrap();
            let Some(twin) = frame_maps_twin(&job(log, o, &rays, 0, f)).unwrap() else {
                return;
            };
            let gpu = runner
                .frame_maps(&job(log, o, &rays, 0, f))
                .unwrap()
                .unwrap();
            let (t, fl) = worst(&gpu, &twin);
            assert!(t < 2e-5 && fl < 1e-6, "{what}: {t:.2e} {fl:.2e}");
            assert!(twin.mean_path_px().1 > 0.5, "{what}");
            (wt, wf) = (wt.max(t), wf.max(fl));
        };
    for (name, (w, h)) in [("running_phone", (192, 108)), ("dashboard_car", (160, 120))] {
        let Some((log, frames)) = shared(name) else {
            continue;
        };
        for (lens, cam) in lenses(example_camera(name).scaled_to(w, h)) {
            for k in picks(&frames) {
                check(
                    &mut runner,
                    &log,
                    &opts(cam, None, false),
                    &frames[k],
                    &format!("{name} {lens} frame {k}"),
                );
            }
        }
    }
    let (log, f, cam, plane) = synthetic();
    runner.set_step_bytes(4096);
    check(
        &mut runner,
        &log,
        &opts(cam, Some(plane), true),
        &f,
        "synthetic, small dispatches",
    );
    eprintln!("GPU vs twin: track {wt:.2e} x (1 + path), flow {wf:.2e} x (1 + |flow|)");
}

/// Every lens model has a path in the kernel (the lens module's formulas or
/// the lens table): `gpu` and `auto` take a Gyroflow model too (it was refused
/// by name), `cpu` stays on the CPU.
#[test]
fn every_lens_model_is_taken() {
    let cam = Camera {
        distortion: Distortion::Poly3 { k1: 0.01 },
        ..Camera::thesis().scaled_to(64, 48)
    };
    assert!(resolve(Backend::Cpu { threads: None }, &cam)
        .unwrap()
        .is_none());
    if common::gpu().is_none() {
        return;
    }
    assert!(resolve(Backend::Gpu, &cam).unwrap().is_some());
    assert!(resolve(Backend::Auto, &cam).unwrap().is_some());
    assert!(resolve(Backend::Gpu, &Camera::thesis()).unwrap().is_some());
    let (log, f, _, _) = synthetic();
    let o = opts(cam, None, false);
    let rays = MapRays::new(&cam).unwrap();
    let m = MapsRunner::new()
        .unwrap()
        .frame_maps(&job(&log, &o, &rays, 0, &f))
        .unwrap()
        .expect("maps");
    assert!(m.mean_path_px().1 > 0.5);
}

/// `frames --maps --backend gpu` writes the kernel's maps, within the twin
/// tolerance of `--backend cpu`'s (f64), and names the adapter; a Gyroflow
/// lens model (table mode) is computed on the GPU too, with `gpu` and `auto`.
#[test]
fn cli_frames_maps_backend() {
    let Some(gyro) = common::shared_log("running_phone") else {
        return;
    };
    if common::gpu().is_none() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let table = tmp.path().join("frames.csv");
    std::fs::write(&table, "t_start,exposure_s\n2.0,0.004\n5.258,0.0013\n").unwrap();
    let run = |backend: &str| {
        let dir = tmp.path().join(backend);
        let f = tmp.path().join("f.csv");
        let out = frames_maps(
            &gyro,
            &table,
            &running_phone_camera(),
            &dir,
            &f,
            &["--backend", backend],
        );
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{err}");
        (dir, err)
    };
    let (cpu, err) = run("cpu");
    assert!(err.contains("on the CPU"), "{err}");
    let (gpu, err) = run("gpu");
    assert!(
        err.contains("maps: 2 frame(s)") && !err.contains("on the CPU"),
        "{err}"
    );
    for k in 0..2 {
        let name = format!("frame_{:06}.exr", k + 1);
        let (_, _, a) = mmbm::io::images::read_exr(&gpu.join(&name)).unwrap();
        let (_, _, b) = mmbm::io::images::read_exr(&cpu.join(&name)).unwrap();
        let get =
            |ch: &[(String, Vec<f32>)], n: &str| ch.iter().find(|c| c.0 == n).unwrap().1.clone();
        let path_cpu = get(&b, "path_px");
        for n in ["disp.u", "disp.v", "path_px"] {
            let (x, y) = (get(&a, n), get(&b, n));
            for i in 0..y.len() {
                let e = (x[i] - y[i]).abs() as f64 / (1.0 + path_cpu[i] as f64);
                assert!(e < 2e-4, "{name} {n} pixel {i}: {} vs {}", x[i], y[i]);
            }
        }
    }
    // A Gyroflow lens model (poly3: table mode) is computed on the GPU with
    // `--backend gpu` and `--backend auto` alike (it was refused by name).
    std::fs::write(&table, "t_start,exposure_s\n5.258,0.0013\n").unwrap();
    let cam = tmp.path().join("poly3.toml");
    std::fs::write(
        &cam,
        "focal_mm = 1.5118\npitch_mm = 0.001\nwidth = 1920\nheight = 1080\nreadout_s = 0.01598\n\
         [distortion]\nmodel = \"poly3\"\nk1 = 0.02\n",
    )
    .unwrap();
    let f = tmp.path().join("f.csv");
    for backend in ["gpu", "auto"] {
        let dir = tmp.path().join(format!("poly3_{backend}"));
        let out = frames_maps(&gyro, &table, &cam, &dir, &f, &["--backend", backend]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{backend}: {err}");
        assert!(!err.contains("on the CPU"), "{backend}: {err}");
        assert!(dir.join("frame_000001.exr").exists());
    }
}

/// A `--backend` that is none of the four is refused by name, before any file is read.
#[test]
fn unknown_backend_is_refused() {
    let o = common::mmbm(&[
        "frames",
        "--backend",
        "tpu",
        "--gyro",
        "no.csv",
        "--frames",
        "no.csv",
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("'tpu'") && e.contains("auto, gpu, cpu or bulk"),
        "{e}"
    );
}
