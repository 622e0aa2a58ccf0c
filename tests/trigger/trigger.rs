//! Trigger policies: each rule checked on crafted logs, camera-busy and
//! causality invariants, quality ordering on the simulated gaits.

use glam::DVec3;
use mmbm::io::gyro::GyroSample;
use mmbm::series::mmbm_series;
use mmbm::sim::{simulate, Gait, GaitConfig};
use mmbm::trigger::*;
use mmbm::{Method, Scene};

fn log(t: &[f64]) -> Vec<GyroSample> {
    t.iter()
        .map(|&t| GyroSample {
            t,
            omega: DVec3::ZERO,
            velocity: None,
            depth: None,
        })
        .collect()
}

fn grid(n: usize, dt: f64) -> Vec<f64> {
    (0..n).map(|i| i as f64 * dt).collect()
}

fn timing0() -> CameraTiming {
    CameraTiming {
        delay: 0.0,
        exposure: 0.05,
        readout: 0.0,
        min_interval: 0.2,
        ..CameraTiming::default()
    }
}

fn go(spec: &str, s: &[GyroSample], m: &[f64], tm: &CameraTiming) -> Vec<Frame> {
    run(s, m, parse_policy(spec).unwrap().as_mut(), tm).unwrap()
}

fn sim(g: Gait, secs: f64, seed: u64) -> (Vec<GyroSample>, Vec<f64>) {
    let s = simulate(&GaitConfig::preset(g), secs, 600.0, seed).unwrap();
    let m = mmbm_series(&s, &Scene::thesis(), Method::default()).unwrap();
    (s, m)
}

/// The hand-made log of the thesis-rule test (100 Hz, 1 s).
fn crafted() -> Vec<f64> {
    let mut m = vec![0.3; 100];
    m[..6].copy_from_slice(&[1.0, 0.9, 0.5, 0.35, 0.3, 0.25]);
    m[30..36].copy_from_slice(&[0.39, 0.38, 0.37, 0.36, 0.35, 0.34]);
    m[60..65].copy_from_slice(&[0.5, 0.45, 0.3, 0.2, 0.1]);
    m
}

#[test]
fn thesis_rule_by_hand() {
    let m = crafted();
    let s = log(&grid(100, 0.01));
    let f = go("threshold:0.4", &s, &m, &timing0());
    // i=5: 0.35 > 0.3 > 0.25, all < 0.4. Next allowed from t=0.25:
    // i=32 (0.39 > 0.38 > 0.37); i=33..35 blocked by the interval;
    // i=62, 63 fail (0.5, 0.45 not below); i=64: 0.3 > 0.2 > 0.1.
    let idx: Vec<usize> = f.iter().map(|f| f.index).collect();
    assert_eq!(idx, vec![5, 32, 64]);
    assert_eq!(f[0].trigger_t, 0.05);
    assert_eq!(f[0].mmbm_trigger_mm_s, 0.25);
    // Exposure [0.05, 0.10]: 0.01 s averaging 0.275 then 0.04 s at 0.3.
    assert!((f[0].mmbm_exposure_mm_s - 0.295).abs() < 1e-12);
    assert!(f.iter().all(|f| f.kept && f.policy == "threshold:0.4"));
    // Threshold 0.36: i=5; i=32..35 fail (0.39.., 0.36 not below 0.36);
    // i=36: 0.35 > 0.34 > 0.3, all below; then i=64.
    let f = go("threshold:0.36", &s, &m, &timing0());
    let idx: Vec<usize> = f.iter().map(|f| f.index).collect();
    assert_eq!(idx, vec![5, 36, 64]);
    // Threshold 0.25: needs all three below 0.25: only 0.2 > 0.1 preceded by 0.3: none.
    assert!(go("threshold:0.25", &s, &m, &timing0()).is_empty());
}

