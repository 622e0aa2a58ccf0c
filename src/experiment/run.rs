//! Running the experiment: walk -> MMBM -> every policy's triggers -> each
//! kept frame rendered with its true motion -> ground-truth blur, image
//! metrics and blob extraction per frame.

use super::config::ExperimentConfig;
use crate::error::{Error, Result};
use crate::io::gyro::{read_log, GyroOptions, GyroSample};
use crate::metric::{Method, Scene};
use crate::model::camera::Camera;
use crate::render::{self, Backend, Quality, RenderJob, Target, Trajectory};
use crate::sim::{simulate, Gait, GaitConfig};
use crate::trigger::{self, parse_policy, CameraTiming, Frame};
use std::str::FromStr;
use std::time::Instant;

/// A 2-D point: board coordinates (m) or pixel coordinates (px).
type Point2 = (f64, f64);

/// One walk (simulated or a real log) with its MMBM series and every policy's frames.
#[derive(Debug, Clone)]
pub struct Walk {
    /// `moderate`, `slow`, `fast` or the log's file name.
    pub name: String,
    /// The gyro samples (true motion and measurement).
    pub samples: Vec<GyroSample>,
    /// Rotation-only MMBM per sample (8x6 grid), mm/s.
    pub mmbm: Vec<f64>,
    /// Distance to the target per sample, m.
    pub distance: Vec<f64>,
    /// `(policy, frames)` in configuration order.
    pub runs: Vec<(String, Vec<Frame>)>,
}

/// What was measured on one rendered frame.
#[derive(Debug, Clone, Default)]
pub struct FrameMeasure {
    /// Distance to the target at exposure start, m.
    pub distance_m: f64,
    /// Mean path length over the sensor (ground-truth blur), px.
    pub blur_px: f64,
    /// Mean end-to-start displacement, px.
    pub disp_px: f64,
    /// JNBM (higher = sharper); NaN when undefined.
    pub jnbm: f64,
    /// CPBD (higher = sharper).
    pub cpbd: f64,
    /// Crete et al. blur effect (0 sharp .. 1 blurred).
    pub blur_effect: f64,
    /// Variance of the Laplacian.
    pub laplacian_var: f64,
    /// Blobs found by the colour threshold.
    pub blobs_found: usize,
    /// Blobs matched to a true centre.
    pub blobs_matched: usize,
    /// All 16 found, each near its true centre.
    pub blobs_ok: bool,
    /// When all 16 blobs were extracted: error of the camera position estimated
    /// from them (planar homography) against the true mid-exposure pose, m.
    pub pose_err_m: f64,
    /// The same for the orientation, degrees.
    pub pose_err_deg: f64,
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
    /// The trigger decision and exposure.
    pub frame: Frame,
    /// Measurements on the rendered frame.
    pub measure: Option<FrameMeasure>,
}

/// Builds a walk from the configuration: the simulation of `gait`, or the log.
pub fn make_walk(cfg: &ExperimentConfig, walk: &str, scene: &Scene) -> Result<Walk> {
    let (name, samples) = match &cfg.gyro {
        Some(p) => (
            p.file_name()
                .map_or("log".into(), |s| s.to_string_lossy().into_owned()),
            read_log(p, GyroOptions::default())?,
        ),
        None => {
            let gait = Gait::from_str(walk)?;
            let g = GaitConfig::preset(gait);
            (
                walk.to_string(),
                simulate(&g, cfg.duration_s, cfg.rate_hz, cfg.seed)?,
            )
        }
    };
    let mmbm = crate::series::mmbm_series(&samples, scene, Method::default())?;
    // Distance to the target: integrate the forward velocity (or the
    // configured speed), starting at start_distance, never closer than min_distance.
    let mut distance = Vec::with_capacity(samples.len());
    let mut d = cfg.start_distance_m;
    for (k, s) in samples.iter().enumerate() {
        if k > 0 {
            let dt = s.t - samples[k - 1].t;
            let vz = s.velocity.map_or(cfg.speed_m_s, |v| v.z);
            d = (d - vz * dt).max(cfg.min_distance_m);
        }
        distance.push(d);
    }
    let timing = timing(cfg);
    let mut runs = Vec::new();
    for p in &cfg.policies {
        let mut policy = parse_policy(p)?;
        let frames = trigger::run(&samples, &mmbm, policy.as_mut(), &timing)?;
        runs.push((p.clone(), frames));
    }
    Ok(Walk {
        name,
        samples,
        mmbm,
        distance,
        runs,
    })
}

