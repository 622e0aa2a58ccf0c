//! The builders of `cli/tests/logs/telemetry.rs`: one camera file per format, made
//! byte by byte from known angular velocities (so the tests know the
//! truth), and the committed fixtures they must equal.

#![allow(dead_code)]

use glam::DVec3;
use mmbm::telemetry::TelemetryOptions;
use std::path::PathBuf;

pub fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-telemetry-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn opts() -> TelemetryOptions {
    TelemetryOptions::default()
}

// ---- a GoPro-style MP4, byte by byte ----

pub fn mp4_box(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
    let mut b = ((body.len() + 8) as u32).to_be_bytes().to_vec();
    b.extend_from_slice(kind);
    b.extend_from_slice(body);
    b
}

pub fn full(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
    let mut b = vec![0u8; 4]; // version 0, flags 0
    b.extend_from_slice(body);
    mp4_box(kind, &b)
}

pub fn be32(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

/// A KLV entry (data padded to 4 bytes).
pub fn klv(key: &[u8; 4], kind: u8, size: u8, repeat: u16, data: &[u8]) -> Vec<u8> {
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

pub fn nest(key: &[u8; 4], children: &[Vec<u8>]) -> Vec<u8> {
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
pub fn gopro_axes(w: DVec3) -> [f64; 3] {
    [-w.x, -w.z, -w.y] // X = -x, Y = -z, Z = -y
}

/// The true camera-frame rate of payload `k`, sample `i` (rad/s; multiples
/// of 1/1000 so that SCAL 1000 is exact).
pub fn truth(k: usize, i: usize) -> DVec3 {
    DVec3::new(
        0.5 - 0.125 * k as f64,
        (i as f64 - 250.0) / 1000.0,
        0.125 * k as f64,
    )
}

/// One GPMF payload of `n` GYRO samples (ORIN `ZXY`: channels Z, X, Y).
pub fn payload(k: usize, n: usize, scal: i16) -> Vec<u8> {
    let rates: Vec<DVec3> = (0..n).map(|i| truth(k, i)).collect();
    payload_of(k, &rates, scal)
}

/// GPMF payload `k` holding the camera-frame rates `rates` (rad/s), written
/// in GoPro's axes as GYRO samples scaled by `scal` (ORIN `ZXY`).
pub fn payload_of(k: usize, rates: &[DVec3], scal: i16) -> Vec<u8> {
    let n = rates.len();
    let mut data = Vec::new();
    for &w in rates {
        let [x, y, z] = gopro_axes(w);
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
pub fn trak(
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
pub fn gopro_mp4() -> Vec<u8> {
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

/// An MP4 with one track: GPMF `payloads`, one a second (a camera file's
/// telemetry alone, for ffmpeg to mux beside a video track).
pub fn gpmf_mp4(payloads: &[Vec<u8>]) -> Vec<u8> {
    let ftyp = mp4_box(b"ftyp", b"mp41\0\0\0\0mp41");
    let mdat_start = ftyp.len() as u32 + 8;
    let mut mdat = Vec::new();
    let mut offs = Vec::new();
    for p in payloads {
        offs.push(mdat_start + mdat.len() as u32);
        mdat.extend_from_slice(p);
    }
    let sizes: Vec<u32> = payloads.iter().map(|p| p.len() as u32).collect();
    let meta = trak(b"meta", b"gpmd", 1000, &sizes, &offs, 1000);
    [ftyp, mp4_box(b"mdat", &mdat), mp4_box(b"moov", &meta)].concat()
}

pub fn gopro_truth() -> Vec<(f64, DVec3)> {
    (0..3)
        .flat_map(|k| (0..200).map(move |i| (k as f64 + i as f64 / 200.0, truth(k, i))))
        .collect()
}

// ---- a Gyroflow project ----

/// A project with 400 samples at 200 Hz (deg/s, orientation XYZ), one sync
/// offset of 20 ms, a 16.5 ms readout, 29.97 fps and a lens profile.
pub fn gyroflow_project() -> String {
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
pub fn project_raw(i: usize) -> [f64; 3] {
    [10.0 + i as f64 * 0.25, -20.0, 5.0 * (i % 7) as f64]
}

// ---- phone apps ----

pub fn sensor_logger_csv() -> String {
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

pub fn phyphox_csv() -> String {
    let mut s = String::from(
        "\"Time (s)\",\"Gyroscope x (rad/s)\",\"Gyroscope y (rad/s)\",\"Gyroscope z (rad/s)\",\"Absolute (rad/s)\"\n",
    );
    for (t, w) in app_truth() {
        s += &format!("{t:e},{:e},{:e},{:e},{:e}\n", w.x, w.y, w.z, w.length());
    }
    s
}

/// (s, device-axis rad/s) of the app logs: 100 Hz for 1 s.
pub fn app_truth() -> Vec<(f64, DVec3)> {
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

pub fn fixtures() -> Vec<(&'static str, Vec<u8>)> {
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

pub fn fixture(name: &str) -> PathBuf {
    crate::common::repo_root()
        .join("tests/fixtures/telemetry")
        .join(name)
}
