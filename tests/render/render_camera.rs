//! The renderer with the real camera of docs/spec.md section 9: rolling-shutter blur
//! maps against a closed form, lens distortion against an exact-undistortion
//! reference and the flow formula, defocus against docs/spec.md section 9's disc, the noise
//! model on rendered frames (photon transfer over a flat region, seeding).

use glam::DVec3;
use mmbm::camera::{Distortion, Lens, Noise, Readout, Shutter};
use mmbm::io::gyro::GyroSample;
use mmbm::render::Integrator;
use mmbm::render::{render_frame, render_sharp, Backend, RenderJob, Target, Trajectory};
use mmbm::{Camera, Twist};

fn cpu(mut j: RenderJob) -> RenderJob {
    j.backend = Backend::Cpu { threads: None };
    j
}

/// Yaw ramp `w_y = c t`: at the principal point the image moves at
/// `|w_y| fx` px/s (to first order in the small angle turned), so a line
/// whose window starts at `t0` has a path of `fx c (t0 + t_e / 2) t_e` px.
#[test]
fn rolling_blur_maps_follow_each_lines_window() {
    let c = 4.0;
    let samples: Vec<GyroSample> = (0..=400)
        .map(|k| {
            let t = k as f64 * 0.5e-3;
            GyroSample {
                t,
                omega: DVec3::new(0.0, c * t, 0.0),
                velocity: None,
                depth: None,
            }
        })
        .collect();
    let (te, tr, t0) = (0.004, 0.03, 0.1);
    let cam = Camera {
        shutter: Shutter {
            readout_s: tr,
            direction: Readout::TopToBottom,
        },
        ..Camera::thesis().with_resolution(64, 48)
    };
    let traj = Trajectory::from_log(&samples, t0, tr + te, false).unwrap();
    let mut job = cpu(RenderJob::new(cam, te, traj, Target::checker(0.02, 2.0)));
    job.with_maps = true;
    let out = render_frame(&job).unwrap();
    let maps = out.maps.unwrap();
    assert!(
        (maps.duration - te).abs() < 1e-15,
        "speed is per line exposure"
    );
    // The centre column at the principal point's column, every row.
    let i = 32;
    for j in [0usize, 12, 24, 47] {
        let delay = tr * j as f64 / 48.0;
        let expect = cam.fx_px() * c * (t0 + delay + te / 2.0) * te;
        let got = maps.path_px[j * 64 + i] as f64;
        eprintln!("row {j}: path {got:.5} px, closed form {expect:.5} px");
        assert!(
            (got - expect).abs() < 2e-3 * expect,
            "row {j}: {got} vs {expect}"
        );
    }
}

#[test]
fn noisy_render_follows_photon_transfer_and_is_seeded() {
    // The blob board at 5 m covers the centre; the rest is flat background.
    let noise = Noise {
        bits: 12,
        seed: 11,
        ..Noise::at_light(40_000.0)
    };
    let cam = Camera {
        noise: Some(noise),
        ..Camera::thesis().with_resolution(160, 120)
    };
    let te = 0.07;
    let job = cpu(RenderJob::new(
        cam,
        te,
        Trajectory::from_twist(Twist::rotation(0.0, 0.0, 0.0), te).unwrap(),
        Target::blobs(1.0, 40.0),
    ));
    let mut ideal = job.clone();
    ideal.camera.noise = None;
    let clean = render_frame(&ideal).unwrap().rgb;
    let a = render_frame(&job).unwrap().rgb;
    let b = render_frame(&job).unwrap().rgb;
    assert_eq!(a, b, "seeded: bit-identical");
    let sharp = render_sharp(&job).unwrap().rgb;
    assert_ne!(a, sharp, "the sharp frame is another realisation");
    // Pixels whose clean value is the background grey (flat field).
    let bg = clean[0];
    let dn: Vec<f64> = a
        .iter()
        .zip(&clean)
        .filter(|(_, &c)| c == bg)
        .map(|(&p, _)| p as f64 * noise.max_dn())
        .collect();
    assert!(dn.len() > 40_000, "{}", dn.len());
    let n = dn.len() as f64;
    let mean = dn.iter().sum::<f64>() / n;
    let var = dn.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let k = noise.gain();
    let mu_e = 40_000.0 * te * bg as f64;
    let (em, ev) = (k * mu_e, k * k * (mu_e + 2.5f64.powi(2)) + 1.0 / 12.0);
    eprintln!("flat field: mean {mean:.2} DN (model {em:.2}), variance {var:.2} (model {ev:.2}), {n} pixels");
    assert!((mean - em).abs() < 5.0 * (ev / n).sqrt());
    assert!((var - ev).abs() < 5.0 * ev * (2.0 / n).sqrt());
}

fn barrel() -> Camera {
    Camera {
        distortion: Distortion::Opencv {
            k1: -0.3,
            k2: 0.08,
            p1: 0.001,
            p2: -0.002,
            k3: 0.0,
        },
        ..Camera::new(0.7, 0.00465, 64, 48) // wide: 0.9 px of distortion at the corners
    }
}

