//! Rolling-shutter exposure MMBM of video frames (docs/spec.md section 3 and 9) against
//! independent computations: each line's window integrated directly, a
//! closed form for a yaw ramp, and the global-shutter time average.

use crate::common;

use glam::DVec3;
use mmbm::camera::{Readout, Shutter};
use mmbm::io::frames::{read_frames, VideoFrame};
use mmbm::io::gyro::{read_log, GyroOptions, GyroSample};
use mmbm::model::flow::flow_at;
use mmbm::series::frames::frame_mmbm;
use mmbm::series::{mmbm_series, SeriesOptions};
use mmbm::trigger::Integral;
use mmbm::{Camera, Method, Scene};
use std::path::Path;

fn opts(camera: Camera, method: Method) -> SeriesOptions {
    SeriesOptions {
        scene: Scene {
            camera,
            plane: None,
        },
        method,
        use_velocity: false,
    }
}

/// The independent computation: for every cell centre of an `nu x nv`
/// midpoint grid over the sensor rectangle (mm, as the metric defines it),
/// its row's window from the frame table, and the speed of the interpolated
/// motion integrated by sub-stepping: in each gyro interval the window
/// covers, `SUB` midpoints, at each the twist interpolated linearly between
/// the two samples and the flow straight from the formula.
fn direct(samples: &[GyroSample], cam: &Camera, f: &VideoFrame, nu: u32, nv: u32) -> f64 {
    const SUB: usize = 48;
    let readout = f.readout_s.unwrap();
    let r = cam.sensor_rect();
    let first = samples
        .partition_point(|s| s.t <= f.t_start)
        .saturating_sub(1);
    let mut total = 0.0;
    for j in 0..nv {
        let v = r.v0 + (j as f64 + 0.5) * (r.v1 - r.v0) / nv as f64;
        // The row holding the point: pixel row = v / pitch_y + cy (skew moves columns only).
        let row = (v / cam.pitch_y_mm + cam.cy + 1e-9).floor();
        let a = f.t_start + readout * row / cam.height as f64;
        let b = a + f.exposure_s;
        for i in 0..nu {
            let u = r.u0 + (i as f64 + 0.5) * (r.u1 - r.u0) / nu as f64;
            let mut integral = 0.0;
            for w in samples[first..].windows(2) {
                let (t0, t1) = (w[0].t, w[1].t);
                if t0 >= b {
                    break;
                }
                let (lo, hi) = (a.max(t0), b.min(t1));
                if hi <= lo {
                    continue;
                }
                let h = (hi - lo) / SUB as f64;
                for k in 0..SUB {
                    let t = lo + (k as f64 + 0.5) * h;
                    let omega = w[0].omega.lerp(w[1].omega, (t - t0) / (t1 - t0));
                    let (du, dv) = flow_at(
                        cam.focal_mm,
                        u,
                        v,
                        &mmbm::Twist::new(omega, DVec3::ZERO),
                        None,
                    );
                    integral += du.hypot(dv) * h;
                }
            }
            total += integral / f.exposure_s;
        }
    }
    total / (nu * nv) as f64
}

fn shared_frames(name: &str) -> Option<(Vec<GyroSample>, Vec<VideoFrame>)> {
    let gyro = common::shared_log(name)?;
    let frames = read_frames(&gyro.with_file_name("frames.csv")).unwrap();
    Some((
        read_log(&gyro, GyroOptions::default())
            .unwrap()
            .into_samples(),
        frames,
    ))
}

fn example_camera(name: &str) -> Camera {
    let p = crate::common::repo_root().join(format!("examples/cameras/{name}.toml"));
    Camera::load(&p).unwrap()
}

/// `frames` with a fine rule (a node on every line) against the direct
/// sub-stepped integration over the same nodes, on every frame of both
/// shared logs: 1e-4 relative (the bar; the midpoint sums' own error
/// is what is left).
#[test]
fn real_logs_match_direct_line_integration() {
    for name in ["running_phone", "dashboard_car"] {
        let Some((samples, frames)) = shared_frames(name) else {
            continue;
        };
        let cam = example_camera(name);
        let (nu, nv) = (4, cam.height);
        let (rows, outside) =
            frame_mmbm(&samples, &opts(cam, Method::Riemann { nu, nv }), &frames).unwrap();
        assert_eq!(rows.len(), frames.len());
        assert!(outside.len() <= 2, "{name}: {outside:?}");
        let mut worst: f64 = 0.0;
        let mut checked = 0;
        for (r, f) in rows.iter().zip(&frames) {
            let Some(m) = r.exposure_mm_s else {
                continue;
            };
            let d = direct(&samples, &cam, f, nu, nv);
            worst = worst.max((m - d).abs() / d);
            checked += 1;
        }
        eprintln!(
            "{name}: {checked} frames, riemann:{nu}x{nv}, worst relative difference {worst:.2e}"
        );
        assert_eq!(checked + outside.len(), frames.len());
        assert!(worst < 1e-4, "{name}: {worst}");
    }
}

