//! `mmbm frames` with the video, through ffmpeg (issue 36): the documented
//! `select` line on current ffmpeg, `--extract` naming the images as the
//! image list does, the hybrid with an image metric, and a clear error
//! without ffmpeg. The clip: `tests/frames_fixture`.

use crate::common;
use crate::frames_fixture;

use common::skip;
use frames_fixture::{argmin, blurs, clip, folder, listed, ok, run, BASE};
use std::path::Path;
use std::process::{Command, Stdio};

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
