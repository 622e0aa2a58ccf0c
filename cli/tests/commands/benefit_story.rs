//! The benefit story (docs/spec.md section 11): the gyro-aware exposure
//! baselines as policies, checked against their formulas by hand; the
//! families that split exposure from timing; and the map's answer to "does
//! timing pay?" (the best `mmbm` policy over the best `gyro-exposure` one).

use crate::common;
use crate::tiny_map;

use mmbm::trigger::{run, CameraTiming, Frame, PolicyFamily, PolicySpec};
use mmbm_lab::experiment::{self, ExperimentConfig, MapSection};

/// 20 s at 600 Hz of an MMBM that swings between 0 and 2 mm/s (a gait-like
/// 1.7 Hz cycle), run through `spec` on the thesis camera (70 ms, 4.65 um).
fn swinging(spec: &str) -> (Vec<Frame>, Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..=12_000).map(|k| k as f64 / 600.0).collect();
    let m: Vec<f64> = t
        .iter()
        .map(|&s| 1.0 - (2.0 * std::f64::consts::PI * 1.7 * s).cos())
        .collect();
    let mut p = PolicySpec::parse(spec).unwrap().build().unwrap();
    let f = run(&t, &m, p.as_mut(), &CameraTiming::default()).unwrap();
    (f, t, m)
}

/// The MMBM of the decision sample of frame `f`, mm/s.
fn mmbm_at(f: &Frame, t: &[f64], m: &[f64]) -> f64 {
    let i = t.partition_point(|&s| s < f.trigger_t - 1e-12);
    m[i]
}

const PITCH_MM: f64 = 0.00465;
const T_REF: f64 = 0.07;

#[test]
fn blur_capped_auto_exposure_keeps_the_budget_and_the_product() {
    let (frames, t, m) = swinging("ae-blur:5:1");
    let (ae, _, _) = swinging("ae:5");
    assert_eq!(frames.len(), ae.len());
    let mut capped = 0;
    for (f, a) in frames.iter().zip(&ae) {
        assert!((f.trigger_t - a.trigger_t).abs() < 1e-12, "same schedule");
        let v = mmbm_at(f, &t, &m) / PITCH_MM; // px/s
        let (te, k) = (f.exposure_s(), f.gain);
        // Same exposure x gain as the motion-blind auto-exposure.
        assert!((te * k - a.exposure_s() * a.gain).abs() < 1e-12);
        if v * a.exposure_s() > 1.0 {
            // Capped: exactly 1 px of predicted blur.
            assert!((v * te - 1.0).abs() < 1e-9, "{}", v * te);
            capped += 1;
        } else {
            assert!((te - a.exposure_s()).abs() < 1e-12);
        }
    }
    // The swing puts frames on both sides of the budget.
    assert!(capped > 5 && capped < frames.len() - 5, "{capped}");
}

#[test]
fn imu_trade_minimises_blur_plus_weighted_gain() {
    for (spec, w, w0) in [("ae-imu:5", 0.1, 0.0), ("ae-imu:5:w=0.5:w0=2", 0.5, 2.0)] {
        let (frames, t, m) = swinging(spec);
        let (ae, _, _) = swinging("ae:5");
        for (f, a) in frames.iter().zip(&ae) {
            let c = a.exposure_s() * a.gain; // what the auto-exposure wants, s
            let v = mmbm_at(f, &t, &m) / PITCH_MM;
            let k = ((v * c + w0) / w).sqrt().max(1.0).max(c / T_REF);
            assert!((f.gain - k).abs() < 1e-9 * k, "{spec}: {} vs {k}", f.gain);
            assert!((f.exposure_s() - c / k).abs() < 1e-12);
            // Unclamped, no other split of c costs less: v T + w (K - 1).
            if w0 == 0.0 && k > 1.0 && k > c / T_REF {
                let cost = |k: f64| v * c / k + w * (k - 1.0);
                assert!(cost(k) <= cost(k * 1.01) && cost(k) <= cost(k / 1.01));
            }
        }
    }
}

