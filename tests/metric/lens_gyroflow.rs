//! Gyroflow's lens models, digital lenses and loading keys (issue 25), each
//! against Gyroflow's formulas written again here, independently of the
//! library (`Gf`: its `distortion_models/*.rs` in f64, its camera matrix
//! rules, its pixel pipeline `digital(K distort(ray))`), and a sample of 40
//! real profiles of its database (`tests/fixtures/lens_profiles/`): each
//! loads, and its MMBM equals the mean pixel speed of the same grid projected
//! through `Gf` to 0.1 %. An ignored test re-measures the whole database
//! (`MMBM_LENS_DB=DIR`).

use mmbm::camera::{CameraFile, CameraOverrides};
use mmbm::{mmbm, Camera, Method, Scene, Twist};
use serde_json::{json, Value};

#[path = "lens_gyroflow_ref/gf.rs"]
mod gf;
use gf::Gf;
use std::path::{Path, PathBuf};

fn write_tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mmbm-lensgf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn resolve(path: &Path, video: Option<(u32, u32)>, focal: Option<f64>) -> mmbm::Result<Camera> {
    let over = CameraOverrides {
        keys: CameraFile::default(),
        scale_to: video,
        light_e_per_s: None,
        lens_focal_mm: focal,
    };
    Camera::resolve(Some(path), &over)
}

const W: [f64; 3] = [0.4, -0.3, 0.7];

/// mmbm's MMBM (riemann on the same grid) against `Gf`'s: the relative
/// difference, and the masked shares (`Gf`'s, mmbm's).
fn compare(c: &Camera, p: &Value, nu: u32, nv: u32) -> (f64, f64, f64) {
    let scene = Scene {
        camera: *c,
        plane: None,
    };
    let m = mmbm(
        &scene,
        &Twist::rotation(W[0], W[1], W[2]),
        Method::Riemann { nu, nv },
    )
    .unwrap()
    .mm_s;
    let (g, masked) = Gf::new(p).mean_speed(W, (c.pitch_x_mm, c.pitch_y_mm), nu, nv);
    ((m - g).abs() / g, masked, c.masked_fraction())
}

/// [`compare`]'s relative difference, the masked shares checked to agree within 2 %.
fn agreement(c: &Camera, p: &Value, nu: u32, nv: u32) -> f64 {
    let (d, g, m) = compare(c, p, nu, nv);
    assert!((g - m).abs() < 0.02, "masked {g} vs {m}");
    d
}

fn profile(model: &str, coeffs: &[f64], extra: Value) -> Value {
    let mut p = json!({
        "calib_dimension": {"w": 1920, "h": 1080},
        "distortion_model": model,
        "fisheye_params": {
            "camera_matrix": [[1100.0, 0.0, 955.0], [0.0, 1090.0, 545.0], [0.0, 0.0, 1.0]],
            "distortion_coeffs": coeffs,
        },
    });
    for (k, v) in extra.as_object().unwrap() {
        p[k] = v.clone();
    }
    p
}

/// Each model's coefficients (monotone over the sensor).
fn models() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("opencv_fisheye", vec![0.03, -0.01, 0.004, -0.001]),
        ("poly3", vec![0.02]),
        ("poly5", vec![-0.05, 0.004]),
        ("ptlens", vec![0.002, -0.01, -0.02]),
        ("sony", vec![0.98, 0.01, -0.04, 0.01, -0.002, 0.0001]),
        (
            "generic_polynomial",
            vec![
                1.0, 0.0, -0.03, 0.0, 0.002, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            ],
        ),
        (
            "insta360",
            vec![-0.02, 0.003, -0.0002, 0.0004, -0.0003, 0.2],
        ),
        (
            "opencv_standard",
            vec![
                -0.21, 0.05, 0.0012, -0.0009, -0.004, 0.08, -0.02, 0.006, 0.0021, -0.0007, -0.0015,
                0.0004,
            ],
        ),
    ]
}

