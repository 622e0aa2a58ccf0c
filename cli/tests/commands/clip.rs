//! `mmbm clip` (issue 36): a gyro log rendered as a video with the camera's
//! orientation carried from frame to frame. Analytic checks of each frame's
//! true blur (a roll about the optical axis, a pan), of the pose carried
//! (the image shift between consecutive decoded frames of a pan, and the
//! truth table's orientation column), frame 0 against `mmbm render` of the
//! same instant, the MP4's frame count and rate (ffprobe), and hostile
//! inputs (clear errors, nothing written). ffmpeg is required as
//! [`common::ffmpeg`] says (`MMBM_REQUIRE_FFMPEG=1` in CI).

use crate::common;

use common::{mmbm_in, mmbm_ok_in};
use std::path::Path;
use std::process::{Command, Stdio};

/// Prints a measurement past libtest's capture.
fn report(line: &str) {
    use std::io::Write;
    let _ = std::io::stderr().write_all(format!("MEASURED: {line}\n").as_bytes());
}

/// The thesis camera's focal length in px (4.2548 mm / 0.00465 mm), which
/// `--resolution` keeps.
const F_PX: f64 = 4.2548 / 0.00465;
/// The frames' size, px.
const W: usize = 128;
const H: usize = 96;
const RES: &str = "128x96";

/// A CSV log of one constant rotation `w` (rad/s, camera frame) at 400 Hz over `[0, secs]`.
fn steady_log(dir: &Path, w: [f64; 3], secs: f64) {
    let mut s = String::from("t,wx,wy,wz\n");
    let n = (secs * 400.0).round() as usize;
    for k in 0..=n {
        s += &format!("{:.6},{},{},{}\n", k as f64 / 400.0, w[0], w[1], w[2]);
    }
    std::fs::write(dir.join("gyro.csv"), s).unwrap();
}

/// A 512 x 512 PNG of smooth random grey blobs (no period, so that an image
/// shift has one answer), as `tex.png`.
fn texture(dir: &Path) {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f64 / (1u64 << 24) as f64
    };
    let g: Vec<f64> = (0..33 * 33).map(|_| rnd()).collect();
    let img = image::GrayImage::from_fn(512, 512, |x, y| {
        let (fx, fy) = (x as f64 / 16.0, y as f64 / 16.0);
        let (i, j) = (fx.floor() as usize, fy.floor() as usize);
        let (a, b) = (fx - i as f64, fy - j as f64);
        let v = |i: usize, j: usize| g[j.min(32) * 33 + i.min(32)];
        let s = v(i, j) * (1.0 - a) * (1.0 - b)
            + v(i + 1, j) * a * (1.0 - b)
            + v(i, j + 1) * (1.0 - a) * b
            + v(i + 1, j + 1) * a * b;
        image::Luma([(30.0 + 200.0 * s) as u8])
    });
    img.save(dir.join("tex.png")).unwrap();
}

fn clip_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "clip",
        "--gyro",
        "gyro.csv",
        "--resolution",
        RES,
        "--backend",
        "cpu",
    ];
    a.extend_from_slice(extra);
    a
}

/// The truth table's rows as numbers (header checked).
fn truth(p: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "frame,t_start_s,blur_mean_px,blur_p50_px,blur_max_px,valid,qw,qx,qy,qz"
    );
    lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect()
}

/// Every frame of `video` as grey bytes (ffmpeg).
fn grey_frames(video: &Path) -> Vec<Vec<u8>> {
    frames_as(video, "gray", 1)
}

