//! Camera pose trajectories over one exposure (docs/spec.md section 4).
//!
//! Convention: the world frame is the camera frame at exposure start, so
//! `pose_at(0) = (identity, 0)`. A pose `(q, c)` maps camera-frame vectors to
//! world vectors (`X_world = c + q * X_cam`); a world point is seen in the
//! camera at time `t` as `q(t)^-1 (X - c(t))`. Body-frame kinematics:
//! `dR/dt = R [w]x`, `dc/dt = R v` (w rad/s, v m/s, t s).

use crate::check::positive;
use crate::error::{Error, Result};
use crate::model::log::GyroSample;
use crate::model::log::{check_times, is_gap, median_interval, min_interval, ImuLog};
use crate::model::motion::Twist;
use glam::{DMat3, DQuat, DVec3};

/// A pose: rotation camera-to-world and camera centre (m), both relative to exposure start.
pub type Pose = (DQuat, DVec3);

#[derive(Debug, Clone, PartialEq)]
enum Kind {
    /// Constant body-frame twist: closed form.
    Twist(Twist),
    /// Poses at `n + 1` uniform times `k * duration / n`, interpolated linearly (nlerp).
    Table(Vec<Pose>),
}

/// The camera's motion during one exposure of `duration` seconds.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    duration: f64,
    kind: Kind,
}

fn skew(w: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, w.z, -w.y),
        DVec3::new(-w.z, 0.0, w.x),
        DVec3::new(w.y, -w.x, 0.0),
    )
}

/// `exp(t [w]x)` and `integral_0^t exp(s [w]x) ds` for the SE(3) closed form.
fn twist_pose(tw: &Twist, t: f64) -> Pose {
    let phi = tw.omega * t;
    let th = phi.length();
    let q = DQuat::from_scaled_axis(phi);
    let k = skew(phi);
    let (a, b) = if th < 1e-4 {
        let t2 = th * th;
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        (
            (1.0 - th.cos()) / (th * th),
            (th - th.sin()) / (th * th * th),
        )
    };
    let v = DMat3::IDENTITY + k * a + k * k * b;
    (q, v * (tw.velocity * t))
}

fn lerp_pose(a: &Pose, b: &Pose, f: f64) -> Pose {
    let qb = if a.0.dot(b.0) < 0.0 { -b.0 } else { b.0 };
    let q = (a.0 * (1.0 - f) + qb * f).normalize();
    (q, a.1.lerp(b.1, f))
}

impl Trajectory {
    /// Constant twist (camera frame at every instant) for `duration` s, closed form.
    pub fn from_twist(tw: Twist, duration: f64) -> Result<Self> {
        positive("exposure (s)", duration)?;
        tw.validate()?;
        Ok(Trajectory {
            duration,
            kind: Kind::Twist(tw),
        })
    }

    /// A table of `n + 1 >= 2` poses at uniform times `k * duration / n`
    /// (pose 0 should be the identity), interpolated linearly between entries.
    pub fn from_poses(duration: f64, poses: Vec<Pose>) -> Result<Self> {
        positive("exposure (s)", duration)?;
        if poses.len() < 2 {
            return Err(Error::invalid("trajectory", "needs at least 2 poses"));
        }
        if poses
            .iter()
            .any(|(q, c)| !q.is_finite() || !c.is_finite() || (q.length() - 1.0).abs() > 1e-6)
        {
            return Err(Error::invalid(
                "trajectory",
                "poses must be finite unit quaternions and finite positions",
            ));
        }
        Ok(Trajectory {
            duration,
            kind: Kind::Table(poses),
        })
    }

    /// True when the camera does not move: a table whose poses are all the
    /// same (e.g. a sharp reference), or a twist of zero.
    pub fn is_still(&self) -> bool {
        match &self.kind {
            Kind::Twist(tw) => tw.omega == DVec3::ZERO && tw.velocity == DVec3::ZERO,
            Kind::Table(p) => p.windows(2).all(|w| w[0] == w[1]),
        }
    }

