//! Experiment configuration (TOML). Every field has a default; the defaults
//! are the thesis setup (chapter 6): 640 x 480, f = 4.2548 mm, 70 ms exposure,
//! the blob board walked towards from 6 m, the thesis policies and their
//! successors.

use super::config_policies::builtin;
use crate::camera::{CameraFile, Noise};
use crate::error::{Error, Result};
use crate::trigger::{CameraTiming, PolicySpec};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The experiment's configuration.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExperimentConfig {
    /// Walk modes to simulate: `slow`, `moderate`, `fast` (ignored with `gyro`).
    pub walks: Vec<String>,
    /// Simulated duration of every walk, s; unset: each gait's thesis walk
    /// time from `walk_s`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    /// Each gait's walk time, s, when `duration_s` is unset: the thesis's
    /// (Table 6.2: about 3 m at 0.085 / 0.17 / 0.53 m/s).
    pub walk_s: WalkTimes,
    /// Gyro rate of the simulation, Hz.
    pub rate_hz: f64,
    /// Simulation seed.
    pub seed: u64,
    /// Several simulation seeds (each walk simulated once per seed; the
    /// headline pools them). Empty: `seed` alone.
    pub seeds: Vec<u64>,
    /// A real gyro log (CSV of docs/spec.md section 5) instead of the simulation.
    pub gyro: Option<PathBuf>,
    /// Forward speed (m/s) used for the target distance when the log has no velocity.
    pub speed_m_s: f64,
    /// Trigger policies, written as `mmbm trigger --policy` strings; each
    /// parsed once as the file is read (a bad one refused there, naming
    /// `policies` and the entry).
    #[serde(deserialize_with = "super::config_policies::policies")]
    pub policies: Vec<PolicySpec>,
    /// Exposure, s.
    pub exposure_s: f64,
    /// Trigger delay, s.
    pub delay_s: f64,
    /// Readout, s.
    pub readout_s: f64,
    /// Minimum interval between MMBM triggers, s.
    pub min_interval_s: f64,
    /// Target: `blobs:0.5` (half size, thesis Table 6.2; the default) or `blobs` (the thesis board).
    pub target: String,
    /// Distance to the target at t = 0, m (the walk approaches it).
    pub start_distance_m: f64,
    /// Closest allowed distance, m (the walk stops approaching there).
    pub min_distance_m: f64,
    /// What is behind the board, in its plane: `none` (the thesis's plain
    /// grey) or `poster` (the procedural CC0 texture of
    /// [`crate::render::poster`]: clutter for blob extraction, corners for
    /// the repeatability metric). The demo keeps `none` (its time with the
    /// poster is not yet measured).
    pub background: String,
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
    /// real camera of docs/spec.md section 9 (`readout_s`, `readout_direction`,
    /// `[camera.distortion]`, `[camera.noise]`, `[camera.lens]`; all off by
    /// default: the thesis's ideal global-shutter pinhole).
    pub camera: CameraFile,
    /// The benefit map of docs/spec.md section 10 (off unless `lights_e_per_s` is set).
    pub map: MapSection,
}

/// The policies of `mmbm demo`'s experiment (`demo --full`'s too): the
/// thesis's Table 6.2 (the fixed rate and its three thresholds), the learned
/// phase predictor and its oracle, and trigger timing with exposure control.
pub const DEMO_POLICIES: [&str; 7] = [
    "fixed:5",
    "threshold:0.8",
    "threshold:0.4",
    "threshold:0.2",
    "phase:0.4",
    "oracle:0.4",
    "deadline:5+exp:3:0.02",
];

