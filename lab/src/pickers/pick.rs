//! The pickers, each on the same clip and the same windows: the gyro alone
//! (`mmbm frames`' best per window), the variance of the Laplacian with a
//! global threshold and best per window, Tenengrad best per window,
//! ffmpeg's `blurdetect` best per window, the hybrid (gyro + Laplacian, as
//! `frames --image-metric laplacian`) and the oracle (least true blur).
//!
//! Per frame measures first ([`Measures`], each timed per frame), then the
//! choices ([`picks`]), which are cheap.

use super::clips::Rendered;
use mmbm::error::{Error, Result};
use mmbm::io::frames::VideoFrame;
use mmbm::metric::Method;
use mmbm::model::log::ImuLog;
use mmbm::series::job::{FramesConfig, FramesJob};
use mmbm::series::select::video::{score_frames, ImageMetric};
use mmbm::series::select::windows::{best_per_window, ranges, Windows};
use std::path::Path;
use std::time::Instant;

/// The pickers, in the table's order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Picker {
    /// The gyro alone, best per window.
    Gyro,
    /// Laplacian variance, every frame over a global threshold.
    LaplacianThreshold,
    /// Laplacian variance, best per window.
    Laplacian,
    /// Tenengrad, best per window.
    Tenengrad,
    /// ffmpeg's `blurdetect`, best (least) per window.
    BlurDetect,
    /// The gyro checked by the Laplacian, best per window.
    Hybrid,
    /// The least true blur per window.
    Oracle,
}

impl Picker {
    /// Every picker, in the table's order.
    pub const ALL: [Picker; 7] = [
        Picker::Gyro,
        Picker::LaplacianThreshold,
        Picker::Laplacian,
        Picker::Tenengrad,
        Picker::BlurDetect,
        Picker::Hybrid,
        Picker::Oracle,
    ];

    /// Its name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            Picker::Gyro => "gyro (mmbm frames)",
            Picker::LaplacianThreshold => "Laplacian, global threshold",
            Picker::Laplacian => "Laplacian, best per window",
            Picker::Tenengrad => "Tenengrad, best per window",
            Picker::BlurDetect => "ffmpeg blurdetect, best per window",
            Picker::Hybrid => "hybrid (gyro + Laplacian)",
            Picker::Oracle => "oracle (true blur)",
        }
    }

    /// Whether it reads only the images.
    pub fn image_only(self) -> bool {
        matches!(
            self,
            Picker::LaplacianThreshold | Picker::Laplacian | Picker::Tenengrad | Picker::BlurDetect
        )
    }
}

/// Per-frame measures of one clip, and what each cost per frame (ms).
#[derive(Debug, Clone, Default)]
pub struct Measures {
    /// Frame `k` shown at `k / fps`, s.
    pub t: Vec<f64>,
    /// The gyro's predicted blur at the true offset, px.
    pub gyro: Vec<Option<f64>>,
    /// Laplacian variance of the decoded frames (higher is sharper).
    pub laplacian: Vec<f64>,
    /// Tenengrad of the decoded frames (higher is sharper).
    pub tenengrad: Vec<f64>,
    /// ffmpeg's `lavfi.blur` (higher is blurrier).
    pub blurdetect: Vec<f64>,
    /// Gyro file to image list, ms per frame: reading the log, the
    /// predicted blur, the choice and the list.
    pub gyro_ms: f64,
    /// Decoding and scoring, ms per frame.
    pub laplacian_ms: f64,
    /// Decoding and scoring, ms per frame.
    pub tenengrad_ms: f64,
    /// ffmpeg's decoding and `blurdetect`, ms per frame.
    pub blurdetect_ms: f64,
}

/// The gyro's predicted blur of every frame (px, `None` outside the log),
/// its frames placed on the gyro's clock with `offset_s` (video time =
/// gyro time + offset), the clip's exposure and the camera's readout.
pub fn gyro_blur(log: &ImuLog, r: &Rendered, offset_s: f64) -> Result<Vec<Option<f64>>> {
    let frames: Vec<VideoFrame> = (0..r.frames())
        .map(|k| VideoFrame {
            t_start: k as f64 / r.fps - offset_s,
            exposure_s: r.exposure_s,
            readout_s: Some(r.camera.shutter.readout_s),
        })
        .collect();
    let job = FramesJob::new(
        FramesConfig {
            camera: r.camera,
            plane: None,
            method: Method::default(),
            use_velocity: false,
        },
        None,
    )?;
    let (mmbm, _) = job.mmbm(log.samples(), &frames)?;
    Ok(mmbm.iter().map(|f| f.blur_px()).collect())
}