/// With a global shutter a frame is the time average of the MMBM of the
/// interpolated motion: the log densified with the interpolated twist
/// (`SUB` samples per interval) and its series averaged over the window
/// converges to it; the MMBM at the start is that of the twist interpolated
/// to the start.
/// The old convention (the speeds' interpolation) is an upper bound.
#[test]
fn global_shutter_is_the_time_average_of_the_interpolated_series() {
    let Some((samples, frames)) = shared_frames("running_phone") else {
        return;
    };
    let cam = example_camera("running_phone");
    let gs: Vec<VideoFrame> = frames
        .iter()
        .map(|f| VideoFrame {
            readout_s: Some(0.0),
            exposure_s: 0.02,
            ..*f
        })
        .collect();
    let method = Method::Riemann { nu: 8, nv: 6 };
    let (rows, _) = frame_mmbm(&samples, &opts(cam, method), &gs).unwrap();
    const SUB: usize = 256;
    let mut dense = Vec::new();
    for w in samples.windows(2) {
        for k in 0..SUB {
            let s = k as f64 / SUB as f64;
            dense.push(GyroSample {
                t: w[0].t + s * (w[1].t - w[0].t),
                omega: w[0].omega.lerp(w[1].omega, s),
                ..w[0]
            });
        }
    }
    dense.push(*samples.last().unwrap());
    let scene = Scene {
        camera: cam,
        plane: None,
    };
    let series = |s: &[GyroSample]| {
        let t: Vec<f64> = s.iter().map(|s| s.t).collect();
        Integral::new(&t, &mmbm_series(s, &scene, method).unwrap())
    };
    let (fine, coarse) = (series(&dense), series(&samples));
    let (mut worst, mut lower, mut n): (f64, f64, usize) = (0.0, 0.0, 0);
    for r in rows.iter().filter(|r| r.exposure_mm_s.is_some()) {
        let got = r.exposure_mm_s.unwrap();
        let e = fine.mean(r.t_start, r.t_start + 0.02);
        worst = worst.max((got - e).abs() / e);
        let old = coarse.mean(r.t_start, r.t_start + 0.02);
        assert!(got <= old * (1.0 + 1e-12), "{r:?}: {got} above {old}");
        lower = lower.max((old - got) / old);
        // The start: the MMBM of the twist interpolated to t_start.
        let j = samples.partition_point(|s| s.t <= r.t_start);
        let (p, q) = (samples[j - 1], samples[j]);
        let at = GyroSample {
            t: r.t_start,
            omega: p.omega.lerp(q.omega, (r.t_start - p.t) / (q.t - p.t)),
            ..p
        };
        let s = mmbm_series(&[at], &scene, method).unwrap()[0];
        assert!(
            (r.start_mm_s.unwrap() - s).abs() < 1e-12 * s,
            "{r:?} vs {s}"
        );
        n += 1;
    }
    eprintln!("{n} frames: worst {worst:.2e} from the densified series; up to {lower:.2e} below the speeds' interpolation");
    assert!(n > 500 && worst < 2e-6, "{worst}");
    assert!(
        lower > 1e-3,
        "the flow turns within some intervals of this log: {lower}"
    );
}

