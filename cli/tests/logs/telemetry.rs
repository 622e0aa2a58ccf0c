//! The gyro from a camera's own files (`mmbm::telemetry`): one fixture per
//! format, built here byte by byte from known angular velocities (so the
//! test knows the truth), read back exactly (after SCAL, the axis order and
//! the orientation); the same log through `mmbm series` gives the same
//! output as the plain CSV of the truth; hostile files are refused with the
//! file, the place and the reason, never a panic.
//!
//! The fixtures in `tests/fixtures/telemetry/` are what the builders below
//! write (checked byte for byte; `MMBM_WRITE_FIXTURES=1` rewrites them).

use crate::common;
use crate::telemetry_fixture;

use glam::DVec3;
use mmbm::telemetry::{read_camera_file, Format, Orientation};
use telemetry_fixture::*;

#[test]
fn fixtures_are_what_the_builders_make() {
    for (name, bytes) in fixtures() {
        let p = fixture(name);
        if std::env::var("MMBM_WRITE_FIXTURES").is_ok_and(|v| v == "1") {
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, &bytes).unwrap();
        }
        let have = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(
            have == bytes,
            "{name}: the fixture differs from its builder (MMBM_WRITE_FIXTURES=1 rewrites it)"
        );
    }
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

#[test]
fn gopro_mp4_gives_the_known_rates_and_frame_rate() {
    let (log, info) = read_camera_file(&fixture("gopro_hero.mp4"), &opts()).unwrap();
    assert_eq!(info.format, Format::GoProMp4);
    assert_eq!(info.device.as_deref(), Some("Camera"));
    assert_eq!(info.orientation, Some(Orientation::ActionCam));
    assert!(
        (info.fps.unwrap() - 30.0).abs() < 1e-9,
        "fps {:?}",
        info.fps
    );
    let want = gopro_truth();
    assert_eq!(log.samples().len(), want.len());
    for (s, (t, w)) in log.samples().iter().zip(&want) {
        assert!((s.t - t).abs() < 1e-12, "t {} vs {t}", s.t);
        assert!(close(s.omega, *w, 1e-12), "at {t}: {} vs {w}", s.omega);
    }
}

#[test]
fn gopro_mp4_takes_offset_and_imu_rotation_after_the_preset() {
    let mut o = opts();
    o.gyro.time_offset = 0.5;
    o.gyro.imu_to_camera = glam::DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let log = mmbm::telemetry::read_gyro(&fixture("gopro_hero.mp4"), &o).unwrap();
    let (t, w) = gopro_truth()[7];
    let s = log.samples()[7];
    assert!((s.t - (t + 0.5)).abs() < 1e-12);
    // Rz(90): (x, y, z) -> (-y, x, z).
    assert!(close(s.omega, DVec3::new(-w.y, w.x, w.z), 1e-12));
}

#[test]
fn gyroflow_project_gives_samples_offset_readout_fps_and_lens() {
    let (log, info) = read_camera_file(&fixture("project.gyroflow"), &opts()).unwrap();
    assert_eq!(info.format, Format::GyroflowProject);
    assert_eq!(info.readout_s, Some(0.0165));
    assert_eq!(info.fps, Some(29.97));
    assert_eq!(info.offsets, vec![(0.0, 0.02)]);
    assert!(info.lens_profile.is_some());
    assert_eq!(log.readout().map(|r| r.readout_s), Some(0.0165));
    let k = std::f64::consts::PI / 180.0;
    assert_eq!(log.samples().len(), 400);
    for (i, s) in log.samples().iter().enumerate() {
        let g = project_raw(i);
        // Orientation XYZ in Gyroflow's frame (x up, y left, z back) is
        // (-gy, -gx, -gz) in the camera frame; the offset moves the sample
        // to video time t + 20 ms.
        let want = DVec3::new(-g[1], -g[0], -g[2]) * k;
        assert!((s.t - (i as f64 * 0.005 + 0.02)).abs() < 1e-12, "t {}", s.t);
        assert!(close(s.omega, want, 1e-12), "{i}: {} vs {want}", s.omega);
    }
}

#[test]
fn gyroflow_offsets_that_drift_are_applied_as_gyroflow_looks_them_up() {
    let d = dir("drift");
    let text = gyroflow_project().replace(
        "\"offsets\": {\"0\": 20.0}",
        "\"offsets\": {\"0\": 10.0, \"10000000\": 30.0}",
    );
    let p = d.join("drift.gyroflow");
    std::fs::write(&p, text).unwrap();
    let log = mmbm::telemetry::read_gyro(&p, &opts()).unwrap();
    // Gyroflow reads the gyro at tv - off(tv), off(tv) = 0.01 + 0.002 tv
    // (s): the sample at gyro time t is at tv = (t + 0.01) / 0.998.
    for (i, s) in log.samples().iter().enumerate() {
        let t = i as f64 * 0.005;
        let tv = (t + 0.01) / 0.998;
        assert!((s.t - tv).abs() < 1e-7, "{i}: {} vs {tv}", s.t);
    }
}

