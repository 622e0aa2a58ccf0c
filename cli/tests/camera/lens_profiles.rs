//! Gyroflow lens profiles read as Gyroflow reads them (issue 25): profiles
//! written in the test, each checked against values computed here by hand
//! from Gyroflow's rules (`lens_profile.rs`, `distortion_models/`), each
//! of which the previous reader got wrong (refused, or read differently).

use crate::common;

use mmbm::camera::{Distortion, Readout};
use mmbm::model::flow::flow_distorted;
use mmbm::{mmbm, Camera, Method, Scene, Twist};
use std::path::PathBuf;

fn write_tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mmbm-lens-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A profile with these pieces (`extra` is more top-level keys, with a trailing comma).
fn profile(w: u32, h: u32, matrix: [f64; 4], model: &str, coeffs: &str, extra: &str) -> String {
    let [fx, fy, cx, cy] = matrix;
    format!(
        r#"{{"calib_dimension": {{"w": {w}, "h": {h}}}, {extra} "distortion_model": "{model}",
        "fisheye_params": {{"camera_matrix": [[{fx},0,{cx}],[0,{fy},{cy}],[0,0,1]],
        "distortion_coeffs": [{coeffs}]}}}}"#
    )
}

fn load(name: &str, text: &str) -> mmbm::Result<Camera> {
    Camera::load(&write_tmp(name, text))
}

/// `theta_d = theta + theta^3 - 0.8 theta^5`: it grows up to theta = 1 rad
/// (slope `1 + 3 t^2 - 4 t^4 = 0`), where it is 1.2, its radial limit.
const TURNING: &str = "1.0, -0.8, 0, 0";

/// Every pixel corner of a coarse grid inside the limit undistorts and maps back.
fn round_trips(c: &Camera) -> usize {
    let mut n = 0;
    for j in 0..=40 {
        for i in 0..=40 {
            let (px, py) = (
                c.width as f64 * i as f64 / 40.0,
                c.height as f64 * j as f64 / 40.0,
            );
            let (ud, vd) = c.pixel_to_mm(px, py);
            if c.is_masked_mm(ud, vd) {
                continue;
            }
            let (u, v) = c
                .undistort_mm(ud, vd)
                .expect("inside the limit, a preimage");
            let (a, b) = c.distort_mm(u, v);
            assert!((a - ud).hypot(b - vd) < 1e-9 * c.focal_mm, "({px}, {py})");
            n += 1;
        }
    }
    n
}

#[test]
fn points_past_newtons_old_start_undistort() {
    // fx = 1150 on 2000 x 1400: the corner is at r_d = 1220 / 1150 = 1.061,
    // inside the limit 1.2 but beyond the turning point's angle (1 rad), where
    // the old solve started Newton (at min(r_d, 1.5)) and gave up.
    let c = load(
        "newton.json",
        &profile(
            2000,
            1400,
            [1150.0, 1150.0, 1000.0, 700.0],
            "opencv_fisheye",
            TURNING,
            "",
        ),
    )
    .unwrap();
    assert_eq!(c.masked_fraction(), 0.0);
    assert_eq!(round_trips(&c), 41 * 41);
    // The corner's ray, solved by bisection here: theta_d(theta) = 1220/1150.
    let rd = 1000f64.hypot(700.0) / 1150.0;
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if m + m.powi(3) - 0.8 * m.powi(5) < rd {
            lo = m;
        } else {
            hi = m;
        }
    }
    let (u, v) = c
        .undistort_mm(1000.0 * c.pitch_x_mm, 700.0 * c.pitch_y_mm)
        .unwrap();
    let theta = (u.hypot(v) / c.focal_mm).atan();
    assert!((theta - lo).abs() < 1e-12, "{theta} vs {lo}");
}

