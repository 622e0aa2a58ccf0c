//! One line of a frame's maps: its motion over its exposure ([`LineMotion`],
//! which the GPU path packs: the poses of the line's window, the one
//! per-pixel track's [`LineTrack`], relative to the line's start) and its
//! track in f64, the CPU path of
//! [`super::frame_maps`] (the motion as matrices, each pixel
//! projected through them).

use crate::camera::Camera;
use crate::model::flow::FlowPoly;
use crate::model::log::ImuLog;
use crate::model::motion::{Plane, Twist};
use crate::model::track::LineTrack;
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
        let steps_v = track
            .poses
            .iter()
            .map(|&(q, c)| {
                let inv = q.inverse();
                (inv * qs, inv * (cs - c))
            })
            .collect();
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

/// One line's motion over its exposure, in matrices (the f64 path).
pub(crate) struct Line {
    /// World-to-camera rotation at the line's start (camera-to-world transposed).
    start_rot: DMat3,
    /// Rotation from the line's start frame to each instant's, and the
    /// offset of the start's centre in each instant's frame (m).
    steps: Vec<(DMat3, DVec3)>,
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
    /// the undistorted ray of the line's pixel `m`): the pixel matrix folded
    /// into each instant's rotation, step-major over the line's pixels so
    /// the inner loop vectorises. The same values to rounding.
    pub fn pinhole(&self, cam: &Camera, ray: impl Fn(usize) -> (f64, f64), out: &mut [[f32; 5]]) {
        let n = out.len();
        let kmat = DMat3::from_cols(
            DVec3::new(cam.focal_mm / cam.pitch_x_mm, 0.0, 0.0),
            DVec3::new(cam.skew, cam.focal_mm / cam.pitch_y_mm, 0.0),
            DVec3::new(cam.cx, cam.cy, 1.0),
        );
        let mut buf = vec![0.0f64; 8 * n];
        let (rx, rest) = buf.split_at_mut(n);
        let (ry, rest) = rest.split_at_mut(n);
        let (is, rest) = rest.split_at_mut(n);
        let (x0, rest) = rest.split_at_mut(n);
        let (y0, rest) = rest.split_at_mut(n);
        let (px, rest) = rest.split_at_mut(n);
        let (py, rest) = rest.split_at_mut(n);
        let path = rest;
        let mut bad = vec![false; n];
        for m in 0..n {
            let r = ray(m);
            rx[m] = r.0;
            ry[m] = r.1;
            match self.inv_depth(DVec3::new(r.0, r.1, 1.0)) {
                Some(x) if r.0.is_finite() && r.1.is_finite() => is[m] = x,
                _ => bad[m] = true,
            }
        }
        for (k, (rot, off)) in self.steps.iter().enumerate() {
            let a = kmat * *rot;
            let c = kmat * *off;
            let (a0, a1, a2) = (a.x_axis, a.y_axis, a.z_axis);
            for m in 0..n {
                let (x, y, s) = (rx[m], ry[m], is[m]);
                let z = a0.z * x + a1.z * y + a2.z + c.z * s;
                bad[m] |= z.is_nan() || z <= 1e-12;
                let q = 1.0 / z;
                let u = (a0.x * x + a1.x * y + a2.x + c.x * s) * q;
                let v = (a0.y * x + a1.y * y + a2.y + c.y * s) * q;
                if k == 0 {
                    x0[m] = u;
                    y0[m] = v;
                } else {
                    let (du, dv) = (u - px[m], v - py[m]);
                    path[m] += (du * du + dv * dv).sqrt();
                }
                px[m] = u;
                py[m] = v;
            }
        }
        for m in 0..n {
            if bad[m] {
                continue;
            }
            let fl = self.flow.eval(cam.focal_mm * rx[m], cam.focal_mm * ry[m]);
            let (fu, fv) = cam.mm_to_px_velocity(fl.0, fl.1);
            out[m] = [
                (px[m] - x0[m]) as f32,
                (py[m] - y0[m]) as f32,
                path[m] as f32,
                fu as f32,
                fv as f32,
            ];
        }
    }

    /// The five channels of the pixel whose undistorted ray is `r`, or `None`.
    #[inline]
    pub fn pixel(&self, cam: &Camera, r: (f64, f64)) -> Option<[f32; 5]> {
        if !r.0.is_finite() {
            return None;
        }
        let ray = DVec3::new(r.0, r.1, 1.0);
        let inv_s = self.inv_depth(ray)?;
        let project = |m: &DMat3, b: DVec3| -> Option<(f64, f64)> {
            let p = *m * ray + b * inv_s;
            (p.z > 1e-12).then(|| cam.ray_to_pixel(p.x / p.z, p.y / p.z))
        };
        let first = project(&self.steps[0].0, self.steps[0].1)?;
        let (mut prev, mut path) = (first, 0.0);
        for (m, b) in &self.steps[1..] {
            let q = project(m, *b)?;
            let (du, dv) = (q.0 - prev.0, q.1 - prev.1);
            path += (du * du + dv * dv).sqrt();
            prev = q;
        }
        let (u, v) = (cam.focal_mm * r.0, cam.focal_mm * r.1);
        let fl = self.flow.eval(u, v);
        let fl = if cam.distortion.is_none() {
            fl
        } else {
            crate::camera::distortion::apply(&cam.distortion_jacobian(u, v), fl)
        };
        let (fu, fv) = cam.mm_to_px_velocity(fl.0, fl.1);
        Some([
            (prev.0 - first.0) as f32,
            (prev.1 - first.1) as f32,
            path as f32,
            fu as f32,
            fv as f32,
        ])
    }
}
