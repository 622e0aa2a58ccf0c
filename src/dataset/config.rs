//! The dataset configuration (TOML): what items are drawn from.

use super::sensor::SensorPipeline;
use crate::camera::{Camera, CameraFile};
use crate::error::{Error, Result};
use crate::render::Quality;
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
    /// Folder of texture images (PNG/JPEG), relative to the working directory.
    pub textures: PathBuf,
    /// Motion sources, one drawn per item: `sim:slow|moderate|fast` (a
    /// simulated walk) or `log:PATH` (a gyro CSV or MCAP log; a window of it).
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
            textures: PathBuf::from("assets/textures"),
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
        }
    }
}

/// Most items one configuration may declare.
pub const MAX_COUNT: u64 = 100_000_000;

impl DatasetConfig {
    /// Loads a TOML file; missing keys take the defaults. Errors name the
    /// file and the key.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::io::input::read_text(path)?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Parses TOML text (`origin` names it in errors); missing keys take the
    /// defaults. Relative paths are relative to the working directory.
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
