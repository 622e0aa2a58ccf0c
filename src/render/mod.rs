//! Ground-truth motion-blur renderer (docs/spec.md section 4).
//!
//! A textured planar [`Target`] seen by a [`Camera`] moving along a
//! [`Trajectory`] during one exposure (box shutter). Each pixel is the mean
//! over its area and the exposure time. Time: `N` instants (step midpoints,
//! the same for every pixel), at each one the homography from pixel to target
//! coordinates (`kernel`); `N` is chosen from the trajectory so that
//! consecutive instants are at most `quality.max_spacing_px()` apart on the
//! image (from the largest image path length over the sensor, or over the
//! job's [`RenderJob::spacing_window`]). Area, per
//! [`Integrator`]: `analytic` (the default without defocus) averages the
//! target over the pixel's footprint in closed form at each instant (the
//! checker and the blob board in `cpu`, images' bilinear interpolant in
//! `exact`); `lattice` (any target; the reference) supersamples area and time
//! with a rank-1 lattice and a per-pixel shift, at least `quality.min_samples()`.
//!
//! The GPU kernel is `render.wgsl` (`gpu`); its CPU twin (`cpu`) is
//! used when no adapter exists (announced once on stderr). [`maps`] gives the
//! per-pixel blur ground truth (path length, displacement, speed), `psf` the
//! point-spread function at a pixel; [`render_window`] renders a window of
//! a frame (the same pixels, none outside it).

pub mod clip;
pub mod clip_panorama;
pub(crate) mod cpu;
pub(crate) mod exact;
pub(crate) mod gpu;
pub(crate) mod homography;
pub(crate) mod kernel;
mod layout;
pub mod maps;
mod motion;
mod pixel_map;
pub mod poster;
pub(crate) mod psf;
mod rect;
mod sampling;
pub mod sharp;
#[doc(hidden)]
pub mod target;
pub mod texture;
mod window;

pub use crate::gpu::Backend;
pub use crate::model::trajectory::{Pose, Trajectory};
pub use gpu::{PRELUDE as PRELUDE_WGSL, SHADER as RENDER_WGSL, TEXTURE_SHADER as TEXTURE_WGSL};
pub use maps::{blur_maps, BlurMaps, BlurMeans};
pub use motion::FrameMotion;
pub use poster::Background;
pub use psf::{psf, Psf};
pub use rect::Window;
pub use sharp::{render_sharp_at, SharpAt};
pub use target::{project, Target, TargetKind, DEFAULT_BACKGROUND};
pub use window::render_window;

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::gpu::Resolved;
use std::fmt;
use std::str::FromStr;
use std::sync::atomic::AtomicBool;

pub use crate::limits::{MAX_PIXELS, MAX_PIXEL_SAMPLES};

/// Most entries of a rolling-shutter homography table (lines x instants; 48 bytes each).
pub const MAX_TABLE: u64 = 1 << 21;

/// Largest sample count per pixel accepted (a longer blur is an error).
pub const MAX_SAMPLES: u32 = 1 << 20;

/// Sampling quality.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Quality {
    /// What `mmbm render` uses: >= 2048 samples, <= 0.25 px between time samples.
    #[default]
    Default,
    /// Cheaper, for many frames: >= 256 samples, <= 0.5 px between time samples.
    Fast,
    /// Explicit minimum sample count and maximum time-sample spacing (px).
    Custom {
        /// Minimum samples per pixel.
        min_samples: u32,
        /// Maximum image distance between consecutive time samples, px.
        max_spacing_px: f64,
    },
}

impl Quality {
    /// Minimum samples per pixel.
    pub fn min_samples(&self) -> u32 {
        match *self {
            Quality::Default => 2048,
            Quality::Fast => 256,
            Quality::Custom { min_samples, .. } => min_samples.max(1),
        }
    }

    /// Maximum image distance (px) between consecutive time samples.
    pub fn max_spacing_px(&self) -> f64 {
        match *self {
            Quality::Default => 0.25,
            Quality::Fast => 0.5,
            Quality::Custom { max_spacing_px, .. } => max_spacing_px,
        }
    }

    /// Instants per pixel of the analytic integrator for a largest image path
    /// of `max_path_px`: the spacing rule alone (the area needs no samples).
    pub fn instants_for(&self, max_path_px: f64) -> Result<u32> {
        Quality::Custom {
            min_samples: 1,
            max_spacing_px: self.max_spacing_px(),
        }
        .samples_for(max_path_px)
    }

