//! Ground-truth blur maps (docs/spec.md section 4): for every pixel, the scene point
//! seen at its centre at exposure start is followed through the exposure;
//! its image path length (px), end-to-start displacement (px) and
//! time-averaged image speed (px/s = path / duration). Their sensor means are
//! the "exposure MMBM". Pixels whose scene point is missing (ray misses the
//! target, or the point goes behind the camera, or the pixel lies beyond the
//! lens's radial distortion limit) are NaN and left out of the means.
//! The track itself (each line's window and poses, the projection through
//! the lens, the chords) is [`crate::model::track`]'s.

use super::target::Target;
use crate::camera::Camera;
use crate::model::track::{self, LineTrack, ScenePoint, Step};
use crate::model::trajectory::{Pose, Trajectory};
use rayon::prelude::*;

/// Per-pixel blur maps, row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct BlurMaps {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Exposure, s.
    pub duration: f64,
    /// Path length of the image point over the exposure, px.
    pub path_px: Vec<f32>,
    /// End-to-start displacement, px.
    pub disp_px: Vec<f32>,
    /// Time-averaged image speed, px/s.
    pub speed_px_s: Vec<f32>,
    /// Time-averaged image speed on the sensor, mm/s (the same path in mm:
    /// `speed_px_s` times the pitch with square, unskewed pixels).
    pub speed_mm_s: Vec<f32>,
}

/// Sensor means of [`BlurMaps`] (NaN pixels left out).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlurMeans {
    /// Mean path length, px (the exposure MMBM as a blur length).
    pub path_px: f64,
    /// Mean displacement, px.
    pub disp_px: f64,
    /// Mean speed, px/s (the exposure MMBM in px/s).
    pub speed_px_s: f64,
    /// Mean speed, mm/s (the exposure MMBM in mm/s).
    pub speed_mm_s: f64,
    /// Share of pixels with a valid track (0..1).
    pub valid: f64,
}

impl BlurMaps {
    /// Writes the maps as a float EXR (channels `path_px`, `disp_px`, `speed_px_s`).
    pub fn write_exr(&self, path: &std::path::Path) -> crate::error::Result<()> {
        crate::io::images::write_exr(
            path,
            self.width as usize,
            self.height as usize,
            &[
                ("path_px", &self.path_px),
                ("disp_px", &self.disp_px),
                ("speed_px_s", &self.speed_px_s),
            ],
        )
    }

    /// Sensor means, f64 accumulation.
    pub fn means(&self) -> BlurMeans {
        let mut s = [0.0f64; 4];
        let mut n = 0usize;
        for i in 0..self.path_px.len() {
            if self.path_px[i].is_finite() {
                s[0] += self.path_px[i] as f64;
                s[1] += self.disp_px[i] as f64;
                s[2] += self.speed_px_s[i] as f64;
                s[3] += self.speed_mm_s[i] as f64;
                n += 1;
            }
        }
        let d = n.max(1) as f64;
        BlurMeans {
            path_px: s[0] / d,
            disp_px: s[1] / d,
            speed_px_s: s[2] / d,
            speed_mm_s: s[3] / d,
            valid: n as f64 / self.path_px.len().max(1) as f64,
        }
    }
}

/// A pixel without a track: path, displacement (px) and path (mm) NaN.
const NO_TRACK: (f32, f32, f64) = (f32::NAN, f32::NAN, f64::NAN);

/// The window of the whole trajectory in `steps` chords
/// ([`LineTrack::whole`]): its start pose and its steps relative to it.
fn whole(traj: &Trajectory, steps: usize) -> (Pose, Vec<Step>) {
    let line = LineTrack::whole(traj, steps);
    (line.start, line.relative())
}

/// Image track (pixel coordinates) of the scene point seen at `(x, y)` at
/// exposure start, at `steps + 1` uniform times; `None` when it is lost.
pub fn track(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    x: f64,
    y: f64,
    steps: usize,
) -> Option<Vec<(f64, f64)>> {
    let (start, steps) = whole(traj, steps);
    track::track(cam, &steps, &scene_point(cam, target, &start, x, y)?)
}