/// A yaw ramp w_y = c t: every point's speed is |c t| g(u, v), so a line's
/// window mean is c (t0 + delay + t_e / 2) g: the later lines see more blur,
/// in the readout direction (signs and directions included).
#[test]
fn yaw_ramp_closed_form_and_directions() {
    let c = 2.0;
    let samples: Vec<GyroSample> = (0..=2000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            GyroSample {
                t,
                omega: DVec3::new(0.0, c * t, 0.0),
                velocity: None,
                depth: None,
            }
        })
        .collect();
    let (te, tr, t0) = (0.01, 0.03, 0.5);
    let frame = [VideoFrame {
        t_start: t0,
        exposure_s: te,
        readout_s: Some(tr),
    }];
    let mut values = vec![];
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
            ..Camera::thesis()
        };
        let (nu, nv) = (8, 6);
        let (rows, _) =
            frame_mmbm(&samples, &opts(cam, Method::Riemann { nu, nv }), &frame).unwrap();
        // Closed form over the same nodes.
        let mut expect = 0.0;
        for j in 0..nv {
            for i in 0..nu {
                let (px, py) = ((i as f64 + 0.5) * 80.0, (j as f64 + 0.5) * 80.0);
                let (u, v) = cam.pixel_to_mm(px, py);
                let g = {
                    let (du, dv) = flow_at(
                        cam.focal_mm,
                        u,
                        v,
                        &mmbm::Twist::rotation(0.0, 1.0, 0.0),
                        None,
                    );
                    du.hypot(dv)
                };
                let delay = cam.shutter.delay_s(px, py, 640, 480);
                expect += c * (t0 + delay + te / 2.0) * g / 48.0;
            }
        }
        let got = rows[0].exposure_mm_s.unwrap();
        assert!(
            (got - expect).abs() < 1e-12 * expect,
            "{dir:?}: {got} vs {expect}"
        );
        values.push(got);
    }
    let global = {
        let (rows, _) = frame_mmbm(
            &samples,
            &opts(Camera::thesis(), Method::Riemann { nu: 8, nv: 6 }),
            &[VideoFrame {
                readout_s: Some(0.0),
                ..frame[0]
            }],
        )
        .unwrap();
        rows[0].exposure_mm_s.unwrap()
    };
    // Later lines, more blur: on a rising ramp any readout adds to it.
    assert!(values.iter().all(|&v| v > global), "{values:?} vs {global}");
}

