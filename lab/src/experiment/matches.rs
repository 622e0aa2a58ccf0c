//! The odometry task as odometry consumes it: feature matches between
//! consecutive kept frames (docs/spec.md section 11).
//!
//! Each frame's FAST-9 corners (the experiment's `corners::corners`, strongest
//! first; at most [`MAX_FEATURES`], those at least [`EDGE_PX`] px inside the
//! image) are described by 256-bit BRIEF descriptors
//! ([`imageproc::binary_descriptors::brief::brief`], with the fixed test pairs
//! of [`test_pairs`] so that every frame and every run describes alike). Each
//! corner of a frame is matched to its nearest descriptor (Hamming distance)
//! in the previous kept frame, and kept when that distance is below
//! [`RATIO`] times the second nearest (Lowe's ratio test). A match is an
//! **inlier** when the previous frame's corner, carried by the true
//! homography between the two frames, lands within [`INLIER_PX`] px of the
//! frame's corner. The renderer knows that homography: the board and the
//! poster behind it lie in one plane, so the homography fitted to the
//! board's 16 blob centres projected at both frames' mid-exposure poses
//! ([`fit_homography`]) carries every point of the scene. Checking against
//! the truth counts the matches a perfect robust estimator (RANSAC) would
//! keep, without its randomness. A frame is **trackable** when it has at
//! least [`TRACK_MIN`] inliers to the previous kept frame.

use crate::error::{Error, Result};
use image::GrayImage;
use imageproc::binary_descriptors::brief::{brief, TestPair};
use imageproc::binary_descriptors::BinaryDescriptor;
use imageproc::point::Point;
use std::sync::OnceLock;

/// Corners described per frame at most (the strongest), bounding the
/// matching's time (quadratic in it).
pub const MAX_FEATURES: usize = 300;
/// BRIEF descriptor length, bits.
pub const BRIEF_BITS: usize = 256;
/// A corner is described only this far inside the image, px (BRIEF's
/// 31 x 31 patch and its 5 x 5 test averages).
pub const EDGE_PX: u32 = 18;
/// Lowe's ratio test: the nearest Hamming distance must be below this
/// share of the second nearest.
pub const RATIO: f64 = 0.8;
/// A match is an inlier of the true homography within this distance, px.
pub const INLIER_PX: f64 = 3.0;
/// Inlier matches to the previous kept frame at which a frame is trackable.
pub const TRACK_MIN: usize = 20;
/// Seed of the fixed BRIEF test pairs.
pub const PAIRS_SEED: u64 = 0x0b21ef;

/// A frame's described corners.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Features {
    /// Corner positions in full-frame px (pixel centres).
    pub points: Vec<(f64, f64)>,
    /// Their BRIEF descriptors, [`BRIEF_BITS`] bits each.
    pub bits: Vec<Vec<u128>>,
}

/// A plane-to-plane homography, row-major, acting on `(x, y, 1)`.
pub type Homography = [[f64; 3]; 3];

/// A point in one image and where it is in another, px.
pub type Correspondence = ((f64, f64), (f64, f64));

/// The BRIEF test pairs every frame uses: [`BRIEF_BITS`] pairs of points in
/// the 31 x 31 patch, each coordinate drawn from a normal distribution
/// centred on the patch with sigma 6.6 px (Calonder et al.'s isotropic
/// Gaussian, as imageproc draws them), with a fixed seed ([`PAIRS_SEED`]).
pub fn test_pairs() -> &'static Vec<TestPair> {
    static PAIRS: OnceLock<Vec<TestPair>> = OnceLock::new();
    PAIRS.get_or_init(|| {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(PAIRS_SEED);
        let mut normal = move || -> f64 {
            // Box-Muller.
            let u: f64 = rng.gen_range(f64::EPSILON..1.0);
            let v: f64 = rng.gen();
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let mut coord = move || loop {
            let c = 16.0 + 6.6 * normal();
            if (0.0..31.0).contains(&c) {
                return c as u32;
            }
        };
        (0..BRIEF_BITS)
            .map(|_| TestPair {
                p0: Point::new(coord(), coord()),
                p1: Point::new(coord(), coord()),
            })
            .collect()
    })
}

