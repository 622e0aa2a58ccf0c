//! Motion-blur augmentation of any image (`mmbm.augment` in Python): the
//! image as a plane filling the view, blurred along a real or simulated
//! camera motion, with the per-pixel blur maps, the homographies that carry
//! labels (keypoints, homographies) from the image to the blurred frame,
//! and on request the per-pixel displacement fields.
//!
//! Geometry: the camera has the image's size in pixels (the thesis focal
//! length and pitch unless a camera is given, which must have that size);
//! the image, `zoom` times the field of view wide (1: it fills the view), is
//! a plane `distance_m` in front of the camera, facing it, at the reference
//! pose. The reference pose, where the image is the sharp frame, is the
//! camera at the instant `sharp` ([`SharpAt`]): exposure start (default), its
//! middle (the motion re-based on its middle pose: no net shift, the blur
//! spread around each point's place, the GoPro / REDS convention) or its end. Where the moving view
//! leaves the image, the [`Border`] shows (default: the image mirrored).
//!
//! Integrators ([`Integrator`]): `fast` (default) and `exact` average the
//! image's bilinear interpolant at each pixel centre's path over instants
//! spaced at most 1 px (fast: within the image contract, mean 0.5/255 and
//! p99 3/255 against the exact time integral; 2 px is not) or 1/32 px
//! (exact: within 0.02/255) apart along the longest path ([`bound`],
//! [`warp`]); `render` is the renderer (each pixel the
//! exact integral of the interpolant over its area and the exposure, so a
//! still image is the (1/8, 3/4, 1/8) filter of the input). The warp
//! integrators run on the CPU or, with [`Augment::backend`], on the GPU
//! ([`gpu`], `warp.wgsl`; its CPU twin [`warp_kernel`]). Without motion
//! every integrator returns the input bit for bit. The blur maps are
//! computed only when asked for ([`Augment::maps`]): they cost more than
//! the fast blur itself.
//!
//! Homographies: `H(t)` maps image pixel coordinates (fractional, `(0, 0)`
//! the top-left corner, as [`crate::render::project`]'s) to the frame's
//! pixel coordinates at time `t` after exposure start; returned at exposure
//! start, middle and end (exact for a camera without lens distortion, and
//! refused with one since the map is not a homography then).

pub mod bound;
pub mod gpu;
pub mod motion;
pub mod pixels;
mod rendered;
pub mod warp;
pub mod warp_kernel;

pub use pixels::{Image, PixelBuf, Pixels};
pub use warp::Border;

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::io::gyro::GyroSample;
use crate::limits::{AUGMENT_MAX_PIXEL_SAMPLES, AUGMENT_MAX_WARP_SAMPLES};
use crate::model::motion::Twist;
use crate::render::{self, Backend, BlurMaps, Pose, Quality, SharpAt, Target};
use crate::sim::Gait;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::str::FromStr;

/// Largest shift (px) of any instant's map for the image to count as still.
const STILL_PX: f64 = 1e-6;

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

/// How the exposure is integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// Warp samples at most 1 px apart along the longest path (within the
    /// image contract; 2 px apart is not: `tests/augment/augment_speed.rs`).
    #[default]
    Fast,
    /// Warp samples at most 1/32 px apart (the reference of `fast`).
    Exact,
    /// The renderer: exact pixel-area and exposure integrals (`quality`).
    Render,
}

impl Integrator {
    /// Largest distance (px) between neighbouring warp samples.
    pub fn spacing_px(self) -> f64 {
        match self {
            Integrator::Fast => 1.0,
            _ => 1.0 / 32.0,
        }
    }

    /// Warp instants for a longest path of `path_px` px (peak speed,
    /// [`bound`]): the path over the spacing; `fast` takes at least
    /// [`FAST_MIN_SAMPLES`] instants (or 0.5 px apart if fewer suffice),
    /// since with a few instants the bilinear interpolant's errors at
    /// each no longer average out (a 3.6 px shake at 4 instants is at
    /// 0.52/255 mean). `render`: 1.
    pub fn samples(self, path_px: f64) -> usize {
        let n = |s: f64| (path_px / s).ceil().max(1.0) as usize;
        match self {
            Integrator::Render => 1,
            Integrator::Fast => n(1.0).max(n(0.5).min(FAST_MIN_SAMPLES)),
            Integrator::Exact => n(self.spacing_px()),
        }
    }
}

/// Fewest warp instants of `fast` for a path of 4 px or more ([`Integrator::samples`]).
pub const FAST_MIN_SAMPLES: usize = 8;

