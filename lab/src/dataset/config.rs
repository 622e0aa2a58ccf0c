//! The dataset configuration (TOML): what items are drawn from.

use super::sensor::SensorPipeline;
use crate::camera::{Camera, CameraFile};
use crate::error::{Error, Result};
use crate::render::{Quality, SharpAt};
use crate::sim::Gait;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What `mmbm dataset` generates. Every range is `[low, high]`, drawn
/// uniformly per item.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DatasetConfig {
    /// Number of items.
    pub count: u64,
    /// Master seed: item `i`'s random draws depend only on it and `i`.
    pub seed: u64,
    /// Folder of texture images (PNG/JPEG); a relative path is relative to
    /// the configuration file's folder (the working directory for TOML text
    /// or no file). `builtin:` (the default): the five textures compiled
    /// into mmbm, the files of `assets/textures/` ([`super::textures`]).
    pub textures: PathBuf,
    /// Motion sources, one drawn per item: `sim:slow|moderate|fast` (a
    /// simulated walk) or `log:PATH` (a gyro CSV or MCAP log; a window of it;
    /// a relative path as `textures`).
    pub motion: Vec<String>,
    /// Exposure range, s.
    pub exposure_s: [f64; 2],
    /// Target distance range (along the optical axis at exposure start), m.
    pub distance_m: [f64; 2],
    /// Target tilt range about the x and the y axis, degrees.
    pub tilt_deg: [f64; 2],
    /// The texture's width as a multiple of the field of view's width at
    /// the target distance (> 1: the picture fills the frame).
    pub fill: f64,
    /// Image size, px (thesis focal length and pixel pitch).
    pub resolution: [u32; 2],
    /// Render preset: `default`, `fast` or `MIN_SAMPLES:SPACING_PX`.
    pub quality: String,
    /// Use the motion's linear velocity where it has one (simulated walks do;
    /// logs without vx,vy,vz are rotation only).
    pub use_velocity: bool,
    /// The instant the sharp frame shows: `mid` (default: the middle of the
    /// motion, as GoPro / REDS pair a blurred frame with its middle sharp
    /// frame), `start` (what mmbm made before this key) or `end`.
    pub sharp: SharpAt,
    /// The `[camera]` section: any of the camera file's keys ([`CameraFile`])
    /// over the thesis camera at `resolution` ([`DatasetConfig::camera`]), as
    /// the experiment's. Left out when empty, so a configuration without it
    /// serialises (and fingerprints) as it always did.
    #[serde(skip_serializing_if = "is_empty")]
    pub camera: CameraFile,
    /// The `[sensor]` section: the camera pipeline applied to the PNG files
    /// ([`SensorPipeline`]: noise seeded per item, saturation, Bayer mosaic
    /// and demosaicing, response curve, JPEG). Left out when absent, so a
    /// configuration without it gives the items it always gave.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor: Option<SensorPipeline>,
    /// The file the configuration was read from (not a key): relative paths
    /// are resolved against its folder, and errors name it.
    #[serde(skip)]
    pub origin: Origin,
}

/// Where a configuration came from: its file, if any. Not part of what the
/// configuration is (two configurations equal whatever their files).
#[derive(Debug, Clone, Default)]
pub struct Origin(pub Option<PathBuf>);

impl PartialEq for Origin {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// True for a `[camera]` section with no keys.
pub(crate) fn is_empty(c: &CameraFile) -> bool {
    *c == CameraFile::default()
}

impl Default for DatasetConfig {
    fn default() -> Self {
        DatasetConfig {
            count: 100,
            seed: 1,
            textures: PathBuf::from(super::textures::BUILTIN),
            motion: vec!["sim:slow".into(), "sim:moderate".into(), "sim:fast".into()],
            exposure_s: [0.01, 0.07],
            distance_m: [1.0, 3.0],
            tilt_deg: [-20.0, 20.0],
            fill: 1.5,
            resolution: [640, 480],
            quality: "default".into(),
            use_velocity: true,
            camera: CameraFile::default(),
            sensor: None,
            sharp: SharpAt::Mid,
            origin: Origin::default(),
        }
    }
}

/// Most items one configuration may declare.
pub const MAX_COUNT: u64 = 100_000_000;

impl DatasetConfig {
    /// Loads a TOML file; missing keys take the defaults. Errors name the
    /// file and the key.
    /// Relative paths in it (`textures`, `log:PATH`) are relative to the
    /// file's folder.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::io::input::read_text(path)?;
        let mut cfg = Self::from_toml(&text, &path.display().to_string())?;
        cfg.origin = Origin(Some(path.to_path_buf()));
        Ok(cfg)
    }

    /// `p` resolved against the configuration file's folder (as it is when
    /// absolute, or when the configuration has no file).
    pub fn resolve(&self, p: &Path) -> PathBuf {
        match self.origin.0.as_deref().and_then(Path::parent) {
            Some(base) if !p.is_absolute() => base.join(p),
            _ => p.to_path_buf(),
        }
    }