#[test]
fn every_model_and_digital_lens_maps_and_measures_as_gyroflow() {
    let mut stretch = vec![0.0; 16];
    stretch[0] = 1.1;
    stretch[1] = 0.95;
    let lenses = [
        json!({}),
        json!({"digital_lens": "gopro_superview"}),
        json!({"digital_lens": "gopro6_superview"}),
        json!({"digital_lens": "gopro_hyperview"}),
        json!({"digital_lens": "digital_stretch", "digital_lens_params": stretch}),
    ];
    for (model, k) in models() {
        for extra in &lenses {
            let p = profile(model, &k, extra.clone());
            let what = format!("{model} {extra}");
            let c = resolve(&write_tmp("m.json", &p.to_string()), None, None)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            let gf = Gf::new(&p);
            // The ray of a pixel, and the pixel of that ray.
            let mut worst: f64 = 0.0;
            for &(px, py) in &[
                (960.0, 540.0),
                (100.0, 80.0),
                (1800.0, 1000.0),
                (1500.0, 300.0),
                (400.0, 900.0),
            ] {
                let (gx, gy) = gf.ray(px, py).unwrap();
                let (rx, ry) = c.pixel_to_ray(px, py).expect("undistorts");
                worst = worst.max(1000.0 * (rx - gx).hypot(ry - gy));
                let (a, b) = c.ray_to_pixel(gx, gy);
                let (ga, gb) = gf.project([gx, gy, 1.0]).unwrap();
                worst = worst
                    .max((a - ga).hypot(b - gb))
                    .max((a - px).hypot(b - py));
            }
            assert!(worst < 1e-7, "{what}: {worst:e} px");
            assert_eq!(c.masked_fraction(), 0.0, "{what}");
            let d = agreement(&c, &p, 64, 36);
            assert!(d < 1e-6, "{what}: MMBM differs by {d:e}");
        }
    }
}

#[test]
fn gpu_kernel_takes_the_other_models_through_its_lens_table() {
    // Per pixel against the twin and the CPU metric: cli/tests/camera/gpu_lens.rs.
    let p = profile("poly5", &[-0.05, 0.004], json!({}));
    let c = resolve(&write_tmp("g.json", &p.to_string()), None, None).unwrap();
    assert!(mmbm::field::Grid::new(&c, 0, 0).unwrap().uses_table());
    let p = profile(
        "opencv_fisheye",
        &[0.03],
        json!({"digital_lens": "gopro_superview"}),
    );
    let c = resolve(&write_tmp("g.json", &p.to_string()), None, None).unwrap();
    assert!(mmbm::field::Grid::new(&c, 0, 0).unwrap().uses_table());
    // The analytic fisheye without a mask needs none.
    let p = profile("opencv_fisheye", &[0.03, -0.01, 0.004, -0.001], json!({}));
    let c = resolve(&write_tmp("g.json", &p.to_string()), None, None).unwrap();
    assert!(!mmbm::field::Grid::new(&c, 0, 0).unwrap().uses_table());
}

#[test]
fn compatible_settings_follow_the_video_size() {
    let mut p = profile(
        "opencv_fisheye",
        &[0.03, -0.01, 0.0, 0.0],
        json!({"frame_readout_time": 20.0}),
    );
    p["calib_dimension"] = json!({"w": 4000, "h": 3000});
    p["fisheye_params"]["camera_matrix"] = json!([
        [2000.0, 0.0, 2000.0],
        [0.0, 2000.0, 1500.0],
        [0.0, 0.0, 1.0]
    ]);
    p["compatible_settings"] = json!([
        {"width": 2000, "height": 1500, "frame_readout_time": 10.0},
        {"width": 1920, "height": 1080, "frame_readout_time": 8.0, "distortion_coeffs": [0.05]},
    ]);
    let path = write_tmp("cs.json", &p.to_string());
    let base = resolve(&path, None, None).unwrap();
    assert_eq!((base.width, base.shutter.readout_s), (4000, 0.020));
    // Same aspect: the matrix scales with the size.
    let c = resolve(&path, Some((2000, 1500)), None).unwrap();
    assert_eq!(c.shutter.readout_s, 0.010);
    assert!((c.fx_px() - 1000.0).abs() < 1e-9, "{}", c.fx_px());
    // Another aspect: a sensor crop (calibration 1920 x 1440 scaled by the
    // width, 1080 by the height: the matrix stays), its coefficients over the profile's.
    let c = resolve(&path, Some((1920, 1080)), None).unwrap();
    assert_eq!(c.shutter.readout_s, 0.008);
    assert!((c.fx_px() - 2000.0).abs() < 1e-9, "{}", c.fx_px());
    assert_eq!(c.distortion.parts().1[..2], [0.05, -0.01]);
    // A portrait video of that size matches the entry too (turned).
    let c = resolve(&path, Some((1080, 1920)), None).unwrap();
    assert_eq!(c.shutter.readout_s, 0.008);
    // No entry of that size or aspect: the profile, scaled.
    let c = resolve(&path, Some((1000, 1000)), None).unwrap();
    assert_eq!(c.shutter.readout_s, 0.020);
}

