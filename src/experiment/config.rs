//! Experiment configuration (TOML). Every field has a default; the defaults
//! are the thesis setup (chapter 6): 640 x 480, f = 4.2548 mm, 70 ms exposure,
//! the blob board walked towards from 6 m, the thesis policies and their
//! successors.

use crate::camera::{CameraFile, Noise};
use crate::error::{Error, Result};
use crate::trigger::CameraTiming;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The experiment's configuration.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExperimentConfig {
    /// Walk modes to simulate: `slow`, `moderate`, `fast` (ignored with `gyro`).
    pub walks: Vec<String>,
    /// Simulated duration per walk, s.
    pub duration_s: f64,
    /// Gyro rate of the simulation, Hz.
    pub rate_hz: f64,
    /// Simulation seed.
    pub seed: u64,
    /// Several simulation seeds (each walk simulated once per seed; the
    /// headline pools them). Empty: `seed` alone.
    pub seeds: Vec<u64>,
    /// A real gyro log (CSV of SPEC section 5) instead of the simulation.
    pub gyro: Option<PathBuf>,
    /// Forward speed (m/s) used for the target distance when the log has no velocity.
    pub speed_m_s: f64,
    /// Trigger policies, as `mmbm trigger --policy` strings.
    pub policies: Vec<String>,
    /// Exposure, s.
    pub exposure_s: f64,
    /// Trigger delay, s.
    pub delay_s: f64,
    /// Readout, s.
    pub readout_s: f64,
    /// Minimum interval between MMBM triggers, s.
    pub min_interval_s: f64,
    /// Target: `blobs` (thesis board) or `blobs:0.5` (half size, thesis Table 6.2).
    pub target: String,
    /// Distance to the target at t = 0, m (the walk approaches it).
    pub start_distance_m: f64,
    /// Closest allowed distance, m (the walk stops approaching there).
    pub min_distance_m: f64,
    /// Rendered resolution `[width, height]` (thesis: 640 x 480), thesis focal length and pitch.
    pub resolution: [u32; 2],
    /// Render quality preset: `default` or `fast` (the report states its measured error).
    pub quality: String,
    /// Render at most this many frames per policy and walk (evenly spread); 0 = all.
    pub max_frames_per_policy: usize,
    /// Exposures (s) of the exposure sweep in the report (the same frames
    /// re-rendered at each); empty: no sweep.
    pub sweep_exposures_s: Vec<f64>,
    /// Frames of the exposure sweep (the fixed-rate schedule's, evenly spread).
    pub sweep_frames: usize,
    /// The `[camera]` section: any of the camera file's keys
    /// ([`CameraFile`]) over the thesis camera at `resolution`, e.g. the
    /// real camera of SPEC section 9 (`readout_s`, `readout_direction`,
    /// `[camera.distortion]`, `[camera.noise]`, `[camera.lens]`; all off by
    /// default: the thesis's ideal global-shutter pinhole).
    pub camera: CameraFile,
}

impl Default for ExperimentConfig {
    fn default() -> Self {
        ExperimentConfig {
            walks: vec!["moderate".into()],
            duration_s: 18.0,
            rate_hz: 600.0,
            seed: 1,
            seeds: Vec::new(),
            gyro: None,
            speed_m_s: 0.17,
            policies: [
                "fixed:5",
                "threshold:0.8",
                "threshold:0.4",
                "threshold:0.2",
                "adaptive",
                "forecast:0.4",
                "phase:0.4",
                "oracle:0.4",
                "gate:0.8",
                "deadline:5",
                "fixed:5+exp:2:0.02",
                "deadline:5+exp:3:0.02",
            ]
            .map(String::from)
            .to_vec(),
            exposure_s: CameraTiming::DEFAULT_EXPOSURE_S,
            delay_s: CameraTiming::DEFAULT_DELAY_S,
            readout_s: CameraTiming::DEFAULT_READOUT_S,
            min_interval_s: CameraTiming::DEFAULT_MIN_INTERVAL_S,
            target: "blobs".into(),
            start_distance_m: 6.0,
            min_distance_m: 1.5,
            resolution: [640, 480],
            quality: "default".into(),
            max_frames_per_policy: 0,
            sweep_exposures_s: vec![0.01, 0.02, 0.035, 0.05, 0.07],
            sweep_frames: 12,
            camera: CameraFile::default(),
        }
    }
}

