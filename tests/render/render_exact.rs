//! Renderer against exact integrals (docs/spec.md section 4): a fronto-parallel
//! checkerboard under pure lateral translation has a closed-form
//! area-and-time integral per pixel (the integral of a square wave is a
//! triangle wave), computed here independently of the renderer.

use glam::DVec3;
use mmbm::render::{render_frame, Backend, Integrator, Quality, RenderJob, Target, Trajectory};
use mmbm::{Camera, Twist};

/// Integral of the +-1 square wave `sq(s) = (-1)^floor(s)` from 0 to `z`.
fn tri(z: f64) -> f64 {
    let m = z.rem_euclid(2.0);
    if m <= 1.0 {
        m
    } else {
        2.0 - m
    }
}

#[allow(clippy::too_many_arguments)]
/// Exact pixel value: checker of side `s` m at depth `d` m, camera moving with
/// `v = (vx, vy, 0)` m/s for `te` s; pixel `(i, j)` of `cam` (no skew).
/// Checker = (1 + sq(X/S) sq(Y/S)) / 2, X = vx t + d u / f.
fn exact_pixel(cam: &Camera, s: f64, d: f64, vx: f64, vy: f64, te: f64, i: u32, j: u32) -> f64 {
    exact_pixel_from(cam, s, d, vx, vy, 0.0, te, i, j)
}

#[allow(clippy::too_many_arguments)]
/// [`exact_pixel`] over the window `[t0, t0 + te]` (a rolling-shutter line's).
fn exact_pixel_from(
    cam: &Camera,
    s: f64,
    d: f64,
    vx: f64,
    vy: f64,
    t0: f64,
    te: f64,
    i: u32,
    j: u32,
) -> f64 {
    let kx = d * cam.pitch_x_mm / cam.focal_mm / s; // a per pixel
    let ky = d * cam.pitch_y_mm / cam.focal_mm / s;
    let ax = |x: f64, t: f64| (vx * (t0 + t) / s) + (x - cam.cx) * kx;
    let ay = |y: f64, t: f64| (vy * (t0 + t) / s) + (y - cam.cy) * ky;
    let (x0, x1) = (i as f64, i as f64 + 1.0);
    let (y0, y1) = (j as f64, j as f64 + 1.0);
    let gx = |t: f64| (tri(ax(x1, t)) - tri(ax(x0, t))) / (ax(x1, t) - ax(x0, t));
    let gy = |t: f64| (tri(ay(y1, t)) - tri(ay(y0, t))) / (ay(y1, t) - ay(y0, t));
    // breakpoints: where an edge coordinate crosses an integer
    let mut bp = vec![0.0, te];
    for (a0, rate) in [
        (ax(x0, 0.0), vx / s),
        (ax(x1, 0.0), vx / s),
        (ay(y0, 0.0), vy / s),
        (ay(y1, 0.0), vy / s),
    ] {
        if rate != 0.0 {
            let a1 = a0 + rate * te;
            let (lo, hi) = (a0.min(a1), a0.max(a1));
            let mut m = lo.ceil();
            while m <= hi {
                bp.push((m - a0) / rate);
                m += 1.0;
            }
        }
    }
    bp.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let f = |t: f64| 0.5 * (1.0 + gx(t) * gy(t));
    let mut acc = 0.0;
    for w in bp.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b > a {
            // piecewise quadratic: Simpson is exact
            acc += (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b));
        }
    }
    if te > 0.0 {
        acc / te
    } else {
        f(0.0)
    }
}

fn errors(img: &[f32], exact: &[f64]) -> (f64, f64, f64) {
    let mut e: Vec<f64> = img
        .chunks(3)
        .zip(exact)
        .map(|(p, x)| (p[0] as f64 - x).abs())
        .collect();
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    e.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let p99 = e[(e.len() as f64 * 0.99) as usize];
    (mean, p99, *e.last().unwrap())
}

fn render_with(
    cam: Camera,
    tw: Twist,
    te: f64,
    target: Target,
    q: Quality,
    seed: u32,
    integrator: Integrator,
) -> Vec<f32> {
    // The trajectory spans the readout (a rolling shutter's) plus the exposure.
    let span = cam.shutter.readout_s + te;
    let mut j = RenderJob::new(cam, te, Trajectory::from_twist(tw, span).unwrap(), target);
    j.quality = q;
    j.integrator = integrator;
    j.backend = Backend::Cpu { threads: None };
    j.seed = seed;
    j.with_maps = false;
    let o = render_frame(&j).unwrap();
    eprintln!(
        "  N = {} samples/pixel, max path {:.1} px",
        o.samples_per_pixel, o.max_path_px
    );
    o.rgb
}