/// Every frame of `video` (or an image) in ffmpeg's pixel format `pix` of
/// `bytes` per pixel.
fn frames_as(video: &Path, pix: &str, bytes: usize) -> Vec<Vec<u8>> {
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(video)
        .args(["-f", "rawvideo", "-pix_fmt", pix, "pipe:1"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o.stdout.chunks(W * H * bytes).map(<[u8]>::to_vec).collect()
}

/// ffprobe's decoded frame count, frame rate and codec of `video`.
fn probe(video: &Path) -> (usize, String, String) {
    let o = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-count_frames"])
        .args([
            "-show_entries",
            "stream=nb_read_frames,r_frame_rate,codec_name",
        ])
        .args(["-of", "default=nw=1"])
        .arg(video)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let get = |k: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{k}=")))
            .unwrap_or_else(|| panic!("{k} in {text}"))
            .to_string()
    };
    (
        get("nb_read_frames").parse().unwrap(),
        get("r_frame_rate"),
        get("codec_name"),
    )
}

/// A pan of 0.5 rad/s about the camera's y axis, exposure T = 10 ms: each
/// frame's mean true blur is the arc the image of a point at infinity
/// travels, f (1 + (x/f)^2) w T at column x; over these narrow frames
/// (|x| <= 64 px of f = 915 px) the mean of 1 + (x/f)^2 is 1.0016, so
/// w f T = 4.575 px within 1 %. The MP4 has the frames asked for, at the rate
/// asked for.
#[test]
fn pan_blur_is_omega_f_t_and_the_mp4_has_the_frames() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let w = 0.5;
    steady_log(d.path(), [0.0, w, 0.0], 2.0);
    let a = clip_args(&[
        "--fps",
        "30",
        "--exposure",
        "0.01",
        "--start",
        "0.1",
        "--duration",
        "0.3",
        "--target",
        "checker:0.05",
        "--distance",
        "3",
        "--out",
        "clip.mp4",
        "--truth",
        "truth.csv",
    ]);
    mmbm_ok_in(d.path(), &a);
    let rows = truth(&d.path().join("truth.csv"));
    assert_eq!(rows.len(), 9);
    let want = w * F_PX * 0.01;
    for r in &rows {
        let err = (r[2] - want).abs() / want;
        assert!(
            err < 0.01,
            "frame {}: mean blur {} px vs w f T = {want} px",
            r[0],
            r[2]
        );
        assert!(r[5] > 0.999, "valid share {}", r[5]);
    }
    let (n, rate, codec) = probe(&d.path().join("clip.mp4"));
    assert_eq!((n, rate.as_str()), (9, "30/1"));
    assert!(codec == "h264" || codec == "mpeg4", "{codec}");
}

/// A roll of 3 rad/s about the optical axis, T = 8 ms: a pixel at radius r
/// (px, from the principal point) moves along an arc of r w T, so the mean
/// blur is w T times the mean radius of the pixel centres (computed here
/// from the grid alone), within 1 %; the orientation column turns by w / fps
/// per frame about the optical axis.
#[test]
fn roll_blur_is_omega_t_times_the_mean_radius_and_the_pose_turns() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let w = 3.0;
    steady_log(d.path(), [0.0, 0.0, w], 1.0);
    let a = clip_args(&[
        "--fps",
        "25",
        "--exposure",
        "0.008",
        "--start",
        "0",
        "--duration",
        "0.2",
        "--target",
        "checker:0.05",
        "--distance",
        "2",
        "--out",
        "clip.mp4",
        "--truth",
        "truth.csv",
    ]);
    mmbm_ok_in(d.path(), &a);
    let rows = truth(&d.path().join("truth.csv"));
    assert_eq!(rows.len(), 5);
    let (cx, cy) = (W as f64 / 2.0, H as f64 / 2.0);
    let mut sum = 0.0;
    for j in 0..H {
        for i in 0..W {
            sum += (i as f64 + 0.5 - cx).hypot(j as f64 + 0.5 - cy);
        }
    }
    let want = w * 0.008 * sum / (W * H) as f64;
    for (k, r) in rows.iter().enumerate() {
        assert!(
            (r[2] - want).abs() / want < 0.01,
            "frame {k}: {} vs {want}",
            r[2]
        );
        // The orientation: a rotation by w k / fps about z.
        let angle = w * k as f64 / 25.0;
        let (qw, qz) = ((angle / 2.0).cos(), (angle / 2.0).sin());
        assert!(
            (r[6] - qw).abs() < 1e-9 && (r[9] - qz).abs() < 1e-9,
            "frame {k}: {r:?}"
        );
        assert!(r[7].abs() < 1e-12 && r[8].abs() < 1e-12);
        assert!((r[1] - k as f64 / 25.0).abs() < 1e-9);
    }
}

