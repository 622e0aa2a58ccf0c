//! docs/frames.md's worked example ("Worked example: a GoPro clip and a
//! Gyroflow project"), run as written: the commands of each fenced block
//! after a `<!-- worked-example: NAME -->` marker are taken from the doc and
//! run by bash in a folder holding the files they name, with the `mmbm`
//! under test first on PATH. The files are made here from one known
//! rotation (issue 36):
//!
//! - `gopro/clip.mp4`: `mmbm clip` renders the rotation over the built-in
//!   poster at 2 m (320x240, 30 fps, 10 ms exposure, 3.5 s, with `--truth`), the
//!   same rotation is written as GPMF payloads (GoPro's axes, 200 Hz, one
//!   payload a second) on a clock [`GOPRO_OFFSET`] from the video's, and
//!   ffmpeg muxes both tracks into one MP4 (`-tag:d gpmd`), as a GoPro
//!   writes them;
//! - `gyroflow/clip.gyroflow` beside `gyroflow/clip.mp4` (the video alone):
//!   a Gyroflow project with the same rotation as embedded `raw_imu`
//!   (Gyroflow's axes, deg/s) on a clock [`PROJECT_OFFSET`] from the video's.
//!
//! Checked against the truth, never against mmbm's own output: the library
//! reads the combined file's GPMF as written and the video decodes
//! (ffprobe), sync's offset is within 2 ms of the known one, every name of
//! the image list is an extracted image, and each window's pick is the
//! frame the renderer's true blur says is sharpest there (within
//! [`PICK_TOLERANCE`]).

use crate::common;
use crate::telemetry_fixture as tf;

