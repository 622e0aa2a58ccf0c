//! Running the experiment: plan the renders, render and measure each planned
//! frame, then write `frames.csv`, the figures and `report.md`.

use super::config::ExperimentConfig;
use super::figures;
use super::frame_figure::{Extremes, Shot};
use super::measure::{image_difference, render_and_measure, FrameRecord};
use super::report::{frames_csv, policy_stats, report_md, Outcome};
use super::walk::{make_walk, Walk};
use crate::error::{Error, Result};
use crate::io::atomic::write_atomic;
use crate::metric::Scene;
use crate::render::Quality;
use crate::trigger::Frame;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::str::FromStr;
use std::time::Instant;

/// Indices of the frames to render for one run: every kept frame, or an even
/// spread of `max` of them.
pub fn frames_to_render(frames: &[Frame], max: usize) -> Vec<usize> {
    let kept: Vec<usize> = (0..frames.len()).filter(|&i| frames[i].kept).collect();
    if max == 0 || kept.len() <= max {
        return kept;
    }
    (0..max).map(|k| kept[k * kept.len() / max]).collect()
}

/// True for a path (relative to the output folder) the experiment writes:
/// `frames.csv`, `report.md` and the PNG figures, all at its top level.
pub fn writes(rel: &Path) -> bool {
    let mut parts = rel.components();
    let (Some(one), None) = (parts.next(), parts.next()) else {
        return false;
    };
    let name = Path::new(one.as_os_str());
    name == Path::new("frames.csv")
        || name == Path::new("report.md")
        || name
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
}

/// Runs the experiment and writes `frames.csv`, `report.md` and the figures into `out`.
pub fn run(cfg: &ExperimentConfig, out: &Path, progress: bool) -> Result<Outcome> {
    cfg.validate()?;
    // The outputs' place is checked before minutes of rendering: writable,
    // and not over the gyro log it reads.
    let mut guard = crate::io::guard::OutputGuard::new()
        .output_dir("--out", Some(out), writes)
        .input("gyro (config)", cfg.gyro.as_deref());
    for l in &cfg.map.logs {
        guard = guard.input("map.logs", Some(l));
    }
    guard.check()?;
    // The map's logs read now, a bad one refused before any render.
    if !cfg.map.lights_e_per_s.is_empty() {
        super::benefit_map::logs::check_logs(cfg, &super::benefit_map::map_gaits(cfg))?;
    }
    let t_start = Instant::now();
    let quality = Quality::from_str(&cfg.quality)?;
    let scene = Scene {
        camera: cfg.camera(),
        plane: None,
    };
    let names: Vec<String> = if cfg.gyro.is_some() {
        vec!["log".into()]
    } else {
        cfg.walks.clone()
    };
    let seeds = cfg.seed_list();
    let several = seeds.len() > 1 && cfg.gyro.is_none();
    let mut walks: Vec<Walk> = Vec::new();
    for w in &names {
        for &seed in seeds
            .iter()
            .take(if cfg.gyro.is_some() { 1 } else { seeds.len() })
        {
            walks.push(make_walk(cfg, w, seed, several, &scene)?);
        }
    }

    // Plan the renders.
    let mut plan = Vec::new();
    for (wi, w) in walks.iter().enumerate() {
        for (pi, (_, frames)) in w.runs.iter().enumerate() {
            for fi in frames_to_render(frames, cfg.max_frames_per_policy) {
                plan.push((wi, pi, fi));
            }
        }
    }
    let bar = crate::diagnostics::progress(progress, "rendering frames", plan.len() as u64);
    let check = quality_check(cfg, &walks, &plan, quality)?;
    let mut measures = HashMap::new();
    let mut extremes: HashMap<(usize, usize), Extremes> = HashMap::new();
    let mut backend = String::new();
    // Frames are rendered and measured in parallel, a chunk at a time (each
    // frame's seed is its place in the plan, so the results do not depend on
    // the thread count), then taken in the plan's order.
    let chunk = 4 * rayon::current_num_threads();
    for (c, part) in plan.chunks(chunk).enumerate() {
        if let Some(&(wi, pi, fi)) = part.first() {
            let w = &walks[wi];
            bar.message(&format!("{} {}", w.name, w.runs[pi].1[fi].policy));
        }
        let rendered: Vec<Result<_>> = part
            .par_iter()
            .enumerate()
            .map(|(j, &(wi, pi, fi))| {
                let w = &walks[wi];
                let k = c * chunk + j;
                render_and_measure(cfg, w, &w.runs[pi].1[fi], cfg.camera(), quality, k as u32)
            })
            .collect();
        for (&(wi, pi, fi), r) in part.iter().zip(rendered) {
            let r = r?;
            let frame = &walks[wi].runs[pi].1[fi];
            if backend.is_empty() {
                backend = r.backend.clone();
            }
            // Keep the sharpest and the most blurred frame of each (walk, policy).
            let m = &r.measure;
            let shot = Shot {
                trigger_t: frame.trigger_t,
                blur_px: m.blur_px,
                blobs_matched: m.blobs_matched,
                blobs_expected: r.expected_px.len(),
                blobs_false: m.blobs_false,
                ok: m.blobs_ok,
                startup: frame.trigger_t
                    < walks[wi].samples.first().map_or(0.0, |s| s.t)
                        + crate::trigger::DEFAULT_HORIZON_S,
                expected_px: r.expected_px.clone(),
                rgb: r.rgb.clone(),
            };
            match extremes.get_mut(&(wi, pi)) {
                Some(e) => e.offer(shot),
                None => {
                    extremes.insert((wi, pi), Extremes::new(shot));
                }
            }
            measures.insert((wi, pi, fi), r.measure);
            bar.advance(1);
        }
    }
    drop(bar);
    let sweep = super::sweep::exposure_sweep(cfg, &walks, quality)?;
    let map = super::benefit_map::benefit_map(cfg, quality, progress)?;

    let mut records = Vec::new();
    for (wi, w) in walks.iter().enumerate() {
        for (pi, (_, frames)) in w.runs.iter().enumerate() {
            for (fi, f) in frames.iter().enumerate() {
                records.push(FrameRecord {
                    walk: w.name.clone(),
                    seed: w.seed,
                    frame: f.clone(),
                    measure: measures.remove(&(wi, pi, fi)),
                });
            }
        }
    }
    // The outputs appear together or not at all; a directory this run
    // created is removed again when writing them fails.
    let created = !out.exists();
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let written = crate::io::atomic::all_or_nothing(|| {
        let stats = policy_stats(&walks, &records);
        let csv = frames_csv(&records, &cfg.quality)?;
        write_atomic(&out.join("frames.csv"), |w| {
            w.write_all(csv.as_bytes())
                .map_err(|e| Error::io(out.join("frames.csv"), e))
        })?;

        let mut figs = figures::write_all(out, cfg, &walks, &records, &extremes)?;
        if let Some(m) = &map {
            super::benefit_map::report::heat_map_png(&out.join(super::report::MAP_FIGURE), m)?;
            figs.push(super::report::MAP_FIGURE.to_string());
        }
        let outcome = Outcome {
            walks,
            records,
            stats,
            seconds: t_start.elapsed().as_secs_f64(),
            rendered: plan.len(),
            sweep,
            backend,
            map,
        };
        let md = report_md(cfg, &outcome, &figs, check);
        write_atomic(&out.join("report.md"), |w| {
            w.write_all(md.as_bytes())
                .map_err(|e| Error::io(out.join("report.md"), e))
        })?;
        Ok(outcome)
    });
    if written.is_err() && created {
        let _ = std::fs::remove_dir(out);
    }
    written
}