/// The sub-pixel shift `s` (px, along x) minimising the mean squared
/// difference of `a(x) = b(x + s)` over the frames' central rows.
fn shift_x(a: &[u8], b: &[u8]) -> f64 {
    let ssd = |s: i64| {
        let mut e = 0.0;
        let mut n = 0.0;
        for y in 16..H - 16 {
            for x in 40..W as i64 - 40 {
                let xb = x + s;
                if xb < 0 || xb >= W as i64 {
                    continue;
                }
                let d = a[y * W + x as usize] as f64 - b[y * W + xb as usize] as f64;
                e += d * d;
                n += 1.0;
            }
        }
        e / n
    };
    let (best, _) = (-38i64..=38)
        .map(|s| (s, ssd(s)))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .unwrap();
    let (l, c, r) = (ssd(best - 1), ssd(best), ssd(best + 1));
    best as f64 + 0.5 * (l - r) / (l - 2.0 * c + r)
}

/// The pose carried: a pan at w = 0.6 rad/s at 30 fps turns the camera by
/// w / fps = 20 mrad between frames, so the image of the (far, textured)
/// plane shifts by f tan(w / fps) = 18.30 px near the centre between
/// consecutive decoded frames (within 0.35 px: H.264 and the plane's
/// perspective); a clip restarting each frame facing the target would show
/// no shift.
#[test]
fn consecutive_frames_of_a_pan_shift_by_omega_f_over_fps() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let w = 0.6;
    steady_log(d.path(), [0.0, w, 0.0], 1.0);
    texture(d.path());
    let a = clip_args(&[
        "--fps",
        "30",
        "--exposure",
        "0.002",
        "--start",
        "0",
        "--duration",
        "0.1",
        "--target",
        "image:tex.png:6",
        "--distance",
        "20",
        "--out",
        "clip.mp4",
        "--truth",
        "truth.csv",
    ]);
    mmbm_ok_in(d.path(), &a);
    let frames = grey_frames(&d.path().join("clip.mp4"));
    assert_eq!(frames.len(), 3);
    let want = F_PX * (w / 30.0_f64).tan();
    for k in 0..2 {
        let s = shift_x(&frames[k], &frames[k + 1]);
        report(&format!(
            "frames {k}-{}: shift {s:.3} px (f tan(w/fps) = {want:.3} px)",
            k + 1
        ));
        assert!((s.abs() - want).abs() < 0.35, "shift {s} px vs {want} px");
    }
    let rows = truth(&d.path().join("truth.csv"));
    let q = |r: &Vec<f64>| glam::DQuat::from_xyzw(r[7], r[8], r[9], r[6]);
    let turned = q(&rows[0]).angle_between(q(&rows[2]));
    assert!((turned - 2.0 * w / 30.0).abs() < 1e-9, "{turned}");
}

