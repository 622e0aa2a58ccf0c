//! Motion-blur augmentation of any image (`mmbm.augment` in Python): the
//! image as a plane filling the view, blurred by the renderer along a real
//! or simulated camera motion, with the per-pixel blur maps and the
//! homographies that carry labels (keypoints, homographies) from the image
//! to the blurred frame.
//!
//! Geometry: the camera has the image's size in pixels (the thesis focal
//! length and pitch unless a camera is given, which must have that size);
//! the image, `zoom` times the field of view wide (1: it fills the view), is
//! a plane `distance_m` in front of the camera, facing it, at the reference
//! pose. The reference pose, where the image is the sharp frame, is the
//! camera at the instant `sharp` ([`SharpAt`]): exposure start (default), its
//! middle (the motion re-based on its middle pose: no net shift, the blur
//! spread around each point's place, the GoPro / REDS convention) or its end.
//! Where the moving view leaves the image, the background colour shows.
//!
//! Homographies: `H(t)` maps image pixel coordinates (fractional, `(0, 0)`
//! the top-left corner, as [`crate::render::project`]'s) to the frame's
//! pixel coordinates at time `t` after exposure start; returned at exposure
//! start, middle and end (exact for a camera without lens distortion, and
//! refused with one since the map is not a homography then).

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::io::gyro::GyroSample;
use crate::model::motion::Twist;
use crate::render::{
    self, Backend, BlurMaps, Pose, Quality, RenderJob, SharpAt, Target, Trajectory,
};
use crate::sim::{simulate, Gait, GaitConfig};
use glam::{DMat3, DVec3};
use rand::{Rng, SeedableRng};

/// Poses in the table of a re-based trajectory (`sharp` not at the start).
const CENTRED_POSES: usize = 1024;
/// Seconds of simulated walk before a drawn exposure may start.
const SETTLE_S: f64 = 1.0;
/// Seconds of simulated walk an exposure start is drawn from.
const DRAW_S: f64 = 4.0;

/// The camera motion of an augmentation.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// A constant twist (camera frame; rad/s, m/s).
    Twist(Twist),
    /// A window of a gyro log: the exposure starts at `at` s (log clock).
    Log {
        /// The samples.
        samples: Vec<GyroSample>,
        /// Exposure start, s.
        at: f64,
    },
    /// A simulated walk of this gait (seeded), the exposure starting at a
    /// time drawn from the seed.
    Gait(Gait),
    /// A random shake: a gait drawn from the seed, then as [`Motion::Gait`].
    Shake,
}

/// An augmentation's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Augment {
    /// The motion.
    pub motion: Motion,
    /// Exposure, s.
    pub exposure_s: f64,
    /// The camera (its size must be the image's); `None`: the thesis focal
    /// length and pitch at the image's size.
    pub camera: Option<Camera>,
    /// Distance of the image plane, m (matters only with translation).
    pub distance_m: f64,
    /// The image's width over the field of view's at the reference pose.
    pub zoom: f64,
    /// The reference pose (where the image is the sharp frame): at exposure
    /// start, its middle (no net shift) or its end.
    pub sharp: SharpAt,
    /// Seed (simulated motion, the renderer's sample shifts).
    pub seed: u64,
    /// Render preset.
    pub quality: Quality,
    /// Linear RGB where the view leaves the image.
    pub background: [f32; 3],
    /// Whether translation from a log or a walk is used (else rotation only).
    pub use_velocity: bool,
}

impl Augment {
    /// Defaults: `exposure_s` of the given motion, thesis camera, 2 m, zoom
    /// 1, exposure start as reference (`sharp` [`SharpAt::Start`]), seed 0, `default` preset, black
    /// background, translation used.
    pub fn new(motion: Motion, exposure_s: f64) -> Self {
        Augment {
            motion,
            exposure_s,
            camera: None,
            distance_m: 2.0,
            zoom: 1.0,
            sharp: SharpAt::Start,
            seed: 0,
            quality: Quality::default(),
            background: [0.0; 3],
            use_velocity: true,
        }
    }
}

/// An augmented image.
#[derive(Debug, Clone)]
pub struct Augmented {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Linear RGB, interleaved, row-major.
    pub rgb: Vec<f32>,
    /// Per-pixel blur maps (path length, displacement, speed).
    pub maps: BlurMaps,
    /// Image px to frame px at exposure start, middle and end (row-major 3x3).
    pub homographies: [[f64; 9]; 3],
    /// What the motion was (e.g. `sim:moderate@3.217s`, `twist`).
    pub motion: String,
}

/// Pose `p` seen from pose `r`: `r^-1 p`.
fn relative(r: &Pose, p: &Pose) -> Pose {
    let qi = r.0.inverse();
    ((qi * p.0).normalize(), qi * (p.1 - r.1))
}