/// The `[map]` section: the benefit map over light x gait x board.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapSection {
    /// The light levels (rows), e-/s for a white pixel; empty: no map.
    pub lights_e_per_s: Vec<f64>,
    /// Gaits (columns); empty: the experiment's `walks` (none when the
    /// experiment has a `gyro` log).
    pub gaits: Vec<String>,
    /// Gyro logs, each a column of the map beside the gaits, named by its
    /// file stem (any format `mmbm::telemetry::read_gyro` reads; paths as
    /// given, relative to the working directory); the experiment's `gyro`
    /// log is one too. The seeds change only the noise of a log's frames.
    pub logs: Vec<PathBuf>,
    /// Boards (columns, with the gaits): `blobs:0.5`, `blobs`.
    pub boards: Vec<String>,
    /// Seeds (at least 5 for the goals); empty: the experiment's seeds.
    pub seeds: Vec<u64>,
    /// The policies besides the baselines' grid: the gyro-driven candidates
    /// (the best `mmbm` one is taken per cell) and the auto-exposure(s);
    /// parsed as the file is read (a bad one refused naming `map.policies`).
    #[serde(deserialize_with = "super::config_policies::map_policies")]
    pub policies: Vec<PolicySpec>,
    /// The frame rate of `fixed` and of the fixed-exposure grid, frames/s.
    pub fps: f64,
    /// The fixed exposures of the best fixed exposure in hindsight, ms (at
    /// most the experiment's `exposure_s`; that one is `fixed:FPS` itself).
    pub grid_ms: Vec<f64>,
    /// The sensor's maximum gain, in units of the full-well gain
    /// `(2^bits - 1) / full_well` (256 = 48 dB; an assumption).
    pub max_gain_x: f64,
}

impl Default for MapSection {
    fn default() -> Self {
        MapSection {
            lights_e_per_s: Vec::new(),
            gaits: Vec::new(),
            logs: Vec::new(),
            boards: vec!["blobs:0.5".into(), "blobs".into()],
            seeds: Vec::new(),
            policies: builtin(&[
                "deadline:5+exp:3:0.02",
                "deadline:5+exp:1:0.003",
                "fixed:5+exp:2:0.02",
                "deadline:5",
                "task:5:light=1000",
                "task:5:light=4000",
                "task:5:light=20000",
                "ae:5:cap=10ms",
                "ae:5:cap=3ms",
                "ae-grad:5:cap=10ms",
                "ae-blur:5:1",
                "ae-imu:5",
            ]),
            fps: 5.0,
            grid_ms: vec![
                1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 14.0, 20.0, 28.0, 40.0, 56.0, 70.0,
            ],
            max_gain_x: 256.0,
        }
    }
}

impl MapSection {
    /// The whole map of `mmbm demo --full`: light 500 to 100,000 e-/s.
    pub fn full() -> Self {
        MapSection {
            lights_e_per_s: vec![500.0, 1_000.0, 2_000.0, 4_000.0, 20_000.0, 100_000.0],
            gaits: ["slow", "moderate", "fast"].map(String::from).to_vec(),
            seeds: (1..=5).collect(),
            ..Self::default()
        }
    }

    /// The reduced map of `mmbm demo`: the half board on the moderate walk,
    /// seeds 1-5, four lights, a coarser grid (3, 10, 20, 70 ms), five
    /// trigger-timing candidates (`deadline:5` with and without exposure
    /// control, the predicted task success at three stated lights), the
    /// blur-capped auto-exposure (`gyro-exposure`, the bar for timing) and
    /// one motion-blind auto-exposure.
    pub fn reduced() -> Self {
        MapSection {
            lights_e_per_s: vec![1_000.0, 4_000.0, 20_000.0, 100_000.0],
            gaits: vec!["moderate".into()],
            boards: vec!["blobs:0.5".into()],
            seeds: (1..=5).collect(),
            policies: builtin(&[
                "deadline:5",
                "deadline:5+exp:3:0.02",
                "task:5:light=1000",
                "task:5:light=4000",
                "task:5:light=20000",
                "ae-blur:5:1",
                "ae:5:cap=10ms",
            ]),
            grid_ms: vec![3.0, 10.0, 20.0, 70.0],
            ..Self::default()
        }
    }

    /// Refuses a list over [`crate::limits::MAX_LIST_ENTRIES`], naming its key.
    fn check_lengths(&self) -> Result<()> {
        use crate::limits::{check_len, MAX_LIST_ENTRIES as MAX};
        check_len("map.lights_e_per_s", self.lights_e_per_s.len(), MAX)?;
        check_len("map.gaits", self.gaits.len(), MAX)?;
        check_len("map.logs", self.logs.len(), MAX)?;
        check_len("map.boards", self.boards.len(), MAX)?;
        check_len("map.policies", self.policies.len(), MAX)?;
        check_len("map.grid_ms", self.grid_ms.len(), MAX)
    }