/// Renders the central 160 x 120 window of the most blurred planned frame of
/// the first policy with the configured preset and with `default`, both
/// without sensor noise: `(mean, p99, blur_px)` of the difference. (With
/// noise the two would differ by the noise: any change of a pixel's mean can
/// change how many draws its Poisson sample takes, and so every later draw.)
fn quality_check(
    cfg: &ExperimentConfig,
    walks: &[Walk],
    plan: &[(usize, usize, usize)],
    quality: Quality,
) -> Result<Option<(f64, f64, f64)>> {
    let worst = plan.iter().filter(|&&(_, pi, _)| pi == 0).max_by(|a, b| {
        let fa = &walks[a.0].runs[a.1].1[a.2];
        let fb = &walks[b.0].runs[b.1].1[b.2];
        fa.mmbm_exposure_mm_s.total_cmp(&fb.mmbm_exposure_mm_s)
    });
    let Some(&(wi, pi, fi)) = worst else {
        return Ok(None);
    };
    if quality == Quality::Default {
        return Ok(None);
    }
    let frame = &walks[wi].runs[pi].1[fi];
    // The central 160 x 120 window (same focal length and pitch), where the
    // board is: the default preset is slow at full resolution on lavapipe.
    let cam = crate::camera::Camera {
        noise: None,
        ..cfg.camera().with_resolution(160, 120)
    };
    let a = render_and_measure(cfg, &walks[wi], frame, cam, quality, 0)?;
    let b = render_and_measure(cfg, &walks[wi], frame, cam, Quality::Default, 0)?;
    let (mean, p99) = image_difference(&a.rgb, &b.rgb);
    Ok(Some((mean, p99, b.measure.blur_px)))
}
