//! Per-frame measurements on rendered images (image blur metrics and blob
//! extraction), and the report's prose.

use super::config::ExperimentConfig;
use super::crop::{pattern_crop, pitch_px};
use super::walk::Walk;
use crate::camera::Camera;
use crate::error::Result;
use crate::io::images::to_rgb8;
use crate::render::{self, Backend, FrameMotion, Quality, RenderJob, Target, Trajectory};

use crate::trigger::Frame;
use std::time::Instant;

/// A 2-D point: board coordinates (m) or pixel coordinates (px).
type Point2 = (f64, f64);

/// What was measured on one rendered frame.
#[derive(Debug, Clone, Default)]
pub struct FrameMeasure {
    /// Distance to the target at exposure start, m.
    pub distance_m: f64,
    /// Mean path length over the sensor (ground-truth blur), px.
    pub blur_px: f64,
    /// Mean end-to-start displacement, px.
    pub disp_px: f64,
    /// Mean horizontal path over the exposure (sum of |dx| along each
    /// pixel's track), px, from tracks on a grid of pixels ([`axis_blur`]).
    pub blur_h_px: f64,
    /// The same vertically (sum of |dy|), px.
    pub blur_v_px: f64,
    /// JNBM (authors' code; higher = sharper); NaN when undefined.
    pub jnbm: f64,
    /// CPBD (authors' code; higher = sharper).
    pub cpbd: f64,
    /// JNBM with edge widths along both axes ([`crate::assess::jnbm_2d`]).
    pub jnbm_2d: f64,
    /// CPBD with edge widths along both axes ([`crate::assess::cpbd_2d`]).
    pub cpbd_2d: f64,
    /// Crete et al. blur effect (0 sharp .. 1 blurred).
    pub blur_effect: f64,
    /// Variance of the Laplacian.
    pub laplacian_var: f64,
    /// Blobs found by the colour threshold.
    pub blobs_found: usize,
    /// Blobs matched to a true centre.
    pub blobs_matched: usize,
    /// False alarms: blobs found farther than half a pitch from every board
    /// place (clutter, noise; fragments of a true blob are not counted).
    pub blobs_false: usize,
    /// All 16 found, each near its true centre.
    pub blobs_ok: bool,
    /// The same with the fixed redness threshold [`FIXED_BLOB_THRESHOLD`]
    /// (a global threshold, as the thesis's OpenCV thresholding).
    pub blobs_ok_fixed: bool,
    /// When all 16 blobs were extracted: error of the camera position estimated
    /// from them (planar homography) against the true mid-exposure pose, m.
    pub pose_err_m: f64,
    /// The same for the orientation, degrees.
    pub pose_err_deg: f64,
    /// Corner repeatability (`corners.rs`): share of the sharp
    /// frame's FAST corners re-found within 2 px; NaN without corners.
    pub corner_rep: f64,
    /// Samples per pixel used by the renderer.
    pub samples_per_pixel: u32,
    /// Render time, ms.
    pub render_ms: f64,
}

/// A frame with its measurements (`None` for frames a gate discarded, or
/// frames skipped by `max_frames_per_policy`).
#[derive(Debug, Clone)]
pub struct FrameRecord {
    /// Walk name.
    pub walk: String,
    /// The walk's simulation seed (0 for a log).
    pub seed: u64,
    /// The trigger decision and exposure.
    pub frame: Frame,
    /// Measurements on the rendered frame.
    pub measure: Option<FrameMeasure>,
}

/// Image blur metrics of one frame (NaN where a metric is undefined).
#[derive(Debug, Clone, Copy)]
pub struct ImageMetrics {
    /// JNBM.
    pub jnbm: f64,
    /// CPBD.
    pub cpbd: f64,
    /// JNBM, widths along both axes.
    pub jnbm_2d: f64,
    /// CPBD, widths along both axes.
    pub cpbd_2d: f64,
    /// Crete et al. blur effect.
    pub blur_effect: f64,
    /// Laplacian variance.
    pub laplacian_var: f64,
}

