//! One line of a frame's maps: its motion over its exposure ([`LineMotion`],
//! which the GPU path packs: the poses of the line's window, the one
//! per-pixel track's [`LineTrack`], relative to the line's start) and its
//! track in f64, the CPU path of [`super::frame_maps`]: each pixel's
//! [`ScenePoint`] through the one per-pixel track ([`track::path_px`]), or
//! for a pinhole camera that track vectorised over the line
//! ([`Line::pinhole`]).

use crate::camera::Camera;
use crate::model::flow::FlowPoly;
use crate::model::log::ImuLog;
use crate::model::motion::{Plane, Twist};
use crate::model::track::{self, LineTrack, ScenePoint, Step};
use glam::{DMat3, DQuat, DVec3};

/// One line's motion over its exposure, as rotations (the GPU path uploads
/// these; the f64 path turns them into matrices, [`Line`]).
pub(crate) struct LineMotion {
    /// Camera-to-world rotation at the line's start.
    pub start: DQuat,
    /// Rotation from the line's start frame to each of `steps + 1` instants'
    /// frames, and the offset of the start's centre in each instant's frame (m).
    pub steps: Vec<(DQuat, DVec3)>,
    /// World-frame normal and offset of the plane seen from the line's start
    /// centre: `n . (X - c_s) = d_s`.
    pub plane: Option<(DVec3, f64)>,
    /// The flow at the line's start (mm/s, undistorted sensor).
    pub flow: FlowPoly,
}

impl LineMotion {
    /// The motion of the line whose window and poses are `track` (the one
    /// per-pixel track's, [`LineTrack::line`], on a trajectory starting at
    /// the frame's start `t_frame`, log clock), relative to its start.
    pub fn new(
        log: &ImuLog,
        track: &LineTrack,
        plane: Option<&Plane>,
        cam: &Camera,
        t_frame: f64,
    ) -> Self {
        let (qs, cs) = track.start;
        let t0 = track.t0;
        let steps_v = track.relative_quats();
        // The twist interpolated to the line's start, and the plane in the
        // line's start frame.
        let t = t_frame + t0;
        let i = log.partition_point(|s| s.t <= t).clamp(1, log.len() - 1);
        let (s0, s1) = (&log[i - 1], &log[i]);
        let f = ((t - s0.t) / (s1.t - s0.t)).clamp(0.0, 1.0);
        let omega = s0.omega.lerp(s1.omega, f);
        let vel = match (s0.velocity, s1.velocity) {
            (Some(a), Some(b)) => a.lerp(b, f),
            _ => DVec3::ZERO,
        };
        let plane_w = plane.map(|p| (p.normal, p.d - p.normal.dot(cs)));
        let plane_line = plane_w.map(|(n, d)| Plane {
            normal: qs.inverse() * n,
            d,
        });
        LineMotion {
            start: qs,
            steps: steps_v,
            plane: plane_w,
            flow: FlowPoly::new(cam.focal_mm, &Twist::new(omega, vel), plane_line.as_ref()),
        }
    }
}

/// [`Line::pinhole`]'s per-pixel buffers (px, f64): the rays, the first and
/// last positions, the path, and the pixels without a track.
struct PinholeTracks {
    rx: Vec<f64>,
    ry: Vec<f64>,
    x0: Vec<f64>,
    y0: Vec<f64>,
    px: Vec<f64>,
    py: Vec<f64>,
    path: Vec<f64>,
    bad: Vec<bool>,
}

/// One line's motion over its exposure, in matrices (the f64 path).
pub(crate) struct Line {
    /// World-to-camera rotation at the line's start (camera-to-world transposed).
    start_rot: DMat3,
    /// The line's poses relative to its start ([`LineTrack::relative`]).
    steps: Vec<Step>,
    /// World-frame normal and offset of the plane seen from the line's start
    /// centre: `n . (X - c_s) = d_s`.
    plane: Option<(DVec3, f64)>,
    /// The flow at the line's start (mm/s, undistorted sensor).
    flow: FlowPoly,
}

impl From<LineMotion> for Line {
    fn from(m: LineMotion) -> Self {
        Line {
            start_rot: DMat3::from_quat(m.start),
            steps: m
                .steps
                .into_iter()
                .map(|(q, b)| (DMat3::from_quat(q), b))
                .collect(),
            plane: m.plane,
            flow: m.flow,
        }
    }
}

