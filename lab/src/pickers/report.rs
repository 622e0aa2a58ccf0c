//! The benchmark's page (`docs/pickers.md`): what was run, the measured
//! tables, the goals each met or not, and where the gyro loses;
//! every number and every sentence about results computed from the
//! [`Outcome`].

use super::pick::{ms_per_frame, Picker};
use super::score::BLURRED_PX;
use super::{ClipResult, Outcome, BUDGET_PX, OFFSET_ERRORS_S, TUNED_ON};
use std::fmt::Write as _;

/// Where and when it ran (for the page's header).
#[derive(Debug, Clone, Default)]
pub struct Machine {
    /// CPU and core count, in words.
    pub cpu: String,
    /// The 1-minute load average at the start and end.
    pub load: String,
    /// The date (UTC).
    pub date: String,
}

/// The largest tolerated excess of the gyro's mean true blur over the
/// oracle's (the goal: within 3 %).
pub const WITHIN_ORACLE: f64 = 0.03;
/// The sync goal, s.
pub const SYNC_GOAL_S: f64 = 0.002;
/// The budget goal: F1 at least this on every clip.
pub const F1_GOAL: f64 = 0.95;
/// The speed goal: gyro file to image list this many times faster than
/// decoding and scoring with the Laplacian.
pub const SPEED_GOAL: f64 = 100.0;

fn met(ok: bool) -> &'static str {
    if ok {
        "**met**"
    } else {
        "**not met**"
    }
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (n, s) = v.fold((0usize, 0.0), |(n, s), x| (n + 1, s + x));
    s / n.max(1) as f64
}

/// The picks table: per picker and clip, mean true blur, share over the
/// limit, largest hole; the mean time per frame over the clips.
pub fn picks_table(o: &Outcome) -> String {
    let mut s = String::from("| picker |");
    for c in &o.clips {
        let _ = write!(s, " {} |", c.spec.name);
    }
    s.push_str(" ms/frame |\n|---|");
    for _ in &o.clips {
        s.push_str("---|");
    }
    s.push_str("---|\n");
    for p in Picker::ALL {
        let _ = write!(s, "| {} |", p.name());
        for c in &o.clips {
            let x = c.score(p);
            let _ = if x.picks == 0 {
                write!(s, " no picks · {:.2} s |", x.hole_s)
            } else {
                write!(
                    s,
                    " {:.2} px · {:.0} % · {:.2} s ({}) |",
                    x.mean_px,
                    100.0 * x.over,
                    x.hole_s,
                    x.picks
                )
            };
        }
        match ms_per_frame(p, &o.clips[0].measures) {
            Some(_) => {
                let ms = mean(o.clips.iter().filter_map(|c| ms_per_frame(p, &c.measures)));
                let _ = writeln!(s, " {ms:.3} |");
            }
            None => s.push_str(" - |\n"),
        }
    }
    s
}

fn sync_table(o: &Outcome) -> String {
    let mut s = String::from(
        "| clip | true offset (ms) | error (ms) | confidence | ms/frame |\n|---|---|---|---|---|\n",
    );
    for c in &o.clips {
        let _ = match &c.sync {
            Ok(r) => writeln!(
                s,
                "| {} | {:.2} | {:+.2} | {:.2} | {:.1} |",
                c.spec.name,
                1e3 * c.clip.offset_s,
                1e3 * r.error_s,
                r.confidence,
                r.ms_per_frame
            ),
            Err(e) => writeln!(
                s,
                "| {} | {:.2} | refused: {} | - | - |",
                c.spec.name,
                1e3 * c.clip.offset_s,
                e.replace(&c.clip.video.display().to_string(), &video_name(c))
                    .replace('|', "/")
            ),
        };
    }
    s
}

