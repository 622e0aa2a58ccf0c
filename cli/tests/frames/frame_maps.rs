//! Per-pixel blur fields of video frames (`mmbm frames --maps`,
//! `series::maps`) against the renderer's maps on the same trajectory, an
//! independent line-by-line integration of the interpolated motion, and the
//! frames' exposure MMBM.

use crate::common;
use crate::maps_fixture;

use glam::{DQuat, DVec3};
use maps_fixture::*;
use mmbm::camera::Distortion;
use mmbm::io::frames::VideoFrame;
use mmbm::io::gyro::{read_log, GyroOptions, GyroSample};
use mmbm::model::log::ImuLog;
use mmbm::render::maps::blur_maps;
use mmbm::render::{Target, Trajectory};
use mmbm::series::frames::frame_mmbm;
use mmbm::series::maps::{frame_maps, FrameMaps, MapRays};
use mmbm::series::SeriesOptions;
use mmbm::{Camera, Method, Plane};

fn maps(
    log: &ImuLog,
    o: &SeriesOptions,
    k: usize,
    f: &VideoFrame,
    steps: Option<usize>,
) -> FrameMaps {
    let rays = MapRays::new(&o.scene.camera).unwrap();
    frame_maps(log, o, &rays, k, f, steps).unwrap().unwrap()
}

/// The renderer's maps (`render --maps`: path and displacement magnitude)
/// on the trajectory the frame's maps use, with as many chords, agree per
/// pixel to f32 rounding: pinhole and a wide-angle lens, several frames.
/// Both follow the one per-pixel track (`model::track::path`); what this
/// still checks is what each side builds for it: the frames job's
/// trajectory and line windows from the log against the renderer's, the
/// frames' scene point (`MapRays`' undistorted ray at infinity) against
/// the renderer's (the ray through the lens meeting the target), and the
/// pinhole line's vectorised track (`Line::pinhole`) against the
/// renderer's per-pixel one.
#[test]
fn maps_equal_render_maps_per_pixel() {
    let Some((log, frames)) = shared("running_phone") else {
        return;
    };
    let base = example_camera("running_phone").scaled_to(240, 135);
    let lens = Camera {
        distortion: Distortion::Opencv {
            k1: -0.05,
            k2: 0.01,
            p1: 0.0005,
            p2: -0.0003,
            k3: 0.0,
        },
        ..base
    };
    let steps = 64;
    for cam in [base, lens] {
        for k in [5, 263, 311, 515] {
            let f = frames[k];
            let readout = f.readout_s.unwrap();
            let cam = Camera {
                shutter: mmbm::camera::Shutter {
                    readout_s: readout,
                    ..cam.shutter
                },
                ..cam
            };
            let m = maps(&log, &opts(cam, None, false), k, &f, Some(steps));
            let traj =
                Trajectory::from_imu_log(&log, f.t_start, readout + f.exposure_s, false).unwrap();
            let r = blur_maps(
                &cam,
                &Target::checker(0.05, 3.0),
                &traj,
                f.exposure_s,
                steps,
            );
            let mut worst: f64 = 0.0;
            for i in 0..m.path_px.len() {
                let d = (m.disp_u[i] as f64).hypot(m.disp_v[i] as f64);
                let e_path = (m.path_px[i] - r.path_px[i]).abs() as f64;
                let e_disp = (d - r.disp_px[i] as f64).abs();
                let scale = 1.0 + r.path_px[i] as f64;
                worst = worst.max(e_path / scale).max(e_disp / scale);
            }
            let (mean, valid) = m.mean_path_px();
            eprintln!("frame {k}: mean path {mean:.4} px, valid {valid}, worst |maps - render| {worst:.2e} px (relative to 1 + path)");
            assert!(valid == 1.0 && mean > 0.0);
            assert!(worst < 2e-5, "frame {k}: {worst}");
        }
    }
}