/// [`track()`] for many pixel positions `points` (px), the poses computed once.
pub fn tracks(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    points: &[(f64, f64)],
    steps: usize,
) -> Vec<Option<Vec<(f64, f64)>>> {
    let (start, steps) = whole(traj, steps);
    points
        .iter()
        .map(|&(x, y)| track::track(cam, &steps, &scene_point(cam, target, &start, x, y)?))
        .collect()
}

/// The scene point seen at pixel position `(x, y)` from pose `start`
/// (relative to it, [`ScenePoint::from_world`]): `None` beyond the lens's
/// radial limit or where the ray misses the target.
fn scene_point(cam: &Camera, target: &Target, start: &Pose, x: f64, y: f64) -> Option<ScenePoint> {
    if masked(cam, x, y) {
        return None;
    }
    let p = target.intersect(cam, start, x, y)?;
    Some(ScenePoint::from_world(start, p))
}

/// Path length and end-to-start displacement (px) and path length on the
/// sensor (mm) of the scene point seen at `(x, y)` from pose `start`, over
/// `steps` relative to it ([`track::path`]).
fn path_disp(
    cam: &Camera,
    target: &Target,
    start: &Pose,
    steps: &[Step],
    x: f64,
    y: f64,
) -> Option<(f64, f64, f64)> {
    let p = track::path(cam, steps, &scene_point(cam, target, start, x, y)?)?;
    Some((p.len_px, p.disp_px(), p.len_mm))
}

/// True for a pixel position beyond the lens's radial distortion limit: no ray.
fn masked(cam: &Camera, x: f64, y: f64) -> bool {
    if cam.distortion.is_none() {
        return false;
    }
    let (ud, vd) = cam.pixel_to_mm(x, y);
    cam.is_masked_mm(ud, vd)
}

/// Largest image path length (px) over the sensor: points on a 33 x 25 grid
/// spanning the sensor edge to edge, 256 time steps, at least the rotation
/// bound below, times 1.1 for safety.
pub fn max_path_px(cam: &Camera, target: &Target, traj: &Trajectory) -> f64 {
    max_path_px_in(cam, target, traj, None)
}

/// [`max_path_px`] over the pixels of `window` only, `[x0, y0, w, h]` px
/// (None, or a window that is the whole image: the whole sensor, the same
/// number; a [`Window`](super::Window) as its four fields): the grid's points
/// span the window edge to edge, no farther apart than the whole sensor's
/// grid (at least 2 x 2 points), and the rotation bound is the image motion
/// of each step's rotation at the window's largest distances from the
/// principal point, axis by axis. About the optical axis the image moves in
/// proportion to the radius, so a window near the centre needs fewer
/// instants for the same spacing between them.
pub fn max_path_px_in(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    window: Option<[u32; 4]>,
) -> f64 {
    let window = window.filter(|&w| w != [0, 0, cam.width, cam.height]);
    let grid = match window {
        None => Grid::whole(cam),
        Some(win) => Grid::over(cam, win),
    };
    // A camera that does not move (e.g. a sharp reference): every grid path
    // is 0 px but for rounding in the interpolated steps (under 1e-9 px, a
    // test), so neither the steps nor the grid are computed; the samples it
    // sets are the same.
    let m = if traj.is_still() {
        0.0
    } else {
        grid_max_path_px(cam, target, traj, &grid)
    };
    // Points that leave the view still smear the pixels they cross: bound the
    // image motion of rotation over the pixels.
    let table = traj.table(4096);
    let rot = match window {
        // The whole sensor: the angle turned times the focal length in px at
        // the sensor corner (where d(pixel)/d(angle) is largest).
        None => {
            let r = cam.sensor_rect();
            let corner2 = r.u0.abs().max(r.u1.abs()).powi(2) + r.v0.abs().max(r.v1.abs()).powi(2);
            let gain =
                cam.fx_px().max(cam.fy_px()) * (1.0 + corner2 / (cam.focal_mm * cam.focal_mm));
            let angle: f64 = table.windows(2).map(|w| w[0].0.angle_between(w[1].0)).sum();
            angle * gain
        }
        // A window: each step's rotation (camera axes) through the image
        // motion of a rotation at normalised image point (x, y), component
        // by component at the window's largest |x| and |y| (so about the
        // optical axis the bound grows with the radius, not the focal length).
        Some([x0, y0, w, h]) => {
            let (x0, y0) = (f64::from(x0), f64::from(y0));
            let (x1, y1) = (x0 + f64::from(w), y0 + f64::from(h));
            let (mut xm, mut ym) = (0.0f64, 0.0f64);
            for (x, y) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)] {
                let (u, v) = cam.pixel_to_mm(x, y);
                xm = xm.max(u.abs() / cam.focal_mm);
                ym = ym.max(v.abs() / cam.focal_mm);
            }
            let f = cam.fx_px().max(cam.fy_px());
            table
                .windows(2)
                .map(|w| {
                    let q = w[0].0.inverse() * w[1].0;
                    // The short way round (q and -q are the same rotation).
                    let d = if q.w < 0.0 { -q } else { q }.to_scaled_axis().abs();
                    let du = xm * ym * d.x + (1.0 + xm * xm) * d.y + ym * d.z;
                    let dv = (1.0 + ym * ym) * d.x + xm * ym * d.y + xm * d.z;
                    f * du.hypot(dv)
                })
                .sum()
        }
    };
    m.max(rot) * 1.1
}