#[test]
fn gyroflow_project_without_samples_reads_its_gyro_file_beside_it() {
    let d = dir("beside");
    std::fs::copy(fixture("gopro_hero.mp4"), d.join("GX010001.MP4")).unwrap();
    let text = r#"{"title": "Gyroflow data file", "videofile": "C:\\Videos\\GX010001.MP4",
        "gyro_source": {"filepath": "C:\\Videos\\GX010001.MP4"}, "offsets": {"0": -5.0}}"#;
    std::fs::write(d.join("p.gyroflow"), text).unwrap();
    let (log, info) = read_camera_file(&d.join("p.gyroflow"), &opts()).unwrap();
    assert_eq!(
        info.gyro_file.as_deref(),
        Some(d.join("GX010001.MP4").as_path())
    );
    for (s, (t, w)) in log.samples().iter().zip(gopro_truth()) {
        assert!((s.t - (t - 0.005)).abs() < 1e-12);
        assert!(close(s.omega, w, 1e-12));
    }
}

#[test]
fn sensor_logger_and_phyphox_read_the_device_axes_and_the_preset() {
    for name in [
        "sensor_logger_Gyroscope.csv",
        "phyphox_Gyroscope rotation rate.csv",
    ] {
        let mut o = opts();
        o.orientation = Some(Orientation::PhoneBackPortrait);
        let log = mmbm::telemetry::read_gyro(&fixture(name), &o).unwrap();
        let want = app_truth();
        assert_eq!(log.samples().len(), want.len(), "{name}");
        for (s, (t, w)) in log.samples().iter().zip(want) {
            assert!((s.t - t).abs() < 1e-12, "{name}");
            // Back camera, portrait: (x, -y, -z).
            assert!(
                close(s.omega, DVec3::new(w.x, -w.y, -w.z), 1e-12),
                "{name}: {} vs {w}",
                s.omega
            );
        }
    }
}

#[test]
fn phyphox_semicolon_export_with_decimal_commas() {
    let d = dir("semicolon");
    let text =
        "\"Time (s)\";\"Gyroscope x (rad/s)\";\"Gyroscope y (rad/s)\";\"Gyroscope z (rad/s)\"\n\
                0,5;1,25;-2,5;0\n0,75;0;0;3,125\n";
    let p = d.join("g.csv");
    std::fs::write(&p, text).unwrap();
    let log = mmbm::telemetry::read_gyro(&p, &opts()).unwrap();
    assert_eq!(log.samples()[0].t, 0.5);
    assert_eq!(log.samples()[0].omega, DVec3::new(1.25, -2.5, 0.0));
    assert_eq!(log.samples()[1].omega, DVec3::new(0.0, 0.0, 3.125));
}

#[test]
fn a_plain_log_reads_as_before() {
    let d = dir("plain");
    let p = d.join("g.csv");
    std::fs::write(&p, "t,wx,wy,wz\n0,1,2,3\n0.01,1,2,3\n0.02,1,2,3\n").unwrap();
    let a = mmbm::io::gyro::read_log(&p, Default::default()).unwrap();
    let b = mmbm::telemetry::read_gyro(&p, &opts()).unwrap();
    assert_eq!(a.samples(), b.samples());
}

/// `mmbm series` on each camera file gives the bytes it gives on the plain
/// CSV of the same samples (written from the truth, not read by mmbm).
#[test]
fn series_of_a_camera_file_equals_series_of_its_truth() {
    let d = dir("series");
    let mut csv = String::from("t,wx,wy,wz\n");
    for (t, w) in gopro_truth() {
        csv += &format!("{t:?},{:?},{:?},{:?}\n", w.x, w.y, w.z);
    }
    std::fs::write(d.join("truth.csv"), csv).unwrap();
    let mp4 = fixture("gopro_hero.mp4");
    let a = common::mmbm_ok_in(&d, &["series", "--gyro", "truth.csv", "--exposure", "0.01"]);
    let b = common::mmbm_ok_in(
        &d,
        &[
            "series",
            "--gyro",
            mp4.to_str().unwrap(),
            "--exposure",
            "0.01",
        ],
    );
    assert_eq!(
        String::from_utf8_lossy(&a.stdout),
        String::from_utf8_lossy(&b.stdout)
    );
    assert_eq!(a.stdout.lines_count(), 601);
}

trait Lines {
    fn lines_count(&self) -> usize;
}
impl Lines for Vec<u8> {
    fn lines_count(&self) -> usize {
        self.iter().filter(|&&b| b == b'\n').count()
    }
}

