//! Video frame tables (`../shared/data/*/frames.csv`): a CSV with `#` comment
//! lines and a header with `t_start` (exposure start of the first line, s, on
//! the gyro log's clock), `exposure_s` and optionally `readout_s` (rolling
//! shutter, s). Other columns are ignored. Errors name the file, line and column.

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
            return Err(("t_start", format!("must be finite, got {}", self.t_start)));
        }
        if !(self.exposure_s.is_finite() && self.exposure_s > 0.0) {
            return Err((
                "exposure_s",
                format!("must be > 0 s, got {}", self.exposure_s),
            ));
        }
        if self.readout_s.is_some_and(|r| !(r.is_finite() && r >= 0.0)) {
            return Err(("readout_s", "must be >= 0 s".into()));
        }
        Ok(())
    }
}

/// Reads a frame table.
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
