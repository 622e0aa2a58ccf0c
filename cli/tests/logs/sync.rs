//! `mmbm sync` against ground truth: clips made here, independently of
//! mmbm's renderer (a pinhole camera turning inside a textured panorama at
//! infinity, each frame the mean of sub-frames over its exposure, optionally
//! line by line for a rolling shutter, encoded by ffmpeg), with a gyro log
//! written from the true angular velocity plus noise, a bias and a known
//! offset. Also the refusals (no overlap, no ffmpeg, not a video, a short
//! log, no texture) and `frames --sync`.

use crate::common;

use common::{ffmpeg, mmbm_cmd, mmbm_in, mmbm_ok_in};
use glam::{DQuat, DVec3};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::Instant;

/// The offset of every clip's log: video time = gyro time + OFFSET.
const OFFSET: f64 = 0.137;
const W: usize = 320;
const H: usize = 240;
/// Focal length, px (horizontal field of view 56 degrees).
const F_PX: f64 = 300.0;
const FPS: f64 = 30.0;
const SECONDS: f64 = 5.0;
/// The camera file of the clips: 300 px focal length.
const CAMERA: &str = "focal_mm = 0.9\npitch_mm = 0.003\nwidth = 320\nheight = 240\n";

/// A small deterministic generator (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-300), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// A panorama at infinity: sums of plane waves over the direction, sampled
/// on a longitude-latitude grid (|lon| < 90, |lat| < 60 degrees).
struct Panorama {
    w: usize,
    h: usize,
    px: Vec<f32>,
}

const PANO_STEP: f64 = 0.0015; // rad per texel (0.45 px at 300 px/rad)

fn panorama() -> &'static Panorama {
    static P: OnceLock<Panorama> = OnceLock::new();
    P.get_or_init(|| {
        let mut rng = Rng(7);
        let waves: Vec<(DVec3, f64, f64)> = (0..12)
            .map(|_| {
                let d = DVec3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
                let k = 15.0 + 140.0 * rng.next();
                (
                    d * k,
                    std::f64::consts::TAU * rng.next(),
                    10.0 + 12.0 * rng.next(),
                )
            })
            .collect();
        let (w, h) = (
            (std::f64::consts::PI / PANO_STEP) as usize,
            (2.0 * std::f64::consts::FRAC_PI_3 / PANO_STEP) as usize,
        );
        let px = (0..h)
            .into_par_iter()
            .flat_map_iter(|j| {
                let waves = &waves;
                (0..w).map(move |i| {
                    let lon = -std::f64::consts::FRAC_PI_2 + (i as f64 + 0.5) * PANO_STEP;
                    let lat = -std::f64::consts::FRAC_PI_3 + (j as f64 + 0.5) * PANO_STEP;
                    let d = DVec3::new(lat.cos() * lon.sin(), lat.sin(), lat.cos() * lon.cos());
                    let v: f64 = waves
                        .iter()
                        .map(|(k, ph, a)| a * (k.dot(d) + ph).sin())
                        .sum();
                    (128.0 + v) as f32
                })
            })
            .collect();
        Panorama { w, h, px }
    })
}

impl Panorama {
    fn sample(&self, d: DVec3) -> f32 {
        let lon = d.x.atan2(d.z);
        let lat = d.y.clamp(-1.0, 1.0).asin();
        let x = (lon + std::f64::consts::FRAC_PI_2) / PANO_STEP - 0.5;
        let y = (lat + std::f64::consts::FRAC_PI_3) / PANO_STEP - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let at = |i: f64, j: f64| {
            let i = (i as isize).clamp(0, self.w as isize - 1) as usize;
            let j = (j as isize).clamp(0, self.h as isize - 1) as usize;
            self.px[j * self.w + i]
        };
        let a = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
        let b = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
        a * (1.0 - fy) + b * fy
    }
}

/// The true angular velocity, rad/s, camera frame (x right, y down, z
/// forward): hand shake and walking sway, up to about 40 deg/s per axis.
fn omega(t: f64, amp: f64) -> DVec3 {
    let s = |f: f64, p: f64| (std::f64::consts::TAU * f * t + p).sin();
    amp * DVec3::new(
        0.30 * s(1.3, 0.4) + 0.15 * s(3.7, 1.1) + 0.06 * s(6.1, 0.0),
        0.40 * s(0.9, 2.0) + 0.18 * s(2.9, 0.3) + 0.05 * s(7.3, 2.2),
        0.22 * s(1.7, 0.8) + 0.08 * s(4.3, 2.5),
    )
}

