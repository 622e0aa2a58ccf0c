//! How many warp instants an exposure needs: the longest path (px) that a
//! pixel centre's image point would travel at its peak speed over the
//! exposure (the instants are uniform in time, so their spacing along the
//! path is set by the peak speed, not the mean: a shake that slows down
//! would otherwise get too few), measured on probe points of the frame
//! (corners, edge midpoints, centre; with a rolling shutter the ends and
//! middle of probe lines) over a fine table of instants, then a margin.
//!
//! The maps are homographies of smooth motions, so the path's speed over the
//! frame is largest at its edges (rotation: the corners; approach: the
//! corners; translation: everywhere alike) and the chord sum of a
//! [`PROBE_INSTANTS`]-step polyline is within a fraction of a percent of
//! the path for motions that turn less than a few degrees per exposure.
//! [`MARGIN`] covers both. It replaces the renderer's bound
//! ([`crate::render::maps::max_path_px`]), which takes the focal gain at the
//! sensor corner for every rotation and so oversampled a yaw by 31 %.

use crate::error::Result;
use glam::{DMat3, DVec3};

/// Instants of the probe table per line.
pub const PROBE_INSTANTS: usize = 48;
/// Probe lines at most (rolling shutter; the first and last always).
pub const PROBE_LINES: usize = 33;
/// Factor on the longest probed path (points between the probes, the chords).
pub const MARGIN: f64 = 1.1;

/// Longest peak-speed path (px, times [`MARGIN`]) of the frame pixel centres' image
/// points: `map(line, t)` is line `line`'s frame-to-image map at instant
/// `t` of `n` (midpoints of its own exposure window); `mode` 0 global (one
/// line), 1 per row, 2 per column, of a `w` x `h` frame.
pub fn longest_path_px(
    w: u32,
    h: u32,
    mode: u32,
    map: impl Fn(usize, usize, usize) -> Result<DMat3>,
) -> Result<f64> {
    let (fw, fh) = (w as f64, h as f64);
    let lines = match mode {
        0 => 1,
        1 => h as usize,
        _ => w as usize,
    };
    let step = lines.div_ceil(PROBE_LINES - 1).max(1);
    let mut probe_lines: Vec<usize> = (0..lines).step_by(step).collect();
    if probe_lines.last() != Some(&(lines - 1)) {
        probe_lines.push(lines - 1);
    }
    let n = PROBE_INSTANTS;
    let mut longest: f64 = 0.0;
    for &line in &probe_lines {
        let c = line as f64 + 0.5;
        let points: Vec<(f64, f64)> = match mode {
            0 => {
                let xs = [0.5, 0.5 * fw, fw - 0.5];
                let ys = [0.5, 0.5 * fh, fh - 0.5];
                xs.iter()
                    .flat_map(|&x| ys.iter().map(move |&y| (x, y)))
                    .collect()
            }
            1 => vec![(0.5, c), (0.5 * fw, c), (fw - 0.5, c)],
            _ => vec![(c, 0.5), (c, 0.5 * fh), (c, fh - 0.5)],
        };
        let maps: Vec<DMat3> = (0..n).map(|m| map(line, m, n)).collect::<Result<_>>()?;
        for &(x, y) in &points {
            let at = |m: &DMat3| {
                let p = *m * DVec3::new(x, y, 1.0);
                (p.z > 0.0).then(|| (p.x / p.z, p.y / p.z))
            };
            // A point that sees beyond the plane's horizon shows the fill.
            let Some(track) = maps.iter().map(at).collect::<Option<Vec<_>>>() else {
                continue;
            };
            // Instants are uniform in time, so the spacing is set by the
            // peak speed: the longest chord over the window's n steps.
            let chord = track
                .windows(2)
                .map(|s| (s[1].0 - s[0].0).hypot(s[1].1 - s[0].1))
                .fold(0.0, f64::max);
            let path = chord * n as f64;
            if path.is_finite() {
                longest = longest.max(path);
            }
        }
    }
    Ok(longest * MARGIN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shift_is_its_length_times_the_margin() {
        // 12 px along x over the window: every point moves 12 px.
        let map = |_l: usize, m: usize, n: usize| {
            let t = (m as f64 + 0.5) / n as f64;
            Ok(DMat3::from_translation(glam::DVec2::new(12.0 * t, 0.0)))
        };
        let l = longest_path_px(64, 48, 0, map).unwrap();
        assert!((l / MARGIN - 12.0).abs() < 1e-9, "{l}");
        let l = longest_path_px(64, 48, 1, map).unwrap();
        assert!((l / MARGIN - 12.0).abs() < 1e-9, "{l}");
        // Moving 12 px in the first half of the window and still after: the
        // peak speed is twice the mean, so the bound is 24 px.
        let half = |_l: usize, m: usize, n: usize| {
            let t = ((m as f64 + 0.5) / n as f64 * 2.0).min(1.0);
            Ok(DMat3::from_translation(glam::DVec2::new(12.0 * t, 0.0)))
        };
        let l = longest_path_px(64, 48, 0, half).unwrap();
        assert!((l / MARGIN - 24.0).abs() < 0.6, "{l}");
    }
}