    /// Samples per pixel for a largest image path of `max_path_px`.
    pub fn samples_for(&self, max_path_px: f64) -> Result<u32> {
        let s = self.max_spacing_px();
        if s.is_nan() || s <= 0.0 || s.is_infinite() {
            return Err(Error::invalid(
                "quality",
                format!("spacing must be > 0 px, got {s}"),
            ));
        }
        let n = (max_path_px / s).ceil().max(self.min_samples() as f64);
        if n.is_nan() || n > MAX_SAMPLES as f64 {
            return Err(Error::invalid(
                "blur",
                format!(
                    "the image path reaches {max_path_px:.0} px, which needs {n:.0} samples per \
                     pixel (limit {MAX_SAMPLES}); shorten the exposure or the motion"
                ),
            ));
        }
        Ok(n as u32)
    }
}

impl FromStr for Quality {
    type Err = Error;
    /// `default`, `fast`, or `MIN_SAMPLES:SPACING_PX` (e.g. `4096:0.1`).
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "default" => Ok(Quality::Default),
            "fast" => Ok(Quality::Fast),
            _ => {
                let bad = || {
                    Error::invalid(
                        "quality",
                        format!("'{s}': expected default, fast or MIN_SAMPLES:SPACING_PX"),
                    )
                };
                let (a, b) = s.split_once(':').ok_or_else(bad)?;
                let min_samples: u32 = a.trim().parse().map_err(|_| bad())?;
                let max_spacing_px: f64 = b.trim().parse().map_err(|_| bad())?;
                if min_samples == 0 || !(max_spacing_px > 0.0 && max_spacing_px.is_finite()) {
                    return Err(bad());
                }
                Ok(Quality::Custom {
                    min_samples,
                    max_spacing_px,
                })
            }
        }
    }
}

impl fmt::Display for Quality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Quality::Default => write!(f, "default"),
            Quality::Fast => write!(f, "fast"),
            Quality::Custom {
                min_samples,
                max_spacing_px,
            } => write!(f, "{min_samples}:{max_spacing_px}"),
        }
    }
}

/// How a pixel's area is integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// `analytic`, or `lattice` with defocus (a camera `[lens]`).
    #[default]
    Auto,
    /// One sample per instant at the pixel centre, the area in closed form:
    /// the checker's and the blob board's (`render.wgsl`), an image's
    /// bilinear interpolant (`texture.wgsl`).
    Analytic,
    /// Supersampling of area and time (a rank-1 lattice; any target).
    Lattice,
}

impl FromStr for Integrator {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Integrator::Auto),
            "analytic" => Ok(Integrator::Analytic),
            "lattice" => Ok(Integrator::Lattice),
            _ => Err(Error::invalid(
                "integrator",
                format!(
                    "{}: expected auto, analytic or lattice",
                    crate::error::quote(s)
                ),
            )),
        }
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Integrator::Auto => "auto",
            Integrator::Analytic => "analytic",
            Integrator::Lattice => "lattice",
        })
    }
}

/// One frame to render.
#[derive(Debug, Clone)]
pub struct RenderJob {
    /// Camera intrinsics.
    pub camera: Camera,
    /// Exposure of each line, s (the whole frame's with a global shutter).
    pub exposure_s: f64,
    /// Camera motion from the first line's exposure start to the last line's
    /// exposure end: [`Self::exposure_s`] plus the camera's rolling-shutter
    /// readout when it has one (each line is exposed over its own window,
    /// docs/spec.md section 9). Checked when the job renders.
    pub trajectory: Trajectory,
    /// The target.
    pub target: Target,
    /// Sampling quality.
    pub quality: Quality,
    /// GPU or CPU.
    pub backend: Backend,
    /// Seed of the per-pixel sample shifts.
    pub seed: u32,
    /// Also compute the per-pixel blur maps.
    pub with_maps: bool,
    /// Area integration.
    pub integrator: Integrator,
    /// The pixels whose image paths set the number of instants
    /// ([`maps::max_path_px_in`]); None (the default): the whole sensor. A
    /// caller that keeps only a window (the benefit map) sets it to that
    /// window: the spacing between instants holds there, not necessarily
    /// outside it. Must lie inside the image.
    pub spacing_window: Option<Window>,
}

impl RenderJob {
    /// A frame exposed `exposure_s` seconds per line along `trajectory` (which
    /// spans the camera's readout plus the exposure): default quality,
    /// automatic backend, seed 0, with maps.
    pub fn new(camera: Camera, exposure_s: f64, trajectory: Trajectory, target: Target) -> Self {
        RenderJob {
            camera,
            exposure_s,
            trajectory,
            target,
            quality: Quality::Default,
            backend: Backend::Auto,
            seed: 0,
            with_maps: true,
            integrator: Integrator::Auto,
            spacing_window: None,
        }
    }

