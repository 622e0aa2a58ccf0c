//! The camera motion of an augmentation: its trajectory (twist, log, walk),
//! re-based on its pose at the sharp instant, and scaled to a target blur length.

use super::{Augment, Motion};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::render::{maps, Pose, Target, Trajectory};
use crate::sim::{simulate, Gait, GaitConfig};
use glam::DQuat;
use rand::{Rng, SeedableRng};

/// Poses in the table of a re-based or scaled trajectory.
const TABLE_POSES: usize = 1024;
/// Seconds of simulated walk before a drawn exposure may start.
const SETTLE_S: f64 = 1.0;
/// Seconds of simulated walk an exposure start is drawn from.
const DRAW_S: f64 = 4.0;
/// Grid (columns, rows) on which the mean blur of `blur_px` is measured.
const BLUR_GRID: (usize, usize) = (17, 13);
/// Time steps of the tracks the mean blur is measured on.
const BLUR_STEPS: usize = 128;
/// Rescaling rounds for `blur_px` (each multiplies the motion by the
/// target over the measured mean; the path is nearly linear in the scale).
const BLUR_ROUNDS: usize = 4;

/// Pose `p` seen from pose `r`: `r^-1 p`.
pub(crate) fn relative(r: &Pose, p: &Pose) -> Pose {
    let qi = r.0.inverse();
    ((qi * p.0).normalize(), qi * (p.1 - r.1))
}

/// The motion's trajectory over `span` s and its description.
pub(crate) fn trajectory(a: &Augment, span: f64) -> Result<(Trajectory, String)> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(a.seed ^ 0x6175_676d_656e_7400);
    let gait = match &a.motion {
        Motion::Twist(tw) => return Ok((Trajectory::from_twist(*tw, span)?, "twist".into())),
        Motion::Log { samples, at } => {
            return Ok((
                Trajectory::from_log(samples, *at, span, a.use_velocity)?,
                format!("log@{at}s"),
            ))
        }
        Motion::Gait(g) => *g,
        Motion::Shake => [Gait::Slow, Gait::Moderate, Gait::Fast][rng.gen_range(0..3)],
    };
    let walk = simulate(
        &GaitConfig::preset(gait),
        SETTLE_S + DRAW_S + span + 0.5,
        600.0,
        a.seed,
    )?;
    let at = SETTLE_S + rng.gen_range(0.0..DRAW_S);
    Ok((
        Trajectory::from_log(&walk, at, span, a.use_velocity)?,
        format!("sim:{}@{at:.4}s", format!("{gait:?}").to_ascii_lowercase()),
    ))
}

/// Re-based on the pose at `fraction` (0 start, 0.5 middle, 1 end) of the
/// span (the exposure, or the whole rolling-shutter span).
pub(crate) fn rebased(traj: &Trajectory, fraction: f64) -> Result<Trajectory> {
    let span = traj.duration();
    let reference = traj.pose_at(fraction * span);
    let poses = traj
        .table(TABLE_POSES)
        .iter()
        .map(|p| relative(&reference, p))
        .collect();
    Trajectory::from_poses(span, poses)
}

/// The motion scaled by `k` about its first pose: each pose's rotation
/// angle and translation from the first pose times `k`.
fn scaled(traj: &Trajectory, k: f64) -> Result<Trajectory> {
    let table = traj.table(TABLE_POSES);
    let p0 = table[0];
    let poses = table
        .iter()
        .map(|p| {
            let r = relative(&p0, p);
            let (axis, angle) = r.0.to_axis_angle();
            let q = if angle.abs() < 1e-15 {
                DQuat::IDENTITY
            } else {
                DQuat::from_axis_angle(axis, angle * k)
            };
            ((p0.0 * q).normalize(), p0.0 * (r.1 * k) + p0.1)
        })
        .collect();
    Trajectory::from_poses(traj.duration(), poses)
}

/// Mean path length (px) of the image points seen at a grid of pixel
/// centres over the trajectory (the mean of the maps' `path_px`).
pub(crate) fn mean_path_px(cam: &Camera, target: &Target, traj: &Trajectory) -> f64 {
    let (nx, ny) = BLUR_GRID;
    let pts: Vec<(f64, f64)> = (0..nx * ny)
        .map(|k| {
            let (i, j) = (k % nx, k / nx);
            (
                (i as f64 + 0.5) / nx as f64 * cam.width as f64,
                (j as f64 + 0.5) / ny as f64 * cam.height as f64,
            )
        })
        .collect();
    let paths: Vec<f64> = maps::tracks(cam, target, traj, &pts, BLUR_STEPS)
        .into_iter()
        .flatten()
        .map(|t| {
            t.windows(2)
                .map(|w| ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt())
                .sum()
        })
        .collect();
    if paths.is_empty() {
        return 0.0;
    }
    paths.iter().sum::<f64>() / paths.len() as f64
}

/// `traj` scaled so that the mean path over the frame is `blur_px` px.
pub(crate) fn fit_blur(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    blur_px: f64,
) -> Result<Trajectory> {
    let l0 = mean_path_px(cam, target, traj);
    if l0.is_nan() || l0 <= 1e-9 {
        return Err(Error::invalid(
            "blur_px",
            format!("{blur_px} px asked of a motion without blur (mean path {l0:.2e} px)"),
        ));
    }
    let mut k = blur_px / l0;
    let mut out = scaled(traj, k)?;
    for _ in 1..BLUR_ROUNDS {
        let l = mean_path_px(cam, target, &out);
        if l.is_nan() || l <= 1e-9 || (l / blur_px - 1.0).abs() < 1e-3 {
            break;
        }
        k *= blur_px / l;
        out = scaled(traj, k)?;
    }
    Ok(out)
}
