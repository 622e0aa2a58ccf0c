//! `mmbm frames`' choice of frames for the next tool: the sharpest (`--select`,
//! `--gap`, `--max-blur`) as a COLMAP image list and an ffmpeg `select`
//! expression, and the blurriest (`--worst`) for a deblurrer. The logic is
//! `mmbm::series::select`'s.

use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::io::guard::OutputGuard;
use mmbm::series::frames::FrameMmbm;
use mmbm::series::select::{blurriest, choose, ffmpeg_select, image_list, Choice, FrameName};
use std::path::{Path, PathBuf};

/// Frames chosen for the next tool.
#[derive(Args, Debug)]
pub struct ChoiceArgs {
    /// Keep only the N sharpest frames (least blur_px) at least --gap apart
    /// (in the output table and the lists).
    #[arg(long, value_name = "N")]
    pub select: Option<usize>,
    /// Smallest time between chosen frames' starts, s (with --select or --max-blur).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub gap: f64,
    /// Keep only frames whose blur_px is at most PX (all of them, or the
    /// --select N sharpest of them).
    #[arg(long, value_name = "PX")]
    pub max_blur: Option<f64>,
    /// Write the chosen frames' image names, one per line, in frame order
    /// (COLMAP's --image_list_path).
    #[arg(long, value_name = "FILE")]
    pub image_list: Option<PathBuf>,
    /// Write the chosen frames as an ffmpeg select expression:
    /// ffmpeg -i in.mp4 -vf "select=$(cat FILE)" -vsync 0 out_%04d.png.
    #[arg(long, value_name = "FILE")]
    pub ffmpeg_select: Option<PathBuf>,
    /// The N blurriest frames, for a deblurrer (without N: the blurriest
    /// 10 %, rounded up), written by --worst-list and --worst-ffmpeg-select.
    #[arg(long, value_name = "N", num_args = 0..=1)]
    pub worst: Option<Option<usize>>,
    /// Write the blurriest frames' image names, one per line, in frame order.
    #[arg(long, value_name = "FILE")]
    pub worst_list: Option<PathBuf>,
    /// Write the blurriest frames as an ffmpeg select expression.
    #[arg(long, value_name = "FILE")]
    pub worst_ffmpeg_select: Option<PathBuf>,
    /// Image name of a frame in the lists, printf style: frame number
    /// (0-based row + --frame-start) in its %d (as ffmpeg -i in.mp4 frame_%06d.png names them).
    #[arg(long, value_name = "PATTERN", default_value = "frame_%06d.png")]
    pub frame_name: FrameName,
    /// Number of the video's first frame in the names (ffmpeg's image2
    /// numbers from 1 unless given -start_number).
    #[arg(long, value_name = "K", default_value_t = 1)]
    pub frame_start: u64,
}

impl ChoiceArgs {
    /// Checks the flags together, before any work (the paths: [`Self::guard`]).
    pub fn check(&self) -> Result<()> {
        let chosen = self.select.is_some() || self.max_blur.is_some();
        if !chosen && (self.gap != 0.0 || self.image_list.is_some() || self.ffmpeg_select.is_some())
        {
            return Err(Error::invalid(
                "--gap, --image-list, --ffmpeg-select",
                "choose the frames first: give --select N and/or --max-blur PX",
            ));
        }
        let worst_out = self.worst_list.is_some() || self.worst_ffmpeg_select.is_some();
        if self.worst.is_some() && !worst_out {
            return Err(Error::invalid(
                "--worst",
                "nothing to write the blurriest frames to: give --worst-list FILE and/or --worst-ffmpeg-select FILE",
            ));
        }
        self.choice().check()
    }

    /// A guard over every output: the table's (`out`, `None` for stdout) and
    /// the lists'; the command adds its inputs and folders.
    pub fn guard(&self, out: Option<&Path>) -> OutputGuard {
        OutputGuard::new()
            .output("--out", out)
            .output("--image-list", self.image_list.as_deref())
            .output("--ffmpeg-select", self.ffmpeg_select.as_deref())
            .output("--worst-list", self.worst_list.as_deref())
            .output("--worst-ffmpeg-select", self.worst_ffmpeg_select.as_deref())
    }

    fn choice(&self) -> Choice {
        Choice {
            count: self.select,
            gap_s: self.gap,
            max_blur_px: self.max_blur,
        }
    }

    /// The rows the table keeps: the chosen frames, or all.
    pub fn keep(&self, rows: &[FrameMmbm]) -> Result<Vec<usize>> {
        if self.select.is_none() && self.max_blur.is_none() {
            return Ok((0..rows.len()).collect());
        }
        choose(rows, &self.choice())
    }

    /// Writes the lists asked for (`keep`: the chosen rows) and says on
    /// stderr what they hold. Call inside `all_or_nothing` with the table.
    pub fn write(&self, rows: &[FrameMmbm], keep: &[usize]) -> Result<()> {
        let text = |p: &Path, s: String| {
            mmbm::io::atomic::write_atomic(p, |w| {
                w.write_all(s.as_bytes()).map_err(|e| Error::io(p, e))
            })
        };
        let blur_range = |ks: &[usize]| -> String {
            let b: Vec<f64> = ks.iter().filter_map(|&k| rows[k].blur_px()).collect();
            match (
                b.iter().copied().reduce(f64::min),
                b.iter().copied().reduce(f64::max),
            ) {
                (Some(lo), Some(hi)) => format!("blur {lo:.3}-{hi:.3} px"),
                _ => "none".into(),
            }
        };
        let chosen = self.select.is_some() || self.max_blur.is_some();
        if let Some(p) = &self.image_list {
            text(p, image_list(keep, &self.frame_name, self.frame_start))?;
        }
        if let Some(p) = &self.ffmpeg_select {
            text(p, ffmpeg_select(keep))?;
        }
        if chosen {
            eprintln!("chosen: {} frames ({})", keep.len(), blur_range(keep));
        }
        if self.worst_list.is_some() || self.worst_ffmpeg_select.is_some() {
            let worst = blurriest(rows, self.worst.flatten());
            if let Some(p) = &self.worst_list {
                text(p, image_list(&worst, &self.frame_name, self.frame_start))?;
            }
            if let Some(p) = &self.worst_ffmpeg_select {
                text(p, ffmpeg_select(&worst))?;
            }
            eprintln!("blurriest: {} frames ({})", worst.len(), blur_range(&worst));
        }
        Ok(())
    }
}
