//! The cost of the odometry task's feature matches between consecutive kept
//! frames (`mmbm_lab::experiment::matches`), per frame and light: describing
//! a window's FAST-9 corners (BRIEF) and matching them against the previous
//! frame's (ratio test, inliers of the homography), on a textured window with
//! noise (random 8 x 8 px blocks, the second frame shifted by 3 px), at two
//! window sizes. The map adds this once per judged frame and light.
//!
//! The FAST-9 corners are timed apart: the map computes them for the
//! repeatability already. Wall time: run it on an idle machine.
//!
//! Run: `cargo run --release -p mmbm-lab --example match_cost [JUDGEMENTS]`;
//! with JUDGEMENTS (frames x lights of a map) it prints the seconds added.

use image::GrayImage;
use mmbm_lab::experiment::matches::{corners, describe, features, inliers, Features};
use rand::{Rng, SeedableRng};
use std::time::Instant;

fn window(w: u32, h: u32, dx: u32, seed: u64) -> GrayImage {
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let cells: Vec<u8> = (0..(w / 8 + 2) * (h / 8 + 1)).map(|_| rng.gen()).collect();
    let mut noise = rand::rngs::StdRng::seed_from_u64(seed);
    GrayImage::from_fn(w, h, |x, y| {
        let v = i32::from(cells[(y / 8 * (w / 8 + 2) + (x + dx) / 8) as usize]);
        image::Luma([(v + noise.gen_range(-6..=6)).clamp(0, 255) as u8])
    })
}

fn main() -> mmbm::Result<()> {
    let judgements: Option<f64> = std::env::args().nth(1).and_then(|a| a.parse().ok());
    let shift = [[1.0, 0.0, -3.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    println!(
        "window        corners  inliers  FAST-9 us (paid already)  added us (BRIEF + matching)"
    );
    for (w, h) in [(320, 240), (640, 480)] {
        let (a, b) = (window(w, h, 0, 2), window(w, h, 3, 3));
        let fa: Features = describe(&a)?;
        let reps = 50;
        // The corners: the map computes them for the repeatability already.
        let t = Instant::now();
        let mut cb = Vec::new();
        for _ in 0..reps {
            cb = corners(&b);
        }
        let fast_us = t.elapsed().as_secs_f64() * 1e6 / f64::from(reps);
        // What the matches add: BRIEF of the corners, matching, inliers.
        let t = Instant::now();
        let mut n = 0;
        for _ in 0..reps {
            let fb = features(&b, &cb, (0.0, 0.0))?;
            n = inliers(&fa, &fb, &shift);
        }
        let us = t.elapsed().as_secs_f64() * 1e6 / f64::from(reps);
        println!(
            "{w:>4} x {h:<4}  {:>7}  {n:>7}  {fast_us:>24.0}  {us:>27.0}",
            fa.points.len()
        );
        if let Some(j) = judgements {
            println!("  x {j} judgements: {:.1} s added", us * 1e-6 * j);
        }
    }
    Ok(())
}