#[test]
fn interpolations_by_focal_length() {
    let mut p = profile(
        "opencv_fisheye",
        &[0.01, 0.0, 0.0, 0.0],
        json!({"focal_length": 14.0}),
    );
    p["interpolations"] = json!({
        "14": {"camera_matrix": [[1000.0, 0.0, 960.0], [0.0, 1000.0, 540.0], [0.0, 0.0, 1.0]],
               "distortion_coeffs": [0.02, 0.0, 0.0, 0.0], "focal_length": 14},
        "24": {"camera_matrix": [[2000.0, 0.0, 960.0], [0.0, 2000.0, 540.0], [0.0, 0.0, 1.0]],
               "distortion_coeffs": [0.04, 0.0, 0.0, 0.0], "focal_length": 24},
    });
    let path = write_tmp("zoom.json", &p.to_string());
    // Default: the profile itself (Gyroflow without lens metadata).
    let c = resolve(&path, None, None).unwrap();
    assert!((c.fx_px() - 1100.0).abs() < 1e-9);
    let at = |f: f64| resolve(&path, None, Some(f)).unwrap();
    let c = at(14.0);
    assert!((c.fx_px() - 1000.0).abs() < 1e-9 && (c.focal_mm - 14.0).abs() < 1e-12);
    let c = at(19.0);
    assert!((c.fx_px() - 1500.0).abs() < 1e-9, "{}", c.fx_px());
    assert!((c.distortion.parts().1[0] - 0.03).abs() < 1e-12 && (c.focal_mm - 19.0).abs() < 1e-9);
    // Beyond the ends: extrapolated from the last two entries (as Gyroflow).
    let c = at(30.0);
    assert!((c.fx_px() - 2600.0).abs() < 1e-9, "{}", c.fx_px());
    let e = resolve(&path, None, Some(-3.0)).unwrap_err().to_string();
    assert!(e.contains("focal length"), "{e}");
}

#[test]
fn stored_radial_limit_is_recomputed_as_gyroflow_does() {
    let mut p = profile("opencv_fisheye", &[1.0, -0.8, 0.0, 0.0], json!({}));
    // The corner at 1.8 normalised, beyond the limit 1.2.
    p["fisheye_params"]["camera_matrix"] =
        json!([[600.0, 0.0, 960.0], [0.0, 600.0, 540.0], [0.0, 0.0, 1.0]]);
    let plain = resolve(&write_tmp("r.json", &p.to_string()), None, None).unwrap();
    let mut q = p.clone();
    q["fisheye_params"]["radial_distortion_limit"] = json!(0.1);
    let stored = resolve(&write_tmp("r.json", &q.to_string()), None, None).unwrap();
    assert_eq!(plain, stored);
    assert!(plain.masked_fraction() > 0.0);
    let mut q = profile("opencv_fisheye", &[], json!({}));
    q["fisheye_params"]["radial_distortion_limit"] = json!(1.5);
    let e = resolve(&write_tmp("r.json", &q.to_string()), None, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("radial_distortion_limit"), "{e}");
}

/// A telephoto fisheye calibration whose polynomial turns down before
/// pi/2 and up again (Sony a6700 at 50 mm in the database): Gyroflow
/// computes no radial limit, and every in-sensor pixel's ray is the root on
/// the first branch (Gyroflow's Newton from theta_d), not a later one.
#[test]
fn a_fisheye_that_turns_back_up_keeps_the_first_branch() {
    let mut p = profile(
        "opencv_fisheye",
        &[
            -0.22452861677115005,
            217.17550024300397,
            -10296.464062136569,
            48050.180651557894,
        ],
        json!({}),
    );
    p["calib_dimension"] = json!({"w": 3840, "h": 2160});
    p["fisheye_params"]["camera_matrix"] = json!([
        [19347.33097906391, 0.0, 2048.20702350777],
        [0.0, 19733.029810849617, 1059.8731880951857],
        [0.0, 0.0, 1.0]
    ]);
    let c = resolve(&write_tmp("tele.json", &p.to_string()), None, None).unwrap();
    assert_eq!(c.masked_fraction(), 0.0);
    assert!(agreement(&c, &p, 64, 36) < 1e-6);
}