/// A still, tilted checkerboard through a barrel lens against a 32 x 32
/// midpoint supersampling of each pixel, every sub-sample undistorted
/// exactly (f64 Newton) and intersected with the plane by the library's
/// pinhole geometry: the kernel's first-order per-pixel map must keep the
/// accuracy contract (mean <= 0.5/255, p99 <= 3/255).
#[test]
fn distorted_still_checker_matches_supersampled_reference() {
    let cam = barrel();
    let mut target = Target::checker(0.05, 1.0);
    target.tilt_deg = [10.0, -15.0];
    let f = target.frame();
    let id = (glam::DQuat::IDENTITY, DVec3::ZERO);
    let s = 0.05;
    let n = 32;
    let mut reference = Vec::new();
    for j in 0..cam.height {
        for i in 0..cam.width {
            let mut acc = 0.0;
            for sy in 0..n {
                for sx in 0..n {
                    let x = i as f64 + (sx as f64 + 0.5) / n as f64;
                    let y = j as f64 + (sy as f64 + 0.5) / n as f64;
                    let p = target.intersect(&cam, &id, x, y).unwrap();
                    let (a, b) = ((p - f.origin).dot(f.e1), (p - f.origin).dot(f.e2));
                    let k = (a / s).floor() as i64 + (b / s).floor() as i64;
                    acc += if k.rem_euclid(2) == 0 { 1.0 } else { 0.0 };
                }
            }
            reference.push(acc / (n * n) as f64);
        }
    }
    for integrator in [
        mmbm::render::Integrator::Analytic,
        mmbm::render::Integrator::Lattice,
    ] {
        let mut job = cpu(RenderJob::new(
            cam,
            0.01,
            Trajectory::from_twist(Twist::default(), 0.01).unwrap(),
            target.clone(),
        ));
        job.integrator = integrator;
        job.with_maps = false;
        let img = render_frame(&job).unwrap().rgb;
        let mut e: Vec<f64> = img
            .chunks(3)
            .zip(&reference)
            .map(|(p, r)| (p[0] as f64 - r).abs())
            .collect();
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        e.sort_by(f64::total_cmp);
        let p99 = e[e.len() * 99 / 100];
        eprintln!(
            "barrel still checker, {integrator}: mean {:.3}/255, p99 {:.3}/255",
            mean * 255.0,
            p99 * 255.0
        );
        assert!(
            mean <= 0.5 / 255.0 && p99 <= 3.0 / 255.0,
            "{integrator}: {mean} {p99}"
        );
    }
}

/// The renderer's ground-truth track through the lens (blur maps over a
/// 1 ms exposure) moves at the speed of the distorted flow formula.
#[test]
fn distorted_track_speed_equals_the_flow_formula() {
    let cam = barrel();
    let tw = Twist::new(DVec3::new(0.4, -0.7, 0.9), DVec3::new(0.3, 0.1, -0.2));
    let mut target = Target::checker(0.05, 1.5);
    target.tilt_deg = [0.0, 0.0];
    let te = 1e-3;
    let mut job = cpu(RenderJob::new(
        cam,
        te,
        Trajectory::from_twist(tw, te).unwrap(),
        target,
    ));
    job.with_maps = true;
    let maps = render_frame(&job).unwrap().maps.unwrap();
    let plane = mmbm::Plane::fronto(1.5);
    for &(i, j) in &[(0usize, 0usize), (63, 47), (32, 24), (10, 40), (50, 5)] {
        let (ud, vd) = cam.pixel_to_mm(i as f64 + 0.5, j as f64 + 0.5);
        let (du, dv) = mmbm::model::flow::flow_distorted(&cam, ud, vd, &tw, Some(&plane)).unwrap();
        let (a, b) = cam.mm_to_px_velocity(du, dv);
        let formula = a.hypot(b);
        let track = maps.speed_px_s[j * 64 + i] as f64;
        eprintln!("pixel ({i}, {j}): track {track:.4} px/s, formula {formula:.4} px/s");
        assert!(
            (track - formula).abs() < 2e-3 * formula,
            "({i}, {j}): {track} vs {formula}"
        );
    }
}

#[test]
fn readout_beyond_the_trajectory_is_a_clear_error() {
    let traj = Trajectory::from_twist(Twist::rotation(0.1, 0.0, 0.0), 0.02).unwrap();
    let base = Camera::thesis().with_resolution(32, 24);
    let cases = [(
        Camera {
            shutter: Shutter {
                readout_s: 0.05,
                direction: Readout::TopToBottom,
            },
            ..base
        },
        "readout_s",
    )];
    for (cam, key) in cases {
        // An exposure of 0.01 s needs 0.06 s of motion with this readout.
        let e = render_frame(&cpu(RenderJob::new(
            cam,
            0.01,
            traj.clone(),
            Target::checker(0.02, 1.0),
        )))
        .unwrap_err()
        .to_string();
        assert!(e.contains(key), "{key}: {e}");
    }
}

