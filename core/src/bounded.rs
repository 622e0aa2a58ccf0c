//! Bounded reading of whole files, below every layer that reads one: the
//! kind check ([`open_file`]: a regular file; [`open_stream`]: also a pipe;
//! a character device such as `/dev/zero`, a directory or a socket is
//! refused before anything is read) and [`read_text`], a configuration or
//! camera file of at most [`MAX_TEXT_BYTES`]. `io::input` re-exports these
//! and adds the line, header and image caps of the log and image readers.

use crate::error::{Error, Result};
use std::fs::File;
use std::io::Read;
use std::path::Path;

/// Largest configuration file (TOML, JSON) read whole, bytes.
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

/// An input refused for its kind or size, as an I/O error naming the file.
pub fn refused(path: &Path, message: String) -> Error {
    Error::io(
        path,
        std::io::Error::new(std::io::ErrorKind::InvalidInput, message),
    )
}

/// What a file type is, in words.
fn kind(ft: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_dir() {
        "a directory"
    } else if ft.is_char_device() {
        "a character device"
    } else if ft.is_block_device() {
        "a block device"
    } else if ft.is_socket() {
        "a socket"
    } else if ft.is_fifo() {
        "a pipe"
    } else {
        "not a regular file"
    }
}

/// Checks the kind of what `path` names (links followed): a regular file,
/// or a pipe when `pipe` is allowed.
fn check_kind(path: &Path, pipe: bool) -> Result<()> {
    use std::os::unix::fs::FileTypeExt;
    let ft = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .file_type();
    if ft.is_file() || (pipe && ft.is_fifo()) {
        return Ok(());
    }
    let want = if pipe {
        "a regular file or a pipe"
    } else {
        "a regular file"
    };
    Err(refused(path, format!("is {}: expected {want}", kind(ft))))
}

/// True when `path` names a regular file (links followed).
pub fn is_regular_file(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.is_file())
}

/// Opens a regular file for reading (anything else is refused unopened).
pub fn open_file(path: &Path) -> Result<File> {
    check_kind(path, false)?;
    File::open(path).map_err(|e| Error::io(path, e))
}

/// Opens a regular file or a pipe for reading, as a stream.
pub fn open_stream(path: &Path) -> Result<File> {
    check_kind(path, true)?;
    File::open(path).map_err(|e| Error::io(path, e))
}

/// Reads a whole text file (a configuration) of at most [`MAX_TEXT_BYTES`]
/// from a regular file or a pipe.
pub fn read_text(path: &Path) -> Result<String> {
    read_text_at_most(path, MAX_TEXT_BYTES)
}

/// Reads a whole UTF-8 text file of at most `max` bytes from a regular file
/// or a pipe (a longer one, or one that is not UTF-8, is refused by name).
pub fn read_text_at_most(path: &Path, max: u64) -> Result<String> {
    let mut bytes = Vec::new();
    open_stream(path)?
        .take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > max {
        return Err(refused(
            path,
            format!("longer than {max} bytes, the most read"),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        refused(
            path,
            format!(
                "not UTF-8 text (byte {} is not part of a character)",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_folders_are_refused_unread() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(
            e.contains("/dev/zero") && e.contains("character device"),
            "{e}"
        );
        let e = read_text(Path::new("/")).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        assert!(!is_regular_file(Path::new("/dev/null")));
    }
}