impl ExperimentConfig {
    /// The seeds to run: `seeds`, or `seed` when `seeds` is empty.
    pub fn seed_list(&self) -> Vec<u64> {
        if self.seeds.is_empty() {
            vec![self.seed]
        } else {
            self.seeds.clone()
        }
    }

    /// The `mmbm demo --full` configuration: the demo over seeds 1 to 5.
    pub fn demo_full() -> Self {
        ExperimentConfig {
            seeds: (1..=5).collect(),
            ..Self::demo()
        }
    }

    /// The light of the demo's camera: a white pixel collects this many
    /// electrons per second (1,400 e- in the thesis's 70 ms; a dim room).
    pub const DEMO_LIGHT_E_PER_S: f64 = 20_000.0;

    /// The `mmbm demo` configuration: the defaults (every kept frame of every
    /// policy rendered at the `default` preset) with realistic frames: the
    /// thesis camera's global shutter and lens, and sensor noise (EMVA 1288
    /// defaults: 2.5 e- read noise, 10,000 e- full well, 8 bits, seed 1) at
    /// [`ExperimentConfig::DEMO_LIGHT_E_PER_S`], with the gain set as a
    /// camera operator would for that light: a white pixel fills the 8-bit
    /// range in the 70 ms exposure (255 DN / 1,400 e- = 0.182 DN/e-).
    pub fn demo() -> Self {
        let d = Self::default();
        ExperimentConfig {
            camera: CameraFile {
                noise: Some(Noise {
                    seed: 1,
                    gain_dn_per_e: Some(255.0 / (Self::DEMO_LIGHT_E_PER_S * d.exposure_s)),
                    ..Noise::at_light(Self::DEMO_LIGHT_E_PER_S)
                }),
                ..CameraFile::default()
            },
            ..d
        }
    }

