//! Gyroflow `.gcsv` logs: the fixture `tests/fixtures/gcsv/walk.gcsv` (written
//! by hand from Gyroflow's format description) reads as the samples computed
//! here from its raw columns, through the library and every command that
//! takes `--gyro`; malformed files are errors that name the file, the line
//! of the `.gcsv` file and the column or header key.

use crate::common;
use crate::gcsv_fixture;

use common::mmbm;
use gcsv_fixture::*;
use glam::{DMat3, DVec3};
use mmbm::io::gcsv::{
    camera_matrix, is_gcsv, orientation_matrix, read_header, ReadoutDirection, GYROFLOW_TO_CAMERA,
};
use mmbm::io::gyro::{read_log, AngleUnit, GyroOptions, GyroSample, TimeUnit};
use std::path::Path;

fn err(path: &Path) -> String {
    match read_log(path, GyroOptions::default()) {
        Ok(v) => panic!(
            "{}: expected an error, read {} samples",
            path.display(),
            v.len()
        ),
        Err(e) => e.to_string(),
    }
}

#[test]
fn walk_reads_as_the_scaled_and_oriented_raw_columns() {
    let samples = read_log(&walk(), GyroOptions::default()).unwrap();
    let raw = raw_rows(&walk_text());
    assert_eq!(raw.len(), 20);
    assert_eq!(samples.len(), raw.len());
    for (s, [t, gx, gy, gz]) in samples.iter().zip(&raw) {
        // orientation YxZ: Gyroflow's IMU axes are (gy, -gx, gz); mmbm's
        // camera frame (x right, y down, z forward) from Gyroflow's (x up,
        // y left, z back) is (-y, -x, -z): so (gx, -gy, -gz).
        let (gx, gy, gz) = (gx * GSCALE, gy * GSCALE, gz * GSCALE);
        let gyroflow = [gy, -gx, gz];
        let camera = DVec3::new(-gyroflow[1], -gyroflow[0], -gyroflow[2]);
        // Time from the first sample (t = 1000 raw units).
        assert_eq!(s.t, (t - 1000.0) * TSCALE);
        assert_eq!(s.omega, camera, "t = {t}");
        assert_eq!(s.omega, DVec3::new(gx, -gy, -gz));
        assert_eq!(s.velocity, None);
        assert_eq!(s.depth, None);
    }
    assert_eq!(samples[0].t, 0.0);
    assert_eq!(samples[19].t, 95.0 * TSCALE);
}

#[test]
fn orientation_xyz_is_gyroflows_identity_and_bad_orientations_are_errors() {
    assert_eq!(orientation_matrix("XYZ").unwrap(), DMat3::IDENTITY);
    assert_eq!(camera_matrix("XYZ").unwrap(), GYROFLOW_TO_CAMERA);
    let dir = tempfile::tempdir().unwrap();
    let text = with_line(&walk_text(), 4, "orientation,XYZ");
    let p = write(dir.path(), "xyz.gcsv", &text);
    let raw = raw_rows(&text);
    let samples = read_log(&p, GyroOptions::default()).unwrap();
    for (s, [_, gx, gy, gz]) in samples.iter().zip(&raw) {
        let g = DVec3::new(gx * GSCALE, gy * GSCALE, gz * GSCALE);
        assert_eq!(s.omega, DVec3::new(-g.y, -g.x, -g.z));
    }
    // --imu-rotation applies after the orientation: undoing Gyroflow's frame
    // gives the file's own axes back, exactly.
    let opts = GyroOptions {
        imu_to_camera: GYROFLOW_TO_CAMERA.transpose(),
        ..GyroOptions::default()
    };
    let own = read_log(&p, opts).unwrap();
    for (s, [_, gx, gy, gz]) in own.iter().zip(&raw) {
        assert_eq!(s.omega, DVec3::new(gx * GSCALE, gy * GSCALE, gz * GSCALE));
    }
    for bad in ["XXZ", "XY", "XYZW", "xyq", ""] {
        let p = write(
            dir.path(),
            "bad_orientation.gcsv",
            &with_line(&walk_text(), 4, &format!("orientation,{bad}")),
        );
        let e = err(&p);
        assert!(
            e.contains("bad_orientation.gcsv:4:orientation:") && e.contains("permutation"),
            "{bad}: {e}"
        );
        let e = read_header(&p).unwrap_err().to_string();
        assert!(e.contains(":4:orientation:"), "{e}");
        assert!(orientation_matrix(bad)
            .unwrap_err()
            .to_string()
            .contains("orientation"));
    }
    // No orientation line: Gyroflow's default for .gcsv, xzY.
    let p = write(
        dir.path(),
        "none.gcsv",
        &with_line(&walk_text(), 4, "note,no orientation"),
    );
    assert_eq!(read_header(&p).unwrap().orientation, "xzY");
    let s = read_log(&p, GyroOptions::default()).unwrap();
    let [_, gx, gy, gz] = raw_rows(&walk_text())[0];
    let g = DVec3::new(gx * GSCALE, gy * GSCALE, gz * GSCALE);
    assert_eq!(s[0].omega, camera_matrix("xzY").unwrap() * g);
    assert_eq!(s[0].omega, DVec3::new(g.z, g.x, -g.y));
}

