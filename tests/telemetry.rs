//! The gyro from a camera's own files (`mmbm::telemetry`): one fixture per
//! format, built here byte by byte from known angular velocities (so the
//! test knows the truth), read back exactly (after SCAL, the axis order and
//! the orientation); the same log through `mmbm series` gives the same
//! output as the plain CSV of the truth; hostile files are refused with the
//! file, the place and the reason, never a panic.
//!
//! The fixtures in `tests/fixtures/telemetry/` are what the builders below
//! write (checked byte for byte; `MMBM_WRITE_FIXTURES=1` rewrites them).

mod common;

use glam::DVec3;
use mmbm::telemetry::{read_camera_file, Format, Orientation, TelemetryOptions};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-telemetry-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn opts() -> TelemetryOptions {
    TelemetryOptions::default()
}

// ---- a GoPro-style MP4, byte by byte ----

fn mp4_box(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
    let mut b = ((body.len() + 8) as u32).to_be_bytes().to_vec();
    b.extend_from_slice(kind);
    b.extend_from_slice(body);
    b
}

fn full(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
    let mut b = vec![0u8; 4]; // version 0, flags 0
    b.extend_from_slice(body);
    mp4_box(kind, &b)
}

fn be32(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

/// A KLV entry (data padded to 4 bytes).
fn klv(key: &[u8; 4], kind: u8, size: u8, repeat: u16, data: &[u8]) -> Vec<u8> {
    let mut b = key.to_vec();
    b.push(kind);
    b.push(size);
    b.extend_from_slice(&repeat.to_be_bytes());
    b.extend_from_slice(data);
    while b.len() % 4 != 0 {
        b.push(0);
    }
    b
}

fn nest(key: &[u8; 4], children: &[Vec<u8>]) -> Vec<u8> {
    let body: Vec<u8> = children.concat();
    let mut b = key.to_vec();
    b.push(0);
    b.push(1);
    b.extend_from_slice(&(body.len() as u16).to_be_bytes());
    b.extend_from_slice(&body);
    b
}

/// GoPro's IMU axes (X left, Y out of the back, Z up) of a camera-frame
/// rate (x right, y down, z forward), written out from the documented axes.
fn gopro_axes(w: DVec3) -> [f64; 3] {
    [-w.x, -w.z, -w.y] // X = -x, Y = -z, Z = -y
}

/// The true camera-frame rate of payload `k`, sample `i` (rad/s; multiples
/// of 1/1000 so that SCAL 1000 is exact).
fn truth(k: usize, i: usize) -> DVec3 {
    DVec3::new(
        0.5 - 0.125 * k as f64,
        (i as f64 - 250.0) / 1000.0,
        0.125 * k as f64,
    )
}

/// One GPMF payload of `n` GYRO samples (ORIN `ZXY`: channels Z, X, Y).
fn payload(k: usize, n: usize, scal: i16) -> Vec<u8> {
    let mut data = Vec::new();
    for i in 0..n {
        let [x, y, z] = gopro_axes(truth(k, i));
        for v in [z, x, y] {
            data.extend_from_slice(&((v * scal as f64).round() as i16).to_be_bytes());
        }
    }
    nest(
        b"DEVC",
        &[
            klv(b"DVID", b'L', 4, 1, &1u32.to_be_bytes()),
            klv(b"DVNM", b'c', 6, 1, b"Camera"),
            nest(
                b"STRM",
                &[
                    klv(b"TSMP", b'L', 4, 1, &((k * n + n) as u32).to_be_bytes()),
                    klv(b"SIUN", b'c', 5, 1, b"rad/s"),
                    klv(b"SCAL", b's', 2, 1, &scal.to_be_bytes()),
                    klv(b"ORIN", b'c', 1, 3, b"ZXY"),
                    klv(b"GYRO", b's', 6, n as u16, &data),
                ],
            ),
        ],
    )
}

/// A track: handler, sample entry format, timescale, (sizes, offsets, deltas).
fn trak(
    handler: &[u8; 4],
    format: &[u8; 4],
    timescale: u32,
    sizes: &[u32],
    offsets: &[u32],
    delta: u32,
) -> Vec<u8> {
    let n = sizes.len() as u32;
    let mut hdlr = be32(&[0]);
    hdlr.extend_from_slice(handler);
    hdlr.extend_from_slice(&[0u8; 12]);
    hdlr.push(0);
    let mdhd = be32(&[0, 0, timescale, n * delta, 0]);
    let mut entry = be32(&[16]);
    entry.extend_from_slice(format);
    entry.extend_from_slice(&[0u8; 8]);
    let mut stsd = be32(&[1]);
    stsd.extend_from_slice(&entry);
    let mut stsz = be32(&[0, n]);
    stsz.extend(be32(sizes));
    let mut stco = be32(&[offsets.len() as u32]);
    stco.extend(be32(offsets));
    let stbl = [
        full(b"stsd", &stsd),
        full(b"stts", &be32(&[1, n, delta])),
        full(b"stsz", &stsz),
        full(b"stsc", &be32(&[1, 1, 1, 1])),
        full(b"stco", &stco),
    ]
    .concat();
    let minf = mp4_box(b"stbl", &stbl);
    let mdia = [
        full(b"mdhd", &mdhd),
        full(b"hdlr", &hdlr),
        mp4_box(b"minf", &minf),
    ]
    .concat();
    mp4_box(b"trak", &mp4_box(b"mdia", &mdia))
}

/// A GoPro-style MP4: 3 one-second GPMF payloads of 200 gyro samples and a
/// 30-frame-per-second video track of 90 one-byte frames.
fn gopro_mp4() -> Vec<u8> {
    let ftyp = mp4_box(b"ftyp", b"mp41\0\0\0\0mp41");
    let payloads: Vec<Vec<u8>> = (0..3).map(|k| payload(k, 200, 1000)).collect();
    let frames = vec![0u8; 90];
    let mdat_start = ftyp.len() as u32 + 8;
    let mut mdat = frames.clone();
    let mut offs = Vec::new();
    for p in &payloads {
        offs.push(mdat_start + mdat.len() as u32);
        mdat.extend_from_slice(p);
    }
    let video_offs: Vec<u32> = (0..90).map(|i| mdat_start + i).collect();
    // The video: 90 chunks of one frame each (stsc 1,1,1 as above).
    let video = trak(b"vide", b"avc1", 30000, &[1; 90], &video_offs, 1000);
    let sizes: Vec<u32> = payloads.iter().map(|p| p.len() as u32).collect();
    let meta = trak(b"meta", b"gpmd", 1000, &sizes, &offs, 1000);
    let moov = mp4_box(b"moov", &[video, meta].concat());
    [ftyp, mp4_box(b"mdat", &mdat), moov].concat()
}

fn gopro_truth() -> Vec<(f64, DVec3)> {
    (0..3)
        .flat_map(|k| (0..200).map(move |i| (k as f64 + i as f64 / 200.0, truth(k, i))))
        .collect()
}

// ---- a Gyroflow project ----

/// A project with 400 samples at 200 Hz (deg/s, orientation XYZ), one sync
/// offset of 20 ms, a 16.5 ms readout, 29.97 fps and a lens profile.
fn gyroflow_project() -> String {
    let mut raw = Vec::new();
    for i in 0..400 {
        let g = project_raw(i);
        raw.push(format!(
            "{{\"timestamp_ms\": {}, \"gyro\": [{}, {}, {}], \"accl\": [0.0, 9.81, 0.0]}}",
            i as f64 * 5.0,
            g[0],
            g[1],
            g[2]
        ));
    }
    format!(
        r#"{{
  "title": "Gyroflow data file",
  "version": 3,
  "videofile": "/somewhere/clip.mp4",
  "calibration_data": {{"calib_dimension": {{"w": 1920, "h": 1080}}, "fisheye_params": {{"camera_matrix": [[1000, 0, 960], [0, 1000, 540], [0, 0, 1]], "distortion_coeffs": [0, 0, 0, 0]}}}},
  "video_info": {{"width": 1920, "height": 1080, "fps": 29.97, "duration_ms": 2000.0}},
  "stabilization": {{"fov": 1.0, "frame_readout_time": 16.5}},
  "gyro_source": {{"filepath": "/somewhere/clip.mp4", "imu_orientation": "XYZ", "rotation": null, "raw_imu": [{}]}},
  "offsets": {{"0": 20.0}}
}}
"#,
        raw.join(", ")
    )
}

