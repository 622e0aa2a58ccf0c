//! Marziliano edge widths as the authors' JNBM and CPBD code measures them,
//! shared by `jnbm`,
//! `cpbd` and `whole_image`.
//!
//! On an array `A` (grey values, `w x h`, row-major: the whole image for
//! CPBD, one 64x64 block for JNBM) and an edge map `E` (a vertical Sobel map,
//! [`super::matlab_edge::sobel_vertical`]):
//!
//! - **Gradient angle** (MATLAB `[Gx, Gy] = gradient(A)`: central
//!   differences, `Gy` pointing down the rows):
//!   `angle = atan2(Gy, Gx) * (180/pi)` where `Gx != 0`; `0` where
//!   `Gx = Gy = 0`; `90` where `Gx = 0` and `Gy = pi/2` (never, for 8-bit
//!   data). Where `Gx = 0` and `Gy != 0` the code assigns nothing, and a
//!   MATLAB array grown by indexed assignment holds `0` there: such pixels
//!   count as angle 0 (a *rising* edge) although their gradient is vertical.
//!   (MATLAB would even fail with an index error if the last row or column
//!   were never assigned; we do not reproduce that.) The angle is quantised
//!   as `45 round(angle / 45)` (half away from zero).
//! - **Which edge pixels get a width** ([`AngleRule`]): quantised angle `0`
//!   -> rising edge (dark to bright left to right); for the falling side
//!   `CPBD_compute.m` tests `round(angle) == 180 || round(angle) == -180`, but
//!   `JNBM_compute.m` tests `round(angle) == 180 || angle == -180`: the
//!   *unrounded* angle against -180. `atan2` returns -180 only for
//!   `Gy = -0`, which a difference of equal values never gives, so in JNBM a
//!   falling edge is measured only when its angle lies in `[157.5, 180]`
//!   (`Gy >= 0`, brightness not decreasing down the column); a falling edge
//!   with `Gy < 0` (angle in `(-180, -157.5]`) gets no width. We follow each
//!   code (the "-180 rule").
//! - **Width**: walk from the edge pixel left and right along the row of
//!   `A` while the intensity keeps falling (rising) away from the edge,
//!   at most 100 steps each way and never past the ends of the row of `A`
//!   (so in JNBM never past the block); each side counts `steps + 1`, the
//!   width is the sum (an ideal step edge has width 2).
//! - Only pixels at least one pixel inside `A` are measured (rows and columns
//!   `2..N-1` in MATLAB terms).
//!
//! The authors' code measures widths along rows only, at vertical Sobel
//! edges: it is blind to blur along the columns. The direction-aware
//! variants run the same measurement on the transposed array as well
//! ([`transpose`]: horizontal edges walked along columns).

/// Maximum walking steps on each side of an edge pixel.
pub const MAX_STEPS: usize = 100;
/// A block is an edge block when more than this share of its pixels are Canny edges.
pub const EDGE_BLOCK_SHARE: f64 = 0.002;

/// Which quantised gradient angles get a width.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum AngleRule {
    /// `JNBM_compute.m`: rounded 0 (rising), rounded 180 or *unrounded* -180
    /// (falling); `Gx = 0` counts as angle 0.
    Jnbm,
    /// `CPBD_compute.m`: rounded 0 (rising), rounded 180 or -180 (falling);
    /// `Gx = 0` counts as angle 0.
    Cpbd,
    /// The earlier approximation (`whole_image`): `|angle| < 22.5`
    /// rising, `|angle| >= 157.5` falling, pixels with `Gx = 0` skipped.
    Symmetric,
}

/// Which edge widths a metric pools.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Axes {
    /// Along rows only, at vertical edges: the authors' metrics.
    Rows,
    /// Along rows at vertical edges and along columns at horizontal edges
    /// (the same measurement on the transposed array): the `_2d` variants.
    Both,
}

/// Direction of the horizontal gradient at an edge pixel.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Dir {
    /// Dark to bright, left to right (quantised angle 0).
    Rising,
    /// Bright to dark, left to right (quantised angle +-180).
    Falling,
}