/// The image-px-to-frame-px homography at pose `pose` of the plane `target`.
fn image_to_frame(cam: &Camera, target: &Target, tex: (u32, u32), pose: &Pose) -> Result<DMat3> {
    // Image px -> plane (a, b) m: centred, width_m wide, square pixels.
    let width_m = match &target.kind {
        render::TargetKind::Image { width_m, .. } => *width_m,
        _ => return Err(Error::invalid("augment", "the target is not an image")),
    };
    let s = width_m / tex.0 as f64;
    let img_to_plane = DMat3::from_cols(
        DVec3::new(s, 0.0, 0.0),
        DVec3::new(0.0, s, 0.0),
        DVec3::new(-0.5 * width_m, -0.5 * s * tex.1 as f64, 1.0),
    );
    let pixel_to_plane = render::homography::homography(cam, target, pose);
    let inv = pixel_to_plane.inverse();
    if !inv.is_finite() {
        return Err(Error::invalid(
            "augment",
            "the image plane is seen edge-on during the exposure",
        ));
    }
    let h = inv * img_to_plane;
    Ok(h * (1.0 / h.z_axis.z))
}

fn row_major(m: &DMat3) -> [f64; 9] {
    let t = m.transpose().to_cols_array();
    [t[0], t[1], t[2], t[3], t[4], t[5], t[6], t[7], t[8]]
}

/// The motion's trajectory over `span` s and its description.
fn trajectory(a: &Augment, span: f64) -> Result<(Trajectory, String)> {
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

/// Blurs the linear RGB image `rgb` (`w` x `h`, interleaved) as [`Augment`] says.
pub fn augment(w: u32, h: u32, rgb: &[f32], a: &Augment) -> Result<Augmented> {
    crate::check::positive("exposure (s)", a.exposure_s)?;
    crate::check::positive("distance (m)", a.distance_m)?;
    crate::check::positive("zoom", a.zoom)?;
    if w < 2 || h < 2 || rgb.len() != w as usize * h as usize * 3 {
        return Err(Error::invalid(
            "augment image",
            format!(
                "{w} x {h} px with {} values: expected (H, W, 3), at least 2 x 2",
                rgb.len()
            ),
        ));
    }
    if let Some(i) = rgb.iter().position(|x| !x.is_finite()) {
        return Err(Error::invalid(
            "augment image",
            format!(
                "value {i} (pixel {}, {}) is not finite",
                (i / 3) % w as usize,
                i / 3 / w as usize
            ),
        ));
    }
    let cam = match &a.camera {
        Some(c) => *c,
        None => crate::camera::CameraFile::default().thesis_at([w, h]),
    };
    cam.validate()?;
    if (cam.width, cam.height) != (w, h) {
        return Err(Error::invalid(
            "augment camera",
            format!(
                "{} x {} px where the image is {w} x {h}",
                cam.width, cam.height
            ),
        ));
    }
    if !cam.distortion.is_none() {
        return Err(Error::invalid(
            "augment camera",
            "lens distortion: the image-to-frame map is not a homography (not supported)",
        ));
    }
    // The image spans zoom x the view's width at the plane's distance.
    let r = cam.sensor_rect();
    let width_m = a.zoom * (r.u1 - r.u0) / cam.focal_mm * a.distance_m;
    let texture = render::texture::MipTexture::from_linear(w, h, rgb.to_vec())?;
    let mut target = Target::from_texture(texture, width_m, a.distance_m);
    target.background = a.background;
    let span = a.exposure_s + cam.shutter.readout_s;
    let (traj, what) = trajectory(a, span)?;
    let traj = if !a.sharp.is_start() {
        // Re-based on the pose at that instant (of the exposure, or of the
        // whole rolling-shutter span).
        let reference = traj.pose_at(a.sharp.fraction() * span);
        let poses = traj
            .table(CENTRED_POSES)
            .iter()
            .map(|p| relative(&reference, p))
            .collect();
        Trajectory::from_poses(span, poses)?
    } else {
        traj
    };
    let tex = (w, h);
    let homographies = [0.0, 0.5, 1.0].map(|f| {
        image_to_frame(&cam, &target, tex, &traj.pose_at(f * span)).map(|m| row_major(&m))
    });
    let [h0, h1, h2] = homographies;
    let homographies = [h0?, h1?, h2?];
    let mut job = RenderJob::new(cam, a.exposure_s, traj, target);
    job.quality = a.quality;
    job.backend = Backend::Cpu { threads: None };
    job.seed = a.seed as u32;
    job.with_maps = true;
    let out = render::render_frame(&job)?;
    let maps = out
        .maps
        .ok_or_else(|| Error::invalid("augment", "the renderer returned no blur maps"))?;
    Ok(Augmented {
        width: out.width,
        height: out.height,
        rgb: out.rgb,
        maps,
        homographies,
        motion: what,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn relative_pose_undoes_the_reference() {
        let r: Pose = (DQuat::from_rotation_y(0.3), DVec3::new(0.1, -0.2, 0.05));
        let p: Pose = (
            DQuat::from_rotation_x(-0.2) * r.0,
            DVec3::new(0.4, 0.0, 0.1),
        );
        let q = relative(&r, &r);
        assert!(q.0.angle_between(DQuat::IDENTITY) < 1e-12 && q.1.length() < 1e-12);
        // r * relative(r, p) = p.
        let b = relative(&r, &p);
        let back = (r.0 * b.0, r.0 * b.1 + r.1);
        assert!(back.0.angle_between(p.0) < 1e-12 && (back.1 - p.1).length() < 1e-12);
    }
}
