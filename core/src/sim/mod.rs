//! Seeded simulation of a hexapod's (SensoRHex-like) straight walk: a gyro log
//! in the camera frame (x right, y down, z forward), docs/spec.md section 7.
//!
//! # Model
//!
//! The robot walks with an alternating tripod gait. One **step** is the stance
//! of one tripod and starts with its **touchdown**; consecutive steps alternate
//! the tripod side `s_k = +1, -1, +1, ...`. RHex's legs follow an open-loop
//! gait clock of period `P = 1 / step_hz`, so touchdowns scatter around the
//! clock ticks without drifting: step `k` starts at
//! `T_k = T_0 + (k + touchdown_jitter * N_k) * P` (`N_k` clamped to +-3), and
//! lasts `P_k = T_{k+1} - T_k` (cycle-to-cycle period jitter of relative std
//! `sqrt(2) * touchdown_jitter`). Its amplitude factor is
//! `a_k = max(0, 1 + amplitude_jitter * M_k)`; `N_k, M_k` are independent
//! standard normals. The step phase is `p = (t - T_k) / P_k` in `[0, 1)`.
//!
//! Body angular velocity on axis `j` (0 = `wx` pitch, 1 = `wy` yaw about the
//! downward axis, 2 = `wz` roll about the optical axis), rad/s:
//!
//! ```text
//! w_j(t) = a_k * sgn_j(k) * sway[j] * sin(2 pi p + sway_phase[j])       smooth body sway
//!        + sum over the touchdowns i <= k of
//!          a_i * sgn_j(i) * touchdown[j] * g(t - T_i)                    touchdown transients
//!        + bias[j] + noise_std * white normal noise                      gyro error
//! g(tau) = exp(-tau / touchdown_decay_s) * sin(2 pi touchdown_freq_hz tau) / g_peak
//! ```
//!
//! `sgn_j(k)` is the tripod side `s_k` for the axes with `alternate[j] = true`
//! (roll and yaw: the left and right tripods tip the body opposite ways) and
//! `+1` otherwise (pitch). `g` is a damped oscillation normalised to a first
//! peak of 1 (`g_peak` is its first maximum), so `touchdown[j]` is the peak
//! angular rate of a transient (rad/s); it rises within a few tens of
//! milliseconds of touchdown (a sharp transient) and rings down. Transients
//! older than `12 * touchdown_decay_s` are dropped (below 1e-5 of the peak).
//! The first touchdown is at a seeded random time in `[-P, 0)`, so runs with
//! different seeds start at different gait phases.
//!
//! Linear velocity (m/s, camera frame): forward `vz = speed_m_s * (1 + surge *
//! cos(2 pi p))` and a vertical bob `y(t) = bob_m * cos(2 pi p)` (y down), so
//! `vy = -bob_m * 2 pi / P_k * sin(2 pi p)`; `vx = 0`.
//!
//! Randomness: `rand::rngs::StdRng::seed_from_u64(seed)`; the same seed,
//! configuration, duration and rate give the same log bit for bit (for a given
//! build of this crate and its locked dependencies).
//!
//! # Calibration
//!
//! The presets are tuned so that the rotation-only MMBM (thesis camera, 8 x 6
//! grid) behaves like the thesis's SensoRHex (chapters 5-6): the moderate walk
//! peaks near 2 mm/s at touchdown and spends a large share of time below
//! 0.4 mm/s (thesis Table 6.2: at threshold 0.4 the moderate walk still gave
//! 3.5 fps), the slow walk is calmer, and the fast walk never settles below
//! about 0.4 mm/s (the thesis got no frames at thresholds 0.4 and 0.2 there).
//! `tests/trigger/sim.rs` checks the moderate targets; the report of the project lists
//! the measured figures for all three.

mod gen;

pub use gen::{samples, simulate, write_log, write_samples, Samples, LOG_HEADER, MAX_SAMPLES};