impl Line {
    /// The inverse depth (1/m) of the scene point along `ray` (line start
    /// frame); 0 for rotation only (points at infinity); `None` when the ray
    /// misses the plane.
    #[inline]
    fn inv_depth(&self, ray: DVec3) -> Option<f64> {
        match self.plane {
            None => Some(0.0),
            Some((n, d)) => {
                let x = n.dot(self.start_rot * ray) / d;
                (x > 0.0 && x.is_finite()).then_some(x)
            }
        }
    }

    /// [`Line::pixel`] for a whole line of a pinhole camera (`ray(m)` is
    /// the undistorted ray of the line's pixel `m`): the vectorised form of
    /// the one per-pixel track ([`track::path_px`] of each pixel's
    /// [`ScenePoint`]), the pixel matrix folded into each instant's
    /// rotation, step-major over the line's pixels so the inner loop
    /// vectorises. The same values to rounding (1e-9 px relative, tested
    /// against [`Line::pixel`]); kept for speed (measured in
    /// docs/performance.md).
    pub fn pinhole(&self, cam: &Camera, ray: impl Fn(usize) -> (f64, f64), out: &mut [[f32; 5]]) {
        let n = out.len();
        let t = self.pinhole_tracks(cam, ray, n);
        for (m, o) in out.iter_mut().enumerate() {
            if t.bad[m] {
                continue;
            }
            let fl = self
                .flow
                .eval(cam.focal_mm * t.rx[m], cam.focal_mm * t.ry[m]);
            let (fu, fv) = cam.mm_to_px_velocity(fl.0, fl.1);
            *o = [
                (t.px[m] - t.x0[m]) as f32,
                (t.py[m] - t.y0[m]) as f32,
                t.path[m] as f32,
                fu as f32,
                fv as f32,
            ];
        }
    }

    /// The tracks of [`Line::pinhole`] in f64, before the flow and the f32
    /// channels.
    fn pinhole_tracks(
        &self,
        cam: &Camera,
        ray: impl Fn(usize) -> (f64, f64),
        n: usize,
    ) -> PinholeTracks {
        let kmat = DMat3::from_cols(
            DVec3::new(cam.focal_mm / cam.pitch_x_mm, 0.0, 0.0),
            DVec3::new(cam.skew, cam.focal_mm / cam.pitch_y_mm, 0.0),
            DVec3::new(cam.cx, cam.cy, 1.0),
        );
        let mut t = PinholeTracks {
            rx: vec![0.0; n],
            ry: vec![0.0; n],
            x0: vec![0.0; n],
            y0: vec![0.0; n],
            px: vec![0.0; n],
            py: vec![0.0; n],
            path: vec![0.0; n],
            bad: vec![false; n],
        };
        let mut is = vec![0.0f64; n];
        for (m, inv) in is.iter_mut().enumerate() {
            let r = ray(m);
            t.rx[m] = r.0;
            t.ry[m] = r.1;
            match self.inv_depth(DVec3::new(r.0, r.1, 1.0)) {
                Some(x) if r.0.is_finite() && r.1.is_finite() => *inv = x,
                _ => t.bad[m] = true,
            }
        }
        let (rx, ry) = (&t.rx, &t.ry);
        for (k, (rot, off)) in self.steps.iter().enumerate() {
            let a = kmat * *rot;
            let c = kmat * *off;
            let (a0, a1, a2) = (a.x_axis, a.y_axis, a.z_axis);
            for m in 0..n {
                let (x, y, s) = (rx[m], ry[m], is[m]);
                let z = a0.z * x + a1.z * y + a2.z + c.z * s;
                t.bad[m] |= z.is_nan() || z <= 1e-12;
                let q = 1.0 / z;
                let u = (a0.x * x + a1.x * y + a2.x + c.x * s) * q;
                let v = (a0.y * x + a1.y * y + a2.y + c.y * s) * q;
                if k == 0 {
                    t.x0[m] = u;
                    t.y0[m] = v;
                } else {
                    let (du, dv) = (u - t.px[m], v - t.py[m]);
                    t.path[m] += (du * du + dv * dv).sqrt();
                }
                t.px[m] = u;
                t.py[m] = v;
            }
        }
        t
    }