fn run(args: &[&str]) -> (bool, String, String) {
    let out = common::mmbm(args);
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn cli_frames_select_and_errors() {
    let Some(gyro) = common::shared_log("running_phone") else {
        return;
    };
    let frames = gyro.with_file_name("frames.csv");
    let cam = crate::common::repo_root().join("examples/cameras/running_phone.toml");
    let base = [
        "frames",
        "--gyro",
        path(&gyro),
        "--frames",
        path(&frames),
        "--camera",
        path(&cam),
    ];
    let (ok, all, err) = run(&base);
    assert!(ok, "{err}");
    assert!(err.contains("warning: 2 frame(s) reach outside"), "{err}");
    let lines: Vec<&str> = all.lines().collect();
    assert_eq!(
        lines[0],
        "frame,t_start,exposure_mmbm_mm_s,blur_px,start_mmbm_mm_s,exposure_s,readout_s"
    );
    assert_eq!(lines.len(), 589);
    assert!(
        lines[1].starts_with("0,") && lines[1].contains(",,,,"),
        "outside: empty values"
    );
    let blur = |l: &str| l.split(',').nth(3).unwrap().parse::<f64>().ok();
    let (ok, sel, err) = run(&[&base[..], &["--select", "5", "--gap", "0.5"]].concat());
    assert!(ok, "{err}");
    let picked: Vec<&str> = sel.lines().skip(1).collect();
    assert_eq!(picked.len(), 5);
    let min_all = lines
        .iter()
        .skip(1)
        .filter_map(|l| blur(l))
        .fold(f64::INFINITY, f64::min);
    assert!(
        picked.iter().any(|l| blur(l) == Some(min_all)),
        "the sharpest frame is picked"
    );
    let ts: Vec<f64> = picked
        .iter()
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    for (a, b) in ts.iter().zip(ts.iter().skip(1)) {
        assert!(b - a >= 0.5, "{ts:?}");
    }
    let (ok, _, err) = run(&[&base[..], &["--method", "gpu"]].concat());
    assert!(
        !ok && err.contains("gpu is not available for frames"),
        "{err}"
    );
    let (ok, _, err) = run(&[&base[..], &["--method", "exact:1e-6"]].concat());
    assert!(!ok && err.contains("riemann:64x1080"), "{err}");
    let bad = std::env::temp_dir().join(format!("mmbm-frames-{}.csv", std::process::id()));
    std::fs::write(&bad, "# c\nt_start,exposure_s\n0.1,0.01\n0.2,abc\n").unwrap();
    let (ok, _, err) = run(&["frames", "--gyro", path(&gyro), "--frames", path(&bad)]);
    assert!(!ok && err.contains(":4:exposure_s"), "{err}");
}

/// The table of the running log's sharpest and blurriest frames in
/// `docs/cli.md` is
/// what `mmbm frames` computes (frames, order and every printed digit), as is
/// the sentence before it (frames inside the log, median blur).
#[test]
fn docs_frames_table_is_current() {
    let Some((samples, frames)) = shared_frames("running_phone") else {
        return;
    };
    let cam = example_camera("running_phone");
    let (rows, _) = frame_mmbm(
        &samples,
        &opts(cam, Method::Riemann { nu: 8, nv: 6 }),
        &frames,
    )
    .unwrap();
    let mut inside: Vec<_> = rows.iter().filter(|r| r.exposure_mm_s.is_some()).collect();
    inside.sort_by(|a, b| a.blur_px().unwrap().total_cmp(&b.blur_px().unwrap()));
    let n = inside.len();
    let median = {
        let b: Vec<f64> = inside.iter().map(|r| r.blur_px().unwrap()).collect();
        0.5 * (b[(n - 1) / 2] + b[n / 2])
    };
    let mut expect: Vec<String> = inside[..5]
        .iter()
        .chain(&inside[n - 5..])
        .map(|r| {
            format!(
                "| {} | {:.3} | {:.4} | {:.3} | {:.4} |",
                r.frame,
                r.t_start,
                r.exposure_mm_s.unwrap(),
                r.blur_px().unwrap(),
                r.start_mm_s.unwrap()
            )
        })
        .collect();
    expect.insert(0, "|---|---|---|---|---|".into());
    expect.insert(
        0,
        "| frame | t_start (s) | exposure MMBM (mm/s) | blur (px) | MMBM at start (mm/s) |".into(),
    );
    let doc = std::fs::read_to_string(crate::common::repo_root().join("docs/cli.md")).unwrap();
    let start = doc
        .find("<!-- frames-table")
        .expect("docs/cli.md frames table");
    let end = doc.find("<!-- /frames-table -->").unwrap();
    let table: Vec<&str> = doc[start..end]
        .lines()
        .skip(1)
        .filter(|l| !l.is_empty())
        .collect();
    assert_eq!(table, expect, "docs/cli.md table vs computed");
    let sentence = format!("{n} frames inside the log, median blur {median:.2} px");
    assert!(
        doc.contains(&sentence),
        "docs/cli.md should say: {sentence}"
    );
}

/// Through a lens, and one masked beyond its radial distortion limit,
/// every method of `frames` gives the mean over the unmasked sensor, as
/// `eval` does (a constant rotation: the exposure MMBM is the instantaneous
/// one). The grid rules used to sum each line's own mean (a lens rescales
/// a line's weights to 1), and `exact` reached the masked corners and
/// failed as not finite.
#[test]
fn masked_lens_frames_are_the_mean_over_the_unmasked_sensor() {
    use mmbm::camera::Distortion;
    let masked = common::turning_fisheye();
    assert!(masked.masked_fraction() > 0.05);
    let wide = Camera {
        distortion: Distortion::WIDE_ANGLE,
        ..Camera::new(1.0, 0.01, 64, 48)
    };
    let w = DVec3::new(0.3, -0.5, 0.8);
    let samples = common::steady_rotation(w, 10, 0.01);
    let frame = [VideoFrame {
        t_start: 0.02,
        exposure_s: 0.03,
        readout_s: None,
    }];
    let tw = mmbm::Twist::rotation(w.x, w.y, w.z);
    for cam in [masked, wide] {
        let scene = Scene {
            camera: cam,
            plane: None,
        };
        for method in [
            Method::Exact { tol: 1e-8 },
            Method::Riemann { nu: 64, nv: 48 },
            Method::Gauss { nu: 8, nv: 6 },
        ] {
            let (rows, _) = frame_mmbm(&samples, &opts(cam, method), &frame).unwrap();
            let got = rows[0].exposure_mm_s.unwrap();
            let want = mmbm::mmbm(&scene, &tw, method).unwrap().mm_s;
            assert!(
                (got - want).abs() < 1e-6 * want,
                "{method}: {got} vs {want}"
            );
        }
    }
}