#[test]
fn camera_busy_blocks_triggers() {
    let m = vec![0.1; 1000];
    let s = log(&grid(1000, 0.001));
    let tm = CameraTiming {
        delay: 0.0025,
        exposure: 0.05,
        readout: 0.02,
        min_interval: 0.0,
        ..CameraTiming::default()
    };
    // 100 fps asks every 10 ms; the camera is busy 72.5 ms per frame.
    let f = go("fixed:100", &s, &m, &tm);
    assert!(!f.is_empty());
    for w in f.windows(2) {
        assert!(w[1].exposure_start >= w[0].exposure_end + tm.readout - 1e-12);
    }
    // Slots every 10 ms: the frame at 0 keeps the camera busy until 0.0725; the
    // pulse of the slot at 0.07 arrives at 0.0725 (after the delay): accepted.
    assert!((f[1].trigger_t - 0.07).abs() < 1e-9, "{}", f[1].trigger_t);
    // Every policy on a simulated walk.
    let (s, m) = sim(Gait::Moderate, 20.0, 3);
    let tm = CameraTiming {
        readout: 0.05,
        ..CameraTiming::default()
    };
    for spec in [
        "fixed:10",
        "threshold:0.8",
        "adaptive",
        "oracle:0.8:0.05",
        "forecast:0.8",
        "phase:0.8",
        "gate:0.5:12",
        "deadline:10",
        "deadline:10:0.5",
    ] {
        let f = go(spec, &s, &m, &tm);
        assert!(f.len() > 10, "{spec}");
        for w in f.windows(2) {
            assert!(
                w[1].exposure_start >= w[0].exposure_end + tm.readout - 1e-12,
                "{spec}"
            );
        }
    }
}

#[test]
fn causal_policies_never_read_the_future() {
    let (s, m) = sim(Gait::Moderate, 24.0, 5);
    let cut = 600 * 13 + 7;
    let tm = CameraTiming::default();
    for spec in [
        "fixed:5@0.03",
        "threshold:0.4",
        "adaptive",
        "adaptive:0.3:3",
        "forecast:0.4",
        "phase:0.4",
        "phase:0.5:0.3",
        "gate:0.5",
        "deadline:5",
        "deadline:5:0.4",
        "fixed:5+exp:2",
        "phase:0.4+exp:1.5:0.005",
    ] {
        let full = go(spec, &s, &m, &tm);
        let part = go(spec, &s[..cut], &m[..cut], &tm);
        let t_last = s[cut - 1].t;
        let want: Vec<Frame> = full
            .into_iter()
            .filter(|f| f.exposure_end <= t_last)
            .collect();
        assert!(part.len() > 20, "{spec}");
        assert_eq!(part, want, "{spec}");
        assert!(parse_policy(spec).unwrap().is_causal());
    }
    assert!(!parse_policy("oracle:0.4").unwrap().is_causal());
}

#[test]
fn fixed_rate_and_phase() {
    let s = log(&grid(6000, 1.0 / 600.0));
    let m = vec![1.0; 6000];
    let tm = CameraTiming::default();
    let f = go("fixed:5", &s, &m, &tm);
    assert_eq!(f.len(), 50);
    for (k, fr) in f.iter().enumerate() {
        // The first sample at or after k / 5 s.
        let want = (k as f64 * 0.2 * 600.0 - 1e-9).ceil() / 600.0;
        assert!(
            (fr.trigger_t - want).abs() < 1e-12,
            "{k}: {} vs {want}",
            fr.trigger_t
        );
        assert_eq!(fr.exposure_start, fr.trigger_t + 0.0025);
        assert_eq!(fr.exposure_end, fr.exposure_start + 0.07);
    }
    let f = go("fixed:5@0.03", &s, &m, &tm);
    assert!((f[0].trigger_t - 0.03).abs() < 1e-12);
    assert_eq!(f[0].policy, "fixed:5@0.03");
}

#[test]
fn policy_strings_round_trip_and_bad_ones_fail() {
    let (s, m) = sim(Gait::Slow, 10.0, 1);
    for spec in [
        "fixed:5",
        "threshold:0.4",
        "threshold:p20",
        "adaptive",
        "adaptive:0.3",
        "oracle:0.4",
        "forecast:0.4:0.1",
        "phase:0.4:0.1",
        "gate:0.8",
        "gate:0.8:4@0.1",
        "deadline:5",
        "deadline:5:0.4",
        "deadline:5+exp:2",
        "threshold:p20+exp:3:0.01",
    ] {
        let f = go(spec, &s, &m, &CameraTiming::default());
        assert!(!f.is_empty(), "{spec}");
        assert!(f.iter().all(|f| f.policy == spec), "{spec}");
        assert_eq!(parse_policy(spec).unwrap().spec(), spec);
    }
    for bad in [
        "",
        "fixed",
        "fixed:0",
        "fixed:-5",
        "fixed:5@x",
        "threshold",
        "threshold:-1",
        "threshold:p101",
        "threshold:abc",
        "oracle:0.4:0",
        "deadline",
        "gate:0.4:5:1",
        "warp:9",
        "fixed:5+exp",
        "fixed:5+exp:0",
        "fixed:5+exp:2:-1",
        "fixed:5+gain:2",
        "+exp:2",
        "warp:9+exp:2",
    ] {
        let e = parse_policy(bad)
            .err()
            .unwrap_or_else(|| panic!("'{bad}' accepted"));
        assert!(e.to_string().contains("policy"), "{bad}: {e}");
    }
}

