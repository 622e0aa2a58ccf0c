//! The video through FFmpeg run as a subprocess (the tool a user with a
//! video already has): one place for the plumbing that `mmbm frames`
//! (scoring and extracting frames), `mmbm sync` (decoding) and `mmbm clip`
//! (encoding) share.
//!
//! - [`decode`]: `ffprobe` for a stream's size, rate, span and frame count
//!   ([`decode::probe`], [`probe_size`], [`count_frames`]), and raw grey or
//!   RGB frames on a pipe, one at a time, bounded ([`decode::decode_raw`]).
//! - [`encode`]: raw RGB frames piped into ffmpeg's stdin, written as an
//!   H.264 MP4 (libx264 when the build has it, else MPEG-4 part 2) to a
//!   temporary name and renamed when complete ([`encode::Encoder`]).
//!
//! A missing `ffmpeg`/`ffprobe` is one error naming the tool with how to
//! install it ([`INSTALL_FFMPEG`]); a failing one is an error with the last
//! line of its stderr.

pub mod decode;
pub mod encode;

pub use decode::{count_frames, probe, probe_size, VideoInfo};
pub use encode::{Codec, Encoder};

use crate::error::{Error, Result};
use std::io::Read;
use std::process::{Command, Stdio};

/// How to get ffmpeg, for the error when it is missing.
pub const INSTALL_FFMPEG: &str = "install ffmpeg (it brings ffprobe): Debian/Ubuntu \
     'apt install ffmpeg', Fedora 'dnf install ffmpeg', macOS 'brew install ffmpeg', Windows \
     'winget install ffmpeg', or https://ffmpeg.org/download.html; then put it on PATH";

/// The error for a tool (`ffmpeg`, `ffprobe`) that could not be started:
/// not on PATH (with [`INSTALL_FFMPEG`]) or another reason.
pub fn spawn_error(tool: &str, e: std::io::Error) -> Error {
    if e.kind() == std::io::ErrorKind::NotFound {
        Error::invalid(tool, format!("not found on PATH: {INSTALL_FFMPEG}"))
    } else {
        Error::invalid(tool, format!("could not be run: {e}"))
    }
}

/// The error for a tool that exited with failure: its stderr's last
/// meaningful line.
pub fn failed(tool: &str, stderr: &[u8]) -> Error {
    let text = String::from_utf8_lossy(stderr);
    Error::invalid(tool, format!("failed: {}", tail_of(&text, 1)))
}

/// The last `n` non-empty lines of a tool's stderr, joined by " / ".
pub fn tail_of(text: &str, n: usize) -> String {
    let kept: Vec<&str> = text
        .lines()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect();
    kept[kept.len().saturating_sub(n)..].join(" / ")
}

/// `tool` (ffmpeg or ffprobe) run with `args`: its stdout, or an error
/// naming the tool (missing: how to install it; failed: its stderr's last
/// line).
pub fn run_tool(tool: &str, args: &[&std::ffi::OsStr]) -> Result<Vec<u8>> {
    let out = Command::new(tool)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| spawn_error(tool, e))?;
    if !out.status.success() {
        return Err(failed(tool, &out.stderr));
    }
    Ok(out.stdout)
}

/// Reads one whole raw frame of ffmpeg's output into `buf`: false at a
/// clean end of stream before the frame's first byte, an error when the
/// stream ends inside it.
pub fn read_frame(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<bool> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) if got == 0 => return Ok(false),
            Ok(0) => {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::UnexpectedEof,
                    "ffmpeg's output ended inside a frame",
                ))
            }
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(true)
}

/// Drains a child's stderr on its own thread (so that a chatty tool can
/// never block on a full pipe), keeping at most its last 32-64 KiB.
pub(crate) fn drain(mut stderr: impl Read + Send + 'static) -> std::thread::JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let (mut v, mut chunk) = (Vec::new(), [0u8; 8192]);
        while let Ok(n @ 1..) = stderr.read(&mut chunk) {
            v.extend_from_slice(&chunk[..n]);
            if v.len() > 1 << 16 {
                v.drain(..v.len() - (1 << 15));
            }
        }
        v
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_read_whole_or_refused() {
        let mut buf = [0u8; 4];
        let mut r: &[u8] = &[1, 2, 3, 4, 5, 6];
        assert!(read_frame(&mut r, &mut buf).unwrap());
        assert_eq!(buf, [1, 2, 3, 4]);
        assert!(read_frame(&mut r, &mut buf).is_err());
        let mut empty: &[u8] = &[];
        assert!(!read_frame(&mut empty, &mut buf).unwrap());
        assert_eq!(tail_of("a\n\n b \n\n", 1), "b");
        assert_eq!(tail_of("a\nb\nc\n", 2), "b / c");
        let e = spawn_error("ffmpeg", std::io::ErrorKind::NotFound.into()).to_string();
        assert!(
            e.contains("not found on PATH") && e.contains("apt install ffmpeg"),
            "{e}"
        );
    }
}