/// The video's file name (the table does not show where the run kept it).
fn video_name(c: &ClipResult) -> String {
    c.clip
        .video
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn offset_table(o: &Outcome) -> String {
    let mut s = String::from("| clip | right offset |");
    for e in OFFSET_ERRORS_S {
        let _ = write!(s, " +{:.0} ms |", 1e3 * e);
    }
    s.push_str(" oracle |\n|---|---|");
    for _ in OFFSET_ERRORS_S {
        s.push_str("---|");
    }
    s.push_str("---|\n");
    for c in &o.clips {
        let g = c.score(Picker::Gyro);
        let _ = write!(
            s,
            "| {} | {:.2} px · {:.0} % |",
            c.spec.name,
            g.mean_px,
            100.0 * g.over
        );
        for x in &c.offset_scores {
            let _ = write!(s, " {:.2} px · {:.0} % |", x.mean_px, 100.0 * x.over);
        }
        let or = c.score(Picker::Oracle);
        let _ = writeln!(s, " {:.2} px |", or.mean_px);
    }
    s
}

fn budget_table(o: &Outcome) -> String {
    let mut s =
        String::from("| clip | gyro P / R / F1 | Laplacian (tuned) P / R / F1 |\n|---|---|---|\n");
    for c in &o.clips {
        let (g, l) = (c.budget_gyro, c.budget_laplacian);
        let _ = writeln!(
            s,
            "| {} | {:.2} / {:.2} / {:.2} | {:.2} / {:.2} / {:.2} |",
            c.spec.name, g.precision, g.recall, g.f1, l.precision, l.recall, l.f1
        );
    }
    s
}

/// Whether the gyro's windowed picks are within [`WITHIN_ORACLE`] of the
/// oracle's mean true blur on clip `c`.
fn near_oracle(c: &ClipResult) -> bool {
    c.score(Picker::Gyro).mean_px <= (1.0 + WITHIN_ORACLE) * c.score(Picker::Oracle).mean_px
}

/// The mean true blur of the picks of `p` on `c` in the windows that do
/// not touch the defocus or the stabilised stretch, px.
fn clear_mean(o: &Outcome, c: &ClipResult, p: Picker) -> f64 {
    let w = o.config.window;
    let st = &o.stretches;
    let touches = |r: &std::ops::Range<usize>, k: usize| {
        let (a, b) = (k / w * w, k / w * w + w);
        a < r.end && r.start < b
    };
    mean(
        c.picks(p)
            .iter()
            .filter(|&&k| !touches(&st.defocus, k) && !touches(&st.ois, k))
            .map(|&k| c.clip.truth[k]),
    )
}

/// The windowed image-only pickers.
const WINDOWED_IMAGE: [Picker; 3] = [Picker::Laplacian, Picker::Tenengrad, Picker::BlurDetect];

/// The mean true blur of the gyro's picks and of `p`'s over the windows
/// where `p` picked a frame (a picker whose metric is undefined on a frame,
/// as `blurdetect`'s on a plain wall, leaves its window empty), and how many
/// windows those are, px.
fn paired(o: &Outcome, c: &ClipResult, p: Picker) -> (f64, f64, usize) {
    let w = o.config.window;
    let gyro = c.picks(Picker::Gyro);
    let (mut g, mut x, mut n) = (0.0, 0.0, 0usize);
    for &k in c.picks(p) {
        if let Some(&j) = gyro.iter().find(|&&j| j / w == k / w) {
            g += c.clip.truth[j];
            x += c.clip.truth[k];
            n += 1;
        }
    }
    (g / n.max(1) as f64, x / n.max(1) as f64, n)
}

/// Whether the gyro's picks have less mean true blur than every windowed
/// image-only picker's on clip `c`, over the windows where that picker
/// picked (none picked: beaten).
fn beats_images(o: &Outcome, c: &ClipResult) -> bool {
    WINDOWED_IMAGE.iter().all(|&p| {
        let (g, x, n) = paired(o, c, p);
        n == 0 || g < x
    })
}

/// The gyro's budget calls on the frames outside the two stretches.
fn clear_budget(o: &Outcome, c: &ClipResult) -> super::score::Prf {
    let st = &o.stretches;
    let keep: Vec<usize> = (0..c.clip.frames())
        .filter(|k| !st.defocus.contains(k) && !st.ois.contains(k))
        .collect();
    let said: Vec<bool> = keep
        .iter()
        .map(|&k| c.measures.gyro[k].is_some_and(|b| b <= BUDGET_PX))
        .collect();
    let is: Vec<bool> = keep.iter().map(|&k| c.clip.truth[k] <= BUDGET_PX).collect();
    super::score::prf(&said, &is)
}

/// The benchmark's goals, each with the numbers and met / not met.
pub fn goals(o: &Outcome) -> String {
    let mut s = String::new();
    let f1: Vec<String> = o
        .clips
        .iter()
        .map(|c| format!("{} {:.2}", c.spec.name, c.budget_gyro.f1))
        .collect();
    let f1_ok = o.clips.iter().all(|c| c.budget_gyro.f1 >= F1_GOAL);
    let tuned = &o.clips[TUNED_ON.min(o.clips.len() - 1)];
    let lap: Vec<String> = o
        .clips
        .iter()
        .map(|c| format!("{} {:.2}", c.spec.name, c.budget_laplacian.f1))
        .collect();
    let clear: Vec<String> = o
        .clips
        .iter()
        .map(|c| format!("{} {:.2}", c.spec.name, clear_budget(o, c).f1))
        .collect();
    let clear_ok = o.clips.iter().all(|c| clear_budget(o, c).f1 >= F1_GOAL);
    let _ = writeln!(
        s,
        "- **Budget that transfers** (every frame under {BUDGET_PX} px, F1 >= {F1_GOAL} on every \
         clip with no tuning): gyro F1 {}: {}; on the frames outside the two stretches the gyro \
         cannot see: {}: {}. The Laplacian threshold tuned on {} ({:.1}): F1 {}.",
        f1.join(", "),
        met(f1_ok),
        clear.join(", "),
        met(clear_ok),
        tuned.spec.name,
        o.lap_threshold,
        lap.join(", ")
    );
    let near: Vec<String> = o
        .clips
        .iter()
        .map(|c| {
            let (g, or) = (
                c.score(Picker::Gyro).mean_px,
                c.score(Picker::Oracle).mean_px,
            );
            format!("{} {:+.1} %", c.spec.name, 100.0 * (g / or - 1.0))
        })
        .collect();
    let near_ok = o.clips.iter().all(near_oracle);
    let clear: Vec<String> = o
        .clips
        .iter()
        .map(|c| {
            let (g, or) = (
                clear_mean(o, c, Picker::Gyro),
                clear_mean(o, c, Picker::Oracle),
            );
            format!("{} {:+.1} %", c.spec.name, 100.0 * (g / or - 1.0))
        })
        .collect();
    let clear_ok = o.clips.iter().all(|c| {
        clear_mean(o, c, Picker::Gyro) <= (1.0 + WITHIN_ORACLE) * clear_mean(o, c, Picker::Oracle)
    });
    let hard: Vec<&ClipResult> = o
        .clips
        .iter()
        .filter(|c| matches!(c.spec.name, "run-wall" | "walk-changing"))
        .collect();
    let beat_ok = !hard.is_empty() && hard.iter().all(|c| beats_images(o, c));
    let beat: Vec<String> = hard
        .iter()
        .map(|c| {
            let each: Vec<String> = WINDOWED_IMAGE
                .iter()
                .map(|&p| {
                    let (g, x, n) = paired(o, c, p);
                    if n == 0 {
                        format!("{} picked nothing", p.name())
                    } else {
                        format!(
                            "{} {x:.2} px against the gyro's {g:.2} px over {n} windows",
                            p.name()
                        )
                    }
                })
                .collect();
            format!("{}: {}", c.spec.name, each.join(", "))
        })
        .collect();
    let _ = writeln!(
        s,
        "- **Windowed picks within 3 % of the oracle** on every clip (gyro's mean true blur over \
         the oracle's: {}): {}; in the windows clear of the two stretches the gyro cannot see \
         ({}): {}; **strictly better than every windowed image-only picker on the \
         low-texture and changing clips** (each over the windows where it picked a frame; {}): \
         {}.",
        near.join(", "),
        met(near_ok),
        clear.join(", "),
        met(clear_ok),
        beat.join("; "),
        met(beat_ok)
    );
    let ratio: Vec<f64> = o
        .clips
        .iter()
        .map(|c| c.measures.laplacian_ms / c.measures.gyro_ms)
        .collect();
    let rmin = ratio.iter().copied().fold(f64::INFINITY, f64::min);
    let _ =
        writeln!(
        s,
        "- **Speed** (gyro file to image list >= {SPEED_GOAL}x faster than decoding and scoring \
         with the Laplacian): {:.0}x to {:.0}x at {}x{}: {}. The 1080p60 real-time goal (>= 20x \
         including sync's decoding) was **not measured** here (the clips are {}x{}); sync took \
         {:.1} ms per frame at this size.",
        rmin,
        ratio.iter().copied().fold(0.0, f64::max),
        o.config.format.width,
        o.config.format.height,
        met(rmin >= SPEED_GOAL),
        o.config.format.width,
        o.config.format.height,
        mean(o.clips.iter().filter_map(|c| c.sync.as_ref().ok().map(|r| r.ms_per_frame)))
    );
    let errs: Vec<String> = o
        .clips
        .iter()
        .map(|c| match &c.sync {
            Ok(r) => format!(
                "{} {:+.2} ms (confidence {:.2})",
                c.spec.name,
                1e3 * r.error_s,
                r.confidence
            ),
            Err(_) => format!("{} refused", c.spec.name),
        })
        .collect();
    let sync_ok = o.clips.iter().all(|c| {
        c.sync
            .as_ref()
            .is_ok_and(|r| r.error_s.abs() <= SYNC_GOAL_S)
    });
    let _ = writeln!(
        s,
        "- **Sync within 2 ms** on every clip: {}: {}.",
        errs.join(", "),
        met(sync_ok)
    );
    s.push_str(
        "- **Formats** (every camera file read from a fixture): not part of this benchmark (the \
         telemetry tests cover it).\n",
    );
    s
}

/// The picks of `p` on `c` that fall in `range`.
fn inside(c: &ClipResult, p: Picker, range: &std::ops::Range<usize>) -> usize {
    c.picks(p).iter().filter(|k| range.contains(k)).count()
}

/// Where the gyro loses, computed.
pub fn losses(o: &Outcome) -> String {
    let mut s = String::new();
    let st = &o.stretches;
    for c in &o.clips {
        let g = c.score(Picker::Gyro).mean_px;
        let better: Vec<String> = Picker::ALL
            .iter()
            .filter(|&&p| p != Picker::Oracle && p != Picker::Gyro)
            .filter(|&&p| c.score(p).mean_px < g)
            .map(|&p| format!("{} ({:.2} px)", p.name(), c.score(p).mean_px))
            .collect();
        let (gd, hd, ld) = (
            inside(c, Picker::Gyro, &st.defocus),
            inside(c, Picker::Hybrid, &st.defocus),
            inside(c, Picker::Laplacian, &st.defocus),
        );
        // Budget calls inside the stabilised stretch: frames truly under the
        // budget that the gyro calls over it.
        let missed = st
            .ois
            .clone()
            .filter(|&k| {
                c.clip.truth[k] <= BUDGET_PX && c.measures.gyro[k].is_none_or(|b| b > BUDGET_PX)
            })
            .count();
        let sharp = st
            .ois
            .clone()
            .filter(|&k| c.clip.truth[k] <= BUDGET_PX)
            .count();
        let _ = writeln!(
            s,
            "- **{}**: {} beat the gyro's {g:.2} px. In the defocus stretch (frames {}-{}) the gyro \
             picked {gd} defocused frame(s), the hybrid {hd}, the Laplacian {ld}. In the \
             stabilised stretch (frames {}-{}) the gyro called {missed} of the {sharp} frames truly \
             under {BUDGET_PX} px blurred.",
            c.spec.name,
            if better.is_empty() {
                "no picker".to_string()
            } else {
                better.join(", ")
            },
            st.defocus.start,
            st.defocus.end.saturating_sub(1),
            st.ois.start,
            st.ois.end.saturating_sub(1),
        );
    }
    s
}

/// The whole page.
pub fn page(o: &Outcome, m: &Machine) -> String {
    let f = &o.config.format;
    let mut s = String::from(include_str!("page_head.md"));
    let _ = writeln!(
        s,
        "\n## The clips\n\nEvery clip: {}x{} px, {} fps, {} frames ({:.1} s), the running phone's \
         field of view (width / focal length {}), a rolling shutter read out top to bottom in \
         {:.0} ms, sensor noise at {:.0e} e-/s, encoded with H.264 (ffmpeg, CRF as `mmbm clip`). \
         Frames {}-{} are defocused (a disc of {:.1} px), frames {}-{} are optically stabilised \
         ({:.0} % of the rotation left). The gyro log: the true rate plus white noise of {} rad/s \
         per sample and axis, a constant bias drawn in +-{} rad/s per axis, on a clock offset by \
         20-50 ms (seeded per clip).\n",
        f.width,
        f.height,
        f.fps,
        f.frames,
        f.frames as f64 / f.fps,
        super::clips::WIDTH_OVER_FOCAL,
        1e3 * super::clips::READOUT_S,
        super::clips::LIGHT_E_PER_S,
        o.stretches.defocus.start,
        o.stretches.defocus.end.saturating_sub(1),
        o.stretches.defocus_px,
        o.stretches.ois.start,
        o.stretches.ois.end.saturating_sub(1),
        100.0 * super::clips::OIS_RESIDUAL,
        super::clips::GYRO_NOISE,
        super::clips::GYRO_BIAS,
    );
    s.push_str("| clip | what | exposure | gyro seed | true offset | true blur (mean, max) |\n|---|---|---|---|---|---|\n");
    for c in &o.clips {
        let t = &c.clip.truth;
        let _ = writeln!(
            s,
            "| {} | {} | {:.0} ms | {} | {:.2} ms | {:.2}, {:.2} px |",
            c.spec.name,
            c.spec.what,
            1e3 * c.spec.exposure_s,
            c.spec.seed,
            1e3 * c.clip.offset_s,
            mean(t.iter().copied()),
            t.iter().copied().fold(0.0, f64::max)
        );
    }
    let _ = writeln!(
        s,
        "\n## Results\n\nMeasured {} on {} (load average {}), `cargo run --release -p mmbm-lab \
         --example pickers`, {:.0} s in all. Windows of {} frames.\n",
        m.date, m.cpu, m.load, o.total_s, o.config.window
    );
    let _ = writeln!(
        s,
        "### Picks\n\nPer picker and clip: the mean true blur of the picks, the share of picks \
         over {BLURRED_PX} px of true blur, the largest time with no pick, (the number of \
         picks); the time per frame is the mean over the clips (the gyro: reading the gyro file, \
         the predicted blur, the choice and the image list; the image metrics: decoding and \
         scoring; the hybrid: both). The Laplacian's global threshold ({:.1}) is the one tuned \
         for the budget task below.\n\n{}",
        o.lap_threshold,
        picks_table(o)
    );
    let _ = writeln!(
        s,
        "### Sync\n\n`mmbm::sync::sync` on each clip's video and gyro log (search +-0.2 s around \
         0).\n\n{}",
        sync_table(o)
    );
    let _ = writeln!(
        s,
        "### Offset error\n\nThe gyro's windowed picks with the frames placed on the gyro's clock \
         with the true offset plus an error (mean true blur · share over {BLURRED_PX} px).\n\n{}",
        offset_table(o)
    );
    let _ = writeln!(
        s,
        "### Budget: every frame under {BUDGET_PX} px\n\nThe gyro calls a frame under the budget \
         when its predicted blur is (no tuning); the Laplacian calls it so when its variance is \
         at least the threshold that maximises F1 on {} ({:.1}), applied unchanged to the other \
         clips. Precision / recall / F1 against the truth.\n\n{}",
        o.clips[TUNED_ON.min(o.clips.len() - 1)].spec.name,
        o.lap_threshold,
        budget_table(o)
    );
    let _ = writeln!(s, "## Goals\n\n{}", goals(o));
    let _ = write!(s, "## Where the gyro loses\n\n{}", losses(o));
    s
}
