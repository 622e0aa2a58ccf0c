//! `mmbm frames`: the exposure MMBM of every frame of a real video, rolling shutter included.

use super::args::{CameraArgs, SceneArgs};
use super::series::GyroArgs;
use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::io::frames::read_frame_table;
use mmbm::series::job::{FramesConfig, FramesJob};
use mmbm::series::maps::write::{is_map_name, parse_channels, stage_maps, MapsFormat, MapsOutput};
use mmbm::series::select::clock::{check_clock, Spans};
use mmbm::AnyMethod;
use std::io::Write;
use std::path::PathBuf;

/// Exposure MMBM of every video frame (each line over its own rolling-shutter window).
#[derive(Args, Debug)]
#[command(
    after_help = "Output columns: frame (0-based row of FRAMES), t_start (s), exposure_mmbm_mm_s
(the sensor mean of each point's speed over its own line's window), blur_px (exposure MMBM x
exposure / pitch), start_mmbm_mm_s (instantaneous MMBM at t_start), exposure_s, readout_s.
A frame whose window leaves the log gets empty values (one warning for all).

Examples:
  mmbm frames --gyro ../shared/data/running_phone/gyro.csv --frames ../shared/data/running_phone/frames.csv \\
      --camera examples/cameras/running_phone.toml --out frames_mmbm.csv
  mmbm frames --gyro log.gcsv --frames frames.csv --camera lens_profile.json --scale-to 1920x1080 \\
      --select 20 --gap 0.5 --out sharpest.csv
  mmbm frames ... --select 200 --gap 0.2 --image-list sharp.txt --ffmpeg-select sharp.select \\
      --worst --worst-list blurry.txt --worst-ffmpeg-select blurry.select
  mmbm frames ... --count 100 --image-list sharp.txt --video video.mp4 --extract sharp/
  mmbm frames ... --per-window 10 --image-metric laplacian --video video.mp4 --image-list sharp.txt

