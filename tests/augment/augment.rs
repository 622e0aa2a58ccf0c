//! `mmbm::augment` (Python `mmbm.augment`): the homographies it returns
//! carry a point of the image to where the blurred frame shows it (the
//! brightness centroid of a dot's streak is its mid-exposure place; its
//! streak runs from the start to the end homography's place), centring
//! removes the net shift, the maps' path length is the streak's, and bad
//! inputs are clear errors.

use glam::{DMat3, DVec3};
use mmbm::augment::{augment, Augment, Motion};
use mmbm::Twist;

const W: u32 = 96;
const H: u32 = 72;

/// A black image with a bright 2 x 2 dot whose centre is at `(x, y)` px.
fn dot(x: u32, y: u32) -> Vec<f32> {
    let mut v = vec![0.0f32; (W * H * 3) as usize];
    for j in y - 1..=y {
        for i in x - 1..=x {
            for c in 0..3 {
                v[((j * W + i) * 3 + c) as usize] = 1.0;
            }
        }
    }
    v
}

fn apply(h: &[f64; 9], x: f64, y: f64) -> (f64, f64) {
    let m = DMat3::from_cols_array(h).transpose();
    let p = m * DVec3::new(x, y, 1.0);
    (p.x / p.z, p.y / p.z)
}

fn centroid(rgb: &[f32]) -> (f64, f64, f64) {
    let (mut s, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for j in 0..H {
        for i in 0..W {
            let g = rgb[((j * W + i) * 3 + 1) as usize] as f64;
            s += g;
            sx += g * (i as f64 + 0.5);
            sy += g * (j as f64 + 0.5);
        }
    }
    (sx / s, sy / s, s)
}

/// A yaw and a little pitch: about 20 px of streak over 30 ms.
fn motion() -> Motion {
    Motion::Twist(Twist::new(DVec3::new(0.05, 0.7, 0.1), DVec3::ZERO))
}

#[test]
fn homographies_carry_a_point_to_its_streak() {
    let img = dot(40, 30);
    let mut a = Augment::new(motion(), 0.03);
    a.maps = true;
    let out = augment(W, H, &img, &a).unwrap();
    // At exposure start the image fills the view: the identity.
    let (x0, y0) = apply(&out.homographies[0], 40.0, 30.0);
    assert!(
        (x0 - 40.0).abs() < 1e-9 && (y0 - 30.0).abs() < 1e-9,
        "{x0} {y0}"
    );
    let (x2, y2) = apply(&out.homographies[2], 40.0, 30.0);
    let len = (x2 - x0).hypot(y2 - y0);
    assert!(len > 15.0 && len < 30.0, "streak {len} px");
    // The dot's light is kept, and its centroid is the mid-exposure place.
    let (cx, cy, s) = centroid(&out.rgb);
    assert!((s - 4.0).abs() < 0.05, "light {s}");
    let (x1, y1) = apply(&out.homographies[1], 40.0, 30.0);
    assert!(
        (cx - x1).abs() < 0.15 && (cy - y1).abs() < 0.15,
        "centroid ({cx}, {cy}) vs ({x1}, {y1})"
    );
    // The maps' path length at the dot is the streak's length.
    let k = (30 * W + 40) as usize;
    let path = out.maps.expect("maps asked for").path_px[k] as f64;
    assert!((path - len).abs() < 0.05 * len, "path {path} vs {len}");
}

#[test]
fn centring_removes_the_net_shift() {
    let img = dot(40, 30);
    let mut a = Augment::new(motion(), 0.03);
    a.sharp = mmbm::render::SharpAt::Mid;
    let out = augment(W, H, &img, &a).unwrap();
    let (x1, y1) = apply(&out.homographies[1], 40.0, 30.0);
    assert!(
        (x1 - 40.0).abs() < 1e-3 && (y1 - 30.0).abs() < 1e-3,
        "{x1} {y1}"
    );
    let (cx, cy, _) = centroid(&out.rgb);
    assert!(
        (cx - 40.0).abs() < 0.15 && (cy - 30.0).abs() < 0.15,
        "({cx}, {cy})"
    );
    // Start and end lie on either side, half a streak each.
    let (xa, _) = apply(&out.homographies[0], 40.0, 30.0);
    let (xb, _) = apply(&out.homographies[2], 40.0, 30.0);
    assert!(
        (xa - 40.0 + (xb - 40.0)).abs() < 0.3 && (xa - xb).abs() > 15.0,
        "{xa} {xb}"
    );
}

#[test]
fn drawn_motions_follow_the_seed() {
    let img: Vec<f32> = (0..W * H * 3)
        .map(|i| ((i * 7919) % 251) as f32 / 250.0)
        .collect();
    let mut a = Augment::new(Motion::Shake, 0.02);
    a.seed = 5;
    let x = augment(W, H, &img, &a).unwrap();
    let y = augment(W, H, &img, &a).unwrap();
    assert_eq!(x.rgb, y.rgb);
    assert_eq!(x.motion, y.motion);
    assert!(x.motion.starts_with("sim:"), "{}", x.motion);
    a.seed = 6;
    let z = augment(W, H, &img, &a).unwrap();
    assert!(z.rgb != x.rgb && z.motion != x.motion);
}

#[test]
fn bad_inputs_are_clear_errors() {
    let img = dot(40, 30);
    let a = Augment::new(motion(), 0.03);
    let e = augment(W, H - 1, &img, &a).unwrap_err().to_string();
    assert!(e.contains("expected (H, W, 3)"), "{e}");
    let mut bad = img.clone();
    bad[3 * (5 * W as usize + 7) + 1] = f32::NAN;
    let e = augment(W, H, &bad, &a).unwrap_err().to_string();
    assert!(e.contains("pixel 7, 5") && e.contains("not finite"), "{e}");
    let mut z = a.clone();
    z.exposure_s = 0.0;
    assert!(augment(W, H, &img, &z)
        .unwrap_err()
        .to_string()
        .contains("exposure"));
    let mut d = a.clone();
    let mut cam = mmbm::camera::CameraFile::default().thesis_at([W, H]);
    cam.distortion = mmbm::camera::Distortion::WIDE_ANGLE;
    d.camera = Some(cam);
    let e = augment(W, H, &img, &d).unwrap_err().to_string();
    assert!(e.contains("distortion"), "{e}");
    let mut s = a.clone();
    s.camera = Some(mmbm::camera::CameraFile::default().thesis_at([W + 2, H]));
    let e = augment(W, H, &img, &s).unwrap_err().to_string();
    assert!(e.contains("98 x 72"), "{e}");
}