#[test]
fn beyond_the_radial_limit_is_masked_not_refused() {
    // fx = 1000: the limit is 1.2 * 1000 = 1200 px from the centre; the
    // corners (1220 px) are beyond it.
    let c = load(
        "mask.json",
        &profile(
            2000,
            1400,
            [1000.0, 1000.0, 1000.0, 700.0],
            "opencv_fisheye",
            TURNING,
            "",
        ),
    )
    .unwrap();
    assert!((c.radial_limit_mm() / c.pitch_x_mm - 1200.0).abs() < 1e-6);
    // The masked share against a count of quarter-pixel cells beyond 1200
    // px, here and with the principal point off the centre (asymmetrical).
    let counted = |cx: f64, cy: f64| {
        let (mut beyond, mut all) = (0u64, 0u64);
        for j in 0..1400 * 2 {
            for i in 0..2000 * 2 {
                let (x, y) = ((i as f64 + 0.5) / 2.0 - cx, (j as f64 + 0.5) / 2.0 - cy);
                beyond += (x.hypot(y) > 1200.0) as u64;
                all += 1;
            }
        }
        beyond as f64 / all as f64
    };
    let want = counted(1000.0, 700.0);
    assert!(want > 0.0);
    assert!(
        (c.masked_fraction() - want).abs() < 2e-5,
        "{} vs {want}",
        c.masked_fraction()
    );
    let off = load(
        "mask_off.json",
        &profile(
            2000,
            1400,
            [1000.0, 1000.0, 300.0, 200.0],
            "opencv_fisheye",
            TURNING,
            r#""asymmetrical": true,"#,
        ),
    )
    .unwrap();
    let want = counted(300.0, 200.0);
    assert!(want > 0.2, "{want}");
    assert!(
        (off.masked_fraction() - want).abs() < 2e-5,
        "{} vs {want}",
        off.masked_fraction()
    );
    assert!(round_trips(&c) < 41 * 41);
    // MMBM over the unmasked sensor: riemann and exact agree, and equal the
    // mean of |J flow| over the unmasked pixel centres.
    let scene = Scene {
        camera: c,
        plane: None,
    };
    let tw = Twist::rotation(0.4, -0.3, 0.7);
    let r = mmbm(&scene, &tw, Method::Riemann { nu: 2000, nv: 1400 })
        .unwrap()
        .mm_s;
    let e = mmbm(&scene, &tw, Method::Exact { tol: 1e-6 }).unwrap().mm_s;
    let (mut sum, mut n) = (0.0, 0u64);
    for j in (0..1400).step_by(7) {
        for i in (0..2000).step_by(8) {
            let (ud, vd) = c.pixel_to_mm(i as f64 + 0.5, j as f64 + 0.5);
            if ud.hypot(vd) > 1200.0 * c.pitch_x_mm {
                continue;
            }
            let (a, b) = flow_distorted(&c, ud, vd, &tw, None).unwrap();
            sum += a.hypot(b);
            n += 1;
        }
    }
    let brute = sum / n as f64;
    assert!((r - e).abs() < 2e-4 * e, "riemann {r} exact {e}");
    assert!((brute - e).abs() < 2e-3 * e, "brute {brute} exact {e}");
    // `mmbm eval` reports the masked share.
    let exe = common::bin();
    let path = write_tmp(
        "mask.json",
        &profile(
            2000,
            1400,
            [1000.0, 1000.0, 1000.0, 700.0],
            "opencv_fisheye",
            TURNING,
            "",
        ),
    );
    let out = std::process::Command::new(&exe)
        .args(["eval", "--omega", "0.4,-0.3,0.7", "--json", "--camera"])
        .arg(&path)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", exe.display()));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["masked_fraction"].as_f64(), Some(c.masked_fraction()));
    // The GPU kernel masks through its lens table (cli/tests/camera/gpu_lens.rs).
    assert!(mmbm::field::Grid::new(&c, 0, 0).unwrap().uses_table());
}

