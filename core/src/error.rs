//! The library's error type: every failure names what went wrong and where.

use std::path::{Path, PathBuf};

/// Result alias used throughout the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Every error the library reports. Messages name the file, line and column
/// (for logs), the parameter (for models) or the adapter list (for the GPU).
///
/// What an error shows is bounded and printable, whatever the input: every
/// field is escaped and cut when displayed ([`shown`], [`show_path`]), so a
/// huge header, a parser's snippet of a huge line or control bytes in a
/// value never reach the terminal whole.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{}: {}", show_path(.path), shown(&.source.to_string(), MAX_SHOWN))]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// A log or table file has bad content at a known place.
    #[error(
        "{}:{}:{}: {}",
        show_path(.path),
        .line,
        shown(.column, 64),
        shown(.message, MAX_SHOWN)
    )]
    Parse {
        /// The file involved.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
        /// Column name (or 1-based index) of the bad field.
        column: String,
        /// What is wrong.
        message: String,
    },
    /// A model parameter is invalid (zero focal length, plane behind the camera, NaN...).
    #[error("invalid {}: {}", shown(.what, MAX_MESSAGE), shown(.message, MAX_SHOWN))]
    Invalid {
        /// The parameter or option name.
        what: String,
        /// Why it is rejected.
        message: String,
    },
    /// A configuration file (TOML or JSON) could not be understood.
    #[error("{}: {}", show_path(.path), shown(.message, MAX_SHOWN))]
    Config {
        /// The file involved.
        path: PathBuf,
        /// Deserializer message.
        message: String,
    },
    /// An image file could not be decoded or encoded.
    #[error("{}: image error: {}", show_path(.path), shown(.message, MAX_SHOWN))]
    Image {
        /// The file involved.
        path: PathBuf,
        /// Decoder or encoder message.
        message: String,
    },
    /// No usable GPU adapter, or a GPU operation failed.
    #[error("GPU: {}", shown(.0, MAX_SHOWN))]
    Gpu(String),
    /// The call was cancelled from outside ([`crate::cancel`]: Ctrl-C in
    /// Python) before it finished; it returned nothing.
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    /// Shorthand for [`Error::Invalid`].
    /// Messages are cut to [`MAX_MESSAGE`] bytes (a huge bad value is not
    /// echoed whole).
    pub fn invalid(what: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid {
            what: clip(&what.into(), MAX_MESSAGE),
            message: clip(&message.into(), MAX_MESSAGE),
        }
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// Longest message or echoed value kept in an error, bytes.
pub const MAX_MESSAGE: usize = 512;

/// `s` cut to at most `max` bytes (at a character boundary), with the
/// original length stated when cut.
pub fn clip(s: &str, max: usize) -> String {
    if s.len() <= max {
        return s.to_string();
    }
    let mut end = max;
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}... ({} bytes in all)", &s[..end], s.len())
}

/// Longest error message shown, bytes, after escaping (a parser's message
/// with a snippet of the source spans a few lines of at most [`MAX_MESSAGE`]).
pub const MAX_SHOWN: usize = 4 * MAX_MESSAGE;

/// `s` made safe and short enough to print: control characters other than
/// newline and tab escaped (`\x00`, `\u{85}`), each line cut to
/// [`MAX_MESSAGE`] bytes, the whole to `max` bytes.
pub fn shown(s: &str, max: usize) -> String {
    let line_max = max.min(MAX_MESSAGE);
    if s.len() <= line_max && !s.chars().any(needs_escape) {
        return s.to_string();
    }
    let mut out = String::new();
    for (i, line) in s.split('\n').enumerate() {
        if i > 0 {
            if out.len() >= max {
                out += &format!("... ({} bytes in all)", s.len());
                break;
            }
            out.push('\n');
        }
        let start = out.len();
        for c in line.chars() {
            if out.len() >= max {
                out += &format!("... ({} bytes in all)", s.len());
                return out;
            }
            if out.len() - start >= line_max {
                out += &format!("... ({} bytes in all)", line.len());
                break;
            }
            match c as u32 {
                _ if !needs_escape(c) => out.push(c),
                n if n < 0x80 => out += &format!("\\x{n:02x}"),
                n => out += &format!("\\u{{{n:x}}}"),
            }
        }
    }
    out
}

/// Characters [`shown`] escapes: controls (C0, DEL, C1) but newline and tab.
fn needs_escape(c: char) -> bool {
    c.is_control() && c != '\n' && c != '\t'
}

/// A path for an error message: bytes that are not UTF-8 shown as `\xNN`
/// (not replaced, so two names stay apart), control characters escaped,
/// cut to [`MAX_MESSAGE`] bytes.
pub fn show_path(p: &Path) -> String {
    #[cfg(unix)]
    let s = {
        use std::os::unix::ffi::OsStrExt;
        let mut s = String::new();
        for chunk in p.as_os_str().as_bytes().utf8_chunks() {
            s += chunk.valid();
            for b in chunk.invalid() {
                s += &format!("\\x{b:02x}");
            }
        }
        s
    };
    #[cfg(not(unix))]
    let s = p.display().to_string();
    shown(&one_line(&s), MAX_MESSAGE)
}

/// `s` with newlines and tabs escaped too (a value or a name is one line).
fn one_line(s: &str) -> String {
    s.replace('\n', "\\x0a").replace('\t', "\\x09")
}

/// A user's value quoted for an error message: `'value'`, escaped as by
/// [`show_path`], cut to 64 bytes.
pub fn quote(s: &str) -> String {
    format!("'{}'", shown(&one_line(s), 64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_escapes_controls_and_bounds_every_line() {
        assert_eq!(shown("plain", 100), "plain");
        assert_eq!(shown("a\0b\rc\u{85}", 100), "a\\x00b\\x0dc\\u{85}");
        assert_eq!(shown("two\nlines\tkept", 100), "two\nlines\tkept");
        let huge = "x".repeat(3_000_000);
        let s = shown(&format!("head\n{huge}\ntail"), MAX_SHOWN);
        assert!(s.len() < MAX_MESSAGE + 64, "{}", s.len());
        assert!(s.starts_with("head\nxxx") && s.contains("3000000 bytes in all"));
        assert!(s.ends_with("\ntail"), "{s}");
        let many = "y\n".repeat(1_000_000);
        let s = shown(&many, MAX_SHOWN);
        assert!(s.len() <= MAX_SHOWN + 64 && s.contains("2000000 bytes in all"));
        let q = quote(&"z".repeat(1000));
        assert!(q.len() < 100 && q.contains("1000 bytes in all"), "{q}");
        let nul = "\0".repeat(1000);
        assert!(shown(&nul, MAX_SHOWN).len() <= MAX_MESSAGE + 64);
    }

    #[cfg(unix)]
    #[test]
    fn paths_keep_their_bytes() {
        use std::os::unix::ffi::OsStrExt;
        let p = Path::new(std::ffi::OsStr::from_bytes(b"tex/caf\xe9\n.png"));
        assert_eq!(show_path(p), "tex/caf\\xe9\\x0a.png");
    }
}