/// Camera-to-world orientations every `DT` s from `T0` (integrated from `omega`).
const DT: f64 = 2.5e-4;
const T0: f64 = -1.5;

fn orientations(amp: f64) -> Vec<DQuat> {
    let n = ((SECONDS + 3.0) / DT) as usize;
    let mut q = DQuat::IDENTITY;
    let mut v = Vec::with_capacity(n);
    for i in 0..n {
        v.push(q);
        let t = T0 + (i as f64 + 0.5) * DT;
        let w = omega(t, amp);
        // Body-frame rate: q' = q * (0, w) / 2.
        q = (q * DQuat::from_scaled_axis(w * DT)).normalize();
    }
    v
}

fn orientation_at(qs: &[DQuat], t: f64) -> DQuat {
    let f = (t - T0) / DT;
    let i = (f.floor() as usize).min(qs.len() - 2);
    qs[i].slerp(qs[i + 1], f - i as f64)
}

/// One clip to make.
#[derive(Clone, Copy)]
struct Clip {
    exposure: f64,
    readout: f64,
    amp: f64,
    textured: bool,
}

/// Writes the clip's frames as PNGs and encodes them; returns the video.
fn make_video(dir: &Path, c: Clip) -> PathBuf {
    let pano = panorama();
    let qs = orientations(c.amp);
    let frames = (SECONDS * FPS) as usize;
    let subs = ((c.exposure * 400.0).ceil() as usize).clamp(1, 8);
    let png_dir = dir.join("png");
    std::fs::create_dir_all(&png_dir).unwrap();
    (0..frames).into_par_iter().for_each(|k| {
        let t_k = k as f64 / FPS;
        let mut img = vec![0u8; W * H];
        for j in 0..H {
            let t_line = t_k + c.readout * (j as f64 + 0.5) / H as f64;
            let qs_line: Vec<DQuat> = (0..subs)
                .map(|s| orientation_at(&qs, t_line + c.exposure * (s as f64 + 0.5) / subs as f64))
                .collect();
            for i in 0..W {
                let v = if c.textured {
                    let ray = DVec3::new(
                        (i as f64 + 0.5 - W as f64 / 2.0) / F_PX,
                        (j as f64 + 0.5 - H as f64 / 2.0) / F_PX,
                        1.0,
                    )
                    .normalize();
                    qs_line.iter().map(|q| pano.sample(*q * ray)).sum::<f32>() / subs as f32
                } else {
                    120.0
                };
                img[j * W + i] = v.round().clamp(0.0, 255.0) as u8;
            }
        }
        image::GrayImage::from_raw(W as u32, H as u32, img)
            .unwrap()
            .save(png_dir.join(format!("f{k:04}.png")))
            .unwrap();
    });
    let encoders = Command::new("ffmpeg")
        .args(["-hide_banner", "-encoders"])
        .output()
        .unwrap();
    let list = String::from_utf8_lossy(&encoders.stdout);
    let (codec, out) = if list.contains("libx264") {
        (
            vec!["-c:v", "libx264", "-crf", "16", "-pix_fmt", "yuv420p"],
            "clip.mp4",
        )
    } else {
        (vec!["-c:v", "mpeg4", "-q:v", "2"], "clip.mp4")
    };
    let video = dir.join(out);
    let st = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-framerate", "30", "-i"])
        .arg(png_dir.join("f%04d.png"))
        .args(&codec)
        .arg(&video)
        .stdin(Stdio::null())
        .status()
        .unwrap();
    assert!(st.success(), "ffmpeg encoding");
    std::fs::remove_dir_all(&png_dir).unwrap();
    video
}

