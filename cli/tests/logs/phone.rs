//! Phone logs read directly: IMU rows with a sensor-type column (the gyro
//! rows give exactly the samples of the same log as a plain CSV), a
//! phone's image list and ffprobe's frame output (each the same frames as
//! the plain table), and bad rows in each (the error names the file and
//! the line of the row that was spoiled, never a panic).

use crate::common;

use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-phone-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// (time ns, wx, wy, wz) of a 2 s gyro log at 200 Hz starting at a phone's
/// boot-clock time.
fn gyro_rows() -> Vec<(u64, f64, f64, f64)> {
    (0..400)
        .map(|i| {
            let ns = 5_000_000_000 + i * 5_000_000;
            let t = i as f64 * 0.005;
            (ns, 0.5 * (3.0 * t).sin(), 0.8 * (2.0 * t).cos(), 0.1 * t)
        })
        .collect()
}

/// The same log twice: a plain `t,wx,wy,wz` CSV (t = ns x 1e-9) and IMU
/// rows with accelerometer rows between, types as names and as numbers.
fn write_logs(d: &Path) -> (PathBuf, PathBuf) {
    let mut plain = String::from("t,wx,wy,wz\n");
    let mut rows = String::from("timestamp_ns,type,x,y,z\n");
    for (k, (ns, x, y, z)) in gyro_rows().into_iter().enumerate() {
        plain += &format!("{},{x},{y},{z}\n", ns as f64 * 1e-9);
        let (g, a) = if k % 2 == 0 {
            ("gyro", "accel")
        } else {
            ("4", "1")
        };
        rows += &format!("{},{a},0.1,9.8,0.2\n", ns - 1000);
        rows += &format!("{ns},{g},{x},{y},{z}\n");
    }
    let (p, r) = (d.join("plain.csv"), d.join("imu.csv"));
    std::fs::write(&p, plain).unwrap();
    std::fs::write(&r, rows).unwrap();
    (p, r)
}

/// 50 frames at 30 fps from 5.1 s (boot clock), 2 ms exposure: (ns, exposure ns).
fn frame_times() -> Vec<(u64, u64)> {
    (0..50)
        .map(|k| (5_100_000_000 + k * 33_333_333, 2_000_000))
        .collect()
}

fn stdout_ok(d: &Path, args: &[&str]) -> String {
    String::from_utf8(common::mmbm_ok_in(d, args).stdout).unwrap()
}

fn column(text: &str, i: usize) -> Vec<String> {
    text.lines()
        .map(|l| l.split(',').nth(i).unwrap_or("").to_string())
        .collect()
}

