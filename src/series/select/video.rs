//! The video itself, through ffmpeg (a subprocess: the tool this user
//! already has): each frame's image sharpness for the hybrid choice
//! ([`score_frames`]), and the chosen frames extracted as images
//! ([`extract`]).
//!
//! Frames are numbered as ffmpeg decodes them (`n`, 0-based, every decoded
//! frame passed through: `-fps_mode passthrough`), which is the frame
//! table's row; a video with a different number of frames than the table is
//! refused, naming both counts.

use super::names::{ffmpeg_select, FrameName};
use crate::error::{Error, Result};
use crate::limits::{MAX_SELECT_EXPR_BYTES, SCORE_MAX_WIDTH};
use image::GrayImage;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};

/// How to get ffmpeg, for the error when it is missing.
pub const INSTALL_FFMPEG: &str = "install ffmpeg (it brings ffprobe): Debian/Ubuntu \
     'apt install ffmpeg', Fedora 'dnf install ffmpeg', macOS 'brew install ffmpeg', Windows \
     'winget install ffmpeg', or https://ffmpeg.org/download.html; then put it on PATH";

/// An image metric of the decoded frames, as a sharpness (higher is sharper).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageMetric {
    /// Variance of the Laplacian ([`crate::assess::laplacian_var`]).
    Laplacian,
    /// Tenengrad ([`crate::assess::tenengrad`]).
    Tenengrad,
    /// 1 - Crete's blur effect ([`crate::assess::blur_effect`]: 0 sharp .. 1 blurred).
    BlurEffect,
}

impl std::str::FromStr for ImageMetric {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "laplacian" => Ok(Self::Laplacian),
            "tenengrad" => Ok(Self::Tenengrad),
            "blur-effect" => Ok(Self::BlurEffect),
            _ => Err(Error::invalid(
                "--image-metric",
                format!("'{s}': expected laplacian, tenengrad or blur-effect"),
            )),
        }
    }
}

impl ImageMetric {
    /// The name the CLI takes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Laplacian => "laplacian",
            Self::Tenengrad => "tenengrad",
            Self::BlurEffect => "blur-effect",
        }
    }

    /// The sharpness of a grey image (higher is sharper).
    pub fn sharpness(self, img: &GrayImage) -> Result<f64> {
        match self {
            Self::Laplacian => crate::assess::laplacian_var(img),
            Self::Tenengrad => crate::assess::tenengrad(img),
            Self::BlurEffect => Ok(1.0 - crate::assess::blur_effect(img)?),
        }
    }
}

/// `tool` (ffmpeg or ffprobe) run with `args`: its stdout, or an error
/// naming the tool (missing: how to install it; failed: its stderr's last
/// line).
fn run_tool(tool: &str, args: &[&std::ffi::OsStr]) -> Result<Vec<u8>> {
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

fn spawn_error(tool: &str, e: std::io::Error) -> Error {
    if e.kind() == std::io::ErrorKind::NotFound {
        Error::invalid(tool, format!("not found on PATH: {INSTALL_FFMPEG}"))
    } else {
        Error::invalid(tool, format!("could not be run: {e}"))
    }
}

fn failed(tool: &str, stderr: &[u8]) -> Error {
    let text = String::from_utf8_lossy(stderr);
    let last = text
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("");
    Error::invalid(tool, format!("failed: {}", last.trim()))
}

/// The video's first video stream's width and height, px (ffprobe).
pub fn probe_size(video: &Path) -> Result<(u32, u32)> {
    crate::io::input::open_file(video)?;
    let out = run_tool(
        "ffprobe",
        &[
            "-v".as_ref(),
            "error".as_ref(),
            "-select_streams".as_ref(),
            "v:0".as_ref(),
            "-show_entries".as_ref(),
            "stream=width,height".as_ref(),
            "-of".as_ref(),
            "csv=p=0".as_ref(),
            video.as_os_str(),
        ],
    )?;
    let text = String::from_utf8_lossy(&out);
    let bad = || {
        Error::invalid(
            "--video",
            format!(
                "{}: no video stream ffprobe can size ({})",
                video.display(),
                text.trim()
            ),
        )
    };
    let line = text.lines().next().ok_or_else(bad)?;
    let (w, h) = line
        .trim()
        .trim_end_matches(',')
        .split_once(',')
        .ok_or_else(bad)?;
    match (w.trim().parse::<u32>(), h.trim().parse::<u32>()) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(bad()),
    }
}

