//! Argument groups shared by several subcommands.

use clap::Args;
use glam::DVec3;
use mmbm::error::{Error, Result};
use mmbm::trigger::CameraTiming;
use mmbm::{Camera, Plane};
use std::path::{Path, PathBuf};

/// Parses `X,Y,Z` into a vector.
pub fn parse_vec3(s: &str) -> std::result::Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("'{s}': expected three comma-separated numbers, e.g. 0.1,-0.2,0"))?;
    if v.len() != 3 {
        return Err(format!(
            "'{s}': expected three comma-separated numbers, got {}",
            v.len()
        ));
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(format!("'{s}': values must be finite"));
    }
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// Parses `NX,NY,NZ,D` into a plane.
pub fn parse_plane(s: &str) -> std::result::Result<Plane, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("'{s}': expected NX,NY,NZ,D (four numbers)"))?;
    if v.len() != 4 || v.iter().any(|x| !x.is_finite()) {
        return Err(format!("'{s}': expected NX,NY,NZ,D (four finite numbers)"));
    }
    Ok(Plane {
        normal: DVec3::new(v[0], v[1], v[2]),
        d: v[3],
    })
}

/// Parses `WxH`.
pub fn parse_resolution(s: &str) -> std::result::Result<(u32, u32), String> {
    let (a, b) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}': expected WxH, e.g. 320x240"))?;
    let w: u32 = a
        .parse()
        .map_err(|_| format!("'{s}': expected WxH, e.g. 320x240"))?;
    let h: u32 = b
        .parse()
        .map_err(|_| format!("'{s}': expected WxH, e.g. 320x240"))?;
    if w == 0 || h == 0 {
        return Err(format!("'{s}': width and height must be positive"));
    }
    Ok((w, h))
}

/// Camera options (thesis camera by default).
#[derive(Args, Debug, Clone)]
pub struct CameraArgs {
    /// Camera file: TOML or JSON with focal_mm, pitch_mm (or pitch_x_mm/pitch_y_mm),
    /// width, height, [cx, cy, skew], and the real-camera keys readout_s,
    /// readout_direction, [distortion] (model = "opencv": k1,k2,p1,p2,k3; "fisheye":
    /// k1..k4), [noise] (phi_e_per_s, read_noise_e, full_well_e, gain_dn_per_e, bits,
    /// seed), [lens] (f_number, focus_m); or a Gyroflow lens profile (.json).
    #[arg(long, value_name = "FILE")]
    pub camera: Option<PathBuf>,
    /// Focal length, mm (overrides the camera file; thesis: 4.2548).
    #[arg(allow_negative_numbers = true, long, value_name = "MM")]
    pub focal: Option<f64>,
    /// Square pixel pitch, mm (thesis: 0.00465).
    #[arg(allow_negative_numbers = true, long, value_name = "MM")]
    pub pitch: Option<f64>,
    /// Sensor resolution WxH (focal length and pixel pitch kept), principal point at the
    /// centre (thesis: 640x480); `--resolution` is the same flag (renders: at most 2^26
    /// pixels, 2^40 pixel-samples per frame).
    #[arg(long, visible_alias = "resolution", value_name = "WxH", value_parser = parse_resolution)]
    pub sensor: Option<(u32, u32)>,
    /// Scale the camera to a WxH image (focal length in px, principal point and skew
    /// scale; the field of view stays): a lens profile calibrated at 4K used for 1080p; a
    /// portrait WxH on a landscape camera transposes it first, as Gyroflow does.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, conflicts_with = "sensor")]
    pub scale_to: Option<(u32, u32)>,
    /// A Gyroflow zoom profile's focal length, mm: the profile's `interpolations` at
    /// it (default: the profile as it is, as Gyroflow without lens metadata).
    #[arg(long, value_name = "MM")]
    pub lens_focal: Option<f64>,
    /// Rolling-shutter readout, s: delay between the first and last line's
    /// exposure start (0 = global shutter; overrides the camera file's readout_s).
    #[arg(long, value_name = "S")]
    pub rolling_readout: Option<f64>,
    /// Readout direction: top-to-bottom, bottom-to-top, left-to-right, right-to-left.
    #[arg(long, value_name = "DIR")]
    pub readout_direction: Option<mmbm::camera::Readout>,
    /// Sensor noise at this light level (electrons per second of a white pixel,
    /// at most 1e12), with the camera file's other noise keys or their defaults.
    #[arg(long, value_name = "E_PER_S")]
    pub light: Option<f64>,
}