/// Highest step rate of a gait, steps/s (legged gaits take a few).
pub const MAX_STEP_HZ: f64 = 100.0;

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// The three walking speeds of the thesis experiment (chapter 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Gait {
    /// 0.085 m/s.
    Slow,
    /// 0.17 m/s.
    Moderate,
    /// 0.53 m/s.
    Fast,
}

impl FromStr for Gait {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "slow" => Ok(Gait::Slow),
            "moderate" => Ok(Gait::Moderate),
            "fast" => Ok(Gait::Fast),
            _ => Err(Error::invalid(
                "gait",
                format!("'{s}': expected slow, moderate or fast"),
            )),
        }
    }
}

impl fmt::Display for Gait {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Gait::Slow => "slow",
            Gait::Moderate => "moderate",
            Gait::Fast => "fast",
        })
    }
}

/// Every parameter of the gait model (see the module docs for the equations).
/// Axis arrays are `[wx, wy, wz]` = `[pitch, yaw, roll]` in the camera frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitConfig {
    /// Mean forward speed, m/s (thesis: 0.085, 0.17, 0.53).
    pub speed_m_s: f64,
    /// Touchdowns (steps) per second; a full stride is two steps.
    pub step_hz: f64,
    /// Standard deviation of each touchdown's time about the gait clock, as a
    /// fraction of the step period (0 ..= 0.15).
    pub touchdown_jitter: f64,
    /// Relative standard deviation of each step's amplitude factor.
    pub amplitude_jitter: f64,
    /// Amplitude of the smooth per-step body sway, rad/s, per axis.
    pub sway: [f64; 3],
    /// Phase of the sway sine at touchdown, radians, per axis.
    pub sway_phase: [f64; 3],
    /// Axes whose sway and transient change sign with the tripod side.
    pub alternate: [bool; 3],
    /// Peak angular rate of a touchdown transient, rad/s, per axis.
    pub touchdown: [f64; 3],
    /// Decay time constant of the touchdown transient, s.
    pub touchdown_decay_s: f64,
    /// Ringing frequency of the touchdown transient, Hz.
    pub touchdown_freq_hz: f64,
    /// Gyro white-noise standard deviation per sample and axis, rad/s.
    pub noise_std: f64,
    /// Constant gyro bias, rad/s, per axis.
    pub bias: [f64; 3],
    /// Vertical bob amplitude (peak), m.
    pub bob_m: f64,
    /// Relative amplitude of the forward-speed oscillation within a step.
    pub surge: f64,
}

impl GaitConfig {
    /// The calibrated preset for one of the thesis speeds.
    pub fn preset(g: Gait) -> Self {
        match g {
            Gait::Slow => GaitConfig {
                speed_m_s: 0.085,
                step_hz: 0.9,
                touchdown_jitter: 0.03,
                amplitude_jitter: 0.15,
                sway: [0.12, 0.05, 0.10],
                sway_phase: [0.0, 0.7, 0.0],
                alternate: [false, true, true],
                touchdown: [0.30, 0.08, 0.20],
                touchdown_decay_s: 0.05,
                touchdown_freq_hz: 6.0,
                noise_std: 0.003,
                bias: [0.002, -0.0015, 0.001],
                bob_m: 0.003,
                surge: 0.3,
            },
            Gait::Moderate => GaitConfig {
                speed_m_s: 0.17,
                step_hz: 1.25,
                touchdown_jitter: 0.03,
                amplitude_jitter: 0.15,
                sway: [0.12, 0.06, 0.10],
                sway_phase: [0.0, 1.2, 0.0],
                alternate: [false, true, true],
                touchdown: [0.42, 0.12, 0.25],
                touchdown_decay_s: 0.05,
                touchdown_freq_hz: 6.0,
                noise_std: 0.003,
                bias: [0.002, -0.0015, 0.001],
                bob_m: 0.005,
                surge: 0.3,
            },
            Gait::Fast => GaitConfig {
                speed_m_s: 0.53,
                step_hz: 2.6,
                touchdown_jitter: 0.03,
                amplitude_jitter: 0.1,
                sway: [0.18, 0.17, 0.12],
                sway_phase: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
                alternate: [false, false, true],
                touchdown: [0.45, 0.15, 0.30],
                touchdown_decay_s: 0.04,
                touchdown_freq_hz: 5.0,
                noise_std: 0.003,
                bias: [0.002, -0.0015, 0.001],
                bob_m: 0.008,
                surge: 0.3,
            },
        }
    }