/// The MATLAB angle in degrees of the central-difference gradient
/// `(gx, gy)`, with the code's rules for `gx = 0` (see the module docs).
pub fn angle_deg(gx: f64, gy: f64) -> f64 {
    if gx != 0.0 {
        gy.atan2(gx) * (180.0 / std::f64::consts::PI)
    } else if gy == std::f64::consts::FRAC_PI_2 {
        90.0
    } else {
        // gy == 0 explicitly, otherwise unassigned (zero-filled)
        0.0
    }
}

/// The walk direction of an edge pixel with gradient `(gx, gy)` under `rule`,
/// `None` when it gets no width.
pub fn walk_dir(gx: f64, gy: f64, rule: AngleRule) -> Option<Dir> {
    match rule {
        AngleRule::Symmetric => {
            if gx == 0.0 {
                return None;
            }
            let ang = gy.atan2(gx).to_degrees().abs();
            if ang < 22.5 {
                Some(Dir::Rising)
            } else if ang >= 157.5 {
                Some(Dir::Falling)
            } else {
                None
            }
        }
        AngleRule::Jnbm | AngleRule::Cpbd => {
            let ang = angle_deg(gx, gy);
            let q = 45.0 * (ang / 45.0).round();
            let falling = match rule {
                AngleRule::Jnbm => q == 180.0 || ang == -180.0,
                _ => q == 180.0 || q == -180.0,
            };
            if falling {
                Some(Dir::Falling)
            } else if q == 0.0 {
                Some(Dir::Rising)
            } else {
                None
            }
        }
    }
}

/// Counts one side of an edge: steps taken (at most [`MAX_STEPS`]) + 1.
/// `step` is -1 (left) or +1 (right); `grow` says whether the intensity must
/// keep increasing (true) or decreasing (false) while walking away.
fn side(row: &[f64], x: usize, step: isize, grow: bool) -> usize {
    let n = row.len() as isize;
    for k in 0..MAX_STEPS as isize {
        let inner = x as isize + step * (1 + k);
        let outer = x as isize + step * (2 + k);
        if outer < 0 || outer >= n {
            return k as usize + 1;
        }
        let d = row[outer as usize] - row[inner as usize];
        if (grow && d <= 0.0) || (!grow && d >= 0.0) {
            return k as usize + 1;
        }
    }
    MAX_STEPS + 1
}

/// Marziliano edge widths, px, row-major, measured along the rows of `a`;
/// 0 where there is no measured edge.
pub fn edge_widths(a: &[f64], w: usize, h: usize, edges: &[bool], rule: AngleRule) -> Vec<u32> {
    let mut out = vec![0u32; w * h];
    if w < 3 || h < 3 {
        return out;
    }
    for y in 1..h - 1 {
        let row = &a[y * w..(y + 1) * w];
        for x in 1..w - 1 {
            if !edges[y * w + x] {
                continue;
            }
            let gx = (row[x + 1] - row[x - 1]) / 2.0;
            let gy = (a[(y + 1) * w + x] - a[(y - 1) * w + x]) / 2.0;
            let width = match walk_dir(gx, gy, rule) {
                // rising left to right: falls going left, rises going right
                Some(Dir::Rising) => side(row, x, -1, false) + side(row, x, 1, true),
                Some(Dir::Falling) => side(row, x, -1, true) + side(row, x, 1, false),
                None => 0,
            };
            out[y * w + x] = width as u32;
        }
    }
    out
}

/// Transpose of a row-major `w x h` array (the result is `h x w`).
pub fn transpose<T: Copy>(a: &[T], w: usize, h: usize) -> Vec<T> {
    let mut out = Vec::with_capacity(w * h);
    for x in 0..w {
        for y in 0..h {
            out.push(a[y * w + x]);
        }
    }
    out
}