/// Independent integration: the rotation integrated here from the log
/// (quaternion steps of 1/64 of a sample interval, the twist interpolated
/// linearly, translation with the log's velocity), each line's pixels
/// tracked at 1024 instants of their own window; the flow at the start is
/// the track's central difference under the twist at that instant.
fn independent(
    log: &[GyroSample],
    cam: &Camera,
    plane: Option<Plane>,
    f: &VideoFrame,
    px: (usize, usize),
) -> [f64; 5] {
    let readout = f.readout_s.unwrap();
    let row = px.1 as f64;
    let tl = f.t_start + readout * row / cam.height as f64;
    let interp = |t: f64| {
        let i = log.partition_point(|s| s.t <= t).clamp(1, log.len() - 1);
        let (a, b) = (&log[i - 1], &log[i]);
        let s = (t - a.t) / (b.t - a.t);
        (
            a.omega.lerp(b.omega, s),
            a.velocity
                .unwrap_or_default()
                .lerp(b.velocity.unwrap_or_default(), s),
        )
    };
    // Poses (camera-to-world, centre) from the frame start, at time t.
    let pose = |t: f64| {
        let dt = (log[1].t - log[0].t) / 64.0;
        let n = ((t - f.t_start) / dt).ceil().max(1.0) as usize;
        let h = (t - f.t_start) / n as f64;
        let (mut q, mut c) = (DQuat::IDENTITY, DVec3::ZERO);
        for k in 0..n {
            let (w, v) = interp(f.t_start + (k as f64 + 0.5) * h);
            let half = q * DQuat::from_scaled_axis(w * (0.5 * h));
            q = (q * DQuat::from_scaled_axis(w * h)).normalize();
            c += half * v * h;
        }
        (q, c)
    };
    let (qs, cs) = pose(tl);
    let (rx, ry) = cam
        .pixel_to_ray(px.0 as f64 + 0.5, px.1 as f64 + 0.5)
        .unwrap();
    let dir = qs * DVec3::new(rx, ry, 1.0);
    let x = match plane {
        None => dir * 1e9, // far away: rotation only
        Some(p) => cs + dir * ((p.d - p.normal.dot(cs)) / p.normal.dot(dir)),
    };
    let seen = |(q, c): (DQuat, DVec3)| {
        let p = q.inverse() * (x - c);
        cam.ray_to_pixel(p.x / p.z, p.y / p.z)
    };
    // Poses along the window, stepped on from the line's start.
    let n = 1024;
    let h = f.exposure_s / n as f64;
    let (mut q, mut c) = (qs, cs);
    let first = seen((q, c));
    let (mut prev, mut path) = (first, 0.0);
    for k in 0..n {
        for j in 0..4 {
            let (w, v) = interp(tl + (k as f64 + (j as f64 + 0.5) / 4.0) * h);
            let hh = h / 4.0;
            let half = q * DQuat::from_scaled_axis(w * (0.5 * hh));
            q = (q * DQuat::from_scaled_axis(w * hh)).normalize();
            c += half * v * hh;
        }
        let p = seen((q, c));
        path += (p.0 - prev.0).hypot(p.1 - prev.1);
        prev = p;
    }
    // Flow: central difference of the track around the line's start, the
    // twist there held (the motion's derivative at that instant).
    let (w0, v0) = interp(tl);
    let dt = 1e-5;
    let at = |s: f64| (qs * DQuat::from_scaled_axis(w0 * s), cs + qs * (v0 * s));
    let (a, b) = (seen(at(-dt)), seen(at(dt)));
    [
        prev.0 - first.0,
        prev.1 - first.1,
        path,
        (b.0 - a.0) / (2.0 * dt),
        (b.1 - a.1) / (2.0 * dt),
    ]
}

fn check_against_independent(log: &ImuLog, o: &SeriesOptions, f: &VideoFrame, k: usize) -> f64 {
    let m = maps(log, o, k, f, None);
    let cam = o.scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut worst: f64 = 0.0;
    for &(i, j) in &[
        (0, 0),
        (w - 1, 0),
        (w / 2, h / 2),
        (w / 3, 2 * h / 3),
        (w - 1, h - 1),
        (7, h - 2),
    ] {
        let e = independent(
            log,
            &cam,
            o.scene
                .plane
                .or(o.use_velocity.then(|| Plane::fronto(log[0].depth.unwrap()))),
            f,
            (i, j),
        );
        let idx = j * w + i;
        let got = [
            m.disp_u[idx],
            m.disp_v[idx],
            m.path_px[idx],
            m.flow_u[idx],
            m.flow_v[idx],
        ];
        let path = e[2];
        let flow = e[3].hypot(e[4]);
        for c in 0..5 {
            let scale = if c < 3 {
                1e-3 * (1.0 + path)
            } else {
                1e-3 * (1.0 + flow)
            };
            let err = (got[c] as f64 - e[c]).abs() / scale;
            worst = worst.max(err);
            assert!(
                err < 1.0,
                "frame {k} pixel ({i}, {j}) channel {c}: {} vs {}",
                got[c],
                e[c]
            );
        }
    }
    worst
}

