//! The per-pixel exposure track (docs/spec.md sections 4 and 9): the image
//! of the scene point a pixel sees at its line's exposure start, followed
//! through the lens over that line's exposure window on a trajectory. With
//! a rolling shutter line `l` of `n` (row or column, in readout order)
//! starts `readout_s l / n` after the frame ([`crate::camera::Shutter::delay_s`]
//! at the line's centre) and is exposed for `exposure_s`; with a global
//! shutter every line starts at once.
//!
//! [`LineTrack`] is the one owner of a line's window and of the instants a
//! track is sampled at (`steps + 1`, uniform, `steps` chords): the
//! renderer's blur maps (`render::maps`) project each pixel's scene point
//! through its poses ([`path`]); the frames' maps
//! (`series::maps`) take the same poses relative to the line's start.

use super::trajectory::{Pose, Trajectory};
use crate::camera::{Camera, Shutter};
use glam::{DMat3, DVec3};

/// One line's exposure window on a trajectory and the camera's poses over it.
#[derive(Debug, Clone, PartialEq)]
pub struct LineTrack {
    /// The line's exposure start after the trajectory's start, s.
    pub t0: f64,
    /// The pose at the line's exposure start (camera-to-world rotation, centre m).
    pub start: Pose,
    /// The poses at `t0 + exposure_s k / steps`, `k = 0..=steps`.
    pub poses: Vec<Pose>,
}

impl LineTrack {
    /// Line `l` (0-based, in readout order's axis: rows or columns of `cam`)
    /// under `shutter` (its readout and direction), exposed `exposure_s` s,
    /// in `steps` chords (at least 1) on `traj`, which starts at the frame's
    /// start (the first line's exposure start).
    pub fn line(
        traj: &Trajectory,
        shutter: &Shutter,
        cam: &Camera,
        l: usize,
        exposure_s: f64,
        steps: usize,
    ) -> Self {
        let c = l as f64 + 0.5;
        let t0 = shutter.delay_s(c, c, cam.width, cam.height);
        Self::at(traj, t0, exposure_s, steps)
    }

    /// The window `[t0, t0 + exposure_s]` s of `traj` in `steps` chords (at
    /// least 1).
    pub fn at(traj: &Trajectory, t0: f64, exposure_s: f64, steps: usize) -> Self {
        let steps = steps.max(1);
        LineTrack {
            t0,
            start: traj.pose_at(t0),
            poses: (0..=steps)
                .map(|k| traj.pose_at(t0 + exposure_s * k as f64 / steps as f64))
                .collect(),
        }
    }

    /// The whole trajectory in `steps` chords ([`Trajectory::table`]): a
    /// global shutter's window.
    pub fn whole(traj: &Trajectory, steps: usize) -> Self {
        let poses = traj.table(steps);
        LineTrack {
            t0: 0.0,
            start: poses[0],
            poses,
        }
    }

    /// The poses as (world-to-camera rotation, centre), for [`path`].
    pub fn world_to_camera(&self) -> Vec<(DMat3, DVec3)> {
        self.poses
            .iter()
            .map(|(q, c)| (DMat3::from_quat(q.inverse()), *c))
            .collect()
    }
}

/// The pixel position (px) of the world point `x` seen from `pose`
/// (world-to-camera rotation, centre) through `cam`'s lens; `None` behind
/// the camera.
pub fn project(cam: &Camera, pose: &(DMat3, DVec3), x: DVec3) -> Option<(f64, f64)> {
    let pc = pose.0 * (x - pose.1);
    (pc.z > 1e-12).then(|| {
        if cam.distortion.is_none() {
            cam.mm_to_pixel(cam.focal_mm * pc.x / pc.z, cam.focal_mm * pc.y / pc.z)
        } else {
            cam.ray_to_pixel(pc.x / pc.z, pc.y / pc.z)
        }
    })
}

/// The track (px) of the world point `x` at each of `poses`
/// ([`LineTrack::world_to_camera`]); `None` when it goes behind the camera.
pub fn track(cam: &Camera, poses: &[(DMat3, DVec3)], x: DVec3) -> Option<Vec<(f64, f64)>> {
    poses.iter().map(|p| project(cam, p, x)).collect()
}

