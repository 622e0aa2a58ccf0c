//! `mmbm clip`: a whole gyro log rendered as a video, the camera's
//! orientation carried from frame to frame, each frame with its true blur.

use super::args::{check_ext, CameraArgs};
use super::series::GyroArgs;
use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::io::atomic::{all_or_nothing, write_atomic, PendingDir};
use mmbm::render::clip::{Clip, ClipTarget, FrameTruth};
use mmbm::render::clip_panorama::Panorama;
use mmbm::render::{Backend, Background, Quality, Target};
use mmbm::video::{encode, Codec};
use std::path::{Path, PathBuf};

/// Render a gyro log as a video (MP4 through ffmpeg), with each frame's true blur.
#[derive(Args, Debug)]
#[command(
    after_help = "Frame k is exposed from t_k = START + k/FPS (s, the log's clock) for --exposure s \
per line (plus the --readout of a rolling shutter); the camera's orientation is the log's rotation \
integrated from START, so it turns over the target as it did in the log. The video is H.264 \
(libx264) when ffmpeg has it, else MPEG-4 part 2; --truth writes per frame: frame, t_start_s, \
blur_mean_px, blur_p50_px, blur_max_px (the blur maps' path length over the pixels that see the \
target), valid (their share), qw,qx,qy,qz (the camera-to-world rotation at t_k, world = the \
camera at START).
Targets: planes at --distance m: poster (the thesis board on the procedural CC0 poster; the
default), checker:S, blobs[:SCALE], image:PATH:WIDTH_M (PNG/JPEG, sRGB); or an equirectangular
panorama at infinity (any rotation): panorama (the built-in one, the CC0 poster wrapped around the
sphere) or panorama:PATH (PNG/JPEG, twice as wide as high).
Examples:
  mmbm clip --gyro ../shared/data/running_phone/gyro.csv --fps 30 --exposure 0.012 \\
      --start 2 --duration 3 --resolution 320x240 --out clip.mp4 --truth truth.csv
  mmbm clip --gyro walk.csv --fps 30 --exposure 0.02 --target panorama --out pano.mp4
  mmbm clip --gyro walk.csv --fps 30 --exposure 0.01 --readout 0.02 \\
      --target image:photo.jpg:4 --distance 2 --out clip.mp4 --maps maps/ --truth truth.csv"
)]
pub struct ClipArgs {
    #[command(flatten)]
    pub opts: Box<ClipOpts>,
}

/// The options of `mmbm clip` (boxed: the command enum stays small).
#[derive(Args, Debug)]
pub struct ClipOpts {
    /// Gyro log (any format `frames` reads): the camera's rotation.
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// Frame rate, frames/s (at most 1000).
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub fps: f64,
    /// Exposure of each line, s (at most one frame period).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub exposure: f64,
    /// Start of frame 0's exposure on the log's clock, s (default: the log's first sample).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub start: Option<f64>,
    /// Length of the clip, s: ceil(duration x fps) frames (default: as many
    /// whole frames as the log holds after --start; at most 100000 frames).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// poster, checker:S, blobs[:SCALE], image:PATH:WIDTH_M, panorama or panorama:PATH.
    #[arg(long, value_name = "SPEC", default_value = "poster")]
    pub target: String,
    /// Distance of the target plane along the optical axis at the clip's start, m.
    #[arg(
        long,
        value_name = "D",
        default_value_t = 3.0,
        allow_negative_numbers = true
    )]
    pub distance: f64,
    /// The video: .mp4.
    #[arg(long, value_name = "FILE.mp4")]
    pub out: PathBuf,
    /// Also write each frame's per-pixel blur maps into this new (or empty)
    /// folder: frame_%06d.exr numbered from 1 (half floats, ZIP; channels
    /// path_px, disp_px, speed_px_s).
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,
    /// Also write each frame's true blur and orientation (CSV).
    #[arg(long, value_name = "FILE.csv")]
    pub truth: Option<PathBuf>,
    /// default, fast (the default here: many frames), or MIN_SAMPLES:SPACING_PX.
    #[arg(long, default_value = "fast")]
    pub quality: Quality,
    /// bulk (a hardware GPU, else the CPU twin), auto, gpu or cpu.
    #[arg(long, default_value = "bulk")]
    pub backend: Backend,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

fn target(spec: &str, distance: f64) -> Result<ClipTarget> {
    match spec.trim() {
        "poster" => {
            let mut t = Target::blobs(1.0, distance);
            t.surround = Background::Poster;
            return Ok(ClipTarget::Plane(t));
        }
        "panorama" => return Ok(ClipTarget::Panorama(Panorama::builtin().into())),
        _ => {}
    }
    if let Some(p) = spec.strip_prefix("panorama:") {
        let pano = Panorama::load(Path::new(p))
            .map_err(|e| Error::invalid("--target panorama:", e.to_string()))?;
        return Ok(ClipTarget::Panorama(pano.into()));
    }
    Target::parse(spec, distance)
        .map(ClipTarget::Plane)
        .map_err(|e| Error::invalid("--target", e.to_string()))
}

/// The texture file of an `image:PATH:WIDTH_M` or `panorama:PATH` target.
fn texture_path(spec: &str) -> Option<PathBuf> {
    if let Some(p) = spec.strip_prefix("panorama:") {
        return Some(PathBuf::from(p));
    }
    let rest = spec.strip_prefix("image:")?;
    rest.rsplit_once(':').map(|(p, _)| PathBuf::from(p))
}

