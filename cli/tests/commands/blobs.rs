//! Blob extraction on synthesized images of the thesis board: sharp -> 16/16
//! OK, heavy motion blur -> failure.

use crate::common;

use image::RgbImage;
use mmbm::board::blobs::{evaluate, extract, BlobParams};
use mmbm::board::{board_centres_px, Board};
use mmbm::io::images::{linear_to_srgb8, srgb8_to_linear};
use mmbm::Camera;

const RED: [u8; 3] = [200, 25, 30];
const WHITE: [u8; 3] = [235, 235, 235];

fn overlap(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    (a1.min(b1) - a0.max(b0)).max(0.0)
}

/// The board fronto-parallel at `d` m, shifted by `(sx, sy)` px, drawn with
/// exact area coverage per pixel (blend in linear light), then blurred
/// horizontally by a box of `blur` px (odd, linear light), sRGB out, plus
/// seeded Gaussian noise of `noise` grey levels.
fn draw(
    cam: &Camera,
    board: &Board,
    d: f64,
    shift: (f64, f64),
    blur: usize,
    noise: f64,
) -> RgbImage {
    let (centres, _) = board_centres_px(cam, board, d).unwrap();
    let half = cam.focal_mm * board.square_m / d / cam.pitch_x_mm / 2.0;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut cov = vec![0.0f64; w * h];
    for &(cx, cy) in &centres {
        let (cx, cy) = (cx + shift.0, cy + shift.1);
        let (x0, x1, y0, y1) = (cx - half, cx + half, cy - half, cy + half);
        for y in (y0.floor().max(0.0) as usize)..(y1.ceil() as usize).min(h) {
            for x in (x0.floor().max(0.0) as usize)..(x1.ceil() as usize).min(w) {
                let xf = x as f64;
                let yf = y as f64;
                cov[y * w + x] += overlap(xf, xf + 1.0, x0, x1) * overlap(yf, yf + 1.0, y0, y1);
            }
        }
    }
    let r = (blur / 2) as isize;
    let lin = |c: [u8; 3], k: usize| srgb8_to_linear(c[k]) as f64;
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(11);
    let normal = rand_distr::Normal::new(0.0, noise.max(1e-12)).unwrap();
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let mut c = 0.0;
        for k in -r..=r {
            let xx = (x as isize + k).clamp(0, w as isize - 1) as usize;
            c += cov[y as usize * w + xx];
        }
        let c = c / (2 * r + 1) as f64;
        let mut px = [0u8; 3];
        for (k, p) in px.iter_mut().enumerate() {
            let v = c * lin(RED, k) + (1.0 - c) * lin(WHITE, k);
            let s = linear_to_srgb8(v as f32) as f64;
            let n: f64 = if noise > 0.0 {
                rand::Rng::sample(&mut rng, normal)
            } else {
                0.0
            };
            *p = (s + n).round().clamp(0.0, 255.0) as u8;
        }
        image::Rgb(px)
    })
}

fn cam() -> Camera {
    Camera::thesis().with_resolution(320, 240)
}

fn run(
    board: &Board,
    d: f64,
    shift: (f64, f64),
    blur: usize,
    noise: f64,
) -> mmbm::board::blobs::BlobResult {
    let c = cam();
    let img = draw(&c, board, d, shift, blur, noise);
    let blobs = extract(&img, &BlobParams::default()).unwrap();
    let (exp, pitch) = board_centres_px(&c, board, d).unwrap();
    evaluate(&blobs, &exp, pitch).unwrap()
}

#[test]
fn sharp_board_gives_16_of_16() {
    for (board, d) in [
        (Board::thesis(), 3.0),
        (Board::thesis(), 6.0),
        (Board::half(), 4.0),
    ] {
        let r = run(&board, d, (0.0, 0.0), 1, 0.0);
        assert!(r.ok, "{board:?} at {d} m: {r:?}");
        assert_eq!((r.found, r.matched, r.false_blobs), (16, 16, 0));
        // exact coverage: centroid error from the mask is sub-pixel
        assert!(r.max_error_px.unwrap() < 0.5, "{r:?}");
    }
}

#[test]
fn mild_blur_and_noise_still_ok() {
    let r = run(&Board::thesis(), 3.0, (0.0, 0.0), 5, 3.0);
    assert!(r.ok, "{r:?}");
    assert!(r.max_error_px.unwrap() < 1.0, "{r:?}");
}