const MEAN_TOL: f64 = 0.5 / 255.0;
const P99_TOL: f64 = 3.0 / 255.0;

fn check_translation(vx: f64, vy: f64, te: f64, q: Quality, mean_tol: f64, p99_tol: f64) {
    for integrator in [Integrator::Analytic, Integrator::Lattice] {
        check_translation_with(vx, vy, te, q, mean_tol, p99_tol, integrator);
    }
}

fn check_translation_with(
    vx: f64,
    vy: f64,
    te: f64,
    q: Quality,
    mean_tol: f64,
    p99_tol: f64,
    integrator: Integrator,
) {
    let cam = Camera::thesis().with_resolution(128, 96);
    let (s, d) = (0.01, 1.0);
    let exact: Vec<f64> = (0..cam.height)
        .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
        .map(|(i, j)| exact_pixel(&cam, s, d, vx, vy, te, i, j))
        .collect();
    let tw = Twist::new(DVec3::ZERO, DVec3::new(vx, vy, 0.0));
    let img = render_with(cam, tw, te, Target::checker(s, d), q, 0, integrator);
    let (mean, p99, max) = errors(&img, &exact);
    eprintln!(
        "translation ({vx}, {vy}) m/s x {te} s, quality {q}, {integrator}: mean |err| {:.3}/255, p99 {:.3}/255, max {:.3}/255",
        mean * 255.0,
        p99 * 255.0,
        max * 255.0
    );
    assert!(mean <= mean_tol && p99 <= p99_tol, "mean {mean} p99 {p99}");
}

/// Rolling shutter (docs/spec.md section 9) under lateral translation: every line is the
/// exact box integral over its own window `[t_r l / n, t_r l / n + t_e]`,
/// with the same contract as the global shutter, for each readout direction.
#[test]
fn rolling_shutter_translation_equals_exact_line_windows() {
    use mmbm::camera::{Readout, Shutter};
    let (s, d, vx, vy, te, tr) = (0.01, 1.0, 0.3, -0.12, 0.02, 0.015);
    for dir in [
        Readout::TopToBottom,
        Readout::BottomToTop,
        Readout::LeftToRight,
    ] {
        let cam = Camera {
            shutter: Shutter {
                readout_s: tr,
                direction: dir,
            },
            ..Camera::thesis().with_resolution(128, 96)
        };
        let exact: Vec<f64> = (0..cam.height)
            .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
            .map(|(i, j)| {
                let t0 = cam.shutter.delay_s(i as f64 + 0.5, j as f64 + 0.5, 128, 96);
                exact_pixel_from(&cam, s, d, vx, vy, t0, te, i, j)
            })
            .collect();
        let tw = Twist::new(DVec3::ZERO, DVec3::new(vx, vy, 0.0));
        for integrator in [Integrator::Analytic, Integrator::Lattice] {
            let img = render_with(
                cam,
                tw,
                te,
                Target::checker(s, d),
                Quality::Default,
                0,
                integrator,
            );
            let (mean, p99, max) = errors(&img, &exact);
            eprintln!(
                "rolling {dir:?} {integrator}: mean |err| {:.3}/255, p99 {:.3}/255, max {:.3}/255",
                mean * 255.0,
                p99 * 255.0,
                max * 255.0
            );
            assert!(mean <= MEAN_TOL && p99 <= P99_TOL, "mean {mean} p99 {p99}");
            // Against the global-shutter image the skew is visible: lines differ.
            let gs: Vec<f64> = (0..cam.height)
                .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
                .map(|(i, j)| exact_pixel(&cam, s, d, vx, vy, te, i, j))
                .collect();
            let (gmean, _, _) = errors(&img, &gs);
            assert!(gmean > 10.0 * mean, "rolling vs global: {gmean} vs {mean}");
        }
    }
}

#[test]
fn zero_motion_equals_exact_area_coverage() {
    check_translation(0.0, 0.0, 0.05, Quality::Default, MEAN_TOL, P99_TOL);
}