#[test]
fn header_readout_in_seconds_and_direction() {
    let h = read_header(&walk()).unwrap();
    assert_eq!(h.readout_s, Some(15.23 / 1000.0));
    assert!((h.readout_s.unwrap() - 0.01523).abs() < 1e-17);
    assert_eq!(h.readout_direction, Some(ReadoutDirection::TopToBottom));
    assert_eq!(h.orientation, "YxZ");
    assert_eq!(h.tscale, TSCALE);
    assert_eq!(h.gscale, GSCALE);
    assert_eq!(h.fields.len(), 16);
    assert_eq!(h.fields[0], ("version".to_string(), "1.3".to_string()));
    assert_eq!(h.get("vendor"), Some("potatocam"));
    assert_eq!(
        h.get("lensprofile"),
        Some("potatocam/potatocam_mark1_prime_7_5mm_4k")
    );
    assert_eq!(h.camera_matrix().unwrap(), camera_matrix("YxZ").unwrap());

    let dir = tempfile::tempdir().unwrap();
    let text = walk_text();
    for (v, d) in [
        ("1", ReadoutDirection::BottomToTop),
        ("2", ReadoutDirection::LeftToRight),
        ("3", ReadoutDirection::RightToLeft),
    ] {
        let p = write(
            dir.path(),
            "dir.gcsv",
            &with_line(&text, 13, &format!("frame_readout_direction,{v}")),
        );
        assert_eq!(read_header(&p).unwrap().readout_direction, Some(d));
    }
    let p = write(
        dir.path(),
        "dir.gcsv",
        &with_line(&text, 13, "frame_readout_direction,7"),
    );
    let e = read_header(&p).unwrap_err().to_string();
    assert!(e.contains("dir.gcsv:13:frame_readout_direction:"), "{e}");
    let p = write(
        dir.path(),
        "rt.gcsv",
        &with_line(&text, 12, "frame_readout_time,fast"),
    );
    let e = read_header(&p).unwrap_err().to_string();
    assert!(e.contains("rt.gcsv:12:frame_readout_time:"), "{e}");
    // Both readout keys are optional.
    let no_readout = text.replace("frame_readout_time,15.23\nframe_readout_direction,0\n", "");
    let p = write(dir.path(), "plain.gcsv", &no_readout);
    let h = read_header(&p).unwrap();
    assert_eq!((h.readout_s, h.readout_direction), (None, None));
    assert_eq!(read_log(&p, GyroOptions::default()).unwrap().len(), 20);
    // A key that is read may not appear twice.
    let twice = text.replace("tscale,0.001\n", "tscale,0.001\ntscale,0.002\n");
    let e = err(&write(dir.path(), "twice.gcsv", &twice));
    assert!(
        e.contains("twice.gcsv:15:tscale:") && e.contains("twice"),
        "{e}"
    );
}