use glam::DVec3;
use mmbm::telemetry::{read_camera_file, Format, TelemetryOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;

const FPS: f64 = 30.0;
/// Exposure of every frame, s (the doc's `--exposure 0.01`).
const EXPOSURE: f64 = 0.01;
/// The log time of the clip's first frame, s.
const START: f64 = 0.5;
/// The clip's length, s (105 frames).
const SECONDS: f64 = 3.5;
/// The GoPro file's clock: video time = GPMF time + this, s.
const GOPRO_OFFSET: f64 = -0.047;
/// The project's clock: video time = raw_imu time + this, s.
const PROJECT_OFFSET: f64 = -0.083;
/// Gyro sample rate of both files, Hz.
const GYRO_HZ: usize = 200;
/// Seconds of gyro in both files (from their time 0).
const GYRO_SECONDS: usize = 4;
/// The doc's `--per-window`.
const WINDOW: usize = 10;
/// A pick's true blur may exceed its window's least by this share and 0.05 px
/// (the offset found is within 2 ms, not exact, and H.264 moves nothing here).
const PICK_TOLERANCE: f64 = 0.05;
/// The camera of the clip and of the doc's `camera.toml`: 600 px focal length.
const CAMERA: &str = "focal_mm = 2.79\npitch_mm = 0.00465\nwidth = 320\nheight = 240\n";

/// The true angular velocity, rad/s, camera frame (x right, y down, z
/// forward) at log time `t`: a hand's sway and shake, up to about 0.6 rad/s,
/// so that the blur changes within every 10 frames.
fn omega(t: f64) -> DVec3 {
    let s = |f: f64, p: f64| (std::f64::consts::TAU * f * t + p).sin();
    DVec3::new(
        0.22 * s(1.3, 0.4) + 0.12 * s(3.7, 1.1) + 0.05 * s(6.1, 0.0),
        0.30 * s(0.9, 2.0) + 0.14 * s(2.9, 0.3) + 0.04 * s(7.3, 2.2),
        0.15 * s(1.7, 0.8) + 0.06 * s(4.3, 2.5),
    )
}

/// What the doc's commands run on, made once.
struct Fixture {
    /// `clip.mp4` (video + GPMF) and `camera.toml`.
    gopro: PathBuf,
    /// `clip.mp4` (video), `clip.gyroflow` and `camera.toml`.
    gyroflow: PathBuf,
    /// Each frame's true mean blur, px (the clip's `--truth`).
    truth: Vec<f64>,
}

fn run_ok(cmd: &mut Command, what: &str) -> String {
    let o = cmd.stdin(Stdio::null()).output().unwrap();
    assert!(
        o.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The rates of a file whose clock is `offset` from the video's: sample
/// `i` at file time `i / GYRO_HZ` holds the rotation at video time
/// `i / GYRO_HZ + offset`, log time `START` later.
fn file_rates(offset: f64) -> Vec<(f64, DVec3)> {
    (0..GYRO_SECONDS * GYRO_HZ)
        .map(|i| {
            let t = i as f64 / GYRO_HZ as f64;
            (t, omega(START + t + offset))
        })
        .collect()
}

/// The Gyroflow project of the rotation (orientation `XYZ`: Gyroflow's
/// frame, x up, y left, z back, is (-y, -x, -z) of the camera's; deg/s).
fn project() -> String {
    let deg = 180.0 / std::f64::consts::PI;
    let raw: Vec<String> = file_rates(PROJECT_OFFSET)
        .iter()
        .map(|(t, w)| {
            format!(
                "{{\"timestamp_ms\": {:.3}, \"gyro\": [{:.6}, {:.6}, {:.6}]}}",
                t * 1e3,
                -w.y * deg,
                -w.x * deg,
                -w.z * deg
            )
        })
        .collect();
    format!(
        r#"{{
  "title": "Gyroflow data file",
  "version": 3,
  "videofile": "clip.mp4",
  "video_info": {{"width": 320, "height": 240, "fps": 30.0, "duration_ms": 3500.0}},
  "stabilization": {{"frame_readout_time": 0.0}},
  "gyro_source": {{"filepath": "clip.mp4", "imu_orientation": "XYZ", "rotation": null, "raw_imu": [{}]}},
  "offsets": {{}}
}}
"#,
        raw.join(", ")
    )
}

fn fixture() -> Option<&'static Fixture> {
    static F: OnceLock<Option<Fixture>> = OnceLock::new();
    F.get_or_init(|| {
        if !common::ffmpeg() {
            return None;
        }
        // Under cargo's per-target scratch folder, replaced on every run (nothing left in the
        // system's temp folder).
        let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mmbm-worked-example");
        let _ = std::fs::remove_dir_all(&root);
        let (gopro, gyroflow) = (root.join("gopro"), root.join("gyroflow"));
        for d in [&root, &gopro, &gyroflow] {
            std::fs::create_dir_all(d).unwrap();
        }
        // The log the clip renders: 400 Hz over the clip and a margin.
        let mut log = String::from("t,wx,wy,wz\n");
        for k in 0..=2000 {
            let t = k as f64 / 400.0;
            let w = omega(t);
            log += &format!("{t:.6},{:.9},{:.9},{:.9}\n", w.x, w.y, w.z);
        }
        std::fs::write(root.join("gyro.csv"), log).unwrap();
        std::fs::write(root.join("camera.toml"), CAMERA).unwrap();
        let (fps, exp, start, secs) = (
            FPS.to_string(),
            EXPOSURE.to_string(),
            START.to_string(),
            SECONDS.to_string(),
        );
        common::mmbm_ok_in(
            &root,
            &[
                "clip",
                "--gyro",
                "gyro.csv",
                "--camera",
                "camera.toml",
                "--fps",
                &fps,
                "--exposure",
                &exp,
                "--start",
                &start,
                "--duration",
                &secs,
                "--target",
                "poster",
                "--distance",
                "2",
                "--backend",
                "cpu",
                "--out",
                "video.mp4",
                "--truth",
                "truth.csv",
            ],
        );
        // GPMF of the same rotation, one payload a second, then both tracks in one MP4.
        let rates = file_rates(GOPRO_OFFSET);
        let payloads: Vec<Vec<u8>> = rates
            .chunks(GYRO_HZ)
            .enumerate()
            .map(|(k, c)| {
                let w: Vec<DVec3> = c.iter().map(|p| p.1).collect();
                tf::payload_of(k, &w, 1000)
            })
            .collect();
        std::fs::write(root.join("gpmf.mp4"), tf::gpmf_mp4(&payloads)).unwrap();
        run_ok(
            Command::new("ffmpeg")
                .args(["-v", "error", "-y", "-i", "video.mp4", "-i", "gpmf.mp4"])
                .args(["-map", "0:v", "-map", "1:d", "-c", "copy", "-tag:d", "gpmd"])
                .arg(gopro.join("clip.mp4"))
                .current_dir(&root),
            "ffmpeg muxing the video and the GPMF",
        );
        std::fs::copy(root.join("video.mp4"), gyroflow.join("clip.mp4")).unwrap();
        std::fs::write(gyroflow.join("clip.gyroflow"), project()).unwrap();
        for d in [&gopro, &gyroflow] {
            std::fs::write(d.join("camera.toml"), CAMERA).unwrap();
        }
        let text = std::fs::read_to_string(root.join("truth.csv")).unwrap();
        let truth = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).unwrap().parse::<f64>().unwrap())
            .collect();
        Some(Fixture {
            gopro,
            gyroflow,
            truth,
        })
    })
    .as_ref()
}

/// The commands of the fenced block after `<!-- worked-example: NAME -->` in
/// docs/frames.md, continuation lines joined.
fn doc_commands(name: &str) -> Vec<String> {
    let doc = std::fs::read_to_string(common::repo_root().join("docs/frames.md")).unwrap();
    let marker = format!("<!-- worked-example: {name} -->");
    let at = doc
        .find(&marker)
        .unwrap_or_else(|| panic!("docs/frames.md has no {marker}"));
    let rest = &doc[at + marker.len()..];
    let open = rest
        .find("```sh\n")
        .expect("a ```sh block after the marker")
        + 6;
    let body = &rest[open..open + rest[open..].find("```").expect("the block's end")];
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    for line in body.lines() {
        let l = line.trim();
        if let Some(head) = l.strip_suffix('\\') {
            cur += head;
            continue;
        }
        cur += l;
        if !cur.trim().is_empty() && !cur.trim_start().starts_with('#') {
            out.push(cur.trim().to_string());
        }
        cur.clear();
    }
    out
}

