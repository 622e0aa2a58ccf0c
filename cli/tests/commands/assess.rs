//! Image blur metrics against scikit-image/SciPy reference values and on
//! images with a known, growing blur.

use crate::common;

use image::{GrayImage, Luma};
use mmbm::assess::{
    assess, blur_effect, blur_effect_axes, cpbd, jnbm, jnbm_report, laplacian_var, load_grey,
};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    crate::common::repo_root().join("tests/fixtures").join(name)
}

fn values() -> serde_json::Value {
    let s = std::fs::read_to_string(fixture("values.json")).unwrap();
    serde_json::from_str(&s).unwrap()
}

const FIXTURES: [&str; 4] = [
    "camera.png",
    "camera_motion9.png",
    "astronaut.png",
    "bars.png",
];

#[test]
fn blur_effect_equals_scikit_image() {
    let v = values();
    for name in FIXTURES {
        let g = load_grey(&fixture(name)).unwrap();
        let want = &v[name];
        assert_eq!(g.width() as u64, want["width"].as_u64().unwrap());
        assert_eq!(g.height() as u64, want["height"].as_u64().unwrap());
        let got = blur_effect(&g).unwrap();
        let exp = want["blur_effect"].as_f64().unwrap();
        // required 1e-3; the port is exact up to summation order
        assert!((got - exp).abs() < 1e-9, "{name}: {got} vs skimage {exp}");
        let axes = blur_effect_axes(&g, 11).unwrap();
        for (ax, got) in axes.iter().enumerate() {
            let exp = want["blur_effect_axes"][ax].as_f64().unwrap();
            assert!((got - exp).abs() < 1e-9, "{name} axis {ax}: {got} vs {exp}");
        }
    }
}

#[test]
fn laplacian_variance_equals_scipy() {
    let v = values();
    for name in FIXTURES {
        let g = load_grey(&fixture(name)).unwrap();
        let got = laplacian_var(&g).unwrap();
        let exp = v[name]["laplacian_var"].as_f64().unwrap();
        assert!(
            ((got - exp) / exp).abs() < 1e-9,
            "{name}: {got} vs scipy {exp}"
        );
    }
}

/// Horizontal motion blur: mean of `len` pixels centred on each pixel
/// (clamped border), rounded to 8 bits.
fn motion_blur(g: &GrayImage, len: u32) -> GrayImage {
    let r = (len / 2) as i64;
    let w = g.width() as i64;
    GrayImage::from_fn(g.width(), g.height(), |x, y| {
        let s: f64 = (-r..=r)
            .map(|d| g.get_pixel((x as i64 + d).clamp(0, w - 1) as u32, y)[0] as f64)
            .sum();
        Luma([(s / (2 * r + 1) as f64).round() as u8])
    })
}

/// Synthetic scene: seeded random grey rectangles over a mid-grey ground.
fn rectangles(w: u32, h: u32, seed: u64) -> GrayImage {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut g = GrayImage::from_pixel(w, h, Luma([128]));
    for _ in 0..40 {
        let (x0, y0) = (rng.gen_range(0..w), rng.gen_range(0..h));
        let (rw, rh) = (rng.gen_range(6..60), rng.gen_range(6..60));
        let c = rng.gen_range(0..=255u8);
        for y in y0..(y0 + rh).min(h) {
            for x in x0..(x0 + rw).min(w) {
                g.put_pixel(x, y, Luma([c]));
            }
        }
    }
    g
}

fn check_monotone(label: &str, base: &GrayImage) {
    let lens = [1, 3, 5, 9, 15, 25];
    let mut prev: Option<(f64, f64, f64, f64)> = None;
    for len in lens {
        let img = motion_blur(base, len);
        let j = jnbm(&img).unwrap();
        let c = cpbd(&img).unwrap();
        let b = blur_effect(&img).unwrap();
        let l = laplacian_var(&img).unwrap();
        eprintln!("{label} len {len:2}: jnbm {j:.4} cpbd {c:.4} blur_effect {b:.4} lapvar {l:.2}");
        assert!(j.is_finite() && j > 0.0);
        if let Some((pj, pc, pb, pl)) = prev {
            assert!(
                j < pj,
                "{label}: JNBM must fall with blur: {pj} -> {j} at len {len}"
            );
            // CPBD saturates near 0 for heavy blur (a few sharp corner pixels
            // remain under horizontal blur): allow 0.005 of jitter there
            assert!(
                c <= pc + 0.005,
                "{label}: CPBD must not rise with blur: {pc} -> {c} at len {len}"
            );
            assert!(
                b > pb,
                "{label}: blur effect must rise: {pb} -> {b} at len {len}"
            );
            assert!(l < pl, "{label}: Laplacian variance must fall: {pl} -> {l}");
        }
        prev = Some((j, c, b, l));
    }
    // the heaviest blur is clearly separated from the sharp image
    let sharp = jnbm(base).unwrap();
    let heavy = jnbm(&motion_blur(base, 25)).unwrap();
    assert!(heavy < 0.5 * sharp, "{label}: {sharp} vs {heavy}");
    // the authors' CPBD keeps every Sobel pixel with |gradient| > 2 grey
    // levels/px, and on 8-bit rounded blur the strictly monotone walk stops at
    // the first flat step: many short widths survive heavy blur, so CPBD
    // does not fall to 0 (0.21 on camera at 25 px)
    let c_sharp = cpbd(base).unwrap();
    let c_heavy = cpbd(&motion_blur(base, 25)).unwrap();
    assert!(
        c_heavy < 0.35 * c_sharp,
        "{label}: CPBD of heavy blur {c_heavy} vs sharp {c_sharp}"
    );
}