#[test]
fn exposure_control_by_hand() {
    // MMBM steps 0.5 -> 0.05 -> 5 -> 0 mm/s (each held 1 s). With a 2 px
    // budget and the 4.65 um pitch: t_e = 2 * 0.00465 / M, clamped to
    // [1 ms, 70 ms]; the gain is 70 ms / t_e; the timing is fixed:5's.
    let n = 2400;
    let t = grid(n, 1.0 / 600.0);
    let m: Vec<f64> = t
        .iter()
        .map(|&x| [0.5, 0.05, 5.0, 0.0][(x as usize).min(3)])
        .collect();
    let tm = CameraTiming::default();
    let fixed = go("fixed:5", &log(&t), &m, &tm);
    let f = go("fixed:5+exp:2", &log(&t), &m, &tm);
    assert_eq!(f.len(), fixed.len());
    for (a, b) in f.iter().zip(&fixed) {
        assert_eq!(a.trigger_t, b.trigger_t);
        let x = a.mmbm_trigger_mm_s;
        let want = if x == 0.5 {
            2.0 * 0.00465 / 0.5 // 18.6 ms
        } else if x == 5.0 {
            0.002 * 0.93 // 1.86 ms
        } else {
            0.07 // 0.05 mm/s asks 186 ms: the camera's 70 ms; no motion: the same
        };
        assert!((a.exposure_s() - want).abs() < 1e-12, "{a:?}");
        assert!((a.gain - 0.07 / want).abs() < 1e-9, "{a:?}");
        assert_eq!(a.exposure_start, b.exposure_start);
    }
    // The shortest exposure bounds it: 5 ms at 5 mm/s.
    let f = go("fixed:5+exp:2:0.005", &log(&t), &m, &tm);
    let fast: Vec<_> = f.iter().filter(|a| a.mmbm_trigger_mm_s == 5.0).collect();
    assert!(!fast.is_empty());
    for a in fast {
        assert!((a.exposure_s() - 0.005).abs() < 1e-12 && (a.gain - 14.0).abs() < 1e-9);
    }
    // The predicted blur over the exposure is the budget where the MMBM is
    // constant over the exposure (the 0.5 mm/s second): 2 px.
    for a in go("fixed:5+exp:2", &log(&t), &m, &tm)
        .iter()
        .filter(|a| a.exposure_end < 0.99)
    {
        let px = a.mmbm_exposure_mm_s * a.exposure_s() / tm.pitch_mm;
        assert!((px - 2.0).abs() < 1e-9, "{px}");
    }
}

#[test]
fn percentile_thresholds_by_hand() {
    let m = [5.0, 1.0, 4.0, 2.0, 3.0];
    assert_eq!(Level::parse("p25", "x").unwrap().resolve(&m).unwrap(), 2.0);
    assert_eq!(Level::parse("p50", "x").unwrap().resolve(&m).unwrap(), 3.0);
    assert_eq!(Level::parse("p10", "x").unwrap().resolve(&m).unwrap(), 1.4);
    assert_eq!(Level::parse("0.4", "x").unwrap(), Level::Abs(0.4));
}

#[test]
fn gate_discards_and_summaries_exclude() {
    let (s, m) = sim(Gait::Moderate, 20.0, 2);
    let tm = CameraTiming::default();
    let f = go("gate:0.5", &s, &m, &tm);
    let fixed = go("fixed:5", &s, &m, &tm);
    assert_eq!(f.len(), fixed.len());
    for (g, x) in f.iter().zip(&fixed) {
        assert_eq!(g.trigger_t, x.trigger_t);
        assert_eq!(g.kept, g.mmbm_exposure_mm_s <= 0.5);
    }
    let kept = f.iter().filter(|f| f.kept).count();
    assert!(kept > 0 && kept < f.len());
    let sm = summary_over(&f, 20.0);
    assert_eq!((sm.frames, sm.kept), (f.len(), kept));
    assert!(sm.max_mm_s <= 0.5);
    assert!((sm.effective_fps - kept as f64 / 20.0).abs() < 1e-12);
}