/// Computes the image metrics of an sRGB frame.
pub fn image_metrics(img: &image::RgbImage) -> ImageMetrics {
    let gray = crate::assess::luma(img);
    // All six at once (each metric shares its edge maps with its 2d variant);
    // an image without a whole 64x64 block has no JNBM or CPBD, but may
    // still have the other two.
    match crate::assess::assess(&gray) {
        Ok(a) => ImageMetrics {
            jnbm: a.jnbm.unwrap_or(f64::NAN),
            cpbd: a.cpbd,
            jnbm_2d: a.jnbm_2d.unwrap_or(f64::NAN),
            cpbd_2d: a.cpbd_2d,
            blur_effect: a.blur_effect,
            laplacian_var: a.laplacian_var,
        },
        Err(_) => ImageMetrics {
            jnbm: f64::NAN,
            cpbd: f64::NAN,
            jnbm_2d: f64::NAN,
            cpbd_2d: f64::NAN,
            blur_effect: crate::assess::blur_effect(&gray).unwrap_or(f64::NAN),
            laplacian_var: crate::assess::laplacian_var(&gray).unwrap_or(f64::NAN),
        },
    }
}

/// Blob extraction outcome.
#[derive(Debug, Clone)]
pub struct BlobOutcome {
    /// Components found.
    pub found: usize,
    /// Matched to a true centre.
    pub matched: usize,
    /// Success (exactly 16, all matched).
    pub ok: bool,
    /// Blobs farther than half a pitch from every expected centre.
    pub false_alarms: usize,
    /// For each expected centre, the centre of its matched blob (px).
    pub matches: Vec<Option<(f64, f64)>>,
}

/// Extracts the red blobs and matches them against the expected centres (px).
pub fn blob_metrics(img: &image::RgbImage, expected: &[(f64, f64)]) -> BlobOutcome {
    let pitch = pitch_px(expected);
    let r = crate::board::blobs::extract(img, &crate::board::blobs::BlobParams::default())
        .and_then(|blobs| {
            crate::board::blobs::evaluate(&blobs, expected, pitch).map(|r| (blobs, r))
        });
    match r {
        Ok((blobs, r)) => BlobOutcome {
            found: r.found,
            matched: r.matched,
            ok: r.ok,
            false_alarms: false_alarms(&blobs, expected, pitch),
            matches: r
                .assignment
                .iter()
                .map(|a| a.map(|i| blobs[i].centre))
                .collect(),
        },
        // An extraction error (e.g. an image too small) counts as a failure.
        Err(_) => BlobOutcome {
            found: 0,
            matched: 0,
            ok: false,
            false_alarms: 0,
            matches: vec![None; expected.len()],
        },
    }
}

/// Blobs whose centre is at least half a pitch (px) from every expected centre.
pub fn false_alarms(
    blobs: &[crate::board::blobs::Blob],
    expected: &[(f64, f64)],
    pitch: f64,
) -> usize {
    blobs
        .iter()
        .filter(|b| {
            expected
                .iter()
                .all(|e| (b.centre.0 - e.0).hypot(b.centre.1 - e.1) >= 0.5 * pitch)
        })
        .count()
}

/// The fixed redness threshold (8-bit sRGB `R - max(G, B)`) of the thesis-style
/// detector: half a saturated red's redness (about 170), whatever the image.
pub const FIXED_BLOB_THRESHOLD: f64 = 85.0;

/// Blob success with the fixed threshold [`FIXED_BLOB_THRESHOLD`].
pub fn blob_ok_fixed(img: &image::RgbImage, expected: &[(f64, f64)]) -> bool {
    let params = crate::board::blobs::BlobParams {
        threshold: Some(FIXED_BLOB_THRESHOLD),
        ..Default::default()
    };
    crate::board::blobs::extract(img, &params)
        .and_then(|b| crate::board::blobs::evaluate(&b, expected, pitch_px(expected)))
        .is_ok_and(|r| r.ok)
}

/// Mean and 99th percentile ([`crate::stats::percentile`]) of the per-value
/// |difference| of two images.
pub fn image_difference(a: &[f32], b: &[f32]) -> (f64, f64) {
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).abs())
        .collect();
    match (crate::stats::mean(&d), crate::stats::percentile(&d, 99.0)) {
        (Some(mean), Some(p99)) => (mean, p99),
        _ => (0.0, 0.0),
    }
}