#[test]
fn metrics_monotone_in_blur_natural_image() {
    let g = load_grey(&fixture("camera.png")).unwrap();
    check_monotone("camera", &g);
}

#[test]
fn metrics_monotone_in_blur_synthetic_image() {
    check_monotone("rectangles", &rectangles(256, 192, 3));
}

#[test]
fn jnbm_falls_with_gaussian_blur() {
    let g = load_grey(&fixture("astronaut.png")).unwrap();
    let mut prev = f64::INFINITY;
    for sigma in [0.0f32, 1.0, 2.0, 4.0] {
        let img = if sigma == 0.0 {
            g.clone()
        } else {
            imageproc::filter::gaussian_blur_f32(&g, sigma)
        };
        let r = jnbm_report(&img).unwrap();
        let j = r.jnbm.unwrap();
        eprintln!(
            "astronaut sigma {sigma}: jnbm {j:.4} ({} edge blocks of {}, {} edges, mean width {:.2})",
            r.edge_blocks, r.blocks, r.edges, r.mean_width
        );
        assert!(j < prev, "sigma {sigma}: {j} !< {prev}");
        prev = j;
    }
}

#[test]
fn colour_image_uses_rec601_luma() {
    // the RGB fixture's reference values were computed on the same integer luma
    let rgb = mmbm::io::images::read_rgb8(&fixture("astronaut.png")).unwrap();
    let g = mmbm::assess::luma(&rgb);
    assert_eq!(g, load_grey(&fixture("astronaut.png")).unwrap());
    let p = rgb.get_pixel(100, 100).0;
    let y = (299 * p[0] as u32 + 587 * p[1] as u32 + 114 * p[2] as u32 + 500) / 1000;
    assert_eq!(g.get_pixel(100, 100)[0] as u32, y);
}

#[test]
fn undefined_and_bad_inputs() {
    // flat: JNBM undefined (None, error from jnbm()), CPBD 0, blur effect 1
    let flat = GrayImage::from_pixel(128, 128, Luma([200]));
    let a = assess(&flat).unwrap();
    assert_eq!(a.jnbm, None);
    assert_eq!(a.cpbd, 0.0);
    assert_eq!(a.jnbm_2d, None);
    assert_eq!(a.cpbd_2d, 0.0);
    assert_eq!(a.blur_effect, 1.0);
    assert_eq!(a.laplacian_var, 0.0);
    assert!(jnbm(&flat).is_err());
    // too small for a 64x64 block
    let small = GrayImage::from_pixel(100, 50, Luma([1]));
    let e = assess(&small).unwrap_err().to_string();
    assert!(e.contains("100x50"), "{e}");
    // unreadable file names the path
    let e = load_grey(&fixture("values.json")).unwrap_err().to_string();
    assert!(e.contains("values.json"), "{e}");
    let e = load_grey(&fixture("missing.png")).unwrap_err().to_string();
    assert!(e.contains("missing.png"), "{e}");
}

#[test]
fn cli_json_in_argument_order() {
    let v = values();
    let names = ["camera_motion9.png", "camera.png"];
    let out = common::mmbm_cmd()
        .arg("assess")
        .args(names.iter().map(|n| fixture(n)))
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let arr = j.as_array().unwrap();
    assert_eq!(arr.len(), 2);
    for (o, n) in arr.iter().zip(names) {
        assert!(o["path"].as_str().unwrap().ends_with(n));
        let be = o["blur_effect"].as_f64().unwrap();
        assert!((be - v[n]["blur_effect"].as_f64().unwrap()).abs() < 1e-9);
        assert!(o["laplacian_var"].as_f64().unwrap() > 0.0);
        assert!(o["cpbd"].as_f64().unwrap() >= 0.0);
        assert!(o["jnbm"].as_f64().unwrap() > 0.0);
        assert!(o["cpbd_2d"].as_f64().unwrap() >= 0.0);
        assert!(o["jnbm_2d"].as_f64().unwrap() > 0.0);
    }
    assert!(arr[0]["jnbm"].as_f64().unwrap() < arr[1]["jnbm"].as_f64().unwrap());
}

#[test]
fn cli_text_and_errors() {
    let out = common::mmbm_cmd()
        .arg("assess")
        .arg(fixture("bars.png"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.contains("jnbm") && s.contains("bars.png"), "{s}");
    assert!(s.contains("jnbm_2d") && s.contains("cpbd_2d"), "{s}");

    let out = common::mmbm_cmd()
        .arg("assess")
        .arg(fixture("camera.png"))
        .arg(fixture("nope.png"))
        .arg("--json")
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(out.stdout.is_empty(), "nothing printed on failure");
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("nope.png"), "{e}");
}
