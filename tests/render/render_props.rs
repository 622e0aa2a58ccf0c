//! Renderer properties that need no GPU: agreement with the flow formula and
//! the metric, sample-count convergence, PSF, gyro-log trajectories, bad input.

use glam::{DQuat, DVec3};
use mmbm::io::gyro::GyroSample;
use mmbm::metric::{mmbm, Method};
use mmbm::model::flow::flow_mm;
use mmbm::render::{self, project, Backend, Quality, RenderJob, Target, Trajectory};
use mmbm::{Camera, Plane, Scene, Twist};

fn cpu_job(cam: Camera, tr: Trajectory, t: Target, q: Quality) -> RenderJob {
    // Global shutter: the exposure is the whole trajectory.
    let mut j = RenderJob::new(cam, tr.duration(), tr, t);
    j.backend = Backend::Cpu { threads: None };
    j.quality = q;
    j
}

#[test]
fn scene_point_motion_matches_flow_formula() {
    // Finite difference of a pixel's scene point, through the renderer's own
    // trajectory, intersection and projection, against docs/spec.md's flow formula.
    let cam = Camera::thesis();
    let tw = Twist::new(DVec3::new(0.7, -1.1, 0.9), DVec3::new(0.3, -0.2, 0.5));
    let dt = 1e-6;
    let tr = Trajectory::from_twist(tw, 0.01).unwrap();
    let mut target = Target::checker(0.1, 2.0);
    target.tilt_deg = [10.0, -25.0];
    let plane = Plane {
        normal: target.frame().normal,
        d: target.frame().normal.dot(target.frame().origin),
    };
    let id = (DQuat::IDENTITY, DVec3::ZERO);
    for (x, y) in [(320.0, 240.0), (10.5, 20.5), (600.5, 400.5), (100.0, 450.0)] {
        let p = target.intersect(&cam, &id, x, y).unwrap();
        let (x1, y1) = project(&cam, &tr.pose_at(dt), p).unwrap();
        let (u, v) = cam.pixel_to_mm(x, y);
        let (u1, v1) = cam.pixel_to_mm(x1, y1);
        let fd = ((u1 - u) / dt, (v1 - v) / dt);
        let iz = plane.inverse_depth(cam.focal_mm, u, v);
        let f = flow_mm(cam.focal_mm, u, v, &tw, iz);
        let tol = 1e-4 * (f.0.hypot(f.1) + 1.0);
        assert!(
            (fd.0 - f.0).abs() < tol && (fd.1 - f.1).abs() < tol,
            "pixel ({x},{y}): finite difference {fd:?} vs formula {f:?}"
        );
    }
}

#[test]
fn mean_path_over_exposure_equals_time_averaged_mmbm() {
    let cam = Camera::thesis().with_resolution(160, 120);
    let te = 0.02;
    // Pure roll: each point keeps its radius, so path / te is exactly the
    // flow speed at the start pixel; the sensor mean is MMBM (pixel-centre
    // midpoint rule vs exact cubature: agreement to 1e-3 relative).
    // General twist: the Eulerian MMBM averaged over the exposure (the plane
    // moves relative to the camera) vs the Lagrangian path mean: agreement to
    // 1 % for a short exposure.
    let cases = [
        (Twist::rotation(0.0, 0.0, 2.0), 1e-3),
        (
            Twist::new(DVec3::new(0.4, -0.3, 0.5), DVec3::new(0.2, 0.1, 0.3)),
            1e-2,
        ),
    ];
    for (tw, tol) in cases {
        let target = Target::checker(0.1, 1.5);
        let tr = Trajectory::from_twist(tw, te).unwrap();
        let maps = render::blur_maps(&cam, &target, &tr, te, 512);
        let m = maps.means();
        // time-averaged exact MMBM, 8-point midpoint in time
        let nt = 8;
        let mut avg = 0.0;
        for k in 0..nt {
            let t = (k as f64 + 0.5) / nt as f64 * te;
            let (q, c) = tr.pose_at(t);
            let n_cam = q.inverse() * DVec3::Z;
            let plane = Plane {
                normal: n_cam,
                d: 1.5 - DVec3::Z.dot(c),
            };
            let s = Scene {
                camera: cam,
                plane: Some(plane),
            };
            avg += mmbm(&s, &tw, Method::Exact { tol: 1e-9 }).unwrap().px_s / nt as f64;
        }
        let rel = (m.speed_px_s - avg).abs() / avg;
        eprintln!(
            "{tw:?}: mean path/te {:.4} px/s, time-averaged MMBM {avg:.4} px/s, rel {rel:.2e}",
            m.speed_px_s
        );
        assert!(rel < tol, "rel {rel}");
        assert!((m.valid - 1.0).abs() < 1e-12);
    }
}

