//! One px/s definition everywhere: the true pixel speed, the flow in px/s on
//! each axis (`u` over `pitch_x`, `v` over `pitch_y`, plus the skew term)
//! averaged over the sensor. On an anamorphic camera (fx != fy) `eval`'s
//! px/s (every CPU method) equals the flow field's mean speed, and not the
//! mm/s over the horizontal pitch.

use crate::common;

use mmbm::field::{flow_field, Backend};
use mmbm::{mmbm, Camera, Method, Scene, Twist};

/// fx = 1.5 fy (pitch_y = 1.5 pitch_x), as an anamorphic profile.
fn anamorphic() -> Camera {
    let mut c = Camera::new(4.0, 0.004, 64, 48);
    c.pitch_y_mm = 0.006;
    c
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn eval_px_s_is_the_flow_fields_mean_speed_on_an_anamorphic_camera() {
    let scene = Scene {
        camera: anamorphic(),
        plane: None,
    };
    for omega in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, -0.7, 0.5]] {
        let tw = Twist::rotation(omega[0], omega[1], omega[2]);
        let f = flow_field(&scene, &tw, 0, 0, Backend::Cpu { threads: None }).unwrap();
        let speed = f.speed();
        let field_mean = speed.iter().map(|&s| s as f64).sum::<f64>() / speed.len() as f64;
        assert!(rel(f.mmbm.px_s, field_mean) < 1e-12, "{omega:?}");
        // The midpoint rule at the field's own cells is the same mean.
        let m = mmbm(&scene, &tw, Method::Riemann { nu: 64, nv: 48 }).unwrap();
        assert!(rel(m.mm_s, f.mmbm.mm_s) < 1e-5, "{omega:?}: {m:?}");
        assert!(
            rel(m.px_s, field_mean) < 1e-5,
            "{omega:?}: {} vs {field_mean}",
            m.px_s
        );
        // Not mm/s over the horizontal pitch (the old definition) where the
        // flow is mostly vertical (pitching about x).
        let old = m.mm_s / scene.camera.pitch_x_mm;
        if omega[0] == 1.0 {
            assert!(rel(old, m.px_s) > 0.3, "{omega:?}: {old} vs {}", m.px_s);
        }
        // Every CPU method estimates the same integral.
        for method in [
            Method::Gauss { nu: 24, nv: 18 },
            Method::Exact { tol: 1e-9 },
        ] {
            let e = mmbm(&scene, &tw, method).unwrap();
            assert!(
                rel(e.px_s, m.px_s) < 1e-3,
                "{method}: {} vs {}",
                e.px_s,
                m.px_s
            );
        }
    }
    // Square pixels: px/s is mm/s over the pitch, exactly.
    let square = Scene {
        camera: Camera::new(4.0, 0.004, 64, 48),
        plane: None,
    };
    let m = mmbm(
        &square,
        &Twist::rotation(0.3, -0.7, 0.5),
        Method::Gauss { nu: 8, nv: 6 },
    )
    .unwrap();
    assert_eq!(m.px_s, m.mm_s / 0.004);
}

/// The command line: `eval`'s px/s on an anamorphic camera file equals `flow`'s.
#[test]
fn eval_and_flow_print_the_same_px_s() {
    let d = tempfile::tempdir().unwrap();
    let cam = d.path().join("ana.toml");
    std::fs::write(
        &cam,
        "focal_mm = 4.0\npitch_x_mm = 0.004\npitch_y_mm = 0.006\nwidth = 64\nheight = 48\n",
    )
    .unwrap();
    let cam = cam.to_str().unwrap();
    let px = |out: &std::process::Output| -> f64 {
        let s = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{s}");
        let i = s.find(" px/s").unwrap_or_else(|| panic!("{s}"));
        s[..i].rsplit(' ').next().unwrap().parse().unwrap()
    };
    let e = common::mmbm(&[
        "eval",
        "--camera",
        cam,
        "--omega",
        "0.3,-0.7,0.5",
        "--method",
        "riemann:64x48",
    ]);
    let exr = d.path().join("f.exr");
    let f = common::mmbm(&[
        "flow",
        "--camera",
        cam,
        "--omega",
        "0.3,-0.7,0.5",
        "--out",
        exr.to_str().unwrap(),
    ]);
    let (a, b) = (px(&e), px(&f));
    assert!(rel(a, b) < 1e-5, "eval {a} vs flow {b}");
}