/// Describes the corners `corners` (px in `gray`, strongest first, as
/// the experiment's `corners::corners` gives them) of the window `gray`, whose
/// top-left pixel is at `offset` px in the full frame.
pub fn features(gray: &GrayImage, corners: &[(f64, f64)], offset: (f64, f64)) -> Result<Features> {
    let (w, h) = gray.dimensions();
    let keys: Vec<Point<u32>> = corners
        .iter()
        .map(|&(x, y)| Point::new(x as u32, y as u32))
        .filter(|p| p.x >= EDGE_PX && p.y >= EDGE_PX && p.x + EDGE_PX < w && p.y + EDGE_PX < h)
        .take(MAX_FEATURES)
        .collect();
    if keys.is_empty() {
        return Ok(Features::default());
    }
    let (descs, _) = brief(gray, &keys, BRIEF_BITS, Some(test_pairs()))
        .map_err(|e| Error::invalid("BRIEF descriptors", e))?;
    Ok(Features {
        points: descs
            .iter()
            .map(|d| {
                let p = d.position();
                (
                    f64::from(p.x) + 0.5 + offset.0,
                    f64::from(p.y) + 0.5 + offset.1,
                )
            })
            .collect(),
        bits: descs.into_iter().map(|d| d.bits).collect(),
    })
}

/// The FAST-9 corners the matches describe (the experiment's `corners::corners`).
pub fn corners(gray: &GrayImage) -> Vec<(f64, f64)> {
    super::corners::corners(gray)
}

/// [`features`] of `gray`'s own FAST-9 corners (the experiment's `corners::corners`),
/// at offset zero.
pub fn describe(gray: &GrayImage) -> Result<Features> {
    features(gray, &corners(gray), (0.0, 0.0))
}

fn hamming(a: &[u128], b: &[u128]) -> u32 {
    a.iter().zip(b).map(|(x, y)| (x ^ y).count_ones()).sum()
}

/// Matches of `cur` to `prev` passing the ratio test: `(index in prev,
/// index in cur)`, at most one per corner of `cur`. `prev` needs two
/// descriptors for a second nearest; with fewer there is no match.
pub fn ratio_matches(prev: &Features, cur: &Features) -> Vec<(usize, usize)> {
    if prev.bits.len() < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (j, d) in cur.bits.iter().enumerate() {
        let (mut best, mut second, mut at) = (u32::MAX, u32::MAX, 0);
        for (i, e) in prev.bits.iter().enumerate() {
            let h = hamming(d, e);
            if h < best {
                (second, best, at) = (best, h, i);
            } else if h < second {
                second = h;
            }
        }
        if f64::from(best) < RATIO * f64::from(second) {
            out.push((at, j));
        }
    }
    out
}

/// `h` applied to `p`; None at infinity.
pub fn apply(h: &Homography, p: (f64, f64)) -> Option<(f64, f64)> {
    let w = h[2][0] * p.0 + h[2][1] * p.1 + h[2][2];
    if w.abs() < 1e-12 {
        return None;
    }
    Some((
        (h[0][0] * p.0 + h[0][1] * p.1 + h[0][2]) / w,
        (h[1][0] * p.0 + h[1][1] * p.1 + h[1][2]) / w,
    ))
}

/// The ratio-test matches of `cur` to `prev` that `h` (prev to cur) confirms
/// within [`INLIER_PX`] px.
pub fn inliers(prev: &Features, cur: &Features, h: &Homography) -> usize {
    ratio_matches(prev, cur)
        .into_iter()
        .filter(|&(i, j)| {
            apply(h, prev.points[i]).is_some_and(|q| {
                let c = cur.points[j];
                (q.0 - c.0).hypot(q.1 - c.1) <= INLIER_PX
            })
        })
        .count()
}