    /// Checks the section (each light positive and at most
    /// [`crate::limits::MAX_LIGHT_E_PER_S`], exposure and gain positive, the
    /// lists at most [`crate::limits::MAX_LIST_ENTRIES`] long, the strings
    /// parse); `max_exposure_s` is the experiment's exposure.
    pub fn validate(&self, max_exposure_s: f64) -> Result<()> {
        use crate::check::positive;
        let key = |k: &str, e: Error| Error::invalid(format!("map.{k}"), e.to_string());
        if self.lights_e_per_s.is_empty() {
            return Ok(());
        }
        self.check_lengths()?;
        for &l in &self.lights_e_per_s {
            crate::limits::check_light("map.lights_e_per_s", l)?;
        }
        positive("[map] fps", self.fps)?;
        if self.fps > crate::trigger::MAX_FPS {
            return Err(Error::invalid(
                "[map] fps",
                format!(
                    "{} frames/s is above the limit of {} frames/s (the trigger policies' cap)",
                    self.fps,
                    crate::trigger::MAX_FPS
                ),
            ));
        }
        positive("map.max_gain_x", self.max_gain_x)?;
        if self.grid_ms.is_empty() {
            return Err(Error::invalid(
                "map.grid_ms",
                "at least one exposure is needed",
            ));
        }
        for &t in &self.grid_ms {
            positive("map.grid_ms", t)?;
            if t * 1e-3 > max_exposure_s * (1.0 + 1e-9) {
                return Err(Error::invalid(
                    "map.grid_ms",
                    format!(
                        "{t} ms is longer than exposure_s ({} ms)",
                        max_exposure_s * 1e3
                    ),
                ));
            }
        }
        if self.boards.is_empty() {
            return Err(Error::invalid("map.boards", "at least one board is needed"));
        }
        for b in &self.boards {
            crate::render::Target::parse(b, 6.0).map_err(|e| key("boards", e))?;
        }
        for g in &self.gaits {
            g.parse::<crate::sim::Gait>().map_err(|e| key("gaits", e))?;
        }
        let mut seeds = self.seeds.clone();
        seeds.sort_unstable();
        seeds.dedup();
        if seeds.len() != self.seeds.len() || seeds.len() > 100 {
            return Err(Error::invalid(
                "map.seeds",
                format!("{:?}: at most 100 seeds, each once", self.seeds),
            ));
        }
        Ok(())
    }
}

/// The walk time of each gait, s (`[walk_s]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WalkTimes {
    /// Slow walk, s (thesis: 35).
    pub slow: f64,
    /// Moderate walk, s (thesis: 16).
    pub moderate: f64,
    /// Fast walk, s (thesis: 5).
    pub fast: f64,
}

impl Default for WalkTimes {
    fn default() -> Self {
        WalkTimes {
            slow: 35.0,
            moderate: 16.0,
            fast: 5.0,
        }
    }
}

impl WalkTimes {
    /// The walk time of `gait`, s.
    pub fn of(&self, gait: crate::sim::Gait) -> f64 {
        match gait {
            crate::sim::Gait::Slow => self.slow,
            crate::sim::Gait::Moderate => self.moderate,
            crate::sim::Gait::Fast => self.fast,
        }
    }
}