/// The camera timing of the configuration.
pub fn timing(cfg: &ExperimentConfig) -> CameraTiming {
    CameraTiming {
        delay: cfg.delay_s,
        exposure: cfg.exposure_s,
        readout: cfg.readout_s,
        min_interval: cfg.min_interval_s,
    }
}

/// The rendering camera: thesis focal length and pitch at the configured resolution.
pub fn camera(cfg: &ExperimentConfig) -> Camera {
    Camera::thesis().with_resolution(cfg.resolution[0], cfg.resolution[1])
}

/// Indices of the frames to render for one run: every kept frame, or an even
/// spread of `max` of them.
pub fn frames_to_render(frames: &[Frame], max: usize) -> Vec<usize> {
    let kept: Vec<usize> = (0..frames.len()).filter(|&i| frames[i].kept).collect();
    if max == 0 || kept.len() <= max {
        return kept;
    }
    (0..max).map(|k| kept[k * kept.len() / max]).collect()
}

/// A rendered frame: measurements and the linear RGB image.
pub struct Rendered {
    /// The measurements.
    pub measure: FrameMeasure,
    /// Linear RGB, interleaved.
    pub rgb: Vec<f32>,
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
    let i = walk
        .samples
        .partition_point(|s| s.t < frame.exposure_start)
        .min(walk.samples.len() - 1);
    let distance = walk.distance[i];
    let use_velocity = walk.samples[i].velocity.is_some();
    let traj = Trajectory::from_log(
        &walk.samples,
        frame.exposure_start,
        cfg.exposure_s,
        use_velocity,
    )?;
    let target = Target::parse(&cfg.target, distance)?;
    let mut job = RenderJob::new(cam, traj.clone(), target.clone());
    job.quality = quality;
    job.backend = Backend::Auto;
    job.seed = seed;
    let t0 = Instant::now();
    let out = render::render_frame(&job)?;
    let render_ms = t0.elapsed().as_secs_f64() * 1e3;
    let maps = out
        .maps
        .as_ref()
        .ok_or_else(|| Error::invalid("render", "no blur maps"))?;
    let means = maps.means();
    let rgb8 = super::measure::to_rgb8(cam.width, cam.height, &out.rgb)?;
    // True blob centres at mid-exposure (the centroid of a smear).
    let mid = traj.pose_at(0.5 * cfg.exposure_s);
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
    let crop = super::measure::pattern_crop(&rgb8, &expected);
    let img = super::measure::image_metrics(&crop);
    let blobs = super::measure::blob_metrics(&rgb8, &expected);
    let (pose_err_m, pose_err_deg) = if blobs.ok {
        pose_error(&cam, &board, &blobs.matches, &frame_pl, &mid)
    } else {
        (f64::NAN, f64::NAN)
    };
    Ok(Rendered {
        measure: FrameMeasure {
            distance_m: distance,
            blur_px: means.path_px,
            disp_px: means.disp_px,
            jnbm: img.jnbm,
            cpbd: img.cpbd,
            blur_effect: img.blur_effect,
            laplacian_var: img.laplacian_var,
            blobs_found: blobs.found,
            blobs_matched: blobs.matched,
            blobs_ok: blobs.ok,
            pose_err_m,
            pose_err_deg,
            samples_per_pixel: out.samples_per_pixel,
            render_ms,
        },
        rgb: out.rgb,
    })
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
