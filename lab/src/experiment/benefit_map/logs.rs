//! The map's columns from gyro logs ("my robot, my light"; docs/spec.md
//! section 11): `[map] logs = ["path.csv", ...]`, any format
//! [`crate::telemetry::read_gyro`] reads (the CSV log of docs/spec.md
//! section 5, phone apps' exports, GoPro and Insta360 files, ...), each a
//! column of the map beside the simulated gaits, named by its file stem.
//!
//! The walk is the log's: the camera turns as the gyro says during each
//! exposure (as `mmbm trigger --gyro` and the experiment's `gyro` log do),
//! without translation unless the log carries velocity; the board's
//! distance follows `speed_m_s` from `start_distance_m` as for the
//! experiment's `gyro` log. The policies and lights are the map's. The log
//! is the same walk for every seed: the seeds change only the sensor noise
//! (and the render's sampling lattice), not the motion or the triggers.

use super::super::config::ExperimentConfig;
use super::super::walk::{walk_of, Walk};
use crate::error::{Error, Result};
use crate::metric::Scene;
use crate::model::log::ImuLog;
use std::path::{Path, PathBuf};

/// The log's column name: its file stem.
pub fn log_name(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "log".into(), |s| s.to_string_lossy().into_owned())
}

/// The error of a bad log: `map.logs (PATH)` and the reason.
fn bad(path: &Path, why: impl std::fmt::Display) -> Error {
    Error::invalid(format!("map.logs ({})", path.display()), why.to_string())
}

/// The logs of the map: `map.logs`, and the experiment's `gyro` log when
/// it is set and not already listed.
pub fn map_logs(cfg: &ExperimentConfig) -> Vec<PathBuf> {
    let mut out = cfg.map.logs.clone();
    if let Some(g) = &cfg.gyro {
        if !out.contains(g) {
            out.push(g.clone());
        }
    }
    out
}

/// Reads `path` and checks that it holds at least one frame interval of
/// the map's rate (`fps`), naming the file and the reason when not.
pub fn read_map_log(path: &Path, fps: f64) -> Result<ImuLog> {
    let log = crate::telemetry::read_gyro(path, &Default::default()).map_err(|e| bad(path, e))?;
    let span = match (log.first(), log.last()) {
        (Some(a), Some(b)) => b.t - a.t,
        _ => 0.0,
    };
    if log.len() < 2 || span < 1.0 / fps {
        return Err(bad(
            path,
            format!(
                "{} samples over {span:.3} s: shorter than one frame interval at the map's {fps} frames/s",
                log.len()
            ),
        ));
    }
    Ok(log)
}

/// Reads every log of the map (before any render, so that a bad one is
/// refused at once), checking that the names are unique and are not a
/// simulated gait's.
pub fn check_logs(cfg: &ExperimentConfig, gaits: &[String]) -> Result<()> {
    let mut names: Vec<String> = gaits.to_vec();
    for p in map_logs(cfg) {
        let n = log_name(&p);
        if names.contains(&n) {
            return Err(bad(
                &p,
                format!("its name `{n}` (the file stem) is already a column of the map"),
            ));
        }
        names.push(n);
        read_map_log(&p, cfg.map.fps)?;
    }
    Ok(())
}

/// The walk of the log `path` with the map's policies (`mcfg`).
pub fn log_walk(mcfg: &ExperimentConfig, path: &Path, scene: &Scene) -> Result<Walk> {
    let samples = read_map_log(path, mcfg.map.fps)?;
    walk_of(mcfg, log_name(path), 0, samples, scene).map_err(|e| bad(path, e))
}