    /// Integrates a gyro log over `[t0, t0 + duration]` (s, log clock after
    /// `GyroOptions`): `w` (and `v` when `use_velocity`) linearly interpolated
    /// between samples, quaternion exponential midpoint steps at 1/16 of the
    /// sample interval (at most 1/512 of the exposure). Errors when the window
    /// is outside the log or velocity is requested but missing.
    pub fn from_log(
        samples: &[GyroSample],
        t0: f64,
        duration: f64,
        use_velocity: bool,
    ) -> Result<Self> {
        check_times(samples, "gyro log")?;
        let median = median_interval(samples).unwrap_or(0.0);
        let dt_min = min_interval(samples).unwrap_or(f64::INFINITY);
        Self::from_samples(samples, (median, dt_min), t0, duration, use_velocity)
    }

    /// [`Self::from_log`] on a validated log, whose median interval is
    /// known (many frames of one log: no per-frame pass over the log).
    pub fn from_imu_log(log: &ImuLog, t0: f64, duration: f64, use_velocity: bool) -> Result<Self> {
        let median = log.median_interval().unwrap_or(0.0);
        let dt_min = log.min_interval().unwrap_or(f64::INFINITY);
        Self::from_samples(log.samples(), (median, dt_min), t0, duration, use_velocity)
    }

    /// `intervals`: the log's median and shortest sample interval, s.
    fn from_samples(
        samples: &[GyroSample],
        (median, dt_min): (f64, f64),
        t0: f64,
        duration: f64,
        use_velocity: bool,
    ) -> Result<Self> {
        positive("exposure (s)", duration)?;
        crate::check::finite("exposure start --at (s)", t0)?;
        let (first, last) = match (samples.first(), samples.last()) {
            (Some(a), Some(b)) if samples.len() >= 2 => (a.t, b.t),
            _ => {
                return Err(Error::invalid(
                    "gyro log",
                    "needs at least 2 samples to integrate a trajectory",
                ))
            }
        };
        let t1 = t0 + duration;
        if t0 < first || t1 > last {
            return Err(Error::invalid(
                "exposure window",
                format!("[{t0}, {t1}] s is outside the gyro log, which covers [{first}, {last}] s"),
            ));
        }
        if use_velocity {
            if let Some(s) = samples.iter().find(|s| s.velocity.is_none()) {
                return Err(Error::invalid(
                    "gyro log",
                    format!(
                        "velocity requested but the sample at t = {} s has no vx,vy,vz",
                        s.t
                    ),
                ));
            }
        }
        // A gap in the log inside the window: no motion is known there.
        let lo = samples.partition_point(|s| s.t <= t0).saturating_sub(1);
        let hi = samples.partition_point(|s| s.t < t1).min(samples.len() - 1);
        let window = &samples[lo..=hi];
        if let Some(w) = window
            .windows(2)
            .find(|w| w[1].t > t0 && w[0].t < t1 && is_gap(w[1].t - w[0].t, median))
        {
            return Err(Error::invalid(
                "exposure window",
                format!(
                    "[{t0}, {t1}] s spans a gap in the gyro log: no sample between t = {} s and {} s \
                     ({:.6} s; the median interval is {median:.6} s), so the motion there is unknown",
                    w[0].t,
                    w[1].t,
                    w[1].t - w[0].t
                ),
            ));
        }
        let n = ((duration / dt_min * 16.0).ceil() as usize).clamp(512, 1 << 20);
        let h = duration / n as f64;
        let interp = |t: f64| -> (DVec3, DVec3) {
            let i = samples
                .partition_point(|s| s.t <= t)
                .clamp(1, samples.len() - 1);
            let (a, b) = (&samples[i - 1], &samples[i]);
            let f = ((t - a.t) / (b.t - a.t)).clamp(0.0, 1.0);
            let w = a.omega.lerp(b.omega, f);
            let v = if use_velocity {
                a.velocity
                    .unwrap_or_default()
                    .lerp(b.velocity.unwrap_or_default(), f)
            } else {
                DVec3::ZERO
            };
            (w, v)
        };
        let mut poses = Vec::with_capacity(n + 1);
        let (mut q, mut c) = (DQuat::IDENTITY, DVec3::ZERO);
        poses.push((q, c));
        for k in 0..n {
            let tm = t0 + (k as f64 + 0.5) * h;
            let (w, v) = interp(tm);
            let half = q * DQuat::from_scaled_axis(w * (0.5 * h));
            q = (q * DQuat::from_scaled_axis(w * h)).normalize();
            c += half * v * h;
            poses.push((q, c));
        }
        Self::from_poses(duration, poses)
    }