/// The points of [`max_path_px_in`]'s grid: `nx` x `ny` spanning
/// `[x0, x0 + w] x [y0, y0 + h]` (px) edge to edge.
struct Grid {
    x0: f64,
    y0: f64,
    w: f64,
    h: f64,
    nx: u32,
    ny: u32,
}

impl Grid {
    /// The whole sensor's grid: 33 x 25 points edge to edge.
    fn whole(cam: &Camera) -> Grid {
        Grid {
            x0: 0.0,
            y0: 0.0,
            w: cam.width as f64,
            h: cam.height as f64,
            nx: 33,
            ny: 25,
        }
    }

    /// The grid over window `[x0, y0, w, h]`: as dense as the whole
    /// sensor's 33 x 25 grid or denser, at least 2 x 2.
    fn over(cam: &Camera, [x0, y0, w, h]: [u32; 4]) -> Grid {
        let (w, h) = (f64::from(w), f64::from(h));
        let n =
            |len: f64, sensor: f64, cells: f64| (len / (sensor / cells)).ceil().max(1.0) as u32 + 1;
        Grid {
            x0: f64::from(x0),
            y0: f64::from(y0),
            w,
            h,
            nx: n(w, cam.width as f64, 32.0),
            ny: n(h, cam.height as f64, 24.0),
        }
    }
}

/// [`max_path_px_in`]'s grid: the longest path (px) of the points seen at
/// `grid`'s points at exposure start, over 256 time steps (0 when none is seen).
fn grid_max_path_px(cam: &Camera, target: &Target, traj: &Trajectory, grid: &Grid) -> f64 {
    let (start, poses) = whole(traj, 256);
    let mut m: f64 = 0.0;
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            let x = grid.x0 + grid.w * i as f64 / (grid.nx - 1) as f64;
            let y = grid.y0 + grid.h * j as f64 / (grid.ny - 1) as f64;
            // The path in px only (track::path_px: path_disp's number).
            let path = scene_point(cam, target, &start, x, y)
                .and_then(|p| track::path_px(cam, &poses, &p));
            if let Some(p) = path {
                m = m.max(p.len_px);
            }
        }
    }
    m
}

