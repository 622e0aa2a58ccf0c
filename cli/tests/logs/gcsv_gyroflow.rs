//! Gyroflow `.gcsv` logs as Gyroflow reads them (the rest of `cli/tests/logs/gcsv.rs`):
//! comma-free header lines, negative readouts, the stated time origin and
//! scales, and Gyroflow's IMU rotation in its IMU frame.

use crate::common;
use crate::gcsv_fixture;

use common::mmbm;
use gcsv_fixture::*;
use glam::{DMat3, DVec3};
use mmbm::io::gcsv::{orientation_matrix, read_header, ReadoutDirection, GYROFLOW_TO_CAMERA};
use mmbm::io::gyro::{read_log, GyroOptions};

/// Header lines without a comma (`version:1.3`, written by real loggers) are
/// skipped, as telemetry-parser skips them; a negative `frame_readout_time`
/// is its magnitude with the direction reversed (Gyroflow's sign).
#[test]
fn comma_free_header_lines_and_negative_readouts() {
    let dir = tempfile::tempdir().unwrap();
    let text = walk_text();
    let p = write(
        dir.path(),
        "colon.gcsv",
        &with_line(&text, 2, "version:1.3"),
    );
    let h = read_header(&p).unwrap();
    assert_eq!(h.get("version"), None);
    assert_eq!(h.fields.len(), 15);
    assert_eq!(
        read_log(&p, GyroOptions::default()).unwrap(),
        read_log(&walk(), GyroOptions::default()).unwrap()
    );
    for (ms, dir_line, want) in [
        (
            "-15.23",
            "frame_readout_direction,0",
            ReadoutDirection::BottomToTop,
        ),
        ("-15.23", "note,none", ReadoutDirection::BottomToTop),
        (
            "-15.23",
            "frame_readout_direction,1",
            ReadoutDirection::TopToBottom,
        ),
        (
            "-15.23",
            "frame_readout_direction,2",
            ReadoutDirection::RightToLeft,
        ),
        (
            "15.23",
            "frame_readout_direction,1",
            ReadoutDirection::BottomToTop,
        ),
    ] {
        let t = with_line(&text, 12, &format!("frame_readout_time,{ms}"));
        let p = write(dir.path(), "neg.gcsv", &with_line(&t, 13, dir_line));
        let h = read_header(&p).unwrap();
        assert_eq!(h.readout_s, Some(0.01523), "{ms} {dir_line}");
        assert_eq!(h.readout_direction, Some(want), "{ms} {dir_line}");
    }
}

/// The time origin and the scales a `.gcsv` log took are stated on stderr.
#[test]
fn the_time_origin_and_scales_are_stated() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "nog.gcsv",
        &walk_text().replace("gscale,0.00122173047\n", ""),
    );
    let o = mmbm(&["series", "--gyro", p.to_str().unwrap(), "--out", "-"]);
    assert!(o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("time from the first sample (t0 = 1 s is t = 0)")
            && e.contains("tscale 0.001 s (from the header)")
            && e.contains("gscale 1 rad/s (telemetry-parser's default"),
        "{e}"
    );
    let first = String::from_utf8(o.stdout).unwrap();
    let t0: f64 = first
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(t0, 0.0, "{first}");
}

/// Gyroflow's IMU rotation (pitch, roll, yaw in degrees) applies in its IMU
/// frame after the orientation, as `Rz(roll) Ry(pitch) Rx(yaw)`; mmbm's
/// `--imu-rotation` applies after it, in the camera frame.
#[test]
fn gyroflow_rotation_acts_in_gyroflows_imu_frame() {
    use mmbm::io::gcsv::gyroflow_rotation;
    let raw = raw_rows(&walk_text());
    let read = |angles: Option<[f64; 3]>, m: DMat3| {
        let opts = GyroOptions {
            gyroflow_rotation: angles,
            imu_to_camera: m,
            ..GyroOptions::default()
        };
        read_log(&walk(), opts).unwrap()
    };
    // Yaw 90 degrees turns about Gyroflow's x (up): its y (left) becomes z
    // (back), z becomes -y. Computed here from the file's columns (YxZ).
    let s = read(Some([0.0, 0.0, 90.0]), DMat3::IDENTITY);
    for (s, [_, gx, gy, gz]) in s.iter().zip(&raw) {
        let gf = DVec3::new(gy * GSCALE, -gx * GSCALE, gz * GSCALE);
        let turned = DVec3::new(gf.x, -gf.z, gf.y);
        let camera = DVec3::new(-turned.y, -turned.x, -turned.z);
        assert!((s.omega - camera).abs().max_element() < 1e-12, "{s:?}");
    }
    // Pitch about y (left), roll about z (back), in that composition.
    let r = gyroflow_rotation([30.0, 20.0, 10.0]).unwrap();
    let want = DMat3::from_rotation_z(20f64.to_radians())
        * DMat3::from_rotation_y(30f64.to_radians())
        * DMat3::from_rotation_x(10f64.to_radians());
    assert!((r - want).to_cols_array().iter().all(|d| d.abs() < 1e-15));
    let m = mmbm::io::gyro::parse_rotation("0,-1,0,1,0,0,0,0,1").unwrap();
    let s = read(Some([30.0, 20.0, 10.0]), m);
    for (s, [_, gx, gy, gz]) in s.iter().zip(&raw) {
        let g = DVec3::new(*gx, *gy, *gz) * GSCALE;
        let want = m * GYROFLOW_TO_CAMERA * r * orientation_matrix("YxZ").unwrap() * g;
        assert!((s.omega - want).abs().max_element() < 1e-12);
    }
    assert!(gyroflow_rotation([f64::NAN, 0.0, 0.0])
        .unwrap_err()
        .to_string()
        .contains("pitch"));
    // The command line: the same as the library, and refused for a CSV log.
    let dir = tempfile::tempdir().unwrap();
    let csv = write(dir.path(), "w.csv", "t,wx,wy,wz\n0,1,2,3\n1,1,2,3\n");
    let o = mmbm(&[
        "series",
        "--gyro",
        csv.to_str().unwrap(),
        "--gyroflow-rotation",
        "0,0,90",
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("w.csv") && e.contains(".gcsv log only"), "{e}");
    let g = walk();
    let a = mmbm(&[
        "series",
        "--gyro",
        g.to_str().unwrap(),
        "--gyroflow-rotation",
        "0,0,90",
        "--out",
        "-",
    ]);
    let b = mmbm(&["series", "--gyro", g.to_str().unwrap(), "--out", "-"]);
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    assert_ne!(a.stdout, b.stdout);
    let o = mmbm(&[
        "series",
        "--gyro",
        g.to_str().unwrap(),
        "--gyroflow-rotation",
        "1,2",
    ]);
    assert_eq!(o.status.code(), Some(2));
}
