//! The benefit map (docs/spec.md section 10) on a tiny configuration: the report
//! leads with it, its numbers hold together (ratios, winners, the
//! hindsight choice, families), the heat map is written, and a bad `[map]`
//! is refused naming its key.

use mmbm::trigger::PolicyFamily;
use mmbm_lab::experiment::{self, ExperimentConfig};

use crate::tiny_map;

fn tiny() -> ExperimentConfig {
    tiny_map::config(
        &[1_000.0, 20_000.0],
        &["deadline:5+exp:3:0.02", "ae:5:cap=10ms"],
        &[10.0, 70.0],
    )
}

#[test]
fn the_map_leads_the_report_and_holds_together() {
    let d = tempfile::tempdir().unwrap();
    let cfg = tiny();
    let o = experiment::run(&cfg, d.path(), false).unwrap();
    let m = o.map.as_ref().expect("a map was configured");
    assert_eq!(m.cells.len(), 2);
    assert_eq!(m.seeds, [1, 2]);
    for c in &m.cells {
        // Two 2-s walks: one block each.
        assert_eq!(c.blocks, 2);
        let names: Vec<&str> = c.policies.iter().map(|p| p.policy.as_str()).collect();
        assert_eq!(
            names,
            [
                "fixed:5",
                "deadline:5+exp:3:0.02",
                "ae:5:cap=10ms",
                "fixed:5@10ms"
            ]
        );
        for p in &c.policies {
            assert!(p.sharp <= p.frames && p.frames > 0, "{p:?}");
            // Sharp frames per second over the walks' 2 x 2 s (the last sample at 1.998 s).
            let secs = p.sharp as f64 / p.sharp_fps;
            assert!(p.sharp == 0 || (secs - 3.997).abs() < 0.01, "{secs}");
        }
        let fps = |i: Option<usize>| c.policies[i.unwrap()].sharp_fps;
        assert_eq!(c.best_mmbm, Some(1));
        assert_eq!(c.ae, Some(2));
        assert_eq!(c.fixed, Some(0));
        // The hindsight choice is the better of the grid's two (70 ms is `fixed:5`).
        let h = c.hindsight.unwrap();
        assert!(h == 0 || h == 3);
        assert!(fps(Some(h)) >= fps(Some(0)).max(fps(Some(3))));
        let winner = c.policies[c.winner].sharp_fps;
        assert!(c.policies.iter().all(|p| p.sharp_fps <= winner));
        if let Some(r) = c.vs_hindsight {
            assert!(
                (r.value - fps(c.best_mmbm) / fps(c.hindsight)).abs() < 1e-12
                    || !r.value.is_finite()
            );
        }
        assert_eq!(c.policies[1].policy.policy_family(), PolicyFamily::Mmbm);
        assert_eq!(
            c.policies[3].policy.policy_family(),
            PolicyFamily::FixedExposure
        );
        // At 1,000 e-/s the reference gain is 3.64 DN/e-; 10 ms at 7x is capped (6.53).
        if c.light == 1_000.0 {
            assert_eq!(c.policies[3].gain_capped, c.policies[3].frames);
            assert_eq!(c.policies[0].gain_capped, 0);
        }
    }
    let md = std::fs::read_to_string(d.path().join("report.md")).unwrap();
    let first = md.find("## ").unwrap();
    assert!(md[first..].starts_with("## Benefit map"), "{md}");
    assert!(
        md.contains("| light (e-/s) | moderate, half board |"),
        "{md}"
    );
    assert!(
        md.contains("every kept frame of seeds [1, 2]") && md.contains("bootstrap seed 20261123")
    );
    assert!(md.contains("each judged in a window around the board"));
    assert!(md.contains("Goals (docs/experiment.md, the benefit map), computed from the map:"));
    for c in &m.cells {
        if let Some(r) = c
            .vs_hindsight
            .filter(|r| r.value.is_finite() && r.lo.is_finite())
        {
            let want = format!(
                "| {} | vs best fixed {:.2}x [{:.2}, {:.2}]",
                c.light, r.value, r.lo, r.hi
            );
            assert!(
                md.contains(&want)
                    || md.contains(&format!(
                        "| {} | **lost** vs best fixed {:.2}x",
                        c.light, r.value
                    )),
                "{want}\n{md}"
            );
        }
    }
    assert!(d.path().join("benefit_map.png").exists());
    assert!(md.contains("![benefit map](benefit_map.png)"));
    // The terminal's answer: the three lines, the ratios and where the report is.
    let report = d.path().join("report.md");
    let answer = o.answer(&report);
    assert_eq!(answer, experiment::map_answer(m, &report).join("\n"));
    assert!(
        answer.ends_with(&format!("Report: {}", report.display())),
        "{answer}"
    );
    // The three computed lines (pays, ties, loses), the summary, a line
    // per cell and the report's place.
    assert_eq!(answer.lines().count(), 5 + m.cells.len());
    let three = experiment::three_lines(m);
    assert!(answer.starts_with(&three.join("\n")), "{answer}");
    // frames.csv names every policy's family.
    let csv = std::fs::read_to_string(d.path().join("frames.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(header.ends_with(&["gain", "family", "blobs_false", "corner_repeatability"]));
    let family = header.iter().position(|c| *c == "family").unwrap();
    // The second task metric: a repeatability in [0, 1] for every rendered frame.
    let rep = header.len() - 1;
    let reps: Vec<f64> = csv
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').nth(rep).and_then(|v| v.parse().ok()))
        .collect();
    assert!(
        !reps.is_empty() && reps.iter().all(|r| (0.0..=1.0).contains(r)),
        "{reps:?}"
    );
    assert!(md.contains("## Clutter and corners") && md.contains("Background `poster`"));
    assert!(md.contains("Second task metric (visual odometry)"));
    for c in &m.cells {
        for p in &c.policies {
            assert!(p.vo_fps >= 0.0 && p.vo_fps <= 5.1, "{p:?}");
            assert!(p.corner_rep.is_nan() || (0.0..=1.0).contains(&p.corner_rep));
        }
    }
    assert!(csv
        .lines()
        .skip(1)
        .all(|l| l.split(',').nth(family) == Some("fixed")));
}

#[test]
fn a_bad_map_is_refused_naming_its_key() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("map.toml");
    for (text, key) in [
        ("[map]\nlights_e_per_s = [-5.0]\n", "map.lights_e_per_s"),
        (
            "[map]\nlights_e_per_s = [1000.0]\ngrid_ms = [90.0]\n",
            "map.grid_ms",
        ),
        (
            "[map]\nlights_e_per_s = [1000.0]\ngrid_ms = []\n",
            "map.grid_ms",
        ),
        (
            "[map]\nlights_e_per_s = [1000.0]\npolicies = [\"ae:5:cap=3\"]\n",
            "map.policies",
        ),
        (
            "[map]\nlights_e_per_s = [1000.0]\nboards = [\"squares\"]\n",
            "map.boards",
        ),
        (
            "[map]\nlights_e_per_s = [1000.0]\nseeds = [1, 1]\n",
            "map.seeds",
        ),
        (
            "[map]\nlights_e_per_s = [1000.0]\nmax_gain_x = 0.0\n",
            "map.max_gain_x",
        ),
        ("[walk_s]\nfast = 0.0\n", "walk_s.fast"),
    ] {
        std::fs::write(&p, text).unwrap();
        let e = ExperimentConfig::load(&p).unwrap_err().to_string();
        assert!(e.contains("map.toml") && e.contains(key), "{text}: {e}");
    }
    // Without lights there is no map.
    std::fs::write(&p, "[map]\ngrid_ms = [90.0]\n").unwrap();
    assert!(ExperimentConfig::load(&p).is_ok());
}

#[test]
fn the_demo_configurations() {
    let d = ExperimentConfig::demo();
    assert_eq!(d.target, "blobs:0.5");
    assert_eq!(d.walks, ["moderate"]);
    assert_eq!(d.walk_duration_s(mmbm::sim::Gait::Moderate), 16.0);
    assert_eq!(d.map.seeds.len(), 5);
    let f = ExperimentConfig::demo_full();
    // The experiment's own frames are the demo's; the map is the whole one.
    assert_eq!(f.walks, d.walks);
    assert_eq!((f.seed_list(), &f.policies), (d.seed_list(), &d.policies));
    assert!(f.sweep_exposures_s.is_empty());
    assert_eq!(f.map.gaits, ["slow", "moderate", "fast"]);
    assert_eq!(f.map.seeds, [1, 2, 3, 4, 5]);
    assert_eq!(f.map.boards, ["blobs:0.5", "blobs"]);
    // The whole map at the fast preset (its render difference in the report); the demo at default.
    assert_eq!(
        (d.quality.as_str(), f.quality.as_str()),
        ("default", "fast")
    );
    assert!(f.map.lights_e_per_s.contains(&500.0) && f.map.lights_e_per_s.contains(&100_000.0));
    assert_eq!(
        [35.0, 16.0, 5.0],
        [
            mmbm::sim::Gait::Slow,
            mmbm::sim::Gait::Moderate,
            mmbm::sim::Gait::Fast
        ]
        .map(|g| f.walk_duration_s(g))
    );
    assert!(d.validate().is_ok() && f.validate().is_ok());
    // The auto-exposure's predicted scene level is the renderer's background.
    assert_eq!(
        mmbm::trigger::AeParams::SCENE_MEAN,
        f64::from(mmbm::render::DEFAULT_BACKGROUND[0])
    );
}