#[test]
fn doubling_samples_changes_image_less_than_the_error_bound() {
    let cam = Camera::thesis().with_resolution(96, 72);
    let tw = Twist::new(DVec3::new(0.5, 0.9, -0.7), DVec3::new(-0.1, 0.2, 0.2));
    let tr = Trajectory::from_twist(tw, 0.05).unwrap();
    let t = Target::blobs(0.5, 1.0);
    let a = render::render_frame(&cpu_job(cam, tr.clone(), t.clone(), Quality::Default)).unwrap();
    let n2 = a.samples_per_pixel * 2;
    let b = render::render_frame(&cpu_job(
        cam,
        tr,
        t,
        Quality::Custom {
            min_samples: n2,
            max_spacing_px: 0.125,
        },
    ))
    .unwrap();
    assert_eq!(b.samples_per_pixel, n2);
    let mut d: Vec<f32> = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| (x - y).abs())
        .collect();
    let mean = d.iter().sum::<f32>() / d.len() as f32;
    d.sort_by(|x, y| x.partial_cmp(y).unwrap());
    let p99 = d[d.len() * 99 / 100];
    eprintln!(
        "N {} vs {n2}: mean |diff| {:.3}/255, p99 {:.3}/255",
        a.samples_per_pixel,
        mean * 255.0,
        p99 * 255.0
    );
    assert!(mean < 0.5 / 255.0 && p99 < 3.0 / 255.0);
}

#[test]
fn psf_sums_to_one_and_is_centred_on_the_mean_track() {
    // Pure lateral translation: the track is a straight line at constant speed,
    // so the PSF's centroid is half the displacement away from its centre.
    let cam = Camera::thesis().with_resolution(160, 120);
    let tr =
        Trajectory::from_twist(Twist::new(DVec3::ZERO, DVec3::new(0.2, -0.1, 0.0)), 0.05).unwrap();
    let t = Target::checker(0.1, 1.0);
    let k = render::psf(&cam, &t, &tr, 80.0, 60.0).unwrap();
    let s: f64 = k.weights.iter().map(|&w| w as f64).sum();
    assert!((s - 1.0).abs() < 1e-5);
    let n = k.size as usize;
    let half = (n / 2) as f64;
    let (mut cx, mut cy) = (0.0, 0.0);
    for (i, &w) in k.weights.iter().enumerate() {
        cx += (i % n) as f64 * w as f64;
        cy += (i / n) as f64 * w as f64;
    }
    // camera moves +x, -y: the image point moves -x, +y by v*te*f/(d*p) px
    let px = cam.focal_mm / cam.pitch_x_mm;
    let (ex, ey) = (-0.2 * 0.05 * px / 2.0, 0.1 * 0.05 * px / 2.0);
    assert!(
        (cx - half - ex).abs() < 0.02 && (cy - half - ey).abs() < 0.02,
        "{cx} {cy} {ex} {ey}"
    );
    assert!(render::psf(&cam, &t, &tr, 500.0, 60.0).is_err());
}

#[test]
fn gyro_log_with_constant_rate_renders_like_the_twist() {
    let w = DVec3::new(0.3, -0.5, 0.4);
    let s: Vec<GyroSample> = (0..50)
        .map(|i| GyroSample {
            t: 1.0 + i as f64 / 200.0,
            omega: w,
            velocity: None,
            depth: None,
        })
        .collect();
    let cam = Camera::thesis().with_resolution(64, 48);
    let t = Target::checker(0.05, 2.0);
    let q = Quality::Fast;
    let a = render::render_frame(&cpu_job(
        cam,
        Trajectory::from_log(&s, 1.05, 0.05, false).unwrap(),
        t.clone(),
        q,
    ))
    .unwrap();
    let b = render::render_frame(&cpu_job(
        cam,
        Trajectory::from_twist(Twist::rotation(w.x, w.y, w.z), 0.05).unwrap(),
        t,
        q,
    ))
    .unwrap();
    let max = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    assert!(max < 2e-2, "max diff {max}");
    let (ma, mb) = (a.maps.unwrap().means(), b.maps.unwrap().means());
    assert!((ma.path_px - mb.path_px).abs() < 1e-3 * mb.path_px);
    // window outside the log
    let e = Trajectory::from_log(&s, 1.2, 0.1, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("outside the gyro log"), "{e}");
    assert!(
        Trajectory::from_log(&s, 1.05, 0.05, true).is_err(),
        "no velocity in the log"
    );
}

#[test]
fn bad_input_is_rejected_with_clear_errors() {
    let cam = Camera::thesis().with_resolution(32, 24);
    assert!(Trajectory::from_twist(Twist::default(), 0.0).is_err());
    assert!(Trajectory::from_twist(Twist::default(), -0.1).is_err());
    let tr = Trajectory::from_twist(Twist::default(), 0.01).unwrap();
    for (t, what) in [
        (Target::checker(0.1, -1.0), "distance"),
        (Target::checker(0.1, 0.0), "distance"),
        (Target::checker(0.0, 1.0), "checker size"),
    ] {
        let e = match render::render_frame(&cpu_job(cam, tr.clone(), t, Quality::Fast)) {
            Ok(_) => panic!("accepted a bad target ({what})"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(what), "{e}");
    }
    let d = tempfile::tempdir().unwrap();
    let bad = d.path().join("not_an_image.png");
    std::fs::write(&bad, b"hello").unwrap();
    let e = Target::parse(&format!("image:{}:1.0", bad.display()), 1.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not_an_image.png"), "{e}");
    assert!("fast".parse::<Quality>().is_ok() && "0:1".parse::<Quality>().is_err());
    // an absurd blur is refused instead of running forever
    let fast = Trajectory::from_twist(Twist::rotation(0.0, 5000.0, 0.0), 1.0).unwrap();
    let e = match render::render_frame(&cpu_job(
        cam,
        fast,
        Target::checker(0.1, 1.0),
        Quality::Default,
    )) {
        Ok(o) => panic!("accepted an absurd blur: N = {}", o.samples_per_pixel),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("samples per pixel"), "{e}");
}
