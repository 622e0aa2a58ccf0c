//! The fast integrator, made cheap (issue 37), still meets the image
//! contract (mean 0.5/255, p99 3/255) against the exact time integral (the
//! 1/32 px integrator) on a twist, shakes, a ~20 px yaw and a rolling
//! shutter, and it would not with half its warp instants (so the choice of
//! the sample count is what these tests check, not a surplus). The blur
//! maps are computed only when asked for.

use glam::DVec3;
use mmbm::augment::{augment_image, Augment, Image, Integrator, Motion, PixelBuf, Pixels};
use mmbm::camera::{Readout, Shutter};
use mmbm::Twist;

/// Focal length of the thesis camera, px.
fn f_px() -> f64 {
    4.2548 / 0.00465
}

/// A deterministic texture: a smooth part and white noise (linear, 0..1),
/// as `bench/augment_bench.py`'s.
fn texture(w: usize, h: usize, c: usize) -> Vec<f32> {
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

fn f32s(b: PixelBuf) -> Vec<f32> {
    match b {
        PixelBuf::F32(v) => v,
        other => panic!("float32 expected, got {other:?}"),
    }
}

/// Mean and 99th percentile of |a - b| in 8-bit levels.
fn err(a: &[f32], b: &[f32]) -> (f64, f64) {
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

/// The image contract of an augmentation against the exact integral.
fn within_contract((mean, p99): (f64, f64)) -> bool {
    mean < 0.5 && p99 < 3.0
}

/// The cases: name, settings (fast integrator, default sample count), and
/// whether the motion's speed is constant (a twist: the instants' spacing
/// is then the bound's 1 px everywhere, and half of them, 2 px apart, must
/// break the contract; a shake's spacing is set by its peak speed, so half
/// its instants may still meet it).
fn cases(w: u32, h: u32) -> Vec<(&'static str, Augment, bool)> {
    let yaw = 20.0 / (f_px() * 0.03);
    let twist = |o: DVec3| Motion::Twist(Twist::new(o, DVec3::ZERO));
    let mut out = vec![
        (
            "yaw 20 px",
            Augment::new(twist(DVec3::new(0.0, yaw, 0.0)), 0.03),
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
    let mut rolling = Augment::new(twist(DVec3::new(0.2, 0.6, 0.1)), 0.02);
    let mut cam = mmbm::camera::CameraFile::default().thesis_at([w, h]);
    cam.shutter = Shutter {
        readout_s: 0.02,
        direction: Readout::TopToBottom,
    };
    rolling.camera = Some(cam);
    out.push(("rolling shutter", rolling, true));
    out
}

#[test]
fn fast_meets_the_contract_and_half_its_samples_do_not() {
    let (w, h) = (160u32, 120u32);
    let img = texture(w as usize, h as usize, 3);
    let image = Image {
        width: w,
        height: h,
        channels: 3,
        pixels: Pixels::F32(&img),
        srgb: false,
    };
    for (name, mut a, constant_speed) in cases(w, h) {
        let fast = augment_image(&image, &a).unwrap();
        let n = fast.samples;
        assert!(fast.maps.is_none(), "{name}: maps not asked for");
        a.integrator = Integrator::Exact;
        let exact = augment_image(&image, &a).unwrap();
        assert!(exact.samples >= 8 * n, "{name}: {} vs {n}", exact.samples);
        let exact = f32s(exact.pixels);
        let e = err(&f32s(fast.pixels), &exact);
        a.integrator = Integrator::Fast;
        a.warps = Some(n / 2);
        let half = augment_image(&image, &a).unwrap();
        assert_eq!(half.samples, n / 2);
        let e_half = err(&f32s(half.pixels), &exact);
        eprintln!(
            "{name} ({}): {n} warps mean {:.3} p99 {:.3}; {} warps mean {:.3} p99 {:.3} /255",
            fast.motion,
            e.0,
            e.1,
            n / 2,
            e_half.0,
            e_half.1
        );
        assert!(within_contract(e), "{name}: {n} warps: {e:?}");
        if constant_speed {
            assert!(
                !within_contract(e_half),
                "{name}: {} warps: {e_half:?}",
                n / 2
            );
        }
    }
}

#[test]
fn the_sample_count_follows_the_longest_path() {
    // A yaw of L px at the centre moves the corners a little more (the
    // focal gain grows off-axis): the fast integrator takes about L / 1 px
    // instants, not the sensor-corner bound's 1.31 L. (Below 8 px of path
    // it takes 8, `FAST_MIN_SAMPLES`.)
    let (w, h) = (640u32, 480u32);
    let img = vec![0.25f32; (w * h) as usize];
    let image = Image {
        width: w,
        height: h,
        channels: 1,
        pixels: Pixels::F32(&img),
        srgb: false,
    };
    for l in [20.0, 60.0] {
        let yaw = l / (f_px() * 0.03);
        let a = Augment::new(
            Motion::Twist(Twist::new(DVec3::new(0.0, yaw, 0.0), DVec3::ZERO)),
            0.03,
        );
        let out = augment_image(&image, &a).unwrap();
        // The corner's path: the angle times f (1 + (x / f)^2) at the
        // frame's left and right edges, along the central row; the top
        // corners' a little longer still. Bound it by the corner gain.
        let x = 0.5 * w as f64;
        let y = 0.5 * h as f64;
        let edge = l * (1.0 + (x / f_px()).powi(2));
        let corner = l * (1.0 + (x * x + y * y) / f_px().powi(2));
        let n = out.samples as f64;
        assert!(
            n >= edge && n <= 1.1 * corner + 1.0,
            "{l} px: {n} instants, edge path {edge:.2}, corner path {corner:.2}"
        );
    }
}

#[test]
fn maps_only_when_asked_for() {
    let (w, h) = (64u32, 48u32);
    let img = texture(w as usize, h as usize, 3);
    let image = Image {
        width: w,
        height: h,
        channels: 3,
        pixels: Pixels::F32(&img),
        srgb: false,
    };
    let mut a = Augment::new(Motion::Shake, 0.03);
    a.seed = 4;
    let plain = augment_image(&image, &a).unwrap();
    assert!(plain.maps.is_none());
    a.maps = true;
    let with = augment_image(&image, &a).unwrap();
    let maps = with.maps.expect("maps asked for");
    assert_eq!(maps.path_px.len(), (w * h) as usize);
    assert!(maps.path_px.iter().any(|&p| p > 0.0));
    // The image does not depend on whether the maps were asked for.
    assert_eq!(plain.pixels, with.pixels);
}
