//! Video frame tables (`../shared/data/*/frames.csv`): a CSV with `#` comment
//! lines and a header with `t_start` (exposure start of the first line, s, on
//! the gyro log's clock), `exposure_s` and optionally `readout_s` (rolling
//! shutter, s). Other columns are ignored. Errors name the file, line and column.
//!
//! [`read_frame_table`] also reads a phone's image list
//! ([`super::phone::read_image_list`]: nanosecond timestamp and exposure,
//! and each frame's readout when it has a `readout_ns` or `readout_s` column)
//! and ffprobe's frame output ([`super::ffprobe`]: presentation times, the
//! exposure given), chosen by the first line.

use crate::error::{Error, Result};
use std::path::Path;

/// One video frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VideoFrame {
    /// Exposure start of the first line, s.
    pub t_start: f64,
    /// Exposure time of each line, s.
    pub exposure_s: f64,
    /// Rolling-shutter readout (first to last line), s; `None` when the table has no such column.
    pub readout_s: Option<f64>,
}

impl VideoFrame {
    /// Checks the values (every door: a table, Python): `t_start` finite,
    /// `exposure_s` finite and > 0, `readout_s` finite and >= 0. An error is
    /// `(column, message)`.
    pub fn check(&self) -> std::result::Result<(), (&'static str, String)> {
        if !self.t_start.is_finite() {
            return Err((
                "t_start",
                format!("must be a finite number, got {}", self.t_start),
            ));
        }
        if !self.exposure_s.is_finite() {
            return Err((
                "exposure_s",
                format!("must be a finite number, got {}", self.exposure_s),
            ));
        }
        if self.exposure_s <= 0.0 {
            return Err((
                "exposure_s",
                format!("must be > 0 s, got {}", self.exposure_s),
            ));
        }
        if let Some(r) = self.readout_s {
            if !r.is_finite() {
                return Err(("readout_s", format!("must be a finite number, got {r}")));
            }
            if r < 0.0 {
                return Err(("readout_s", format!("must be >= 0 s, got {r}")));
            }
        }
        Ok(())
    }
}

/// The kinds of frame table [`read_frame_table`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableKind {
    /// `t_start, exposure_s[, readout_s]` (s).
    Plain,
    /// A phone's image list: `timestamp_ns, exposure_ns`.
    ImageList,
    /// `ffprobe -show_frames` output: presentation times only.
    Ffprobe,
}

/// The kind of the frame table at `path`, from its first non-blank line (a
/// pipe, which cannot be read twice, is taken as a plain table).
pub fn table_kind(path: &Path) -> TableKind {
    if !super::input::is_regular_file(path) {
        return TableKind::Plain;
    }
    let Ok(mut lines) = super::input::TextLines::open(path) else {
        return TableKind::Plain;
    };
    while let Ok(Some((_, l))) = lines.next_line() {
        if l.trim().is_empty() {
            continue;
        }
        if super::phone::is_image_list_header(&l) {
            return TableKind::ImageList;
        }
        if super::ffprobe::is_ffprobe_line(&l) {
            return TableKind::Ffprobe;
        }
        if !l.trim_start().starts_with('#') {
            break;
        }
    }
    TableKind::Plain
}

/// Reads a frame table of any [`TableKind`]. `exposure_s` (s, > 0) is the
/// exposure of every frame of a table without one (ffprobe's); a table
/// with its own exposure refuses it. The readout is the camera's unless a
/// plain table has `readout_s` or an image list `readout_ns` / `readout_s`
/// (each frame's own).
pub fn read_frame_table(path: &Path, exposure_s: Option<f64>) -> Result<Vec<VideoFrame>> {
    let kind = table_kind(path);
    if let Some(e) = exposure_s {
        if !(e.is_finite() && e > 0.0) {
            return Err(Error::invalid(
                "--exposure",
                format!("must be > 0 s, got {e}"),
            ));
        }
        if kind != TableKind::Ffprobe {
            return Err(Error::invalid(
                "--exposure",
                format!(
                    "{} has its own exposure column; --exposure is for a table of times only (ffprobe's)",
                    path.display()
                ),
            ));
        }
    }
    match kind {
        TableKind::Plain => read_frames(path),
        TableKind::ImageList => Ok(super::phone::read_image_list(path)?
            .into_iter()
            .map(|(t_start, exposure_s, readout_s)| VideoFrame {
                t_start,
                exposure_s,
                readout_s,
            })
            .collect()),
        TableKind::Ffprobe => {
            let Some(exposure_s) = exposure_s else {
                return Err(Error::invalid(
                    path.display().to_string(),
                    "an ffprobe frame table has presentation times only: give the exposure, --exposure S",
                ));
            };
            Ok(super::ffprobe::read_ffprobe_times(path)?
                .into_iter()
                .map(|t_start| VideoFrame {
                    t_start,
                    exposure_s,
                    readout_s: None,
                })
                .collect())
        }
    }
}

/// Reads a plain frame table.
pub fn read_frames(path: &Path) -> Result<Vec<VideoFrame>> {
    use super::input::{open_stream, LineCap, MAX_LINE_BYTES};
    let file = LineCap::new(open_stream(path)?, path, MAX_LINE_BYTES);
    let mut rd = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(std::io::BufReader::new(file));
    let parse_err = |line: u64, column: &str, message: String| Error::Parse {
        path: path.into(),
        line,
        column: column.into(),
        message,
    };
    let headers = rd
        .headers()
        .map_err(|e| parse_err(1, "header", e.to_string()))?
        .clone();
    let find = |n: &str| headers.iter().position(|h| h == n);
    let (Some(it), Some(ie)) = (find("t_start"), find("exposure_s")) else {
        return Err(parse_err(
            1,
            "header",
            format!(
                "expected columns t_start and exposure_s (and optionally readout_s), found: {}",
                headers.iter().collect::<Vec<_>>().join(",")
            ),
        ));
    };
    let ir = find("readout_s");
    let mut out = Vec::new();
    let mut record = csv::StringRecord::new();
    loop {
        match rd.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e.position().map_or(0, |p| p.line());
                return Err(parse_err(line, "record", e.to_string()));
            }
        }
        let line = record.position().map_or(0, |p| p.line());
        let field = |i: usize, name: &str| -> Result<f64> {
            let s = record.get(i).unwrap_or("");
            let x: f64 = s
                .parse()
                .map_err(|_| parse_err(line, name, format!("'{s}' is not a number")))?;
            if !x.is_finite() {
                return Err(parse_err(line, name, format!("'{s}' is not finite")));
            }
            Ok(x)
        };
        let frame = VideoFrame {
            t_start: field(it, "t_start")?,
            exposure_s: field(ie, "exposure_s")?,
            readout_s: ir.map(|i| field(i, "readout_s")).transpose()?,
        };
        frame
            .check()
            .map_err(|(column, message)| parse_err(line, column, message))?;
        out.push(frame);
    }
    Ok(out)
}
