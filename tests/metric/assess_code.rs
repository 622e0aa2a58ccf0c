//! JNBM and CPBD as the authors' MATLAB code computes them (block-local edge
//! maps for JNBM, fixed Sobel threshold for CPBD, the code's angle rules) and
//! the direction-aware `_2d` variants, on images whose edge widths are known.

use image::{GrayImage, Luma};
use mmbm::assess::edges::{edge_widths, AngleRule};
use mmbm::assess::matlab_edge::sobel_vertical;
use mmbm::assess::{
    assess, cpbd, cpbd_2d, cpbd_whole_image, jnbm, jnbm_2d, jnbm_2d_report, jnbm_report,
    jnbm_whole_image_report,
};

const BETA: f64 = 3.6;

/// `L / (sum over edges of (w / w_jnb)^beta)^(1/beta)` for `(count, width)`
/// groups that all have `w_jnb = 3` (contrast > 59).
fn expected_jnbm(blocks: usize, groups: &[(usize, f64)]) -> f64 {
    let s: f64 = groups
        .iter()
        .map(|&(n, w)| n as f64 * (w / 3.0).powf(BETA))
        .sum();
    blocks as f64 / s.powf(1.0 / BETA)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

/// Grey ramp along x: `lo` up to `x0`, then `step` per px for `steps`
/// pixels, then flat.
fn ramp_x(w: u32, h: u32, x0: u32, steps: u32, lo: u8, step: u8) -> GrayImage {
    GrayImage::from_fn(w, h, |x, _| {
        let k = x.saturating_sub(x0).min(steps);
        Luma([lo + step * k as u8])
    })
}

fn transpose(g: &GrayImage) -> GrayImage {
    GrayImage::from_fn(g.height(), g.width(), |x, y| *g.get_pixel(y, x))
}

#[test]
fn sharp_step_has_width_two_in_every_row() {
    // 128x128, step 20 -> 220 at x = 31|32: blocks (0,0) and (0,1) are edge
    // blocks with 62 measured rows each (block rows 2..63), width 2
    let img = GrayImage::from_fn(128, 128, |x, _| Luma([if x >= 32 { 220 } else { 20 }]));
    let r = jnbm_report(&img).unwrap();
    assert_eq!((r.blocks, r.edge_blocks, r.edges), (4, 2, 124));
    assert_eq!(r.mean_width, 2.0);
    assert!(close(r.jnbm.unwrap(), expected_jnbm(4, &[(124, 2.0)])));
    assert_eq!(cpbd(&img).unwrap(), 1.0);
}

#[test]
fn horizontal_ramp_is_measured_and_vertical_ramp_only_by_2d() {
    // 8-step ramp 40 -> 200 (20 per px) from x = 28 to 36, inside one block
    let img = ramp_x(64, 64, 28, 8, 40, 20);
    let r = jnbm_report(&img).unwrap();
    assert_eq!((r.edge_blocks, r.edges), (1, 62));
    assert_eq!(r.mean_width, 8.0);
    let want = expected_jnbm(1, &[(62, 8.0)]);
    assert!(close(r.jnbm.unwrap(), want), "{r:?} vs {want}");
    // no horizontal edge: the 2d variant gives the same
    assert_eq!(jnbm_2d_report(&img).unwrap(), r);

    // the same ramp along y: an edge block (Canny sees it) without a single
    // width along the rows: JNBM undefined, CPBD 0; the 2d variant measures it
    let v = transpose(&img);
    let r = jnbm_report(&v).unwrap();
    assert_eq!((r.edge_blocks, r.edges, r.jnbm), (1, 0, None));
    assert!(jnbm(&v).is_err());
    let r2 = jnbm_2d_report(&v).unwrap();
    assert_eq!((r2.edge_blocks, r2.edges), (1, 62));
    assert_eq!(r2.mean_width, 8.0);
    assert!(close(r2.jnbm.unwrap(), want));
    assert!(close(jnbm_2d(&v).unwrap(), want));

    // CPBD: width 3 is at the just noticeable blur (P = 63 %, counted
    // sharp), width 4 is beyond it (w_JNB = 3 at contrast > 50)
    for (steps, sharp) in [(3u32, 1.0), (4, 0.0)] {
        let h = ramp_x(64, 64, 30, steps, 40, 40);
        assert_eq!(cpbd(&h).unwrap(), sharp, "{steps} steps along x");
        assert_eq!(cpbd_2d(&h).unwrap(), sharp, "{steps} steps along x, 2d");
        let v = transpose(&h);
        assert_eq!(cpbd(&v).unwrap(), 0.0, "{steps} steps along y");
        assert_eq!(cpbd_2d(&v).unwrap(), sharp, "{steps} steps along y, 2d");
    }
}

/// Checkerboard of 32 px squares (40 / 200), offset by 16 px so that no
/// square border coincides with a 64 px block border.
fn checkerboard(n: u32) -> GrayImage {
    GrayImage::from_fn(n, n, |x, y| {
        Luma([if ((x + 16) / 32 + (y + 16) / 32) % 2 == 0 {
            40
        } else {
            200
        }])
    })
}

/// Box blur of `len` px along x (`along_x`) or y, clamped border, rounded.
fn box_blur(g: &GrayImage, len: u32, along_x: bool) -> GrayImage {
    let r = (len / 2) as i64;
    let (w, h) = (g.width() as i64, g.height() as i64);
    GrayImage::from_fn(g.width(), g.height(), |x, y| {
        let s: f64 = (-r..=r)
            .map(|d| {
                let (xx, yy) = if along_x {
                    ((x as i64 + d).clamp(0, w - 1), y as i64)
                } else {
                    (x as i64, (y as i64 + d).clamp(0, h - 1))
                };
                g.get_pixel(xx as u32, yy as u32)[0] as f64
            })
            .sum();
        Luma([(s / (2 * r + 1) as f64).round() as u8])
    })
}

#[test]
fn checkerboard_blur_along_x_and_y() {
    let sharp = checkerboard(128);
    // a 5 px box blur turns each 40 -> 200 step into a 5-step ramp (32 per px)
    let bx = box_blur(&sharp, 5, true);
    let by = box_blur(&sharp, 5, false);
    let rep = |g: &GrayImage| (jnbm_report(g).unwrap(), jnbm_2d_report(g).unwrap());
    let (s1, s2) = rep(&sharp);
    let (x1, x2) = rep(&bx);
    let (y1, y2) = rep(&by);
    for (name, r) in [
        ("sharp", s1),
        ("sharp 2d", s2),
        ("x", x1),
        ("x 2d", x2),
        ("y", y1),
        ("y 2d", y2),
    ] {
        eprintln!("{name}: {r:?}");
    }
    // the original measures rows only: blur along y leaves every row a
    // sequence of flat runs and steps (every width stays 2), blur along x
    // widens them to 5
    assert_eq!(s1.mean_width, 2.0);
    assert_eq!(y1.mean_width, 2.0);
    assert_eq!(x1.mean_width, 5.0);
    let (js, jx, jy) = (s1.jnbm.unwrap(), x1.jnbm.unwrap(), y1.jnbm.unwrap());
    assert!(jx < 0.6 * js, "x blur: {jx} vs sharp {js}");
    assert!((jy - js).abs() < 0.1 * js, "y blur: {jy} vs sharp {js}");
    // the 2d variant sees both, and symmetrically (the board is symmetric
    // under transposition)
    assert_eq!(s2.mean_width, 2.0);
    let (j2s, j2x, j2y) = (s2.jnbm.unwrap(), x2.jnbm.unwrap(), y2.jnbm.unwrap());
    assert!(j2x < 0.8 * j2s && j2y < 0.8 * j2s, "{j2s} {j2x} {j2y}");
    assert_eq!((x2.edges, x2.mean_width), (y2.edges, y2.mean_width));
    assert!(close(j2x, j2y), "{j2x} vs {j2y}");

    // CPBD along the same lines (w_JNB = 3: width 5 is blurred, 2 sharp)
    let (cs, cx, cy) = (
        cpbd(&sharp).unwrap(),
        cpbd(&bx).unwrap(),
        cpbd(&by).unwrap(),
    );
    eprintln!("cpbd sharp {cs} x {cx} y {cy}");
    assert_eq!(cs, 1.0);
    assert_eq!(cx, 0.0);
    assert_eq!(cy, 1.0);
    let (c2x, c2y) = (cpbd_2d(&bx).unwrap(), cpbd_2d(&by).unwrap());
    eprintln!("cpbd_2d x {c2x} y {c2y}");
    assert_eq!(cpbd_2d(&sharp).unwrap(), 1.0);
    assert!(c2x > 0.2 && c2x < 0.8, "{c2x}");
    assert_eq!(c2x, c2y);
}

#[test]
fn jnbm_walk_stops_at_the_block_border() {
    // 8-step ramp 40 -> 200 from x = 60 to 68, across the block border at 64.
    // Block-local (authors' code): block 0 sees x = 60..63 (3 steps) and
    // measures width 3 at x = 62; block 1 sees x = 64..68 (4 steps) and
    // measures width 4 at x = 67 (its walk cannot go left of x = 64).
    let img = ramp_x(128, 64, 60, 8, 40, 20);
    let r = jnbm_report(&img).unwrap();
    assert_eq!((r.blocks, r.edge_blocks, r.edges), (2, 2, 124));
    assert_eq!(r.mean_width, 3.5);
    let want = expected_jnbm(2, &[(62, 3.0), (62, 4.0)]);
    assert!(close(r.jnbm.unwrap(), want), "{r:?} vs {want}");
    // the same Sobel map and walk on the whole image: one edge per row, at
    // x = 67, walked over the whole ramp: width 8
    let (w, h) = (128, 64);
    let a: Vec<f64> = img.as_raw().iter().map(|&v| v as f64).collect();
    let e = sobel_vertical(&a, w, h, None);
    let wd = edge_widths(&a, w, h, &e, AngleRule::Jnbm);
    for y in 1..h - 1 {
        let row: Vec<(usize, u32)> = (0..w)
            .filter(|&x| wd[y * w + x] > 0)
            .map(|x| (x, wd[y * w + x]))
            .collect();
        assert_eq!(row, vec![(67, 8)], "row {y}");
    }
}

#[test]
fn cpbd_fixed_sobel_threshold() {
    // a step of height s has |Sobel/8| = s/2 beside it: the code's fixed
    // threshold 2 keeps s = 5 (width 2: CPBD 1) and drops s = 4 (no width:
    // CPBD 0); the automatic cutoff of the whole-image version keeps both
    for (s, want) in [(4u8, 0.0), (5, 1.0)] {
        let img = GrayImage::from_fn(64, 64, |x, _| Luma([100 + if x >= 32 { s } else { 0 }]));
        assert_eq!(cpbd(&img).unwrap(), want, "step {s}");
        assert_eq!(
            cpbd_whole_image(&img).unwrap(),
            1.0,
            "step {s}, whole image"
        );
    }
}

/// Vertical step `hi` -> `lo` (falling, left to right) at x = 31|32 with a
/// vertical gradient of `slope` grey levels per row.
fn falling_step(slope: i32) -> GrayImage {
    GrayImage::from_fn(64, 64, |x, y| {
        let base = if x < 32 { 180 } else { 60 };
        Luma([(base + slope * (y as i32 - 32)) as u8])
    })
}

#[test]
fn minus_180_rule() {
    // at the edge pixel gx = -60, gy = slope: angle 180 - 0.95 degrees for
    // slope +1, -(180 - 0.95) for slope -1, exactly 180 for slope 0.
    // JNBM_compute.m measures rounded 180 or *unrounded* -180: the first
    // and last get widths, the middle one none. CPBD_compute.m measures
    // rounded +-180: all three.
    for (slope, measured) in [(1, true), (0, true), (-1, false)] {
        let img = falling_step(slope);
        let r = jnbm_report(&img).unwrap();
        assert_eq!(r.edge_blocks, 1, "slope {slope}");
        if measured {
            assert_eq!((r.edges, r.mean_width), (62, 2.0), "slope {slope}");
            assert!(close(r.jnbm.unwrap(), expected_jnbm(1, &[(62, 2.0)])));
        } else {
            assert_eq!((r.edges, r.jnbm), (0, None), "slope {slope}");
        }
        assert_eq!(cpbd(&img).unwrap(), 1.0, "slope {slope}");
        // the earlier whole-image version measured all three
        assert_eq!(jnbm_whole_image_report(&img).unwrap().edges, 62);
    }
    // a rising edge with a falling vertical gradient (angle -0.95 degrees,
    // rounded 0) is measured by both
    let rising = GrayImage::from_fn(64, 64, |x, y| {
        Luma([((if x < 32 { 60 } else { 180 }) - (y as i32 - 32)) as u8])
    });
    assert_eq!(jnbm_report(&rising).unwrap().edges, 62);
}

#[test]
fn zero_horizontal_difference_counts_as_rising() {
    // step 50 -> 200 above row 20, 50 -> 150 below it, row 20 flat at 50.
    // At (32, 20) the central difference gx is 0 and gy = -25: the code
    // leaves the angle unassigned, MATLAB zero-fills it, and the pixel is
    // walked as a rising edge (width 2). Rows 19 and 21 have angles of -45
    // and +45 degrees and get no width. MATLAB's thinning also keeps (31, 18),
    // where bx^2 is a vertical local maximum (75^2 in rows 17 and 18, 56.25^2
    // in row 19): 62 - 2 + 1 = 61 widths, all 2.
    let img = GrayImage::from_fn(64, 64, |x, y| {
        let v = match (x >= 32, y) {
            (false, _) | (_, 20) => 50,
            (true, y) if y < 20 => 200,
            _ => 150,
        };
        Luma([v])
    });
    let r = jnbm_report(&img).unwrap();
    assert_eq!((r.edges, r.mean_width), (61, 2.0));
    // the earlier version skipped gx = 0
    assert_eq!(jnbm_whole_image_report(&img).unwrap().edges, 59);
}

#[test]
fn assess_matches_the_single_metrics() {
    let img = box_blur(&checkerboard(192), 3, false);
    let a = assess(&img).unwrap();
    assert_eq!(a.jnbm, Some(jnbm(&img).unwrap()));
    assert_eq!(a.jnbm_2d, Some(jnbm_2d(&img).unwrap()));
    assert_eq!(a.cpbd, cpbd(&img).unwrap());
    assert_eq!(a.cpbd_2d, cpbd_2d(&img).unwrap());
    // pooling more widths only adds distortion
    assert!(a.jnbm_2d.unwrap() < a.jnbm.unwrap());
}