/// The least-squares homography taking each `pairs[k].0` to `pairs[k].1`
/// (the direct linear transform with `h33 = 1`, on points normalised to a
/// zero centroid and unit mean distance); None with fewer than 4 pairs or a
/// degenerate set.
pub fn fit_homography(pairs: &[Correspondence]) -> Option<Homography> {
    if pairs.len() < 4 {
        return None;
    }
    let norm = |pts: &mut dyn Iterator<Item = (f64, f64)>| {
        let v: Vec<(f64, f64)> = pts.collect();
        let n = v.len() as f64;
        let (cx, cy) = v
            .iter()
            .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
        let d = v.iter().map(|p| (p.0 - cx).hypot(p.1 - cy)).sum::<f64>() / n;
        let s = if d > 1e-12 { 1.0 / d } else { 1.0 };
        [[s, 0.0, -s * cx], [0.0, s, -s * cy], [0.0, 0.0, 1.0]]
    };
    let ta = norm(&mut pairs.iter().map(|p| p.0));
    let tb = norm(&mut pairs.iter().map(|p| p.1));
    // Normal equations of the 2 n x 8 system.
    let mut m = [[0.0f64; 9]; 8];
    for &(a, b) in pairs {
        let (x, y) = apply(&ta, a)?;
        let (u, v) = apply(&tb, b)?;
        for (row, rhs) in [
            ([x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y], u),
            ([0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y], v),
        ] {
            for (mr, &a) in m.iter_mut().zip(&row) {
                for (v, &b) in mr.iter_mut().zip(&row) {
                    *v += a * b;
                }
                mr[8] += a * rhs;
            }
        }
    }
    let h = solve8(m)?;
    let hn = [[h[0], h[1], h[2]], [h[3], h[4], h[5]], [h[6], h[7], 1.0]];
    // Undo the normalisations: H = Tb^-1 Hn Ta.
    let s = tb[0][0];
    let tb_inv = [
        [1.0 / s, 0.0, -tb[0][2] / s],
        [0.0, 1.0 / s, -tb[1][2] / s],
        [0.0, 0.0, 1.0],
    ];
    let out = mul(&tb_inv, &mul(&hn, &ta));
    out.iter().flatten().all(|v| v.is_finite()).then_some(out)
}

fn mul(a: &Homography, b: &Homography) -> Homography {
    let mut c = [[0.0; 3]; 3];
    for (r, row) in c.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|j| a[r][j] * b[j][k]).sum();
        }
    }
    c
}

/// Gaussian elimination with partial pivoting of the augmented 8 x 9 system.
fn solve8(mut m: [[f64; 9]; 8]) -> Option<[f64; 8]> {
    for col in 0..8 {
        let piv = (col..8).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[piv][col].abs() < 1e-12 {
            return None;
        }
        m.swap(col, piv);
        let pivot = m[col];
        for (r, mr) in m.iter_mut().enumerate() {
            if r != col {
                let f = mr[col] / pivot[col];
                for (v, p) in mr.iter_mut().zip(&pivot).skip(col) {
                    *v -= f * p;
                }
            }
        }
    }
    let mut x = [0.0; 8];
    for (r, (v, mr)) in x.iter_mut().zip(&m).enumerate() {
        *v = mr[8] / mr[r];
    }
    Some(x)
}