/// A folder for the maps: new, or existing and empty.
fn check_maps_dir(dir: &Path) -> Result<()> {
    match std::fs::read_dir(dir) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                return Err(Error::invalid(
                    "--maps",
                    format!("{}: the folder is not empty", dir.display()),
                ));
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(dir, e)),
    }
}

pub fn run(args: ClipArgs) -> Result<()> {
    let a = *args.opts;
    check_ext(&a.out, &["mp4"], "--out")?;
    if let Some(p) = &a.truth {
        check_ext(p, &["csv"], "--truth")?;
    }
    mmbm::check::positive("--distance", a.distance)?;
    if let Some(d) = a.duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(Error::invalid(
                "--duration",
                format!("{d} s: must be finite and > 0"),
            ));
        }
    }
    if let Some(d) = &a.maps {
        check_maps_dir(d)?;
    }
    let maps_parent = a.maps.as_ref().map(|d| {
        let p = d.parent().filter(|p| !p.as_os_str().is_empty());
        p.map_or_else(|| PathBuf::from("."), Path::to_path_buf)
    });
    mmbm::io::guard::OutputGuard::new()
        .output("--out", Some(&a.out))
        .output("--truth", a.truth.as_deref())
        .input("--gyro", Some(&a.gyro))
        .input("--camera", a.camera.camera.as_deref())
        .input("--target image:", texture_path(&a.target).as_deref())
        .check()?;
    if let Some(p) = &maps_parent {
        mmbm::io::atomic::check_output_dir(p)
            .map_err(|e| Error::invalid("--maps", e.to_string()))?;
    }
    let target = target(&a.target, a.distance)?;
    let camera = a.camera.camera()?;
    let log = mmbm::telemetry::read_gyro(&a.gyro, &a.gyro_opts.telemetry()?)?;
    // The log's own rolling-shutter readout, where the camera has none.
    let (camera, from_log) = log.apply_readout(camera)?;
    if from_log {
        super::args::print_log_readout(&camera.shutter, &a.gyro);
    }
    let s = log.samples();
    let (first, last) = (s[0].t, s[s.len() - 1].t);
    let start_s = a.start.unwrap_or(first);
    let frames = match a.duration {
        Some(d) => (d * a.fps - 1e-9).ceil().max(0.0),
        // Whole frames whose busy time ends inside the log.
        None => {
            let busy = camera.shutter.busy_s(a.exposure.max(0.0));
            ((last - start_s - busy) * a.fps).floor() + 1.0
        }
    };
    let frames = if frames.is_finite() && frames >= 0.0 {
        frames.min(1e12) as usize
    } else {
        0
    };
    let clip = Clip {
        camera,
        log: &log,
        fps: a.fps,
        exposure_s: a.exposure,
        start_s,
        frames,
        target,
        quality: a.quality,
        backend: a.backend,
    };
    clip.check()?;
    let codec = Codec::available()?;
    let staging = match &a.maps {
        Some(d) => {
            let name = d
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "maps".into());
            let tmp = maps_parent
                .as_ref()
                .expect("with --maps")
                .join(format!(".mmbm-clip-{name}-{}", std::process::id()));
            Some(PendingDir::create(&tmp)?)
        }
        None => None,
    };
    let t0 = std::time::Instant::now();
    let mut rows: Vec<FrameTruth> = Vec::with_capacity(frames.min(1 << 20));
    let size = (clip.camera.width, clip.camera.height);
    let result = all_or_nothing(|| {
        encode::encode(&a.out, size, a.fps, codec, |enc| {
            clip.render(|f| {
                enc.push(&f.rgb8)?;
                if let Some(dir) = &staging {
                    let p = dir
                        .path()
                        .join(mmbm::series::maps::write::file_name(f.truth.frame));
                    let m = &f.maps;
                    mmbm::io::images::write_exr_as(
                        &p,
                        m.width as usize,
                        m.height as usize,
                        &[
                            ("path_px", &m.path_px),
                            ("disp_px", &m.disp_px),
                            ("speed_px_s", &m.speed_px_s),
                        ],
                        true,
                    )?;
                }
                rows.push(f.truth);
                let k = rows.len();
                if k % 10 == 0 || k == frames {
                    eprint!("\rframe {k}/{frames}");
                }
                Ok(())
            })
        })?;
        eprintln!();
        if let Some(p) = &a.truth {
            write_atomic(p, |w| {
                writeln!(w, "{}", FrameTruth::CSV_HEADER).map_err(|e| Error::io(p, e))?;
                for r in &rows {
                    writeln!(w, "{}", r.csv_row()).map_err(|e| Error::io(p, e))?;
                }
                Ok(())
            })?;
        }
        Ok(())
    });
    if let Err(e) = result {
        if let Some(dir) = &staging {
            let _ = std::fs::remove_dir_all(dir.path());
        }
        return Err(e);
    }
    if let (Some(dir), Some(to)) = (&staging, &a.maps) {
        if to.is_dir() {
            std::fs::remove_dir(to).map_err(|e| Error::io(to, e))?;
        }
        std::fs::rename(dir.path(), to).map_err(|e| Error::io(to, e))?;
    }
    let secs = t0.elapsed().as_secs_f64();
    let mean = rows.iter().map(|r| r.mean_px).filter(|x| x.is_finite());
    let (n, sum) = mean.fold((0usize, 0.0), |(n, s), x| (n + 1, s + x));
    eprintln!(
        "{frames} frames of {}x{} ({}) in {secs:.1} s ({:.3} s/frame); mean true blur {:.3} px",
        size.0,
        size.1,
        codec.name(),
        secs / frames.max(1) as f64,
        sum / n.max(1) as f64
    );
    Ok(())
}
