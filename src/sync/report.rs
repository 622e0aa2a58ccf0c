//! The TOML `mmbm sync` writes and `frames --sync` reads.
//!
//! Keys: `offset_s` (s; video time = gyro time + offset, the value `frames
//! --time-offset` takes), `readout_s` (s, the rolling-shutter readout the
//! offset was found with), `confidence` (0..1), then diagnostics:
//! `readout_distinguishable`, `explained`, `rival_cost`, `rival_offset_s`,
//! `focal_scale`, `exposure_s`, `search_s`, `frames`, `pairs_used`,
//! `tracked_share`, `motion_rms_px`, the spans (`video_start_s`,
//! `video_end_s`, `gyro_start_s`, `gyro_end_s`, each on its own clock), the
//! files, and `[[readout_scan]]` (`readout_s`, `offset_s`, `cost`).

use super::SyncOutcome;
use crate::bounded::read_text_at_most;
use crate::error::{show_path, Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Largest sync file read, bytes.
const MAX_SYNC_FILE_BYTES: u64 = 1 << 20;

/// One readout of the scan.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ScanRow {
    /// Readout, s.
    pub readout_s: f64,
    /// Best offset with it, s.
    pub offset_s: f64,
    /// Cost there (0 all motion explained, 1 none).
    pub cost: f64,
}

/// The sync file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SyncFile {
    /// Offset, s: video time = gyro time + offset (`frames --time-offset`).
    pub offset_s: f64,
    /// Rolling-shutter readout the offset goes with, s.
    pub readout_s: f64,
    /// Confidence, 0..1: explained share x uniqueness of the minimum.
    pub confidence: f64,
    /// Whether the readout scan could tell readouts apart.
    #[serde(default)]
    pub readout_distinguishable: bool,
    /// Share of the measured motion the gyro explains at the offset, 0..1.
    #[serde(default)]
    pub explained: f64,
    /// Cost of the best offset farther than 0.1 s (or 3 frames) away.
    #[serde(default)]
    pub rival_cost: f64,
    /// Where that rival lies, s (NaN when the search range has none).
    #[serde(default)]
    pub rival_offset_s: f64,
    /// Measured over predicted motion: 1 when the camera's focal length is right.
    #[serde(default)]
    pub focal_scale: f64,
    /// Exposure assumed, s.
    #[serde(default)]
    pub exposure_s: f64,
    /// Half width of the search, s.
    #[serde(default)]
    pub search_s: f64,
    /// Frames decoded.
    #[serde(default)]
    pub frames: usize,
    /// Frame pairs scored at the offset.
    #[serde(default)]
    pub pairs_used: usize,
    /// Share of the patches tracked.
    #[serde(default)]
    pub tracked_share: f64,
    /// RMS patch motion between frames, px at the analysis size.
    #[serde(default)]
    pub motion_rms_px: f64,
    /// First frame's presentation time, s (video clock).
    #[serde(default)]
    pub video_start_s: f64,
    /// Last frame's presentation time, s (video clock).
    #[serde(default)]
    pub video_end_s: f64,
    /// First gyro sample, s (gyro clock).
    #[serde(default)]
    pub gyro_start_s: f64,
    /// Last gyro sample, s (gyro clock).
    #[serde(default)]
    pub gyro_end_s: f64,
    /// The video.
    #[serde(default)]
    pub video: String,
    /// The gyro log.
    #[serde(default)]
    pub gyro: String,
    /// The readout scan.
    #[serde(default)]
    pub readout_scan: Vec<ScanRow>,
}

impl SyncFile {
    /// The file for an outcome (`exposure_s`, `search_s` as asked).
    pub fn new(
        out: &SyncOutcome,
        video: &Path,
        gyro: &Path,
        exposure_s: f64,
        search_s: f64,
    ) -> Self {
        let e = &out.estimate;
        SyncFile {
            offset_s: e.offset_s,
            readout_s: e.readout_s,
            confidence: e.confidence,
            readout_distinguishable: e.readout_distinguishable,
            explained: 1.0 - e.cost,
            rival_cost: e.rival_cost,
            rival_offset_s: e.rival_offset_s,
            focal_scale: e.scale,
            exposure_s,
            search_s,
            frames: out.frames,
            pairs_used: e.pairs,
            tracked_share: out.tracked_share,
            motion_rms_px: out.motion_rms_px,
            video_start_s: out.video_span.0,
            video_end_s: out.video_span.1,
            gyro_start_s: out.gyro_span.0,
            gyro_end_s: out.gyro_span.1,
            video: video.display().to_string(),
            gyro: gyro.display().to_string(),
            readout_scan: e
                .readout_scan
                .iter()
                .map(|&(readout_s, offset_s, cost)| ScanRow {
                    readout_s,
                    offset_s,
                    cost,
                })
                .collect(),
        }
    }

    /// The TOML text, with a header comment.
    pub fn to_toml(&self) -> Result<String> {
        let body = toml::to_string(self)
            .map_err(|e| Error::invalid("sync file", format!("cannot be written: {e}")))?;
        Ok(format!(
            "# mmbm sync: video time = gyro time + offset_s (frames --time-offset / --sync)\n{body}"
        ))
    }
}

/// Reads a sync file: `offset_s` finite, `readout_s` finite and not
/// negative, `confidence` in 0..1; refused naming the file and key.
pub fn read_sync_file(path: &Path) -> Result<SyncFile> {
    let text = read_text_at_most(path, MAX_SYNC_FILE_BYTES)?;
    let f: SyncFile = toml::from_str(&text).map_err(|e| {
        Error::invalid(
            show_path(path),
            format!(
                "not a sync file (mmbm sync --out): {}",
                e.to_string().lines().next().unwrap_or("")
            ),
        )
    })?;
    let bad = |key: &str, v: f64, want: &str| {
        Error::invalid(
            format!("{}: {key}", show_path(path)),
            format!("{v}: expected {want}"),
        )
    };
    if !f.offset_s.is_finite() {
        return Err(bad("offset_s", f.offset_s, "a finite number of seconds"));
    }
    if !(f.readout_s.is_finite() && f.readout_s >= 0.0) {
        return Err(bad("readout_s", f.readout_s, "a finite readout >= 0 s"));
    }
    if !(0.0..=1.0).contains(&f.confidence) {
        return Err(bad("confidence", f.confidence, "a number in 0..1"));
    }
    Ok(f)
}