/// Is a block with `canny_edges` Canny pixels out of `pixels` an edge block?
pub fn is_edge_block(canny_edges: usize, pixels: usize) -> bool {
    canny_edges as f64 > pixels as f64 * EDGE_BLOCK_SHARE
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assess::matlab_edge::sobel_vertical;

    fn widths_of_row(a: &[f64], w: usize, h: usize, rule: AngleRule) -> Vec<u32> {
        let e = sobel_vertical(a, w, h, None);
        let wd = edge_widths(a, w, h, &e, rule);
        wd[2 * w..3 * w]
            .iter()
            .copied()
            .filter(|&v| v > 0)
            .collect()
    }

    #[test]
    fn step_edge_has_width_two_and_ramp_its_length() {
        let (w, h) = (40, 5);
        let a: Vec<f64> = (0..w * h)
            .map(|i| if i % w > 10 { 200.0 } else { 10.0 })
            .collect();
        assert_eq!(widths_of_row(&a, w, h, AngleRule::Cpbd), vec![2]);
        // 6-step falling ramp 200 -> 20 over x = 10..=16 (30 per px)
        let a: Vec<f64> = (0..w * h)
            .map(|i| 200.0 - 30.0 * ((i % w) as f64 - 10.0).clamp(0.0, 6.0))
            .collect();
        for rule in [AngleRule::Jnbm, AngleRule::Cpbd, AngleRule::Symmetric] {
            assert_eq!(widths_of_row(&a, w, h, rule), vec![6], "{rule:?}");
        }
    }

    #[test]
    fn angle_rules() {
        use AngleRule::*;
        // rising, falling with gy = 0 (+180), gy > 0 and gy < 0
        assert_eq!(walk_dir(10.0, 1.0, Jnbm), Some(Dir::Rising));
        assert_eq!(walk_dir(-10.0, 0.0, Jnbm), Some(Dir::Falling));
        assert_eq!(walk_dir(-10.0, 1.0, Jnbm), Some(Dir::Falling));
        assert_eq!(walk_dir(-10.0, -1.0, Jnbm), None);
        assert_eq!(walk_dir(-10.0, -1.0, Cpbd), Some(Dir::Falling));
        assert_eq!(walk_dir(-10.0, -1.0, Symmetric), Some(Dir::Falling));
        // -0.0 is the only way to -180 exactly (never from a difference)
        assert_eq!(walk_dir(-10.0, -0.0, Jnbm), Some(Dir::Falling));
        assert_eq!((-1.0f64 + 1.0).to_bits(), 0.0f64.to_bits());
        // gx = 0: angle 0 (rising) in the authors' code, skipped before
        assert_eq!(walk_dir(0.0, 5.0, Jnbm), Some(Dir::Rising));
        assert_eq!(walk_dir(0.0, -5.0, Cpbd), Some(Dir::Rising));
        assert_eq!(walk_dir(0.0, 0.0, Cpbd), Some(Dir::Rising));
        assert_eq!(walk_dir(0.0, 5.0, Symmetric), None);
        // 45-degree bins: 22 -> 0, 23 -> 45, 157 -> 135, 158 -> 180
        let t = |deg: f64| (deg.to_radians().cos(), deg.to_radians().sin());
        for (deg, want) in [
            (22.0, Some(Dir::Rising)),
            (23.0, None),
            (157.0, None),
            (158.0, Some(Dir::Falling)),
            (-158.0, None),
        ] {
            let (gx, gy) = t(deg);
            assert_eq!(walk_dir(gx, gy, Jnbm), want, "{deg}");
        }
        let (gx, gy) = t(-158.0);
        assert_eq!(walk_dir(gx, gy, Cpbd), Some(Dir::Falling));
    }

    #[test]
    fn transpose_round_trip() {
        let a: Vec<u32> = (0..12).collect();
        let t = transpose(&a, 4, 3);
        assert_eq!(t, vec![0, 4, 8, 1, 5, 9, 2, 6, 10, 3, 7, 11]);
        assert_eq!(transpose(&t, 3, 4), a);
    }

    #[test]
    fn edge_block_share() {
        // 0.2 % of 4096 = 8.192: 9 edge pixels make an edge block, 8 do not
        assert!(!is_edge_block(8, 4096));
        assert!(is_edge_block(9, 4096));
    }
}
