//! The benefit map's shared renders (each frame's judged window rendered
//! once for all lights, `Renders::Shared`) give the very numbers of the
//! unshared reference (the whole frame and its sharp reference rendered
//! again for each light, the window cut from them: `Renders::PerLight`),
//! and its parallel judging gives the same numbers on any thread count.

use mmbm::render::Quality;
use mmbm_lab::experiment::{benefit_map_with, Renders};

use crate::tiny_map;

#[test]
fn shared_renders_give_the_unshared_numbers() {
    let cfg = tiny_map::config(
        &[1_000.0, 4_000.0, 100_000.0],
        &["deadline:5+exp:3:0.02", "ae:5:cap=10ms"],
        &[3.0, 70.0],
    );
    let q: Quality = cfg.quality.parse().unwrap();
    let shared = benefit_map_with(&cfg, q, false, Renders::Shared)
        .unwrap()
        .unwrap();
    let each = benefit_map_with(&cfg, q, false, Renders::PerLight)
        .unwrap()
        .unwrap();
    assert_eq!(shared.renders, each.renders);
    assert_eq!(shared.cells.len(), 3);
    // Every number of every cell (Debug: NaN equals NaN there).
    for (a, b) in shared.cells.iter().zip(&each.cells) {
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
    // The lights differ, so the comparison has something to see.
    let sharp = |c: &mmbm_lab::experiment::Cell| c.policies.iter().map(|p| p.sharp).sum::<usize>();
    let reps = |c: &mmbm_lab::experiment::Cell| {
        format!(
            "{:?}",
            c.policies.iter().map(|p| p.corner_rep).collect::<Vec<_>>()
        )
    };
    let c = &shared.cells;
    assert!(sharp(&c[0]) != sharp(&c[2]) || reps(&c[0]) != reps(&c[2]));
}

/// The map judges a walk's policies and each policy's frames in parallel;
/// each frame's seed is its place in the serial order, so one thread and
/// three give every number the same.
#[test]
fn the_thread_count_changes_no_number() {
    let cfg = tiny_map::config(
        &[1_000.0, 20_000.0],
        &["deadline:5", "deadline:5+exp:3:0.02", "ae:5:cap=10ms"],
        &[3.0, 40.0],
    );
    let q: Quality = cfg.quality.parse().unwrap();
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| benefit_map_with(&cfg, q, false, Renders::Shared))
            .unwrap()
            .unwrap()
    };
    let (one, three) = (with(1), with(3));
    assert_eq!(one.renders, three.renders);
    assert!(one.renders > 0);
    // Every number of every cell (Debug: NaN equals NaN there).
    for (a, b) in one.cells.iter().zip(&three.cells) {
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
}