/// Defocus (docs/spec.md section 9): a small bright patch at depth `z`, focused at `s`,
/// spreads over a disc of diameter `c = A f / (s - f) |z - s| / z`. The
/// disc's radial second moment is `D^2 / 8`; the in-focus render's moment
/// (the patch's own size, filtering and pixel area) is subtracted, since
/// spreads add under convolution.
#[test]
fn defocus_disc_has_the_spec_diameter() {
    let dir = tempfile::tempdir().unwrap();
    let tex = dir.path().join("dot.png");
    // 33 x 33 black with one white texel: 1 mm texels on a 33 mm square.
    image::RgbImage::from_fn(33, 33, |x, y| {
        if x == 16 && y == 16 {
            image::Rgb([255, 255, 255])
        } else {
            image::Rgb([0, 0, 0])
        }
    })
    .save(&tex)
    .unwrap();
    let z = 0.6;
    let render = |focus_m: f64| {
        let cam = Camera {
            lens: Some(Lens {
                f_number: 1.4,
                focus_m,
            }),
            ..Camera::new(8.0, 0.005, 96, 96)
        };
        let mut target = Target::parse(&format!("image:{}:0.033", tex.display()), z).unwrap();
        target.background = [0.0; 3];
        let job = cpu(RenderJob::new(
            cam,
            0.01,
            Trajectory::from_twist(Twist::default(), 0.01).unwrap(),
            target,
        ));
        let mut j = job;
        j.with_maps = false;
        j.quality = mmbm::render::Quality::Custom {
            min_samples: 8192,
            max_spacing_px: 0.25,
        };
        (cam, render_frame(&j).unwrap().rgb)
    };
    let moment = |rgb: &[f32]| {
        let (mut s, mut sx, mut sy) = (0.0f64, 0.0, 0.0);
        for (k, p) in rgb.chunks(3).enumerate() {
            let (x, y) = ((k % 96) as f64 + 0.5, (k / 96) as f64 + 0.5);
            s += p[0] as f64;
            sx += p[0] as f64 * x;
            sy += p[0] as f64 * y;
        }
        let (cx, cy) = (sx / s, sy / s);
        let mut m = 0.0;
        for (k, p) in rgb.chunks(3).enumerate() {
            let (x, y) = ((k % 96) as f64 + 0.5, (k / 96) as f64 + 0.5);
            m += p[0] as f64 * ((x - cx).powi(2) + (y - cy).powi(2));
        }
        m / s
    };
    let (_, sharp) = render(z);
    let m0 = moment(&sharp);
    for s in [1.0, 2.5, 0.4] {
        let (cam, img) = render(s);
        let d = (8.0 * (moment(&img) - m0)).sqrt();
        let lens = cam.lens.unwrap();
        let spec = lens.coc_mm(cam.focal_mm, z) / cam.pitch_x_mm;
        eprintln!(
            "focus {s} m, point at {z} m: disc {d:.3} px, docs/spec.md section 9 {spec:.3} px"
        );
        assert!((d - spec).abs() < 0.5, "focus {s}: {d} vs {spec}");
    }
    // The analytic integrator cannot sample the aperture.
    let cam = Camera {
        lens: Some(Lens {
            f_number: 2.0,
            focus_m: 1.0,
        }),
        ..Camera::thesis().with_resolution(32, 24)
    };
    let mut job = cpu(RenderJob::new(
        cam,
        0.01,
        Trajectory::from_twist(Twist::default(), 0.01).unwrap(),
        Target::checker(0.02, 1.0),
    ));
    job.integrator = Integrator::Analytic;
    assert!(render_frame(&job)
        .unwrap_err()
        .to_string()
        .contains("lattice"));
}

/// The job's exposure is explicit: a trajectory that does not span the
/// readout plus the exposure, or an exposure that is not positive, is refused.
#[test]
fn exposure_and_trajectory_must_agree() {
    let cam = Camera {
        shutter: Shutter {
            readout_s: 0.01,
            direction: Readout::TopToBottom,
        },
        ..Camera::thesis().with_resolution(32, 24)
    };
    let traj = Trajectory::from_twist(Twist::rotation(0.1, 0.0, 0.0), 0.03).unwrap();
    let target = Target::checker(0.02, 1.0);
    // 0.02 s exposure + 0.01 s readout = 0.03 s: renders.
    assert!(render_frame(&cpu(RenderJob::new(
        cam,
        0.02,
        traj.clone(),
        target.clone()
    )))
    .is_ok());
    for (te, key) in [
        (0.03, "trajectory"),
        (0.0, "exposure"),
        (f64::NAN, "exposure"),
    ] {
        let e = render_frame(&cpu(RenderJob::new(cam, te, traj.clone(), target.clone())))
            .unwrap_err()
            .to_string();
        assert!(e.contains(key), "{te}: {e}");
    }
}
