//! `mmbm::augment` as augmentation users expect it: without motion the input
//! comes back bit for bit (every dtype, channel count and integrator), the
//! fast integrator meets the image contract (mean 0.5/255, p99 3/255)
//! against the exact time integral (closed form for a translation; the
//! 1/32 px integrator for a twist and a shake), `blur_px` is the maps' mean
//! path, borders, fields, and a batch in parallel equals the images one by one.

use crate::augment_fixture;

use augment_fixture::{api_cases, err, f32_image, f_px, out_f32, texture, within_contract};
use glam::{DMat3, DVec3};
use mmbm::augment::{
    augment_batch, augment_image, Augment, Border, Image, Integrator, Motion, Pixels,
};
use mmbm::Twist;

fn still() -> Augment {
    Augment::new(Motion::Twist(Twist::new(DVec3::ZERO, DVec3::ZERO)), 0.03)
}

#[test]
fn zero_motion_returns_the_input_bit_for_bit() {
    let (w, h) = (37u32, 23u32);
    let lin = texture(w as usize, h as usize, 4);
    let u8s: Vec<u8> = lin.iter().map(|x| (x * 255.0) as u8).collect();
    let u16s: Vec<u16> = lin.iter().map(|x| (x * 65535.0) as u16).collect();
    let f64s: Vec<f64> = lin.iter().map(|&x| x as f64 * 1.000_000_1).collect();
    for integrator in [Integrator::Fast, Integrator::Exact, Integrator::Render] {
        for c in [1u32, 3, 4] {
            let n = (w * h * c) as usize;
            for pixels in [
                Pixels::U8(&u8s[..n]),
                Pixels::U16(&u16s[..n]),
                Pixels::F32(&lin[..n]),
                Pixels::F64(&f64s[..n]),
            ] {
                let img = Image {
                    width: w,
                    height: h,
                    channels: c,
                    pixels,
                    srgb: true,
                };
                let mut a = still();
                a.integrator = integrator;
                a.border = Border::Constant;
                a.fields = true;
                a.maps = true;
                let out = augment_image(&img, &a).unwrap();
                assert_eq!(out.pixels, pixels.to_buf(), "{integrator:?}, {c} channels");
                assert_eq!(out.samples, 0);
                assert!(out.maps.unwrap().path_px.iter().all(|&p| p == 0.0));
                assert!(out.fields.unwrap().iter().all(|&d| d.abs() < 1e-4));
            }
        }
    }
}

/// Closed form: the mean over s in [0, L] of the bilinear interpolant of row
/// `r` (texel j at j + 0.5, mirrored beyond the ends) at x + s, by its
/// antiderivative on a fine grid of the piecewise-linear function.
fn translation_exact(r: &[f32], x: f64, l: f64) -> f64 {
    let f = |u: f64| {
        let u = u - 0.5;
        let j = u.floor();
        let t = u - j;
        let j = j as usize;
        r[j] as f64 * (1.0 - t) + r[j + 1] as f64 * t
    };
    // Exact integral of a piecewise-linear function: trapezoids between knots.
    let mut knots = vec![x];
    let mut k = (x - 0.5).floor() + 1.5;
    while k < x + l {
        knots.push(k);
        k += 1.0;
    }
    knots.push(x + l);
    knots
        .windows(2)
        .map(|p| 0.5 * (p[1] - p[0]) * (f(p[0]) + f(p[1])))
        .sum::<f64>()
        / l
}

#[test]
fn fast_meets_the_contract_on_a_20_px_translation_in_closed_form() {
    let (w, h) = (160usize, 24usize);
    let img = texture(w, h, 1);
    let (d, t, l) = (2.0, 0.03, 20.0);
    // The camera moves +x: the frame at pixel x shows texture x + s, s: 0..L.
    let v = l * d / (f_px() * t);
    let a = Augment::new(
        Motion::Twist(Twist::new(DVec3::ZERO, DVec3::new(v, 0.0, 0.0))),
        t,
    );
    let out = out_f32(
        augment_image(&f32_image(w as u32, h as u32, 1, &img), &a)
            .unwrap()
            .pixels,
    );
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for j in 0..h {
        for i in 0..w - 24 {
            got.push(out[j * w + i]);
            want.push(translation_exact(&img[j * w..(j + 1) * w], i as f64 + 0.5, l) as f32);
        }
    }
    let (mean, p99) = err(&got, &want);
    eprintln!("20 px translation: mean {mean:.3}, p99 {p99:.3} /255");
    assert!(
        within_contract((mean, p99)),
        "mean {mean:.3}, p99 {p99:.3} /255"
    );
}

#[test]
fn fast_meets_the_contract_against_the_exact_integrator() {
    let (w, h) = (128u32, 96u32);
    let img = texture(w as usize, h as usize, 3);
    let cases = api_cases();
    for mut a in cases {
        let fast = augment_image(&f32_image(w, h, 3, &img), &a).unwrap();
        a.integrator = Integrator::Exact;
        let exact = augment_image(&f32_image(w, h, 3, &img), &a).unwrap();
        assert!(fast.samples >= 1 && exact.samples >= 8 * fast.samples);
        let (mean, p99) = err(&out_f32(fast.pixels), &out_f32(exact.pixels));
        eprintln!(
            "{}: {} vs {} samples, mean {mean:.3}, p99 {p99:.3} /255",
            fast.motion, fast.samples, exact.samples
        );
        assert!(
            within_contract((mean, p99)),
            "{}: mean {mean:.3}, p99 {p99:.3} /255",
            fast.motion
        );
    }
}

