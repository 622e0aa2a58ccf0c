//! The causal policies: fixed rate, the thesis threshold rule, its adaptive
//! version, the fixed-rate quality gate and the deadline schedule.

use super::policy::{rate_slot, thesis_rule, Level, LogView, Observation, Policy};
use super::timing::{CameraTiming, Frame};
use crate::error::Result;
use std::collections::VecDeque;

/// A fixed-rate schedule: slot `k` at `t_0 + phase + k / fps` (`t_0` = the
/// log's first sample).
#[derive(Debug, Clone)]
struct Schedule {
    fps: f64,
    phase: f64,
    k: u64,
}

impl Schedule {
    fn slot(&self, t0: f64, k: u64) -> f64 {
        t0 + self.phase + k as f64 / self.fps
    }

    /// True at the first sample at or after the pending slot; slots at or
    /// before `now` are then consumed (also when the camera is busy: skipped).
    fn due(&mut self, obs: &Observation) -> bool {
        let t0 = obs.t0;
        let now = obs.now();
        if now < self.slot(t0, self.k) {
            return false;
        }
        // Jump near the first slot after `now` (a long gap or a high rate
        // passes many slots), then settle on it exactly.
        let guess = ((now - t0 - self.phase) * self.fps).floor();
        if guess.is_finite() && guess > self.k as f64 + 2.0 {
            self.k = (guess as u64).saturating_sub(1);
        }
        // Bounded: where the times cannot resolve 1/FPS the slot would stop
        // moving (the runner refuses such a time base; live gets here).
        for _ in 0..64 {
            if self.slot(t0, self.k) > now {
                break;
            }
            self.k = self.k.saturating_add(1);
        }
        true
    }
}

/// `fixed:FPS[@PHASE]`: the baseline. Triggers at the first sample at or
/// after each slot `t_0 + PHASE + k / FPS`; a slot that finds the camera busy
/// is skipped. No minimum-interval rule (the period spaces the frames).
#[derive(Debug, Clone)]
pub struct Fixed {
    spec: String,
    sched: Schedule,
}

impl Fixed {
    /// A fixed rate `fps` with the first slot `phase` s after the log start.
    pub fn new(spec: &str, fps: f64, phase: f64) -> Self {
        Fixed {
            spec: spec.to_string(),
            sched: Schedule { fps, phase, k: 0 },
        }
    }
}

impl Policy for Fixed {
    fn label(&self) -> &str {
        &self.spec
    }
    fn prepare(&mut self, log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.sched.k = 0;
        let t_max = crate::model::log::max_abs_time(log.t);
        crate::model::log::check_resolution(t_max, 1.0 / self.sched.fps, "the frame interval")
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        self.sched.due(obs) && obs.camera_free
    }
}

/// `threshold:X`: exactly the thesis rule (section 5.1): trigger when the
/// camera is free, the minimum interval has passed since the previous
/// trigger, and the last three MMBM samples (the decision sample and the two
/// before it) are all below `X` and strictly decreasing.
#[derive(Debug, Clone)]
pub struct Threshold {
    spec: String,
    level: Level,
    x: f64,
}

impl Threshold {
    /// The thesis rule with threshold `level`.
    pub fn new(spec: &str, level: Level) -> Self {
        Threshold {
            spec: spec.to_string(),
            level,
            x: f64::NAN,
        }
    }

    /// The resolved threshold, mm/s (after `prepare`).
    pub fn threshold(&self) -> f64 {
        self.x
    }
}

impl Policy for Threshold {
    fn label(&self) -> &str {
        &self.spec
    }
    fn prepare(&mut self, log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.x = self.level.resolve(log.mmbm)?;
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        obs.camera_free && obs.interval_passed() && thesis_rule(obs.mmbm, self.x)
    }
}

/// `adaptive[:X[:FPS]]`: the thesis rule with the adaptive threshold the
/// thesis proposes (end of section 6.3):
///
/// ```text
/// thr(t) = max(X, SCALE * min MMBM over [t - WINDOW, t]) * (1 + GAIN * deficit)
/// deficit = max(0, 1 - achieved / FPS),  achieved = frames triggered in [t - WINDOW, t] / WINDOW
/// ```
///
/// with `WINDOW` = 2 s, `SCALE` = 1.5, `GAIN` = 1 (so at most twice the
/// threshold); the rate term applies only once `WINDOW` seconds of log have
/// passed. Defaults `X` = 0.4 mm/s, `FPS` = 2.5. The first term raises the
/// threshold when the metric does not get below it (a fast walk), the second
/// when the achieved frame rate falls below the target.
#[derive(Debug, Clone)]
pub struct Adaptive {
    spec: String,
    level: Level,
    target_fps: f64,
    x: f64,
    mins: VecDeque<(f64, f64)>,
    triggers: VecDeque<f64>,
    last_thr: f64,
}

impl Adaptive {
    /// Window of the minimum and of the achieved rate, s.
    pub const WINDOW: f64 = 2.0;
    /// Scale on the recent minimum.
    pub const SCALE: f64 = 1.5;
    /// Gain on the frame-rate deficit.
    pub const GAIN: f64 = 1.0;

    /// Base threshold `level`, target frame rate `target_fps`.
    pub fn new(spec: &str, level: Level, target_fps: f64) -> Self {
        Adaptive {
            spec: spec.to_string(),
            level,
            target_fps,
            x: f64::NAN,
            mins: VecDeque::new(),
            triggers: VecDeque::new(),
            last_thr: f64::NAN,
        }
    }

    /// The threshold used at the last decision, mm/s.
    pub fn last_threshold(&self) -> f64 {
        self.last_thr
    }
}