impl Default for ExperimentConfig {
    fn default() -> Self {
        ExperimentConfig {
            walks: vec!["moderate".into()],
            duration_s: None,
            walk_s: WalkTimes::default(),
            rate_hz: 600.0,
            seed: 1,
            seeds: Vec::new(),
            gyro: None,
            speed_m_s: 0.17,
            policies: builtin(&[
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
            ]),
            exposure_s: CameraTiming::DEFAULT_EXPOSURE_S,
            delay_s: CameraTiming::DEFAULT_DELAY_S,
            readout_s: CameraTiming::DEFAULT_READOUT_S,
            min_interval_s: CameraTiming::DEFAULT_MIN_INTERVAL_S,
            target: "blobs:0.5".into(),
            background: "none".into(),
            start_distance_m: 6.0,
            min_distance_m: 1.5,
            resolution: [640, 480],
            quality: "default".into(),
            max_frames_per_policy: 0,
            sweep_exposures_s: vec![0.01, 0.02, 0.035, 0.05, 0.07],
            sweep_frames: 12,
            camera: CameraFile::default(),
            map: MapSection::default(),
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

    /// The simulated duration of a walk of `gait`, s: `duration_s`, else the gait's `walk_s`.
    pub fn walk_duration_s(&self, gait: crate::sim::Gait) -> f64 {
        self.duration_s.unwrap_or_else(|| self.walk_s.of(gait))
    }

    /// The `mmbm demo --full` configuration: the demo's own frames (its
    /// policies, its seed, its moderate walk, judged whole) and the whole
    /// benefit map ([`MapSection::full`]: three gaits, both boards, six lights,
    /// seeds 1 to 5), whose cell at the demo's light, gait and board is the
    /// headline. The experiment's own frames feed only the ground-truth blur
    /// tables and figures, so they are rendered for one seed and one walk.
    /// Rendered at the `fast` preset (0.5 px between instants, not 0.25):
    /// less time for the map (docs/performance.md), at a render difference the
    /// report measures (its render-quality note, without sensor noise: 0.02/255
    /// on average and 0.16/255 at the 99th percentile on the demo's most
    /// blurred frame), far below the sensor noise of any of the map's lights.
    pub fn demo_full() -> Self {
        ExperimentConfig {
            map: MapSection::full(),
            quality: "fast".into(),
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
    /// range in the 70 ms exposure (255 DN / 1,400 e- = 0.182 DN/e-); the
    /// poster behind the board (`background = "poster"`: clutter for blob
    /// extraction, corners for the second task metric).
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
            map: MapSection::reduced(),
            policies: builtin(&DEMO_POLICIES),
            // The map's fixed-exposure grid replaces the exposure sweep.
            sweep_exposures_s: Vec::new(),
            // Clutter for blob extraction and corners for the second task
            // metric (docs/spec.md section 10): the poster behind the board.
            background: "poster".into(),
            ..d
        }
    }

    /// The target `spec` at `distance` m with this experiment's [`Self::background`].
    pub fn scene_target(&self, spec: &str, distance: f64) -> Result<crate::render::Target> {
        let mut t = crate::render::Target::parse(spec, distance)?;
        t.surround = self.background.parse()?;
        Ok(t)
    }

    /// Loads a TOML file; missing fields take the defaults.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::io::input::read_text(path)?;
        let cfg: Self = toml::from_str(&text).map_err(|e| Error::Config {
            path: path.into(),
            message: super::config_policies::one_line(&e, &text),
        })?;
        cfg.validate().map_err(|e| Error::Config {
            path: path.into(),
            message: e.to_string(),
        })?;
        Ok(cfg)
    }

    /// Checks ranges (times positive, distances positive and ordered, a
    /// policy at least, lists at most [`crate::limits::MAX_LIST_ENTRIES`]).
    pub fn validate(&self) -> Result<()> {
        use crate::check::positive;
        use crate::limits::{check_len, MAX_LIST_ENTRIES as MAX};
        // The lists' lengths first: nothing is sized or walked by them before.
        check_len("policies", self.policies.len(), MAX)?;
        check_len("walks", self.walks.len(), MAX)?;
        check_len("sweep_exposures_s", self.sweep_exposures_s.len(), MAX)?;
        if let Some(d) = self.duration_s {
            positive("duration_s", d)?;
        }
        positive("walk_s.slow", self.walk_s.slow)?;
        positive("walk_s.moderate", self.walk_s.moderate)?;
        positive("walk_s.fast", self.walk_s.fast)?;
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
        // before any work (the policies were parsed as they were read).
        let key = |k: &str, e: Error| Error::invalid(k.to_string(), e.to_string());
        if self.gyro.is_none() {
            for w in &self.walks {
                w.parse::<crate::sim::Gait>().map_err(|e| key("walks", e))?;
            }
        }
        self.quality
            .parse::<crate::render::Quality>()
            .map_err(|e| key("quality", e))?;
        // The error names the key (`background`).
        self.background.parse::<crate::render::Background>()?;
        crate::render::Target::parse(&self.target, self.start_distance_m)
            .map_err(|e| key("target", e))?;
        for &e in &self.sweep_exposures_s {
            positive("sweep_exposures_s", e)?;
        }
        self.camera().validate().map_err(|e| key("camera", e))?;
        self.map.validate(self.exposure_s)?;
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
    fn background_key_is_checked_and_reaches_the_target() {
        let d = ExperimentConfig {
            background: "poster".into(),
            ..ExperimentConfig::demo()
        };
        assert_eq!(ExperimentConfig::demo().background, "poster");
        assert_eq!(ExperimentConfig::demo_full().background, "poster");
        assert_eq!(ExperimentConfig::default().background, "none");
        let t = d.scene_target("blobs:0.5", 6.0).unwrap();
        assert_eq!(t.surround, crate::render::Background::Poster);
        let bad = ExperimentConfig {
            background: "bricks".into(),
            ..ExperimentConfig::default()
        };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("background") && e.contains("bricks"), "{e}");
    }

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