impl FromStr for Integrator {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "fast" => Ok(Integrator::Fast),
            "exact" => Ok(Integrator::Exact),
            "render" => Ok(Integrator::Render),
            _ => Err(Error::invalid(
                "integrator",
                format!("'{s}': expected fast, exact or render"),
            )),
        }
    }
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
    /// Render preset (integrator `render` only).
    pub quality: Quality,
    /// Linear RGB of the constant border.
    pub background: [f32; 3],
    /// Whether translation from a log or a walk is used (else rotation only).
    pub use_velocity: bool,
    /// The integrator.
    pub integrator: Integrator,
    /// Beyond the image's edges.
    pub border: Border,
    /// Scale the motion so that the mean path over the frame (the mean of
    /// the maps' `path_px`) is this many px.
    pub blur_px: Option<f64>,
    /// Also return the displacement fields.
    pub fields: bool,
    /// Also compute the blur maps ([`AugmentedImage::maps`]).
    pub maps: bool,
    /// Warp instants per pixel; `None` (default): from the longest path and
    /// the integrator's spacing ([`Integrator::spacing_px`]).
    pub warps: Option<usize>,
    /// Where the warp integrators run: `Bulk` (default: a hardware GPU,
    /// else the CPU; a software adapter such as lavapipe is slower than
    /// the CPU), `Auto` (any adapter, else the CPU), `Gpu` (an adapter or
    /// an error), `Cpu`. `render` always runs on the CPU.
    pub backend: Backend,
}

impl Augment {
    /// Defaults: `exposure_s` of the given motion, thesis camera, 2 m, zoom
    /// 1, exposure start as reference, seed 0, `fast` integrator, reflected
    /// border, black background, translation used, no blur target, no
    /// fields, no maps, warp instants from the path, backend `bulk`.
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
            integrator: Integrator::Fast,
            border: Border::Reflect,
            blur_px: None,
            fields: false,
            maps: false,
            warps: None,
            backend: Backend::Bulk,
        }
    }
}

/// An augmented linear RGB image ([`augment`]).
#[derive(Debug, Clone)]
pub struct Augmented {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Linear RGB, interleaved, row-major.
    pub rgb: Vec<f32>,
    /// Per-pixel blur maps (path length, displacement, speed), when asked
    /// for ([`Augment::maps`]).
    pub maps: Option<BlurMaps>,
    /// Image px to frame px at exposure start, middle and end (row-major 3x3).
    pub homographies: [[f64; 9]; 3],
    /// What the motion was (e.g. `sim:moderate@3.217s`, `twist`).
    pub motion: String,
}

/// An augmented image of any dtype ([`augment_image`]).
#[derive(Debug, Clone)]
pub struct AugmentedImage {
    /// The blurred image: the input's size, channels and dtype.
    pub pixels: PixelBuf,
    /// Per-pixel blur maps (path length, displacement, speed), when asked
    /// for ([`Augment::maps`]).
    pub maps: Option<BlurMaps>,
    /// Image px to frame px at exposure start, middle and end (row-major 3x3).
    pub homographies: [[f64; 9]; 3],
    /// With `fields`: for each frame pixel, the displacement (px; x, y) from
    /// its centre to the image point it sees at its line's exposure start,
    /// middle and end: 3 planes of (H, W, 2).
    pub fields: Option<Vec<f32>>,
    /// What the motion was (e.g. `sim:moderate@3.217s`, `twist`).
    pub motion: String,
    /// Warp instants per pixel (0: still, returned as given; 1 with `render`).
    pub samples: usize,
}

/// Image px -> plane (a, b) m: centred, `width_m` wide, square pixels.
fn image_to_plane(target: &Target, tex: (u32, u32)) -> Result<DMat3> {
    let width_m = match &target.kind {
        render::TargetKind::Image { width_m, .. } => *width_m,
        _ => return Err(Error::invalid("augment", "the target is not an image")),
    };
    let s = width_m / tex.0 as f64;
    Ok(DMat3::from_cols(
        DVec3::new(s, 0.0, 0.0),
        DVec3::new(0.0, s, 0.0),
        DVec3::new(-0.5 * width_m, -0.5 * s * tex.1 as f64, 1.0),
    ))
}

/// The frame-px-to-image-px map at pose `pose` (normalised, `[2][2] = 1`).
fn frame_to_image(cam: &Camera, target: &Target, tex: (u32, u32), pose: &Pose) -> Result<DMat3> {
    let g =
        image_to_plane(target, tex)?.inverse() * render::homography::homography(cam, target, pose);
    Ok(g * (1.0 / g.z_axis.z))
}