/// Frame 0 of a clip is `mmbm render` of the same instant (the clip starts
/// facing the target): the same renderer, quality, seed and backend, so the
/// decoded frame and the rendered PNG (both made grey by ffmpeg) differ only
/// by the video's coding: mean absolute difference under 1.5 of 255.
#[test]
fn frame_zero_is_mmbm_render_of_the_same_instant() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    steady_log(d.path(), [0.3, -0.5, 0.8], 1.0);
    texture(d.path());
    let shared = [
        "--exposure",
        "0.02",
        "--target",
        "image:tex.png:1",
        "--distance",
        "2",
        "--resolution",
        RES,
        "--backend",
        "cpu",
        "--quality",
        "fast",
        "--gyro",
        "gyro.csv",
    ];
    let mut a = vec![
        "clip",
        "--fps",
        "30",
        "--start",
        "0.2",
        "--duration",
        "0.03",
    ];
    a.extend_from_slice(&shared);
    a.extend_from_slice(&["--out", "clip.mp4"]);
    mmbm_ok_in(d.path(), &a);
    let mut r = vec!["render", "--at", "0.2"];
    r.extend_from_slice(&shared);
    r.extend_from_slice(&["--out", "r.png"]);
    mmbm_ok_in(d.path(), &r);
    // The render coded as the clip was (same codec and settings): the
    // coding's own error then cancels out of the comparison.
    let codec = match probe(&d.path().join("clip.mp4")).2.as_str() {
        "h264" => ["libx264", "-preset", "veryfast", "-crf", "18"],
        _ => ["mpeg4", "-q:v", "2", "-sn", "-dn"],
    };
    // As the clip's encoder takes frames: raw RGB on the input (a PNG input
    // takes another colour-conversion path in ffmpeg).
    let png = frames_as(&d.path().join("r.png"), "rgb24", 3);
    std::fs::write(d.path().join("r.raw"), &png[0]).unwrap();
    let o = Command::new("ffmpeg")
        .args([
            "-v", "error", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", RES,
        ])
        .args(["-framerate", "30", "-i", "r.raw", "-an", "-c:v"])
        .args(codec)
        .args(["-pix_fmt", "yuv420p", "-f", "mp4", "r.mp4"])
        .current_dir(d.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let clip = frames_as(&d.path().join("clip.mp4"), "rgb24", 3);
    assert_eq!(clip.len(), 1);
    let png = frames_as(&d.path().join("r.mp4"), "rgb24", 3);
    let diff: f64 = clip[0]
        .iter()
        .zip(&png[0])
        .map(|(&a, &b)| (a as f64 - b as f64).abs())
        .sum::<f64>()
        / (3 * W * H) as f64;
    report(&format!(
        "frame 0 vs mmbm render: mean |diff| {diff:.3} of 255"
    ));
    assert!(diff < 0.05, "mean |clip - render| = {diff} of 255");
}

/// `--maps DIR`: one EXR per frame, named as `frames --maps` names them.
#[test]
fn maps_per_frame() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    steady_log(d.path(), [0.0, 0.5, 0.0], 1.0);
    let a = clip_args(&[
        "--fps",
        "30",
        "--exposure",
        "0.01",
        "--duration",
        "0.1",
        "--target",
        "checker:0.05",
        "--out",
        "clip.mp4",
        "--maps",
        "maps",
    ]);
    mmbm_ok_in(d.path(), &a);
    let mut names: Vec<String> = std::fs::read_dir(d.path().join("maps"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["frame_000001.exr", "frame_000002.exr", "frame_000003.exr"]
    );
    let (w, h, ch) = mmbm::io::images::read_exr(&d.path().join("maps/frame_000002.exr")).unwrap();
    assert_eq!((w, h), (W, H));
    let path = &ch.iter().find(|c| c.0 == "path_px").expect("path_px").1;
    let mean = path.iter().map(|&x| x as f64).sum::<f64>() / path.len() as f64;
    assert!((mean - 0.5 * F_PX * 0.01).abs() < 0.05, "{mean}");
}

