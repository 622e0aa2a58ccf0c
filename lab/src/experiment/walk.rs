//! The walks of the experiment: a simulated gait or a real log, its MMBM
//! series, the board's distance, and every policy's frames.

use super::config::ExperimentConfig;
use crate::error::Result;
use crate::io::gyro::{read_log, GyroOptions};
use crate::metric::{Method, Scene};
use crate::model::log::ImuLog;
use crate::sim::{simulate, Gait, GaitConfig};
use crate::trigger::{CameraTiming, Frame, Policies, PolicySpec};
use std::str::FromStr;

/// One walk (simulated or a real log) with its MMBM series and every policy's frames.
#[derive(Debug, Clone)]
pub struct Walk {
    /// `moderate`, `slow`, `fast` or the log's file name; with several seeds,
    /// `moderate-s2` etc.
    pub name: String,
    /// The gait (or the log's file name), shared by the seeds of one walk.
    pub gait: String,
    /// Simulation seed (0 for a log).
    pub seed: u64,
    /// The gyro samples (true motion and measurement).
    pub samples: ImuLog,
    /// Rotation-only MMBM per sample (8x6 grid), mm/s.
    pub mmbm: Vec<f64>,
    /// Distance to the target per sample, m.
    pub distance: Vec<f64>,
    /// `(policy, frames)` in configuration order.
    pub runs: Vec<(PolicySpec, Vec<Frame>)>,
}

/// Builds a walk from the configuration: the simulation of `gait` with
/// `seed`, or the log. `suffix` adds the seed to the name (several seeds).
pub fn make_walk(
    cfg: &ExperimentConfig,
    walk: &str,
    seed: u64,
    suffix: bool,
    scene: &Scene,
) -> Result<Walk> {
    let (name, samples) = match &cfg.gyro {
        Some(p) => (
            p.file_name()
                .map_or("log".into(), |s| s.to_string_lossy().into_owned()),
            read_log(p, GyroOptions::default())?,
        ),
        None => {
            let gait = Gait::from_str(walk)?;
            let g = GaitConfig::preset(gait);
            (
                walk.to_string(),
                ImuLog::new(simulate(&g, cfg.walk_duration_s(gait), cfg.rate_hz, seed)?)?,
            )
        }
    };
    let mut w = walk_of(cfg, name, seed, samples, scene)?;
    if cfg.gyro.is_some() {
        w.seed = 0;
    } else if suffix {
        w.name = format!("{}-s{seed}", w.name);
    }
    Ok(w)
}

/// The walk of `samples` named `name` (the gait or the log): its MMBM
/// series, the board's distance and every policy's frames; `seed` is
/// recorded as the walk's seed.
pub fn walk_of(
    cfg: &ExperimentConfig,
    name: String,
    seed: u64,
    samples: ImuLog,
    scene: &Scene,
) -> Result<Walk> {
    let mmbm = crate::series::mmbm_series(&samples, scene, Method::default())?;
    // Distance to the target: integrate the forward velocity (or the
    // configured speed), starting at start_distance, never closer than min_distance.
    let mut distance = Vec::with_capacity(samples.len());
    let mut d = cfg.start_distance_m;
    for (k, s) in samples.iter().enumerate() {
        if k > 0 {
            let dt = s.t - samples[k - 1].t;
            let vz = s.velocity.map_or(cfg.speed_m_s, |v| v.z);
            d = (d - vz * dt).max(cfg.min_distance_m);
        }
        distance.push(d);
    }
    let specs = cfg.policies.clone();
    let frames = Policies::new(specs.clone(), timing(cfg))?.run(&samples, &mmbm)?;
    let runs: Vec<(PolicySpec, Vec<Frame>)> = specs.into_iter().zip(frames).collect();
    Ok(Walk {
        name: name.clone(),
        gait: name,
        seed,
        samples,
        mmbm,
        distance,
        runs,
    })
}

/// The camera timing of the configuration (a rolling shutter's line readout
/// keeps the camera busy too).
pub fn timing(cfg: &ExperimentConfig) -> CameraTiming {
    CameraTiming {
        delay: cfg.delay_s,
        exposure: cfg.exposure_s,
        readout: cfg.readout_s,
        min_interval: cfg.min_interval_s,
        pitch_mm: 0.0,
    }
    .for_camera(&cfg.camera())
}
