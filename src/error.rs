//! The library's error type: every failure names what went wrong and where.

use std::path::PathBuf;

/// Result alias used throughout the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Every error the library reports. Messages name the file, line and column
/// (for logs), the parameter (for models) or the adapter list (for the GPU).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// A log or table file has bad content at a known place.
    #[error("{path}:{line}:{column}: {message}")]
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
    #[error("invalid {what}: {message}")]
    Invalid {
        /// The parameter or option name.
        what: String,
        /// Why it is rejected.
        message: String,
    },
    /// A configuration file (TOML or JSON) could not be understood.
    #[error("{path}: {message}")]
    Config {
        /// The file involved.
        path: PathBuf,
        /// Deserializer message.
        message: String,
    },
    /// An image file could not be decoded or encoded.
    #[error("{path}: image error: {message}")]
    Image {
        /// The file involved.
        path: PathBuf,
        /// Decoder or encoder message.
        message: String,
    },
    /// No usable GPU adapter, or a GPU operation failed.
    #[error("GPU: {0}")]
    Gpu(String),
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

/// A user's value quoted for an error message: `'value'`, cut to 64 bytes.
pub fn quote(s: &str) -> String {
    format!("'{}'", clip(s, 64))
}

/// Checks that `x` is finite, naming it in the error.
pub fn finite(what: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::invalid(
            what,
            format!("must be a finite number, got {x}"),
        ))
    }
}

/// Checks that `x` is finite and strictly positive, naming it in the error.
pub fn positive(what: &str, x: f64) -> Result<f64> {
    finite(what, x)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(Error::invalid(what, format!("must be > 0, got {x}")))
    }
}