/// The maps against the independent integration: a real log (rotation
/// only, rolling shutter) with a lens, and a synthetic log with velocity
/// and a depth column (translation on a fronto-parallel plane). Tolerance
/// 1e-3 x (1 + path px) for displacement and path, 1e-3 x (1 + |flow|)
/// for the flow (px/s).
#[test]
fn maps_match_independent_line_integration() {
    if let Some((log, frames)) = shared("running_phone") {
        let cam = Camera {
            distortion: Distortion::WIDE_ANGLE,
            ..example_camera("running_phone").scaled_to(320, 180)
        };
        for k in [263, 433, 515] {
            let w = check_against_independent(&log, &opts(cam, None, false), &frames[k], k);
            eprintln!("running_phone frame {k}: worst {w:.2e} of the tolerance");
        }
    }
    // Synthetic: turning rotation, forward-and-sideways velocity, depth 1.5 m.
    let log = synthetic_log(Some(1.5));
    let cam = Camera {
        shutter: mmbm::camera::Shutter {
            readout_s: 0.02,
            direction: mmbm::camera::Readout::TopToBottom,
        },
        ..Camera::thesis().scaled_to(160, 120)
    };
    let f = VideoFrame {
        t_start: 0.7,
        exposure_s: 0.01,
        readout_s: Some(0.02),
    };
    let w = check_against_independent(&log, &opts(cam, None, true), &f, 0);
    eprintln!("synthetic with velocity: worst {w:.2e} of the tolerance");
    // Translation matters here: the maps without it differ.
    let rot = maps(&log, &opts(cam, None, false), 0, &f, None);
    let tr = maps(&log, &opts(cam, None, true), 0, &f, None);
    assert!((rot.mean_path_px().0 - tr.mean_path_px().0).abs() > 0.1);
}

/// Every frame of both shared logs has maps, and their mean path is the
/// frame's exposure MMBM in px (`frames` with a node on every pixel, the
/// same points): they differ by the scene point's drift over the exposure
/// (the maps follow it, the metric's points stay put), which is second
/// order in the blur; bound measured here.
#[test]
fn mean_path_is_the_exposure_mmbm_on_every_frame() {
    for (name, (w, h)) in [("running_phone", (192, 108)), ("dashboard_car", (160, 120))] {
        let Some((log, frames)) = shared(name) else {
            continue;
        };
        let cam = example_camera(name).scaled_to(w, h);
        let o = SeriesOptions {
            method: Method::Riemann { nu: w, nv: h },
            ..opts(cam, None, false)
        };
        let (rows, outside) = frame_mmbm(&log, &o, &frames).unwrap();
        let rays = MapRays::new(&cam).unwrap();
        let (mut worst, mut n, mut gaps): (f64, usize, usize) = (0.0, 0, 0);
        for (k, f) in frames.iter().enumerate() {
            let m = frame_maps(&log, &o, &rays, k, f, None).unwrap();
            let Some(blur) = rows[k].blur_px() else {
                assert!(outside.contains(&k) && m.is_none(), "{name} frame {k}");
                continue;
            };
            let Some(m) = m else {
                // The frame's span crosses a gap in the log: the renderer
                // has no motion there either.
                assert!(Trajectory::from_imu_log(
                    &log,
                    f.t_start,
                    f.readout_s.unwrap() + f.exposure_s,
                    false
                )
                .is_err());
                gaps += 1;
                continue;
            };
            let (mean, valid) = m.mean_path_px();
            assert_eq!(valid, 1.0);
            // Pixel distances (pitch_y may differ from pitch_x, skew) vs mm / pitch_x.
            worst = worst.max((mean - blur).abs() / blur);
            n += 1;
        }
        eprintln!("{name}: {n} frames with maps ({gaps} across a gap in the log), worst |mean path - exposure MMBM px| {worst:.2e} relative");
        assert_eq!(n + gaps + outside.len(), frames.len());
        assert!(gaps <= 2, "{name}: {gaps}");
        assert!(worst < 5e-3, "{name}: {worst}");
    }
}