#[test]
fn frames_reads_a_project_and_takes_its_readout() {
    let d = dir("frames");
    let mut table = String::from("t_start,exposure_s\n");
    for i in 0..40 {
        table += &format!("{},0.01\n", 0.1 + i as f64 / 29.97);
    }
    std::fs::write(d.join("frames.csv"), table).unwrap();
    let p = fixture("project.gyroflow");
    let o = common::mmbm_ok_in(
        &d,
        &[
            "frames",
            "--gyro",
            p.to_str().unwrap(),
            "--frames",
            "frames.csv",
            "--out",
            "f.csv",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("0.0165") || err.contains("16.5"),
        "the project's readout is said: {err}"
    );
    let out = std::fs::read_to_string(d.join("f.csv")).unwrap();
    assert_eq!(out.lines().count(), 41);
    assert!(
        out.lines().nth(1).unwrap().ends_with(",0.01,0.0165"),
        "{}",
        out.lines().nth(1).unwrap()
    );
}

#[test]
fn orientation_flag_is_parsed_and_refused_where_it_cannot_apply() {
    let d = dir("flag");
    let p = fixture("sensor_logger_Gyroscope.csv");
    let o = common::mmbm_in(
        &d,
        &[
            "series",
            "--gyro",
            p.to_str().unwrap(),
            "--orientation",
            "sideways",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("phone-back-landscape"));
    let o = common::mmbm_ok_in(
        &d,
        &[
            "series",
            "--gyro",
            p.to_str().unwrap(),
            "--orientation",
            "phone-back-landscape",
        ],
    );
    // Landscape, top left: (x, y, z) -> (-y, -x, -z) in the camera frame;
    // the first sample's rate is (0.5, -1.25, 2) and gives a non-zero MMBM.
    assert!(String::from_utf8_lossy(&o.stdout).lines().count() == 101);
}

// ---- hostile files ----

/// Reads `bytes` as a file named `name`: the error's text (no panic).
fn refused(name: &str, bytes: &[u8]) -> String {
    let d = dir(&format!("bad-{}", name.replace(['.', ' '], "_")));
    let p = d.join(name);
    std::fs::write(&p, bytes).unwrap();
    match read_camera_file(&p, &opts()) {
        Ok(_) => panic!("{name}: read, expected a refusal"),
        Err(e) => {
            let m = e.to_string();
            assert!(
                m.contains(name),
                "{name}: the error does not name the file: {m}"
            );
            assert!(!m.contains('\n'), "{name}: not one line: {m}");
            m
        }
    }
}

fn replace_once(hay: &[u8], needle: &[u8], with: &[u8]) -> Vec<u8> {
    let at = hay
        .windows(needle.len())
        .position(|w| w == needle)
        .expect("needle");
    [&hay[..at], with, &hay[at + needle.len()..]].concat()
}

#[test]
fn hostile_mp4s_are_refused_with_place_and_reason() {
    let good = gopro_mp4();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty.mp4", Vec::new(), "not an MP4"),
        ("text.mp4", b"t,wx,wy,wz\n0,0,0,0\n".to_vec(), "not an MP4"),
        (
            "truncated.mp4",
            good[..good.len() / 2].to_vec(),
            "past the end",
        ),
        ("no_moov.mp4", good[..good.len() - 10].to_vec(), "moov"),
        // stsz of the gpmd track claims 2^30 entries.
        (
            "huge_count.mp4",
            replace_once(
                &good,
                b"stsz\0\0\0\0\0\0\0\0\0\0\0\x03",
                b"stsz\0\0\0\0\0\0\0\0\x40\0\0\0",
            ),
            "do not fit",
        ),
        (
            "zero_scal.mp4",
            replace_once(
                &good,
                &klv(b"SCAL", b's', 2, 1, &1000i16.to_be_bytes()),
                &klv(b"SCAL", b's', 2, 1, &0i16.to_be_bytes()),
            ),
            "SCAL",
        ),
        ("bad_orin.mp4", replace_once(&good, b"ZXY", b"ZXX"), "ORIN"),
        (
            "gyro_as_text.mp4",
            replace_once(&good, b"GYROs\x06", b"GYROc\x06"),
            "not a number type",
        ),
        (
            "gyro_past_parent.mp4",
            replace_once(&good, b"GYROs\x06\x00\xc8", b"GYROs\x06\x7f\xff"),
            "run past",
        ),
        (
            "no_gpmd.mp4",
            replace_once(&good, b"gpmd", b"abcd"),
            "no GPMF",
        ),
    ];
    for (name, bytes, reason) in cases {
        let m = refused(name, &bytes);
        assert!(m.contains(reason), "{name}: expected '{reason}' in: {m}");
    }
    // NaN in float GYRO data.
    let nan = {
        let mut data = Vec::new();
        for v in [0.0f32, f32::NAN, 1.0] {
            data.extend_from_slice(&v.to_be_bytes());
        }
        let p = nest(
            b"DEVC",
            &[nest(b"STRM", &[klv(b"GYRO", b'f', 12, 1, &data)])],
        );
        let ftyp = mp4_box(b"ftyp", b"mp41\0\0\0\0mp41");
        let at = ftyp.len() as u32 + 8;
        let meta = trak(b"meta", b"gpmd", 1000, &[p.len() as u32], &[at], 1000);
        [ftyp, mp4_box(b"mdat", &p), mp4_box(b"moov", &meta)].concat()
    };
    let m = refused("nan.mp4", &nan);
    assert!(m.contains("not finite"), "{m}");
}

#[test]
fn hostile_projects_are_refused_with_place_and_reason() {
    let good = gyroflow_project();
    let cases: Vec<(&str, String, &str)> = vec![
        ("empty.gyroflow", String::new(), "not a Gyroflow project"),
        ("not_json.gyroflow", "{\"gyro_source\": [".into(), "JSON"),
        ("compressed.gyroflow", r#"{"gyro_source": {"raw_imu": "Xk9a!"}}"#.into(), "compressed"),
        ("wrong_type.gyroflow", good.replacen("[10, -20, 0]", "[10, \"a\", 0]", 1), "raw_imu[0].gyro"),
        ("short_gyro.gyroflow", good.replacen("\"gyro\": [10, -20, 0]", "\"gyro\": [10]", 1), "raw_imu[0].gyro"),
        ("bad_offset.gyroflow", good.replace("\"offsets\": {\"0\": 20.0}", "\"offsets\": {\"soon\": 20.0}"), "offsets.soon"),
        ("backwards.gyroflow", good.replacen("\"timestamp_ms\": 5,", "\"timestamp_ms\": -5,", 1), "not strictly increasing"),
        (
            "outside.gyroflow",
            r#"{"title": "Gyroflow data file", "gyro_source": {"filepath": "../../../etc/passwd"}}"#.into(),
            "project's folder only",
        ),
        ("dotdot.gyroflow", r#"{"gyro_source": {"filepath": "/x/.."}}"#.into(), "names no file"),
        ("bad_orientation.gyroflow", good.replace("\"XYZ\"", "\"XXZ\""), "imu_orientation"),
    ];
    assert!(good.contains("[10, -20, 0]"), "the builder's first sample");
    for (name, text, reason) in cases {
        let m = refused(name, text.as_bytes());
        assert!(m.contains(reason), "{name}: expected '{reason}' in: {m}");
    }
}

#[test]
fn hostile_app_csvs_are_refused_with_line_and_column() {
    let good = sensor_logger_csv();
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    lines[3] = lines[3].replacen(",", ",abc", 2);
    let bad_number = lines.join("\n");
    let m = refused("Gyroscope.csv", bad_number.as_bytes());
    assert!(
        m.contains(":4:") && m.contains("not a finite number"),
        "{m}"
    );
    let short = "time,seconds_elapsed,z,y,x\n1,0.5,1,2\n";
    let m = refused("short.csv", short.as_bytes());
    assert!(m.contains(":2:x") && m.contains("missing"), "{m}");
    let nan = "\"Time (s)\",\"Gyroscope x (rad/s)\",\"Gyroscope y (rad/s)\",\"Gyroscope z (rad/s)\"\n0,NaN,0,0\n";
    let m = refused("nan.csv", nan.as_bytes());
    assert!(
        m.contains("Gyroscope x (rad/s)") && m.contains("not a finite number"),
        "{m}"
    );
    let header_only = "time,seconds_elapsed,z,y,x\n";
    let m = refused("header_only.csv", header_only.as_bytes());
    assert!(m.contains("no samples"), "{m}");
}

#[test]
fn unknown_binary_is_refused_listing_what_is_accepted() {
    let m = refused("blob.bin", &[0u8, 1, 2, 3, 0, 0, 7, 8]);
    assert!(
        m.contains("GoPro MP4") && m.contains("Gyroflow project") && m.contains("phyphox"),
        "{m}"
    );
}

#[test]
fn cli_refuses_a_hostile_mp4_in_one_line() {
    let d = dir("cli-bad");
    let good = gopro_mp4();
    std::fs::write(d.join("cut.mp4"), &good[..good.len() - 40]).unwrap();
    std::fs::write(d.join("frames.csv"), "t_start,exposure_s\n0.1,0.01\n").unwrap();
    let o = common::mmbm_in(
        &d,
        &[
            "frames",
            "--gyro",
            "cut.mp4",
            "--frames",
            "frames.csv",
            "--out",
            "o.csv",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.lines().filter(|l| l.starts_with("error: ")).count() == 1 && e.contains("cut.mp4"),
        "{e}"
    );
    assert!(!d.join("o.csv").exists());
}
