//! The second task metric, for visual-odometry users: corner repeatability.
//! FAST-9 corners ([`imageproc::corners::corners_fast9`], threshold
//! [`FAST_THRESHOLD`] on 8-bit luma, non-maximum suppression over
//! [`NMS_RADIUS`] px) are detected on the frame and on the sharp frame of the
//! same pose (rendered without motion and without noise at the frame's
//! mid-exposure pose: the places a tracker would want); the repeatability is
//! the share of the sharp frame's corners with a frame corner within
//! [`MATCH_PX`] px. Of the frame's corners only the strongest (highest FAST
//! score), as many as the sharp frame has, take part: a noisy frame's many
//! noise corners would otherwise land near sharp corners by chance. A frame
//! is usable for odometry when its repeatability is at least [`REPEAT_OK`].

use crate::camera::Camera;
use crate::error::Result;
use crate::render::{self, Pose, RenderJob, Trajectory};
use image::GrayImage;

/// FAST-9 intensity threshold, 8-bit luma.
pub const FAST_THRESHOLD: u8 = 20;
/// Non-maximum suppression radius, px.
pub const NMS_RADIUS: u32 = 2;
/// A sharp corner is re-found when a frame corner is this close, px.
pub const MATCH_PX: f64 = 2.0;
/// Repeatability at which a frame counts as usable for odometry.
pub const REPEAT_OK: f64 = 0.5;

/// FAST-9 corners of `gray` after non-maximum suppression, px (pixel
/// centres), strongest first (ties in raster order).
pub fn corners(gray: &GrayImage) -> Vec<(f64, f64)> {
    let all = imageproc::corners::corners_fast9(gray, FAST_THRESHOLD);
    let mut kept = imageproc::suppress::local_maxima(&all, NMS_RADIUS);
    kept.sort_by(|a, b| b.score.total_cmp(&a.score));
    kept.iter()
        .map(|c| (c.x as f64 + 0.5, c.y as f64 + 0.5))
        .collect()
}

/// Repeatability of `frame`'s corners (strongest first, as [`corners`]
/// gives them) against `sharp`'s: [`repeatability`] with the strongest
/// `sharp.len()` of the frame's.
pub fn repeatability_strongest(sharp: &[(f64, f64)], frame: &[(f64, f64)]) -> Option<f64> {
    repeatability(sharp, &frame[..frame.len().min(sharp.len())], MATCH_PX)
}

/// Share of `sharp` with a point of `frame` within `radius` px; `None`
/// when `sharp` is empty (nothing to re-find).
pub fn repeatability(sharp: &[(f64, f64)], frame: &[(f64, f64)], radius: f64) -> Option<f64> {
    if sharp.is_empty() {
        return None;
    }
    let mut f: Vec<(f64, f64)> = frame.to_vec();
    f.sort_by(|a, b| a.0.total_cmp(&b.0));
    let found = sharp
        .iter()
        .filter(|s| {
            let lo = f.partition_point(|p| p.0 < s.0 - radius);
            f[lo..]
                .iter()
                .take_while(|p| p.0 <= s.0 + radius)
                .any(|p| (p.0 - s.0).hypot(p.1 - s.1) <= radius)
        })
        .count();
    Some(found as f64 / sharp.len() as f64)
}

/// The sharp frame of `job` (its camera without noise and with no motion,
/// at pose `pose`): linear RGB. Without motion the analytic integrator
/// takes one instant per pixel, so this costs a fraction of the frame's render.
pub fn sharp_at(job: &RenderJob, pose: Pose) -> Result<Vec<f32>> {
    Ok(render::render_frame(&still_at(job, pose)?)?.rgb)
}

/// The job of [`sharp_at`]: `job`'s camera without noise, held at `pose`
/// for the whole exposure, without blur maps.
pub fn still_at(job: &RenderJob, pose: Pose) -> Result<RenderJob> {
    Ok(RenderJob {
        camera: Camera {
            noise: None,
            ..job.camera
        },
        trajectory: Trajectory::from_poses(job.trajectory.duration(), vec![pose, pose])?,
        with_maps: false,
        ..job.clone()
    })
}

/// 8-bit luma of linear RGB (`w` x `h`), as [`crate::assess::luma`] of its sRGB image.
pub fn luma(w: u32, h: u32, rgb: &[f32]) -> Result<GrayImage> {
    Ok(crate::assess::luma(&crate::io::images::to_rgb8(w, h, rgb)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeatability_counts_sharp_corners_refound_within_the_radius() {
        let sharp = [(10.0, 10.0), (20.0, 20.0), (30.0, 30.0), (40.0, 40.0)];
        let frame = [(11.0, 11.0), (20.0, 22.5), (31.9, 30.0), (100.0, 100.0)];
        // (10,10): 1.41 px; (20,20): 2.5 px (no); (30,30): 1.9 px; (40,40): none.
        assert_eq!(repeatability(&sharp, &frame, 2.0), Some(0.5));
        assert_eq!(repeatability(&sharp, &[], 2.0), Some(0.0));
        assert_eq!(repeatability(&[], &frame, 2.0), None);
        assert_eq!(repeatability(&sharp, &sharp, 2.0), Some(1.0));
        // Only the strongest 4 of the frame's count: a fifth (weaker) corner
        // at (40, 40) is not used.
        let mut many = frame.to_vec();
        many.push((40.0, 40.0));
        assert_eq!(repeatability_strongest(&sharp, &many), Some(0.5));
        assert_eq!(repeatability(&sharp, &many, 2.0), Some(0.75));
    }

    #[test]
    fn fast_finds_the_corners_of_a_square_and_not_a_flat_image() {
        let mut g = GrayImage::from_pixel(64, 64, image::Luma([40]));
        assert!(corners(&g).is_empty());
        for y in 20..44 {
            for x in 20..44 {
                g.put_pixel(x, y, image::Luma([220]));
            }
        }
        let c = corners(&g);
        assert!(!c.is_empty() && c.len() <= 8, "{c:?}");
        // Each corner is within 3.5 px of one of the square's four corners (not on an edge).
        for &(x, y) in &c {
            let near = [(20.0, 20.0), (44.0, 20.0), (20.0, 44.0), (44.0, 44.0)]
                .iter()
                .any(|&(a, b): &(f64, f64)| (x - a).hypot(y - b) <= 3.5);
            assert!(near, "({x}, {y})");
        }
    }
}
