//! The gyro from a camera's own files: one entry point, [`read_gyro`] (and
//! [`read_camera_file`] with the file's metadata), that knows the file by
//! its content first and its extension second, and reads:
//!
//! - a GoPro MP4 (HERO5 and later; GPMF in a `gpmd` track): [`mp4`],
//!   [`gpmf`];
//! - a Gyroflow project (`.gyroflow`): [`project`] (samples, sync offsets,
//!   lens profile, frame rate, rolling-shutter readout);
//! - a phone logging app's CSV (Sensor Logger, phyphox): [`apps`];
//! - every log [`crate::io::gyro::read_log`] reads (CSV, `.gcsv`, MCAP, a
//!   phone's IMU rows), through it, unchanged.
//!
//! Each format's samples are in its device's axes; an [`Orientation`]
//! preset (the format's default: `action-cam` for a GoPro, the identity for
//! the others) takes them to mmbm's camera frame, then
//! [`GyroOptions::imu_to_camera`] (`--imu-rotation`) and
//! [`GyroOptions::time_offset`] apply, as for every log. A camera file
//! carries its own units: `time_unit` and `angle_unit` must stay at their
//! defaults, and `gyroflow_rotation` is for `.gcsv` logs only.

pub mod apps;
pub mod gpmf;
pub mod mp4;
pub mod orientation;
pub mod project;

use crate::error::{Error, Result};
use crate::io::gyro::{read_log, AngleUnit, GyroOptions, GyroSample, TimeUnit};
use crate::model::log::{ImuLog, LogReadout};
use glam::{DMat3, DVec3};
pub use orientation::Orientation;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The formats [`read_gyro`] knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A GoPro MP4 with a GPMF (`gpmd`) track.
    GoProMp4,
    /// A Gyroflow project (`.gyroflow`).
    GyroflowProject,
    /// A phone app's gyro CSV.
    App(apps::App),
    /// A log read by [`crate::io::gyro::read_log`].
    Log,
}

/// What every format above is, in words (the unknown-format error lists it).
pub const ACCEPTED: &str = "a GoPro MP4 (HERO5 or later, GPMF telemetry), a Gyroflow project (.gyroflow with \
    embedded samples or its gyro file beside it), Sensor Logger's Gyroscope.csv, phyphox's gyroscope CSV, \
    a Gyroflow .gcsv log, a ROS 2 .mcap, a phone's IMU rows (timestamp_ns,type,x,y,z) or a CSV t,wx,wy,wz";

/// What a camera file says besides its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFileInfo {
    /// The format read.
    pub format: Format,
    /// The video's frame rate, 1/s (a GoPro's video track; a project's `video_info.fps`).
    pub fps: Option<f64>,
    /// Rolling-shutter readout of a whole frame, s (a project's `frame_readout_time`).
    pub readout_s: Option<f64>,
    /// The lens profile (a project's `calibration_data`, Gyroflow's JSON).
    pub lens_profile: Option<serde_json::Value>,
    /// Sync points: (video time s, offset s) (a project's `offsets`), already applied to the samples.
    pub offsets: Vec<(f64, f64)>,
    /// The device (GPMF `DVNM`) or app.
    pub device: Option<String>,
    /// The orientation preset applied.
    pub orientation: Option<Orientation>,
    /// The file the samples came from, when not the one given (a project's gyro file).
    pub gyro_file: Option<PathBuf>,
}

impl CameraFileInfo {
    /// Empty metadata of `format`.
    pub fn new(format: Format) -> Self {
        CameraFileInfo {
            format,
            fps: None,
            readout_s: None,
            lens_profile: None,
            offsets: Vec::new(),
            device: None,
            orientation: None,
            gyro_file: None,
        }
    }
}

/// How to read a camera file: the log options plus an orientation preset.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TelemetryOptions {
    /// The options of every gyro log (`imu_to_camera` applies after the preset).
    pub gyro: GyroOptions,
    /// The device-to-camera preset (None: the format's default).
    pub orientation: Option<Orientation>,
}