    /// An error about `path`, written as `value` under `key`: names the
    /// key and the file, and the resolved path when it differs.
    pub(crate) fn key_error(
        &self,
        key: &str,
        value: &str,
        path: &Path,
        message: impl Into<String>,
    ) -> Error {
        let file = match &self.origin.0 {
            Some(f) => format!(" in {}", crate::error::show_path(f)),
            None => String::new(),
        };
        let mut message = message.into();
        let resolved = self.resolve(path);
        let shown = crate::error::show_path(&resolved);
        if resolved != path && !message.contains(&shown) {
            message = format!("{message} (resolved against the configuration's folder: {shown})");
        }
        Error::invalid(
            format!(
                "{key} = \"{}\" (key '{key}'{file})",
                crate::error::shown(value, 200)
            ),
            message,
        )
    }

    /// Parses TOML text (`origin` names it in errors); missing keys take the
    /// defaults. Relative paths are relative to the working directory (see
    /// [`Self::load`] for a file).
    pub fn from_toml(text: &str, origin: &str) -> Result<Self> {
        let cfg: DatasetConfig = toml::from_str(text).map_err(|e| {
            Error::invalid(
                origin,
                crate::error::clip(&e.to_string(), crate::error::MAX_MESSAGE),
            )
        })?;
        cfg.validate()
            .map_err(|e| Error::invalid(origin, e.to_string()))?;
        Ok(cfg)
    }

    /// The configuration as TOML.
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::invalid("dataset config", e.to_string()))
    }

    /// The items' camera: the thesis focal length and pitch at
    /// `resolution`, with the `[camera]` section's keys over it
    /// ([`CameraFile::thesis_at`]). Not validated (see [`Self::validate`]).
    pub fn camera(&self) -> Camera {
        self.camera.thesis_at(self.resolution)
    }

    /// Checks every value (not the files: see [`super::Sources::open`]).
    pub fn validate(&self) -> Result<()> {
        let key = |k: &str, m: String| Error::invalid(k, m);
        if let Some(s) = &self.sensor {
            s.validate()?;
        }
        if self.count == 0 || self.count > MAX_COUNT {
            return Err(key(
                "count",
                format!("{} is not in 1..={MAX_COUNT}", self.count),
            ));
        }
        let range = |k: &str, r: [f64; 2], lo: f64, hi: f64| {
            if !(r[0].is_finite() && r[1].is_finite() && lo <= r[0] && r[0] <= r[1] && r[1] <= hi) {
                return Err(key(
                    k,
                    format!(
                        "[{}, {}] must be finite, increasing, within [{lo}, {hi}]",
                        r[0], r[1]
                    ),
                ));
            }
            Ok(())
        };
        range("exposure_s", self.exposure_s, 1e-6, 10.0)?;
        if self.exposure_s[0] <= 0.0 {
            return Err(key("exposure_s", "must be > 0".into()));
        }
        range("distance_m", self.distance_m, 0.01, 1e4)?;
        range("tilt_deg", self.tilt_deg, -60.0, 60.0)?;
        if !(self.fill.is_finite() && self.fill >= 1.0 && self.fill <= 100.0) {
            return Err(key("fill", format!("{} is not in [1, 100]", self.fill)));
        }
        let [w, h] = self.resolution;
        if w == 0 || h == 0 || w as u64 * h as u64 > crate::render::MAX_PIXELS {
            return Err(key("resolution", format!("{w}x{h} is not a usable size")));
        }
        let cam = self.camera();
        cam.validate().map_err(|e| key("camera", e.to_string()))?;
        // Items' JSON carries the section: every number in it must be an
        // int64 (Arrow, pandas, Python's C long).
        if let Some(n) = self
            .camera
            .noise
            .as_ref()
            .filter(|n| n.seed > i64::MAX as u64)
        {
            return Err(key(
                "camera.noise.seed",
                format!(
                    "{} is above 2^63 - 1 (items' JSON must load as int64 in Arrow / Hugging Face datasets)",
                    n.seed
                ),
            ));
        }
        if cam.width as u64 * cam.height as u64 > crate::render::MAX_PIXELS {
            return Err(key(
                "camera",
                format!("{}x{} is not a usable size", cam.width, cam.height),
            ));
        }
        self.quality
            .parse::<Quality>()
            .map_err(|e| key("quality", e.to_string()))?;
        if self.motion.is_empty() {
            return Err(key("motion", "needs at least one source".into()));
        }
        for m in &self.motion {
            MotionSource::parse(m).map_err(|e| key("motion", e.to_string()))?;
        }
        Ok(())
    }
}

/// Where an item's motion comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionSource {
    /// A simulated walk of this gait (seeded per item).
    Sim(Gait),
    /// A window of a recorded log.
    Log(PathBuf),
}

impl MotionSource {
    /// `sim:GAIT` or `log:PATH`.
    pub fn parse(s: &str) -> Result<Self> {
        match s.split_once(':') {
            Some(("sim", g)) => Ok(MotionSource::Sim(g.parse()?)),
            Some(("log", p)) if !p.is_empty() => Ok(MotionSource::Log(PathBuf::from(p))),
            _ => Err(Error::invalid(
                "motion",
                format!(
                    "{}: expected sim:slow|moderate|fast or log:PATH",
                    crate::error::quote(s)
                ),
            )),
        }
    }
}