impl Policy for Adaptive {
    fn label(&self) -> &str {
        &self.spec
    }
    fn prepare(&mut self, log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.x = self.level.resolve(log.mmbm)?;
        self.mins.clear();
        self.triggers.clear();
        self.last_thr = f64::NAN;
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        let now = obs.now();
        let m = obs.current();
        // Sliding minimum over the window (monotone deque).
        while self.mins.back().is_some_and(|&(_, v)| v >= m) {
            self.mins.pop_back();
        }
        self.mins.push_back((now, m));
        while self
            .mins
            .front()
            .is_some_and(|&(t, _)| t < now - Self::WINDOW)
        {
            self.mins.pop_front();
        }
        while self
            .triggers
            .front()
            .is_some_and(|&t| t < now - Self::WINDOW)
        {
            self.triggers.pop_front();
        }
        let recent_min = self.mins.front().map_or(m, |&(_, v)| v);
        let mut thr = self.x.max(Self::SCALE * recent_min);
        if now - obs.t0 >= Self::WINDOW {
            let achieved = self.triggers.len() as f64 / Self::WINDOW;
            let deficit = (1.0 - achieved / self.target_fps).max(0.0);
            thr *= 1.0 + Self::GAIN * deficit;
        }
        self.last_thr = thr;
        let fire = obs.camera_free && obs.interval_passed() && thesis_rule(obs.mmbm, thr);
        if fire {
            self.triggers.push_back(now);
        }
        fire
    }
}

/// `gate:X[:FPS[@PHASE]]`: the fixed schedule (default 5 fps), and a frame
/// whose exposure-averaged MMBM is above `X` is marked not kept (thesis
/// section 5.3.1, its "enhancement": the average over the exposure rather
/// than the value at its start). `gate0:X[:FPS[@PHASE]]` is the thesis's own
/// test: the MMBM of the decision sample (the last one before the exposure
/// starts) above `X` marks the frame not kept.
#[derive(Debug, Clone)]
pub struct Gate {
    fixed: Fixed,
    level: Level,
    x: f64,
    at_start: bool,
}

impl Gate {
    /// Gate at `level` (on the exposure average) on a fixed rate `fps` with phase `phase` s.
    pub fn new(spec: &str, level: Level, fps: f64, phase: f64) -> Self {
        Gate {
            fixed: Fixed::new(spec, fps, phase),
            level,
            x: f64::NAN,
            at_start: false,
        }
    }

    /// The thesis's gate: on the MMBM at the exposure start (the decision sample).
    pub fn at_start(spec: &str, level: Level, fps: f64, phase: f64) -> Self {
        Gate {
            at_start: true,
            ..Self::new(spec, level, fps, phase)
        }
    }
}

impl Policy for Gate {
    fn label(&self) -> &str {
        self.fixed.label()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.x = self.level.resolve(log.mmbm)?;
        self.fixed.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        self.fixed.decide(obs)
    }
    fn keep(&self, frame: &Frame) -> bool {
        if self.at_start {
            frame.mmbm_trigger_mm_s <= self.x
        } else {
            frame.mmbm_exposure_mm_s <= self.x
        }
    }
}

/// `deadline:FPS[:X]`: one frame per slot `[t_0 + k / FPS, t_0 + (k + 1) / FPS)`,
/// advancing as well as delaying triggers within the slot to keep the fixed
/// schedule's frame count (end of thesis chapter 6). In each slot, while the
/// camera is free and the slot has no frame yet:
///
/// - with `X`: trigger at the first sample satisfying the thesis rule with `X`
///   (last three below `X`, strictly decreasing);
/// - without `X`: observe the first `1/e` of the slot (the secretary rule) and
///   then trigger at the first sample whose MMBM is below the minimum observed;
/// - in both cases, trigger at the slot's last sample (the deadline: the next
///   sample, expected one interval `dt = t_i - t_{i-1}` later, would come
///   within `dt / 2` of the slot's end or after it) if nothing triggered before.
///
/// No minimum interval (frames of adjacent slots may be closer than `1/FPS`).
#[derive(Debug, Clone)]
pub struct Deadline {
    spec: String,
    fps: f64,
    level: Option<Level>,
    x: f64,
    slot: i64,
    taken: bool,
    obs_min: f64,
}

impl Deadline {
    /// Slots at `fps`, optional thesis-rule threshold `level`.
    pub fn new(spec: &str, fps: f64, level: Option<Level>) -> Self {
        Deadline {
            spec: spec.to_string(),
            fps,
            level,
            x: f64::NAN,
            slot: -1,
            taken: false,
            obs_min: f64::INFINITY,
        }
    }
}

impl Policy for Deadline {
    fn label(&self) -> &str {
        &self.spec
    }
    fn prepare(&mut self, log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.x = match &self.level {
            Some(l) => l.resolve(log.mmbm)?,
            None => f64::NAN,
        };
        self.slot = -1;
        self.taken = false;
        self.obs_min = f64::INFINITY;
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        let t0 = obs.t0;
        let now = obs.now();
        let period = 1.0 / self.fps;
        let (slot, start) = rate_slot(t0, self.fps, now);
        if slot != self.slot {
            self.slot = slot;
            self.taken = false;
            self.obs_min = f64::INFINITY;
        }
        let end = start + period;
        let m = obs.current();
        let observing = self.level.is_none() && now < start + period / std::f64::consts::E;
        if observing {
            self.obs_min = self.obs_min.min(m);
        }
        if self.taken || !obs.camera_free {
            return false;
        }
        let dt = obs.previous_time().map_or(0.0, |p| now - p);
        let deadline = now + 1.5 * dt >= end;
        let good = match self.level {
            Some(_) => thesis_rule(obs.mmbm, self.x),
            None => !observing && m < self.obs_min,
        };
        if good || deadline {
            self.taken = true;
            return true;
        }
        false
    }
}
