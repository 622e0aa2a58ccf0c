//! Camera pose from the 16 blob centres: the planar homography (DLT, least
//! squares) between board coordinates and normalised image coordinates,
//! decomposed into rotation and translation (Zhang's method with `K` applied
//! first). Used to check what the blob extraction is worth: the pose error
//! against the true pose.

use crate::camera::Camera;
use crate::error::{Error, Result};
use glam::{DMat3, DVec3};

/// Camera pose relative to a planar board.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarPose {
    /// Rotation taking board-frame vectors to the camera frame.
    pub rotation: DMat3,
    /// Board origin in the camera frame, m.
    pub translation: DVec3,
    /// RMS reprojection error of the correspondences, px.
    pub rms_px: f64,
}

impl PlanarPose {
    /// The camera centre in board coordinates, m.
    pub fn camera_centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }
}

/// Solves `a x = b` (n x n, row-major) by Gaussian elimination with partial pivoting.
fn solve(mut a: Vec<[f64; 8]>, mut b: Vec<f64>) -> Option<[f64; 8]> {
    let n = 8;
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        let (pivot_row, pivot_b) = (a[col], b[col]);
        for (row, br) in a.iter_mut().zip(b.iter_mut()).skip(col + 1) {
            let k = row[col] / pivot_row[col];
            for (x, p) in row.iter_mut().zip(pivot_row.iter()).skip(col) {
                *x -= k * p;
            }
            *br -= k * pivot_b;
        }
    }
    let mut x = [0.0; 8];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|c| a[r][c] * x[c]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Homography `H` (with `H[2][2] = 1`) mapping board points `(X, Y)` (m) to
/// normalised image points `(x, y)`: `(x, y, 1) ~ H (X, Y, 1)`. Least squares
/// over at least 4 correspondences.
pub fn homography(board: &[(f64, f64)], image: &[(f64, f64)]) -> Result<DMat3> {
    if board.len() != image.len() || board.len() < 4 {
        return Err(Error::invalid(
            "homography",
            format!(
                "needs at least 4 correspondences, got {} and {}",
                board.len(),
                image.len()
            ),
        ));
    }
    let mut ata = vec![[0.0f64; 8]; 8];
    let mut atb = vec![0.0f64; 8];
    for (&(bx, by), &(x, y)) in board.iter().zip(image) {
        let rows = [
            ([bx, by, 1.0, 0.0, 0.0, 0.0, -x * bx, -x * by], x),
            ([0.0, 0.0, 0.0, bx, by, 1.0, -y * bx, -y * by], y),
        ];
        for (r, rhs) in rows {
            for i in 0..8 {
                for j in 0..8 {
                    ata[i][j] += r[i] * r[j];
                }
                atb[i] += r[i] * rhs;
            }
        }
    }
    let h = solve(ata, atb)
        .ok_or_else(|| Error::invalid("homography", "degenerate correspondences"))?;
    Ok(DMat3::from_cols(
        DVec3::new(h[0], h[3], h[6]),
        DVec3::new(h[1], h[4], h[7]),
        DVec3::new(h[2], h[5], 1.0),
    ))
}

/// Pose of `cam` from board points (m, board frame, Z = 0) and their pixels.
pub fn planar_pose(
    cam: &Camera,
    board: &[(f64, f64)],
    pixels: &[(f64, f64)],
) -> Result<PlanarPose> {
    let f = cam.focal_mm;
    let norm: Vec<(f64, f64)> = pixels
        .iter()
        .map(|&(x, y)| {
            let (u, v) = cam.pixel_to_mm(x, y);
            (u / f, v / f)
        })
        .collect();
    let h = homography(board, &norm)?;
    let (h1, h2, h3) = (h.x_axis, h.y_axis, h.z_axis);
    let mut lambda = 2.0 / (h1.length() + h2.length());
    // The board is in front of the camera: positive depth of its origin.
    if h3.z < 0.0 {
        lambda = -lambda;
    }
    let r1 = h1 * lambda;
    let r2 = h2 * lambda;
    let t = h3 * lambda;
    // Nearest rotation to [r1 r2 r1xr2] (Gram-Schmidt on the first two columns).
    let c1 = r1.normalize();
    let c2 = (r2 - c1 * c1.dot(r2)).normalize();
    let rotation = DMat3::from_cols(c1, c2, c1.cross(c2));
    if !rotation.is_finite() || !t.is_finite() {
        return Err(Error::invalid(
            "pose",
            "the homography does not decompose into a pose",
        ));
    }
    let mut sq = 0.0;
    for (&(bx, by), &(x, y)) in board.iter().zip(pixels) {
        let p = rotation * DVec3::new(bx, by, 0.0) + t;
        let (px, py) = cam.mm_to_pixel(f * p.x / p.z, f * p.y / p.z);
        sq += (px - x).powi(2) + (py - y).powi(2);
    }
    Ok(PlanarPose {
        rotation,
        translation: t,
        rms_px: (sq / board.len() as f64).sqrt(),
    })
}

/// Angle (degrees) of the rotation taking `a` to `b`.
pub fn rotation_angle_deg(a: &DMat3, b: &DMat3) -> f64 {
    let m = a.transpose() * *b;
    let c = ((m.x_axis.x + m.y_axis.y + m.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
    c.acos().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn recovers_a_known_pose() {
        let cam = Camera::thesis();
        let rot = DMat3::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.2, -0.3, 0.1));
        let t = DVec3::new(0.1, -0.05, 3.0);
        let board: Vec<(f64, f64)> = (0..16)
            .map(|k| (((k % 4) as f64 - 1.5) * 0.12, ((k / 4) as f64 - 1.5) * 0.12))
            .collect();
        let px: Vec<(f64, f64)> = board
            .iter()
            .map(|&(x, y)| {
                let p = rot * DVec3::new(x, y, 0.0) + t;
                cam.mm_to_pixel(cam.focal_mm * p.x / p.z, cam.focal_mm * p.y / p.z)
            })
            .collect();
        let p = planar_pose(&cam, &board, &px).unwrap();
        assert!((p.translation - t).length() < 1e-9, "{:?}", p.translation);
        assert!(rotation_angle_deg(&p.rotation, &rot) < 1e-6);
        assert!(p.rms_px < 1e-6);
        assert!(planar_pose(&cam, &board[..3], &px[..3]).is_err());
    }
}