#[test]
fn lateral_translation_equals_exact_box_integral() {
    // 0.3 m/s x 50 ms at 1 m: about 14 px of blur in x and 9 px in y
    check_translation(0.3, -0.2, 0.05, Quality::Default, MEAN_TOL, P99_TOL);
    // long horizontal blur (about 55 px)
    check_translation(1.2, 0.0, 0.05, Quality::Default, MEAN_TOL, P99_TOL);
}

#[test]
fn fast_preset_error_is_bounded() {
    // The cheap preset is allowed 4x the default tolerances.
    check_translation(0.0, 0.0, 0.05, Quality::Fast, 4.0 * MEAN_TOL, 4.0 * P99_TOL);
    check_translation(
        0.3,
        -0.2,
        0.05,
        Quality::Fast,
        4.0 * MEAN_TOL,
        4.0 * P99_TOL,
    );
}

/// Default render against an independent reference: the lattice
/// (supersampling) integrator with 32x the samples and another seed, whose
/// own error is far below the tolerance.
fn check_against_lattice(name: &str, tw: Twist, te: f64, t: Target) {
    let cam = Camera::thesis().with_resolution(96, 72);
    let refq = Quality::Custom {
        min_samples: 32 * 1024,
        max_spacing_px: 0.25 / 32.0,
    };
    let reference = render_with(cam, tw, te, t.clone(), refq, 7, Integrator::Lattice);
    for integrator in [Integrator::Auto, Integrator::Lattice] {
        let img = render_with(cam, tw, te, t.clone(), Quality::Default, 0, integrator);
        // Every channel (the blob board is coloured), one pixel per entry.
        let (mut mean, mut p99, mut max) = (0.0f64, 0.0f64, 0.0f64);
        for c in 0..3 {
            let r: Vec<f64> = reference.chunks(3).map(|p| p[c] as f64).collect();
            let im: Vec<f32> = img.chunks(3).flat_map(|p| [p[c], 0.0, 0.0]).collect();
            let (m, p, x) = errors(&im, &r);
            (mean, p99, max) = (mean.max(m), p99.max(p), max.max(x));
        }
        eprintln!(
            "{name}, {integrator} vs lattice reference: mean |err| {:.3}/255, p99 {:.3}/255, max {:.3}/255",
            mean * 255.0,
            p99 * 255.0,
            max * 255.0
        );
        assert!(
            mean <= MEAN_TOL && p99 <= P99_TOL,
            "{name} {integrator}: mean {mean} p99 {p99}"
        );
    }
}

#[test]
fn six_dof_against_high_sample_reference() {
    let tw = Twist::new(DVec3::new(0.8, -0.6, 1.5), DVec3::new(0.2, 0.1, 0.4));
    let mut t = Target::checker(0.02, 1.0);
    t.tilt_deg = [15.0, -20.0];
    check_against_lattice("checker 6-DoF tilted", tw, 0.04, t);
}

#[test]
fn rolled_targets_against_high_sample_reference() {
    // The analytic integrator's one approximation is at corners crossing a
    // footprint that is not aligned with the target: a fast roll makes every
    // footprint a rotated square.
    let roll = Twist::new(DVec3::new(0.1, -0.2, 12.0), DVec3::ZERO);
    check_against_lattice(
        "checker, roll 12 rad/s",
        roll,
        0.05,
        Target::checker(0.01, 1.0),
    );
    let mut b = Target::blobs(0.5, 1.2);
    b.tilt_deg = [-10.0, 25.0];
    let tw = Twist::new(DVec3::new(0.6, 0.4, -2.0), DVec3::new(-0.1, 0.05, 0.2));
    check_against_lattice("blob board 6-DoF tilted", tw, 0.05, b);
}

