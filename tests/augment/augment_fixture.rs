//! Shared setup of the augment tests (`augment_api`, `augment_speed`,
//! `augment_gpu`): the thesis focal length, the test texture, the cases
//! checked against the exact integral, and the one image-contract check.

// Each test binary uses some of these helpers, not all of them.
#![allow(dead_code)]

use glam::DVec3;
use mmbm::augment::{Augment, Image, Motion, PixelBuf, Pixels};
use mmbm::camera::{Readout, Shutter};
use mmbm::Twist;

/// Focal length of the thesis camera, px.
pub fn f_px() -> f64 {
    4.2548 / 0.00465
}

/// A deterministic texture with detail at every scale: a smooth part and
/// white noise (linear, 0..1), as `bench/augment_bench.py`'s.
pub fn texture(w: usize, h: usize, c: usize) -> Vec<f32> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    (0..w * h * c)
        .map(|k| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let (i, j) = ((k / c) % w, k / c / w);
            let smooth = 0.5 + 0.25 * ((i as f64 * 0.11).sin() * (j as f64 * 0.07).cos());
            let noise = (s >> 40) as f64 / (1u64 << 24) as f64;
            (0.6 * smooth + 0.4 * noise) as f32
        })
        .collect()
}

/// A linear float32 image of `c` channels.
pub fn f32_image(w: u32, h: u32, c: u32, v: &[f32]) -> Image<'_> {
    Image {
        width: w,
        height: h,
        channels: c,
        pixels: Pixels::F32(v),
        srgb: false,
    }
}

/// The values of a float32 result.
pub fn out_f32(b: PixelBuf) -> Vec<f32> {
    match b {
        PixelBuf::F32(v) => v,
        other => panic!("float32 expected, got {other:?}"),
    }
}

/// Mean and 99th percentile of |a - b| in 8-bit levels.
pub fn err(a: &[f32], b: &[f32]) -> (f64, f64) {
    assert_eq!(a.len(), b.len(), "compared images differ in size");
    let mut e: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).abs() * 255.0)
        .collect();
    e.sort_by(|a, b| a.total_cmp(b));
    (
        e.iter().sum::<f64>() / e.len() as f64,
        e[(e.len() as f64 * 0.99) as usize],
    )
}

/// The image contract of an augmentation against the exact integral:
/// mean below 0.5/255 and 99th percentile below 3/255.
pub fn within_contract((mean, p99): (f64, f64)) -> bool {
    mean < 0.5 && p99 < 3.0
}

/// A constant twist (rad/s), no translation.
pub fn twist(omega: DVec3) -> Motion {
    Motion::Twist(Twist::new(omega, DVec3::ZERO))
}

/// A yaw rate (rad/s) that moves the centre `px` px in `t` s.
pub fn yaw_for(px: f64, t: f64) -> f64 {
    px / (f_px() * t)
}

/// The motions `tests/augment_api.rs` checks the fast integrator on
/// against the exact one: a twist with roll, a 20 px yaw, two shakes.
pub fn api_cases() -> Vec<Augment> {
    let mut cases = vec![
        Augment::new(twist(DVec3::new(0.3, 0.5, 2.5)), 0.03),
        Augment::new(twist(DVec3::new(0.0, yaw_for(20.0, 0.03), 0.0)), 0.03),
    ];
    for seed in [1, 2] {
        let mut a = Augment::new(Motion::Shake, 0.03);
        a.seed = seed;
        cases.push(a);
    }
    cases
}

/// The speed cases of `tests/augment_speed.rs`: name, settings (fast
/// integrator, default sample count), and whether the motion's speed is
/// constant (a twist: the instants' spacing is then the bound's 1 px
/// everywhere, and half of them, 2 px apart, must break the contract; a
/// shake's spacing is set by its peak speed, so half its instants may
/// still meet it). The rolling-shutter case has a `w` x `h` camera.
pub fn speed_cases(w: u32, h: u32) -> Vec<(&'static str, Augment, bool)> {
    let mut out = vec![
        (
            "yaw 20 px",
            Augment::new(twist(DVec3::new(0.0, yaw_for(20.0, 0.03), 0.0)), 0.03),
            true,
        ),
        (
            "twist with roll",
            Augment::new(twist(DVec3::new(0.3, 0.5, 2.5)), 0.03),
            true,
        ),
    ];
    for seed in [1, 2] {
        let mut a = Augment::new(Motion::Shake, 0.03);
        a.seed = seed;
        a.blur_px = Some(20.0);
        out.push(("shake", a, false));
        let mut small = Augment::new(Motion::Shake, 0.03);
        small.seed = seed;
        small.blur_px = Some(3.0);
        out.push(("shake of 3 px", small, false));
    }
    out.push(("rolling shutter", rolling(w, h), true));
    out
}

/// A twist seen by a `w` x `h` thesis camera with a 20 ms top-to-bottom
/// rolling shutter.
pub fn rolling(w: u32, h: u32) -> Augment {
    let mut a = Augment::new(twist(DVec3::new(0.2, 0.6, 0.1)), 0.02);
    let mut cam = mmbm::camera::CameraFile::default().thesis_at([w, h]);
    cam.shutter = Shutter {
        readout_s: 0.02,
        direction: Readout::TopToBottom,
    };
    a.camera = Some(cam);
    a
}
