//! Bounded input, the one place where the kind and the size of what is read
//! are checked, for every reader (gyro CSV, `.gcsv`, MCAP, frame tables,
//! line streams, images, configuration files):
//!
//! - [`open_file`] opens only a regular file (a whole-file reader: MCAP,
//!   images, EXR); [`open_stream`] also a pipe (a FIFO, a process
//!   substitution): a character device such as `/dev/zero`, a directory or a
//!   socket is refused before anything is read.
//! - [`LineCap`] (a byte stream for a CSV reader) and [`read_line`] (one line
//!   of a [`BufRead`]) refuse a line longer than [`MAX_LINE_BYTES`];
//!   [`MAX_HEADER_BYTES`] bounds a `.gcsv` header (every line before its
//!   column line together).
//! - [`check_image_size`] refuses an image whose header claims more than
//!   [`MAX_IMAGE_PIXELS`] before it is decoded; [`read_text`] reads a
//!   configuration file of at most [`MAX_TEXT_BYTES`].
//!
//! The kind check and [`read_text`] live in `crate::bounded` (layer 0, so
//! that the camera layer reads its files with the same caps) and are
//! re-exported here.

pub use crate::bounded::{is_regular_file, open_file, open_stream, read_text, MAX_TEXT_BYTES};
use crate::error::{Error, Result};
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};

/// Longest line of any text input (a log row, a header line, a live line), bytes.
pub const MAX_LINE_BYTES: usize = 4 << 20;

/// Longest `.gcsv` header (the magic line, `key,value` lines and comments
/// before the column line, together), bytes.
pub const MAX_HEADER_BYTES: usize = 16 << 20;

/// Most pixels (width x height) an input image may declare to be decoded
/// (16384 x 16384).
pub use crate::limits::MAX_IMAGE_PIXELS;

/// The error for line `line` of `path` longer than `cap` bytes.
pub fn line_too_long(path: &Path, line: u64, cap: usize) -> Error {
    Error::Parse {
        path: path.into(),
        line,
        column: "-".into(),
        message: format!("the line is longer than {cap} bytes, the most read"),
    }
}

/// How one line was read by [`read_line`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Line {
    /// A line (its `\n` kept, if it had one) is in the buffer.
    Read,
    /// The line was longer than the cap: the buffer holds its first `cap`
    /// bytes, the rest was read and dropped (up to its `\n`).
    TooLong,
    /// End of input.
    Eof,
}

/// Reads one line into `buf` (cleared first) holding at most `cap` bytes of
/// it (not counting its `\n`): a longer line is read to its end in bounded memory and reported as
/// [`Line::TooLong`].
pub fn read_line(src: &mut dyn BufRead, buf: &mut Vec<u8>, cap: usize) -> std::io::Result<Line> {
    // Never stopped: `None` cannot come back.
    Ok(read_line_or_stop(src, buf, cap, &|| false)?.unwrap_or(Line::Eof))
}