/// `mmbm frames --maps DIR` writes one EXR per frame inside the log, equal to
/// the library's maps, and agreeing per pixel with `mmbm render --gyro --at
/// --maps` on the same frame (its own chord count: 1e-3 x (1 + path));
/// a --maps that is a file is refused before any work.
#[test]
fn cli_frames_maps() {
    let Some(gyro) = common::shared_log("running_phone") else {
        return;
    };
    let tmp = std::env::temp_dir().join(format!("mmbm-frame-maps-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    // Three frames, the readout the camera's (as render takes it), one outside the log.
    let table = tmp.join("frames.csv");
    std::fs::write(
        &table,
        "t_start,exposure_s\n2.0,0.004\n5.258,0.0013\n99.0,0.001\n",
    )
    .unwrap();
    let dir = tmp.join("maps");
    let cam_file = running_phone_camera();
    let out = frames_maps(&gyro, &table, &cam_file, &dir, &tmp.join("f.csv"), &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("maps: 2 frame(s)"), "{err}");
    let names: Vec<String> = {
        let mut v: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names, ["frame_000001.exr", "frame_000002.exr"]);
    let (w, h, ch) = mmbm::io::images::read_exr(&dir.join("frame_000002.exr")).unwrap();
    assert_eq!((w, h), (192, 108));
    let get = |n: &str| {
        ch.iter()
            .find(|c| c.0 == n)
            .unwrap_or_else(|| panic!("channel {n}"))
            .1
            .clone()
    };
    let log = read_log(&gyro, GyroOptions::default()).unwrap();
    let cam = example_camera("running_phone").scaled_to(192, 108);
    let f = VideoFrame {
        t_start: 5.258,
        exposure_s: 0.0013,
        readout_s: None,
    };
    let m = maps(&log, &opts(cam, None, false), 1, &f, None);
    for (name, v) in m.channels() {
        assert_eq!(get(name), v, "{name}");
    }
    let rmaps = tmp.join("render_maps.exr");
    let out = common::mmbm(&[
        "render",
        "--gyro",
        path(&gyro),
        "--at",
        "5.258",
        "--exposure",
        "0.0013",
        "--camera",
        path(&cam_file),
        "--scale-to",
        "192x108",
        "--target",
        "checker:0.05",
        "--distance",
        "3",
        "--backend",
        "cpu",
        "--maps",
        path(&rmaps),
        "--out",
        path(&tmp.join("img.png")),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (_, _, rch) = mmbm::io::images::read_exr(&rmaps).unwrap();
    let rget = |n: &str| rch.iter().find(|c| c.0 == n).unwrap().1.clone();
    let (rp, rd) = (rget("path_px"), rget("disp_px"));
    let mut worst: f64 = 0.0;
    for i in 0..rp.len() {
        let scale = 1.0 + rp[i] as f64;
        let d = (m.disp_u[i] as f64).hypot(m.disp_v[i] as f64);
        worst = worst
            .max((m.path_px[i] - rp[i]).abs() as f64 / scale)
            .max((d - rd[i] as f64).abs() / scale);
    }
    eprintln!("frames --maps vs render --maps: worst {worst:.2e} (relative to 1 + path px)");
    assert!(worst < 1e-3, "{worst}");
    // A file where the directory should be: refused before any work.
    let file = tmp.join("f.csv");
    let out = common::mmbm(&[
        "frames",
        "--gyro",
        path(&gyro),
        "--frames",
        path(&table),
        "--maps",
        path(&file),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("f.csv"), "{err}");
    let _ = std::fs::remove_dir_all(&tmp);
}
