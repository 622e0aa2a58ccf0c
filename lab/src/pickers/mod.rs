//! The proof for docs/pickers.md: gyro-based frame picking against the image-only
//! pickers photogrammetry and splatting users run today, on rendered clips
//! with ground truth (`cargo run --release -p mmbm-lab --example pickers`;
//! the results page is `docs/pickers.md`).
//!
//! - [`clips`]: the clips (true motion, scene, noise, rolling shutter,
//!   H.264; a defocus and an optical-stabilisation stretch) and their gyro
//!   logs (noise, bias, a known offset);
//! - [`pick`]: the per-frame measures and the pickers;
//! - [`score`]: mean true blur, share blurred, largest hole, budget F1;
//! - [`report`]: the tables and the sentences computed from them.

pub mod clips;
pub mod pick;
pub mod report;
mod rng;
pub mod score;

use clips::{ClipSpec, Format, Rendered, Stretches};
use mmbm::error::Result;
use pick::{Measures, Picker};
use score::{prf, Prf, Score};
use std::path::PathBuf;

/// Offset errors the gyro picker is run with, s.
pub const OFFSET_ERRORS_S: [f64; 3] = [0.005, 0.010, 0.020];
/// The blur budget of the budget task, px.
pub const BUDGET_PX: f64 = score::BLURRED_PX;
/// The clip the Laplacian's threshold is tuned on (index into the specs).
pub const TUNED_ON: usize = 1;

/// How to run the benchmark.
#[derive(Debug, Clone)]
pub struct Config {
    /// The clips' size and length.
    pub format: Format,
    /// Frames per window.
    pub window: usize,
    /// The repository root (textures, `../shared/data`).
    pub repo: PathBuf,
    /// Where clips and scratch files go.
    pub out: PathBuf,
    /// The clips.
    pub specs: Vec<ClipSpec>,
}

impl Config {
    /// The full benchmark (`quick`: a small, short version to try it out).
    pub fn new(repo: PathBuf, out: PathBuf, quick: bool) -> Self {
        let format = if quick {
            Format {
                width: 160,
                height: 120,
                fps: 30.0,
                frames: 60,
                invisible: true,
            }
        } else {
            Format {
                width: 320,
                height: 240,
                fps: 30.0,
                frames: 180,
                invisible: true,
            }
        };
        let specs = clips::specs(&repo);
        Config {
            format,
            window: 10,
            repo,
            out,
            specs,
        }
    }
}

/// The sync's result on one clip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SyncResult {
    /// Estimate minus the true offset, s.
    pub error_s: f64,
    /// Its confidence (0..1).
    pub confidence: f64,
    /// Time per frame, ms.
    pub ms_per_frame: f64,
}

/// Everything measured on one clip.
#[derive(Debug, Clone)]
pub struct ClipResult {
    /// The clip's spec.
    pub spec: ClipSpec,
    /// The rendered clip.
    pub clip: Rendered,
    /// Its measures.
    pub measures: Measures,
    /// Per picker (in [`Picker::ALL`]'s order): its picks and their score.
    pub scores: Vec<(Picker, Vec<usize>, Score)>,
    /// The sync (an error message when it refused).
    pub sync: std::result::Result<SyncResult, String>,
    /// The gyro picker's score with each of [`OFFSET_ERRORS_S`].
    pub offset_scores: Vec<Score>,
    /// Budget task: the gyro's calls.
    pub budget_gyro: Prf,
    /// Budget task: the Laplacian threshold tuned on [`TUNED_ON`].
    pub budget_laplacian: Prf,
}

/// The whole benchmark's results.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// What was run.
    pub config: Config,
    /// Per clip.
    pub clips: Vec<ClipResult>,
    /// The Laplacian threshold tuned on [`TUNED_ON`].
    pub lap_threshold: f64,
    /// The stretches the gyro cannot see.
    pub stretches: Stretches,
    /// Wall time of the whole run, s.
    pub total_s: f64,
}