/// [`read_line`] that gives up once `stop()` is true, asked before each
/// chunk the source yields (a few kB): an endless line (input that never
/// sends its `\n`) is left at a stop request instead of when it ends.
/// `None` when stopped (the part read is dropped). A read blocked on a
/// silent source is not interrupted.
pub fn read_line_or_stop(
    src: &mut dyn BufRead,
    buf: &mut Vec<u8>,
    cap: usize,
    stop: &dyn Fn() -> bool,
) -> std::io::Result<Option<Line>> {
    buf.clear();
    let mut total = 0usize;
    loop {
        if stop() {
            return Ok(None);
        }
        let chunk = match src.fill_buf() {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if chunk.is_empty() {
            return Ok(Some(match (total, total > cap) {
                (0, _) => Line::Eof,
                (_, true) => Line::TooLong,
                _ => Line::Read,
            }));
        }
        let (n, end) = match chunk.iter().position(|&b| b == b'\n') {
            Some(i) => (i + 1, true),
            None => (chunk.len(), false),
        };
        let room = (cap + 1).saturating_sub(buf.len()).min(n);
        buf.extend_from_slice(&chunk[..room]);
        // The line's length does not count its `\n` (as for [`LineCap`]).
        total = total.saturating_add(n - usize::from(end));
        src.consume(n);
        if end {
            return Ok(Some(if total > cap {
                buf.truncate(cap);
                Line::TooLong
            } else {
                Line::Read
            }));
        }
        if total > cap {
            buf.truncate(cap);
        }
    }
}

/// A byte stream (for a CSV reader) that ends with an error at a line
/// longer than `cap` bytes. A line break inside a quoted CSV field does not
/// end the line (quotes are counted, except on `#` comment lines), so a
/// record cannot grow past the cap either. The stream keeps the typed
/// [`Error`] (naming the file and the line) for [`LineCap::take_error`];
/// the I/O error it returns carries only that error's text.
pub struct LineCap<R> {
    inner: R,
    path: PathBuf,
    cap: usize,
    run: usize,
    line: u64,
    quoted: bool,
    comment: bool,
    start: bool,
    error: Option<Error>,
}

impl<R: Read> LineCap<R> {
    /// `inner`, named `path` in errors, with lines of at most `cap` bytes.
    pub fn new(inner: R, path: &Path, cap: usize) -> Self {
        LineCap {
            inner,
            path: path.into(),
            cap,
            run: 0,
            line: 1,
            quoted: false,
            comment: false,
            start: true,
            error: None,
        }
    }

    /// The error that ended the stream (a line over the cap), once.
    pub fn take_error(&mut self) -> Option<Error> {
        self.error.take()
    }
}

impl<R: Read> LineCap<R> {
    /// Adds `k` bytes to the current line; the error once it is over the cap.
    fn grow(&mut self, k: usize) -> std::io::Result<()> {
        self.run += k;
        if self.run > self.cap {
            let e = line_too_long(&self.path, self.line, self.cap);
            let text = e.to_string();
            self.error = Some(e);
            return Err(std::io::Error::other(text));
        }
        Ok(())
    }
}

impl<R: Read> Read for LineCap<R> {
    fn read(&mut self, dst: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(dst)?;
        let buf = &dst[..n];
        let mut i = 0;
        // Only line breaks and quotes change the state (and `#` first on a
        // line): the bytes between them are counted in one step.
        while i < n {
            if self.start {
                self.start = false;
                if buf[i] == b'#' && !self.quoted {
                    self.comment = true;
                }
            }
            let Some(j) = memchr::memchr2(b'\n', b'"', &buf[i..]) else {
                self.grow(n - i)?;
                break;
            };
            self.grow(j)?;
            let b = buf[i + j];
            i += j + 1;
            if b == b'\n' && !self.quoted {
                self.run = 0;
                self.line += 1;
                self.comment = false;
                self.start = true;
                continue;
            }
            if b == b'\n' {
                self.line += 1;
            }
            if b == b'"' && !self.comment {
                self.quoted = !self.quoted;
            }
            self.grow(1)?;
        }
        Ok(n)
    }
}

/// The lines of a text file (or pipe) one at a time, each at most
/// [`MAX_LINE_BYTES`], without their line break (and `\r`): for the small
/// hand-read tables (image lists, ffprobe output). Errors name the file and
/// the line.
pub struct TextLines {
    src: std::io::BufReader<Box<dyn Read + Send>>,
    path: PathBuf,
    line: u64,
    buf: Vec<u8>,
}

impl TextLines {
    /// Opens `path` ([`open_stream`]).
    pub fn open(path: &Path) -> Result<Self> {
        let f: Box<dyn Read + Send> = Box::new(open_stream(path)?);
        Ok(TextLines {
            src: std::io::BufReader::with_capacity(1 << 16, f),
            path: path.into(),
            line: 0,
            buf: Vec::new(),
        })
    }

    /// The next line and its number (1-based), `None` at the end.
    pub fn next_line(&mut self) -> Result<Option<(u64, String)>> {
        let r = read_line(&mut self.src, &mut self.buf, MAX_LINE_BYTES)
            .map_err(|e| Error::io(&self.path, e))?;
        self.line += 1;
        match r {
            Line::Eof => Ok(None),
            Line::TooLong => Err(line_too_long(&self.path, self.line, MAX_LINE_BYTES)),
            Line::Read => {
                let text = std::str::from_utf8(&self.buf).map_err(|_| Error::Parse {
                    path: self.path.clone(),
                    line: self.line,
                    column: "-".into(),
                    message: "the line is not UTF-8 text".into(),
                })?;
                let text = text.strip_suffix('\n').unwrap_or(text);
                let text = text.strip_suffix('\r').unwrap_or(text);
                Ok(Some((self.line, text.to_string())))
            }
        }
    }
}

/// Checks that time `t` (s) of the sample on `line` comes after the previous
/// sample's (`prev`: its time, s, and line); the error names the file, the
/// line and the time column `column`.
pub fn check_increasing(
    path: &Path,
    line: u64,
    column: &str,
    t: f64,
    prev: Option<(f64, u64)>,
) -> Result<()> {
    match prev {
        Some((prev, prev_line)) if t <= prev => Err(Error::Parse {
            path: path.into(),
            line,
            column: column.into(),
            message: format!(
                "time {t} s is not after the previous sample's {prev} s (line {prev_line}): time must strictly increase"
            ),
        }),
        _ => Ok(()),
    }
}

/// Refuses an image of `width` x `height` over [`MAX_IMAGE_PIXELS`].
pub fn check_image_size(path: &Path, width: u64, height: u64) -> Result<()> {
    let pixels = width as u128 * height as u128;
    if pixels > MAX_IMAGE_PIXELS as u128 {
        return Err(Error::Image {
            path: path.into(),
            message: format!(
                "the header declares {width} x {height} pixels, more than the {MAX_IMAGE_PIXELS} mmbm decodes"
            ),
        });
    }
    Ok(())
}

/// The width and height an image file's header declares (a regular file,
/// format guessed from its content), checked against [`MAX_IMAGE_PIXELS`]
/// without decoding it.
pub fn image_dimensions(path: &Path) -> Result<(u32, u32)> {
    let file = open_file(path)?;
    let r = image::ImageReader::new(std::io::BufReader::new(file))
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    let (w, h) = r.into_dimensions().map_err(|e| Error::Image {
        path: path.into(),
        message: e.to_string(),
    })?;
    check_image_size(path, w as u64, h as u64)?;
    Ok((w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_over_the_cap() {
        let text = b"abc\ncdefg\n\nxy";
        let mut src: &[u8] = text;
        let mut buf = Vec::new();
        let mut got = Vec::new();
        loop {
            let r = read_line(&mut src, &mut buf, 3).unwrap();
            if r == Line::Eof {
                break;
            }
            got.push((r, String::from_utf8(buf.clone()).unwrap()));
        }
        assert_eq!(
            got,
            [
                (Line::Read, "abc\n".to_string()),
                (Line::TooLong, "cde".to_string()),
                (Line::Read, "\n".to_string()),
                (Line::Read, "xy".to_string()),
            ]
        );
        let read = |s: &'static [u8]| {
            let mut out = Vec::new();
            LineCap::new(s, Path::new("x"), 4)
                .read_to_end(&mut out)
                .map(|_| out)
        };
        assert!(read(b"abcd\nabcd\n# \"x\nabcd").is_ok());
        assert!(read(b"abcd\nabcde\n").is_err());
        // A quoted field spanning lines is one record.
        assert!(read(b"\"a\nb\nc\"\n").is_err());
        assert!(read(b"\"a\"\nb\n").is_ok());
    }
}
