//! The fast integrator, made cheap (issue 37), still meets the image
//! contract (mean 0.5/255, p99 3/255) against the exact time integral (the
//! 1/32 px integrator) on a twist, shakes, a ~20 px yaw and a rolling
//! shutter, and it would not with half its warp instants (so the choice of
//! the sample count is what these tests check, not a surplus). The blur
//! maps are computed only when asked for.

use crate::augment_fixture;

use augment_fixture::{
    err, f32_image, f_px, out_f32 as f32s, speed_cases, texture, twist, within_contract,
};
use glam::DVec3;
use mmbm::augment::{augment_image, Augment, Integrator};

#[test]
fn fast_meets_the_contract_and_half_its_samples_do_not() {
    let (w, h) = (160u32, 120u32);
    let img = texture(w as usize, h as usize, 3);
    let image = f32_image(w, h, 3, &img);
    for (name, mut a, constant_speed) in speed_cases(w, h) {
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
    let image = f32_image(w, h, 1, &img);
    for l in [20.0, 60.0] {
        let yaw = l / (f_px() * 0.03);
        let a = Augment::new(twist(DVec3::new(0.0, yaw, 0.0)), 0.03);
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
    let image = f32_image(w, h, 3, &img);
    let mut a = Augment::new(mmbm::augment::Motion::Shake, 0.03);
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