    /// The five channels of the pixel whose undistorted ray is `r`, or
    /// `None`: the track of the pixel's [`ScenePoint`] (its ray, the
    /// plane's inverse depth) by [`track::path_px`], and the start flow.
    #[inline]
    pub fn pixel(&self, cam: &Camera, r: (f64, f64)) -> Option<[f32; 5]> {
        if !r.0.is_finite() {
            return None;
        }
        let ray = DVec3::new(r.0, r.1, 1.0);
        let point = ScenePoint {
            ray,
            inv_depth: self.inv_depth(ray)?,
        };
        let p = track::path_px(cam, &self.steps, &point)?;
        let (u, v) = (cam.focal_mm * r.0, cam.focal_mm * r.1);
        let fl = self.flow.eval(u, v);
        let fl = if cam.distortion.is_none() {
            fl
        } else {
            crate::camera::distortion::apply(&cam.distortion_jacobian(u, v), fl)
        };
        let (fu, fv) = cam.mm_to_px_velocity(fl.0, fl.1);
        Some([
            p.disp.0 as f32,
            p.disp.1 as f32,
            p.len_px as f32,
            fu as f32,
            fv as f32,
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::trajectory::Trajectory;

    /// A line of the thesis camera (64 px wide) under a twist with rotation
    /// and translation, seeing a tilted plane (`plane`) or the points at
    /// infinity (`None`).
    fn line(plane: Option<(DVec3, f64)>) -> (Camera, Line) {
        let cam = Camera::thesis().with_resolution(64, 48);
        let twist = Twist::new(DVec3::new(0.4, -0.7, 0.3), DVec3::new(0.5, -0.2, 0.3));
        let traj = Trajectory::from_twist(twist, 0.03).unwrap();
        let line = Line {
            start_rot: DMat3::IDENTITY,
            steps: LineTrack::whole(&traj, 16).relative(),
            plane,
            flow: FlowPoly::new(cam.focal_mm, &twist, None),
        };
        (cam, line)
    }

    /// [`Line::pinhole`], the vectorised form of the one per-pixel track,
    /// equals [`track::path_px`] of each pixel's [`ScenePoint`] to 1e-9 px
    /// relative (displacement and path), on a tilted plane and at infinity,
    /// every row of the sensor; [`Line::pixel`] gives the same channels.
    #[test]
    fn pinhole_equals_the_shared_track_per_pixel() {
        for plane in [Some((DVec3::new(0.1, -0.2, 1.0).normalize(), 2.5)), None] {
            let (cam, line) = line(plane);
            for j in 0..cam.height as usize {
                let ray = |m: usize| cam.pixel_to_ray(m as f64 + 0.5, j as f64 + 0.5).unwrap();
                let n = cam.width as usize;
                let t = line.pinhole_tracks(&cam, ray, n);
                let mut out = vec![[f32::NAN; 5]; n];
                line.pinhole(&cam, ray, &mut out);
                for (m, o) in out.iter().enumerate() {
                    let r = DVec3::new(ray(m).0, ray(m).1, 1.0);
                    let point = ScenePoint {
                        ray: r,
                        inv_depth: line.inv_depth(r).unwrap(),
                    };
                    let want = track::path_px(&cam, &line.steps, &point).unwrap();
                    assert!(!t.bad[m] && want.len_px > 0.5, "row {j} px {m}");
                    let tol = 1e-9 * want.len_px;
                    let got = (t.px[m] - t.x0[m], t.py[m] - t.y0[m], t.path[m]);
                    assert!((got.0 - want.disp.0).abs() < tol, "{got:?} vs {want:?}");
                    assert!((got.1 - want.disp.1).abs() < tol, "{got:?} vs {want:?}");
                    assert!((got.2 - want.len_px).abs() < tol, "{got:?} vs {want:?}");
                    let px = line.pixel(&cam, ray(m)).unwrap();
                    let f = |x: f64| x as f32;
                    assert_eq!(&px[..3], &[f(want.disp.0), f(want.disp.1), f(want.len_px)]);
                    let close = |a: f32, b: f32| (a - b).abs() <= 1e-6 * (1.0 + a.abs());
                    assert!(px.iter().zip(o).all(|(a, b)| close(*a, *b)));
                }
            }
        }
    }
}
