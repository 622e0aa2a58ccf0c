//! GPU flow kernels against their CPU twins, the f64 formula and the exact
//! integral. Tests that need an adapter skip (with a printed line) without one,
//! unless MMBM_REQUIRE_GPU=1.

use crate::common;

use glam::DVec3;
use mmbm::field::cpu as flow_cpu;
use mmbm::field::{flow_field_gpu, mmbm_gpu, FlowRunner, Grid, TwistGpu};
use mmbm::io::gyro::GyroSample;
use mmbm::series::gpu::series_evaluator;
use mmbm::series::{eval_batch_cpu, SeriesOptions};
use mmbm::{mmbm, Camera, Method, Plane, Scene, Twist};
use std::process::Command;

fn odd_camera() -> Camera {
    // Non-square pixels, off-centre principal point, skew.
    Camera {
        focal_mm: 3.1,
        pitch_x_mm: 0.0041,
        pitch_y_mm: 0.0047,
        width: 200,
        height: 150,
        cx: 93.25,
        cy: 80.5,
        skew: 1.3,
        ..Camera::thesis()
    }
}

fn tilted() -> Plane {
    Plane {
        normal: DVec3::new(0.15, -0.3, 1.0),
        d: 1.2,
    }
}

/// Per pixel: GPU vs the f32 CPU twin (1e-6 of the max speed: same formula,
/// only fused multiply-adds may differ) and vs the f64 formula (1e-5 of the max speed).
fn check_field(scene: &Scene, tw: &Twist) {
    let (tol_twin, tol_ref) = (1e-6, 1e-5);
    let f = flow_field_gpu(scene, tw, 0, 0).unwrap();
    let grid = Grid::new(&scene.camera, 0, 0).unwrap();
    let g = TwistGpu::new(scene.camera.focal_mm, tw, scene.plane.as_ref());
    let twin = flow_cpu::flow_tiles(&grid, &g, true).unwrap();
    let (reff, mean) = flow_cpu::reference_f64(&grid, tw, scene.plane.as_ref());
    assert_eq!(f.u.len(), grid.len());
    let max = reff.iter().map(|a| a[0].hypot(a[1])).fold(0.0, f64::max);
    let (mut e_twin, mut e_ref) = (0f64, 0f64);
    for (k, r) in reff.iter().enumerate() {
        let (u, v) = (f.u[k] as f64, f.v[k] as f64);
        let t = twin.field[k];
        e_twin = e_twin
            .max((u - t[0] as f64).abs())
            .max((v - t[1] as f64).abs());
        e_ref = e_ref.max((u - r[0]).abs()).max((v - r[1]).abs());
    }
    eprintln!(
        "field {}x{} {tw:?}: max |GPU - twin| = {:.2e}, max |GPU - f64| = {:.2e} (of max speed {max:.1} px/s)",
        grid.width, grid.height, e_twin / max, e_ref / max
    );
    assert!(e_twin <= tol_twin * max, "GPU vs twin {e_twin} (max {max})");
    assert!(e_ref <= tol_ref * max, "GPU vs f64 {e_ref} (max {max})");
    // Mean: the GPU's f32 partial sums vs the f64 midpoint sum over the same pixels.
    assert!(
        (f.mmbm.mm_s - mean).abs() <= tol_twin * mean,
        "{} {mean}",
        f.mmbm.mm_s
    );
    assert!((twin.mean_mm_s - f.mmbm.mm_s).abs() <= tol_twin * mean);
    // px/s: mm/s over the pitch with square pixels, else the mean true pixel
    // speed of the field's samples (docs/cameras.md).
    let px_mean = match mmbm::metric::pixel_map(&scene.camera) {
        None => f.mmbm.mm_s / scene.camera.pitch_x_mm,
        Some(_) => f.speed().iter().map(|&s| s as f64).sum::<f64>() / (f.u.len() as f64),
    };
    assert!((f.mmbm.px_s - px_mean).abs() < 1e-9 * f.mmbm.px_s);
}

