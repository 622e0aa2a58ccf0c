//! One judging rule (docs/spec.md section 11): the report's headline is a view
//! of the benefit map's cell at the experiment's light, gait and board, so its
//! sharp frames per second and its ratios to the fixed rate are the map's,
//! judged on the same frames (the map's seeds, its window, its verdict); and
//! changing how the map judges (here its seeds) changes the headline with it.

use crate::tiny_map;

use mmbm_lab::experiment::{self, ExperimentConfig};

/// The small map at the camera's own light (20,000 e-/s): one cell.
fn config(seeds: &[u64]) -> ExperimentConfig {
    let mut cfg = tiny_map::config(
        &[20_000.0],
        &["deadline:5+exp:3:0.02", "ae-blur:5:1"],
        &[70.0],
    );
    cfg.map.seeds = seeds.to_vec();
    cfg
}

/// The headline section of a report and its table rows: policy -> (sharp
/// frames/s cell, ratio cell).
fn headline(md: &str) -> (String, Rows) {
    let at = md.find("## Headline").expect("a headline section");
    let end = md[at + 3..].find("\n## ").map_or(md.len(), |e| at + 3 + e);
    let sec = md[at..end].to_string();
    let rows = sec
        .lines()
        .filter(|l| l.starts_with("| moderate |"))
        .map(|l| {
            let c: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            (c[1].to_string(), c[3].to_string(), c[4].to_string())
        })
        .collect();
    (sec, rows)
}

/// A headline table's rows: (policy, sharp frames/s cell, ratio cell).
type Rows = Vec<(String, String, String)>;

/// Runs the small experiment; returns the headline section, its rows and
/// the map's (policy, sharp frames/s, ratio to `fixed:5`) of its one cell.
fn run(seeds: &[u64]) -> (String, Rows, Vec<(String, f64, f64)>) {
    let d = tempfile::tempdir().unwrap();
    let cfg = config(seeds);
    let o = experiment::run(&cfg, d.path(), false).unwrap();
    let md = std::fs::read_to_string(d.path().join("report.md")).unwrap();
    let m = o.map.as_ref().expect("a map was configured");
    assert_eq!(m.cells.len(), 1);
    let c = &m.cells[0];
    let f = c.fixed.expect("the fixed rate is in the map");
    let cell = c
        .policies
        .iter()
        .map(|p| {
            (
                p.policy.to_string(),
                p.sharp_fps,
                p.sharp_fps / c.policies[f].sharp_fps,
            )
        })
        .collect();
    // The headline's rows are the cell's numbers, exactly.
    let hc = experiment::headline_cell(&cfg, m).expect("the headline's cell");
    assert!(std::ptr::eq(hc, c));
    let hs = experiment::headlines_of(m, c);
    assert_eq!(hs.len(), c.policies.len());
    for (h, p) in hs.iter().zip(&c.policies) {
        assert_eq!(h.policy, p.policy);
        assert_eq!(h.sharp_fps.value.to_bits(), p.sharp_fps.to_bits());
        assert_eq!(h.sharp_fps, p.sharp_ci);
        assert_eq!(h.ratio, p.vs_fixed);
        assert_eq!((h.seeds.as_slice(), h.blocks), (seeds, c.blocks));
    }
    let (sec, rows) = headline(&md);
    (sec, rows, cell)
}

#[test]
fn the_headline_reads_the_maps_cell() {
    let mut seen = Vec::new();
    for seeds in [&[1u64, 2][..], &[3][..]] {
        let (sec, rows, cell) = run(seeds);
        // The headline states the frames it judged: the map's seeds and window.
        assert!(sec.contains(&format!("seeds {seeds:?}")), "{sec}");
        assert!(sec.contains("window"), "{sec}");
        // One row per policy of the map's cell, with the map's numbers.
        assert_eq!(rows.len(), cell.len(), "{sec}");
        for (name, fps, ratio) in &cell {
            let row = rows
                .iter()
                .find(|r| &r.0 == name)
                .unwrap_or_else(|| panic!("{name} not in the headline\n{sec}"));
            assert!(
                row.1.starts_with(&format!("{fps:.2}")),
                "{name}: headline {} vs map {fps:.2}\n{sec}",
                row.1
            );
            if ratio.is_finite() {
                assert!(
                    row.2.starts_with(&format!("{ratio:.2}x")),
                    "{name}: headline {} vs map {ratio:.2}x\n{sec}",
                    row.2
                );
            }
        }
        seen.push(rows);
    }
    // Judging other frames (other seeds) moves the headline with the map.
    assert_ne!(seen[0], seen[1]);
}