impl CameraArgs {
    /// The camera these options describe, validated: the file (or the
    /// thesis camera) with the flags over it, by the library.
    pub fn camera(&self) -> Result<Camera> {
        // Over the cap: named by the flag (a non-positive light is named by
        // its key, noise.phi_e_per_s, as it always was).
        if let Some(phi) = self.light.filter(|&p| p > mmbm::limits::MAX_LIGHT_E_PER_S) {
            mmbm::limits::check_light("--light", phi)?;
        }
        let over = mmbm::camera::CameraOverrides {
            keys: mmbm::camera::CameraFile {
                focal_mm: self.focal,
                pitch_mm: self.pitch,
                width: self.sensor.map(|(w, _)| w),
                height: self.sensor.map(|(_, h)| h),
                readout_s: self.rolling_readout,
                readout_direction: self.readout_direction,
                ..Default::default()
            },
            scale_to: self.scale_to,
            light_e_per_s: self.light,
            lens_focal_mm: self.lens_focal,
        };
        Camera::resolve(self.camera.as_deref(), &over)
    }
}

/// Says on stderr that `session`'s camera took the rolling shutter of the
/// log `gyro` (the library applies a Gyroflow `.gcsv` log's
/// `frame_readout_time` and `frame_readout_direction` when the camera gives
/// none: a camera file's or `--rolling-readout`'s readout wins), when it did.
pub fn report_log_readout(session: &mmbm::trigger::Session, gyro: &Path) {
    if session.readout_from_log() {
        print_log_readout(&session.camera().shutter, gyro);
    }
}

/// Says on stderr that the camera took the rolling shutter `shutter` of the
/// log `gyro`.
pub fn print_log_readout(shutter: &mmbm::camera::Shutter, gyro: &Path) {
    eprintln!(
        "rolling shutter from {}: readout {} s, {:?}",
        gyro.display(),
        shutter.readout_s,
        shutter.direction
    );
}

/// Scene depth options.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// Depth of a fronto-parallel scene plane, m (needed with translation).
    #[arg(
        long,
        value_name = "Z",
        conflicts_with = "plane",
        allow_hyphen_values = true
    )]
    pub depth: Option<f64>,
    /// Tilted scene plane n.X = d in the camera frame (metres), e.g. 0,0.2,1,3.
    #[arg(long, value_name = "NX,NY,NZ,D", value_parser = parse_plane, allow_hyphen_values = true)]
    pub plane: Option<Plane>,
}

impl SceneArgs {
    /// The plane, if any (depth must be positive and finite).
    pub fn plane(&self) -> Result<Option<Plane>> {
        if let Some(z) = self.depth {
            if !(z.is_finite() && z > 0.0) {
                return Err(Error::invalid(
                    "--depth",
                    format!("must be a positive number of metres, got {z}"),
                ));
            }
            return Ok(Some(Plane::fronto(z)));
        }
        Ok(self.plane)
    }
}

/// The lower-cased extension of `p` when it is one of `allowed`, else an
/// error naming the option.
pub fn check_ext(p: &Path, allowed: &[&str], what: &str) -> Result<String> {
    let e = p
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if allowed.contains(&e.as_str()) {
        Ok(e)
    } else {
        Err(Error::invalid(
            what,
            format!("{}: extension must be one of {allowed:?}", p.display()),
        ))
    }
}

/// The trigger timing options (`trigger`, `live`).
#[derive(Args, Debug, Clone)]
pub struct TimingArgs {
    /// Exposure t_e, s (thesis: 0.05, 0.07).
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        default_value_t = CameraTiming::DEFAULT_EXPOSURE_S
    )]
    pub exposure: f64,
    /// Trigger delay t_d, s.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        default_value_t = CameraTiming::DEFAULT_DELAY_S
    )]
    pub delay: f64,
    /// Readout t_r after the exposure, s.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        default_value_t = CameraTiming::DEFAULT_READOUT_S
    )]
    pub readout: f64,
    /// Minimum interval between MMBM-triggered frames, s.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        default_value_t = CameraTiming::DEFAULT_MIN_INTERVAL_S
    )]
    pub min_interval: f64,
}

impl TimingArgs {
    /// The camera timing; the pixel pitch is the default until a
    /// [`mmbm::trigger::Session`] takes the camera's.
    pub fn timing(&self) -> CameraTiming {
        CameraTiming {
            delay: self.delay,
            exposure: self.exposure,
            readout: self.readout,
            min_interval: self.min_interval,
            ..CameraTiming::default()
        }
    }
}
