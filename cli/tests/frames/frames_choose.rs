//! `mmbm frames` choosing frames as photogrammetry and splatting users do
//! (issue 36): the best frame per window (`--per-window`, `--per-seconds`),
//! a count with even coverage (`--count`), a blur budget (`--max-blur`),
//! `--select` saying why it kept fewer, the clock check, the camera note,
//! and maps named and stored as a user can keep them (the video's side:
//! `cli/tests/frames/frames_video.rs`). The clip: `tests/frames_fixture`.

use crate::common;
use crate::frames_fixture;

use common::mmbm_in;
use frames_fixture::{argmin, blurs, clip, folder, listed, ok, run};

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