    /// A frame exposed `exposure_s` seconds per line while the camera moves as
    /// `motion` says: the camera takes a log's own rolling-shutter readout
    /// where it has none ([`FrameMotion::camera`]), the trajectory spans the
    /// camera's busy time (exposure plus readout). The target is checked
    /// against the camera. Defaults as [`Self::new`].
    pub fn for_motion(
        camera: Camera,
        exposure_s: f64,
        motion: FrameMotion<'_>,
        target: Target,
    ) -> Result<Self> {
        let (camera, _) = motion.camera(camera)?;
        let trajectory = motion.trajectory(&camera, exposure_s)?;
        target.validate_for(&camera)?;
        Ok(Self::new(camera, exposure_s, trajectory, target))
    }

    /// Checks the job's timing: a positive exposure, and a trajectory that
    /// spans the camera's readout plus the exposure (first line's exposure
    /// start to the last line's exposure end).
    pub(crate) fn check_timing(&self) -> Result<()> {
        crate::check::positive("exposure", self.exposure_s)?;
        let readout = self.camera.shutter.readout_s;
        let span = self.camera.shutter.busy_s(self.exposure_s);
        let dur = self.trajectory.duration();
        if (dur - span).abs() > 1e-9 * span.max(1.0) {
            return Err(Error::invalid(
                "trajectory",
                format!(
                    "spans {dur} s, but an exposure of {} s with the camera's readout_s {readout} s \
                     needs {span} s (readout + exposure)",
                    self.exposure_s
                ),
            ));
        }
        Ok(())
    }
}

/// A rendered frame.
#[derive(Debug, Clone)]
pub struct RenderOutput {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Linear RGB (0..1), interleaved, row-major, top row first.
    pub rgb: Vec<f32>,
    /// Blur maps (when requested).
    pub maps: Option<BlurMaps>,
    /// Samples per pixel used.
    pub samples_per_pixel: u32,
    /// Largest image path length over the sensor (px, with the 1.1 safety factor).
    pub max_path_px: f64,
    /// `gpu: <adapter>` or `cpu (N threads)`.
    pub backend_used: String,
}

impl RenderOutput {
    /// Writes the image: `.exr` (linear float R, G, B) or `.png` (sRGB 8-bit),
    /// by extension.
    pub fn write_image(&self, path: &std::path::Path) -> Result<()> {
        let is_exr = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if !is_exr {
            return crate::io::images::write_png_linear_rgb(
                path,
                self.width,
                self.height,
                &self.rgb,
            );
        }
        let n = (self.width * self.height) as usize;
        let ch = |c: usize| (0..n).map(|i| self.rgb[3 * i + c]).collect::<Vec<f32>>();
        crate::io::images::write_exr(
            path,
            self.width as usize,
            self.height as usize,
            &[("R", &ch(0)), ("G", &ch(1)), ("B", &ch(2))],
        )
    }
}

static ANNOUNCED: AtomicBool = AtomicBool::new(false);

/// Renders one frame. With sensor noise in the camera, the image is the
/// noisy digital image (EMVA 1288 model, [`crate::camera::Noise`]) scaled to 0..1.
pub fn render_frame(job: &RenderJob) -> Result<RenderOutput> {
    render_frame_stream(job, 0)
}

/// What one frame's pass needs: the kernel's parameters, its homography
/// table, the integrator, the instants per pixel and the largest image path.
struct Pass {
    params: layout::RenderParams,
    homs: Vec<layout::GpuHomography>,
    analytic: bool,
    n: u32,
    lmax: f64,
}