/// The true homography from the previous kept frame to this one: fitted to
/// the board's blob centres at both frames' mid-exposure poses (`None` for
/// a blob off either image); None with fewer than 4 blobs seen in both.
pub fn true_homography(
    prev: &[Option<(f64, f64)>],
    cur: &[Option<(f64, f64)>],
) -> Option<Homography> {
    let pairs: Vec<Correspondence> = prev
        .iter()
        .zip(cur)
        .filter_map(|(a, b)| Some(((*a)?, (*b)?)))
        .collect();
    fit_homography(&pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A textured test image: random 8 x 8 px blocks of 256 grey levels
    /// (a fixed seed), corners everywhere.
    fn texture(w: u32, h: u32, seed: u64) -> GrayImage {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let cells: Vec<u8> = (0..(w / 8 + 1) * (h / 8 + 1)).map(|_| rng.gen()).collect();
        GrayImage::from_fn(w, h, |x, y| {
            image::Luma([cells[(y / 8 * (w / 8 + 1) + x / 8) as usize]])
        })
    }

    fn shift(img: &GrayImage, dx: u32, dy: u32) -> GrayImage {
        let (w, h) = img.dimensions();
        GrayImage::from_fn(w - dx, h - dy, |x, y| *img.get_pixel(x + dx, y + dy))
    }

    fn feats(img: &GrayImage) -> Features {
        features(img, &corners(img), (0.0, 0.0)).unwrap()
    }

    #[test]
    fn a_shifted_copy_matches_with_every_match_an_inlier() {
        let big = texture(120, 100, 7);
        let a = shift(&big, 0, 0);
        // The same scene 7 px right and 5 px down in the second frame's
        // window: a point (x, y) of `a` is at (x - 7, y - 5) in `b`.
        let b = shift(&big, 7, 5);
        let h = [[1.0, 0.0, -7.0], [0.0, 1.0, -5.0], [0.0, 0.0, 1.0]];
        let (fa, fb) = (feats(&a), feats(&b));
        // Every corner described (none left out by the cap), so each corner
        // of `b` has its true partner among `a`'s.
        assert!(fa.points.len() < MAX_FEATURES, "{}", fa.points.len());
        let m = ratio_matches(&fa, &fb);
        assert!(m.len() >= 30, "{} matches", m.len());
        let n = inliers(&fa, &fb, &h);
        assert_eq!(n, m.len(), "every match is an inlier of the shift");
        // A wrong homography (the shift the other way) confirms almost none.
        let wrong = [[1.0, 0.0, 7.0], [0.0, 1.0, 5.0], [0.0, 0.0, 1.0]];
        assert!(inliers(&fa, &fb, &wrong) * 20 < n);
    }

    #[test]
    fn a_blurred_copy_keeps_fewer_and_an_unrelated_image_almost_none() {
        let a = texture(200, 160, 7);
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let fa = feats(&a);
        let same = inliers(&fa, &fa, &id);
        assert_eq!(same, fa.points.len());
        // A horizontal 9-px box blur (motion blur).
        let blurred = GrayImage::from_fn(200, 160, |x, y| {
            let s: u32 = (0..9)
                .map(|k| u32::from(a.get_pixel((x + k).saturating_sub(4).min(199), y)[0]))
                .sum();
            image::Luma([(s / 9) as u8])
        });
        let blur = inliers(&fa, &feats(&blurred), &id);
        assert!(blur * 2 < same, "blurred {blur} of {same}");
        let other = inliers(&fa, &feats(&texture(200, 160, 99)), &id);
        assert!(other * 50 < same, "unrelated {other} of {same}");
    }

    #[test]
    fn homography_fit_recovers_a_projective_map() {
        let h: Homography = [[1.1, 0.05, 12.0], [-0.03, 0.95, -4.0], [1e-4, -2e-4, 1.0]];
        let pairs: Vec<_> = (0..16)
            .map(|k| {
                let p = (
                    40.0 + 30.0 * f64::from(k % 4),
                    30.0 + 25.0 * f64::from(k / 4),
                );
                (p, apply(&h, p).unwrap())
            })
            .collect();
        let fit = fit_homography(&pairs).unwrap();
        for (p, q) in &pairs {
            let r = apply(&fit, *p).unwrap();
            assert!((r.0 - q.0).hypot(r.1 - q.1) < 1e-6);
        }
        // Collinear points do not determine it.
        let line: Vec<_> = (0..6)
            .map(|k| ((f64::from(k), 0.0), (f64::from(k), 1.0)))
            .collect();
        assert!(fit_homography(&line).is_none());
        assert!(fit_homography(&pairs[..3]).is_none());
        let seen: Vec<Option<(f64, f64)>> = pairs.iter().map(|p| Some(p.0)).collect();
        let moved: Vec<Option<(f64, f64)>> = pairs.iter().map(|p| Some(p.1)).collect();
        assert!(true_homography(&seen, &moved).is_some());
        assert!(true_homography(&seen[..3], &moved).is_none());
    }
}