/// ffmpeg's `blurdetect` of every frame (`lavfi.blur`, higher is blurrier),
/// through its `metadata` filter into `scratch` (a file it overwrites).
pub fn blurdetect(video: &Path, frames: usize, scratch: &Path) -> Result<Vec<f64>> {
    let vf = format!("blurdetect,metadata=mode=print:file={}", scratch.display());
    mmbm::video::run_tool(
        "ffmpeg",
        &[
            "-v".as_ref(),
            "error".as_ref(),
            "-nostdin".as_ref(),
            "-i".as_ref(),
            video.as_os_str(),
            "-vf".as_ref(),
            vf.as_ref(),
            "-f".as_ref(),
            "null".as_ref(),
            "-".as_ref(),
        ],
    )?;
    let text = std::fs::read_to_string(scratch).map_err(|e| Error::io(scratch, e))?;
    let out: Vec<f64> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("lavfi.blur="))
        .map(|v| v.trim().parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    if out.len() != frames {
        return Err(Error::invalid(
            scratch.display().to_string(),
            format!("blurdetect gave {} values for {frames} frames", out.len()),
        ));
    }
    Ok(out)
}

/// Every per-frame measure of a clip, each timed. `dir`: a folder for the
/// gyro file and ffmpeg's metadata.
pub fn measure(r: &Rendered, dir: &Path, name: &str, window: usize) -> Result<Measures> {
    let n = r.frames();
    let per = |t: Instant| t.elapsed().as_secs_f64() * 1e3 / n as f64;
    let gyro_file = dir.join(format!("{name}-gyro.csv"));
    mmbm::sim::write_log(&gyro_file, r.gyro.samples())?;
    let t0 = Instant::now();
    let log = mmbm::telemetry::read_gyro(&gyro_file, &Default::default())?;
    let gyro = gyro_blur(&log, r, r.offset_s)?;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / r.fps).collect();
    let p = best_per_window(&gyro, &t, Windows::Frames(window), None, None)?;
    let name_of: mmbm::series::select::FrameName = "frame_%06d.png".parse()?;
    let list = mmbm::series::select::image_list(&p.chosen, &name_of, 1);
    std::hint::black_box(list);
    let gyro_ms = per(t0);
    let t0 = Instant::now();
    let laplacian = score_frames(&r.video, ImageMetric::Laplacian, n)?;
    let laplacian_ms = per(t0);
    let t0 = Instant::now();
    let tenengrad = score_frames(&r.video, ImageMetric::Tenengrad, n)?;
    let tenengrad_ms = per(t0);
    let t0 = Instant::now();
    let blurdetect = blurdetect(&r.video, n, &dir.join(format!("{name}-blurdetect.txt")))?;
    let blurdetect_ms = per(t0);
    Ok(Measures {
        t,
        gyro,
        laplacian,
        tenengrad,
        blurdetect,
        gyro_ms,
        laplacian_ms,
        tenengrad_ms,
        blurdetect_ms,
    })
}

/// The row of each window with the highest `score` (ties: the earlier).
pub fn best_by(score: &[f64], t: &[f64], window: usize) -> Result<Vec<usize>> {
    let all = vec![Some(0.0); score.len()];
    let w = ranges(&all, t, Windows::Frames(window))?;
    Ok(w.into_iter()
        .filter_map(|r| {
            r.filter(|&k| score[k].is_finite())
                .min_by(|&a, &b| score[b].total_cmp(&score[a]).then(a.cmp(&b)))
        })
        .collect())
}

/// What picker `p` picks (rows, in order) from the measures `m`, the true
/// blur `truth` (px; the oracle's), windows of `window` frames, and the
/// Laplacian's global threshold `lap_threshold`.
pub fn picks(
    p: Picker,
    m: &Measures,
    truth: &[f64],
    window: usize,
    lap_threshold: f64,
) -> Result<Vec<usize>> {
    let w = Windows::Frames(window);
    let neg = |v: &[f64]| v.iter().map(|x| -x).collect::<Vec<f64>>();
    Ok(match p {
        Picker::Gyro => best_per_window(&m.gyro, &m.t, w, None, None)?.chosen,
        Picker::LaplacianThreshold => (0..m.laplacian.len())
            .filter(|&k| m.laplacian[k] >= lap_threshold)
            .collect(),
        Picker::Laplacian => best_by(&m.laplacian, &m.t, window)?,
        Picker::Tenengrad => best_by(&m.tenengrad, &m.t, window)?,
        Picker::BlurDetect => best_by(&neg(&m.blurdetect), &m.t, window)?,
        Picker::Hybrid => best_per_window(&m.gyro, &m.t, w, None, Some(&m.laplacian))?.chosen,
        Picker::Oracle => {
            let b: Vec<Option<f64>> = truth.iter().map(|&x| Some(x)).collect();
            best_per_window(&b, &m.t, w, None, None)?.chosen
        }
    })
}

/// Time per frame of picker `p`, ms (the oracle: none).
pub fn ms_per_frame(p: Picker, m: &Measures) -> Option<f64> {
    match p {
        Picker::Gyro => Some(m.gyro_ms),
        Picker::LaplacianThreshold | Picker::Laplacian => Some(m.laplacian_ms),
        Picker::Tenengrad => Some(m.tenengrad_ms),
        Picker::BlurDetect => Some(m.blurdetect_ms),
        Picker::Hybrid => Some(m.gyro_ms + m.laplacian_ms),
        Picker::Oracle => None,
    }
}