#[test]
fn blur_px_is_the_mean_path_of_the_maps() {
    let (w, h) = (96u32, 64u32);
    let img = texture(w as usize, h as usize, 3);
    for (motion, target) in [
        (
            Motion::Twist(Twist::new(DVec3::new(0.2, 0.9, 0.4), DVec3::ZERO)),
            12.0,
        ),
        (Motion::Shake, 20.0),
    ] {
        let mut a = Augment::new(motion, 0.02);
        a.blur_px = Some(target);
        a.sharp = mmbm::render::SharpAt::Mid;
        a.maps = true;
        let out = augment_image(&f32_image(w, h, 3, &img), &a).unwrap();
        let p = &out.maps.unwrap().path_px;
        let mean = p.iter().map(|&x| x as f64).sum::<f64>() / p.len() as f64;
        assert!(
            (mean / target - 1.0).abs() < 0.03,
            "{}: {mean} px for {target}",
            out.motion
        );
    }
    let mut a = still();
    a.blur_px = Some(5.0);
    let e = augment_image(&f32_image(w, h, 3, &img), &a).unwrap_err();
    assert!(e.to_string().contains("blur_px"), "{e}");
}

#[test]
fn borders_reflect_replicate_or_show_the_background() {
    // A flat grey image moved a long way: mirrored or repeated it stays grey;
    // with a constant border the black background darkens the trailing edge.
    let (w, h) = (64u32, 48u32);
    let img = vec![0.5f32; (w * h * 3) as usize];
    let mut a = Augment::new(
        Motion::Twist(Twist::new(
            DVec3::new(0.0, 30.0 / (f_px() * 0.03), 0.0),
            DVec3::ZERO,
        )),
        0.03,
    );
    for b in [Border::Reflect, Border::Replicate] {
        a.border = b;
        let out = out_f32(augment_image(&f32_image(w, h, 3, &img), &a).unwrap().pixels);
        assert!(out.iter().all(|&x| (x - 0.5).abs() < 1e-5), "{b:?}");
    }
    a.border = Border::Constant;
    let out = out_f32(augment_image(&f32_image(w, h, 3, &img), &a).unwrap().pixels);
    let min = out.iter().cloned().fold(1.0f32, f32::min);
    assert!(min < 0.3, "constant border: darkest {min}");
    assert!("wrap".parse::<Border>().is_err());
}

#[test]
fn fields_follow_the_homographies() {
    let (w, h) = (64u32, 48u32);
    let img = texture(w as usize, h as usize, 3);
    let mut a = Augment::new(
        Motion::Twist(Twist::new(DVec3::new(0.2, 0.7, 0.3), DVec3::ZERO)),
        0.03,
    );
    a.fields = true;
    let out = augment_image(&f32_image(w, h, 3, &img), &a).unwrap();
    let f = out.fields.unwrap();
    assert_eq!(f.len(), 3 * (w * h * 2) as usize);
    for (k, hm) in out.homographies.iter().enumerate() {
        let m = DMat3::from_cols_array(hm).transpose();
        for (i, j) in [(0u32, 0u32), (31, 20), (63, 47)] {
            let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
            let at = (k * (w * h) as usize + (j * w + i) as usize) * 2;
            // The image point the pixel sees, carried back by H, is the pixel.
            let p = m * DVec3::new(x + f[at] as f64, y + f[at + 1] as f64, 1.0);
            assert!(
                (p.x / p.z - x).abs() < 1e-3 && (p.y / p.z - y).abs() < 1e-3,
                "plane {k} pixel ({i}, {j})"
            );
        }
    }
}

#[test]
fn a_batch_in_parallel_is_the_images_one_by_one() {
    let (w, h) = (48u32, 32u32);
    let imgs: Vec<Vec<u8>> = (0..4)
        .map(|k| {
            texture(w as usize, h as usize + k, 3)[k * 3 * w as usize..]
                .iter()
                .map(|x| (x * 255.0) as u8)
                .collect()
        })
        .collect();
    let images: Vec<Image> = imgs
        .iter()
        .map(|v| Image {
            width: w,
            height: h,
            channels: 3,
            pixels: Pixels::U8(v),
            srgb: true,
        })
        .collect();
    let settings: Vec<Augment> = (0..4)
        .map(|k| {
            let mut a = Augment::new(Motion::Shake, 0.03);
            a.seed = k;
            a
        })
        .collect();
    let batch = augment_batch(&images, &settings).unwrap();
    for (k, out) in batch.iter().enumerate() {
        let one = augment_image(&images[k], &settings[k]).unwrap();
        assert_eq!(out.pixels, one.pixels);
        assert_eq!(out.motion, one.motion);
    }
    assert!(augment_batch(&images, &settings[..3]).is_err());
}