/// A rendered frame: measurements and the linear RGB image.
pub struct Rendered {
    /// The measurements.
    pub measure: FrameMeasure,
    /// Where it was rendered (`gpu: <adapter>` or `cpu (N threads)`).
    pub backend: String,
    /// Linear RGB, interleaved.
    pub rgb: Vec<f32>,
    /// The blob centres at mid-exposure, px (empty unless the target is a blob board).
    pub expected_px: Vec<(f64, f64)>,
}

/// The walk at `frame`: the distance to the target at exposure start (m)
/// and the camera's trajectory from the log. A rolling shutter exposes each
/// line over its own window, so the motion spans `cam`'s busy time
/// ([`FrameMotion::trajectory`]: the exposure plus the readout).
pub(crate) fn frame_motion(walk: &Walk, frame: &Frame, cam: &Camera) -> Result<(f64, Trajectory)> {
    let i = walk
        .samples
        .partition_point(|s| s.t < frame.exposure_start)
        .min(walk.samples.len() - 1);
    let use_velocity = walk.samples[i].velocity.is_some();
    let motion = FrameMotion::Log {
        log: &walk.samples,
        at_s: frame.exposure_start,
        use_velocity,
    };
    let traj = motion.trajectory(cam, frame.exposure_s())?;
    Ok((walk.distance[i], traj))
}

/// The experiment's render of one frame: many frames, so a hardware GPU,
/// else the CPU twin (see `Backend::Bulk`); `seed` seeds the sampling.
pub(crate) fn bulk_job(
    cam: Camera,
    exposure_s: f64,
    traj: &Trajectory,
    target: &Target,
    quality: Quality,
    seed: u32,
) -> RenderJob {
    let mut job = RenderJob::new(cam, exposure_s, traj.clone(), target.clone());
    job.quality = quality;
    job.backend = Backend::Bulk;
    job.seed = seed;
    job
}

/// Renders and measures one frame.
pub fn render_and_measure(
    cfg: &ExperimentConfig,
    walk: &Walk,
    frame: &Frame,
    cam: Camera,
    quality: Quality,
    seed: u32,
) -> Result<Rendered> {
    let exposure = frame.exposure_s();
    let (distance, traj) = frame_motion(walk, frame, &cam)?;
    // Exposure control raised the gain: the system gain K scales with it
    // (the same DN from fewer electrons).
    let mut cam = cam;
    if let Some(n) = cam.noise.as_mut() {
        if frame.gain != 1.0 {
            n.gain_dn_per_e = Some(n.gain() * frame.gain);
        }
    }
    let target = cfg.scene_target(&cfg.target, distance)?;
    let mut job = bulk_job(cam, exposure, &traj, &target, quality, seed);
    // Only the maps' sensor means are read: they are computed without the
    // maps (render::maps::path_means, the same numbers).
    job.with_maps = false;
    let t0 = Instant::now();
    let out = render::render_frame(&job)?;
    let render_ms = t0.elapsed().as_secs_f64() * 1e3;
    let (blur_px, disp_px) = render::maps::path_means(
        &cam,
        &target,
        &traj,
        exposure,
        render::maps::steps_for(out.max_path_px),
    );
    let (blur_h_px, blur_v_px) = axis_blur(&cam, &target, &traj);
    let rgb8 = to_rgb8(cam.width, cam.height, &out.rgb)?;
    // True blob centres at mid-exposure (the centroid of a smear).
    // (Rolling shutter: the middle line's mid-exposure.)
    let mid = traj.pose_at(0.5 * cam.shutter.busy_s(exposure));
    let frame_pl = target.frame();
    let (board, expected): (Vec<Point2>, Vec<Point2>) = target
        .blob_centres()
        .unwrap_or_default()
        .iter()
        .filter_map(|&p| {
            let d = p - frame_pl.origin;
            render::project(&cam, &mid, p).map(|px| ((d.dot(frame_pl.e1), d.dot(frame_pl.e2)), px))
        })
        .unzip();
    // Like the thesis, judge sharpness on the pattern cropped from the frame.
    let crop = pattern_crop(&rgb8, &expected);
    let img = image_metrics(&crop);
    let blobs = blob_metrics(&rgb8, &expected);
    // Corners of the frame against those of the sharp frame at mid-exposure.
    let sharp = super::corners::sharp_at(&job, mid)?;
    let corner_rep = super::corners::repeatability_strongest(
        &super::corners::corners(&super::corners::luma(cam.width, cam.height, &sharp)?),
        &super::corners::corners(&crate::assess::luma(&rgb8)),
    )
    .unwrap_or(f64::NAN);
    let (pose_err_m, pose_err_deg) = if blobs.ok {
        pose_error(&cam, &board, &blobs.matches, &frame_pl, &mid)
    } else {
        (f64::NAN, f64::NAN)
    };
    Ok(Rendered {
        backend: out.backend_used.clone(),
        measure: FrameMeasure {
            distance_m: distance,
            blur_px,
            disp_px,
            blur_h_px,
            blur_v_px,
            jnbm: img.jnbm,
            cpbd: img.cpbd,
            jnbm_2d: img.jnbm_2d,
            cpbd_2d: img.cpbd_2d,
            blur_effect: img.blur_effect,
            laplacian_var: img.laplacian_var,
            blobs_found: blobs.found,
            blobs_matched: blobs.matched,
            blobs_false: blobs.false_alarms,
            blobs_ok: blobs.ok,
            blobs_ok_fixed: blob_ok_fixed(&rgb8, &expected),
            pose_err_m,
            pose_err_deg,
            corner_rep,
            samples_per_pixel: out.samples_per_pixel,
            render_ms,
        },
        rgb: out.rgb,
        expected_px: expected,
    })
}