#[test]
fn summary_and_table51_by_hand() {
    let fr = |t: f64, trig: f64, exp: f64, kept: bool| Frame {
        policy: mmbm::trigger::PolicySpec::custom("p"),
        index: 0,
        trigger_t: t,
        exposure_start: t,
        exposure_end: t + 0.1,
        mmbm_trigger_mm_s: trig,
        mmbm_exposure_mm_s: exp,
        kept,
        gain: 1.0,
    };
    let f = vec![
        fr(0.0, 0.5, 1.0, true),
        fr(0.2, 1.0, 0.5, true),
        fr(0.4, 0.2, 0.3, true),
        fr(0.6, 1.0, 9.0, false),
    ];
    let s = summary_over(&f, 2.0);
    assert_eq!((s.frames, s.kept), (4, 3));
    assert!((s.effective_fps - 1.5).abs() < 1e-12);
    assert!((s.mean_mm_s - 0.6).abs() < 1e-12);
    assert!((s.max_mm_s - 1.0).abs() < 1e-12);
    // p95 of [0.3, 0.5, 1.0]: rank 1.9 -> 0.5 + 0.9 * 0.5.
    assert!((s.p95_mm_s - 0.95).abs() < 1e-12);
    // Span rate: 4 frames over 0.6 s * 4/3 = 0.8 s; 3 kept -> 3.75 fps.
    assert!((summary(&f).effective_fps - 3.75).abs() < 1e-12);
    // Errors (exp - trig): 0.5, -0.5, 0.1, 8.0; percent: 100, -50, 50, 800.
    let t = prediction_error(&f);
    assert!((t.abs.min + 0.5).abs() < 1e-12 && (t.abs.max - 8.0).abs() < 1e-12);
    assert!((t.abs.mean - 2.025).abs() < 1e-12);
    assert!((t.abs.mean_abs - 2.275).abs() < 1e-12);
    let var = [0.5f64, -0.5, 0.1, 8.0]
        .iter()
        .map(|x| (x - 2.025).powi(2))
        .sum::<f64>()
        / 3.0;
    assert!((t.abs.std - var.sqrt()).abs() < 1e-12);
    assert!((t.pct.mean - 225.0).abs() < 1e-9 && (t.pct.min + 50.0).abs() < 1e-9);
}

#[test]
fn oracle_rule_sample_by_sample() {
    let (s, m) = sim(Gait::Moderate, 20.0, 4);
    let tm = CameraTiming::default();
    let t: Vec<f64> = s.iter().map(|x| x.t).collect();
    let e = exposure_means(&t, &m, &tm);
    let f = go("oracle:0.4", &s, &m, &tm);
    assert!(f.len() > 20);
    for fr in &f {
        let i = fr.index;
        assert!((e[i] - fr.mmbm_exposure_mm_s).abs() < 1e-12);
        assert!(e[i] < 0.4);
        for j in i + 1..t.len() {
            if t[j] > t[i] + 0.2 {
                break;
            }
            assert!(
                e[i] <= e[j],
                "frame at {} is not the minimum of the next 0.2 s",
                t[i]
            );
        }
    }
    // Between frames, no admissible instant was skipped: any sample that met
    // the rule with the camera free and the interval passed triggered.
    let fm: std::collections::HashSet<usize> = f.iter().map(|f| f.index).collect();
    let mut last: Option<f64> = None;
    let mut free = f64::NEG_INFINITY;
    for i in 0..t.len() {
        if t[i] + tm.delay + tm.exposure > t[t.len() - 1] {
            break;
        }
        let fut = (i + 1..t.len())
            .take_while(|&j| t[j] <= t[i] + 0.2)
            .map(|j| e[j])
            .fold(f64::INFINITY, f64::min);
        let ok = t[i] + tm.delay >= free
            && last.is_none_or(|l| t[i] - l >= 0.2 - 1e-9)
            && e[i] < 0.4
            && e[i] <= fut;
        assert_eq!(ok, fm.contains(&i), "sample {i}");
        if ok {
            last = Some(t[i]);
            free = t[i] + tm.delay + tm.exposure + tm.readout;
        }
    }
}

#[test]
fn adaptive_raises_an_unreachable_threshold() {
    // A sawtooth between 1.0 and 0.9: never below 0.4, strictly decreasing runs.
    let n = 2000;
    let m: Vec<f64> = (0..n).map(|i| 1.0 - 0.01 * (i % 11) as f64).collect();
    let s = log(&grid(n, 0.005));
    let tm = CameraTiming::default();
    assert!(go("threshold:0.4", &s, &m, &tm).is_empty());
    // 1.5 * min (0.9) = 1.35 > 1.0: every strictly decreasing triple fires once
    // the interval allows: the first at i = 2.
    let f = go("adaptive:0.4", &s, &m, &tm);
    assert_eq!(f[0].index, 2);
    for w in f.windows(2) {
        assert!(w[1].trigger_t - w[0].trigger_t >= 0.2 - 1e-9);
    }
    assert!(f.len() > 30);
}