/// Lens distortion (docs/spec.md section 9): the kernel undistorts each pixel by 16 Newton
/// steps in f32 and pushes the flow through the Jacobian; the twin runs the
/// same f32 steps (the fisheye's atan is a polynomial in both, not the
/// platform's). Same tolerances as the pinhole field (measured on lavapipe:
/// GPU = twin exactly, 3.1e-7 of the max speed from the f64 formula).
#[test]
fn gpu_field_with_distortion() {
    if common::gpu().is_none() {
        return;
    }
    let opencv = Camera {
        distortion: mmbm::camera::Distortion::Opencv {
            k1: -0.28,
            k2: 0.07,
            p1: 0.001,
            p2: -0.0015,
            k3: -0.008,
        },
        ..odd_camera()
    };
    let fisheye = Camera {
        distortion: mmbm::camera::Distortion::Fisheye {
            k1: 0.03,
            k2: 0.06,
            k3: -0.05,
            k4: 0.012,
        },
        ..Camera::new(2.0, 0.003, 640, 480)
    };
    for cam in [opencv, fisheye] {
        let scene = Scene {
            camera: cam,
            plane: Some(tilted()),
        };
        let tw = Twist::new(DVec3::new(0.3, -0.5, 0.8), DVec3::new(0.4, -0.2, 1.5));
        check_field(&scene, &tw);
        // The GPU mean is the method `gpu`; the CPU rules on the same camera agree with it.
        let gpu = mmbm_gpu(&scene, &tw, 0, 0).unwrap().mm_s;
        let exact = mmbm(&scene, &tw, Method::Exact { tol: 1e-9 }).unwrap().mm_s;
        eprintln!("{:?}: gpu {gpu} exact {exact}", cam.distortion);
        assert!(
            (gpu - exact).abs() < 1e-4 * exact,
            "gpu {gpu} vs exact {exact}"
        );
    }
}

#[test]
fn gpu_field_matches_twin_and_formula() {
    if common::gpu().is_none() {
        return;
    }
    let thesis = Scene::thesis();
    check_field(&thesis, &Twist::rotation(1.0, 1.0, 1.0));
    check_field(&thesis, &Twist::rotation(-0.2, 0.7, -2.0));
    let odd = Scene {
        camera: odd_camera(),
        plane: Some(tilted()),
    };
    check_field(
        &odd,
        &Twist::new(DVec3::new(0.3, -0.5, 0.8), DVec3::new(0.4, -0.2, 1.5)),
    );
}

#[test]
fn gpu_field_signs_follow_the_formula() {
    // Independent of the twin: pitch up (wx > 0) moves every point down (+v), at f*wx/p_y px/s in the centre.
    if common::gpu().is_none() {
        return;
    }
    let s = Scene::thesis();
    let f = flow_field_gpu(&s, &Twist::rotation(1.0, 0.0, 0.0), 0, 0).unwrap();
    let centre = 240 * 640 + 320;
    let want = 4.2548 / 0.00465;
    assert!(f.v.iter().all(|&v| v > 0.0));
    assert!(
        (f.v[centre] as f64 - want).abs() < 1e-3 * want,
        "{}",
        f.v[centre]
    );
    // Translation right (vx > 0) moves the image left.
    let s = Scene {
        plane: Some(Plane::fronto(2.0)),
        ..s
    };
    let f = flow_field_gpu(
        &s,
        &Twist::new(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0)),
        0,
        0,
    )
    .unwrap();
    assert!(f.u.iter().all(|&u| u < 0.0));
}

