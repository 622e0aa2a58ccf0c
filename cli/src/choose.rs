//! `mmbm frames`' choice of frames for the next tool: the sharpest (`--select`,
//! `--gap`), the best of each window (`--per-window`, `--per-seconds`,
//! `--count`, optionally checked by an image metric of the video,
//! `--image-metric`), every frame under a budget (`--max-blur`), as a COLMAP
//! image list, an ffmpeg `select` expression and extracted images
//! (`--extract`), and the blurriest (`--worst`) for a deblurrer. The logic is
//! `mmbm::series::select`'s.

use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::io::guard::OutputGuard;
use mmbm::series::frames::FrameMmbm;
use mmbm::series::select::video::ImageMetric;
use mmbm::series::select::windows::{best_per_window, Windows};
use mmbm::series::select::{
    blur_and_times, blurriest, choose_series, coverage, ffmpeg_select, image_list, Choice,
    FrameName,
};
use std::path::{Path, PathBuf};

/// The rows chosen and what to say about them.
pub struct Kept {
    /// Rows kept, in order.
    pub rows: Vec<usize>,
    /// Lines for stderr: why fewer were chosen, the coverage.
    pub notes: Vec<String>,
}

/// Frames chosen for the next tool.
#[derive(Args, Debug)]
pub struct ChoiceArgs {
    /// Keep only the N sharpest frames (least blur_px) at least --gap apart
    /// (in the output table and the lists); greedy, so the picks may bunch:
    /// for even coverage use --count, --per-window or --per-seconds.
    #[arg(long, value_name = "N", conflicts_with_all = ["per_window", "per_seconds", "count"])]
    pub select: Option<usize>,
    /// Smallest time between chosen frames' starts, s (with --select or --max-blur alone).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub gap: f64,
    /// The sharpest frame (least blur_px) of every K frames (rows 0..K, K..2K, ...).
    #[arg(long, value_name = "K", conflicts_with_all = ["per_seconds", "count"])]
    pub per_window: Option<usize>,
    /// The sharpest frame of every S seconds of frame starts (from the first frame's).
    #[arg(long, value_name = "S", conflicts_with = "count")]
    pub per_seconds: Option<f64>,
    /// N frames with even coverage: the frames inside the log cut into N
    /// windows of equal frame counts, the sharpest of each (no two picks
    /// more than 2 x ceil(frames/N) - 1 frames apart).
    #[arg(long, value_name = "N")]
    pub count: Option<usize>,
    /// Keep only frames whose blur_px is at most PX (alone: every such
    /// frame; with another mode: its picks among them).
    #[arg(long, value_name = "PX")]
    pub max_blur: Option<f64>,
    /// The hybrid (with --per-window, --per-seconds or --count and --video):
    /// also score the decoded frames with laplacian (variance), tenengrad or
    /// blur-effect (1 - Crete's), and override the gyro's pick of a window
    /// when its image is less than half as sharp as the window's sharpest.
    #[arg(long, value_name = "METRIC", requires = "video")]
    pub image_metric: Option<ImageMetric>,
    /// The video of the frame table (decoded with ffmpeg for --image-metric
    /// and --extract; its frames must be the table's rows).
    #[arg(long, value_name = "FILE")]
    pub video: Option<PathBuf>,
    /// Extract the chosen frames from --video into DIR with ffmpeg, named
    /// as --image-list names them (format from the name's extension).
    #[arg(long, value_name = "DIR", requires = "video")]
    pub extract: Option<PathBuf>,
    /// Write the chosen frames' image names, one per line, in frame order
    /// (COLMAP's --image_list_path).
    #[arg(long, value_name = "FILE")]
    pub image_list: Option<PathBuf>,
    /// Write the chosen frames as an ffmpeg select expression:
    /// `ffmpeg -i in.mp4 -vf "select=$(cat FILE)" -fps_mode passthrough out_%04d.png`.
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
    /// (0-based row + --frame-start) in its %d (as `ffmpeg -i in.mp4 frame_%06d.png` names them).
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
        let chosen = self.chosen();
        if !chosen
            && (self.gap != 0.0
                || self.image_list.is_some()
                || self.ffmpeg_select.is_some()
                || self.extract.is_some())
        {
            return Err(Error::invalid(
                "--gap, --image-list, --ffmpeg-select, --extract",
                "choose the frames first: give --count N, --per-window K, --per-seconds S, \
                 or --select N and/or --max-blur PX",
            ));
        }
        if let Some(w) = self.windows() {
            w.check()?;
            if self.gap != 0.0 {
                return Err(Error::invalid(
                    "--gap",
                    "goes with --select (the windows already space the picks)",
                ));
            }
        } else if self.image_metric.is_some() {
            return Err(Error::invalid(
                "--image-metric",
                "the hybrid chooses per window: give --count, --per-window or --per-seconds",
            ));
        }
        if self.video.is_some() && self.image_metric.is_none() && self.extract.is_none() {
            return Err(Error::invalid(
                "--video",
                "is read for --image-metric or --extract: give one of them",
            ));
        }
        if self.extract.is_some() && self.frame_name.has_folder() {
            return Err(Error::invalid(
                "--frame-name",
                "--extract names the images after it: give a name without a folder",
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

    /// True when frames are chosen (any mode or a budget).
    pub fn chosen(&self) -> bool {
        self.select.is_some() || self.max_blur.is_some() || self.windows().is_some()
    }

    /// The windows of the windowed modes, if one was given.
    pub fn windows(&self) -> Option<Windows> {
        match (self.per_window, self.per_seconds, self.count) {
            (Some(k), _, _) => Some(Windows::Frames(k)),
            (_, Some(s), _) => Some(Windows::Seconds(s)),
            (_, _, Some(n)) => Some(Windows::Count(n)),
            _ => None,
        }
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
            .output_dir("--extract", self.extract.as_deref(), |_| true)
            .input("--video", self.video.as_deref())
    }

    fn choice(&self) -> Choice {
        Choice {
            count: self.select,
            gap_s: self.gap,
            max_blur_px: self.max_blur,
        }
    }

    /// The rows the table keeps (the chosen frames, or all) and what to say
    /// about the choice on stderr. `sharpness`: the image metric per row for
    /// the hybrid.
    pub fn keep(&self, rows: &[FrameMmbm], sharpness: Option<&[f64]>) -> Result<Kept> {
        if !self.chosen() {
            return Ok(Kept {
                rows: (0..rows.len()).collect(),
                notes: Vec::new(),
            });
        }
        let (blur, t) = blur_and_times(rows);
        let mut notes = Vec::new();
        let keep = if let Some(w) = self.windows() {
            let p = best_per_window(&blur, &t, w, self.max_blur, sharpness)?;
            let mut note = format!("{} window(s)", p.windows);
            if p.empty > 0 {
                note += &format!(
                    ", {} without a frame {}",
                    p.empty,
                    if self.max_blur.is_some() {
                        "inside the log within --max-blur"
                    } else {
                        "inside the log"
                    }
                );
            }
            if let Some(m) = self.image_metric {
                note += &format!(
                    ", the gyro's pick overridden by {} in {} (less than half as sharp as the window's best)",
                    m.name(),
                    p.overridden
                );
            }
            notes.push(note);
            p.chosen
        } else {
            let (keep, refused) = choose_series(&blur, &t, &self.choice())?;
            if let Some(n) = self.select.filter(|&n| keep.len() < n) {
                let mut why = Vec::new();
                if refused.by_gap > 0 {
                    why.push(format!(
                        "{} frame(s) lie within --gap {} s of a sharper pick",
                        refused.by_gap, self.gap
                    ));
                }
                if refused.over_budget > 0 {
                    why.push(format!(
                        "{} frame(s) are over --max-blur",
                        refused.over_budget
                    ));
                }
                if refused.without_value > 0 {
                    why.push(format!(
                        "{} frame(s) reach outside the gyro log",
                        refused.without_value
                    ));
                }
                notes.push(format!(
                    "fewer than --select {n}: {}",
                    if why.is_empty() {
                        "no more frames".to_string()
                    } else {
                        why.join("; ")
                    }
                ));
            }
            keep
        };
        if let Some(c) = coverage(&keep, &blur, &t) {
            notes.push(format!(
                "{} adjacent pair(s); largest hole {:.3} s (frames {} to {})",
                c.adjacent_pairs, c.largest_hole_s, c.hole.0, c.hole.1
            ));
        }
        Ok(Kept { rows: keep, notes })
    }

    /// Writes the lists asked for (`keep`: the chosen rows) and says on
    /// stderr what they hold. Call inside `all_or_nothing` with the table.
    pub fn write(&self, rows: &[FrameMmbm], kept: &Kept) -> Result<()> {
        let keep = &kept.rows[..];
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
        let chosen = self.chosen();
        if let Some(p) = &self.image_list {
            text(p, image_list(keep, &self.frame_name, self.frame_start))?;
        }
        if let Some(p) = &self.ffmpeg_select {
            text(p, ffmpeg_select(keep))?;
        }
        if chosen {
            eprintln!("chosen: {} frames ({})", keep.len(), blur_range(keep));
            for n in &kept.notes {
                eprintln!("  {n}");
            }
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