/// Computes the maps with `steps` time steps (chords of the track; choose
/// steps so that a chord is well under a pixel, e.g. `max_path_px / 0.25`).
///
/// With a rolling shutter each pixel's path is over its own line's window
/// of `exposure_s` seconds (the trajectory spans readout + exposure; docs/spec.md section 9)
/// and the speed is the path over the line's exposure. With a global
/// shutter the window is the whole trajectory.
pub fn blur_maps(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    exposure_s: f64,
    steps: usize,
) -> BlurMaps {
    if !cam.shutter.is_global() {
        return blur_maps_rolling(cam, target, traj, exposure_s, steps);
    }
    let (start, poses) = whole(traj, steps.max(1));
    let (w, h) = (cam.width as usize, cam.height as usize);
    let dur = traj.duration();
    // Once a stop is requested (crate::cancel) the pixels left are NaN; the
    // caller checks the token and drops the maps.
    let stop = crate::cancel::current();
    let vals: Vec<(f32, f32, f64)> = (0..w * h)
        .into_par_iter()
        .map(|idx| {
            if stop.is_cancelled() {
                return NO_TRACK;
            }
            let (i, j) = (idx % w, idx / w);
            match path_disp(cam, target, &start, &poses, i as f64 + 0.5, j as f64 + 0.5) {
                Some((l, d, mm)) => (l as f32, d as f32, mm),
                None => NO_TRACK,
            }
        })
        .collect();
    BlurMaps {
        width: cam.width,
        height: cam.height,
        duration: dur,
        path_px: vals.iter().map(|v| v.0).collect(),
        disp_px: vals.iter().map(|v| v.1).collect(),
        speed_px_s: vals.iter().map(|v| (v.0 as f64 / dur) as f32).collect(),
        speed_mm_s: vals.iter().map(|v| (v.2 / dur) as f32).collect(),
    }
}

/// The blur maps' steps for a largest image path of `max_path_px` px
/// ([`super::render_frame`]'s maps): a step per quarter pixel, 64 to 4096.
pub fn steps_for(max_path_px: f64) -> usize {
    ((max_path_px / 0.25).ceil() as usize).clamp(64, 4096)
}

/// The sensor means of the path length and the displacement (px) of
/// [`blur_maps`] (`blur_maps(..).means()`'s `path_px` and `disp_px`, the
/// same numbers, bit for bit) without keeping the maps and without the
/// millimetre paths. A rolling shutter takes [`blur_maps`] itself.
pub fn path_means(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    exposure_s: f64,
    steps: usize,
) -> (f64, f64) {
    if !cam.shutter.is_global() {
        let m = blur_maps(cam, target, traj, exposure_s, steps).means();
        return (m.path_px, m.disp_px);
    }
    let (start, poses) = whole(traj, steps.max(1));
    let w = cam.width as usize;
    let stop = crate::cancel::current();
    let vals: Vec<(f32, f32)> = (0..w * cam.height as usize)
        .into_par_iter()
        .map(|idx| {
            let (i, j) = (idx % w, idx / w);
            let track = (!stop.is_cancelled())
                .then(|| scene_point(cam, target, &start, i as f64 + 0.5, j as f64 + 0.5))
                .flatten()
                .and_then(|x| track::path_px(cam, &poses, &x));
            track.map_or((f32::NAN, f32::NAN), |p| {
                (p.len_px as f32, p.disp_px() as f32)
            })
        })
        .collect();
    // As BlurMaps::means: the finite pixels, in order, f64 accumulation.
    let (mut s, mut n) = ([0.0f64; 2], 0usize);
    for v in vals.iter().filter(|v| v.0.is_finite()) {
        s[0] += v.0 as f64;
        s[1] += v.1 as f64;
        n += 1;
    }
    let d = n.max(1) as f64;
    (s[0] / d, s[1] / d)
}