#[test]
fn malformed_rows_name_the_line_of_the_gcsv_file() {
    let dir = tempfile::tempdir().unwrap();
    let text = walk_text();
    let row = |n: usize| text.lines().nth(n - 1).unwrap().to_string();
    // Line 23 is the fifth sample.
    let mut f: Vec<String> = row(23).split(',').map(String::from).collect();
    f[2] = "abc".into();
    let bad = with_line(&text, 23, &f.join(","));
    let e = err(&write(dir.path(), "walk_bad.gcsv", &bad));
    assert!(
        e.contains("walk_bad.gcsv:23:gy:") && e.contains("'abc'"),
        "{e}"
    );
    let bad = with_line(&text, 30, "1055,1,2");
    let e = err(&write(dir.path(), "ragged.gcsv", &bad));
    assert!(
        e.contains("ragged.gcsv:30:field count (expected at least 4, found 3)"),
        "{e}"
    );
    let bad = with_line(&text, 30, &row(30).replacen(",", ",inf,", 1));
    let e = err(&write(dir.path(), "inf.gcsv", &bad));
    assert!(
        e.contains("inf.gcsv:30:gx:") && e.contains("not finite"),
        "{e}"
    );
    let bad = with_line(&text, 19, &row(19).replacen("40", "NaN", 1));
    let e = err(&write(dir.path(), "nan.gcsv", &bad));
    assert!(
        e.contains("nan.gcsv:19:gx:") && e.contains("not finite"),
        "{e}"
    );
    let bad = with_line(&text, 26, &row(26).replacen("1035", "1030", 1));
    let e = err(&write(dir.path(), "order.gcsv", &bad));
    assert!(
        e.contains("order.gcsv:26:t:") && e.contains("strictly increase") && e.contains("line 25"),
        "{e}"
    );
    // Blank and '#' lines among the samples keep the numbering.
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines.insert(21, String::new());
    lines.insert(22, "# a pause".into());
    lines[27] = lines[27].replacen(',', ",x,", 1);
    let e = err(&write(dir.path(), "gaps.gcsv", &(lines.join("\n") + "\n")));
    assert!(e.contains("gaps.gcsv:28:"), "{e}");
    lines[27] = lines[20].clone(); // an earlier time, after the blank and comment lines
    let e = err(&write(dir.path(), "back.gcsv", &(lines.join("\n") + "\n")));
    assert!(e.contains("back.gcsv:28:t:"), "{e}");
    // The valid file with blank and comment lines reads as the fixture.
    let p = write(dir.path(), "ok.gcsv", &{
        let mut l: Vec<String> = text.lines().map(String::from).collect();
        l.insert(21, String::new());
        l.insert(22, "# a pause".into());
        l.join("\r\n") + "\r\n"
    });
    assert_eq!(
        read_log(&p, GyroOptions::default()).unwrap(),
        read_log(&walk(), GyroOptions::default()).unwrap()
    );
    // Converted text: one CSV line per .gcsv line.
    let csv = mmbm::io::gcsv::to_csv(&walk()).unwrap();
    assert_eq!(csv.lines().count(), text.lines().count());
    assert_eq!(csv.lines().nth(17), Some("t,wx,wy,wz"));
    assert!(csv.lines().take(17).all(|l| l == "#"));
    // Header-only file.
    let head: String = text.lines().take(18).map(|l| format!("{l}\n")).collect();
    let e = err(&write(dir.path(), "empty.gcsv", &head));
    assert!(e.contains("empty.gcsv") && e.contains("no samples"), "{e}");
}

