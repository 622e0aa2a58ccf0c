//! The real camera of docs/spec.md section 9 (distortion, camera files, Gyroflow lens
//! profiles) against independent computations: finite differences of the
//! projection, brute-force sensor means, hand-computed profile values.

use crate::common;

use glam::DVec3;
use mmbm::camera::{Distortion, Readout};
use mmbm::model::flow::flow_distorted;
use mmbm::{mmbm, Camera, Method, Plane, Scene, Twist};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    crate::common::repo_root()
        .join("tests/fixtures/camera")
        .join(name)
}

fn opencv() -> Camera {
    Camera::load(&fixture("opencv.toml")).unwrap()
}

fn fisheye() -> Camera {
    Camera {
        distortion: Distortion::Fisheye {
            k1: 0.03,
            k2: 0.06,
            k3: -0.05,
            k4: 0.012,
        },
        ..Camera::new(2.0, 0.003, 640, 480)
    }
}

fn tilted() -> Plane {
    Plane {
        normal: DVec3::new(0.15, -0.3, 1.0),
        d: 1.2,
    }
}

#[test]
fn camera_file_holds_every_spec9_key() {
    let c = opencv();
    assert_eq!(
        (c.focal_mm, c.pitch_x_mm, c.width, c.cx),
        (2.8, 0.0028, 640, 322.5)
    );
    assert_eq!(c.shutter.readout_s, 0.016);
    assert_eq!(c.shutter.direction, Readout::TopToBottom);
    assert_eq!(
        c.distortion,
        Distortion::Opencv {
            k1: -0.28,
            k2: 0.07,
            p1: 0.001,
            p2: -0.0015,
            k3: -0.008
        }
    );
    let n = c.noise.unwrap();
    assert_eq!(
        (n.phi_e_per_s, n.read_noise_e, n.bits, n.seed),
        (50000.0, 3.0, 10, 4)
    );
    assert_eq!(n.full_well_e, 10_000.0, "default full well");
    let l = c.lens.unwrap();
    assert_eq!((l.f_number, l.focus_m), (2.0, 1.5));
}

#[test]
fn gyroflow_profile_is_a_camera_file() {
    let c = Camera::load(&fixture("gyroflow_fisheye.json")).unwrap();
    // No focal length in mm: nominal 1 um pixels, so f = fx * 0.001 mm.
    assert_eq!((c.width, c.height), (4000, 3000));
    assert!((c.focal_mm - 1.8).abs() < 1e-15);
    assert!((c.fx_px() - 1800.0).abs() < 1e-9 && (c.fy_px() - 1795.0).abs() < 1e-9);
    // Not `asymmetrical`: Gyroflow's principal point is the image centre
    // (the matrix says 2010, 1490).
    assert_eq!((c.cx, c.cy, c.skew), (2000.0, 1500.0, 0.0));
    assert!((c.shutter.readout_s - 0.0155).abs() < 1e-15, "15.5 ms");
    assert_eq!(
        c.distortion,
        Distortion::Fisheye {
            k1: 0.031,
            k2: 0.06,
            k3: -0.05,
            k4: 0.012
        }
    );
    // Used for a 1920x1440 video: the matrix scales by 0.48.
    let s = c.scaled_to(1920, 1440);
    assert!((s.fx_px() - 864.0).abs() < 1e-9 && (s.fy_px() - 861.6).abs() < 1e-9);
    assert!((s.cx - 960.0).abs() < 1e-9 && (s.cy - 720.0).abs() < 1e-9);
    assert_eq!(s.focal_mm, c.focal_mm, "the field of view is unchanged");
    // The same ray lands on the same relative position.
    let (a, b) = (c.mm_to_pixel(0.3, -0.2), s.mm_to_pixel(0.3, -0.2));
    assert!((a.0 * 0.48 - b.0).abs() < 1e-9 && (a.1 * 0.48 - b.1).abs() < 1e-9);
}