Without --camera the thesis's 640x480 camera is used (a note on stderr says so).
If no frame lies inside the gyro log the command refuses, printing both time spans and a
--time-offset to try."
)]
pub struct FramesArgs {
    /// Gyro log (CSV, Gyroflow .gcsv, ROS 2 .mcap, or a phone's IMU rows
    /// timestamp_ns,type,x,y,z), on the clock of FRAMES (else --time-offset);
    /// or a camera's own file: GoPro MP4, Gyroflow project, Sensor Logger or phyphox CSV.
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// Frame table: CSV with t_start (first line's exposure start, s), exposure_s
    /// and optionally readout_s (else the camera's readout); '#' lines are comments.
    /// Also a phone's image list (timestamp_ns,exposure_ns) or the output of
    /// ffprobe -show_frames -of csv (presentation times; give --exposure).
    #[arg(long, value_name = "FRAMES.csv")]
    pub frames: PathBuf,
    /// Exposure of every frame, s, for a table of times only (ffprobe's).
    #[arg(long, value_name = "S")]
    pub exposure: Option<f64>,
    /// The TOML `mmbm sync` wrote: its offset_s as --time-offset (not both), and its
    /// readout_s unless --rolling-readout, the camera or the log gives one.
    #[arg(long, value_name = "FILE", conflicts_with = "time_offset")]
    pub sync: Option<PathBuf>,
    /// riemann[:NUxNV], gauss[:N] or exact[:TOL] (gpu is not available here).
    #[arg(long, default_value = "riemann:8x6")]
    pub method: AnyMethod,
    /// Output CSV (default: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub choice: super::choose::ChoiceArgs,
    /// Also write each frame's per-pixel blur fields to DIR, one EXR per frame named as
    /// --image-list names the frame with the extension .exr (frame_000006.exr for
    /// frame_000006.png), for the frames written (all, or the chosen ones) inside the log.
    /// Channels: disp.u, disp.v (px), path_px (px), flow.u, flow.v (px/s); NaN beyond the
    /// lens's radial limit. The maps appear together with the table and the lists, or not at
    /// all (staged in a hidden folder, removed on failure or interrupt); no other output may
    /// lie in DIR.
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,
    /// Samples of the --maps EXRs: half (f16, ZIP; about 3 significant digits) or float (f32, ZIP).
    #[arg(
        long,
        value_name = "half|float",
        default_value = "half",
        requires = "maps"
    )]
    pub maps_format: MapsFormat,
    /// Channels of the --maps EXRs, comma-separated, of disp.u, disp.v, path_px, flow.u,
    /// flow.v (default: all five).
    #[arg(long, value_name = "LIST", requires = "maps")]
    pub maps_channels: Option<String>,
    /// Where --maps computes: cpu (f64, all cores), gpu (the maps kernel, or an error), auto
    /// (GPU if any adapter, else CPU) or bulk (a hardware GPU, else CPU). The kernel takes
    /// every lens model (OpenCV and fisheye by formula, the others through a lens table).
    #[arg(long, default_value = "bulk")]
    pub backend: mmbm::gpu::Backend,
    /// Include the log's vx,vy,vz (needs a depth column, --depth or --plane).
    #[arg(long)]
    pub use_velocity: bool,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn run(a: FramesArgs) -> Result<()> {
    // Every output's place, against the others and every input, before any work.
    a.choice.check()?;
    a.choice
        .guard(a.out.as_deref())
        .output_dir("--maps", a.maps.as_deref(), is_map_name)
        .input("--gyro", Some(&a.gyro))
        .input("--frames", Some(&a.frames))
        .input("--camera", a.camera.camera.as_deref())
        .input("--sync", a.sync.as_deref())
        .check()?;
    let method = match a.method {
        AnyMethod::Cpu(m) => m,
        AnyMethod::Gpu { .. } => {
            return Err(Error::invalid(
                "method",
                "gpu is not available for frames (each line has its own window); use riemann, gauss or exact",
            ))
        }
    };
    let maps_out = MapsOutput {
        name: a.choice.frame_name.with_extension("exr"),
        start: a.choice.frame_start,
        format: a.maps_format,
        channels: match &a.maps_channels {
            Some(list) => parse_channels(list)?,
            None => MapsOutput::default().channels,
        },
    };
    if a.maps.is_some() && a.choice.frame_name.has_folder() {
        return Err(Error::invalid(
            "--frame-name",
            "--maps names the EXRs after it: give a name without a folder",
        ));
    }
    let camera = a.camera.camera()?;
    if a.camera.camera.is_none() {
        eprintln!(
            "note: no --camera: using the thesis's camera ({}x{} px, focal {} mm, pitch {} mm{}); \
             give yours with --camera FILE (TOML or a Gyroflow lens profile, docs/cameras.md)",
            camera.width,
            camera.height,
            camera.focal_mm,
            camera.pitch_x_mm,
            if a.camera.focal.is_some() || a.camera.pitch.is_some() || a.camera.sensor.is_some() {
                ", with the flags given"
            } else {
                ""
            }
        );
    }
    if a.maps.is_some() {
        // The maps' size, before the log is read or anything allocated.
        mmbm::series::maps::check_size(&camera)?;
    }
    let frames = read_frame_table(&a.frames, a.exposure)?;
    mmbm::series::select::check_frame_start(a.choice.frame_start, frames.len())?;
    let synced = a
        .sync
        .as_deref()
        .map(super::sync::read_for_frames)
        .transpose()?;
    let mut telemetry = a.gyro_opts.telemetry()?;
    if let Some(s) = &synced {
        telemetry.gyro.time_offset = s.offset_s;
    }
    let samples = mmbm::telemetry::read_gyro(&a.gyro, &telemetry)?;
    // The job: the camera with the log's readout applied once, then the
    // sync file's where neither the camera nor the log gave one.
    let cfg = FramesConfig {
        camera,
        plane: a.scene.plane()?,
        method,
        use_velocity: a.use_velocity,
    };
    let job = FramesJob::new(cfg, samples.readout())?;
    if job.readout_from_log() {
        super::args::print_log_readout(&job.camera().shutter, &a.gyro);
    }
    let job = match (&synced, &a.sync) {
        (Some(s), Some(path)) => job.map_camera(|c| {
            super::sync::synced_readout(c, s, path, a.camera.rolling_readout.is_some())
        })?,
        _ => job,
    };
    let camera = *job.camera();
    let (rows, outside) = job.mmbm(&samples, &frames)?;
    let log_t: Vec<f64> = samples.samples().iter().map(|s| s.t).collect();
    let spans = Spans::of(&rows, &log_t);
    let offset = a.gyro_opts.time_offset;
    check_clock(spans, rows.len() - outside.len(), offset)?;
    if !outside.is_empty() {
        let list: Vec<String> = outside.iter().take(8).map(|k| k.to_string()).collect();
        eprintln!(
            "warning: {} frame(s) reach outside the gyro log ({}{}): their values are empty; {}",
            outside.len(),
            list.join(", "),
            if outside.len() > 8 { ", ..." } else { "" },
            spans.map_or(String::new(), |s| s.describe(offset)),
        );
    }
    let sharpness = match (&a.choice.image_metric, &a.choice.video) {
        (Some(m), Some(v)) => Some(mmbm::series::select::video::score_frames(
            v,
            *m,
            rows.len(),
        )?),
        _ => None,
    };
    let kept = a.choice.keep(&rows, sharpness.as_deref())?;
    let keep = &kept.rows;
    let write = |w: &mut dyn Write| -> Result<()> {
        let werr = |e: std::io::Error| mmbm::Error::io("<frames output>", e);
        writeln!(
            w,
            "frame,t_start,exposure_mmbm_mm_s,blur_px,start_mmbm_mm_s,exposure_s,readout_s"
        )
        .map_err(werr)?;
        let opt =
            |x: Option<f64>| x.map_or(String::new(), |v| ryu::Buffer::new().format(v).to_string());
        for &k in keep {
            let r = &rows[k];
            writeln!(
                w,
                "{},{},{},{},{},{},{}",
                r.frame,
                ryu::Buffer::new().format(r.t_start),
                opt(r.exposure_mm_s),
                opt(r.blur_px()),
                opt(r.start_mm_s),
                ryu::Buffer::new().format(r.exposure_s),
                ryu::Buffer::new().format(r.readout_s),
            )
            .map_err(werr)?;
        }
        Ok(())
    };
    // The maps go to a staging folder; they, the table and the lists appear
    // together once all were written, or none does.
    let staged = match &a.maps {
        Some(dir) => Some(stage_maps(
            &samples,
            job.series(),
            &frames,
            keep,
            dir,
            a.backend,
            &maps_out,
        )?),
        None => None,
    };
    let extracted = match (&a.choice.extract, &a.choice.video) {
        (Some(dir), Some(video)) => {
            let mut staged = mmbm::series::maps::write::StagedMaps::empty(dir)?;
            let names = mmbm::series::select::video::extract(
                video,
                keep,
                &a.choice.frame_name,
                a.choice.frame_start,
                staged.root(),
                rows.len(),
            )?;
            staged.add(names);
            Some(staged)
        }
        _ => None,
    };
    let done = mmbm::io::atomic::all_or_nothing(|| {
        match &a.out {
            Some(p) => mmbm::io::atomic::write_atomic(p, |w| write(w))?,
            None => write(&mut std::io::stdout().lock())?,
        }
        a.choice.write(&rows, &kept)?;
        if let Some(x) = extracted {
            x.publish()?;
        }
        staged.map(|s| s.publish()).transpose()
    })?;
    if let Some(dir) = &a.choice.extract {
        eprintln!("extracted: {} frame(s) to {}", keep.len(), dir.display());
    }
    if let (Some(dir), Some(done)) = (&a.maps, done) {
        let n = done.written.len();
        let mean = done.written.iter().map(|d| d.1).sum::<f64>() / n.max(1) as f64;
        eprintln!(
            "maps: {n} frame(s) to {} (mean path {mean:.3} px) on {}",
            dir.display(),
            done.adapter.as_deref().unwrap_or("the CPU")
        );
        if !done.skipped.is_empty() {
            let list: Vec<String> = done.skipped.iter().take(8).map(|k| k.to_string()).collect();
            eprintln!(
                "warning: {} frame(s) have no maps: their span leaves the gyro log or crosses a gap in it ({}{})",
                done.skipped.len(),
                list.join(", "),
                if done.skipped.len() > 8 { ", ..." } else { "" }
            );
        }
    }
    eprintln!(
        "{} frames ({} written), method {method}, camera readout {} s",
        rows.len(),
        keep.len(),
        camera.shutter.readout_s
    );
    Ok(())
}
