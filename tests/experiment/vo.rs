//! The benefit map with gyro logs (`[map] logs`, docs/experiment.md "My
//! robot, my light") and the odometry task's feature matches between
//! consecutive kept frames: a log is a column of the map in the report and
//! the heat map; a log without motion makes every policy tie (every frame
//! sharp, sharp frames/s = frame rate) with its frames trackable; a bad log
//! is refused naming the file.

use mmbm_lab::experiment::{self, cell_verdict, ExperimentConfig, TRACK_MIN};
use std::path::Path;

use crate::tiny_map;

/// Writes a CSV gyro log (docs/spec.md section 5) of `seconds` at 200 Hz
/// turning about the camera's y axis at `w(t)` rad/s.
fn write_log(path: &Path, seconds: f64, w: impl Fn(f64) -> f64) {
    let mut s = String::from("t,wx,wy,wz\n");
    let n = (seconds * 200.0).round() as usize;
    for k in 0..=n {
        let t = k as f64 / 200.0;
        s += &format!("{t:.4},0,{:.6},0\n", w(t));
    }
    std::fs::write(path, s).unwrap();
}

/// The tiny map at one bright light, `fixed:5` against `deadline:5` (the
/// grid's only exposure is `fixed:5`'s own), one seed.
fn config() -> ExperimentConfig {
    let mut cfg = tiny_map::config(&[100_000.0], &["deadline:5"], &[70.0]);
    cfg.map.seeds = vec![1];
    cfg
}

/// The PNG's width, px (IHDR).
fn png_width(path: &Path) -> u32 {
    let b = std::fs::read(path).unwrap();
    u32::from_be_bytes([b[16], b[17], b[18], b[19]])
}

#[test]
fn a_still_log_ties_every_policy_and_a_moving_one_is_a_column_too() {
    let d = tempfile::tempdir().unwrap();
    let still = d.path().join("still.csv");
    let moving = d.path().join("moving.csv");
    write_log(&still, 2.0, |_| 0.0);
    write_log(&moving, 2.0, |t| {
        0.6 * (std::f64::consts::TAU * 1.5 * t).sin()
    });
    let mut cfg = config();
    // The experiment's own log is a column too (no simulated gait with it).
    cfg.gyro = Some(moving.clone());
    cfg.map.logs = vec![still.clone()];
    let out = d.path().join("out");
    let o = experiment::run(&cfg, &out, false).unwrap();
    let m = o.map.as_ref().expect("a map");
    assert_eq!(m.gaits, ["still", "moving"]);
    assert_eq!(m.cells.len(), 2);
    for c in &m.cells {
        for p in &c.policies {
            eprintln!(
                "{}: {} {} frames {} sharp, rep. {:.2}, {:.1} inliers, {:.2} VO/s, {:.2} trackable/s",
                c.gait,
                p.policy,
                p.frames,
                p.sharp,
                p.corner_rep,
                p.mean_inliers,
                p.vo_fps,
                p.trackable_fps
            );
        }
    }
    let c = m.cells.iter().find(|c| c.gait == "still").unwrap();
    let names: Vec<&str> = c.policies.iter().map(|p| p.policy.as_str()).collect();
    assert_eq!(names, ["fixed:5", "deadline:5"]);
    for p in &c.policies {
        // No motion: every kept frame sharp, 5 frames/s over the 2-s log.
        assert!(p.frames >= 9 && p.sharp == p.frames, "{p:?}");
        // And each tracks the previous one (the poster behind the board).
        assert!(p.mean_inliers >= TRACK_MIN as f64, "{p:?}");
    }
    // A tie: each policy's sharp frames/s is its frame rate, so timing
    // gains nothing. `deadline:5` takes each slot's frame at the slot's end
    // when nothing moves, so its last exposure runs past the log's end: at
    // most one frame fewer, and its ratio to `fixed:5` (the strongest
    // baseline here) is that of the frame counts, nothing more.
    let (a, b) = (&c.policies[0], &c.policies[1]);
    assert!(a.frames.abs_diff(b.frames) <= 1, "{a:?} {b:?}");
    for p in [a, b] {
        assert!((p.sharp_fps * 2.0 - p.frames as f64).abs() < 0.02, "{p:?}");
    }
    let (_, _, r, base) = cell_verdict(c).expect("an mmbm policy and a baseline");
    assert_eq!(base, 0);
    assert!(
        (r.value - b.frames as f64 / a.frames as f64).abs() < 1e-12,
        "{r:?}"
    );
    // The report's map table and the heat map have a column per log.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("| light (e-/s) | still, half board | moving, half board |"),
        "{md}"
    );
    assert!(md.contains("**VO rule**"));
    // Two columns of 330 px in each of the two panels (130 px of labels
    // each) and the 120-px colour bar.
    assert_eq!(
        png_width(&out.join("benefit_map.png")),
        2 * (130 + 330 * 2) + 120
    );
}

#[test]
fn a_bad_log_is_refused_naming_the_file_before_any_output() {
    let d = tempfile::tempdir().unwrap();
    let short = d.path().join("short.csv");
    write_log(&short, 0.05, |_| 0.0);
    let garbage = d.path().join("garbage.csv");
    std::fs::write(&garbage, "t,wx,wy,wz\n0,0,zero,0\n").unwrap();
    let missing = d.path().join("missing.csv");
    for (log, why) in [
        (&short, "shorter than one frame interval"),
        (&garbage, "garbage.csv"),
        (&missing, "missing.csv"),
    ] {
        let mut cfg = config();
        cfg.map.logs = vec![log.clone()];
        let out = d.path().join("out");
        let e = experiment::run(&cfg, &out, false)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("map.logs") && e.contains(why), "{e}");
        assert!(!out.join("report.md").exists());
    }
    // Two logs of one name (the file stem) would be one column.
    let other = d.path().join("sub");
    std::fs::create_dir(&other).unwrap();
    write_log(&other.join("short.csv"), 2.0, |_| 0.0);
    write_log(&short, 2.0, |_| 0.0);
    let mut cfg = config();
    cfg.map.logs = vec![short.clone(), other.join("short.csv")];
    let e = experiment::run(&cfg, &d.path().join("out"), false)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("already a column"), "{e}");
}

#[test]
fn the_example_map_for_my_robot_loads_with_its_log() {
    let root = crate::common::repo_root();
    let cfg = ExperimentConfig::load(&root.join("examples/map-my-robot.toml")).unwrap();
    assert_eq!(cfg.map.logs.len(), 1);
    assert!(root.join(&cfg.map.logs[0]).is_file());
    assert_eq!(cfg.map.gaits, ["moderate"]);
}