fn write_tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mmbm-camera-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn bad_camera_files_name_the_key() {
    let base = "focal_mm = 2.8\npitch_mm = 0.0028\nwidth = 640\nheight = 480\n";
    let cases = [
        (
            "fold.toml",
            format!("{base}[distortion]\nmodel = \"opencv\"\nk1 = -2.0\n"),
            "distortion",
        ),
        (
            "readout.toml",
            format!("{base}readout_s = -0.01\n"),
            "readout_s",
        ),
        (
            "bits.toml",
            format!("{base}[noise]\nphi_e_per_s = 100\nbits = 40\n"),
            "noise.bits",
        ),
        (
            "phi.toml",
            format!("{base}[noise]\nphi_e_per_s = 0\n"),
            "noise.phi_e_per_s",
        ),
        (
            "lens.toml",
            format!("{base}[lens]\nf_number = -2\nfocus_m = 1\n"),
            "lens.f_number",
        ),
        (
            "model.toml",
            format!("{base}[distortion]\nmodel = \"mystery\"\n"),
            "mystery",
        ),
        (
            "dir.toml",
            format!("{base}readout_direction = \"sideways\"\n"),
            "sideways",
        ),
    ];
    for (name, text, key) in cases {
        let e = Camera::load(&write_tmp(name, &text))
            .unwrap_err()
            .to_string();
        assert!(e.contains(key) && e.contains(name), "{name}: {e}");
    }
    let json = r#"{"calib_dimension": {"w": 100, "h": 80}, "distortion_model": "gopro",
        "fisheye_params": {"camera_matrix": [[90,0,50],[0,90,40],[0,0,1]], "distortion_coeffs": [0.1]}}"#;
    let e = Camera::load(&write_tmp("p.json", json))
        .unwrap_err()
        .to_string();
    assert!(e.contains("distortion_model") && e.contains("gopro"), "{e}");
}

/// Distorted sensor point (mm) of the scene point `x` (camera frame, m).
fn project(cam: &Camera, x: DVec3) -> (f64, f64) {
    cam.distort_mm(cam.focal_mm * x.x / x.z, cam.focal_mm * x.y / x.z)
}

/// Central difference of the projection of the scene point seen at the
/// distorted sensor point `(ud, vd)` under twist `tw` (docs/spec.md section 2: a scene point
/// moves as `dX/dt = -v - w x X` in the camera frame).
fn fd_flow(cam: &Camera, plane: &Plane, tw: &Twist, ud: f64, vd: f64) -> (f64, f64) {
    let (u, v) = cam.undistort_mm(ud, vd).unwrap();
    let ray = DVec3::new(u / cam.focal_mm, v / cam.focal_mm, 1.0);
    let x = ray * (plane.d / plane.normal.dot(ray));
    let vel = -tw.velocity - tw.omega.cross(x);
    let h = 1e-5;
    let (a, b) = (project(cam, x + vel * h), project(cam, x - vel * h));
    ((a.0 - b.0) / (2.0 * h), (a.1 - b.1) / (2.0 * h))
}

#[test]
fn distorted_flow_equals_finite_differences() {
    let tw = Twist::new(DVec3::new(0.3, -0.5, 0.8), DVec3::new(0.4, -0.2, 1.5));
    let plane = tilted();
    for cam in [opencv(), fisheye()] {
        let mut worst: f64 = 0.0;
        for &(px, py) in &[
            (0.5, 0.5),
            (639.5, 479.5),
            (320.0, 240.0),
            (100.25, 400.75),
            (600.0, 20.0),
        ] {
            let (ud, vd) = cam.pixel_to_mm(px, py);
            let (a, b) = flow_distorted(&cam, ud, vd, &tw, Some(&plane)).unwrap();
            let (c, d) = fd_flow(&cam, &plane, &tw, ud, vd);
            let rel = (a - c).hypot(b - d) / c.hypot(d);
            worst = worst.max(rel);
            // Signs included: both components agree in sign where they are not tiny.
            assert!(
                a * c >= 0.0 || a.abs() < 1e-6 * c.hypot(d),
                "u sign at ({px}, {py})"
            );
            assert!(
                b * d >= 0.0 || b.abs() < 1e-6 * c.hypot(d),
                "v sign at ({px}, {py})"
            );
        }
        eprintln!("{:?}: worst relative FD error {worst:.2e}", cam.distortion);
        assert!(worst < 1e-7, "{worst}");
    }
}

