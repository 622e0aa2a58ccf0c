//! The per-pixel exposure track (docs/spec.md sections 4 and 9): the image
//! of the scene point a pixel sees at its line's exposure start, followed
//! through the lens over that line's exposure window on a trajectory. With
//! a rolling shutter line `l` of `n` (row or column, in readout order)
//! starts `readout_s l / n` after the frame ([`crate::camera::Shutter::delay_s`]
//! at the line's centre) and is exposed for `exposure_s`; with a global
//! shutter every line starts at once.
//!
//! [`LineTrack`] is the one owner of a line's window and of the instants a
//! track is sampled at (`steps + 1`, uniform, `steps` chords), and
//! [`ScenePoint`] with [`project`], [`track`] and [`path`] the one owner of
//! the per-pixel track: the pixel's scene point in homogeneous form in the
//! line's start frame (a finite point or one at infinity), projected
//! through the lens at each of the line's poses relative to its start
//! ([`LineTrack::relative`]), and its chords. The renderer's blur maps
//! (`render::maps`, the point where the pixel's ray meets the target) and
//! the frames' maps (`series::maps`, a ray and an inverse depth from the
//! log's plane) both call them.

use super::trajectory::{Pose, Trajectory};
use crate::camera::{Camera, Shutter};
use glam::{DMat3, DQuat, DVec3};

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

    /// The poses relative to the line's start, as rotations (start frame
    /// to each instant's) and the start's centre in each instant's frame
    /// (m): what the GPU maps upload.
    pub fn relative_quats(&self) -> Vec<(DQuat, DVec3)> {
        let (qs, cs) = self.start;
        self.poses
            .iter()
            .map(|&(q, c)| {
                let inv = q.inverse();
                (inv * qs, inv * (cs - c))
            })
            .collect()
    }

    /// [`LineTrack::relative_quats`] as matrices: the [`Step`]s of
    /// [`project`], [`track`] and [`path`].
    pub fn relative(&self) -> Vec<Step> {
        self.relative_quats()
            .into_iter()
            .map(|(q, b)| (DMat3::from_quat(q), b))
            .collect()
    }
}

/// One instant's pose relative to a line's start: the rotation from the
/// start's camera frame to the instant's, and the offset of the start's
/// centre in the instant's frame (m) ([`LineTrack::relative`]).
pub type Step = (DMat3, DVec3);

/// The scene point a pixel sees at its line's start, in homogeneous form in
/// the start's camera frame: the point is `ray / inv_depth` (m), and
/// `inv_depth = 0` is a point at infinity (rotation only). Seen from an
/// instant `(M, b)` ([`Step`]) it lies along `M ray + b inv_depth`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScenePoint {
    /// A direction to the point in the start's camera frame (any length).
    pub ray: DVec3,
    /// The inverse of the point's distance in units of `ray` (0: at infinity).
    pub inv_depth: f64,
}

impl ScenePoint {
    /// The world point `x` (m) seen from `start` (camera-to-world rotation,
    /// centre): its start-frame position, `inv_depth` 1.
    pub fn from_world(start: &Pose, x: DVec3) -> Self {
        ScenePoint {
            ray: start.0.inverse() * (x - start.1),
            inv_depth: 1.0,
        }
    }
}

/// Path length (px), end-minus-start displacement (px) and path length on
/// the sensor (mm) of a scene point's track (the sum of its chords).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackPath {
    /// Sum of the track's chords, px.
    pub len_px: f64,
    /// End minus start position, px (x right, y down).
    pub disp: (f64, f64),
    /// Sum of the chords on the sensor, mm (0 from [`path_px`]).
    pub len_mm: f64,
}

impl TrackPath {
    /// The displacement's magnitude, px.
    pub fn disp_px(&self) -> f64 {
        (self.disp.0.powi(2) + self.disp.1.powi(2)).sqrt()
    }
}

/// The pixel position (px) of `point` seen from `step` (relative to the
/// point's start frame) through `cam`'s lens; `None` behind the camera.
#[inline]
pub fn project(cam: &Camera, step: &Step, point: &ScenePoint) -> Option<(f64, f64)> {
    let pc = step.0 * point.ray + step.1 * point.inv_depth;
    (pc.z > 1e-12).then(|| {
        if cam.distortion.is_none() {
            cam.mm_to_pixel(cam.focal_mm * pc.x / pc.z, cam.focal_mm * pc.y / pc.z)
        } else {
            cam.ray_to_pixel(pc.x / pc.z, pc.y / pc.z)
        }
    })
}

/// The track (px) of `point` at each of `steps` ([`LineTrack::relative`]);
/// `None` when it goes behind the camera.
pub fn track(cam: &Camera, steps: &[Step], point: &ScenePoint) -> Option<Vec<(f64, f64)>> {
    steps.iter().map(|s| project(cam, s, point)).collect()
}

/// The path of `point`'s track over `steps` ([`LineTrack::relative`]): px,
/// displacement and mm; `None` when it goes behind the camera.
pub fn path(cam: &Camera, steps: &[Step], point: &ScenePoint) -> Option<TrackPath> {
    chords::<true>(cam, steps, point)
}

/// [`path`] without the path on the sensor in mm (`len_mm` 0; half the
/// work: no millimetre chords), the same px numbers.
pub fn path_px(cam: &Camera, steps: &[Step], point: &ScenePoint) -> Option<TrackPath> {
    chords::<false>(cam, steps, point)
}

