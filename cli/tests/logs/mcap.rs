//! ROS 2 MCAP logs: the fixture written by the Python `mcap` packages
//! (`tests/fixtures/mcap/make_imu_mcap.py`) reads as the CSV the same script
//! printed, through the library and every command that takes `--gyro`.

use crate::common;

use common::mmbm;
use mmbm::io::gyro::{read_log, GyroOptions};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    crate::common::repo_root()
        .join("tests/fixtures/mcap")
        .join(name)
}

fn with_topic(topic: &str) -> GyroOptions {
    GyroOptions {
        topic: Some(topic.into()),
        ..GyroOptions::default()
    }
}

#[test]
fn imu_topic_reads_as_the_writers_csv() {
    let bag = read_log(&fixture("imu.mcap"), with_topic("/imu/data")).unwrap();
    let csv = read_log(&fixture("imu_expected.csv"), GyroOptions::default()).unwrap();
    assert_eq!(bag.len(), 240);
    assert_eq!(bag, csv, "header stamps (not log times) and rad/s, exactly");
    let other = read_log(&fixture("imu.mcap"), with_topic("/imu/other")).unwrap();
    assert_eq!(other.len(), 10);
    assert!(other.iter().all(|s| s.omega.x == 9.0));
}

#[test]
fn the_topic_must_be_chosen_and_exist() {
    let e = read_log(&fixture("imu.mcap"), GyroOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("--topic"), "{e}");
    assert!(e.contains("/imu/data (240 messages)"), "{e}");
    assert!(e.contains("/imu/other (10 messages)"), "{e}");
    let e = read_log(&fixture("imu.mcap"), with_topic("/chatter"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no sensor_msgs/msg/Imu messages on topic '/chatter'"),
        "{e}"
    );
}

#[test]
fn damaged_files_are_errors() {
    let bytes = std::fs::read(fixture("imu.mcap")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (k, cut) in [9, 100, bytes.len() / 2, bytes.len() - 30]
        .into_iter()
        .enumerate()
    {
        let p = dir.path().join(format!("cut{k}.mcap"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let r = read_log(&p, with_topic("/imu/data"));
        assert!(r.is_err(), "{cut} bytes read as {:?}", r.map(|v| v.len()));
    }
    let mut flipped = bytes.clone();
    for b in flipped.iter_mut().skip(200).step_by(97) {
        *b ^= 0x5a;
    }
    let p = dir.path().join("flipped.mcap");
    std::fs::write(&p, &flipped).unwrap();
    // Damaged compressed chunks are errors (or, where the damage misses
    // them, still decode): never a crash.
    let _ = read_log(&p, with_topic("/imu/data"));
}

/// Bits flipped in the fixture's compressed chunks can decode to a record
/// that claims an exabyte: that is an error naming the file, not an
/// allocation of the claimed size (which aborted the process).
#[test]
fn a_damaged_record_length_is_an_error_not_an_allocation() {
    let bytes = std::fs::read(fixture("imu.mcap")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("huge.mcap");
    let mut damaged = bytes;
    for (at, bit) in [(10720, 64u8), (11949, 64), (4485, 1), (8925, 128)] {
        damaged[at] ^= bit;
    }
    std::fs::write(&p, &damaged).unwrap();
    let o = mmbm(&[
        "series",
        "--gyro",
        p.to_str().unwrap(),
        "--topic",
        "/imu/data",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("huge.mcap") && err.contains("MCAP record near message"),
        "{err}"
    );
    assert!(o.stdout.is_empty());
}

#[test]
fn every_gyro_command_takes_mcap() {
    let bag = fixture("imu.mcap");
    let csv = fixture("imu_expected.csv");
    let (bag, csv) = (bag.to_str().unwrap(), csv.to_str().unwrap());
    let topic = ["--topic", "/imu/data"];
    let pairs: [Vec<&str>; 3] = [
        vec!["series"],
        vec![
            "trigger",
            "--policy",
            "fixed:5",
            "--policy",
            "threshold:0.4",
            "--exposure",
            "0.02",
        ],
        vec!["live", "--policy", "fixed:5", "--speed", "0", "--all"],
    ];
    for args in pairs {
        let flag = if args[0] == "live" {
            "--replay"
        } else {
            "--gyro"
        };
        let a = mmbm(&[&args[..], &[flag, bag], &topic[..]].concat());
        let b = mmbm(&[&args[..], &[flag, csv]].concat());
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
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.png");
    let o = mmbm(&[
        "render",
        "--gyro",
        bag,
        "--topic",
        "/imu/data",
        "--at",
        "1700000000.4",
        "--exposure",
        "0.02",
        "--resolution",
        "32x24",
        "--backend",
        "cpu",
        "--target",
        "checker:0.02",
        "--distance",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.exists());
}
