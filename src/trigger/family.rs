//! The two ways a policy is grouped: its rule ([`Family`], the name before
//! the first `:`) and its benefit-map family ([`PolicyFamily`], docs/spec.md
//! sections 10-11).

/// The family of a policy (its name before the first `:`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Family {
    /// `fixed:FPS[@PHASE]`.
    Fixed,
    /// `threshold:X`, the thesis rule.
    Threshold,
    /// `adaptive[:X[:FPS]]`.
    Adaptive,
    /// `oracle:X[:H]` (needs the future).
    Oracle,
    /// `forecast:X[:H]`.
    Forecast,
    /// `phase:X[:H]`.
    Phase,
    /// `gate:X[:FPS[@PHASE]]`.
    Gate,
    /// `gate0:X[:FPS[@PHASE]]`.
    Gate0,
    /// `deadline:FPS[:X]`.
    Deadline,
    /// `ae:FPS[...]`, motion-blind auto-exposure.
    Ae,
    /// `task:FPS:light=E[...]`, the predicted task success.
    Task,
    /// `ae-blur:FPS:B[...]`, auto-exposure capped at a gyro-predicted blur budget.
    AeBlur,
    /// `ae-imu:FPS[...]`, the IMU exposure/gain trade.
    AeImu,
    /// `ae-grad:FPS[...]`, gradient auto-exposure (motion-blind).
    AeGrad,
    /// A user's own policy, known by its label only (`PolicySpec::custom`);
    /// no policy string parses to it.
    Custom,
}

impl Family {
    /// The family's name as written in a policy string.
    pub fn name(self) -> &'static str {
        match self {
            Family::Fixed => "fixed",
            Family::Threshold => "threshold",
            Family::Adaptive => "adaptive",
            Family::Oracle => "oracle",
            Family::Forecast => "forecast",
            Family::Phase => "phase",
            Family::Gate => "gate",
            Family::Gate0 => "gate0",
            Family::Deadline => "deadline",
            Family::Ae => "ae",
            Family::Task => "task",
            Family::AeBlur => "ae-blur",
            Family::AeImu => "ae-imu",
            Family::AeGrad => "ae-grad",
            Family::Custom => "custom",
        }
    }

    pub(super) fn from_name(s: &str) -> Option<Self> {
        [
            Family::Fixed,
            Family::Threshold,
            Family::Adaptive,
            Family::Oracle,
            Family::Forecast,
            Family::Phase,
            Family::Gate,
            Family::Gate0,
            Family::Deadline,
            Family::Ae,
            Family::Task,
            Family::AeBlur,
            Family::AeImu,
            Family::AeGrad,
        ]
        .into_iter()
        .find(|f| f.name() == s)
    }
}

/// The family of docs/spec.md section 10, by which the benefit map groups the
/// policies (the `family` column of `frames.csv`). Not the rule ([`Family`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PolicyFamily {
    /// The thesis's fixed rate at the camera's exposure (`fixed:FPS[@PHASE]`).
    Fixed,
    /// A fixed rate at a fixed shorter exposure, gain raised (`fixed:FPS@Tms`).
    FixedExposure,
    /// Motion-blind auto-exposure (`ae:...`, `ae-grad:...`).
    AutoExposure,
    /// Fixed rate, exposure and gain from the gyro (`ae-blur`, `ae-imu`,
    /// `fixed:FPS[@PHASE]+exp:...`; docs/spec.md section 11).
    GyroExposure,
    /// Trigger timing from the gyro, with or without exposure control (MMBM
    /// rules, gates, `deadline`, `task`).
    Mmbm,
    /// Every non-causal one (the oracle; the best fixed exposure in hindsight).
    Oracle,
    /// A user's own policy ([`Family::Custom`]): its rule is unknown.
    Custom,
}

impl PolicyFamily {
    /// The family's name: `fixed`, `fixed-exposure`, `auto-exposure`,
    /// `gyro-exposure`, `mmbm`, `oracle`, `custom`.
    pub fn name(self) -> &'static str {
        match self {
            PolicyFamily::Fixed => "fixed",
            PolicyFamily::FixedExposure => "fixed-exposure",
            PolicyFamily::AutoExposure => "auto-exposure",
            PolicyFamily::GyroExposure => "gyro-exposure",
            PolicyFamily::Mmbm => "mmbm",
            PolicyFamily::Oracle => "oracle",
            PolicyFamily::Custom => "custom",
        }
    }
}

impl std::fmt::Display for PolicyFamily {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