#[test]
fn a_superview_calibration_at_4_3_is_widened() {
    let mut p = profile(
        "opencv_fisheye",
        &[0.05, 0.01, 0.0, 0.0],
        json!({"digital_lens": "gopro_superview"}),
    );
    p["calib_dimension"] = json!({"w": 2704, "h": 2028});
    let c = resolve(&write_tmp("sv.json", &p.to_string()), None, None).unwrap();
    assert_eq!((c.width, c.height, c.cx), (3605, 2028, 1802.5));
    assert!(agreement(&c, &p, 120, 68) < 1e-6);
}

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/lens_profiles");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    v.sort();
    v
}

fn read(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap();
    serde_json::from_str(text.trim_start_matches('\u{feff}')).unwrap()
}

#[test]
fn real_profiles_load_and_agree_with_gyroflow() {
    let files = fixtures();
    assert!(files.len() >= 30, "{} fixtures", files.len());
    let mut worst: (f64, String) = (0.0, String::new());
    let mut bad = Vec::new();
    for f in &files {
        let c = resolve(f, None, None).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let (d, g, m) = compare(&c, &read(f), 160, 90);
        if (g - m).abs() >= 0.02 || d >= 1e-3 {
            bad.push(format!(
                "{}: MMBM differs by {d:e}, masked {g} vs {m}",
                f.display()
            ));
        }
        if d > worst.0 {
            worst = (d, f.display().to_string());
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
    println!("worst MMBM difference {:e} ({})", worst.0, worst.1);
}

/// The whole database: `MMBM_LENS_DB=DIR cargo test --release --test
/// metric -- --ignored --nocapture whole_database` prints the share loaded, the
/// refusals grouped by message, and the MMBM agreement over every `step`-th
/// loaded profile (`MMBM_LENS_STEP`, default 10).
#[test]
#[ignore]
fn whole_database() {
    let Ok(dir) = std::env::var("MMBM_LENS_DB") else {
        panic!("set MMBM_LENS_DB to a checkout of gyroflow/lens_profiles");
    };
    let step: usize = std::env::var("MMBM_LENS_STEP").map_or(10, |s| s.parse().unwrap());
    let mut files = Vec::new();
    let mut stack = vec![PathBuf::from(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "json") {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut refused: std::collections::BTreeMap<String, usize> = Default::default();
    let (mut loaded, mut compared, mut over) = (0usize, 0usize, Vec::new());
    let mut diffs = Vec::new();
    for (i, f) in files.iter().enumerate() {
        match resolve(f, None, None) {
            Err(e) => {
                let msg = e.to_string();
                let key = msg.split(": ").skip(1).collect::<Vec<_>>().join(": ");
                let key: String = key
                    .chars()
                    .filter(|c| !c.is_ascii_digit())
                    .take(90)
                    .collect();
                *refused.entry(key).or_default() += 1;
            }
            Ok(c) => {
                loaded += 1;
                if i % step == 0 {
                    let (d, g, m) = compare(&c, &read(f), 64, 36);
                    if (g - m).abs() >= 0.02 {
                        over.push((g - m, format!("masked share {g} vs {m}: {}", f.display())));
                    }
                    compared += 1;
                    diffs.push(d);
                    if d > 1e-3 {
                        over.push((d, f.display().to_string()));
                    }
                }
            }
        }
    }
    diffs.sort_by(f64::total_cmp);
    println!(
        "profiles {}, loaded {} ({:.2} %), compared {compared}, median diff {:e}, max {:e}, over 0.1 %: {}",
        files.len(),
        loaded,
        100.0 * loaded as f64 / files.len() as f64,
        diffs[diffs.len() / 2],
        diffs[diffs.len() - 1],
        over.len()
    );
    for (k, n) in &refused {
        println!("refused {n}: {k}");
    }
    for (d, f) in &over {
        println!("over: {d:e} {f}");
    }
}
