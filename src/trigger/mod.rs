//! Camera trigger policies driven by the MMBM of a gyro log (docs/spec.md section 6,
//! thesis chapters 5-6).
//!
//! # Timing model (thesis Fig. 5.1)
//!
//! A decision is made at a gyro sample `t_i` (the `trigger_t` of a frame).
//! The trigger pulse reaches the camera after the delay `t_d`; the exposure
//! runs over `[t_i + t_d, t_i + t_d + t_e]`; the readout `t_r` follows, after
//! which the camera is free again. A pulse is accepted only when the camera is
//! free at its arrival (`t_i + t_d >= previous exposure end + t_r`); the runner
//! enforces this for every policy. The minimum interval between triggers
//! (default 0.2 s, the thesis's fair comparison with 5 fps) is part of the
//! MMBM-triggered policies' rules (`threshold`, `adaptive`, `oracle`,
//! `forecast`), not of the schedules (`fixed`, `gate`, `deadline`), whose own
//! period spaces the frames. The run stops at the last sample whose exposure
//! still ends inside the log.
//!
//! # Exposure MMBM
//!
//! `mmbm_exposure_mm_s` is the time average over the exposure of the MMBM
//! series linearly interpolated between samples (held constant outside the
//! log), the quantity the instantaneous MMBM at the trigger tries to predict
//! (thesis section 5.2, Table 5.1). It is computed from a prefix integral, so
//! each frame costs two binary searches.
//!
//! # Policies
//!
//! Parsed by [`parse_policy`]; every threshold `X` may be a number (mm/s) or
//! `pNN`, the NN-th percentile (0..100, linear interpolation between order
//! statistics) of the whole log's MMBM series, resolved once before the run:
//! an offline calibration, like choosing the number by looking at the data;
//! the decision rule itself stays causal.
//!
//! | policy | rule |
//! |---|---|
//! | `fixed:FPS[@PHASE]` | trigger at the first sample at or after `t_0 + PHASE + k / FPS` (slots the busy camera cannot take are skipped) |
//! | `fixed:FPS[@PHASE]@Tms` | the same schedule, every frame exposed for `T` ms with the gain raised by the camera's exposure / `T` (see [`FixedExposure`]) |
//! | `ae:FPS[@PHASE][:cap=Tms][:target=F][:damp=F][:scene=F]` | the same schedule with a motion-blind auto-exposure (see [`AutoExposure`]) |
//! | `ae-blur:FPS[@PHASE]:B[:ae keys]` | the auto-exposure with its exposure capped where the gyro-predicted blur passes `B` px, the gain making up the light (family `gyro-exposure`; see [`BlurCappedAe`]) |
//! | `ae-imu:FPS[@PHASE][:w=W][:w0=W0][:ae keys]` | the auto-exposure's product split into exposure and gain by the IMU trade `K = sqrt((v c + w0) / w)` (family `gyro-exposure`; see [`ImuTradeAe`]) |
//! | `ae-grad:FPS[@PHASE][:white=F][:cap=Tms][:scene=F]` | motion-blind gradient auto-exposure (family `auto-exposure`; see [`GradientAe`]) |
//! | `threshold:X` | thesis rule: camera free, minimum interval passed, the last three MMBM samples below `X` and strictly decreasing |
//! | `adaptive[:X[:FPS]]` | thesis rule with an adaptive threshold (see [`Adaptive`]); `X` default 0.4, target `FPS` default 2.5 |
//! | `oracle:X[:H]` | perfect future knowledge (see [`Oracle`]); `H` default 0.2 s |
//! | `forecast:X[:H]` | the oracle's rule on a blind periodic forecast (see [`Forecast`]) |
//! | `phase:X[:H]` | the oracle's rule on a forecast folded over the last gait cycles, aligned on detected touchdowns (see [`Phase`]) |
//! | `gate:X[:FPS[@PHASE]]` | `fixed` (default 5 fps), frames whose exposure MMBM is above `X` marked not kept |
//! | `gate0:X[:FPS[@PHASE]]` | the same, on the MMBM at the exposure start (the decision sample): the thesis's test |
//! | `deadline:FPS[:X]` | one frame per fixed-rate slot at the best causal instant (see [`Deadline`]) |
//! | `task:FPS:light=E[:read=E][:tmin=Tms]` | one frame per fixed-rate slot, exposure and instant chosen for the highest predicted probability that the frame is sharp, from the predicted blur and the SNR at the stated light (see [`Task`], [`TaskModel`]) |
//! | `P+exp:B[:TMIN]` | any policy `P` with exposure control: each frame's exposure shortened (and gain raised) so the blur predicted over the exposure stays within `B` px: the forecast of `phase`, the MMBM at the decision sample for the others (see [`Exposure`]) |
//!
//! # Live
//!
//! [`Live`] runs one causal policy a sample at a time; [`Stream`] is the loop
//! of `mmbm live` around it: samples from text lines, UDP datagrams or a
//! replayed log, one MMBM evaluation per sample for every policy, JSON lines
//! out, [`Latency`] statistics, stopped through a [`StreamControl`].
//!
//! # Assembly
//!
//! [`Session`] puts a run together once for `mmbm trigger`, `mmbm live` and
//! Python: the camera with a log's readout applied, the scene, the timing
//! with the camera's pitch and rolling readout, the method and the
//! [`Policies`]; it evaluates a log's series and runs every policy over it.

mod ae_params;
mod baselines;
mod exposure;
mod family;
mod grad_ae;
mod gyro_ae;
mod latency;
mod level;
mod live;
mod numbers;
mod pace;
mod parse;
mod phase;
mod policy;
mod predict;
mod rules;
mod run;
mod session;
mod spec;
mod spec_text;
mod specified;
mod stats;
mod stream;
mod task;
mod task_model;
mod timing;

pub use ae_params::{AeParams, AeVariant};
pub use baselines::{AutoExposure, FixedExposure};
pub use exposure::Exposure;
pub use family::{Family, PolicyFamily};
pub use grad_ae::GradientAe;
pub use gyro_ae::{BlurCappedAe, ImuTradeAe};
pub use latency::Latency;
pub use level::Level;
pub use live::{Event, Live};
pub use pace::check_speed;
pub use parse::{parse_policy, DEFAULT_HORIZON_S, MAX_FPS, THESIS_POLICY};
pub use phase::Phase;
pub use policy::{LogView, Observation, Policy};
pub use predict::{Forecast, Oracle};
pub use rules::{Adaptive, Deadline, Fixed, Gate, Threshold};
pub use run::{run, run_px};
pub use session::{Policies, Session, SessionConfig, SessionRun};
pub use spec::{ExposureControl, PolicySpec, Rate};
pub use stats::{
    prediction_error, summary, summary_over, write_frames, ErrorStats, Summary, Table51,
    FRAME_HEADER,
};
pub use stream::{Stream, StreamControl, StreamEnd, StreamOptions, StreamOutcome, POLL};
pub use task::{Prediction, Task};
pub use task_model::TaskModel;
pub use timing::{exposure_means, CameraTiming, Frame, Integral};
