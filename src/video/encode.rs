//! Writing a video: raw RGB frames piped into ffmpeg's stdin, encoded as
//! H.264 in an MP4 (libx264, `yuv420p`, CRF 18) when the ffmpeg build has
//! libx264, else MPEG-4 part 2 (`mpeg4`, `-q:v 2`). The file is written to a
//! temporary name beside the output and renamed when ffmpeg has finished
//! ([`crate::io::atomic::write_atomic_path`]): a failed or interrupted run
//! leaves nothing under the output's name.

use super::{drain, failed, run_tool, spawn_error};
use crate::error::{show_path, Error, Result};
use std::io::Write;
use std::path::Path;
use std::process::{ChildStdin, Command, Stdio};

/// The video codec of the MP4.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Codec {
    /// H.264 through libx264 (`yuv420p`, CRF 18, preset `veryfast`).
    H264,
    /// MPEG-4 part 2 (ffmpeg's own `mpeg4`, `-q:v 2`).
    Mpeg4,
}

impl Codec {
    /// The best codec this ffmpeg can encode: libx264 when its encoder list
    /// (`ffmpeg -encoders`) has it, else mpeg4; an error when it has neither
    /// or ffmpeg is missing.
    pub fn available() -> Result<Codec> {
        let out = run_tool("ffmpeg", &["-hide_banner".as_ref(), "-encoders".as_ref()])?;
        let text = String::from_utf8_lossy(&out);
        let has = |name: &str| {
            text.lines()
                .any(|l| l.split_whitespace().nth(1) == Some(name))
        };
        if has("libx264") {
            Ok(Codec::H264)
        } else if has("mpeg4") {
            Ok(Codec::Mpeg4)
        } else {
            Err(Error::invalid(
                "ffmpeg",
                "has neither the libx264 nor the mpeg4 encoder (ffmpeg -encoders)",
            ))
        }
    }

    /// The codec's name as ffprobe reports it (`h264`, `mpeg4`).
    pub fn name(self) -> &'static str {
        match self {
            Codec::H264 => "h264",
            Codec::Mpeg4 => "mpeg4",
        }
    }

    fn args(self) -> &'static [&'static str] {
        match self {
            Codec::H264 => &["-c:v", "libx264", "-preset", "veryfast", "-crf", "18"],
            Codec::Mpeg4 => &["-c:v", "mpeg4", "-q:v", "2"],
        }
    }
}

/// The frames going into ffmpeg: [`Encoder::push`] one RGB frame at a time.
pub struct Encoder<'a> {
    stdin: ChildStdin,
    frame_bytes: usize,
    frames: usize,
    out: &'a Path,
}

impl Encoder<'_> {
    /// Sends one frame: `rgb` row-major, top row first, 3 bytes per pixel
    /// (R, G, B), exactly width x height pixels.
    pub fn push(&mut self, rgb: &[u8]) -> Result<()> {
        if rgb.len() != self.frame_bytes {
            return Err(Error::invalid(
                "video frame",
                format!(
                    "{} bytes, but a frame of this video has {}",
                    rgb.len(),
                    self.frame_bytes
                ),
            ));
        }
        self.stdin.write_all(rgb).map_err(|e| {
            Error::invalid(
                show_path(self.out),
                format!("ffmpeg stopped taking frames after {}: {e}", self.frames),
            )
        })?;
        self.frames += 1;
        Ok(())
    }

    /// Frames sent so far.
    pub fn frames(&self) -> usize {
        self.frames
    }
}

/// Checks the size and rate of a video to encode: both sides even and >= 2
/// px (`yuv420p` halves the colour planes), a finite rate > 0 frames/s.
pub fn check_format(size: (u32, u32), fps: f64) -> Result<()> {
    let (w, h) = size;
    if w < 2 || h < 2 || w % 2 == 1 || h % 2 == 1 {
        return Err(Error::invalid(
            "video size",
            format!("{w}x{h} px: an MP4 (yuv420p) needs even sides of at least 2 px"),
        ));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(Error::invalid(
            "frame rate",
            format!("{fps} frames/s: must be finite and > 0"),
        ));
    }
    Ok(())
}

/// Encodes the frames `fill` pushes into the MP4 `out` of `size` (px) at
/// `fps` frames/s with `codec`; returns the number of frames. `out` appears
/// only when ffmpeg finished (a temporary file beside it until then).
pub fn encode(
    out: &Path,
    size: (u32, u32),
    fps: f64,
    codec: Codec,
    fill: impl FnOnce(&mut Encoder<'_>) -> Result<()>,
) -> Result<usize> {
    check_format(size, fps)?;
    let (w, h) = size;
    let mut frames = 0;
    crate::io::atomic::write_atomic_path(out, |tmp| {
        let mut child = Command::new("ffmpeg")
            .args(["-hide_banner", "-nostats", "-loglevel", "error", "-y"])
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-s"])
            .arg(format!("{w}x{h}"))
            .arg("-framerate")
            .arg(format!("{fps}"))
            .args(["-i", "pipe:0", "-an"])
            .args(codec.args())
            .args([
                "-pix_fmt",
                "yuv420p",
                "-movflags",
                "+faststart",
                "-f",
                "mp4",
            ])
            .arg(tmp)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| spawn_error("ffmpeg", e))?;
        let errs = drain(child.stderr.take().expect("piped stderr"));
        let mut enc = Encoder {
            stdin: child.stdin.take().expect("piped stdin"),
            frame_bytes: w as usize * h as usize * 3,
            frames: 0,
            out,
        };
        let r = fill(&mut enc);
        frames = enc.frames;
        // Closing stdin ends the stream; on failure ffmpeg is stopped first.
        if r.is_err() {
            let _ = child.kill();
        }
        drop(enc);
        let status = child.wait().map_err(|e| Error::io(out, e))?;
        let stderr = errs.join().unwrap_or_default();
        r?;
        if !status.success() {
            return Err(failed("ffmpeg", &stderr));
        }
        if frames == 0 {
            return Err(Error::invalid(show_path(out), "no frames to encode"));
        }
        Ok(())
    })?;
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_checked() {
        assert!(check_format((640, 480), 30.0).is_ok());
        let e = check_format((641, 480), 30.0).unwrap_err().to_string();
        assert!(e.contains("641x480") && e.contains("even"), "{e}");
        assert!(check_format((0, 480), 30.0).is_err());
        assert!(check_format((640, 480), 0.0).is_err());
        assert!(check_format((640, 480), f64::NAN).is_err());
        assert_eq!(Codec::H264.name(), "h264");
    }
}