/// [`blur_maps`] with a rolling shutter: one pose table per line (row or
/// column), over that line's exposure window.
fn blur_maps_rolling(
    cam: &Camera,
    target: &Target,
    traj: &Trajectory,
    te: f64,
    steps: usize,
) -> BlurMaps {
    let steps = steps.max(1);
    let rows = cam.shutter.direction.is_rows();
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (lines, len) = if rows { (h, w) } else { (w, h) };
    let stop = crate::cancel::current();
    let per_line: Vec<Vec<(f32, f32, f64)>> = (0..lines)
        .into_par_iter()
        .map(|l| {
            if stop.is_cancelled() {
                return vec![NO_TRACK; len];
            }
            // The line's window and poses: the one per-pixel track's.
            let line = LineTrack::line(traj, &cam.shutter, cam, l, te, steps);
            let (start, poses) = (line.start, line.relative());
            (0..len)
                .map(|m| {
                    let (i, j) = if rows { (m, l) } else { (l, m) };
                    match path_disp(cam, target, &start, &poses, i as f64 + 0.5, j as f64 + 0.5) {
                        Some((a, d, mm)) => (a as f32, d as f32, mm),
                        None => NO_TRACK,
                    }
                })
                .collect()
        })
        .collect();
    let mut path = vec![0f32; w * h];
    let mut disp = vec![0f32; w * h];
    let mut speed_mm = vec![0f32; w * h];
    for (l, vals) in per_line.iter().enumerate() {
        for (m, v) in vals.iter().enumerate() {
            let idx = if rows { l * w + m } else { m * w + l };
            path[idx] = v.0;
            disp[idx] = v.1;
            speed_mm[idx] = (v.2 / te) as f32;
        }
    }
    BlurMaps {
        width: cam.width,
        height: cam.height,
        duration: te,
        speed_mm_s: speed_mm,
        speed_px_s: path.iter().map(|&p| (p as f64 / te) as f32).collect(),
        path_px: path,
        disp_px: disp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DQuat, DVec3};

    /// A camera that does not move: every grid point's path, computed point
    /// by point over the 256 steps, is under 1e-9 px (rounding in the
    /// interpolated steps), so skipping the grid changes no sample count.
    #[test]
    fn a_still_camera_skips_the_grid_with_the_same_samples() {
        let cam = Camera::thesis().with_resolution(160, 120);
        let target = Target::parse("blobs", 2.0).unwrap();
        let pose = (
            DQuat::from_rotation_y(0.1) * DQuat::from_rotation_x(-0.05),
            DVec3::new(0.01, -0.02, 0.0),
        );
        let still = Trajectory::from_poses(0.07, vec![pose, pose]).unwrap();
        assert!(still.is_still());
        let (start, steps) = whole(&still, 256);
        let (mut seen, mut grid) = (0, 0.0f64);
        for j in 0..25 {
            for i in 0..33 {
                let (x, y) = (160.0 * i as f64 / 32.0, 120.0 * j as f64 / 24.0);
                if let Some(p) = scene_point(&cam, &target, &start, x, y)
                    .and_then(|p| track::path_px(&cam, &steps, &p))
                {
                    grid = grid.max(p.len_px);
                    seen += 1;
                }
            }
        }
        assert!(seen > 100, "the board fills the view: {seen} points");
        assert!(grid < 1e-9, "{grid}");
        assert_eq!(
            grid_max_path_px(&cam, &target, &still, &Grid::whole(&cam)),
            grid
        );
        let m = max_path_px(&cam, &target, &still);
        assert!(m < 1e-6, "{m}");
        for q in [
            crate::render::Quality::Default,
            crate::render::Quality::Fast,
        ] {
            assert_eq!(
                q.instants_for(m).unwrap(),
                q.instants_for(grid * 1.1).unwrap()
            );
            assert_eq!(
                q.samples_for(m).unwrap(),
                q.samples_for(grid * 1.1).unwrap()
            );
        }
        // A moving camera still measures its grid.
        let moving = Trajectory::from_poses(
            0.07,
            vec![pose, (pose.0 * DQuat::from_rotation_y(0.01), pose.1)],
        )
        .unwrap();
        assert!(!moving.is_still());
        let m = max_path_px(&cam, &target, &moving);
        assert!(m > 1.0, "{m}");
    }
}