/// The first bytes of `path` (at most 4 KiB).
fn head(path: &Path) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    crate::bounded::open_file(path)?
        .take(4096)
        .read_to_end(&mut buf)
        .map_err(|e| Error::io(path, e))?;
    Ok(buf)
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

/// The format of `path`: by content, then by extension (a `.mp4`, `.mov`
/// or `.gyroflow` whose content is not that format is refused by name).
pub fn sniff(path: &Path) -> Result<Format> {
    if path.as_os_str() == "-" || !crate::bounded::is_regular_file(path) {
        return Ok(Format::Log);
    }
    let h = head(path)?;
    if mp4::looks_like_mp4(&h) {
        return Ok(Format::GoProMp4);
    }
    if project::looks_like_project(&h) {
        return Ok(Format::GyroflowProject);
    }
    let text = String::from_utf8_lossy(&h);
    if let Some(app) = apps::detect(&text) {
        return Ok(Format::App(app));
    }
    let ext = extension(path);
    let refuse = |what: &str| {
        Err(mp4::bad(path, what, format!("the content is not {what} (the file is known by its content); accepted: {ACCEPTED}")))
    };
    match ext.as_str() {
        "mp4" | "mov" | "360" | "lrv" => return refuse("an MP4 (no ftyp box first)"),
        "gyroflow" => return refuse("a Gyroflow project (a JSON object with gyro_source)"),
        _ => {}
    }
    if h.is_empty() {
        return Err(mp4::bad(
            path,
            "file",
            format!("empty; accepted: {ACCEPTED}"),
        ));
    }
    if h.contains(&0) && &h[..h.len().min(8)] != b"\x89MCAP0\r\n" {
        // Where the first NUL is (line, 1-based) and how the file starts, as
        // the text readers name a bad byte.
        let nul = h.iter().position(|&b| b == 0).unwrap_or(0);
        let line = 1 + h[..nul].iter().filter(|&&b| b == b'\n').count();
        let start: String = h[..h.len().min(8)]
            .iter()
            .flat_map(|&b| std::ascii::escape_default(b))
            .map(char::from)
            .collect();
        return Err(Error::invalid(
            format!("{}:{line}", path.display()),
            format!(
                "binary content of no known format (a NUL byte; the file starts with '{start}'); \
                 accepted: {ACCEPTED}"
            ),
        ));
    }
    Ok(Format::Log)
}

/// The gyro of `path`, in mmbm's camera frame (see the module docs).
pub fn read_gyro(path: &Path, opts: &TelemetryOptions) -> Result<ImuLog> {
    Ok(read_camera_file(path, opts)?.0)
}