/// Mean horizontal and vertical path lengths (px) over the exposure: the
/// tracks of the blur maps ([`render::maps::tracks`], 64 steps) of the pixel
/// centres of a 32 x 24 grid, summing `|dx|` and `|dy|` along each (pixels
/// whose track is lost are left out). Their sum bounds the path length from
/// above (a diagonal track counts in both).
pub fn axis_blur(cam: &Camera, target: &Target, traj: &Trajectory) -> (f64, f64) {
    let (nx, ny) = (32, 24);
    let points: Vec<(f64, f64)> = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| {
                (
                    (i as f64 + 0.5) * cam.width as f64 / nx as f64,
                    (j as f64 + 0.5) * cam.height as f64 / ny as f64,
                )
            })
        })
        .collect();
    let (mut h, mut v, mut n) = (0.0, 0.0, 0usize);
    for tr in render::maps::tracks(cam, target, traj, &points, 64)
        .into_iter()
        .flatten()
    {
        for w in tr.windows(2) {
            h += (w[1].0 - w[0].0).abs();
            v += (w[1].1 - w[0].1).abs();
        }
        n += 1;
    }
    if n == 0 {
        (f64::NAN, f64::NAN)
    } else {
        (h / n as f64, v / n as f64)
    }
}

/// Pose from the matched blob centres against the true camera pose `mid`
/// (world = camera at exposure start): `(position error m, angle error deg)`,
/// NaN when the pose cannot be estimated.
fn pose_error(
    cam: &Camera,
    board: &[(f64, f64)],
    matches: &[Option<(f64, f64)>],
    plane: &crate::render::target::PlaneFrame,
    mid: &crate::render::Pose,
) -> (f64, f64) {
    let (b, px): (Vec<Point2>, Vec<Point2>) = board
        .iter()
        .zip(matches)
        .filter_map(|(b, m)| m.map(|m| (*b, m)))
        .unzip();
    let Ok(est) = crate::board::pose::planar_pose(cam, &b, &px) else {
        return (f64::NAN, f64::NAN);
    };
    // True camera-from-board transform: X_cam = R_q^T (O + B x - c).
    let rq_t = glam::DMat3::from_quat(mid.0).transpose();
    let board_axes = glam::DMat3::from_cols(plane.e1, plane.e2, plane.e1.cross(plane.e2));
    let truth = crate::board::pose::PlanarPose {
        rotation: rq_t * board_axes,
        translation: rq_t * (plane.origin - mid.1),
        rms_px: 0.0,
    };
    (
        (est.camera_centre() - truth.camera_centre()).length(),
        crate::board::pose::rotation_angle_deg(&est.rotation, &truth.rotation),
    )
}
