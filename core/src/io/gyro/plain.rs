//! The plain gyro CSV source of [`super::GyroReader`]: the header row
//! (`t, wx, wy, wz`, optional `vx, vy, vz` and `depth`, each at most once)
//! and one sample per record, every field a finite number, in the file's
//! own units and axes. Lines are capped ([`LineCap`]); errors name the file,
//! line and column.

use super::fast::{FastRows, Layout};
use super::raw::Raw;
use crate::error::{quote, Error, Result};
use crate::io::input::{LineCap, MAX_LINE_BYTES};
use glam::DVec3;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

type Records = csv::Reader<LineCap<Box<dyn Read + Send>>>;

/// A gyro CSV, record by record.
pub(super) struct CsvSource {
    path: PathBuf,
    reader: Records,
    idx_t: usize,
    idx_w: [usize; 3],
    idx_v: Option<[usize; 3]>,
    idx_depth: Option<usize>,
    names: Vec<String>,
    record: csv::ByteRecord,
    /// The fast path ([`super::fast`]), while it lasts.
    fast: Option<FastRows>,
}

impl CsvSource {
    /// Reads and checks the header of `input`, named `path` in errors.
    pub fn open(input: Box<dyn Read + Send>, path: &Path) -> Result<Self> {
        let capped = LineCap::new(input, path, MAX_LINE_BYTES);
        // Fields are trimmed where they are read (`field`, the header here):
        // the reader's own trimming rebuilds every record (an allocation each).
        let mut reader = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .flexible(false)
            // The reader's own buffer reads the capped stream directly (a
            // second buffer below it would copy every byte once more).
            .buffer_capacity(1 << 18)
            .from_reader(capped);
        let names: Vec<String> = match reader.headers() {
            Ok(h) => h.iter().map(|s| s.trim().to_string()).collect(),
            Err(e) => return Err(csv_error(&mut reader, path, e, "header")),
        };
        let columns = Columns::find(&names, path)?;
        Ok(CsvSource {
            path: path.into(),
            reader,
            idx_t: columns.t,
            idx_w: columns.w,
            idx_v: columns.v,
            idx_depth: columns.depth,
            names,
            record: csv::ByteRecord::new(),
            fast: None,
        })
    }

    /// Opens a file: a regular file is read by the fast path
    /// ([`super::fast`]) while its lines are plain numeric rows, by the exact
    /// reader from the first line that is not (`fast` false: the exact
    /// reader only).
    pub fn open_file(file: File, path: &Path, fast: bool) -> Result<Self> {
        let twin = match fast && file.metadata().is_ok_and(|m| m.is_file()) {
            true => file.try_clone().ok(),
            false => None,
        };
        let mut src = Self::open(Box::new(file), path)?;
        src.fast = twin.map(|f| FastRows::new(f, src.layout()));
        Ok(src)
    }

    /// The fast path's view of the header.
    pub(super) fn layout(&self) -> Layout {
        Layout::new(
            self.names.len(),
            self.idx_t,
            self.idx_w,
            self.idx_v,
            self.idx_depth,
        )
    }

    /// The next record of the fast path while it lasts; when it meets a line
    /// that is not plain, the exact reader skips the records it gave.
    fn next_fast(&mut self) -> Result<Option<Option<Raw>>> {
        let Some(fast) = &mut self.fast else {
            return Ok(None);
        };
        match fast.next_raw() {
            Ok(r) => Ok(Some(r)),
            Err(_) => {
                let skip = fast.delivered();
                self.fast = None;
                for _ in 0..skip {
                    if let Err(e) = self.reader.read_byte_record(&mut self.record) {
                        return Err(csv_error(&mut self.reader, &self.path, e, "record"));
                    }
                }
                Ok(None)
            }
        }
    }

    /// True when the log has `vx, vy, vz`.
    pub fn has_velocity(&self) -> bool {
        self.idx_v.is_some()
    }

    /// True when the log has `depth`.
    pub fn has_depth(&self) -> bool {
        self.idx_depth.is_some()
    }

    /// The time column's name.
    pub fn time_column(&self) -> &str {
        &self.names[self.idx_t]
    }

    /// The reader's line (after the last record: where the end is reported).
    pub fn position_line(&self) -> u64 {
        self.reader.position().line()
    }