/// Runs the doc's commands `name` in a copy of `src`; returns the folder.
fn run_doc(name: &str, src: &Path) -> PathBuf {
    let cmds = doc_commands(name);
    assert!(
        cmds.iter().any(|c| c.starts_with("mmbm sync"))
            && cmds.iter().any(|c| c.starts_with("mmbm frames")),
        "{cmds:?}"
    );
    let d = src.with_file_name(format!("{name}-run"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    for e in std::fs::read_dir(src).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), d.join(e.file_name())).unwrap();
    }
    let bin_dir = common::bin().parent().unwrap().to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for c in &cmds {
        run_ok(
            Command::new("bash")
                .args(["-c", &format!("set -eo pipefail; {c}")])
                .env("PATH", &path)
                .current_dir(&d),
            &format!("docs/frames.md ({name}): {c}"),
        );
    }
    d
}

/// Checks the run of the doc's commands in `d` against the truth.
fn check_run(d: &Path, truth: &[f64], offset: f64) {
    let t: toml::Table =
        toml::from_str(&std::fs::read_to_string(d.join("sync.toml")).unwrap()).expect("sync.toml");
    let off = t["offset_s"].as_float().unwrap();
    assert!(
        (off - offset).abs() < 0.002,
        "offset {off} s against the known {offset} s: {t:?}"
    );
    let list: Vec<String> = std::fs::read_to_string(d.join("sharp.txt"))
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    let windows = truth.len().div_ceil(WINDOW);
    assert_eq!(list.len(), windows, "one pick per window: {list:?}");
    let mut extracted: Vec<String> = std::fs::read_dir(d.join("sharp"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    extracted.sort();
    assert_eq!(extracted, list, "the extracted images are the listed ones");
    for (w, name) in list.iter().enumerate() {
        let img = image::open(d.join("sharp").join(name)).unwrap();
        assert_eq!((img.width(), img.height()), (320, 240), "{name}");
        // frame_%06d.png numbered from 1: frame n is the table's row n - 1.
        let n: usize = name
            .strip_prefix("frame_")
            .and_then(|s| s.strip_suffix(".png"))
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("{name}"));
        let k = n - 1;
        let win = &truth[w * WINDOW..((w + 1) * WINDOW).min(truth.len())];
        assert_eq!(k / WINDOW, w, "{name} is not in window {w}");
        let best = win.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            truth[k] <= best * (1.0 + PICK_TOLERANCE) + 0.05,
            "window {w}: picked frame {k} of true blur {:.3} px, the sharpest has {best:.3} px ({win:?})",
            truth[k]
        );
    }
}

/// The combined file's GPMF is the rotation written (GoPro's axes back in
/// the camera frame, 1 mrad/s steps), at the file times written, and its
/// video decodes to the clip's frames.
#[test]
fn the_gopro_fixture_holds_the_video_and_the_gpmf() {
    let Some(f) = fixture() else { return };
    let p = f.gopro.join("clip.mp4");
    let (log, info) = read_camera_file(&p, &TelemetryOptions::default()).unwrap();
    assert_eq!(info.format, Format::GoProMp4);
    assert!((info.fps.unwrap() - FPS).abs() < 1e-6, "{:?}", info.fps);
    let want = file_rates(GOPRO_OFFSET);
    assert_eq!(log.samples().len(), want.len());
    for (s, (t, w)) in log.samples().iter().zip(&want) {
        assert!((s.t - t).abs() < 1e-9, "t {} vs {t}", s.t);
        assert!(
            (s.omega - *w).abs().max_element() <= 5.1e-4,
            "{t}: {} vs {w}",
            s.omega
        );
    }
    let (log, info) = read_camera_file(
        &f.gyroflow.join("clip.gyroflow"),
        &TelemetryOptions::default(),
    )
    .unwrap();
    assert_eq!(info.format, Format::GyroflowProject);
    let want = file_rates(PROJECT_OFFSET);
    assert_eq!(log.samples().len(), want.len());
    for (s, (t, w)) in log.samples().iter().zip(&want) {
        assert!((s.t - t).abs() < 1e-9, "t {} vs {t}", s.t);
        assert!(
            (s.omega - *w).abs().max_element() < 1e-7,
            "{t}: {} vs {w}",
            s.omega
        );
    }
    let o = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-count_frames"])
        .args(["-show_entries", "stream=nb_read_frames", "-of", "csv=p=0"])
        .arg(&p)
        .output()
        .unwrap();
    let n: usize = String::from_utf8_lossy(&o.stdout).trim().parse().unwrap();
    assert_eq!(n, f.truth.len());
    assert_eq!(n, (SECONDS * FPS).round() as usize);
}

#[test]
fn the_worked_example_on_a_gopro_clip() {
    let Some(f) = fixture() else { return };
    let d = run_doc("gopro", &f.gopro);
    check_run(&d, &f.truth, GOPRO_OFFSET);
}

#[test]
fn the_worked_example_on_a_gyroflow_project() {
    let Some(f) = fixture() else { return };
    let d = run_doc("gyroflow", &f.gyroflow);
    check_run(&d, &f.truth, PROJECT_OFFSET);
}