#[test]
fn principal_point_is_the_centre_unless_asymmetrical() {
    let m = [1800.0, 1790.0, 9134.0, 1200.0];
    let c = load(
        "pp.json",
        &profile(3840, 2160, m, "opencv_standard", "0.01", ""),
    )
    .unwrap();
    assert_eq!((c.cx, c.cy), (1920.0, 1080.0));
    let c = load(
        "asym.json",
        &profile(
            3840,
            2160,
            m,
            "opencv_standard",
            "0.01",
            r#""asymmetrical": true,"#,
        ),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((c.cx, c.cy), (9134.0, 1200.0));
}

#[test]
fn negative_readout_is_the_opposite_direction() {
    let m = [1800.0, 1800.0, 2000.0, 1500.0];
    for (dir, want) in [
        ("", Readout::BottomToTop),
        (
            r#""frame_readout_direction": "LeftToRight","#,
            Readout::RightToLeft,
        ),
    ] {
        let extra = format!(r#""frame_readout_time": -15.5, {dir}"#);
        let c = load(
            "ro.json",
            &profile(4000, 3000, m, "opencv_fisheye", "0.01", &extra),
        )
        .unwrap();
        assert_eq!(c.shutter.direction, want, "{dir}");
        assert!((c.shutter.readout_s - 0.0155).abs() < 1e-15);
    }
}

#[test]
fn zero_or_no_coefficients_are_a_pinhole() {
    let m = [1800.0, 1800.0, 2000.0, 1500.0];
    for coeffs in ["", "0, 0, 0, 0", "0.0, 0.0"] {
        for model in ["opencv_fisheye", "opencv_standard"] {
            let c = load("zero.json", &profile(4000, 3000, m, model, coeffs, "")).unwrap();
            assert_eq!(c.distortion, Distortion::None, "{model} [{coeffs}]");
        }
    }
}

#[test]
fn opencv_standard_reads_all_twelve_coefficients() {
    let k = [
        -0.21, 0.05, 0.0012, -0.0009, -0.004, 0.08, -0.02, 0.006, 0.0021, -0.0007, -0.0015, 0.0004,
    ];
    let list = k.map(|x| x.to_string()).join(", ");
    let m = [1500.0, 1500.0, 960.0, 540.0];
    let c = load(
        "k12.json",
        &profile(1920, 1080, m, "opencv_standard", &list, ""),
    )
    .unwrap();
    assert_eq!(c.distortion, Distortion::OpencvStandard { k });
    // OpenCV's formula, written out here.
    let (x, y) = (0.41, -0.23);
    let r2 = x * x + y * y;
    let radial = (1.0 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2)
        / (1.0 + k[5] * r2 + k[6] * r2 * r2 + k[7] * r2 * r2 * r2);
    let xd =
        x * radial + 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x) + k[8] * r2 + k[9] * r2 * r2;
    let yd =
        y * radial + k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y + k[10] * r2 + k[11] * r2 * r2;
    let (a, b) = c.distortion.distort(x, y);
    assert!((a - xd).abs() < 1e-15 && (b - yd).abs() < 1e-15);
    let (ux, uy) = c.distortion.undistort(xd, yd).unwrap();
    assert!((ux - x).hypot(uy - y) < 1e-11);
    assert_eq!(round_trips(&c), 41 * 41);
    // Five non-zero coefficients: the five-coefficient model (the GPU's).
    let c = load(
        "k5.json",
        &profile(
            1920,
            1080,
            m,
            "opencv_standard",
            "-0.2, 0.05, 0, 0, 0.01, 0, 0, 0",
            "",
        ),
    )
    .unwrap();
    assert!(matches!(c.distortion, Distortion::Opencv { .. }));
    // A 13th non-zero coefficient, or a 5th for the fisheye, is refused by index.
    let e = load(
        "k13.json",
        &profile(
            1920,
            1080,
            m,
            "opencv_standard",
            &format!("{list}, 0.1"),
            "",
        ),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("distortion_coeffs[12]") && e.contains("12 coefficients"),
        "{e}"
    );
    let e = load(
        "f5.json",
        &profile(1920, 1080, m, "opencv_fisheye", "0.1, 0, 0, 0, 0.2", ""),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("distortion_coeffs[4]"), "{e}");
}

#[test]
fn focal_sign_crop_and_unsupported_lenses() {
    let extra = r#""crop": 1.25,"#;
    let c = load(
        "neg.json",
        &profile(
            4000,
            3000,
            [-1800.0, 1790.0, 2000.0, 1500.0],
            "opencv_fisheye",
            "0.01",
            extra,
        ),
    )
    .unwrap();
    assert!((c.fx_px() - 1440.0).abs() < 1e-9 && (c.fy_px() - 1432.0).abs() < 1e-9);
    for (extra, model, want) in [
        (
            r#""digital_lens": "gopro_fancyview","#,
            "opencv_fisheye",
            "not a digital lens",
        ),
        ("", "gopro", "not supported"),
        ("", "kannala", "not supported"),
    ] {
        let e = load(
            "dl.json",
            &profile(
                4000,
                3000,
                [1800.0, 1800.0, 2000.0, 1500.0],
                model,
                "0.01",
                extra,
            ),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn portrait_video_transposes_the_profile() {
    use mmbm::camera::{CameraFile, CameraOverrides};
    let path = write_tmp(
        "land.json",
        &profile(
            1920,
            1080,
            [1500.0, 1480.0, 960.0, 540.0],
            "opencv_fisheye",
            "0.02",
            "",
        ),
    );
    let over = CameraOverrides {
        keys: CameraFile::default(),
        scale_to: Some((1080, 1920)),
        light_e_per_s: None,
        lens_focal_mm: None,
    };
    let c = Camera::resolve(Some(&path), &over).unwrap();
    // Gyroflow's swap: fx and fy trade places (no stretch), so do cx and cy.
    assert_eq!((c.width, c.height), (1080, 1920));
    assert!((c.fx_px() - 1480.0).abs() < 1e-9 && (c.fy_px() - 1500.0).abs() < 1e-9);
    assert_eq!((c.cx, c.cy), (540.0, 960.0));
    // The same orientation is a plain scaling.
    let over = CameraOverrides {
        scale_to: Some((960, 540)),
        ..over
    };
    let c = Camera::resolve(Some(&path), &over).unwrap();
    assert!((c.fx_px() - 750.0).abs() < 1e-9 && (c.fy_px() - 740.0).abs() < 1e-9);
}