/// Checks `job` (target, motion, timing, caps) and builds its pass.
fn prepare(job: &RenderJob) -> Result<Pass> {
    let cam = &job.camera;
    job.target.validate_for(cam)?;
    // The camera must stay in front of the target for the whole exposure.
    let f = job.target.frame();
    let check = job.trajectory.table(1024);
    if let Some(k) = check.iter().position(|p| {
        f.normal.dot(f.origin - p.1).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    }) {
        let t = job.trajectory.duration() * k as f64 / (check.len().max(2) - 1) as f64;
        return Err(Error::invalid(
            "motion",
            format!(
                "the camera reaches the target plane {t:.6} s into the exposure; \
                 shorten the exposure or start farther away"
            ),
        ));
    }
    job.check_timing()?;
    if let Some(w) = job.spacing_window {
        w.check("spacing_window", cam.width, cam.height)?;
    }
    let window = job.spacing_window.map(|w| [w.x0, w.y0, w.w, w.h]);
    let lmax = maps::max_path_px_in(cam, &job.target, &job.trajectory, window);
    let defocus = cam.lens.is_some();
    let analytic = match job.integrator {
        Integrator::Analytic if defocus => {
            return Err(Error::invalid(
                "integrator",
                "defocus ([lens] in the camera) samples the aperture: use lattice (or auto)",
            ))
        }
        Integrator::Auto => !defocus,
        Integrator::Analytic => true,
        Integrator::Lattice => false,
    };
    let n = if analytic {
        job.quality.instants_for(lmax)?
    } else {
        job.quality.samples_for(lmax)?
    };
    let pixels = cam.width as u64 * cam.height as u64;
    if pixels > MAX_PIXELS || pixels * n as u64 > MAX_PIXEL_SAMPLES {
        return Err(Error::invalid(
            "resolution",
            format!(
                "{}x{} pixels x {n} samples: the renderer takes at most {MAX_PIXELS} pixels \
                 and {MAX_PIXEL_SAMPLES} pixel-samples per frame",
                cam.width, cam.height
            ),
        ));
    }
    let lines = homography::table_lines(cam) as u64 * homography::table_stride(cam) as u64;
    if lines * n as u64 > MAX_TABLE {
        return Err(Error::invalid(
            "render table",
            format!(
                "{n} instants x {lines} entries per instant and line (rolling shutter lines, \
                 defocus derivatives) = {} homographies, limit {MAX_TABLE}; shorten the \
                 exposure or the motion, or lower the resolution",
                lines * n as u64
            ),
        ));
    }
    let mut homs = kernel::homographies(cam, &job.target, &job.trajectory, job.exposure_s, n);
    // The bounding box over every line's instants: the whole span, as finely.
    // With distortion, straight target edges image as curves, and defocus
    // spreads them: the whole image.
    let span_n = (n as f64 * job.trajectory.duration() / job.exposure_s).ceil() as u32;
    let bbox = if cam.distortion.is_none() && !defocus {
        kernel::target_bbox(cam, &job.target, &job.trajectory, span_n.max(n))
    } else {
        [0, 0, cam.width, cam.height]
    };
    let mut params = kernel::params(cam, &job.target, n, bbox, job.seed);
    if params.distortion.model == crate::gpu::lens::MODEL_TABLE {
        if let Some(maps) = kernel::pixel_maps(cam)? {
            params.lattice[2] = homs.len() as u32;
            homs.extend(maps);
        }
    }
    Ok(Pass {
        params,
        homs,
        analytic,
        n,
        lmax,
    })
}

/// [`render_frame`] with the noise drawn from RNG stream `stream`.
fn render_frame_stream(job: &RenderJob, stream: u64) -> Result<RenderOutput> {
    let cam = &job.camera;
    let Pass {
        params,
        homs,
        analytic,
        n,
        lmax,
    } = prepare(job)?;
    let tex = kernel::texture_of(&job.target);
    let (rgb, backend_used) = match job.backend.resolve("render", "renderer", &ANNOUNCED)? {
        Resolved::Gpu(ctx) => (
            gpu::render(ctx, &params, &homs, tex, analytic)?,
            format!("gpu: {}", ctx.description),
        ),
        Resolved::Cpu(threads) => {
            let t = threads.unwrap_or_else(rayon::current_num_threads);
            (
                cpu::render(&params, &homs, tex, analytic, threads),
                format!("cpu ({t} threads)"),
            )
        }
    };
    // A stop requested during the pass (crate::cancel): the image is partial.
    crate::cancel::check()?;
    let mut rgb = rgb;
    // Pixels beyond the lens's radial distortion limit see no ray: black.
    if let Some(mask) = kernel::masked_pixels(cam) {
        for (px, &m) in rgb.chunks_mut(3).zip(&mask) {
            if m {
                px.fill(0.0);
            }
        }
    }
    if let Some(noise) = &cam.noise {
        noise.apply(&mut rgb, job.exposure_s, stream)?;
    }
    let maps = job.with_maps.then(|| {
        let steps = maps::steps_for(lmax);
        maps::blur_maps(cam, &job.target, &job.trajectory, job.exposure_s, steps)
    });
    crate::cancel::check()?;
    Ok(RenderOutput {
        width: cam.width,
        height: cam.height,
        rgb,
        maps,
        samples_per_pixel: n,
        max_path_px: lmax,
        backend_used,
    })
}

/// The sharp frame at exposure start (no motion), same quality and backend;
/// with sensor noise, another realisation of it (RNG stream 1).
pub fn render_sharp(job: &RenderJob) -> Result<RenderOutput> {
    let still = RenderJob {
        trajectory: Trajectory::from_twist(
            crate::model::motion::Twist::default(),
            job.trajectory.duration(),
        )?,
        with_maps: false,
        ..job.clone()
    };
    render_frame_stream(&still, 1)
}