/// `series`' px/s column (and its blur) is the same true pixel speed as
/// `eval`'s, with a CPU method and with `gpu:WxH`'s midpoint cells.
#[test]
fn series_px_s_is_evals() {
    let d = tempfile::tempdir().unwrap();
    let cam = d.path().join("ana.toml");
    std::fs::write(
        &cam,
        "focal_mm = 4.0\npitch_x_mm = 0.004\npitch_y_mm = 0.006\nwidth = 64\nheight = 48\n",
    )
    .unwrap();
    let log = d.path().join("g.csv");
    std::fs::write(&log, "t,wx,wy,wz\n0,0.3,-0.7,0.5\n0.01,1,0,0\n").unwrap();
    let scene = Scene {
        camera: Camera::load(&cam).unwrap(),
        plane: None,
    };
    let (cam, log) = (cam.to_str().unwrap(), log.to_str().unwrap());
    let o = common::mmbm(&[
        "series",
        "--gyro",
        log,
        "--camera",
        cam,
        "--method",
        "gauss:6x5",
        "--exposure",
        "0.01",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    for (row, w) in text
        .lines()
        .skip(1)
        .zip([[0.3, -0.7, 0.5], [1.0, 0.0, 0.0]])
    {
        let f: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
        let m = mmbm(
            &scene,
            &Twist::rotation(w[0], w[1], w[2]),
            Method::Gauss { nu: 6, nv: 5 },
        )
        .unwrap();
        assert_eq!(f[1], m.mm_s, "{row}");
        assert_eq!(f[2], m.px_s, "{row}");
        assert_eq!(f[3], m.px_s * 0.01, "{row}");
    }
}

/// `frames`' blur_px is the same true pixel speed times the exposure: on
/// an anamorphic camera with a constant rotation, the exposure MMBM in px/s
/// of a frame is the flow field's mean pixel speed (and `riemann`'s px/s
/// on the same cells), not mm/s over the horizontal pitch; with square
/// pixels it is mm/s over the pitch, exactly as before. Every method gives
/// the same (the flow does not change in time).
#[test]
fn frames_blur_px_is_the_true_pixel_speed_times_the_exposure() {
    use glam::DVec3;
    use mmbm::io::frames::VideoFrame;
    use mmbm::series::frames::frame_mmbm;
    use mmbm::series::SeriesOptions;
    let w = DVec3::new(1.0, 0.2, -0.3);
    let samples = common::steady_rotation(w, 100, 0.01);
    let te = 0.02;
    let frame = [VideoFrame {
        t_start: 0.3,
        exposure_s: te,
        readout_s: None,
    }];
    let tw = Twist::rotation(w.x, w.y, w.z);
    for cam in [anamorphic(), Camera::new(4.0, 0.004, 64, 48)] {
        let scene = Scene {
            camera: cam,
            plane: None,
        };
        let field = flow_field(&scene, &tw, 0, 0, Backend::Cpu { threads: None }).unwrap();
        let riemann = Method::Riemann { nu: 64, nv: 48 };
        let m = mmbm(&scene, &tw, riemann).unwrap();
        for method in [
            riemann,
            Method::Gauss { nu: 8, nv: 6 },
            Method::Exact { tol: 1e-9 },
        ] {
            let opts = SeriesOptions {
                scene,
                method,
                use_velocity: false,
            };
            let (rows, _) = frame_mmbm(&samples, &opts, &frame).unwrap();
            let r = rows[0];
            let blur = r.blur_px().unwrap();
            let mm = r.exposure_mm_s.unwrap();
            let tol = if method == riemann { 1e-12 } else { 1e-3 };
            assert!(
                rel(blur, m.px_s * te) < tol,
                "{method}: {blur} vs {}",
                m.px_s * te
            );
            assert!(rel(blur, field.mmbm.px_s * te) < tol.max(1e-5), "{method}");
            if mmbm::metric::pixel_map(&cam).is_none() {
                assert_eq!(blur, mm / cam.pitch_x_mm * te, "{method}");
            } else {
                // The old definition, mm/s over pitch_x, is 20 % off here.
                let old = mm / cam.pitch_x_mm * te;
                assert!(rel(old, blur) > 0.1, "{method}: {old} vs {blur}");
            }
        }
    }
}

/// Exposure control on anamorphic pixels (pitch_y = 1.5 pitch_x): `mmbm
/// live` chooses the same exposures as `mmbm trigger` (both convert each
/// decision sample's mm/s with its own true pixel speed; the library test
/// `pixel_budgets_use_the_true_pixel_speed` checks the px budget itself).
#[test]
fn anamorphic_exposure_control_live_equals_offline() {
    let d = tempfile::tempdir().unwrap();
    let log = common::simulated_walk(d.path());
    let log_s = log.to_str().unwrap();
    let cam = d.path().join("ana.toml");
    std::fs::write(
        &cam,
        "focal_mm = 4.2548\npitch_x_mm = 0.00465\npitch_y_mm = 0.006975\nwidth = 640\nheight = 480\n",
    )
    .unwrap();
    let cam = cam.to_str().unwrap();
    let policy = "fixed:5+exp:0.5";
    let o = common::mmbm(&[
        "trigger", "--policy", policy, "--camera", cam, "--gyro", log_s,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut r = csv::Reader::from_reader(&o.stdout[..]);
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    let (ct, ce) = (col("trigger_t"), col("exposure_end"));
    let offline: Vec<(f64, f64)> = r
        .records()
        .map(|x| {
            let x = x.unwrap();
            (x[ct].parse().unwrap(), x[ce].parse().unwrap())
        })
        .collect();
    assert!(offline.len() > 10);
    let input = std::fs::read(&log).unwrap();
    let args = ["live", "--policy", policy, "--camera", cam];
    let o = common::mmbm_within(d.path(), &args, input, 120);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let live: Vec<(f64, f64)> = String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|v| v["trigger"] == true)
        .map(|v| {
            (
                v["t"].as_f64().unwrap(),
                v["exposure_end"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(&live[..offline.len()], &offline[..]);
}

/// The renderer's blur maps on anamorphic pixels: their mean speed in px/s
/// is the true pixel speed and in mm/s the sensor speed (a short exposure
/// of a steady rotation: both the instantaneous MMBM on the same pixels),
/// so the dataset's `mmbm_exposure_mm_s` is not px/s times pitch_x.
#[test]
fn blur_maps_give_both_speeds_on_anamorphic_pixels() {
    use mmbm::render::maps::blur_maps;
    use mmbm::render::{Target, Trajectory};
    let cam = anamorphic();
    let tw = Twist::rotation(0.9, -0.3, 0.4);
    let te = 1e-3;
    let traj = Trajectory::from_twist(tw, te).unwrap();
    let maps = blur_maps(&cam, &Target::checker(0.05, 1.5), &traj, te, 64);
    let m = maps.means();
    let scene = Scene {
        camera: cam,
        plane: None,
    };
    let want = mmbm(&scene, &tw, Method::Riemann { nu: 64, nv: 48 }).unwrap();
    assert!(
        rel(m.speed_mm_s, want.mm_s) < 2e-3,
        "{} vs {}",
        m.speed_mm_s,
        want.mm_s
    );
    assert!(
        rel(m.speed_px_s, want.px_s) < 2e-3,
        "{} vs {}",
        m.speed_px_s,
        want.px_s
    );
    assert!(rel(m.speed_px_s * cam.pitch_x_mm, want.mm_s) > 0.05);
}