/// The folder's entries (names), to see that nothing was left behind.
fn entries(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Bad values, a log shorter than the clip, a missing ffmpeg, an
/// unwritable folder: one clear error each, non-zero exit, nothing written.
#[test]
fn hostile_inputs_are_clear_errors_and_write_nothing() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    steady_log(d.path(), [0.0, 0.5, 0.0], 1.0);
    let before = entries(d.path());
    let base = [
        "--target",
        "checker:0.05",
        "--out",
        "clip.mp4",
        "--truth",
        "t.csv",
    ];
    let cases: &[(&[&str], &[&str])] = &[
        (&["--fps", "0", "--exposure", "0.01"], &["--fps", "0"]),
        (&["--fps", "NaN", "--exposure", "0.01"], &["--fps"]),
        (
            &["--fps", "5000", "--exposure", "0.0001"],
            &["--fps", "1000"],
        ),
        (&["--fps", "30", "--exposure", "0"], &["--exposure"]),
        (
            &["--fps", "30", "--exposure", "0.05"],
            &["--exposure", "frame period"],
        ),
        (
            &["--fps", "30", "--exposure", "0.01", "--duration", "0"],
            &["--duration"],
        ),
        (
            &["--fps", "30", "--exposure", "0.01", "--duration", "1e9"],
            &["--duration", "100000"],
        ),
        (
            &["--fps", "30", "--exposure", "0.01", "--duration", "5"],
            &["--gyro", "covers [0.000000, 1.000000]"],
        ),
        (
            &[
                "--fps",
                "30",
                "--exposure",
                "0.01",
                "--start",
                "-3",
                "--duration",
                "0.1",
            ],
            &["--gyro", "covers"],
        ),
        (
            &["--fps", "30", "--exposure", "0.01", "--target", "stripes:1"],
            &["target", "stripes"],
        ),
        (
            &[
                "--fps",
                "30",
                "--exposure",
                "0.01",
                "--target",
                "image:nope.png:1",
            ],
            &["nope.png"],
        ),
        (
            &["--fps", "30", "--exposure", "0.01", "--distance", "-1"],
            &["--distance"],
        ),
    ];
    for (extra, needles) in cases {
        let mut a = clip_args(extra);
        a.extend_from_slice(&base[2..]);
        if !extra.contains(&"--target") {
            a.extend_from_slice(&base[..2]);
        }
        let o = mmbm_in(d.path(), &a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{extra:?} succeeded");
        for n in *needles {
            assert!(err.contains(n), "{extra:?}: '{n}' not in: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(entries(d.path()), before, "{extra:?} left files");
    }
    // Odd sizes cannot be an MP4 (yuv420p).
    let mut a = clip_args(&["--fps", "30", "--exposure", "0.01"]);
    a.extend_from_slice(&base);
    let i = a.iter().position(|&x| x == RES).unwrap();
    a[i] = "127x96";
    let o = mmbm_in(d.path(), &a);
    assert!(String::from_utf8_lossy(&o.stderr).contains("127x96"));
    // ffmpeg missing: the install hint, before any frame is rendered.
    let mut a = clip_args(&["--fps", "30", "--exposure", "0.01", "--duration", "0.1"]);
    a.extend_from_slice(&base);
    let o = common::mmbm_cmd()
        .args(&a)
        .current_dir(d.path())
        .env("PATH", "")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("ffmpeg") && err.contains("apt install ffmpeg"),
        "{err}"
    );
    assert_eq!(entries(d.path()), before);
    // An output folder that does not exist, and one this user cannot write.
    let mut a = clip_args(&["--fps", "30", "--exposure", "0.01", "--duration", "0.1"]);
    a.extend_from_slice(&["--out", "no/such/clip.mp4"]);
    let o = mmbm_in(d.path(), &a);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no/such"));
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = d.path().join("ro");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        // root writes anywhere: nothing to check then.
        if std::fs::write(ro.join("probe"), b"").is_err() {
            let mut a = clip_args(&["--fps", "30", "--exposure", "0.01", "--duration", "0.1"]);
            a.extend_from_slice(&["--out", "ro/clip.mp4"]);
            let o = mmbm_in(d.path(), &a);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success() && err.contains("ro"), "{err}");
            assert!(entries(&ro).is_empty());
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    // The wrong extension.
    let mut a = clip_args(&["--fps", "30", "--exposure", "0.01"]);
    a.extend_from_slice(&["--out", "clip.avi"]);
    let o = mmbm_in(d.path(), &a);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--out"));
}

/// The built-in equirectangular panorama at infinity, turned through more
/// than a right angle (a pan of 2 rad/s for 0.9 s: 1.8 rad, where no plane
/// stays in view): every pixel sees it (valid share 1), each frame's mean
/// blur is w f T within 1 % as for a plane, the last frame's orientation
/// has turned by 1.8 rad, and the frames show texture (not a blank
/// background) all along.
#[test]
fn panorama_at_infinity_takes_any_rotation() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let w = 2.0;
    steady_log(d.path(), [0.0, w, 0.0], 1.2);
    let a = clip_args(&[
        "--fps",
        "10",
        "--exposure",
        "0.005",
        "--start",
        "0",
        "--duration",
        "1",
        "--target",
        "panorama",
        "--out",
        "clip.mp4",
        "--truth",
        "truth.csv",
    ]);
    mmbm_ok_in(d.path(), &a);
    let rows = truth(&d.path().join("truth.csv"));
    assert_eq!(rows.len(), 10);
    let want = w * F_PX * 0.005;
    for r in &rows {
        assert!(
            (r[2] - want).abs() / want < 0.01,
            "frame {}: {} vs {want}",
            r[0],
            r[2]
        );
        assert!(r[5] > 0.999, "{r:?}");
    }
    let q = |r: &Vec<f64>| glam::DQuat::from_xyzw(r[7], r[8], r[9], r[6]);
    assert!((q(&rows[0]).angle_between(q(&rows[9])) - 1.8).abs() < 1e-9);
    for (k, f) in grey_frames(&d.path().join("clip.mp4")).iter().enumerate() {
        let mean = f.iter().map(|&x| x as f64).sum::<f64>() / f.len() as f64;
        let var = f.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / f.len() as f64;
        assert!(var.sqrt() > 5.0, "frame {k}: std {} of 255", var.sqrt());
    }
}

/// The round trip: a clip rendered from a simulated walk's log, its video
/// clock starting at the log's t = 2 s (so video time = gyro time - 2:
/// `offset_s` = -2), goes through `mmbm sync`, which recovers the offset
/// within 2 ms.
#[test]
fn sync_recovers_the_offset_of_a_rendered_clip() {
    if !common::ffmpeg() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    common::simulated_walk(d.path());
    let cam = ["--resolution", "320x240"];
    let mut a = vec![
        "clip",
        "--gyro",
        "walk.csv",
        "--fps",
        "30",
        "--exposure",
        "0.01",
        "--start",
        "2",
        "--duration",
        "4",
        "--target",
        "poster",
        "--distance",
        "2",
        "--out",
        "clip.mp4",
        "--backend",
        "cpu",
    ];
    a.extend_from_slice(&cam);
    let t = std::time::Instant::now();
    mmbm_ok_in(d.path(), &a);
    let secs = t.elapsed().as_secs_f64();
    let mut s = vec![
        "sync",
        "--video",
        "clip.mp4",
        "--gyro",
        "walk.csv",
        "--exposure",
        "0.01",
        "--search",
        "3",
        "--out",
        "sync.toml",
    ];
    s.extend_from_slice(&cam);
    mmbm_ok_in(d.path(), &s);
    let t: toml::Table =
        toml::from_str(&std::fs::read_to_string(d.path().join("sync.toml")).unwrap()).unwrap();
    let off = t["offset_s"].as_float().unwrap();
    let conf = t["confidence"].as_float().unwrap();
    report(&format!(
        "sync on a 120-frame 320x240 clip of a simulated walk (rendered in {secs:.1} s): offset \
         error {:.3} ms, confidence {conf:.3}",
        (off + 2.0) * 1e3
    ));
    assert!((off + 2.0).abs() < 0.002, "offset {off} s: {t:?}");
}