#[test]
fn gradient_auto_exposure_fills_the_range_with_white() {
    // White 0.8 on the 0.25 scene: the best product is near 1 / 0.8 = 1.25;
    // from 1, sqrt 2 (white clips: G = 1 - g(0.354) = 0.377) beats 1
    // (g(0.8) - g(0.25) = 0.371), 2 (1 - g(0.5) = 0.270) and 1 / sqrt 2;
    // at sqrt 2 it stays (its neighbours are 1 and 2).
    let g = |x: f64| x.min(1.0).powf(1.0 / 2.2);
    let gp = |p: f64| g(0.8 * p) - g(0.25 * p);
    let s2 = 2f64.sqrt();
    assert!(gp(s2) > gp(1.0) && gp(s2) > gp(2.0) && gp(s2) > gp(1.0 / s2));
    let (f, _, _) = swinging("ae-grad:5:white=0.8");
    assert!((f[0].exposure_s() - T_REF).abs() < 1e-12 && f[0].gain == 1.0);
    assert!(f[1..]
        .iter()
        .all(|x| (x.exposure_s() - T_REF).abs() < 1e-12 && (x.gain - s2).abs() < 1e-9));
    // ... and white 0.3: 1 / 0.3 = 3.3, from 1 by the largest step (2) then
    // sqrt 2 (2.83: G = g(0.85) - g(0.71) beats 4 and 2), motion-blind.
    let gp = |p: f64| g(0.3 * p) - g(0.25 * p);
    assert!(gp(2.0) > gp(2f64.sqrt()) && gp(2.0 * 2f64.sqrt()) > gp(4.0));
    let (f, _, _) = swinging("ae-grad:5:white=0.3:cap=10ms");
    let p: Vec<f64> = f.iter().map(|x| x.exposure_s() * x.gain / T_REF).collect();
    assert!((p[0] - 1.0).abs() < 1e-12 && (p[1] - 2.0).abs() < 1e-9);
    assert!((p[2] - 2.0 * 2f64.sqrt()).abs() < 1e-9);
    assert!(p[3..].iter().all(|&x| (x - 2.0 * 2f64.sqrt()).abs() < 1e-9));
    assert!(f.iter().all(|x| (x.exposure_s() - 0.01).abs() < 1e-12));
}

#[test]
fn families_split_exposure_from_timing() {
    for (s, fam) in [
        ("fixed:5", "fixed"),
        ("fixed:5@10ms", "fixed-exposure"),
        ("ae:5:cap=10ms", "auto-exposure"),
        ("ae-grad:5", "auto-exposure"),
        ("ae-blur:5:1", "gyro-exposure"),
        ("ae-imu:5", "gyro-exposure"),
        ("fixed:5+exp:2:0.02", "gyro-exposure"),
        ("fixed:5@0.1+exp:2", "gyro-exposure"),
        ("deadline:5", "mmbm"),
        ("deadline:5+exp:3:0.02", "mmbm"),
        ("threshold:0.4+exp:2", "mmbm"),
        ("gate:0.8", "mmbm"),
        ("task:5:light=1000", "mmbm"),
        ("oracle:0.4", "oracle"),
    ] {
        let p = PolicySpec::parse(s).unwrap();
        assert_eq!(p.policy_family().name(), fam, "{s}");
        assert_eq!(p.build().unwrap().spec(), p);
    }
    for (s, says) in [
        ("ae-blur:5", "blur budget"),
        ("ae-blur:5:1+exp:2", "+exp does not apply"),
        ("ae-imu:5:w=0", "gain weight"),
        ("ae-grad:5:damp=0.5", "'damp' does not apply"),
    ] {
        let e = PolicySpec::parse(s).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains(s), "{s}: {e}");
    }
}

/// A 2 x 2-s map at one light: `deadline:5` (timing) against two
/// `gyro-exposure` policies.
fn tiny() -> ExperimentConfig {
    tiny_map::config(
        &[4_000.0],
        &["deadline:5", "fixed:5+exp:2:0.02", "ae-blur:5:1"],
        &[70.0],
    )
}

#[test]
fn each_cell_says_whether_timing_pays() {
    let d = tempfile::tempdir().unwrap();
    let o = experiment::run(&tiny(), d.path(), false).unwrap();
    let m = o.map.as_ref().expect("a map was configured");
    let md = std::fs::read_to_string(d.path().join("report.md")).unwrap();
    for c in &m.cells {
        let fam: Vec<PolicyFamily> = c
            .policies
            .iter()
            .map(|p| p.policy.policy_family())
            .collect();
        assert_eq!(
            fam,
            [
                PolicyFamily::Fixed,
                PolicyFamily::Mmbm,
                PolicyFamily::GyroExposure,
                PolicyFamily::GyroExposure
            ]
        );
        let fps = |i: usize| c.policies[i].sharp_fps;
        assert_eq!(c.best_mmbm, Some(1));
        let g = c.gyro.expect("two gyro-exposure policies");
        assert!(g == 2 || g == 3);
        assert!(fps(g) >= fps(2).max(fps(3)));
        let r = c.vs_gyro.expect("both families present");
        assert!((r.value - fps(1) / fps(g)).abs() < 1e-12 || !r.value.is_finite());
        let verdict = mmbm_lab::experiment::timing_verdict(c);
        let want = if !(r.lo.is_finite() && r.hi.is_finite()) {
            "n/a"
        } else if r.lo > 1.0 {
            "pays"
        } else if r.hi < 1.0 {
            "loses"
        } else {
            "ties"
        };
        assert_eq!(verdict, want, "{r:?}");
        let shown = if r.value.is_finite() {
            format!("timing vs gyro-exposure {:.2}x", r.value)
        } else {
            "timing vs gyro-exposure n/a".to_string()
        };
        assert!(md.contains(&shown), "{shown}\n{md}");
        assert!(md.contains(&format!("({verdict})")), "{md}");
    }
    // The report and the terminal open with the three computed lines, each
    // cell in the line of its verdict.
    let lines = mmbm_lab::experiment::three_lines(m);
    let map_at = md.find("## Benefit map").unwrap();
    for l in &lines {
        let at = md.find(&format!("- {l}\n")).expect(l);
        assert!(at < map_at, "{md}");
    }
    for c in &m.cells {
        let (v, ..) = mmbm_lab::experiment::cell_verdict(c).expect("a verdict");
        let k = [
            mmbm_lab::experiment::Verdict::Pays,
            mmbm_lab::experiment::Verdict::Ties,
            mmbm_lab::experiment::Verdict::Loses,
        ]
        .iter()
        .position(|x| *x == v)
        .unwrap();
        let tag = format!("{} e-/s, moderate, half board", c.light);
        for (j, l) in lines.iter().enumerate() {
            assert_eq!(l.contains(&tag), j == k, "{l}");
        }
    }
    let said = o.answer(&d.path().join("report.md"));
    let first: Vec<&str> = said.lines().take(3).collect();
    assert_eq!(first, lines.iter().map(String::as_str).collect::<Vec<_>>());
}