impl ClipResult {
    /// The score of picker `p`.
    pub fn score(&self, p: Picker) -> Score {
        self.scores
            .iter()
            .find(|s| s.0 == p)
            .map(|s| s.2)
            .expect("every picker scored")
    }

    /// The picks of picker `p`.
    pub fn picks(&self, p: Picker) -> &[usize] {
        self.scores
            .iter()
            .find(|s| s.0 == p)
            .map(|s| s.1.as_slice())
            .expect("every picker scored")
    }
}

fn sync_clip(r: &Rendered) -> std::result::Result<SyncResult, String> {
    let t0 = std::time::Instant::now();
    let o = mmbm::sync::SyncOptions {
        exposure_s: r.exposure_s,
        centre_s: 0.0,
        search_s: 0.2,
    };
    match mmbm::sync::sync(&r.video, &r.gyro, &r.camera, &o) {
        Ok(s) => Ok(SyncResult {
            error_s: s.estimate.offset_s - r.offset_s,
            confidence: s.estimate.confidence,
            ms_per_frame: t0.elapsed().as_secs_f64() * 1e3 / r.frames() as f64,
        }),
        Err(e) => Err(e.to_string()),
    }
}

/// Renders every clip, measures, picks and scores (progress on stderr).
pub fn run(config: Config) -> Result<Outcome> {
    let t0 = std::time::Instant::now();
    std::fs::create_dir_all(&config.out).map_err(|e| mmbm::error::Error::io(&config.out, e))?;
    let mut rendered = Vec::new();
    for spec in &config.specs {
        eprintln!("rendering {} ...", spec.name);
        let r = clips::render(spec, &config.format, &config.repo, &config.out)?;
        eprintln!(
            "  {} frames in {:.1} s; true blur mean {:.2} px",
            r.frames(),
            r.render_s,
            r.truth.iter().sum::<f64>() / r.frames() as f64
        );
        let m = pick::measure(&r, &config.out, spec.name, config.window)?;
        rendered.push((spec.clone(), r, m));
    }
    let ok = |r: &Rendered| -> Vec<bool> { r.truth.iter().map(|&b| b <= BUDGET_PX).collect() };
    let (_, tr, tm) = &rendered[TUNED_ON.min(rendered.len() - 1)];
    let lap_threshold = score::tune_threshold(&tm.laplacian, &ok(tr));
    let mut clips = Vec::new();
    for (spec, r, m) in rendered {
        eprintln!("scoring {} ...", spec.name);
        let mut scores = Vec::new();
        for p in Picker::ALL {
            let chosen = pick::picks(p, &m, &r.truth, config.window, lap_threshold)?;
            let s = score::score(&chosen, &r.truth, &m.t);
            scores.push((p, chosen, s));
        }
        let mut offset_scores = Vec::new();
        for e in OFFSET_ERRORS_S {
            let mut m2 = m.clone();
            m2.gyro = pick::gyro_blur(&r.gyro, &r, r.offset_s + e)?;
            let chosen = pick::picks(Picker::Gyro, &m2, &r.truth, config.window, lap_threshold)?;
            offset_scores.push(score::score(&chosen, &r.truth, &m.t));
        }
        let is = ok(&r);
        let said: Vec<bool> = m
            .gyro
            .iter()
            .map(|b| b.is_some_and(|b| b <= BUDGET_PX))
            .collect();
        let budget_gyro = prf(&said, &is);
        let said: Vec<bool> = m.laplacian.iter().map(|&s| s >= lap_threshold).collect();
        let budget_laplacian = prf(&said, &is);
        let sync = sync_clip(&r);
        clips.push(ClipResult {
            spec,
            clip: r,
            measures: m,
            scores,
            sync,
            offset_scores,
            budget_gyro,
            budget_laplacian,
        });
    }
    Ok(Outcome {
        stretches: Stretches::of(&config.format),
        config,
        clips,
        lap_threshold,
        total_s: t0.elapsed().as_secs_f64(),
    })
}