#[test]
fn gpu_mean_matches_exact_integral() {
    if common::gpu().is_none() {
        return;
    }
    let cam = Camera::thesis();
    let cases = [
        (Twist::rotation(1.0, 1.0, 1.0), None),
        (Twist::rotation(0.0, 0.0, 1.0), None), // kink at the centre
        (Twist::rotation(1.0, 0.0, 0.0), None),
        (Twist::rotation(0.02, -0.3, 0.9), None), // zero of the flow inside the sensor
        (
            Twist::new(DVec3::ZERO, DVec3::new(0.25, 0.125, -1.0)),
            Some(Plane::fronto(1.0)),
        ),
        (
            Twist::new(DVec3::new(0.5, 0.5, 1.0), DVec3::new(0.5, 0.25, -2.0)),
            Some(Plane::fronto(0.5)),
        ),
        (
            Twist::new(DVec3::new(0.2, 0.1, 0.0), DVec3::new(0.0, 0.0, 1.0)),
            Some(Plane {
                normal: DVec3::new(0.0, -0.3, 1.0),
                d: 2.0,
            }),
        ),
    ];
    for (tw, plane) in cases {
        let s = Scene { camera: cam, plane };
        let g = mmbm_gpu(&s, &tw, 0, 0).unwrap().mm_s;
        let ex = mmbm(&s, &tw, Method::Exact { tol: 1e-12 }).unwrap().mm_s;
        let mid = mmbm(&s, &tw, Method::Riemann { nu: 640, nv: 480 })
            .unwrap()
            .mm_s;
        eprintln!(
            "{tw:?} {plane:?}: exact {ex:.10}, GPU rel err {:.2e}, f64 midpoint 640x480 rel err {:.2e}, GPU vs midpoint {:.2e}",
            (g - ex).abs() / ex,
            (mid - ex).abs() / ex,
            (g - mid).abs() / ex
        );
        assert!((g - ex).abs() <= 1e-5 * ex, "{tw:?}: gpu {g} exact {ex}");
        assert!(
            (g - mid).abs() <= 1e-6 * ex,
            "{tw:?}: gpu {g} midpoint {mid}"
        );
    }
}

fn twists(n: usize) -> Vec<(Twist, Option<Plane>)> {
    (0..n)
        .map(|k| {
            let x = k as f64;
            let w = DVec3::new(
                (x * 0.37).sin(),
                (x * 0.71).cos() * 0.8,
                (x * 0.13).sin() * 0.4,
            );
            if k % 3 == 0 {
                let v = DVec3::new((x * 0.5).cos() * 0.3, 0.1, (x * 0.9).sin());
                (Twist::new(w, v), Some(Plane::fronto(0.5 + (k % 7) as f64)))
            } else {
                (Twist::rotation(w.x, w.y, w.z), None)
            }
        })
        .collect()
}

#[test]
fn batched_matches_single_and_cpu() {
    if common::gpu().is_none() {
        return;
    }
    let cam = Camera::thesis();
    let tws = twists(200);
    let gtw: Vec<TwistGpu> = tws
        .iter()
        .map(|(t, p)| TwistGpu::new(cam.focal_mm, t, p.as_ref()))
        .collect();
    let mut r = FlowRunner::new().unwrap();
    // 8x6 and 64x48 use rows_per_twist, 160x120 flow_tiles.
    for (w, h) in [(8u32, 6u32), (64, 48), (160, 120)] {
        let grid = Grid::new(&cam, w, h).unwrap();
        let batch = r.batch_means(&grid, &gtw).unwrap();
        let twin = flow_cpu::batch_means(&grid, &gtw).unwrap();
        assert_eq!(batch.len(), tws.len());
        for (k, (tw, plane)) in tws.iter().enumerate() {
            let s = Scene {
                camera: cam,
                plane: *plane,
            };
            let cpu = mmbm(&s, tw, Method::Riemann { nu: w, nv: h }).unwrap().mm_s;
            assert!(
                (batch[k] - cpu).abs() <= 1e-6 * cpu,
                "{w}x{h} #{k}: {} {cpu}",
                batch[k]
            );
            assert!((batch[k] - twin[k]).abs() <= 1e-6 * cpu);
            if k % 50 == 0 {
                let single = mmbm_gpu(&s, tw, w, h).unwrap().mm_s;
                assert!(
                    (batch[k] - single).abs() <= 1e-6 * cpu,
                    "{} {single}",
                    batch[k]
                );
            }
        }
    }
}

fn samples(n: usize) -> Vec<GyroSample> {
    twists(n)
        .into_iter()
        .enumerate()
        .map(|(k, (tw, p))| GyroSample {
            t: k as f64 / 600.0,
            omega: tw.omega,
            velocity: Some(tw.velocity),
            depth: p.map(|p| p.d),
        })
        .collect()
}

