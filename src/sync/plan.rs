//! Which frames `sync` decodes. Decoding is most of sync's time (a 1080p
//! H.264 frame costs several times its tracking), and the offset needs
//! neither every frame nor consecutive frames across the whole clip, only
//! pairs of consecutive frames with motion. So a clip of more than twice the
//! frame budget is decoded in windows of consecutive frames, each starting
//! at a keyframe (where decoding can start without decoding what precedes
//! it), spread evenly over the clip's keyframes, as Gyroflow syncs at a few
//! points of a clip. A shorter clip, or a budget of 0, is decoded whole.

use crate::error::{show_path, Error, Result};
use crate::video::decode::Window;
use std::path::Path;

/// Frames `sync` decodes by default (`--decode-frames`): a clip of more
/// than twice this many frames is decoded in windows of about this many
/// frames in all.
pub const DEFAULT_DECODE_FRAMES: usize = 64;
/// Most windows.
pub const MAX_WINDOWS: usize = 8;
/// Fewest frames of a window: each window costs an ffmpeg start and a
/// keyframe (about as much as 20 frames of 1080p), so a few long windows
/// beat many short ones.
pub const MIN_WINDOW_FRAMES: usize = 24;

/// The first video stream's packets (demuxed, not decoded): how many, and
/// the keyframes' presentation times, s, on the file's clock, in order.
pub fn keyframes(video: &Path) -> Result<(usize, Vec<f64>)> {
    let text = crate::video::decode::probe_csv(video, "packet=pts_time,flags")?;
    let mut n = 0usize;
    let mut keys = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        n += 1;
        let mut f = line.trim().split(',');
        let t = f.next().and_then(|t| t.parse::<f64>().ok());
        let key = f.next().is_some_and(|fl| fl.starts_with('K'));
        if let (Some(t), true) = (t, key) {
            if t.is_finite() {
                keys.push(t);
            }
        }
    }
    if n == 0 {
        return Err(Error::invalid(
            show_path(video),
            "ffprobe lists no packets of its video stream",
        ));
    }
    keys.sort_by(f64::total_cmp);
    keys.dedup();
    Ok((n, keys))
}

/// The windows to decode for a clip of `packets` frames at `fps` frames/s
/// whose file starts at `start_s` (s, file clock) with keyframes at `keys`
/// (s, file clock), about `budget` frames in all; `None`: decode it whole
/// (a budget of 0, a clip of at most twice the budget, or no keyframe).
/// Each window seeks a quarter frame past its keyframe (so that the seek
/// lands on it, not on the one before), and no two windows overlap.
pub fn plan(
    packets: usize,
    keys: &[f64],
    start_s: f64,
    fps: f64,
    budget: usize,
) -> Option<Vec<Window>> {
    if budget == 0 || packets <= 2 * budget || keys.is_empty() || fps.is_nan() || fps <= 0.0 {
        return None;
    }
    // The keyframes with a whole window after them (the keyframe itself is
    // dropped: the seek lands a quarter frame past it), else the first.
    let end = start_s + packets as f64 / fps;
    let room = |k: f64, frames: usize| k + (frames + 1) as f64 / fps <= end + 1e-9;
    let spread = (budget / MIN_WINDOW_FRAMES).max(1);
    let eligible: Vec<f64> = keys
        .iter()
        .copied()
        .filter(|&k| room(k, budget.div_ceil(spread).max(MIN_WINDOW_FRAMES)))
        .collect();
    let keys: &[f64] = if eligible.is_empty() {
        &keys[..1]
    } else {
        &eligible
    };
    let n = MAX_WINDOWS.min(keys.len()).min(spread);
    let frames = budget.div_ceil(n).max(MIN_WINDOW_FRAMES);
    let mut out: Vec<Window> = Vec::new();
    let mut next_free = f64::NEG_INFINITY;
    for i in 0..n {
        // Keyframes spread by index, the first and the last included.
        let j = if n == 1 {
            keys.len() / 2
        } else {
            (i * (keys.len() - 1) + (n - 1) / 2) / (n - 1)
        };
        let k = keys[j];
        if k < next_free {
            continue;
        }
        next_free = k + frames as f64 / fps;
        out.push(Window {
            start_s: (k - start_s).max(0.0) + 0.25 / fps,
            frames,
        });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_clips_and_a_zero_budget_are_decoded_whole() {
        let keys = [0.0, 1.0, 2.0];
        assert_eq!(plan(192, &keys, 0.0, 60.0, 96), None);
        assert_eq!(plan(600, &keys, 0.0, 60.0, 0), None);
        assert_eq!(plan(600, &[], 0.0, 60.0, 96), None);
    }

    #[test]
    fn windows_start_at_spread_keyframes_without_overlap() {
        // 10 s at 60 fps, a keyframe every 0.5 s.
        let keys: Vec<f64> = (0..20).map(|i| i as f64 * 0.5).collect();
        let w = plan(600, &keys, 0.0, 60.0, 96).unwrap();
        assert_eq!(w.len(), 4);
        assert!(w.iter().all(|w| w.frames == 24));
        assert!((w[0].start_s - 0.25 / 60.0).abs() < 1e-12);
        // The last keyframe with 25 frames after it: 9.5 s.
        assert!((w[3].start_s - (9.5 + 0.25 / 60.0)).abs() < 1e-12);
        for p in w.windows(2) {
            assert!(p[1].start_s >= p[0].start_s + 24.0 / 60.0, "{p:?}");
        }
        // A larger budget: up to 8 windows.
        let w = plan(6000, &keys, 0.0, 60.0, 400).unwrap();
        assert_eq!(w.len(), 8);
        assert!(w.iter().all(|w| w.frames == 50));
        // Three keyframes (x264's default keyint of 250 at 60 fps): three
        // longer windows, 32 frames each.
        let w = plan(600, &[0.0, 4.1667, 8.3333], 0.0, 60.0, 96).unwrap();
        assert_eq!(w.len(), 3);
        assert!(w.iter().all(|w| w.frames == 32));
        // Keyframes closer than a window: the overlapping ones are left out.
        let keys: Vec<f64> = (0..8).map(|i| i as f64 * 0.1).collect();
        let w = plan(600, &keys, 0.0, 60.0, 96).unwrap();
        assert_eq!(w.len(), 2, "{w:?}");
        for p in w.windows(2) {
            assert!(p[1].start_s >= p[0].start_s + 24.0 / 60.0, "{p:?}");
        }
    }
}