#[test]
fn imu_rows_give_the_samples_of_the_plain_log() {
    let d = dir("imu");
    let (plain, rows) = write_logs(&d);
    let a = stdout_ok(&d, &["series", "--gyro", s(&plain)]);
    let b = stdout_ok(&d, &["series", "--gyro", s(&rows)]);
    assert_eq!(a.lines().count(), 401);
    // The values are the same to the bit; the times to rounding of ns x 1e-9.
    assert_eq!(column(&a, 1), column(&b, 1));
    assert_eq!(column(&a, 2), column(&b, 2));
    for (x, y) in column(&a, 0).iter().zip(column(&b, 0)).skip(1) {
        let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
        assert!((x - y).abs() < 1e-12, "{x} {y}");
    }
    // Only accelerometer (and other) rows: the error names what the file has.
    let accel = d.join("accel.csv");
    std::fs::write(
        &accel,
        "timestamp_ns,type,x,y,z\n1,accel,0,0,9.8\n2,1,0,0,9.8\n3,mag,1,2,3\n",
    )
    .unwrap();
    let o = common::mmbm_in(&d, &["series", "--gyro", s(&accel)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("accel.csv:5:type")
            && err.contains("'accel' (2 rows)")
            && err.contains("'mag' (1 rows)"),
        "{err}"
    );
    // A time unit other than the format's is refused.
    let o = common::mmbm_in(&d, &["series", "--gyro", s(&rows), "--time-unit", "ms"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("nanosecond"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn image_lists_and_ffprobe_tables_give_the_frames_of_the_plain_table() {
    let d = dir("frames");
    let (plain_log, rows) = write_logs(&d);
    let cam = crate::common::repo_root().join("examples/cameras/running_phone.toml");
    let mut table = String::from("t_start,exposure_s\n");
    let mut list = String::from("#timestamp [ns],exposure [ns]\n");
    let (mut ff_csv, mut ff_keys, mut ff_one) = (String::new(), String::new(), String::new());
    for (k, (ns, e)) in frame_times().into_iter().enumerate() {
        let t = ns as f64 * 1e-9;
        table += &format!("{t},{}\n", e as f64 * 1e-9);
        list += &format!("{ns},{e}\n");
        // ffprobe's presentation times on the video clock (0 at the first
        // frame); --time-offset moves the log onto it.
        let pts = k as f64 * 0.033333333;
        ff_csv += &format!(
            "frame,video,0,{},{},{pts:.6},{},{pts:.6},{},{pts:.6},N/A,N/A,1000,4567,1920,1080\n",
            (k == 0) as u8,
            k * 512,
            k * 512,
            k * 512
        );
        ff_csv += "frame,audio,1,1,0,0.000000,0,0.000000,0,0.000000\n";
        ff_keys += &format!(
            "frame|media_type=video|stream_index=0|pts_time={pts:.6}|best_effort_timestamp_time={pts:.6}\n"
        );
        ff_one += &format!("{pts:.6}\n");
    }
    let write = |n: &str, t: &str| {
        let p = d.join(n);
        std::fs::write(&p, t).unwrap();
        p
    };
    let (table, list) = (write("table.csv", &table), write("images.csv", &list));
    let run = |gyro: &Path, frames: &Path, extra: &[&str]| {
        let mut args = vec![
            "frames",
            "--gyro",
            s(gyro),
            "--frames",
            s(frames),
            "--camera",
            s(&cam),
        ];
        args.extend_from_slice(extra);
        stdout_ok(&d, &args)
    };
    let want = run(&plain_log, &table, &[]);
    assert_eq!(want.lines().count(), 51);
    assert!(want
        .lines()
        .nth(5)
        .unwrap()
        .split(',')
        .nth(3)
        .unwrap()
        .parse::<f64>()
        .is_ok());
    assert_eq!(run(&rows, &list, &[]), want, "image list and IMU rows");
    // ffprobe: frame k at pts k x 0.0333333 s; the log's clock is 5.1 s ahead.
    let mut ff_want = String::from("t_start,exposure_s\n");
    for k in 0..50 {
        ff_want += &format!("{:.6},0.002\n", k as f64 * 0.033333333);
    }
    let ff_table = write("ff_table.csv", &ff_want);
    let shift = ["--time-offset=-5.1"];
    let want = run(&plain_log, &ff_table, &shift);
    for (name, text) in [
        ("ff.csv", &ff_csv),
        ("ffk.txt", &ff_keys),
        ("ff1.csv", &ff_one),
    ] {
        let p = write(name, text);
        let got = run(
            &plain_log,
            &p,
            &[&shift[..], &["--exposure", "0.002"]].concat(),
        );
        assert_eq!(got, want, "{name}");
        let o = common::mmbm_in(&d, &["frames", "--gyro", s(&plain_log), "--frames", s(&p)]);
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("--exposure S"),
            "{name}"
        );
    }
    // A table with its own exposure refuses --exposure.
    let o = common::mmbm_in(
        &d,
        &[
            "frames",
            "--gyro",
            s(&plain_log),
            "--frames",
            s(&list),
            "--exposure",
            "0.002",
        ],
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("its own exposure"));
    let _ = std::fs::remove_dir_all(&d);
}

/// A small deterministic generator for the spoiled rows.
struct Lcg(u64);
impl Lcg {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as usize
    }
}

#[test]
fn bad_rows_name_the_file_and_line() {
    let d = dir("bad");
    let (_, rows) = write_logs(&d);
    let imu = std::fs::read_to_string(&rows).unwrap();
    let mut list = String::from("timestamp_ns,exposure_ns\n");
    let mut ff = String::new();
    for (k, (ns, e)) in frame_times().into_iter().enumerate() {
        list += &format!("{ns},{e}\n");
        ff += &format!(
            "frame,video,0,1,{k},{:.6},{k},{:.6},{k},{:.6}\n",
            k as f64 / 30.0,
            k as f64 / 30.0,
            k as f64 / 30.0
        );
    }
    let spoil = ["abc", "nan", "inf", "", "1e999", "--1", "0x10"];
    let mut rng = Lcg(7);
    let mut checked = 0;
    for (name, text, gyro) in [
        ("bad_imu.csv", &imu, true),
        ("bad_list.csv", &list, false),
        ("bad_ff.csv", &ff, false),
    ] {
        let lines: Vec<&str> = text.lines().collect();
        for _ in 0..12 {
            // A data row (ffprobe has no header), a gyro row for the IMU rows.
            let first = if name == "bad_ff.csv" { 0 } else { 1 };
            let mut k = first + rng.below(lines.len() - first);
            if gyro && k % 2 == 1 {
                k += 1;
            }
            let mut fields: Vec<String> = lines[k].split(',').map(String::from).collect();
            // ffprobe's rows fall back to pts_time without the 10th field.
            let ways = spoil.len() + usize::from(name != "bad_ff.csv");
            let how = rng.below(ways);
            let field = match name {
                "bad_imu.csv" => [0, 2, 3, 4][rng.below(4)],
                "bad_list.csv" => rng.below(2),
                _ => 9,
            };
            if how == spoil.len() {
                fields.truncate(field.max(1)); // too few fields
            } else {
                fields[field] = spoil[how].into();
            }
            let mut spoiled: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            spoiled[k] = fields.join(",");
            let p = d.join(name);
            std::fs::write(&p, spoiled.join("\n") + "\n").unwrap();
            let o = if gyro {
                common::mmbm_in(&d, &["series", "--gyro", s(&p)])
            } else {
                let mut args = vec!["frames", "--gyro", s(&rows), "--frames", s(&p)];
                if name == "bad_ff.csv" {
                    args.extend(["--exposure", "0.002"]);
                }
                common::mmbm_in(&d, &args)
            };
            let err = String::from_utf8_lossy(&o.stderr);
            let at = format!("{name}:{}:", k + 1);
            assert!(
                !o.status.success() && o.status.code() != Some(101) && err.contains(&at),
                "{name} line {} ({:?}): {err}",
                k + 1,
                spoiled[k]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 36);
    let _ = std::fs::remove_dir_all(&d);
}

/// The `mmbm` commands of `docs/frames.md`'s worked example (its numbered
/// sections 1-4, on the phone's files), continuation lines joined. The
/// sections after it ("Syncing the gyro to the video", "Gyro from the
/// camera's own files") show commands on placeholder files (a GoPro clip, a
/// Gyroflow project): `cli/tests/logs/sync.rs` and `cli/tests/logs/telemetry.rs` run those
/// commands on files they make.
fn doc_commands() -> Vec<Vec<String>> {
    let doc = std::fs::read_to_string(crate::common::repo_root().join("docs/frames.md")).unwrap();
    let end = doc
        .find("\n## Syncing the gyro to the video")
        .expect("docs/frames.md has its sync section after the worked example");
    let mut out = Vec::new();
    let (mut fenced, mut cur) = (false, String::new());
    for line in doc[..end].lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            continue;
        }
        cur.push_str(line.trim_end_matches('\\'));
        cur.push(' ');
        if !line.ends_with('\\') {
            if cur.trim_start().starts_with("mmbm ") {
                out.push(cur.split_whitespace().skip(1).map(String::from).collect());
            }
            cur.clear();
        }
    }
    out
}

#[test]
fn the_worked_example_runs() {
    let d = dir("doc");
    write_logs(&d);
    let mut list = String::from("timestamp_ns,exposure_ns\n");
    let mut probe = String::new();
    for (k, (ns, e)) in frame_times().into_iter().enumerate() {
        list += &format!("{ns},{e}\n");
        let pts = k as f64 * 0.033333333;
        probe += &format!("frame,video,0,1,{k},{pts:.6},{k},{pts:.6},{k},{pts:.6},N/A,N/A\n");
    }
    std::fs::write(d.join("images.csv"), list).unwrap();
    std::fs::write(d.join("probe.csv"), probe).unwrap();
    std::fs::copy(
        crate::common::repo_root().join("examples/cameras/running_phone.toml"),
        d.join("camera.toml"),
    )
    .unwrap();
    let commands = doc_commands();
    assert_eq!(commands.len(), 7, "{commands:?}");
    let help = String::from_utf8(common::mmbm(&["frames", "--help"]).stdout).unwrap();
    // The video of the 50 frames, for the lines that decode it (ffmpeg's test pattern).
    let video = std::process::Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=160x120:rate=30",
        ])
        .args(["-frames:v", "50", "-pix_fmt", "yuv420p", "video.mp4"])
        .current_dir(&d)
        .output()
        .is_ok_and(|o| o.status.success());
    let mut ran = 0;
    for args in &commands {
        if args.iter().any(|a| a == "--maps") && !help.contains("--maps") {
            common::skip(
                "`frames --maps` is not in this build (the maps work): its line is not run",
            );
            continue;
        }
        if args.iter().any(|a| a == "--video") && !video {
            common::skip("ffmpeg is not installed: the lines with --video are not run");
            continue;
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        common::mmbm_ok_in(&d, &args);
        ran += 1;
    }
    assert!(ran >= 4);
    for f in ["frames.csv", "frames_from_probe.csv", "sharp.csv"] {
        let text = std::fs::read_to_string(d.join(f)).unwrap();
        assert_eq!(
            text.lines().count(),
            if f == "sharp.csv" {
                1 + std::fs::read_to_string(d.join("sharp.txt"))
                    .unwrap()
                    .lines()
                    .count()
            } else {
                51
            },
            "{f}"
        );
    }
    for f in ["sharp.txt", "sharp.select", "blurry.txt", "blurry.select"] {
        assert!(
            !std::fs::read_to_string(d.join(f))
                .unwrap()
                .trim()
                .is_empty(),
            "{f}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}