    /// Checks every parameter (finite; rates, times and scales positive or
    /// non-negative as their meaning requires), naming the bad one.
    pub fn validate(&self) -> Result<()> {
        let nonneg = |what: &str, x: f64| -> Result<()> {
            crate::check::finite(what, x)?;
            if x < 0.0 {
                return Err(Error::invalid(what, format!("must be >= 0, got {x}")));
            }
            Ok(())
        };
        nonneg("speed_m_s", self.speed_m_s)?;
        crate::check::positive("step_hz", self.step_hz)?;
        if self.step_hz > MAX_STEP_HZ {
            return Err(Error::invalid(
                "step_hz",
                format!("must be <= {MAX_STEP_HZ} steps/s, got {}", self.step_hz),
            ));
        }
        nonneg("touchdown_jitter", self.touchdown_jitter)?;
        if self.touchdown_jitter > 0.15 {
            return Err(Error::invalid(
                "touchdown_jitter",
                format!(
                    "must be <= 0.15 (steps stay in order), got {}",
                    self.touchdown_jitter
                ),
            ));
        }
        nonneg("amplitude_jitter", self.amplitude_jitter)?;
        for j in 0..3 {
            nonneg(&format!("sway[{j}]"), self.sway[j])?;
            crate::check::finite(&format!("sway_phase[{j}]"), self.sway_phase[j])?;
            nonneg(&format!("touchdown[{j}]"), self.touchdown[j])?;
            crate::check::finite(&format!("bias[{j}]"), self.bias[j])?;
        }
        crate::check::positive("touchdown_decay_s", self.touchdown_decay_s)?;
        crate::check::positive("touchdown_freq_hz", self.touchdown_freq_hz)?;
        nonneg("noise_std", self.noise_std)?;
        nonneg("bob_m", self.bob_m)?;
        nonneg("surge", self.surge)?;
        Ok(())
    }

    /// Parses a TOML document over the preset `base`: keys present in the file
    /// replace the preset's, unknown keys are an error. A top-level key
    /// `gait = "slow" | "moderate" | "fast"` in the file picks the base preset
    /// instead of `base`. `path` is only used in error messages.
    pub fn from_toml_str(text: &str, base: Gait, path: &Path) -> Result<Self> {
        let cfg_err = |m: String| Error::Config {
            path: path.into(),
            message: m,
        };
        let mut file: toml::Table = text.parse().map_err(|e| cfg_err(format!("{e}")))?;
        let base = match file.remove("gait") {
            Some(toml::Value::String(s)) => s.parse::<Gait>()?,
            Some(v) => return Err(cfg_err(format!("'gait' must be a string, got {v}"))),
            None => base,
        };
        let mut table =
            toml::Table::try_from(GaitConfig::preset(base)).map_err(|e| cfg_err(format!("{e}")))?;
        for (k, v) in file {
            table.insert(k, v);
        }
        let cfg: GaitConfig = toml::Value::Table(table)
            .try_into()
            .map_err(|e: toml::de::Error| cfg_err(e.to_string()))?;
        cfg.validate()
            .map_err(|e| cfg_err(format!("after applying the file: {e}")))?;
        Ok(cfg)
    }

    /// Loads a TOML file over the preset `base` (see [`GaitConfig::from_toml_str`]).
    pub fn load(path: &Path, base: Gait) -> Result<Self> {
        let text = crate::io::input::read_text(path)?;
        Self::from_toml_str(&text, base, path)
    }

    /// The configuration as TOML (every parameter).
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::invalid("gait config", e.to_string()))
    }
}
