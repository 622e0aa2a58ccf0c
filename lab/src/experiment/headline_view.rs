//! The headline as a view of the benefit map (docs/spec.md section 11, one
//! judging rule): its sharp frames per second and its ratios to the fixed
//! rate are read from the map's cell at the experiment's light, gait and
//! board, so the headline and the map judge the same frames (the map's seeds,
//! its window around the board, its blob verdict) by construction.

use super::benefit::{headline_md_titled, Estimate, Headline};
use super::benefit_map::render::WINDOW_PITCHES;
use super::benefit_map::verdict::column;
use super::benefit_map::{BenefitMap, Cell};
use super::config::ExperimentConfig;
use crate::trigger::PolicySpec;

/// The map's cell the headline reads: at the experiment's light (the
/// camera's `phi_e_per_s`, else the map's first light; the nearest map light
/// when it is not one of them), its first walk's gait (else the map's first)
/// and its target board (else the map's first); None without cells.
pub fn headline_cell<'a>(cfg: &ExperimentConfig, m: &'a BenefitMap) -> Option<&'a Cell> {
    let want = cfg
        .camera
        .noise
        .map_or(m.lights.first().copied()?, |n| n.phi_e_per_s);
    let light = m
        .lights
        .iter()
        .copied()
        .min_by(|a, b| (a - want).abs().total_cmp(&(b - want).abs()))?;
    let gait = cfg
        .walks
        .iter()
        .find(|g| m.gaits.contains(g))
        .or(m.gaits.first())?;
    let board = if m.boards.contains(&cfg.target) {
        &cfg.target
    } else {
        m.boards.first()?
    };
    m.cells
        .iter()
        .find(|c| c.light == light && &c.gait == gait && &c.board == board)
}

/// The headline rows of cell `c` of map `m`: every policy of the cell with
/// its sharp frames per second and its ratio to the fixed rate, exactly the
/// map's numbers (the map renders no blur maps, so no blur is stated).
pub fn headlines_of(m: &BenefitMap, c: &Cell) -> Vec<Headline> {
    let none = Estimate {
        value: f64::NAN,
        lo: f64::NAN,
        hi: f64::NAN,
    };
    c.policies
        .iter()
        .map(|p| Headline {
            gait: c.gait.clone(),
            policy: p.policy.clone(),
            seeds: m.seeds.clone(),
            blocks: c.blocks,
            sharp_fps: p.sharp_ci,
            ratio: p.vs_fixed,
            blur_px: none,
            rendered: p.frames,
            kept: p.frames,
        })
        .collect()
}

/// The sentence that says which frames the map (and so the headline) judged.
pub fn judged_sentence(m: &BenefitMap, c: &Cell) -> String {
    format!(
        "Frames judged: the benefit map's cell at {} e-/s, {}: every kept frame of seeds {:?} ({} blocks), each judged \
         by the blob verdict in a window around the board (the blob grid padded by {} blob pitches), the same frames, \
         seeds, window and verdict as the map's table; the numbers below are that cell's.",
        c.light,
        column(c),
        m.seeds,
        c.blocks,
        WINDOW_PITCHES
    )
}

/// The headline section read from the map: None when the map has no cell
/// for the headline ([`headline_cell`]).
pub fn headline_view_md(cfg: &ExperimentConfig, m: &BenefitMap) -> Option<String> {
    let c = headline_cell(cfg, m)?;
    let hs = headlines_of(m, c);
    let policies: Vec<PolicySpec> = c.policies.iter().map(|p| p.policy.clone()).collect();
    Some(headline_md_titled(
        &hs,
        &policies,
        "Headline: sharp frames per second",
        &judged_sentence(m, c),
    ))
}