/// The file's gyro of project sample `i`, deg/s.
fn project_raw(i: usize) -> [f64; 3] {
    [10.0 + i as f64 * 0.25, -20.0, 5.0 * (i % 7) as f64]
}

// ---- phone apps ----

fn sensor_logger_csv() -> String {
    let mut s = String::from("time,seconds_elapsed,z,y,x\n");
    for (t, w) in app_truth() {
        s += &format!(
            "{},{t},{},{},{}\n",
            1_700_000_000_000_000_000u64 + (t * 1e9) as u64,
            w.z,
            w.y,
            w.x
        );
    }
    s
}

fn phyphox_csv() -> String {
    let mut s = String::from(
        "\"Time (s)\",\"Gyroscope x (rad/s)\",\"Gyroscope y (rad/s)\",\"Gyroscope z (rad/s)\",\"Absolute (rad/s)\"\n",
    );
    for (t, w) in app_truth() {
        s += &format!("{t:e},{:e},{:e},{:e},{:e}\n", w.x, w.y, w.z, w.length());
    }
    s
}

/// (s, device-axis rad/s) of the app logs: 100 Hz for 1 s.
fn app_truth() -> Vec<(f64, DVec3)> {
    (0..100)
        .map(|i| {
            (
                0.25 + i as f64 * 0.01,
                DVec3::new(0.5, -1.25 + i as f64 * 0.0625, 2.0),
            )
        })
        .collect()
}

// ---- the fixtures ----

fn fixtures() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("gopro_hero.mp4", gopro_mp4()),
        ("project.gyroflow", gyroflow_project().into_bytes()),
        (
            "sensor_logger_Gyroscope.csv",
            sensor_logger_csv().into_bytes(),
        ),
        (
            "phyphox_Gyroscope rotation rate.csv",
            phyphox_csv().into_bytes(),
        ),
    ]
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/telemetry")
        .join(name)
}

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
        e.starts_with("error: ") && e.contains("cut.mp4") && e.lines().count() == 1,
        "{e}"
    );
    assert!(!d.join("o.csv").exists());
}
