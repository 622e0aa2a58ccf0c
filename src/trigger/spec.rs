//! The typed policy ([`PolicySpec`]): what a policy string is parsed into
//! (`parse.rs`), what a built policy reports ([`super::Policy::spec`]) and
//! every frame carries ([`super::Frame::policy`]). Data only: it imports
//! none of the policies, which import it.

use super::ae_params::{AeParams, AeVariant};
use super::family::{Family, PolicyFamily};
use super::level::Level;
use super::task_model::TaskModel;
use std::sync::Arc;

/// A frame rate with its phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rate {
    /// Frames per second, in `(0, MAX_FPS]`.
    pub fps: f64,
    /// Offset of the first slot after the log's start, s (`@PHASE`; 0 when not given).
    pub phase: f64,
}

/// Exposure control (`+exp:B[:TMIN]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExposureControl {
    /// Blur budget, px.
    pub budget_px: f64,
    /// Shortest exposure, s.
    pub min_exposure_s: f64,
}

/// A policy string parsed once: what the experiment, the figures, the report,
/// `live` and Python ask of a policy without re-reading its text.
///
/// It owns the string it was parsed from (shared: a clone is cheap), which
/// [`Self::as_str`], `Display` and serde write back unchanged; serde reads
/// and writes a spec as that string, refusing a bad one while deserialising.
#[derive(Debug, Clone, PartialEq)]
pub struct PolicySpec {
    /// The string exactly as given.
    pub(super) text: Arc<str>,
    /// Length of the part before `+exp` (the whole string without it).
    pub(super) base_len: usize,
    /// The family.
    pub family: Family,
    /// The frame rate: the schedule's (`fixed`, `gate`, `gate0`, `deadline`;
    /// 5 fps when a gate gives none) or the target (`adaptive`, default 2.5).
    pub rate: Option<Rate>,
    /// The MMBM threshold (every family but `fixed`; optional for `deadline`).
    pub threshold: Option<Level>,
    /// The forecast horizon, s (`oracle`, `forecast`, `phase`; default 0.2).
    pub horizon: Option<f64>,
    /// Exposure control, when the string ends in `+exp:B[:TMIN]`.
    pub exposure: Option<ExposureControl>,
    /// The fixed exposure of `fixed:FPS@Tms`, s.
    pub fixed_exposure_s: Option<f64>,
    /// The auto-exposure of `ae:...` and `ae-*:...`.
    pub ae: Option<AeParams>,
    /// What an `ae-*` policy adds to the auto-exposure (`None` for `ae:`).
    pub ae_variant: Option<AeVariant>,
    /// The success model of `task:...` (with its stated light).
    pub task: Option<TaskModel>,
}

impl PolicySpec {
    /// The string exactly as given (the `policy` column).
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// The family of docs/spec.md section 10 (the benefit map's grouping).
    pub fn policy_family(&self) -> PolicyFamily {
        if self.family == Family::Custom {
            PolicyFamily::Custom
        } else if !self.is_causal() {
            PolicyFamily::Oracle
        } else if self.ae_variant.is_some_and(|v| v.reads_gyro()) {
            PolicyFamily::GyroExposure
        } else if self.ae.is_some() {
            PolicyFamily::AutoExposure
        } else if self.fixed_exposure_s.is_some() {
            PolicyFamily::FixedExposure
        } else if self.is_baseline() {
            PolicyFamily::Fixed
        } else if self.family == Family::Fixed {
            // The fixed rate with `+exp`: exposure from the gyro, no timing.
            PolicyFamily::GyroExposure
        } else {
            PolicyFamily::Mmbm
        }
    }

    /// False for the policies that use knowledge of the future (the oracle).
    pub fn is_causal(&self) -> bool {
        self.family != Family::Oracle
    }

    /// True for a plain fixed-rate policy (`fixed:FPS[@PHASE]`), the baseline
    /// the others are compared with; `fixed:5+exp:2` (exposure control) is not.
    pub fn is_baseline(&self) -> bool {
        self.family == Family::Fixed && self.exposure.is_none() && self.fixed_exposure_s.is_none()
    }

    /// True for the thesis's rule at its threshold ([`THESIS_POLICY`](super::THESIS_POLICY), no exposure control).
    pub fn is_thesis_rule(&self) -> bool {
        self.family == Family::Threshold
            && self.threshold == Some(Level::Abs(0.4))
            && self.exposure.is_none()
    }

    /// The threshold in mm/s when it is one (not a percentile).
    pub fn threshold_mm_s(&self) -> Option<f64> {
        match self.threshold {
            Some(Level::Abs(x)) => Some(x),
            _ => None,
        }
    }

    /// The spec of a user's own policy, known by its label only (the
    /// default [`Policy::spec`](super::Policy::spec)): family
    /// [`Family::Custom`] (benefit-map family `custom`), no rate, threshold
    /// or exposure; `Display` and [`Self::as_str`] give `label` unchanged.
    /// [`Self::build`] refuses it, and no policy string parses to it.
    ///
    /// ```
    /// use mmbm::trigger::{Family, PolicySpec};
    /// let c = PolicySpec::custom("my-rule:3");
    /// assert_eq!((c.family, c.to_string()), (Family::Custom, "my-rule:3".into()));
    /// assert!(c.build().is_err());
    /// ```
    pub fn custom(label: &str) -> Self {
        PolicySpec {
            text: label.into(),
            base_len: label.len(),
            family: Family::Custom,
            rate: None,
            threshold: None,
            horizon: None,
            exposure: None,
            fixed_exposure_s: None,
            ae: None,
            ae_variant: None,
            task: None,
        }
    }
}