/// MMBM through distortion: the midpoint rule at the pixel centres equals the
/// brute-force mean of finite-difference speeds over the pixel centres; the
/// Gauss rule and the adaptive exact method agree with it.
#[test]
fn distorted_metric_matches_brute_force() {
    let tw = Twist::new(DVec3::new(0.3, -0.5, 0.8), DVec3::new(0.4, -0.2, 1.5));
    for cam in [opencv(), fisheye()] {
        let cam = cam.with_resolution(160, 120);
        let cam = Camera {
            focal_mm: cam.focal_mm / 4.0,
            ..cam
        }; // keep the wide field of view
        let plane = tilted();
        let mut sum = 0.0;
        for j in 0..cam.height {
            for i in 0..cam.width {
                let (ud, vd) = cam.pixel_to_mm(i as f64 + 0.5, j as f64 + 0.5);
                let (a, b) = fd_flow(&cam, &plane, &tw, ud, vd);
                sum += a.hypot(b);
            }
        }
        let brute = sum / (cam.width * cam.height) as f64;
        let scene = Scene {
            camera: cam,
            plane: Some(plane),
        };
        let riemann = mmbm(
            &scene,
            &tw,
            Method::Riemann {
                nu: cam.width,
                nv: cam.height,
            },
        )
        .unwrap()
        .mm_s;
        let gauss = mmbm(&scene, &tw, Method::Gauss { nu: 64, nv: 48 })
            .unwrap()
            .mm_s;
        let exact = mmbm(&scene, &tw, Method::Exact { tol: 1e-10 }).unwrap();
        let ideal = mmbm(
            &Scene {
                camera: Camera {
                    distortion: Distortion::None,
                    ..cam
                },
                plane: Some(plane),
            },
            &tw,
            Method::Exact { tol: 1e-10 },
        )
        .unwrap()
        .mm_s;
        eprintln!(
            "{:?}: brute {brute:.9} riemann {riemann:.9} gauss {gauss:.9} exact {:.9} (+- {:.1e}); pinhole {ideal:.6}",
            cam.distortion, exact.mm_s, exact.error_estimate.unwrap()
        );
        assert!(
            (riemann - brute).abs() < 1e-7 * brute,
            "{riemann} vs {brute}"
        );
        assert!(
            (gauss - exact.mm_s).abs() < 1e-5 * exact.mm_s,
            "{gauss} vs {}",
            exact.mm_s
        );
        // The midpoint rule on 160x120 cells is within its O(h^2) error of the integral.
        assert!((riemann - exact.mm_s).abs() < 1e-4 * exact.mm_s);
        assert!(
            (ideal - exact.mm_s).abs() > 1e-3 * exact.mm_s,
            "distortion changes MMBM"
        );
    }
}

#[test]
fn explicit_defaults_change_nothing() {
    let plain = write_tmp(
        "plain.toml",
        "focal_mm = 4.2548\npitch_mm = 0.00465\nwidth = 640\nheight = 480\n",
    );
    let explicit = write_tmp(
        "explicit.toml",
        "focal_mm = 4.2548\npitch_mm = 0.00465\nwidth = 640\nheight = 480\nreadout_s = 0\n\
         readout_direction = \"top-to-bottom\"\n[distortion]\nmodel = \"none\"\n",
    );
    assert_eq!(Camera::load(&explicit).unwrap(), Camera::thesis());
    let run = |cam: Option<&PathBuf>, method: &str| {
        let mut c = common::mmbm_cmd();
        c.args(["eval", "--omega", "0.3,-0.2,0.5", "--method", method]);
        if let Some(p) = cam {
            c.arg("--camera").arg(p);
        }
        let out = c.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out.stdout
    };
    for method in ["riemann:8x6", "gauss:4x3", "exact:1e-9"] {
        let base = run(None, method);
        assert_eq!(base, run(Some(&plain), method), "{method}");
        assert_eq!(base, run(Some(&explicit), method), "{method}");
    }
}
