//! `mmbm frames` choosing frames as photogrammetry and splatting users do
//! (issue 36): the best frame per window (`--per-window`, `--per-seconds`),
//! a count with even coverage (`--count`), a blur budget (`--max-blur`),
//! `--select` saying why it kept fewer, the hybrid with an image metric of
//! the video, extraction through ffmpeg, the clock check, the camera note,
//! and maps named and stored as a user can keep them.
//!
//! The synthetic clip: a narrow camera (focal 100 mm, pitch 0.01 mm,
//! 64 x 48: half a field of view of 0.0032 rad) turning about its y axis at
//! a rate held constant over each frame's exposure (0.01 s, global shutter),
//! so every pixel moves f/pitch x w = 10^4 w px/s to a relative 1e-5, and a
//! frame's blur is 100 w px: the rate of frame k is b_k / 100 rad/s for a
//! blur of b_k px chosen by the test.

mod common;

use common::{mmbm_in, skip};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// A fresh folder for the running test.
fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-frames-choose-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes cam.toml, gyro.csv (1 kHz, from -0.1 s to past the last frame)
/// and frames.csv (frame k at `t0 + 0.1 k` s) for frame blurs `blur` px.
fn clip(d: &Path, blur: &[f64], t0: f64) {
    std::fs::write(
        d.join("cam.toml"),
        "focal_mm = 100\npitch_mm = 0.01\nwidth = 64\nheight = 48\nreadout_s = 0\n",
    )
    .unwrap();
    let n = blur.len();
    let mut g = String::from("t,wx,wy,wz\n");
    let samples = (n as f64 * 100.0) as usize + 200;
    for i in 0..=samples {
        let t = -0.1 + i as f64 * 0.001;
        let k = ((t / 0.1).round().max(0.0) as usize).min(n - 1);
        g += &format!("{t:.6},0,{},0\n", blur[k] / 100.0);
    }
    std::fs::write(d.join("gyro.csv"), g).unwrap();
    let mut f = String::from("t_start,exposure_s\n");
    for k in 0..n {
        f += &format!("{:.6},0.01\n", t0 + 0.1 * k as f64);
    }
    std::fs::write(d.join("frames.csv"), f).unwrap();
}

/// Blurs, px, of `n` frames: distinct, 1 to 10 px, no two within 0.05 px.
fn blurs(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 1.0 + ((k * 37 + 11) % 91) as f64 * 0.1)
        .collect()
}

const BASE: &[&str] = &[
    "frames",
    "--gyro",
    "gyro.csv",
    "--frames",
    "frames.csv",
    "--camera",
    "cam.toml",
];

fn run(d: &Path, extra: &[&str]) -> Output {
    let args: Vec<&str> = BASE.iter().chain(extra).copied().collect();
    mmbm_in(d, &args)
}

fn ok(d: &Path, extra: &[&str]) -> String {
    let o = run(d, extra);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{extra:?}: {err}");
    err
}

/// The rows of an image list of the default names (frame_%06d.png from 1).
fn listed(p: &Path) -> Vec<usize> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .map(|l| {
            let n: usize = l
                .strip_prefix("frame_")
                .and_then(|r| r.strip_suffix(".png"))
                .unwrap()
                .parse()
                .unwrap();
            n - 1
        })
        .collect()
}

/// The row of least blur in `r` (blurs are distinct).
fn argmin(b: &[f64], r: std::ops::Range<usize>) -> usize {
    r.min_by(|&x, &y| b[x].total_cmp(&b[y])).unwrap()
}