/// The image-px-to-frame-px homography at pose `pose` of the plane `target`.
fn image_to_frame(cam: &Camera, target: &Target, tex: (u32, u32), pose: &Pose) -> Result<DMat3> {
    let inv = frame_to_image(cam, target, tex, pose)?.inverse();
    if !inv.is_finite() {
        return Err(Error::invalid(
            "augment",
            "the image plane is seen edge-on during the exposure",
        ));
    }
    Ok(inv * (1.0 / inv.z_axis.z))
}

fn row_major(m: &DMat3) -> [f64; 9] {
    m.transpose().to_cols_array()
}

/// Blurs the linear RGB image `rgb` (`w` x `h`, interleaved) as [`Augment`] says.
pub fn augment(w: u32, h: u32, rgb: &[f32], a: &Augment) -> Result<Augmented> {
    let img = Image {
        width: w,
        height: h,
        channels: 3,
        pixels: Pixels::F32(rgb),
        srgb: false,
    };
    let out = augment_image(&img, a)?;
    let PixelBuf::F32(rgb) = out.pixels else {
        return Err(Error::invalid("augment", "float32 in, not float32 out"));
    };
    Ok(Augmented {
        width: w,
        height: h,
        rgb,
        maps: out.maps,
        homographies: out.homographies,
        motion: out.motion,
    })
}

/// [`augment_image`] over a batch, in parallel (one task per image): image
/// `k` with settings `a[k]`.
pub fn augment_batch(images: &[Image], a: &[Augment]) -> Result<Vec<AugmentedImage>> {
    if images.len() != a.len() {
        return Err(Error::invalid(
            "augment batch",
            format!("{} settings for {} images", a.len(), images.len()),
        ));
    }
    images
        .par_iter()
        .zip(a.par_iter())
        .enumerate()
        .map(|(k, (img, s))| {
            augment_image(img, s)
                .map_err(|e| Error::invalid("augment batch", format!("image {k}: {e}")))
        })
        .collect()
}

/// The checked camera of image `(w, h)`.
fn camera(a: &Augment, w: u32, h: u32) -> Result<Camera> {
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
    Ok(cam)
}

/// Blurs `img` as [`Augment`] says; the result has its size, channels and dtype.
pub fn augment_image(img: &Image, a: &Augment) -> Result<AugmentedImage> {
    augment_with(
        img,
        a,
        &|src, maps| match gpu::device(a.backend, src.w, src.h, maps.m.len())? {
            Some(ctx) => gpu::integrate(ctx, src, maps),
            None => Ok(warp::integrate(src, maps)),
        },
    )
}

/// [`augment_image`] with the warp integrators run by the GPU kernel's CPU
/// twin ([`warp_kernel`]; `backend` unused): the reference the GPU path is
/// checked against (`tests/augment_gpu.rs`).
pub fn augment_twin(img: &Image, a: &Augment) -> Result<AugmentedImage> {
    augment_with(img, a, &|src, maps| Ok(warp_kernel::twin(src, maps)))
}

/// The warp integrator's run: the warp average of a linear image over maps.
type WarpFn<'a> = &'a dyn Fn(&warp::Src, &warp::Maps) -> Result<Vec<f32>>;