/// The gyro log of the clip's motion: 200 Hz, noise 0.004 rad/s, a bias,
/// stamped `gyro = video - OFFSET - extra` over `span` (video clock).
fn write_gyro(dir: &Path, amp: f64, extra: f64, span: (f64, f64)) -> PathBuf {
    let mut rng = Rng(11);
    let bias = DVec3::new(0.010, -0.008, 0.005);
    let mut s = String::from("t,wx,wy,wz\n");
    let mut t = span.0;
    while t <= span.1 {
        let w = omega(t, amp) + bias + 0.004 * DVec3::new(rng.normal(), rng.normal(), rng.normal());
        s += &format!(
            "{:.6},{:.7},{:.7},{:.7}\n",
            t - OFFSET - extra,
            w.x,
            w.y,
            w.z
        );
        t += 0.005;
    }
    let p = dir.join("gyro.csv");
    std::fs::write(&p, s).unwrap();
    p
}

fn setup(c: Clip) -> (tempfile::TempDir, f64) {
    let dir = tempfile::tempdir().unwrap();
    let t = Instant::now();
    make_video(dir.path(), c);
    write_gyro(dir.path(), c.amp, 0.0, (-1.0, SECONDS + 1.0));
    std::fs::write(dir.path().join("camera.toml"), CAMERA).unwrap();
    (dir, t.elapsed().as_secs_f64())
}