/// [`path`]; the millimetre path only when `MM` (else 0).
fn chords<const MM: bool>(cam: &Camera, steps: &[Step], point: &ScenePoint) -> Option<TrackPath> {
    let first = project(cam, steps.first()?, point)?;
    let mut prev = first;
    let (mut len, mut len_mm) = (0.0, 0.0);
    for s in &steps[1..] {
        let q = project(cam, s, point)?;
        let (du, dv) = (q.0 - prev.0, q.1 - prev.1);
        len += (du * du + dv * dv).sqrt();
        if MM {
            let (a, b) = (cam.pixel_to_mm(q.0, q.1), cam.pixel_to_mm(prev.0, prev.1));
            len_mm += (a.0 - b.0).hypot(a.1 - b.1);
        }
        prev = q;
    }
    Some(TrackPath {
        len_px: len,
        disp: (prev.0 - first.0, prev.1 - first.1),
        len_mm,
    })
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

    /// The relative steps of a twist's whole trajectory.
    fn steps(omega: DVec3, v: DVec3, t: f64, n: usize) -> Vec<Step> {
        let traj = Trajectory::from_twist(Twist::new(omega, v), t).unwrap();
        LineTrack::whole(&traj, n).relative()
    }

    /// A point on the optical axis 2 m ahead, the camera moving 0.1 m
    /// sideways: the pinhole track moves by f x / z = 0.1 * focal / 2 on
    /// the sensor, a straight path (length equals displacement), to the
    /// left; a point behind the camera has no track.
    #[test]
    fn a_sideways_move_tracks_a_straight_path() {
        let cam = Camera::thesis();
        let st = steps(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), 0.1, 8);
        let start = (DQuat::IDENTITY, DVec3::ZERO);
        let p = path(
            &cam,
            &st,
            &ScenePoint::from_world(&start, DVec3::new(0.0, 0.0, 2.0)),
        )
        .unwrap();
        let mm = 0.1 * cam.focal_mm / 2.0;
        assert!((p.len_mm - mm).abs() < 1e-9, "{} vs {mm}", p.len_mm);
        assert!((p.len_px - mm / cam.pitch_x_mm).abs() < 1e-6);
        assert!((p.len_px - p.disp_px()).abs() < 1e-9);
        assert!((p.disp.0 + mm / cam.pitch_x_mm).abs() < 1e-6 && p.disp.1.abs() < 1e-9);
        let behind = ScenePoint::from_world(&start, DVec3::new(0.0, 0.0, -2.0));
        assert!(path(&cam, &st, &behind).is_none());
        assert!(track(&cam, &st, &behind).is_none());
    }

    /// A plane at depth Z moving sideways at v for T: every pixel's path is
    /// f v T / Z (px: f in px), the same for a point given by its ray and
    /// inverse depth (`ray (x, y, 1)`, `inv_depth 1 / Z`) as for the world
    /// point; a point at infinity does not move.
    #[test]
    fn a_plane_at_depth_z_moves_f_v_t_over_z() {
        let cam = Camera::thesis();
        let (v, t, z) = (0.4, 0.05, 3.0);
        let st = steps(DVec3::ZERO, DVec3::new(0.0, v, 0.0), t, 16);
        let f_px = cam.fy_px();
        for (x, y) in [(0.0, 0.0), (0.2, -0.1), (-0.3, 0.25)] {
            let p = ScenePoint {
                ray: DVec3::new(x, y, 1.0),
                inv_depth: 1.0 / z,
            };
            let got = path(&cam, &st, &p).unwrap();
            let want = f_px * v * t / z;
            assert!(
                (got.len_px - want).abs() < 1e-9 * want,
                "{} vs {want}",
                got.len_px
            );
            assert!((got.disp.1 + want).abs() < 1e-9 * want && got.disp.0.abs() < 1e-9);
            let world = ScenePoint::from_world(&(DQuat::IDENTITY, DVec3::ZERO), p.ray * z);
            let w = path(&cam, &st, &world).unwrap();
            assert!((w.len_px - got.len_px).abs() < 1e-9 * want);
            let far = ScenePoint {
                inv_depth: 0.0,
                ..p
            };
            assert!(path(&cam, &st, &far).unwrap().len_px.abs() < 1e-12);
        }
    }

    /// A pure yaw at omega for T, the point at infinity on the optical
    /// axis: its track is an arc of f omega T px (f in px), in chords of
    /// f tan; the centre pixel's path converges to it.
    #[test]
    fn a_pure_yaw_at_infinity_moves_f_omega_t() {
        let cam = Camera::thesis();
        let (w, t) = (0.3, 0.02);
        let st = steps(DVec3::new(0.0, w, 0.0), DVec3::ZERO, t, 64);
        let p = ScenePoint {
            ray: DVec3::Z,
            inv_depth: 0.0,
        };
        let got = path(&cam, &st, &p).unwrap();
        // On the axis the image moves by f tan(angle): f tan(omega T) in all.
        let want = cam.fx_px() * (w * t).tan();
        assert!(
            (got.len_px - want).abs() < 1e-9 * want,
            "{} vs {want}",
            got.len_px
        );
        assert!((got.len_px - cam.fx_px() * w * t).abs() < 1e-4 * want);
        assert!((got.disp_px() - want).abs() < 1e-9 * want);
        // Turned past 90 degrees the point goes behind the camera.
        let st = steps(DVec3::new(0.0, 2.0, 0.0), DVec3::ZERO, 1.0, 8);
        assert!(path(&cam, &st, &p).is_none());
    }
}