#[test]
fn absent_scales_are_telemetry_parsers_defaults_and_bad_ones_errors() {
    let dir = tempfile::tempdir().unwrap();
    let text = walk_text();
    let raw = raw_rows(&text);
    // No gscale: 1.0 (the raw gyro columns are rad/s).
    let p = write(
        dir.path(),
        "nog.gcsv",
        &text.replace("gscale,0.00122173047\n", ""),
    );
    assert_eq!(read_header(&p).unwrap().gscale, 1.0);
    let s = read_log(&p, GyroOptions::default()).unwrap();
    for (s, [t, gx, gy, gz]) in s.iter().zip(&raw) {
        assert_eq!(s.omega, DVec3::new(*gx, -gy, -gz));
        assert_eq!(s.t, (t - 1000.0) * TSCALE);
    }
    // No tscale: 0.001 (ms), the same times as the fixture's tscale,0.001.
    let p = write(dir.path(), "not.gcsv", &text.replace("tscale,0.001\n", ""));
    assert_eq!(read_header(&p).unwrap().tscale, 0.001);
    assert_eq!(
        read_log(&p, GyroOptions::default()).unwrap(),
        read_log(&walk(), GyroOptions::default()).unwrap()
    );
    let e = err(&write(
        dir.path(),
        "zero.gcsv",
        &text.replace("gscale,0.00122173047", "gscale,0"),
    ));
    assert!(e.contains("zero.gcsv:15:gscale:"), "{e}");
    // Columns by position: the names are not read.
    let p = write(
        dir.path(),
        "names.gcsv",
        &text.replace("t,gx,gy,gz,ax,ay,az,mx,my,mz", "time,x,y,z"),
    );
    assert_eq!(
        read_log(&p, GyroOptions::default()).unwrap(),
        read_log(&walk(), GyroOptions::default()).unwrap()
    );
    let e = err(&write(
        dir.path(),
        "short.gcsv",
        &text.replace("t,gx,gy,gz,ax,ay,az,mx,my,mz", "t,gx,gy"),
    ));
    assert!(
        e.contains("short.gcsv:18:") && e.contains("at least 4"),
        "{e}"
    );
    // A .gcsv name needs the magic line; the magic line needs no .gcsv name.
    let p = write(dir.path(), "plain.gcsv", "t,wx,wy,wz\n0,1,2,3\n");
    assert!(is_gcsv(&p));
    let e = err(&p);
    assert!(
        e.contains("plain.gcsv:1:") && e.contains("GYROFLOW IMU LOG"),
        "{e}"
    );
    let p = write(dir.path(), "walk.csv", &text);
    assert!(is_gcsv(&p));
    assert_eq!(
        read_log(&p, GyroOptions::default()).unwrap(),
        read_log(&walk(), GyroOptions::default()).unwrap()
    );
    let p = write(
        dir.path(),
        "camera.txt",
        &text.replacen("GYROFLOW IMU LOG", "CAMERA IMU LOG", 1),
    );
    assert!(is_gcsv(&p));
    assert_eq!(read_log(&p, GyroOptions::default()).unwrap().len(), 20);
    assert!(!is_gcsv(&write(dir.path(), "x.csv", "t,wx,wy,wz\n")));
    assert!(!is_gcsv(Path::new("/nonexistent/x.csv")));
    let e = err(Path::new("/nonexistent/x.gcsv"));
    assert!(e.contains("/nonexistent/x.gcsv"), "{e}");
    // The file carries its own scales.
    for opts in [
        GyroOptions {
            time_unit: TimeUnit::Ms,
            ..GyroOptions::default()
        },
        GyroOptions {
            angle_unit: AngleUnit::Deg,
            ..GyroOptions::default()
        },
    ] {
        let e = read_log(&walk(), opts).unwrap_err().to_string();
        assert!(e.contains("walk.gcsv") && e.contains("--time-unit"), "{e}");
    }
}