fn sync_args(exposure: f64) -> Vec<String> {
    [
        "sync",
        "--video",
        "clip.mp4",
        "--gyro",
        "gyro.csv",
        "--camera",
        "camera.toml",
        "--exposure",
        &exposure.to_string(),
        "--out",
        "sync.toml",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

fn read_toml(p: &Path) -> toml::Table {
    toml::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn num(t: &toml::Table, k: &str) -> f64 {
    t[k].as_float().unwrap_or_else(|| panic!("{k} in {t:?}"))
}

fn run_sync(dir: &Path, exposure: f64) -> (toml::Table, f64, String) {
    let args = sync_args(exposure);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    let t = Instant::now();
    let o = mmbm_ok_in(dir, &a);
    let secs = t.elapsed().as_secs_f64();
    (
        read_toml(&dir.join("sync.toml")),
        secs,
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

/// Prints a measurement past libtest's capture.
fn report(line: &str) {
    use std::io::Write;
    let _ = std::io::stderr().write_all(format!("MEASURED: {line}\n").as_bytes());
}

#[test]
fn offset_recovered_within_2ms_for_exposures_5_12_20_ms() {
    if !ffmpeg() {
        return;
    }
    for exposure in [0.005, 0.012, 0.020] {
        let (dir, made) = setup(Clip {
            exposure,
            readout: 0.0,
            amp: 1.0,
            textured: true,
        });
        let (t, secs, line) = run_sync(dir.path(), exposure);
        let err = num(&t, "offset_s") - OFFSET;
        let conf = num(&t, "confidence");
        let frames = t["frames"].as_integer().unwrap() as f64;
        report(&format!(
            "exposure {exposure} s: offset error {:.3} ms, confidence {conf:.3}, readout {} s, \
             sync {secs:.2} s for {frames} frames ({:.0} frames/s, {:.1}x real time), clip made \
             in {made:.1} s; {line}",
            err * 1e3,
            num(&t, "readout_s"),
            frames / secs,
            frames / FPS / secs
        ));
        assert!(
            err.abs() < 0.002,
            "exposure {exposure}: offset error {err} s: {t:?}"
        );
        assert!(conf > 0.7, "exposure {exposure}: confidence {conf}: {t:?}");
        let scale = num(&t, "focal_scale");
        assert!((scale - 1.0).abs() < 0.1, "focal scale {scale}");
    }
}

#[test]
fn rolling_shutter_clip_offset_and_readout() {
    if !ffmpeg() {
        return;
    }
    let (dir, _) = setup(Clip {
        exposure: 0.012,
        readout: 0.024,
        amp: 1.0,
        textured: true,
    });
    let (t, secs, _) = run_sync(dir.path(), 0.012);
    let err = num(&t, "offset_s") - OFFSET;
    let r = num(&t, "readout_s");
    report(&format!(
        "rolling shutter 24 ms: offset error {:.3} ms, readout {r} s (distinguishable {}), \
         confidence {:.3}, {secs:.2} s",
        err * 1e3,
        t["readout_distinguishable"],
        num(&t, "confidence")
    ));
    assert!(err.abs() < 0.002, "offset error {err} s: {t:?}");
    assert!((r - 0.024).abs() < 0.008, "readout {r}: {t:?}");
}

#[test]
fn no_motion_gives_low_confidence() {
    if !ffmpeg() {
        return;
    }
    let (dir, _) = setup(Clip {
        exposure: 0.012,
        readout: 0.0,
        amp: 0.0,
        textured: true,
    });
    let (t, _, _) = run_sync(dir.path(), 0.012);
    let conf = num(&t, "confidence");
    report(&format!("no motion: confidence {conf:.3}"));
    assert!(conf < 0.3, "confidence {conf}: {t:?}");
}

fn fails(dir: &Path, args: &[&str], needles: &[&str]) -> String {
    let o = mmbm_in(dir, args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
    }
    assert_eq!(
        err.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{err}"
    );
    assert!(!dir.join("sync.toml").exists(), "half-written output");
    err
}

#[test]
fn textureless_clip_is_refused() {
    if !ffmpeg() {
        return;
    }
    let (dir, _) = setup(Clip {
        exposure: 0.012,
        readout: 0.0,
        amp: 1.0,
        textured: false,
    });
    let args = sync_args(0.012);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    fails(dir.path(), &a, &["clip.mp4", "too little texture"]);
}

#[test]
fn no_overlap_is_refused_with_both_spans_and_an_offset() {
    if !ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A short still clip is enough: the refusal comes before decoding.
    let st = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=160x120:rate=30:duration=3",
        ])
        .args(["-c:v", "mpeg4", "clip.mp4"])
        .current_dir(d)
        .status()
        .unwrap();
    assert!(st.success());
    // The log lies 100 s after the video: gyro = video + 100 (before OFFSET).
    write_gyro(d, 1.0, -100.0, (-1.0, 4.0));
    std::fs::write(d.join("camera.toml"), CAMERA).unwrap();
    let args = sync_args(0.01);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    let err = fails(
        d,
        &a,
        &[
            "video spans 0.000 to 3.000 s",
            "gyro log 98.863",
            "--time-offset=-",
        ],
    );
    // The suggested offset aligns the middles: 1.5 - (98.863 + 103.863) / 2.
    let want = 1.5 - (98.863 + 103.863) / 2.0;
    assert!(err.contains(&format!("--time-offset={want:.3}")), "{err}");
    // With the suggestion the overlap is there: sync runs (and finds the offset).
    let mut a2 = a.clone();
    let off = format!("--time-offset={want:.3}");
    a2.push(&off);
    let o = mmbm_in(d, &a2);
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("no 10 frame pairs"),
        "{o:?}"
    );
}

#[test]
fn hostile_inputs_are_clear_errors() {
    if !ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("camera.toml"), CAMERA).unwrap();
    write_gyro(d, 1.0, 0.0, (-1.0, 4.0));
    // Not a video.
    std::fs::write(d.join("clip.mp4"), "t,wx,wy,wz\n0,0,0,0\n").unwrap();
    let args = sync_args(0.01);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    fails(d, &a, &["clip.mp4", "not a video ffprobe can read"]);
    // ffmpeg missing: PATH empty.
    let o = mmbm_cmd()
        .args(&a)
        .current_dir(d)
        .env("PATH", "")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("ffprobe") && err.contains("not found on PATH") && err.contains("install"),
        "{err}"
    );
    // A log too short (0.2 s) for a 3 s clip.
    std::fs::remove_file(d.join("clip.mp4")).unwrap();
    let st = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=160x120:rate=30:duration=3",
        ])
        .args(["-c:v", "mpeg4", "clip.mp4"])
        .current_dir(d)
        .status()
        .unwrap();
    assert!(st.success());
    write_gyro(d, 1.0, 0.0, (0.0, 0.2));
    fails(d, &a, &["gyro log", "spans only"]);
    // A missing video.
    std::fs::remove_file(d.join("clip.mp4")).unwrap();
    fails(d, &a, &["clip.mp4"]);
    // Bad flags.
    let mut bad = a.clone();
    bad.extend(["--search", "0"]);
    fails(d, &bad, &["--search"]);
    // The output may not replace an input.
    let mut same = sync_args(0.01);
    let n = same.len();
    same[n - 1] = "gyro.csv".into();
    let s: Vec<&str> = same.iter().map(String::as_str).collect();
    let o = mmbm_in(d, &s);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--gyro"));
}