#[test]
fn deadline_keeps_the_fixed_frame_count() {
    for g in [Gait::Slow, Gait::Moderate, Gait::Fast] {
        let (s, m) = sim(g, 30.0, 6);
        let tm = CameraTiming::default();
        let fixed = go("fixed:5", &s, &m, &tm).len();
        for spec in ["deadline:5", "deadline:5:0.4"] {
            let f = go(spec, &s, &m, &tm);
            assert!(f.len() + 1 >= fixed, "{g} {spec}: {} vs {fixed}", f.len());
            // One frame per 0.2 s slot.
            let mut slots: Vec<i64> = f
                .iter()
                .map(|f| (f.trigger_t / 0.2).floor() as i64)
                .collect();
            slots.dedup();
            assert_eq!(slots.len(), f.len(), "{g} {spec}");
        }
    }
}

#[test]
fn forecast_finds_the_period_of_a_periodic_log() {
    let n = 6000;
    let t = grid(n, 1.0 / 600.0);
    let m: Vec<f64> = t
        .iter()
        .map(|&t| (std::f64::consts::PI * t / 0.7).sin().powi(2))
        .collect();
    let mut p = Forecast::new("forecast:0.2", Level::Abs(0.2), 0.2);
    let f = run(&log(&t), &m, &mut p, &CameraTiming::default()).unwrap();
    assert!((p.period().unwrap() - 0.7).abs() < 0.01, "{:?}", p.period());
    // After the first 4 s the forecast is exact for a periodic log: every frame
    // sits at a minimum with exposure MMBM well below the threshold.
    for fr in f.iter().filter(|f| f.trigger_t > 4.5) {
        assert!(fr.mmbm_exposure_mm_s < 0.2, "{fr:?}");
    }
}

#[test]
fn phase_learns_touchdowns_of_a_clocked_gait() {
    // A gait clock of 0.8 s with touchdowns jittered by +-30 ms: each step is
    // a sharp transient (1.5 mm/s decaying over 0.1 s) on a 0.2 mm/s floor,
    // with a second, smaller bump (0.25 mm/s) at 0.5 s after touchdown. The phase policy
    // must find the touchdowns (each within 1 sample of the level crossing
    // it reports) and, once locked, put every frame in a quiet part.
    let n = 600 * 30;
    let t = grid(n, 1.0 / 600.0);
    let jitter = [0.0, 0.03, -0.02, 0.01, -0.03, 0.02, 0.0, -0.01];
    let td: Vec<f64> = (0..40).map(|k| 0.8 * k as f64 + jitter[k % 8]).collect();
    let m: Vec<f64> = t
        .iter()
        .map(|&x| {
            let k = td.partition_point(|&d| d <= x);
            let s = if k == 0 { 10.0 } else { x - td[k - 1] };
            0.2 + 1.5 * (-s / 0.03).exp() + 0.25 * (-((s - 0.5) / 0.05).powi(2)).exp()
        })
        .collect();
    let mut p = Phase::new("phase:0.4", Level::Abs(0.4), 0.2);
    let f = run(&log(&t), &m, &mut p, &CameraTiming::default()).unwrap();
    let found: Vec<f64> = p.touchdowns().collect();
    assert_eq!(found.len(), Phase::CYCLES + 1);
    for x in &found {
        // The level crossing lies on the transient's rise, within 2 samples of the touchdown.
        let near = td.iter().map(|d| (x - d).abs()).fold(f64::MAX, f64::min);
        assert!(
            near <= 2.0 / 600.0,
            "touchdown at {x}: {near} s from the nearest"
        );
    }
    let late: Vec<_> = f.iter().filter(|f| f.trigger_t > 10.0).collect();
    assert!(late.len() >= 20, "{}", late.len());
    for fr in late {
        assert!(fr.mmbm_exposure_mm_s < 0.3, "{fr:?}");
    }
}

