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
use crate::video::decode::{decode_raw, Pixels, RawDecode};
use crate::video::run_tool;
use image::GrayImage;
use std::path::Path;

pub use crate::video::{count_frames, probe_size, read_frame, INSTALL_FFMPEG};

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
    let o = RawDecode {
        size: (sw, sh),
        pixels: Pixels::Gray,
        as_stored: false,
        times: false,
        // One frame more than the table is the count mismatch below.
        max_frames: usize::MAX,
        who: "frames",
    };
    let mut scores = Vec::with_capacity(frames.min(1 << 20));
    decode_raw(video, &o, |k, px| {
        if k == frames {
            return Err(count_mismatch(video, None, frames));
        }
        let img = GrayImage::from_raw(sw, sh, px.to_vec()).expect("sized");
        scores.push(metric.sharpness(&img)?);
        Ok(())
    })?;
    if scores.len() != frames {
        return Err(count_mismatch(video, Some(scores.len()), frames));
    }
    Ok(scores)
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