    /// Loads a TOML file; missing fields take the defaults.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::io::input::read_text(path)?;
        let cfg: Self = toml::from_str(&text).map_err(|e| Error::Config {
            path: path.into(),
            message: e.to_string(),
        })?;
        cfg.validate().map_err(|e| Error::Config {
            path: path.into(),
            message: e.to_string(),
        })?;
        Ok(cfg)
    }

    /// Checks ranges (times positive, distances positive and ordered, a policy at least).
    pub fn validate(&self) -> Result<()> {
        use crate::check::positive;
        positive("duration_s", self.duration_s)?;
        positive("rate_hz", self.rate_hz)?;
        let mut seeds = self.seeds.clone();
        seeds.sort_unstable();
        seeds.dedup();
        if seeds.len() != self.seeds.len() || seeds.len() > 100 {
            return Err(Error::invalid(
                "seeds",
                format!("{:?}: at most 100 seeds, each once", self.seeds),
            ));
        }
        positive("exposure_s", self.exposure_s)?;
        positive("start_distance_m", self.start_distance_m)?;
        positive("min_distance_m", self.min_distance_m)?;
        crate::check::finite("speed_m_s", self.speed_m_s)?;
        if self.min_distance_m > self.start_distance_m {
            return Err(Error::invalid(
                "min_distance_m",
                "must not exceed start_distance_m",
            ));
        }
        if self.policies.is_empty() {
            return Err(Error::invalid("policies", "at least one policy is needed"));
        }
        if self.gyro.is_none() && self.walks.is_empty() {
            return Err(Error::invalid(
                "walks",
                "at least one walk mode (or a gyro log) is needed",
            ));
        }
        if self.resolution[0] == 0 || self.resolution[1] == 0 {
            return Err(Error::invalid("resolution", "must be positive"));
        }
        // The strings, parsed now so that a bad one is reported with its key
        // before any work.
        let key = |k: &str, e: Error| Error::invalid(k.to_string(), e.to_string());
        for p in &self.policies {
            crate::trigger::parse_policy(p).map_err(|e| key("policies", e))?;
        }
        if self.gyro.is_none() {
            for w in &self.walks {
                w.parse::<crate::sim::Gait>().map_err(|e| key("walks", e))?;
            }
        }
        self.quality
            .parse::<crate::render::Quality>()
            .map_err(|e| key("quality", e))?;
        crate::render::Target::parse(&self.target, self.start_distance_m)
            .map_err(|e| key("target", e))?;
        for &e in &self.sweep_exposures_s {
            positive("sweep_exposures_s", e)?;
        }
        self.camera().validate().map_err(|e| key("camera", e))?;
        Ok(())
    }

    /// The camera: thesis focal length and pitch at `resolution`, with the
    /// `[camera]` section's keys over it ([`CameraFile::thesis_at`]).
    pub fn camera(&self) -> crate::camera::Camera {
        self.camera.thesis_at(self.resolution)
    }

    /// The configuration as TOML (written into the report).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# could not serialise: {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_camera_fills_the_range_at_the_nominal_exposure() {
        let d = ExperimentConfig::demo();
        let n = d.camera.noise.expect("the demo has sensor noise");
        // White: 20,000 e-/s x 70 ms = 1,400 e-, times the gain = 255 DN.
        let white = n.phi_e_per_s * d.exposure_s * n.gain();
        assert!((white - n.max_dn()).abs() < 1e-9, "{white}");
        assert!(n.validate().is_ok());
        // The ideal camera stays the experiment's default.
        assert!(ExperimentConfig::default().camera.noise.is_none());
        assert_eq!(ExperimentConfig::demo_full().camera.noise, Some(n));
    }

    #[test]
    fn camera_sections_give_the_camera_they_always_gave() {
        // The keys a `[camera]` section had before it was the camera file's schema.
        let cfg: ExperimentConfig = toml::from_str(
            "resolution = [320, 240]\n[camera]\nreadout_s = 0.012\n\
             readout_direction = \"bottom-to-top\"\n\
             [camera.distortion]\nmodel = \"fisheye\"\nk1 = 0.03\n\
             [camera.noise]\nphi_e_per_s = 20000\n[camera.lens]\nf_number = 2\nfocus_m = 3\n",
        )
        .unwrap();
        let mut want = crate::camera::Camera::thesis().with_resolution(320, 240);
        want.shutter.readout_s = 0.012;
        want.shutter.direction = crate::camera::Readout::BottomToTop;
        want.distortion = crate::camera::Distortion::Fisheye {
            k1: 0.03,
            k2: 0.0,
            k3: 0.0,
            k4: 0.0,
        };
        want.noise = Some(Noise::at_light(20_000.0));
        want.lens = Some(crate::camera::Lens {
            f_number: 2.0,
            focus_m: 3.0,
        });
        assert_eq!(cfg.camera(), want);
        assert!(cfg.validate().is_ok());
        // The camera file's other keys work there too, and the written
        // configuration reads back to the same camera.
        let other: ExperimentConfig =
            toml::from_str("[camera]\nfocal_mm = 3.5\npitch_mm = 0.003\n").unwrap();
        assert_eq!(other.camera().focal_mm, 3.5);
        assert_eq!(other.camera().pitch_y_mm, 0.003);
        for c in [
            cfg,
            other,
            ExperimentConfig::demo(),
            ExperimentConfig::default(),
        ] {
            let back: ExperimentConfig = toml::from_str(&c.to_toml()).unwrap();
            assert_eq!(back.camera(), c.camera());
        }
    }
}