/// The fixture as a plain gyro CSV, computed here.
fn equivalent_csv(samples_from_raw: &[[f64; 4]]) -> String {
    let mut s = String::from("t,wx,wy,wz\n");
    let t0 = samples_from_raw[0][0];
    for [t, gx, gy, gz] in samples_from_raw {
        let w = [gx * GSCALE, -(gy * GSCALE), -(gz * GSCALE)];
        s += &format!("{},{},{},{}\n", (t - t0) * TSCALE, w[0], w[1], w[2]);
    }
    s
}

#[test]
fn every_gyro_command_takes_gcsv() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write(
        dir.path(),
        "walk.csv",
        &equivalent_csv(&raw_rows(&walk_text())),
    );
    let from_csv: Vec<GyroSample> = read_log(&csv, GyroOptions::default())
        .unwrap()
        .into_samples();
    assert_eq!(
        from_csv,
        read_log(&walk(), GyroOptions::default()).unwrap().samples()
    );
    let (g, c) = (walk(), csv);
    let (g, c) = (g.to_str().unwrap(), c.to_str().unwrap());
    let runs: [Vec<&str>; 3] = [
        vec!["series", "--out", "-"],
        vec![
            "trigger",
            "--policy",
            "fixed:20",
            "--policy",
            "threshold:0.4",
            "--exposure",
            "0.01",
        ],
        vec!["live", "--policy", "fixed:20", "--speed", "0", "--all"],
    ];
    for args in runs {
        let flag = if args[0] == "live" {
            "--replay"
        } else {
            "--gyro"
        };
        let a = mmbm(&[&args[..], &[flag, g]].concat());
        let b = mmbm(&[&args[..], &[flag, c]].concat());
        assert!(
            a.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&a.stderr)
        );
        assert!(
            b.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&b.stderr)
        );
        assert!(!a.stdout.is_empty());
        assert_eq!(a.stdout, b.stdout, "{args:?}");
    }
    let out = mmbm(&["series", "--gyro", g, "--out", "-"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().count(), 21, "{text}");
    // A bad row stops the command with the file's line number.
    let bad = write(
        dir.path(),
        "bad.gcsv",
        &with_line(&walk_text(), 21, "1010,75,-210"),
    );
    let o = mmbm(&["series", "--gyro", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("bad.gcsv:21:field count"), "{e}");
    let o = mmbm(&["series", "--gyro", g, "--angle-unit", "deg"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("tscale, gscale"));
}

/// `mmbm frames` takes the rolling-shutter readout from the `.gcsv` header
/// (15.23 ms) when neither the camera nor the frame table gives one.
#[test]
fn frames_use_the_gcsv_readout() {
    let dir = tempfile::tempdir().unwrap();
    let frames = write(
        dir.path(),
        "frames.csv",
        "t_start,exposure_s\n0.001,0.002\n0.050,0.002\n",
    );
    let out = common::mmbm_cmd()
        .args(["frames", "--gyro"])
        .arg(walk())
        .arg("--frames")
        .arg(&frames)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<&str> = stdout.lines().collect();
    assert_eq!(rows.len(), 3, "{stdout}");
    assert!(rows[1].ends_with(",0.002,0.01523"), "{}", rows[1]);
    assert!(rows[1].split(',').nth(2).unwrap().parse::<f64>().unwrap() > 0.0);
}

/// `mmbm live --replay` of a `.gcsv` log applies the header's readout (as
/// `trigger` and `frames` do) when the camera gives none, and not when it
/// gives its own.
#[test]
fn live_replay_uses_the_gcsv_readout() {
    let run = |extra: &[&str]| {
        let out = common::mmbm_cmd()
            .args(["live", "--replay"])
            .arg(walk())
            .args([
                "--speed",
                "0",
                "--policy",
                "fixed:100",
                "--exposure",
                "0.001",
            ])
            .args(extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{err}");
        err
    };
    let err = run(&[]);
    assert!(
        err.contains("rolling shutter from") && err.contains("readout 0.01523 s"),
        "{err}"
    );
    let own = run(&["--rolling-readout", "0.005"]);
    assert!(!own.contains("rolling shutter from"), "{own}");
}