/// `frames --sync` is `--time-offset` with the file's offset (and its readout).
#[test]
fn frames_reads_the_sync_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_gyro(d, 1.0, 0.0, (-1.0, 4.0));
    std::fs::write(d.join("camera.toml"), CAMERA).unwrap();
    let mut ft = String::from("t_start,exposure_s\n");
    for k in 0..60 {
        ft += &format!("{},0.01\n", k as f64 / 30.0);
    }
    std::fs::write(d.join("frames.csv"), ft).unwrap();
    std::fs::write(
        d.join("s.toml"),
        "offset_s = 0.137\nreadout_s = 0.02\nconfidence = 0.9\n",
    )
    .unwrap();
    let base = [
        "frames",
        "--gyro",
        "gyro.csv",
        "--frames",
        "frames.csv",
        "--camera",
        "camera.toml",
    ];
    let mut a = base.to_vec();
    a.extend(["--sync", "s.toml", "--out", "a.csv"]);
    mmbm_ok_in(d, &a);
    let mut b = base.to_vec();
    b.extend([
        "--time-offset",
        "0.137",
        "--rolling-readout",
        "0.02",
        "--out",
        "b.csv",
    ]);
    mmbm_ok_in(d, &b);
    let (ta, tb) = (
        std::fs::read_to_string(d.join("a.csv")).unwrap(),
        std::fs::read_to_string(d.join("b.csv")).unwrap(),
    );
    assert_eq!(ta, tb);
    assert!(ta.lines().nth(1).unwrap().ends_with(",0.02"), "{ta}");
    // Not both.
    let mut c = base.to_vec();
    c.extend(["--sync", "s.toml", "--time-offset", "0.1", "--out", "c.csv"]);
    let o = mmbm_in(d, &c);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--time-offset"));
    // A bad sync file names itself and the key.
    std::fs::write(
        d.join("bad.toml"),
        "offset_s = nan\nreadout_s = 0\nconfidence = 1\n",
    )
    .unwrap();
    let mut e = base.to_vec();
    e.extend(["--sync", "bad.toml", "--out", "e.csv"]);
    let o = mmbm_in(d, &e);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("bad.toml") && err.contains("offset_s"),
        "{err}"
    );
    assert!(!d.join("e.csv").exists());
}

/// A clip with a keyframe every 15 frames, as cameras write them, synced
/// from 3 windows of 24 consecutive frames spread over it (`--decode-frames
/// 72` of its 150): the offset within 2 ms, as from every frame.
#[test]
fn windows_of_frames_give_the_offset_within_2ms() {
    if !ffmpeg() {
        return;
    }
    let (dir, _) = setup(Clip {
        exposure: 0.012,
        readout: 0.0,
        amp: 1.0,
        textured: true,
    });
    let d = dir.path();
    let st = Command::new("ffmpeg")
        .args([
            "-v", "error", "-y", "-i", "clip.mp4", "-g", "15", "-q:v", "2",
        ])
        .args(["-crf", "16", "-pix_fmt", "yuv420p", "keys.mp4"])
        .current_dir(d)
        .stdin(Stdio::null())
        .status()
        .unwrap();
    assert!(st.success(), "ffmpeg re-encoding");
    std::fs::rename(d.join("keys.mp4"), d.join("clip.mp4")).unwrap();
    let mut args = sync_args(0.012);
    args.extend(["--decode-frames".to_string(), "72".to_string()]);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = mmbm_ok_in(d, &a);
    let line = String::from_utf8_lossy(&o.stdout).into_owned();
    let t = read_toml(&d.join("sync.toml"));
    let err = num(&t, "offset_s") - OFFSET;
    report(&format!(
        "3 windows of 24 frames: offset error {:.3} ms, confidence {:.3}; {line}",
        err * 1e3,
        num(&t, "confidence")
    ));
    assert!(line.contains("3 windows"), "{line}");
    assert_eq!(t["frames"].as_integer(), Some(72), "{t:?}");
    assert!(err.abs() < 0.002, "offset error {err} s: {t:?}");
    assert!(num(&t, "confidence") > 0.7, "{t:?}");
}