#[test]
fn exact_integral_sanity() {
    // Independent checks of the reference itself: a pixel inside one square is 0 or 1,
    // a pixel straddling one vertical edge at its middle is 0.5.
    let cam = Camera::new(4.0, 0.004, 100, 100);
    // d/f*p = 1 mm per pixel at 1 m; S = 10 mm -> squares of 10 px, edges at pixel borders of x = 50 +- 10k
    let v = exact_pixel(&cam, 0.01, 1.0, 0.0, 0.0, 0.05, 52, 52);
    assert!((v - 1.0).abs() < 1e-12, "{v}");
    let v = exact_pixel(&cam, 0.01, 1.0, 0.0, 0.0, 0.05, 42, 52);
    assert!(v.abs() < 1e-12, "{v}");
    // move by exactly one period (20 mm) in x over the exposure: average of white/black ramps = 0.5
    let v = exact_pixel(&cam, 0.01, 1.0, 0.4, 0.0, 0.05, 52, 52);
    assert!((v - 0.5).abs() < 1e-9, "{v}");
}

/// An image target under lateral translation against its exact integral.
/// The target is what the renderer defines an image to be: the bilinear
/// interpolant of the linear-light texels (level 0 of the mip pyramid while a
/// texel is at least 1/8 of the pixel footprint, as here: texels are 0.5 px).
/// The texture varies along x only (random grey columns), so the pixel value
/// is a 1-D integral over the pixel width and the exposure, of a piecewise
/// linear function: closed form through its antiderivative G (piecewise
/// quadratic), integrated in time exactly by Simpson between breakpoints.
#[test]
fn image_texture_lateral_translation_equals_exact_integral() {
    let cam = Camera::thesis().with_resolution(128, 96);
    let d = 1.0;
    let k = d * cam.pitch_x_mm / cam.focal_mm; // m per px on the target
    let n_tex = 512usize;
    let width_m = n_tex as f64 * 0.5 * k;
    // Column values: a fixed pseudo-random sequence of 8-bit greys.
    let mut x: u32 = 12345;
    let bytes: Vec<u8> = (0..n_tex)
        .map(|_| {
            x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
            (x >> 16) as u8
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("stripes.png");
    let img = image::GrayImage::from_fn(n_tex as u32, n_tex as u32, |c, _| {
        image::Luma([bytes[c as usize]])
    });
    img.save(&png).unwrap();
    let v: Vec<f64> = bytes
        .iter()
        .map(|&b| mmbm::io::images::srgb8_to_linear(b) as f64)
        .collect();
    // Texel centres a_m and the antiderivative G at them.
    let dx = width_m / n_tex as f64;
    let centre = |m: usize| (m as f64 + 0.5) * dx - 0.5 * width_m;
    let mut cum = vec![0.0; n_tex];
    for m in 1..n_tex {
        cum[m] = cum[m - 1] + 0.5 * (v[m - 1] + v[m]) * dx;
    }
    let g = |a: f64| {
        let m = (((a + 0.5 * width_m) / dx - 0.5).floor() as usize).min(n_tex - 2);
        let s = (a - centre(m)) / dx;
        cum[m] + dx * (v[m] * s + 0.5 * (v[m + 1] - v[m]) * s * s)
    };
    let (vx, te) = (0.3, 0.05);
    let a_at = |px: f64, t: f64| vx * t + (px - cam.cx) * k;
    let exact: Vec<f64> = (0..cam.height)
        .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
        .map(|(i, _)| {
            let (x0, x1) = (i as f64, i as f64 + 1.0);
            // Breakpoints: an end of the pixel crossing a texel centre.
            let mut bp = vec![0.0, te];
            for x in [x0, x1] {
                let (lo, hi) = (a_at(x, 0.0), a_at(x, te));
                let mut m = ((lo + 0.5 * width_m) / dx - 0.5).ceil();
                while centre(m as usize) <= hi {
                    bp.push((centre(m as usize) - lo) / vx);
                    m += 1.0;
                }
            }
            bp.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let f = |t: f64| (g(a_at(x1, t)) - g(a_at(x0, t))) / k;
            let mut acc = 0.0;
            for w in bp.windows(2) {
                let (a, b) = (w[0], w[1]);
                if b > a {
                    acc += (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b));
                }
            }
            acc / te
        })
        .collect();
    let spec = format!("image:{}:{width_m}", png.display());
    let target = Target::parse(&spec, d).unwrap();
    let tw = Twist::new(DVec3::ZERO, DVec3::new(vx, 0.0, 0.0));
    for integrator in [Integrator::Analytic, Integrator::Lattice] {
        let img = render_with(cam, tw, te, target.clone(), Quality::Default, 0, integrator);
        let (mean, p99, max) = errors(&img, &exact);
        eprintln!(
            "image texture, translation {vx} m/s x {te} s, {integrator}: mean |err| {:.3}/255, p99 {:.3}/255, max {:.3}/255",
            mean * 255.0,
            p99 * 255.0,
            max * 255.0
        );
        assert!(
            mean <= MEAN_TOL && p99 <= P99_TOL,
            "{integrator}: mean {mean} p99 {p99}"
        );
    }
}

/// The poster behind the board (`background = "poster"`): still, each pixel
/// inside one of its patches is that patch's colour (`poster::at`), pixels
/// beyond it the plain grey; moving, the analytic integrator agrees with
/// supersampling (`lattice`), and with `none` nothing changes off the board.
#[test]
fn poster_renders_its_texture_around_the_board() {
    use mmbm::render::poster;
    let cam = Camera::thesis().with_resolution(160, 120);
    let mut t = Target::blobs(0.5, 6.0);
    t.surround = mmbm::render::Background::Poster;
    let still = Trajectory::from_twist(Twist::default(), 0.01).unwrap();
    let job = |t: &Target, tr: &Trajectory, i: Integrator, q: Quality| {
        let mut j = RenderJob::new(cam, 0.01, tr.clone(), t.clone());
        j.backend = Backend::Cpu { threads: None };
        j.integrator = i;
        j.quality = q;
        j.with_maps = false;
        render_frame(&j).unwrap().rgb
    };
    let img = job(&t, &still, Integrator::Analytic, Quality::Default);
    let id = (glam::DQuat::IDENTITY, DVec3::ZERO);
    let plane = |x: f64, y: f64| {
        let p = t.intersect(&cam, &id, x, y).unwrap();
        (p.x, p.y)
    };
    let grey = mmbm::render::DEFAULT_BACKGROUND;
    let half = 0.165; // the half board's half width, m
    let (mut patches, mut plain) = (0, 0);
    for j in 0..cam.height {
        for i in 0..cam.width {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(dx, dy)| plane(i as f64 + dx, j as f64 + dy));
            let px = &img[3 * (j * cam.width + i) as usize..][..3];
            let outside = |l: f64| corners.iter().all(|c| c.0.abs() > l || c.1.abs() > l);
            if outside(2.0 * half + 0.01) {
                // Beyond the poster: the plain grey.
                assert_eq!(px, grey, "pixel ({i}, {j})");
                plain += 1;
                continue;
            }
            let inside_poster = corners
                .iter()
                .all(|c| c.0.abs() < 2.0 * half && c.1.abs() < 2.0 * half);
            let off_board = corners
                .iter()
                .all(|c| c.0.abs() > half + 0.01 || c.1.abs() > half + 0.01);
            let colours = corners.map(|c| poster::at(grey, c.0, c.1));
            if inside_poster && off_board && colours.iter().all(|c| *c == colours[0]) {
                for k in 0..3 {
                    assert!(
                        (px[k] - colours[0][k]).abs() < 1e-4,
                        "({i}, {j}): {px:?} vs {colours:?}"
                    );
                }
                patches += 1;
            }
        }
    }
    assert!(
        patches > 2000 && plain > 2000,
        "{patches} patch pixels, {plain} plain"
    );
    // Moving: analytic against 4096 supersamples.
    let tw = Twist::new(DVec3::new(0.3, -0.5, 0.2), DVec3::ZERO);
    let moving = Trajectory::from_twist(tw, 0.01).unwrap();
    let a = job(&t, &moving, Integrator::Analytic, Quality::Default);
    let l = job(
        &t,
        &moving,
        Integrator::Lattice,
        Quality::Custom {
            min_samples: 4096,
            max_spacing_px: 0.25,
        },
    );
    let mean = a
        .iter()
        .zip(&l)
        .map(|(x, y)| (x - y).abs() as f64)
        .sum::<f64>()
        / a.len() as f64;
    assert!(mean < 2e-3, "mean |analytic - lattice| = {mean}");
    // Plain: the same board, grey around it.
    let mut p = t.clone();
    p.surround = mmbm::render::Background::Plain;
    let g = job(&p, &still, Integrator::Analytic, Quality::Default);
    let differ = g.iter().zip(&img).filter(|(x, y)| x != y).count();
    assert!(differ > 3 * 4000, "{differ} values differ");
}
