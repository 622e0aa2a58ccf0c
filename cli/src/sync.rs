//! `mmbm sync`: the gyro-to-video clock offset from the video itself.

use super::args::CameraArgs;
use super::series::GyroArgs;
use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::limits::SYNC_MAX_SEARCH_S;
use mmbm::sync::{sync_decoding, SyncFile, SyncOptions};
use std::path::PathBuf;

/// The gyro-to-video clock offset (and rolling-shutter readout) from the video's own motion.
#[derive(Args, Debug)]
#[command(
    after_help = "Decodes the video with FFmpeg (ffprobe and ffmpeg on PATH), measures the image
motion between consecutive frames, and finds the offset at which the gyro's rotation, through the
camera's intrinsics, explains it best (a coarse search over --search s around --time-offset, then a
parabola to a fraction of a millisecond), for each readout of a small rolling-shutter scan.

Output (TOML): offset_s (video time = gyro time + offset_s: the value frames --time-offset takes;
frames --sync FILE reads it), readout_s, confidence (0..1: the share of the motion the gyro explains
x how much lower the cost is than at any offset 0.1 s away), the spans and diagnostics.

Examples:
  mmbm sync --video clip.mp4 --gyro imu.csv --camera camera.toml --exposure 0.01 --out sync.toml
  mmbm frames --gyro imu.csv --frames probe.csv --exposure 0.01 --camera camera.toml --sync sync.toml"
)]
pub struct SyncArgs {
    /// The video (any file ffmpeg reads; decoded as stored, without its rotation tag).
    #[arg(long, value_name = "FILE")]
    pub video: PathBuf,
    /// Gyro log (CSV, Gyroflow .gcsv, ROS 2 .mcap, or a phone's IMU rows), camera frame.
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// Exposure of every frame, s (default 0: the offset then carries up to half the
    /// real exposure as an error).
    #[arg(long, value_name = "S")]
    pub exposure: Option<f64>,
    /// Half width of the offset search around --time-offset, s (at most 60).
    #[arg(long, value_name = "S", default_value_t = 2.0)]
    pub search: f64,
    /// Frames to decode of a long clip, about: a clip of more than twice as many frames
    /// is decoded in windows of consecutive frames from keyframes spread over it (most of
    /// sync's time is decoding); 0 decodes every frame.
    #[arg(long, value_name = "N", default_value_t = mmbm::sync::plan::DEFAULT_DECODE_FRAMES)]
    pub decode_frames: usize,
    /// Output TOML (written whole or not at all).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn run(a: SyncArgs) -> Result<()> {
    let exposure_s = match a.exposure {
        Some(e) if !(0.0..=1.0).contains(&e) => {
            return Err(Error::invalid(
                "--exposure",
                format!("{e}: expected a finite exposure of 0 to 1 s"),
            ))
        }
        Some(e) => e,
        None => {
            eprintln!(
                "warning: no --exposure: each frame's time is taken at its exposure's start; the \
                 offset then carries up to half the real exposure as an error"
            );
            0.0
        }
    };
    if !(a.search.is_finite() && a.search > 0.0 && a.search <= SYNC_MAX_SEARCH_S) {
        return Err(Error::invalid(
            "--search",
            format!(
                "{}: expected a half width of more than 0 and at most {SYNC_MAX_SEARCH_S} s",
                a.search
            ),
        ));
    }
    mmbm::io::guard::OutputGuard::new()
        .output("--out", Some(&a.out))
        .input("--video", Some(&a.video))
        .input("--gyro", Some(&a.gyro))
        .input("--camera", a.camera.camera.as_deref())
        .check()?;
    if a.camera.camera.is_none() && a.camera.focal.is_none() {
        eprintln!(
            "warning: no --camera: the thesis camera's field of view is assumed (focal_scale in \
             the output says how far the measured motion is from the predicted)"
        );
    }
    let camera = a.camera.camera()?;
    let mut telemetry = a.gyro_opts.telemetry()?;
    let centre_s = telemetry.gyro.time_offset;
    telemetry.gyro.time_offset = 0.0;
    let log = mmbm::telemetry::read_gyro(&a.gyro, &telemetry)?;
    let opts = SyncOptions {
        exposure_s,
        centre_s,
        search_s: a.search,
    };
    let started = std::time::Instant::now();
    let out = sync_decoding(&a.video, &log, &camera, &opts, a.decode_frames)?;
    if let Some(shutter) = &out.log_shutter {
        super::args::print_log_readout(shutter, &a.gyro);
    }
    let secs = started.elapsed().as_secs_f64();
    let file = SyncFile::new(&out, &a.video, &a.gyro, exposure_s, a.search);
    let text = file.to_toml()?;
    mmbm::io::atomic::write_atomic(&a.out, |w| {
        w.write_all(text.as_bytes())
            .map_err(|e| Error::io(&a.out, e))
    })?;
    println!(
        "sync: offset {:.5} s (--time-offset), readout {:.4} s ({}), confidence {:.2} (explained {:.3}, focal scale {:.2}); {} frames ({}) in {secs:.2} s ({:.0} frames/s)",
        file.offset_s,
        file.readout_s,
        if file.readout_distinguishable { "distinguishable" } else { "not distinguishable" },
        file.confidence,
        file.explained,
        file.focal_scale,
        file.frames,
        if out.windows > 1 { format!("{} windows", out.windows) } else { "the whole clip".into() },
        file.frames as f64 / secs.max(1e-9),
    );
    if file.confidence < 0.5 {
        eprintln!(
            "warning: low confidence {:.2}: too little motion, texture or agreement with the gyro \
             to tell the offset (rival offset {:.3} s scores {:.3} against {:.3})",
            file.confidence,
            file.rival_offset_s,
            file.rival_cost,
            1.0 - file.explained
        );
    }
    Ok(())
}

/// `frames --sync FILE`: the sync file, with a warning when its confidence is low.
pub fn read_for_frames(path: &std::path::Path) -> Result<SyncFile> {
    let f = mmbm::sync::read_sync_file(path)?;
    eprintln!(
        "sync from {}: --time-offset {} s (confidence {:.2})",
        path.display(),
        f.offset_s,
        f.confidence
    );
    if f.confidence < 0.5 {
        eprintln!(
            "warning: {}: confidence {:.2} is low; check the offset",
            path.display(),
            f.confidence
        );
    }
    Ok(f)
}

/// The camera with the sync file's readout when nothing else gave one
/// (`--rolling-readout`, the camera file or the log); else a warning when
/// they differ by over 1 ms (the offset was found with the file's readout).
pub fn synced_readout(
    mut camera: mmbm::Camera,
    s: &SyncFile,
    path: &std::path::Path,
    flag: bool,
) -> mmbm::Camera {
    let r = camera.shutter.readout_s;
    if !flag && r == 0.0 {
        if s.readout_s > 0.0 {
            camera.shutter.readout_s = s.readout_s;
            eprintln!(
                "rolling shutter from {}: readout {} s",
                path.display(),
                s.readout_s
            );
        }
    } else if (r - s.readout_s).abs() > 1e-3 {
        eprintln!(
            "warning: readout {r} s, but {} found its offset with readout {} s: the offset may be \
             off by about half their difference",
            path.display(),
            s.readout_s
        );
    }
    camera
}