fn augment_with(img: &Image, a: &Augment, warp_fn: WarpFn) -> Result<AugmentedImage> {
    crate::check::positive("exposure (s)", a.exposure_s)?;
    crate::check::positive("distance (m)", a.distance_m)?;
    crate::check::positive("zoom", a.zoom)?;
    if let Some(b) = a.blur_px {
        if !(b.is_finite() && (0.0..=crate::limits::AUGMENT_MAX_BLUR_PX).contains(&b)) {
            return Err(Error::invalid(
                "blur_px",
                format!(
                    "{b}: expected 0 to {} px",
                    crate::limits::AUGMENT_MAX_BLUR_PX
                ),
            ));
        }
    }
    img.validate()?;
    let (w, h) = (img.width, img.height);
    let cam = camera(a, w, h)?;
    // The image spans zoom x the view's width at the plane's distance.
    let r = cam.sensor_rect();
    let width_m = a.zoom * (r.u1 - r.u0) / cam.focal_mm * a.distance_m;
    // The geometry only (the warp reads the image itself).
    let texture = render::texture::MipTexture::from_linear(2, 2, vec![0.0; 12])?;
    let mut target = Target::from_texture(texture, width_m, a.distance_m);
    target.background = a.background;
    let span = cam.shutter.busy_s(a.exposure_s);
    let (traj, what) = motion::trajectory(a, span)?;
    let traj = match a.blur_px {
        Some(b) if b > 0.0 => motion::fit_blur(&cam, &target, &traj, b)?,
        _ => traj,
    };
    let traj = if !a.sharp.is_start() {
        motion::rebased(&traj, a.sharp.fraction())?
    } else {
        traj
    };
    let tex = (w, h);
    let homographies = [0.0, 0.5, 1.0].map(|f| {
        image_to_frame(&cam, &target, tex, &traj.pose_at(f * span)).map(|m| row_major(&m))
    });
    let [h0, h1, h2] = homographies;
    let homographies = [h0?, h1?, h2?];
    // The frame-to-image map of each line at each instant.
    let mode = render::homography::line_mode(&cam);
    let lines = render::homography::table_lines(&cam) as usize;
    let at = |line: usize, m: usize, n: usize| {
        let t = render::homography::line_instant(
            &cam,
            &traj,
            a.exposure_s,
            line as u32,
            m as u32,
            n as u32,
        );
        frame_to_image(&cam, &target, tex, &traj.pose_at(t))
    };
    let lmax = bound::longest_path_px(w, h, mode, at)?;
    let n = match (a.integrator, a.warps) {
        (Integrator::Render, _) => 1,
        (_, Some(n)) => n.max(1),
        (i, None) => i.samples(lmax),
    };
    let pixels = w as u64 * h as u64;
    if n > AUGMENT_MAX_WARP_SAMPLES || pixels * n as u64 > AUGMENT_MAX_PIXEL_SAMPLES {
        return Err(Error::invalid(
            "augment",
            format!(
                "{w} x {h} px x {n} warp samples ({lmax:.0} px of blur): at most \
                 {AUGMENT_MAX_WARP_SAMPLES} samples and {AUGMENT_MAX_PIXEL_SAMPLES} pixel-samples"
            ),
        ));
    }
    let mats: Vec<DMat3> = (0..lines * n)
        .map(|k| at(k / n, k % n, n))
        .collect::<Result<_>>()?;
    let (fw, fh) = (w as f64, h as f64);
    let moved = |m: &DMat3| warp::max_shift(m, fw, fh) >= STILL_PX;
    let still = !mats.iter().any(moved)
        && !homographies
            .iter()
            .any(|m| moved(&DMat3::from_cols_array(m).transpose()));
    let fields = a
        .fields
        .then(|| {
            // Instants 0, 1/2 and 1 of each line's exposure.
            let planes = [0.0, 0.5, 1.0].map(|f| {
                (0..lines)
                    .map(|l| {
                        let t = if cam.shutter.is_global() {
                            f * span
                        } else {
                            let c = l as f64 + 0.5;
                            cam.shutter.delay_s(c, c, w, h) + f * a.exposure_s
                        };
                        frame_to_image(&cam, &target, tex, &traj.pose_at(t))
                    })
                    .collect::<Result<Vec<_>>>()
            });
            let [p0, p1, p2] = planes;
            Ok::<_, Error>(warp::fields(w as usize, h as usize, mode, &[p0?, p1?, p2?]))
        })
        .transpose()?;
    let maps = if !a.maps {
        None
    } else if still {
        let zero = vec![0.0f32; (w * h) as usize];
        Some(BlurMaps {
            width: w,
            height: h,
            duration: traj.duration(),
            path_px: zero.clone(),
            disp_px: zero.clone(),
            speed_px_s: zero.clone(),
            speed_mm_s: zero,
        })
    } else {
        // Chords of about 2 px (the maps are a measure, not the image).
        let lmax = render::maps::max_path_px(&cam, &target, &traj);
        let steps = ((0.5 * lmax).ceil() as usize).clamp(8, 4096);
        Some(render::maps::blur_maps(
            &cam,
            &target,
            &traj,
            a.exposure_s,
            steps,
        ))
    };
    crate::cancel::check()?;
    let (pixels, samples) = if still {
        (img.pixels.to_buf(), 0)
    } else if a.integrator == Integrator::Render {
        (
            img.encode(rendered::rendered(img, a, &cam, traj, width_m)?),
            1,
        )
    } else {
        let lin = img.to_linear();
        let c = img.channels as usize;
        let fill: Vec<f32> = match c {
            1 => vec![a.background[0]],
            3 => a.background.to_vec(),
            _ => vec![0.0; 4],
        };
        let src = warp::Src {
            w: w as usize,
            h: h as usize,
            c,
            v: &lin,
            border: a.border,
            fill: &fill,
        };
        let maps = warp::Maps {
            m: mats.iter().map(warp::to_f32).collect(),
            n,
            mode,
        };
        (img.encode(warp_fn(&src, &maps)?), n)
    };
    crate::cancel::check()?;
    Ok(AugmentedImage {
        pixels,
        maps,
        homographies,
        fields,
        motion: what,
        samples,
    })
}

#[cfg(test)]
mod tests {
    use super::motion::relative;
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
