//! The benchmark's scores against closed forms, and its pickers on a tiny
//! clip (64x48, 30 frames) whose rotation is constant within each frame.

use crate::common;
use mmbm::model::log::GyroSample;
use mmbm_lab::pickers::clips::{self, ClipSpec, Format, Motion, Scene};
use mmbm_lab::pickers::pick::{self, Picker};
use mmbm_lab::pickers::score::{largest_hole, prf, score, tune_threshold};

const FPS: f64 = 30.0;

fn times(n: usize) -> Vec<f64> {
    (0..n).map(|k| k as f64 / FPS).collect()
}

/// The largest hole of a hand-made pick list: frames 1/30 s apart, picks
/// 2, 3, 7, 20 of 30: the holes are 2, 1, 4, 13 and 9 frame periods.
#[test]
fn largest_hole_of_a_hand_made_list() {
    let t = times(30);
    assert!((largest_hole(&[2, 3, 7, 20], &t) - 13.0 / 30.0).abs() < 1e-12);
    // The ends count: one pick at frame 0 leaves 29 periods.
    assert!((largest_hole(&[0], &t) - 29.0 / 30.0).abs() < 1e-12);
    // Nothing picked: the whole span.
    assert!((largest_hole(&[], &t) - 29.0 / 30.0).abs() < 1e-12);
}

/// Mean, share over 2 px, precision / recall / F1 and the tuned threshold
/// of hand-made lists.
#[test]
fn scores_of_hand_made_lists() {
    let truth = [1.0, 3.0, 0.5, 2.5, 1.5];
    let s = score(&[0, 1, 3], &truth, &times(5));
    assert!((s.mean_px - 6.5 / 3.0).abs() < 1e-12);
    assert!((s.over - 2.0 / 3.0).abs() < 1e-12);
    assert_eq!(s.picks, 3);
    // tp 2 (frames 0, 2), fp 1 (frame 1), fn 2 (frames 3, 4): precision
    // 2/3, recall 1/2, F1 2 (2/3)(1/2) / (2/3 + 1/2) = 4/7.
    let said = [true, true, true, false, false];
    let is = [true, false, true, true, true];
    let r = prf(&said, &is);
    assert!((r.precision - 2.0 / 3.0).abs() < 1e-12, "{r:?}");
    assert!((r.recall - 0.5).abs() < 1e-12, "{r:?}");
    assert!((r.f1 - 4.0 / 7.0).abs() < 1e-12, "{r:?}");
    // Sharpness that orders the frames as the truth does: the threshold
    // that calls exactly the sharp ones (truth <= 2) is the least sharpness
    // among them, 100 / 1.5.
    let sharp: Vec<f64> = truth.iter().map(|b| 100.0 / b).collect();
    let ok: Vec<bool> = truth.iter().map(|&b| b <= 2.0).collect();
    assert!((tune_threshold(&sharp, &ok) - 100.0 / 1.5).abs() < 1e-9);
}

/// Frame k's rate about y, rad/s: 0.3 + 0.05 ((7k + 3) mod 10), least
/// where 7k + 3 = 0 mod 10, i.e. k = 1 mod 10.
fn rate(k: usize) -> f64 {
    0.3 + 0.05 * ((7 * k + 3) % 10) as f64
}

/// A log at 1 kHz whose rate is `rate(k)` over frame k's busy time (its
/// exposure starting at `start + k / FPS`), switching 3 ms before it starts.
fn stepped_log(start: f64, frames: usize) -> Vec<GyroSample> {
    (0..((start + frames as f64 / FPS + 0.5) * 1000.0) as usize)
        .map(|i| {
            let t = i as f64 / 1000.0;
            let k = ((t - start + 0.003) * FPS)
                .floor()
                .clamp(0.0, frames as f64 - 1.0) as usize;
            GyroSample {
                t,
                omega: glam::DVec3::new(0.0, rate(k), 0.0),
                velocity: None,
                depth: None,
            }
        })
        .collect()
}

/// The gyro picker on a clip with a known offset and a rotation constant
/// within each frame picks the frames the rate schedule says (1, 11, 21),
/// as does the oracle from the rendered truth; a picker given the truth
/// picks as the oracle does; and the oracle's picks have the least mean
/// true blur of the pickers over the same windows.
#[test]
fn gyro_picks_what_the_truth_says_on_a_tiny_clip() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (start, n) = (0.5, 30);
    let log = dir.path().join("stepped.csv");
    mmbm::sim::write_log(&log, &stepped_log(start, n)).unwrap();
    let spec = ClipSpec {
        name: "tiny",
        what: "a stepped rotation over the poster",
        motion: Motion::Log {
            path: log,
            start_s: start,
        },
        scene: Scene::Poster,
        exposure_s: 0.01,
        seed: 7,
    };
    let f = Format {
        width: 64,
        height: 48,
        fps: FPS,
        frames: n,
        invisible: false,
    };
    let r = clips::render(&spec, &f, &common::repo_root(), dir.path()).unwrap();
    assert_eq!(r.frames(), n);
    // The truth follows the schedule: its least per window is at k = 1 mod 10.
    let want = vec![1, 11, 21];
    let window = 10;
    let m = pick::measure(&r, dir.path(), "tiny", window).unwrap();
    let truth = &r.truth;
    assert_eq!(
        pick::picks(Picker::Oracle, &m, truth, window, 0.0).unwrap(),
        want
    );
    assert_eq!(
        pick::picks(Picker::Gyro, &m, truth, window, 0.0).unwrap(),
        want
    );
    // A picker given the truth (sharpness = -blur) ranks as the oracle.
    let neg: Vec<f64> = truth.iter().map(|b| -b).collect();
    assert_eq!(pick::best_by(&neg, &m.t, window).unwrap(), want);
    // The oracle's picks have the least mean true blur of the windowed pickers.
    let oracle = score(&want, truth, &m.t).mean_px;
    for p in Picker::ALL
        .into_iter()
        .filter(|&p| p != Picker::LaplacianThreshold)
    {
        let picks = pick::picks(p, &m, truth, window, 0.0).unwrap();
        let s = score(&picks, truth, &m.t);
        if s.picks == 3 {
            assert!(
                oracle <= s.mean_px + 1e-12,
                "{}: {} < {oracle}",
                p.name(),
                s.mean_px
            );
        }
    }
}