#[test]
fn quality_order_on_simulated_gaits() {
    // Lower mean exposure MMBM is better. Summed over three 120 s logs.
    for g in [Gait::Slow, Gait::Moderate] {
        let mean = |spec: &str| {
            let mut acc = 0.0;
            for seed in [11, 12, 13] {
                let (s, m) = sim(g, 120.0, seed);
                acc += summary_over(&go(spec, &s, &m, &CameraTiming::default()), 120.0).mean_mm_s;
            }
            acc / 3.0
        };
        let (o, f, t, x, ph) = (
            mean("oracle:0.4"),
            mean("forecast:0.4"),
            mean("threshold:0.4"),
            mean("fixed:5"),
            mean("phase:0.4"),
        );
        println!("{g}: oracle {o:.4} forecast {f:.4} phase {ph:.4} threshold {t:.4} fixed {x:.4}; forecast recovers {:.0} %, phase {:.0} % of the oracle's gain over threshold", 100.0 * (t - f) / (t - o), 100.0 * (t - ph) / (t - o));
        assert!(o < f && f < t && t < x, "{g}: {o} {f} {t} {x}");
        // The learned phase forecast: issue 11's goal is 70 % of the oracle's
        // gain on the moderate walk (68 % on these seeds; 74 % mean, 65-80 %,
        // over the 60 s walks of seeds 1-5); the slow walk 55 %. Floors below those,
        // so the test fails on a predictor that stops learning (the blind
        // forecast: 5 % and 13 %).
        let share = (t - ph) / (t - o);
        let floor = if g == Gait::Moderate { 0.55 } else { 0.4 };
        assert!(share >= floor, "{g}: phase {ph} threshold {t} oracle {o}");
    }
}

#[test]
fn bad_inputs_are_errors() {
    let s = log(&grid(10, 0.01));
    let mut p = parse_policy("fixed:5").unwrap();
    assert!(run(&s, &[0.0; 9], p.as_mut(), &CameraTiming::default()).is_err());
    assert!(run::<f64>(&[], &[], p.as_mut(), &CameraTiming::default()).is_err());
    let bad = CameraTiming {
        exposure: -1.0,
        ..CameraTiming::default()
    };
    assert!(run(&s, &[0.0; 10], p.as_mut(), &bad).is_err());
    let mut m = vec![0.0; 10];
    m[3] = f64::NAN;
    let e = run(&s, &m, p.as_mut(), &CameraTiming::default()).unwrap_err();
    assert!(e.to_string().contains("sample 3"), "{e}");
}

/// A rolling shutter (docs/spec.md section 9) keeps the camera busy from the first line's
/// exposure start to the last line's exposure end plus the readout: frames
/// start at least `t_e + t_rs + t_r` apart.
#[test]
fn rolling_readout_extends_the_busy_time() {
    let (s, m) = sim(Gait::Moderate, 5.0, 3);
    let gs = timing0();
    let rs = gs.with_rolling_readout(0.04);
    assert_eq!(rs.readout, 0.04);
    let gap = |f: &[Frame]| {
        f.windows(2)
            .map(|w| w[1].exposure_start - w[0].exposure_start)
            .fold(f64::INFINITY, f64::min)
    };
    let a = go("fixed:20", &s, &m, &gs);
    let b = go("fixed:20", &s, &m, &rs);
    assert!(
        gap(&a) < 0.06,
        "global shutter: every 50 ms slot ({})",
        gap(&a)
    );
    assert!(
        gap(&b) >= 0.09 - 1e-9,
        "rolling: busy 50 + 40 ms ({})",
        gap(&b)
    );
    assert!(b.len() < a.len());
}

/// `gate0` (the thesis's test) keeps a fixed-rate frame when the MMBM of its
/// decision sample is <= X; `gate` when the exposure average is. Both fire
/// exactly the fixed schedule's triggers.
#[test]
fn gate_at_start_and_over_the_exposure() {
    let (s, m) = sim(Gait::Moderate, 10.0, 5);
    let tm = timing0();
    let fixed = go("fixed:5", &s, &m, &tm);
    let g = go("gate:0.6", &s, &m, &tm);
    let g0 = go("gate0:0.6", &s, &m, &tm);
    assert_eq!(fixed.len(), g.len());
    assert_eq!(fixed.len(), g0.len());
    for ((f, a), b) in fixed.iter().zip(&g).zip(&g0) {
        assert_eq!((f.index, a.index), (b.index, b.index));
        assert_eq!(a.kept, f.mmbm_exposure_mm_s <= 0.6);
        assert_eq!(b.kept, f.mmbm_trigger_mm_s <= 0.6);
    }
    assert!(
        g.iter().zip(&g0).any(|(a, b)| a.kept != b.kept),
        "the two tests differ somewhere"
    );
}