#[test]
fn the_demo_maps_hold_the_bar_for_timing() {
    let fams = |m: &MapSection| -> Vec<PolicyFamily> {
        m.policies.iter().map(|s| s.policy_family()).collect()
    };
    let (reduced, full) = (MapSection::reduced(), MapSection::full());
    for m in [&reduced, &full] {
        let f = fams(m);
        for want in [
            PolicyFamily::Mmbm,
            PolicyFamily::GyroExposure,
            PolicyFamily::AutoExposure,
        ] {
            assert!(f.contains(&want), "{want}: {:?}", m.policies);
        }
        assert!(m
            .policies
            .iter()
            .any(|p| p.as_str().starts_with("ae-blur:")));
    }
    for p in ["ae-blur:5:1", "ae-imu:5", "ae-grad:5:cap=10ms"] {
        assert!(full.policies.iter().any(|q| q == p), "{p}");
    }
}

#[test]
fn the_docs_scene_table_is_the_codes() {
    let want = mmbm::camera::scene_table_md(mmbm::camera::TABLE_CAMERA).unwrap();
    let doc = std::fs::read_to_string(crate::common::repo_root().join("docs/light.md")).unwrap();
    let a = doc
        .find("<!-- scene table begin -->\n")
        .expect("begin marker")
        + 27;
    let b = doc.find("<!-- scene table end -->").expect("end marker");
    assert_eq!(&doc[a..b], want, "docs/light.md's table should be:\n{want}");
    // Hand check of one row: 500 lx at f/2 on 4.65 um, QE 0.5.
    let phi: f64 = 500.0 / 16.0 * 4.0906e15 * 4.65e-6 * 4.65e-6 * 0.5;
    assert!(want.contains(&format!("| office | 500 | {} |", (phi / 1e4).round() * 1e4)));
}

#[test]
fn light_from_lux_and_trigger_at_a_stated_light() {
    // 500 lx at f/2 on 4.65 um, QE 0.5: 31.25 lx x 4.0906e15 x 2.162e-11 m^2 x 0.5.
    let o = common::mmbm(&[
        "light",
        "--lux",
        "500",
        "--f-number",
        "2",
        "--pixel-um",
        "4.65",
        "--qe",
        "0.5",
        "--exposure",
        "0.07",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let phi: f64 = out.split_whitespace().next().unwrap().parse().unwrap();
    let want = 31.25 * 4.0906e15 * 4.65e-6 * 4.65e-6 * 0.5;
    assert!((phi / want - 1.0).abs() < 1e-4, "{out}");
    assert!(out.contains("e- in 0.07 s"), "{out}");
    for (flag, v) in [
        ("--lux", "0"),
        ("--f-number", "0.2"),
        ("--qe", "2"),
        ("--pixel-um", "nan"),
    ] {
        let mut args = vec![
            "light",
            "--lux",
            "500",
            "--f-number",
            "2",
            "--pixel-um",
            "4.65",
            "--qe",
            "0.5",
        ];
        let i = args.iter().position(|a| *a == flag).unwrap();
        args[i + 1] = v;
        let o = common::mmbm(&args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(flag), "{flag}={v}: {e}");
    }
    // trigger --light: 1 ms at 2,000 e-/s holds 2 e- (SNR 0.6): predicted
    // never sharp; 70 ms holds 140 e- (SNR 11.7).
    let d = tempfile::tempdir().unwrap();
    let walk = common::simulated_walk(d.path());
    let f = d.path().join("f.csv");
    let o = common::mmbm(&[
        "trigger",
        "--gyro",
        walk.to_str().unwrap(),
        "--policy",
        "fixed:5",
        "--policy",
        "fixed:5@1ms",
        "--exposure",
        "0.07",
        "--light",
        "2000",
        "--out",
        f.to_str().unwrap(),
        "--summary",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let snr = |mu: f64| mu / (mu + 6.25f64).sqrt();
    assert!(
        out.contains(&format!(
            "at 2000 e-/s: white-pixel SNR mean {:.1} min {:.1}",
            snr(140.0),
            snr(140.0)
        )),
        "{out}"
    );
    assert!(out.contains(&format!("at 2000 e-/s: white-pixel SNR mean {:.1} min {:.1}; predicted sharp (task model) 0.0 of", snr(2.0), snr(2.0))), "{out}");
}