/// The gyro of `path` and what else the file says.
pub fn read_camera_file(path: &Path, opts: &TelemetryOptions) -> Result<(ImuLog, CameraFileInfo)> {
    let format = sniff(path)?;
    if format == Format::Log {
        let mut g = opts.gyro.clone();
        if let Some(o) = opts.orientation {
            g.imu_to_camera *= o.matrix();
        }
        let log = read_log(path, g)?;
        let mut info = CameraFileInfo::new(Format::Log);
        info.orientation = opts.orientation;
        return Ok((log, info));
    }
    own_units(path, &opts.gyro)?;
    let (samples, mut info, default) = match format {
        Format::GoProMp4 => {
            let tracks = mp4::tracks(path)?;
            let meta = tracks
                .iter()
                .find(|t| &t.format == b"gpmd")
                .ok_or_else(|| {
                    mp4::bad(
                        path,
                        "moov",
                        "no GPMF (gpmd) track: not a GoPro HERO5-or-later recording",
                    )
                })?;
            let g = gpmf::read(path, &meta.samples)?;
            let mut info = CameraFileInfo::new(Format::GoProMp4);
            info.fps = tracks
                .iter()
                .find(|t| &t.handler == b"vide")
                .and_then(|t| t.rate());
            info.device = g.device.clone();
            (g.samples, info, Orientation::ActionCam)
        }
        Format::GyroflowProject => {
            let p = project::read(path)?;
            let mut info = p.info;
            let samples = match (p.samples, p.gyro_file) {
                (Some(s), _) => s,
                (None, Some(file)) => {
                    // The project's gyro file: a camera file itself (not another project).
                    let inner = TelemetryOptions {
                        gyro: opts.gyro.clone(),
                        orientation: opts.orientation,
                    };
                    if sniff(&file)? == Format::GyroflowProject {
                        return Err(mp4::bad(
                            path,
                            "gyro_source.filepath",
                            "points at another Gyroflow project",
                        ));
                    }
                    let plain = TelemetryOptions {
                        gyro: GyroOptions {
                            imu_to_camera: DMat3::IDENTITY,
                            time_offset: 0.0,
                            ..inner.gyro.clone()
                        },
                        ..inner
                    };
                    let (log, sub) = read_camera_file(&file, &plain)?;
                    info.fps = info.fps.or(sub.fps);
                    info.device = sub.device;
                    info.gyro_file = Some(file);
                    let s: Vec<(f64, DVec3)> =
                        log.samples().iter().map(|s| (s.t, s.omega)).collect();
                    return finish(
                        path,
                        shift(s, &p.offsets),
                        info,
                        DMat3::IDENTITY,
                        &opts.gyro,
                    );
                }
                (None, None) => unreachable!("a project without samples names its gyro file"),
            };
            let s = shift(samples, &p.offsets);
            let m = opts
                .orientation
                .map_or(DMat3::IDENTITY, Orientation::matrix);
            info.orientation = opts.orientation;
            return finish(path, s, info, m, &opts.gyro);
        }
        Format::App(app) => {
            let (_, s) = apps::read(path)?;
            let mut info = CameraFileInfo::new(format);
            info.device = Some(app.name().to_string());
            if opts.orientation.is_none() {
                log::warn!(
                    "warning: {}: {} logs the phone's axes; without --orientation they are taken as the camera's \
                     (give --orientation phone-back-portrait or phone-back-landscape for a phone video)",
                    crate::error::show_path(path),
                    app.name()
                );
            }
            (s, info, Orientation::Camera)
        }
        Format::Log => unreachable!("handled above"),
    };
    let o = opts.orientation.unwrap_or(default);
    info.orientation = Some(o);
    finish(path, samples, info, o.matrix(), &opts.gyro)
}

/// Moves each sample to the video time a project's offsets give it.
fn shift(samples: Vec<(f64, DVec3)>, offsets: &[(f64, f64)]) -> Vec<(f64, DVec3)> {
    if offsets.is_empty() {
        return samples;
    }
    samples
        .into_iter()
        .map(|(t, w)| (project::video_time(offsets, t), w))
        .collect()
}

/// Refuses unit options a camera file does not take.
fn own_units(path: &Path, g: &GyroOptions) -> Result<()> {
    if g.time_unit != TimeUnit::S || g.angle_unit != AngleUnit::Rad {
        return Err(Error::invalid(
            crate::error::show_path(path),
            "a camera file carries its own units: leave --time-unit and --angle-unit at their defaults",
        ));
    }
    if g.gyroflow_rotation.is_some() {
        return Err(Error::invalid(
            crate::error::show_path(path),
            "--gyroflow-rotation applies to a .gcsv log only (a Gyroflow project carries its own rotation); give --imu-rotation",
        ));
    }
    if g.topic.is_some() {
        return Err(Error::invalid(
            crate::error::show_path(path),
            "--topic applies to an MCAP log only",
        ));
    }
    Ok(())
}

/// The log: `orient` then the options, every sample checked (named by file).
fn finish(
    path: &Path,
    samples: Vec<(f64, DVec3)>,
    info: CameraFileInfo,
    orient: DMat3,
    g: &GyroOptions,
) -> Result<(ImuLog, CameraFileInfo)> {
    let out: Vec<GyroSample> = samples
        .into_iter()
        .map(|(t, w)| GyroSample {
            t: t + g.time_offset,
            omega: g.imu_to_camera * (orient * w),
            velocity: None,
            depth: None,
        })
        .collect();
    let log = ImuLog::new(out).map_err(|e| mp4::bad(path, "samples", e))?;
    let readout = info.readout_s.map(|readout_s| LogReadout {
        readout_s,
        direction: None,
    });
    Ok((log.with_readout(readout), info))
}