/// Path length (px), end-to-start displacement magnitude (px) and path
/// length on the sensor (mm) of the world point `x`'s track over `poses`
/// ([`LineTrack::world_to_camera`]: the sum of its chords); `None` when it
/// goes behind the camera.
pub fn path(cam: &Camera, poses: &[(DMat3, DVec3)], x: DVec3) -> Option<(f64, f64, f64)> {
    chords::<true>(cam, poses, x)
}

/// [`path`]'s path length and displacement (px), the same numbers, without
/// the path on the sensor in mm (half the work: no millimetre chords).
pub fn path_px(cam: &Camera, poses: &[(DMat3, DVec3)], x: DVec3) -> Option<(f64, f64)> {
    chords::<false>(cam, poses, x).map(|(len, disp, _)| (len, disp))
}

/// [`path`]; the millimetre path only when `MM` (else 0).
fn chords<const MM: bool>(
    cam: &Camera,
    poses: &[(DMat3, DVec3)],
    x: DVec3,
) -> Option<(f64, f64, f64)> {
    let first = project(cam, &poses[0], x)?;
    let mut prev = first;
    let (mut len, mut len_mm) = (0.0, 0.0);
    for p in &poses[1..] {
        let q = project(cam, p, x)?;
        len += ((q.0 - prev.0).powi(2) + (q.1 - prev.1).powi(2)).sqrt();
        if MM {
            let (a, b) = (cam.pixel_to_mm(q.0, q.1), cam.pixel_to_mm(prev.0, prev.1));
            len_mm += (a.0 - b.0).hypot(a.1 - b.1);
        }
        prev = q;
    }
    Some((
        len,
        ((prev.0 - first.0).powi(2) + (prev.1 - first.1).powi(2)).sqrt(),
        len_mm,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::Twist;

    /// A line's window starts at its readout delay: row 99 of 100 under a
    /// 20 ms readout starts at 20 ms x 99 / 100; its poses are the
    /// trajectory's at the window's uniform instants.
    #[test]
    fn a_lines_window_is_its_readout_delay_plus_the_exposure() {
        let mut cam = Camera::thesis();
        cam.width = 160;
        cam.height = 100;
        let shutter = Shutter {
            readout_s: 0.02,
            ..Shutter::global()
        };
        let traj = Trajectory::from_twist(Twist::new(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO), 0.03)
            .unwrap();
        let t = LineTrack::line(&traj, &shutter, &cam, 99, 0.01, 4);
        assert!((t.t0 - 0.02 * 99.0 / 100.0).abs() < 1e-15);
        assert_eq!(t.poses.len(), 5);
        // About the optical axis at 1 rad/s: the angle turned is the time.
        let angle = |p: &Pose| p.0.to_axis_angle().1;
        assert!((angle(&t.start) - t.t0).abs() < 1e-12);
        assert!((angle(&t.poses[4]) - (t.t0 + 0.01)).abs() < 1e-12);
        // A global shutter's window is the whole trajectory.
        let w = LineTrack::whole(&traj, 3);
        assert_eq!((w.t0, w.poses.len()), (0.0, 4));
        assert!((angle(&w.poses[3]) - 0.03).abs() < 1e-12);
    }

    /// A point on the optical axis 2 m ahead, the camera moving 0.1 m
    /// sideways: the pinhole track moves by f x / z = 0.1 * focal / 2 on
    /// the sensor, a straight path (length equals displacement).
    #[test]
    fn a_sideways_move_tracks_a_straight_path() {
        let cam = Camera::thesis();
        let traj = Trajectory::from_twist(Twist::new(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0)), 0.1)
            .unwrap();
        let poses = LineTrack::whole(&traj, 8).world_to_camera();
        let (len, disp, len_mm) = path(&cam, &poses, DVec3::new(0.0, 0.0, 2.0)).unwrap();
        let mm = 0.1 * cam.focal_mm / 2.0;
        assert!((len_mm - mm).abs() < 1e-9, "{len_mm} vs {mm}");
        assert!((len - mm / cam.pitch_x_mm).abs() < 1e-6);
        assert!((len - disp).abs() < 1e-9);
        assert!(path(&cam, &poses, DVec3::new(0.0, 0.0, -2.0)).is_none());
    }
}