    /// The next record (None at the end of the file).
    pub fn next_raw(&mut self) -> Result<Option<Raw>> {
        if let Some(r) = self.next_fast()? {
            return Ok(r);
        }
        let more = match self.reader.read_byte_record(&mut self.record) {
            Ok(more) => more,
            Err(e) => return Err(csv_error(&mut self.reader, &self.path, e, "record")),
        };
        if !more {
            return Ok(None);
        }
        let line = self.record.position().map_or(0, |p| p.line());
        let t = self.field(self.idx_t, line)?;
        let w = DVec3::new(
            self.field(self.idx_w[0], line)?,
            self.field(self.idx_w[1], line)?,
            self.field(self.idx_w[2], line)?,
        );
        let v = match self.idx_v {
            Some(i) => Some(DVec3::new(
                self.field(i[0], line)?,
                self.field(i[1], line)?,
                self.field(i[2], line)?,
            )),
            None => None,
        };
        let depth = match self.idx_depth {
            Some(i) => Some(self.field(i, line)?),
            None => None,
        };
        Ok(Some(Raw {
            line,
            t,
            w,
            v,
            depth,
        }))
    }

    fn field(&self, idx: usize, line: u64) -> Result<f64> {
        let raw = &self.record[idx];
        let col = &self.names[idx];
        // Bytes: only the columns read need be text (and numbers).
        let fast = crate::io::decimal::parse_f64(raw.trim_ascii());
        let text = || String::from_utf8_lossy(raw);
        let x: f64 = match fast {
            Some(x) => x,
            None => text().trim().parse().map_err(|_| Error::Parse {
                path: self.path.clone(),
                line,
                column: col.clone(),
                message: format!("{} is not a number", quote(text().trim())),
            })?,
        };
        if !x.is_finite() {
            return Err(Error::Parse {
                path: self.path.clone(),
                line,
                column: col.clone(),
                message: format!("{} is not finite", quote(text().trim())),
            });
        }
        Ok(x)
    }
}

/// The positions of the columns read.
struct Columns {
    t: usize,
    w: [usize; 3],
    v: Option<[usize; 3]>,
    depth: Option<usize>,
}

impl Columns {
    fn find(names: &[String], path: &Path) -> Result<Self> {
        let header_err = |column: &str, message: String| Error::Parse {
            path: path.into(),
            line: 1,
            column: column.into(),
            message,
        };
        for n in ["t", "wx", "wy", "wz", "vx", "vy", "vz", "depth"] {
            if names.iter().filter(|h| *h == n).count() > 1 {
                return Err(header_err(
                    n,
                    format!("column '{n}' appears more than once in the header"),
                ));
            }
        }
        let find = |n: &str| names.iter().position(|h| h == n);
        let need = |n: &str| {
            find(n).ok_or_else(|| {
                header_err(
                    n,
                    format!(
                        "missing required column '{n}' (header is: {})",
                        names.join(",")
                    ),
                )
            })
        };
        let t = need("t")?;
        let w = [need("wx")?, need("wy")?, need("wz")?];
        let v = match (find("vx"), find("vy"), find("vz")) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            (None, None, None) => None,
            _ => {
                return Err(header_err(
                    "vx,vy,vz",
                    "velocity columns must come as all three of vx, vy, vz".into(),
                ))
            }
        };
        Ok(Columns {
            t,
            w,
            v,
            depth: find("depth"),
        })
    }
}

/// A CSV reader error as an [`Error`]: a line over the cap is the
/// [`LineCap`]'s own error (file and line), anything else names the CSV
/// position.
fn csv_error(reader: &mut Records, path: &Path, e: csv::Error, what: &str) -> Error {
    if let csv::ErrorKind::Io(_) = e.kind() {
        if let Some(capped) = reader.get_mut().take_error() {
            return capped;
        }
    }
    let (line, column) = match e.kind() {
        csv::ErrorKind::UnequalLengths {
            pos,
            expected_len,
            len,
        } => (
            pos.as_ref().map_or(0, |p| p.line()),
            format!("field count (expected {expected_len}, found {len})"),
        ),
        _ => (e.position().map_or(0, |p| p.line()), what.to_string()),
    };
    Error::Parse {
        path: path.into(),
        line,
        column,
        message: e.to_string(),
    }
}