/// The size frames are scored at: `(w, h)` scaled to at most
/// [`SCORE_MAX_WIDTH`] wide, the aspect kept, both even and >= 2.
pub fn score_size(w: u32, h: u32) -> (u32, u32) {
    let sw = w.min(SCORE_MAX_WIDTH);
    let sh = ((h as u64 * sw as u64) / w as u64) as u32;
    ((sw / 2 * 2).max(2), (sh / 2 * 2).max(2))
}

/// Every frame of `video` decoded by ffmpeg (grey, scaled to
/// [`score_size`], one frame in memory at a time) and scored by `metric`;
/// `frames`: the frame table's row count, which the video must match.
pub fn score_frames(video: &Path, metric: ImageMetric, frames: usize) -> Result<Vec<f64>> {
    let (w, h) = probe_size(video)?;
    let (sw, sh) = score_size(w, h);
    let scale = format!("scale={sw}:{sh}:flags=area,format=gray");
    let mut child = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-i"])
        .arg(video)
        .args(["-map", "0:v:0", "-fps_mode", "passthrough", "-vf", &scale])
        .args(["-f", "rawvideo", "-pix_fmt", "gray", "pipe:1"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| spawn_error("ffmpeg", e))?;
    let mut stdout = child.stdout.take().expect("piped");
    let mut stderr = child.stderr.take().expect("piped");
    // stderr drained aside, so that a chatty ffmpeg cannot block.
    let errs = std::thread::spawn(move || {
        // Read to the end (ffmpeg must never block on it), keep the tail.
        let (mut v, mut chunk) = (Vec::new(), [0u8; 8192]);
        while let Ok(n @ 1..) = stderr.read(&mut chunk) {
            v.extend_from_slice(&chunk[..n]);
            if v.len() > 1 << 16 {
                v.drain(..v.len() - (1 << 15));
            }
        }
        v
    });
    let mut buf = vec![0u8; sw as usize * sh as usize];
    let mut scores = Vec::with_capacity(frames.min(1 << 20));
    let result = (|| -> Result<()> {
        loop {
            crate::cancel::check()?;
            match read_frame(&mut stdout, &mut buf) {
                Ok(false) => return Ok(()),
                Ok(true) => {}
                Err(e) => return Err(Error::io(video, e)),
            }
            if scores.len() == frames {
                return Err(count_mismatch(video, None, frames));
            }
            let img = GrayImage::from_raw(sw, sh, std::mem::take(&mut buf)).expect("sized");
            scores.push(metric.sharpness(&img)?);
            buf = img.into_raw();
        }
    })();
    if result.is_err() {
        let _ = child.kill();
    }
    drop(stdout);
    let status = child.wait().map_err(|e| spawn_error("ffmpeg", e))?;
    let stderr = errs.join().unwrap_or_default();
    result?;
    if !status.success() {
        return Err(failed("ffmpeg", &stderr));
    }
    if scores.len() != frames {
        return Err(count_mismatch(video, Some(scores.len()), frames));
    }
    Ok(scores)
}

/// Reads one whole raw frame of ffmpeg's output into `buf`: false at a
/// clean end of stream before the frame's first byte, an error when the
/// stream ends inside it (also `mmbm sync`'s decoder).
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

fn count_mismatch(video: &Path, got: Option<usize>, frames: usize) -> Error {
    let got = got.map_or(format!("more than {frames}"), |n| n.to_string());
    Error::invalid(
        "--video",
        format!(
            "{}: the video has {got} frames, the frame table (--frames) has {frames} rows; \
             frame numbers would not match (is it the same video?)",
            video.display()
        ),
    )
}

/// The number of frames (packets) of the video's first video stream, as
/// ffprobe counts them (demuxed, not decoded).
pub fn count_frames(video: &Path) -> Result<usize> {
    crate::io::input::open_file(video)?;
    let out = run_tool(
        "ffprobe",
        &[
            "-v".as_ref(),
            "error".as_ref(),
            "-select_streams".as_ref(),
            "v:0".as_ref(),
            "-count_packets".as_ref(),
            "-show_entries".as_ref(),
            "stream=nb_read_packets".as_ref(),
            "-of".as_ref(),
            "csv=p=0".as_ref(),
            video.as_os_str(),
        ],
    )?;
    let text = String::from_utf8_lossy(&out);
    text.trim()
        .trim_end_matches(',')
        .parse::<usize>()
        .map_err(|_| {
            Error::invalid(
                "--video",
                format!(
                    "{}: ffprobe counts no video frames ({})",
                    video.display(),
                    text.trim()
                ),
            )
        })
}

/// Extracts the frames `chosen` (rows, in order) of `video` into the
/// folder `into` (which must exist and be empty of those names), named
/// `name` with number `row + start`, as the image list names them; the
/// format follows the name's extension (ffmpeg's image2 muxer). `frames`:
/// the frame table's row count, which the video's frame count must match.
pub fn extract(
    video: &Path,
    chosen: &[usize],
    name: &FrameName,
    start: u64,
    into: &Path,
    frames: usize,
) -> Result<Vec<String>> {
    let n = count_frames(video)?;
    if n != frames {
        return Err(count_mismatch(video, Some(n), frames));
    }
    let ext = name.extension().ok_or_else(|| {
        Error::invalid(
            "--extract",
            "the --frame-name has no extension to say the image format (e.g. frame_%06d.png)",
        )
    })?;
    let expr = ffmpeg_select(chosen);
    let expr = expr.trim_end();
    if expr.len() > MAX_SELECT_EXPR_BYTES {
        return Err(Error::invalid(
            "--extract",
            format!(
                "the select expression of {} frames is {} bytes, over the {MAX_SELECT_EXPR_BYTES} \
                 bytes a command line takes; extract with fewer frames or with --ffmpeg-select",
                chosen.len(),
                expr.len()
            ),
        ));
    }
    if chosen.is_empty() {
        return Ok(Vec::new());
    }
    // ffmpeg writes into a folder of its own, so that its names cannot meet the final ones.
    let raw = into.join(".ffmpeg");
    std::fs::create_dir(&raw).map_err(|e| Error::io(&raw, e))?;
    let pattern = raw.join(format!("x%08d.{ext}"));
    let vf = format!("select={expr}");
    run_tool(
        "ffmpeg",
        &[
            "-v".as_ref(),
            "error".as_ref(),
            "-nostdin".as_ref(),
            "-i".as_ref(),
            video.as_os_str(),
            "-map".as_ref(),
            "0:v:0".as_ref(),
            "-vf".as_ref(),
            vf.as_ref(),
            "-fps_mode".as_ref(),
            "passthrough".as_ref(),
            "-start_number".as_ref(),
            "0".as_ref(),
            pattern.as_os_str(),
        ],
    )?;
    let mut names = Vec::with_capacity(chosen.len());
    for (i, &k) in chosen.iter().enumerate() {
        let from = raw.join(format!("x{i:08}.{ext}"));
        if !from.is_file() {
            return Err(Error::invalid(
                "--video",
                format!(
                    "{}: ffmpeg wrote {i} of the {} chosen frames (frame {k} is past the video's end?)",
                    video.display(),
                    chosen.len()
                ),
            ));
        }
        let to_name = name.name((k as u64).saturating_add(start));
        let to = into.join(&to_name);
        std::fs::rename(&from, &to).map_err(|e| Error::io(&to, e))?;
        names.push(to_name);
    }
    std::fs::remove_dir_all(&raw).map_err(|e| Error::io(&raw, e))?;
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metric_names_and_sizes() {
        assert_eq!(
            "tenengrad".parse::<ImageMetric>().unwrap(),
            ImageMetric::Tenengrad
        );
        let e = "sobel".parse::<ImageMetric>().unwrap_err().to_string();
        assert!(
            e.contains("--image-metric") && e.contains("laplacian"),
            "{e}"
        );
        assert_eq!(score_size(1920, 1080), (640, 360));
        assert_eq!(score_size(320, 241), (320, 240));
        assert_eq!(score_size(1, 1), (2, 2));
    }
}