#[test]
fn heavy_motion_blur_fails() {
    // at 6 m: squares 15.2 px, gaps 3 px; a 15-px box fuses each row of squares
    let r = run(&Board::thesis(), 6.0, (0.0, 0.0), 15, 0.0);
    assert!(!r.ok, "{r:?}");
    assert!(r.found < 16, "{r:?}");
    eprintln!("heavy blur: {r:?}");
    assert!(r.missed > 0, "{r:?}");
}

#[test]
fn misplaced_board_is_not_matched() {
    // the whole board one pitch to the right: every blob sits on the true
    // centre of its right-hand neighbour, so 12 centres are (wrongly) matched,
    // the left column is missed and the blobs right of the board are false
    let c = cam();
    let (_, pitch) = board_centres_px(&c, &Board::thesis(), 3.0).unwrap();
    let r = run(&Board::thesis(), 3.0, (pitch, 0.0), 1, 0.0);
    assert_eq!(r.found, 16);
    assert_eq!((r.matched, r.missed, r.false_blobs), (12, 4, 4));
    assert!(!r.ok);
    // half a pitch off: nothing within tolerance
    let r = run(&Board::thesis(), 3.0, (0.5 * pitch, 0.5 * pitch), 1, 0.0);
    assert_eq!(r.matched, 0);
}

#[test]
fn no_red_no_blobs() {
    let img = RgbImage::from_pixel(160, 120, image::Rgb(WHITE));
    assert!(extract(&img, &BlobParams::default()).unwrap().is_empty());
    let bad = BlobParams {
        threshold: Some(f64::NAN),
        ..BlobParams::default()
    };
    assert!(extract(&img, &bad).is_err());
}

#[test]
fn cli_blobs() {
    let dir = tempfile::tempdir().unwrap();
    let sharp = dir.path().join("sharp.png");
    let blurred = dir.path().join("blurred.png");
    let c = cam();
    draw(&c, &Board::thesis(), 6.0, (0.0, 0.0), 1, 0.0)
        .save(&sharp)
        .unwrap();
    draw(&c, &Board::thesis(), 6.0, (0.0, 0.0), 15, 0.0)
        .save(&blurred)
        .unwrap();
    let mask = dir.path().join("mask.png");
    for (img, ok) in [(&sharp, true), (&blurred, false)] {
        let out = common::mmbm_cmd()
            .args([
                "blobs",
                img.to_str().unwrap(),
                "--target",
                "blobs",
                "--distance",
                "6",
            ])
            .args([
                "--sensor",
                "320x240",
                "--json",
                "--mask",
                mask.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(j["result"]["ok"].as_bool().unwrap(), ok, "{j}");
        assert_eq!(j["blobs"].as_array().unwrap().len() == 16, ok);
    }
    let m = image::open(&mask).unwrap().to_luma8();
    assert_eq!(m.dimensions(), (320, 240));

    // --expected file
    let (exp, pitch) = board_centres_px(&c, &Board::thesis(), 6.0).unwrap();
    let ef = dir.path().join("truth.json");
    std::fs::write(
        &ef,
        serde_json::json!({"centres_px": exp, "pitch_px": pitch}).to_string(),
    )
    .unwrap();
    let out = common::mmbm_cmd()
        .args([
            "blobs",
            sharp.to_str().unwrap(),
            "--expected",
            ef.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && s.contains("OK"), "{s}");

    // errors: camera/image size mismatch, unreadable image
    let out = common::mmbm_cmd()
        .args(["blobs", sharp.to_str().unwrap(), "--distance", "6"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("320x240"));
    let out = common::mmbm_cmd()
        .args(["blobs", "/nonexistent/x.png"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.png"));
}

/// `mmbm blobs --target` takes `render --target`'s names: a half-size board
/// drawn at 3 m is found with `blobs:0.5` and with its alias `blobs-half`, and
/// not with the full board's centres; a bad board name is clap's error.
#[test]
fn blobs_target_takes_the_render_names() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("half.png");
    draw(&cam(), &Board::half(), 3.0, (0.0, 0.0), 1, 0.0)
        .save(&img)
        .unwrap();
    let run = |target: &str| {
        let out = common::mmbm_cmd()
            .arg("blobs")
            .arg(&img)
            .args([
                "--target",
                target,
                "--distance",
                "3",
                "--sensor",
                "320x240",
                "--json",
            ])
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    for t in ["blobs:0.5", "blobs-half"] {
        let (code, out) = run(t);
        assert_eq!(code, Some(0), "{t}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(j["result"]["ok"].as_bool().unwrap(), "{t}: {j}");
    }
    let (code, out) = run("blobs");
    assert_eq!(code, Some(0));
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(!j["result"]["ok"].as_bool().unwrap(), "{j}");
    assert_eq!(run("blobs:-1").0, Some(2));
}