#[test]
fn per_window_and_per_seconds_pick_each_window_s_least_blur() {
    let d = folder("window");
    let b = blurs(60);
    clip(&d, &b, 0.0);
    let err = ok(
        &d,
        &[
            "--per-window",
            "10",
            "--image-list",
            "w.txt",
            "--out",
            "w.csv",
        ],
    );
    let want: Vec<usize> = (0..6).map(|i| argmin(&b, i * 10..i * 10 + 10)).collect();
    assert_eq!(listed(&d.join("w.txt")), want, "{err}");
    assert!(
        err.contains("chosen: 6 frames") && err.contains("largest hole"),
        "{err}"
    );
    // 0.1 s apart: windows of 0.5 s hold frames 0-4, 5-9, ... (0.5, 1.0, ... are exact in binary).
    ok(
        &d,
        &[
            "--per-seconds",
            "0.5",
            "--image-list",
            "s.txt",
            "--out",
            "s.csv",
        ],
    );
    let want: Vec<usize> = (0..12).map(|i| argmin(&b, i * 5..i * 5 + 5)).collect();
    assert_eq!(listed(&d.join("s.txt")), want);
    // The table holds the same rows.
    let rows: Vec<usize> = std::fs::read_to_string(d.join("s.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(rows, want);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn count_covers_evenly_with_a_bounded_hole() {
    let d = folder("count");
    let b = blurs(60);
    clip(&d, &b, 0.0);
    let err = ok(
        &d,
        &["--count", "7", "--image-list", "c.txt", "--out", "c.csv"],
    );
    let got = listed(&d.join("c.txt"));
    // Window i: rows floor(60 i / 7) up to floor(60 (i+1) / 7).
    let want: Vec<usize> = (0..7)
        .map(|i| argmin(&b, i * 60 / 7..(i + 1) * 60 / 7))
        .collect();
    assert_eq!(got, want, "{err}");
    // No two picks more than 2 ceil(60/7) - 1 = 17 frames apart.
    assert!(got.windows(2).all(|w| w[1] - w[0] <= 17), "{got:?}");
    assert!(
        err.contains("chosen: 7 frames") && err.contains("largest hole"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn budget_keeps_exactly_the_frames_under_it() {
    let d = folder("budget");
    let b = blurs(40);
    clip(&d, &b, 0.0);
    // Budgets halfway between the blurs (0.1 px apart; the model's is b (1 + 1e-5)).
    ok(
        &d,
        &[
            "--max-blur",
            "4.55",
            "--image-list",
            "b.txt",
            "--out",
            "b.csv",
        ],
    );
    let want: Vec<usize> = (0..40).filter(|&k| b[k] <= 4.55).collect();
    assert!(!want.is_empty() && want.len() < 40);
    assert_eq!(listed(&d.join("b.txt")), want);
    // A budget with windows: each window's pick within it, or none.
    let err = ok(
        &d,
        &[
            "--per-window",
            "5",
            "--max-blur",
            "2.05",
            "--image-list",
            "bw.txt",
            "--out",
            "bw.csv",
        ],
    );
    let want: Vec<usize> = (0..8)
        .map(|i| argmin(&b, i * 5..i * 5 + 5))
        .filter(|&k| b[k] <= 2.05)
        .collect();
    assert_eq!(listed(&d.join("bw.txt")), want);
    if want.len() < 8 {
        assert!(err.contains("without a frame"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn select_says_why_it_chose_fewer() {
    let d = folder("fewer");
    clip(&d, &blurs(40), 0.0);
    let err = ok(&d, &["--select", "30", "--gap", "0.25", "--out", "x.csv"]);
    assert!(err.contains("fewer than --select 30"), "{err}");
    assert!(
        err.contains("within --gap 0.25 s of a sharper pick"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn modes_refuse_bad_values_by_flag() {
    let d = folder("bad");
    clip(&d, &blurs(10), 0.0);
    for (args, want) in [
        (&["--count", "0"][..], "--count"),
        (&["--per-window", "0"], "--per-window"),
        (&["--per-seconds", "0"], "--per-seconds"),
        (&["--per-seconds", "NaN"], "--per-seconds"),
        (&["--count", "3", "--gap", "0.5"], "--gap"),
        (
            &[
                "--select",
                "3",
                "--image-metric",
                "laplacian",
                "--video",
                "frames.csv",
            ],
            "--image-metric",
        ),
        (&["--count", "3", "--per-window", "2"], "--per-window"),
        (&["--count", "3", "--extract", "x"], "--video"),
        (
            &[
                "--count",
                "3",
                "--image-metric",
                "sobel",
                "--video",
                "v.mp4",
            ],
            "--image-metric",
        ),
        (&["--maps-format", "half"], "--maps"),
    ] {
        let o = run(&d, &[args, &["--out", "o.csv"]].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{args:?}: {err}");
        assert!(!d.join("o.csv").exists(), "{args:?}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn no_frame_inside_the_log_is_refused_with_both_spans_and_an_offset() {
    let d = folder("clock");
    // The log runs -0.1 to 2.1 s; the frames 100 to 101.91 s.
    let b = blurs(20);
    clip(&d, &b, 0.0);
    let mut f = String::from("t_start,exposure_s\n");
    for k in 0..20 {
        f += &format!("{:.6},0.01\n", 100.0 + 0.1 * k as f64);
    }
    std::fs::write(d.join("frames.csv"), f).unwrap();
    let o = run(
        &d,
        &["--count", "5", "--image-list", "l.txt", "--out", "o.csv"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("no frame lies inside the gyro log"), "{err}");
    assert!(
        err.contains("100.000 to 101.910 s") && err.contains("-0.100 to"),
        "{err}"
    );
    // The video (1.91 s) fits in the log (2.2 s): align the starts, +100.1 s.
    assert!(err.contains("--time-offset=100.100"), "{err}");
    assert!(!d.join("l.txt").exists() && !d.join("o.csv").exists());
    // With that offset the same run works.
    ok(
        &d,
        &[
            "--count",
            "5",
            "--image-list",
            "l.txt",
            "--out",
            "o.csv",
            "--time-offset=100.1",
        ],
    );
    assert_eq!(listed(&d.join("l.txt")).len(), 5);
    // Some frames outside: a warning naming the spans.
    let err = ok(&d, &["--time-offset=99.5", "--out", "p.csv"]);
    assert!(
        err.contains("reach outside the gyro log") && err.contains("the frames span"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn without_a_camera_the_default_is_named() {
    let d = folder("camera");
    clip(&d, &blurs(5), 0.0);
    let o = mmbm_in(
        &d,
        &[
            "frames",
            "--gyro",
            "gyro.csv",
            "--frames",
            "frames.csv",
            "--out",
            "o.csv",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("no --camera") && err.contains("640x480") && err.contains("--camera FILE"),
        "{err}"
    );
    let err = ok(&d, &["--out", "o.csv"]);
    assert!(!err.contains("no --camera"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn maps_are_named_as_the_image_list_names_the_frames_half_and_chosen_channels() {
    let d = folder("maps");
    let b = blurs(12);
    clip(&d, &b, 0.0);
    let err = ok(
        &d,
        &[
            "--per-window",
            "4",
            "--image-list",
            "l.txt",
            "--frame-name",
            "img_%03d.jpg",
            "--frame-start",
            "0",
            "--maps",
            "m",
            "--backend",
            "cpu",
            "--out",
            "o.csv",
        ],
    );
    let list = std::fs::read_to_string(d.join("l.txt")).unwrap();
    let want: Vec<String> = list.lines().map(|l| l.replace(".jpg", ".exr")).collect();
    let mut names: Vec<String> = std::fs::read_dir(d.join("m"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, want, "{err}");
    // Rows 0-3: the pick's number is its row (start 0).
    assert_eq!(want[0], format!("img_{:03}.exr", argmin(&b, 0..4)));
    let first = d.join("m").join(&want[0]);
    let (w, h, ch) = mmbm::io::images::read_exr(&first).unwrap();
    assert_eq!((w, h, ch.len()), (64, 48, 5));
    // The path of a pixel is the blur, 100 w px = b px (to 1e-5), in half floats (3 digits).
    let path = &ch.iter().find(|c| c.0 == "path_px").unwrap().1;
    let want_b = b[argmin(&b, 0..4)];
    assert!(
        path.iter()
            .all(|&p| ((p as f64) - want_b).abs() < want_b * 2e-3),
        "{want_b}"
    );
    let half = std::fs::metadata(&first).unwrap().len();
    ok(
        &d,
        &[
            "--per-window",
            "4",
            "--frame-name",
            "img_%03d.jpg",
            "--frame-start",
            "0",
            "--maps",
            "f",
            "--maps-format",
            "float",
            "--maps-channels",
            "path_px,disp.u",
            "--backend",
            "cpu",
            "--out",
            "o2.csv",
        ],
    );
    let (_, _, ch) = mmbm::io::images::read_exr(&d.join("f").join(&want[0])).unwrap();
    let mut got: Vec<&str> = ch.iter().map(|c| c.0.as_str()).collect();
    got.sort();
    assert_eq!(got, ["disp.u", "path_px"]);
    assert!(half > 0);
    let o = run(
        &d,
        &[
            "--count",
            "2",
            "--maps",
            "g",
            "--maps-channels",
            "blur",
            "--out",
            "o3.csv",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--maps-channels") && err.contains("flow.v"),
        "{err}"
    );
    assert!(!d.join("g").exists() && !d.join("o3.csv").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// ffmpeg on PATH, or `None` (skipped).
fn ffmpeg() -> Option<()> {
    let ok = Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        skip("ffmpeg is not installed");
        return None;
    }
    Some(())
}

/// A 30-frame 128x96 video of ffmpeg's test pattern (lossless FFV1), with
/// frames `blurred` (a range of n) box-blurred hard.
fn video(d: &Path, blurred: &str) {
    let vf = format!("boxblur=8:4:enable='{blurred}'");
    let o = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=128x96:rate=10:duration=3",
        ])
        .args(["-vf", &vf, "-c:v", "ffv1", "v.mkv"])
        .current_dir(d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn the_documented_ffmpeg_line_and_extract_give_the_listed_frames() {
    if ffmpeg().is_none() {
        return;
    }
    let d = folder("extract");
    let b = blurs(30);
    clip(&d, &b, 0.0);
    video(&d, "0");
    let err = ok(
        &d,
        &[
            "--count",
            "4",
            "--image-list",
            "l.txt",
            "--ffmpeg-select",
            "s.select",
            "--video",
            "v.mkv",
            "--extract",
            "x",
            "--out",
            "o.csv",
        ],
    );
    assert!(err.contains("extracted: 4"), "{err}");
    let list: Vec<String> = std::fs::read_to_string(d.join("l.txt"))
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    let mut got: Vec<String> = std::fs::read_dir(d.join("x"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    got.sort();
    assert_eq!(got, list);
    // The line docs/frames.md and --help give, on the ffmpeg installed.
    std::fs::create_dir_all(d.join("sharp")).unwrap();
    let o = Command::new("bash")
        .args([
            "-c",
            r#"ffmpeg -v error -i v.mkv -vf "select=$(cat s.select)" -fps_mode passthrough sharp/out_%04d.png"#,
        ])
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (i, name) in list.iter().enumerate() {
        let a = image::open(d.join("sharp").join(format!("out_{:04}.png", i + 1)))
            .unwrap()
            .to_luma8();
        let x = image::open(d.join("x").join(name)).unwrap().to_luma8();
        assert_eq!(a, x, "{name}");
    }
    assert!(!d
        .join("sharp")
        .join(format!("out_{:04}.png", list.len() + 1))
        .exists());
    // A video with another frame count than the table is refused, nothing written.
    let f = std::fs::read_to_string(d.join("frames.csv")).unwrap();
    std::fs::write(d.join("frames.csv"), format!("{f}3.0,0.01\n")).unwrap();
    let o = run(
        &d,
        &[
            "--count",
            "4",
            "--video",
            "v.mkv",
            "--extract",
            "y",
            "--out",
            "o4.csv",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("30 frames") && err.contains("31 rows"),
        "{err}"
    );
    assert!(!d.join("y").exists() && !d.join("o4.csv").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_hybrid_overrides_a_defocused_gyro_pick() {
    if ffmpeg().is_none() {
        return;
    }
    let d = folder("hybrid");
    let b = blurs(30);
    clip(&d, &b, 0.0);
    // The gyro's pick of window 0 (rows 0-9) is defocused in the video.
    let g0 = argmin(&b, 0..10);
    video(&d, &format!("eq(n,{g0})"));
    for metric in ["laplacian", "tenengrad", "blur-effect"] {
        let l = format!("{metric}.txt");
        let err = ok(
            &d,
            &[
                "--per-window",
                "10",
                "--image-metric",
                metric,
                "--video",
                "v.mkv",
                "--image-list",
                &l,
                "--out",
                "o.csv",
            ],
        );
        let got = listed(&d.join(&l));
        let mut rest: Vec<usize> = (0..10).filter(|&k| k != g0).collect();
        rest.sort_by(|&x, &y| b[x].total_cmp(&b[y]));
        assert_eq!(got[0], rest[0], "{metric}: {err}");
        assert_eq!(
            got[1..],
            [argmin(&b, 10..20), argmin(&b, 20..30)],
            "{metric}: {err}"
        );
        assert!(
            err.contains("overridden by") && err.contains("in 1 "),
            "{metric}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn missing_ffmpeg_is_named_with_how_to_install_it() {
    let d = folder("noffmpeg");
    clip(&d, &blurs(10), 0.0);
    std::fs::write(d.join("v.mkv"), b"not a video").unwrap();
    let empty = d.join("empty-path");
    std::fs::create_dir_all(&empty).unwrap();
    let args: Vec<&str> = BASE
        .iter()
        .copied()
        .chain([
            "--count",
            "3",
            "--image-metric",
            "laplacian",
            "--video",
            "v.mkv",
            "--out",
            "o.csv",
        ])
        .collect();
    let o = common::mmbm_cmd()
        .args(&args)
        .current_dir(&d)
        .env("PATH", &empty)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("ffprobe") || err.contains("ffmpeg"), "{err}");
    assert!(
        err.contains("install ffmpeg") && err.contains("apt install ffmpeg"),
        "{err}"
    );
    assert!(!d.join("o.csv").exists());
    let _ = std::fs::remove_dir_all(&d);
}