#[test]
fn series_evaluator_matches_cpu_series() {
    if common::gpu().is_none() {
        return;
    }
    let batch = samples(300);
    for use_velocity in [false, true] {
        let opts = SeriesOptions {
            scene: Scene {
                camera: Camera::thesis(),
                plane: Some(tilted()),
            },
            method: Method::Riemann { nu: 32, nv: 24 },
            use_velocity,
        };
        let mut eval = series_evaluator(opts, 32, 24).unwrap();
        let gpu = eval(&batch).unwrap();
        let cpu = eval_batch_cpu(&batch, &opts).unwrap();
        for (a, b) in gpu.iter().zip(&cpu) {
            assert!(
                (a - b).abs() <= 1e-6 * b,
                "use_velocity={use_velocity}: {a} {b}"
            );
        }
        assert!(eval(&[]).unwrap().is_empty());
    }
    // A sample whose plane is behind the camera is an error naming the sample.
    let mut bad = samples(4);
    bad[2].depth = Some(-1.0);
    let opts = SeriesOptions {
        scene: Scene {
            camera: Camera::thesis(),
            plane: Some(Plane::fronto(2.0)),
        },
        method: Method::default(),
        use_velocity: true,
    };
    let mut eval = series_evaluator(opts, 8, 6).unwrap();
    let e = eval(&bad).unwrap_err().to_string();
    assert!(e.contains("t = 0.00333"), "{e}");
}

fn mmbm_bin() -> Command {
    let mut c = common::mmbm_cmd();
    let d = std::env::temp_dir().join("mmbm-test-xdg");
    let _ = std::fs::create_dir_all(&d);
    c.env("XDG_RUNTIME_DIR", d);
    c
}

#[test]
fn no_adapter_is_a_clear_error_not_a_panic() {
    // Runs without a GPU too: an adapter filter that matches nothing.
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("f.exr");
    for args in [
        vec!["flow", "--omega", "1,0,0", "--out", out.to_str().unwrap()],
        vec!["eval", "--omega", "1,0,0", "--method", "gpu"],
    ] {
        let o = mmbm_bin()
            .args(&args)
            .env("MMBM_ADAPTER", "no-such-adapter-xyz")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains(
                "error: GPU: no GPU adapter found matching MMBM_ADAPTER='no-such-adapter-xyz'"
            ),
            "{err}"
        );
        assert!(err.contains("mesa-vulkan-drivers"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    assert!(!out.exists());
}

#[test]
fn flow_command_writes_exr_and_quiver() {
    if common::gpu().is_none() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let exr = d.path().join("f.exr");
    let png = d.path().join("q.png");
    let o = mmbm_bin()
        .args([
            "flow",
            "--omega",
            "0.5,0.5,1",
            "--velocity",
            "0.5,0.25,-2",
            "--depth",
            "0.5",
            "--sensor",
            "160x120",
            "--exposure",
            "0.05",
            "--out",
        ])
        .arg(&exr)
        .arg("--quiver")
        .arg(&png)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (w, h, ch) = mmbm::io::images::read_exr(&exr).unwrap();
    assert_eq!((w, h), (160, 120));
    let get = |n: &str| {
        &ch.iter()
            .find(|c| c.0 == n)
            .unwrap_or_else(|| panic!("{n}"))
            .1
    };
    let (u, v, sp) = (get("flow.u"), get("flow.v"), get("flow.speed"));
    let cam = Camera::thesis().with_resolution(160, 120);
    let tw = Twist::new(DVec3::new(0.5, 0.5, 1.0), DVec3::new(0.5, 0.25, -2.0));
    let grid = Grid::new(&cam, 0, 0).unwrap();
    let (reff, _) = flow_cpu::reference_f64(&grid, &tw, Some(&Plane::fronto(0.5)));
    let max = reff.iter().map(|a| a[0].hypot(a[1])).fold(0.0, f64::max);
    assert_eq!(reff.len(), w * h);
    for (k, r) in reff.iter().enumerate() {
        assert!((u[k] as f64 - r[0]).abs() <= 1e-5 * max);
        assert!((v[k] as f64 - r[1]).abs() <= 1e-5 * max);
        assert!((sp[k] as f64 - r[0].hypot(r[1])).abs() <= 1e-5 * max);
    }
    let img = mmbm::io::images::read_rgb8(&png).unwrap();
    assert!(img.width() >= 640 && img.height() >= 300);
    // Bad input: exposure must be positive; nothing written.
    let exr2 = d.path().join("g.exr");
    let o = mmbm_bin()
        .args(["flow", "--omega", "1,0,0", "--exposure", "0", "--out"])
        .arg(&exr2)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(!exr2.exists());
}