    /// Exposure duration, s.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The constant twist, when the trajectory was built from one.
    pub fn twist(&self) -> Option<Twist> {
        match &self.kind {
            Kind::Twist(t) => Some(*t),
            Kind::Table(_) => None,
        }
    }

    /// Pose at time `t` s after exposure start (clamped to `[0, duration]`).
    pub fn pose_at(&self, t: f64) -> Pose {
        let t = t.clamp(0.0, self.duration);
        match &self.kind {
            Kind::Twist(tw) => twist_pose(tw, t),
            Kind::Table(p) => {
                let n = p.len() - 1;
                let x = t / self.duration * n as f64;
                let i = (x.floor() as usize).min(n - 1);
                lerp_pose(&p[i], &p[i + 1], x - i as f64)
            }
        }
    }

    /// `n + 1` poses at uniform times `k * duration / n` (what the renderer uploads).
    pub fn table(&self, n: usize) -> Vec<Pose> {
        let n = n.max(1);
        (0..=n)
            .map(|k| self.pose_at(self.duration * k as f64 / n as f64))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_matches_integration() {
        let tw = Twist::new(DVec3::new(2.0, -1.0, 3.0), DVec3::new(0.3, 0.1, -0.5));
        let tr = Trajectory::from_twist(tw, 0.2).unwrap();
        // Integrate dR/dt = R[w]x, dc/dt = R v with tiny RK-free midpoint steps.
        let n = 20000;
        let h = 0.2 / n as f64;
        let (mut q, mut c) = (DQuat::IDENTITY, DVec3::ZERO);
        for _ in 0..n {
            let half = q * DQuat::from_scaled_axis(tw.omega * (0.5 * h));
            q = (q * DQuat::from_scaled_axis(tw.omega * h)).normalize();
            c += half * tw.velocity * h;
        }
        let (q2, c2) = tr.pose_at(0.2);
        assert!(q.angle_between(q2) < 1e-9, "{q} {q2}");
        assert!((c - c2).length() < 1e-9, "{c} {c2}");
    }

    #[test]
    fn log_window_checks_and_constant_log_matches_twist() {
        let w = DVec3::new(0.5, -0.25, 1.0);
        let v = DVec3::new(0.1, 0.0, 0.2);
        let s: Vec<GyroSample> = (0..100)
            .map(|i| GyroSample {
                t: i as f64 * 0.005,
                omega: w,
                velocity: Some(v),
                depth: None,
            })
            .collect();
        assert!(Trajectory::from_log(&s, -0.01, 0.05, false).is_err());
        assert!(Trajectory::from_log(&s, 0.47, 0.05, false).is_err());
        assert!(Trajectory::from_log(&s, 0.1, 0.0, false).is_err());
        let tr = Trajectory::from_log(&s, 0.1, 0.05, true).unwrap();
        let ex = Trajectory::from_twist(Twist::new(w, v), 0.05).unwrap();
        for t in [0.0, 0.013, 0.05] {
            let (a, b) = (tr.pose_at(t), ex.pose_at(t));
            assert!(a.0.angle_between(b.0) < 1e-9 && (a.1 - b.1).length() < 1e-9);
        }
    }
}
