//! Property tests of every reader of user files: random bytes and random
//! mutations (replaced, inserted and deleted bytes) of valid files give a
//! value or an error, never a panic; an error names the file.

use crate::common;
// Hostile camera files and dataset manifests (issue #23).
#[path = "fuzz_readers/hostile.rs"]
mod hostile;

use mmbm::io::gyro::{read_log, GyroOptions};
use mmbm::io::lines::LineParser;
use mmbm::sim::{Gait, GaitConfig};
use mmbm::Camera;
use mmbm_lab::experiment::ExperimentConfig;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    crate::common::repo_root().join(name)
}

const GYRO: &str = "# a comment\nt,wx,wy,wz,vx,vy,vz,depth\n0,0.1,-0.2,0.3,0,0,0.1,2\n\
0.01,0.1,-0.2,0.31,0,0,0.1,2\n0.02,0.12,-0.2,0.3,0,0,0.1,2\n0.03,0.1,-0.25,0.3,0,0,0.1,2\n";
const GCSV: &str = "GYROFLOW IMU LOG\nversion,1.3\norientation,YxZ\nframe_readout_time,15.23\n\
frame_readout_direction,0\ntscale,0.001\ngscale,0.00122173047\nt,gx,gy,gz,ax,ay,az\n\
0,39,86,183,-1137,-15689,-2986\n1,56,100,202,-1179,-15654,-3009\n2,63,108,218,-1247,-15702,-2794\n";
const CAMERA: &str =
    "focal_mm = 4.2548\npitch_mm = 0.00465\nwidth = 640\nheight = 480\ncx = 320\ncy = 240\n";
const GAIT: &str = "speed_m_s = 0.2\nstep_hz = 1.5\nsway = [0.1, 0.05, 0.1]\nnoise_std = 0.002\n";
const EXPERIMENT: &str =
    "walks = [\"moderate\"]\nduration_s = 4.0\npolicies = [\"fixed:5\", \"threshold:0.4\"]\n\
exposure_s = 0.07\ntarget = \"blobs\"\nresolution = [64, 48]\nquality = \"fast\"\n";

/// A valid file with some bytes replaced, inserted or deleted.
fn mutated(valid: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let n = valid.len();
    prop::collection::vec((0..3u8, 0..n.max(1), any::<u8>()), 1..8).prop_map(move |edits| {
        let mut b = valid.clone();
        for (kind, at, byte) in edits {
            let at = at.min(b.len());
            match kind {
                0 if at < b.len() => b[at] = byte,
                1 => b.insert(at, byte),
                _ if at < b.len() => {
                    b.remove(at);
                }
                _ => b.push(byte),
            }
        }
        b
    })
}

/// Random bytes, or a mutation of `valid`.
fn inputs(valid: &[u8]) -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..300),
        mutated(valid.to_vec()),
    ]
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// An error must name the file it is about.
fn names_file<T>(r: mmbm::Result<T>, name: &str) -> std::result::Result<(), TestCaseError> {
    if let Err(e) = r {
        let msg = e.to_string();
        prop_assert!(msg.contains(name), "error does not name {name}: {msg}");
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn gyro_csv(bytes in inputs(GYRO.as_bytes())) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "log.csv", &bytes);
        names_file(read_log(&p, GyroOptions::default()), "log.csv")?;
    }

    #[test]
    fn gyro_gcsv(bytes in inputs(GCSV.as_bytes())) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "log.gcsv", &bytes);
        names_file(read_log(&p, GyroOptions::default()), "log.gcsv")?;
        names_file(mmbm::io::gcsv::read_header(&p), "log.gcsv")?;
    }

    #[test]
    fn gyro_gcsv_after_magic(tail in prop::collection::vec(any::<u8>(), 0..400)) {
        // Random bytes after the magic line, under a name that does not say .gcsv.
        let d = tempfile::tempdir().unwrap();
        let bytes = [b"GYROFLOW IMU LOG\n".as_slice(), &tail].concat();
        let p = write(d.path(), "imu.txt", &bytes);
        prop_assert!(mmbm::io::gcsv::is_gcsv(&p));
        names_file(read_log(&p, GyroOptions::default()), "imu.txt")?;
        names_file(mmbm::io::gcsv::read_header(&p), "imu.txt")?;
    }

    #[test]
    fn gyro_lines(bytes in inputs(GYRO.as_bytes())) {
        let mut parser = LineParser::new(GyroOptions::default(), "<stdin>");
        for (k, line) in String::from_utf8_lossy(&bytes).lines().enumerate() {
            if let Err(e) = parser.parse(line, k as u64 + 1) {
                prop_assert!(e.to_string().contains(&format!("<stdin>:{}:", k + 1)), "{e}");
            }
        }
    }

    #[test]
    fn camera_toml(bytes in inputs(CAMERA.as_bytes())) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "cam.toml", &bytes);
        names_file(Camera::load(&p), "cam.toml")?;
        let p = write(d.path(), "cam.json", &bytes);
        names_file(Camera::load(&p), "cam.json")?;
    }

    #[test]
    fn gait_toml(bytes in inputs(GAIT.as_bytes())) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "gait.toml", &bytes);
        names_file(GaitConfig::load(&p, Gait::Moderate), "gait.toml")?;
    }

    #[test]
    fn experiment_toml(bytes in inputs(EXPERIMENT.as_bytes())) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "exp.toml", &bytes);
        names_file(ExperimentConfig::load(&p), "exp.toml")?;
    }

    #[test]
    fn dataset_toml(bytes in inputs(b"count = 24\nseed = 3\nmotion = [\"sim:fast\"]\nexposure_s = [0.01, 0.05]\n")) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "ds.toml", &bytes);
        names_file(mmbm_lab::dataset::DatasetConfig::load(&p), "ds.toml")?;
    }

    #[test]
    fn images(bytes in inputs(&std::fs::read(fixture("tests/fixtures/bars.png")).unwrap())) {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "img.png", &bytes);
        names_file(mmbm::io::images::read_rgb8(&p), "img.png")?;
        names_file(mmbm::assess::load_grey(&p), "img.png")?;
        names_file(mmbm::render::texture::MipTexture::load(&p), "img.png")?;
        let p = write(d.path(), "img.exr", &bytes);
        names_file(mmbm::io::images::read_exr(&p), "img.exr")?;
    }
}

/// Valid EXR bytes mutated (the PNG strategy above rarely makes a valid EXR header).
#[test]
fn exr_mutations() {
    let d = tempfile::tempdir().unwrap();
    let src = d.path().join("f.exr");
    let o = common::mmbm_cmd()
        .args([
            "render",
            "--omega",
            "0.1,0.2,0.3",
            "--exposure",
            "0.02",
            "--backend",
            "cpu",
        ])
        .args([
            "--target",
            "checker:0.02",
            "--distance",
            "1",
            "--resolution",
            "16x12",
            "--out",
        ])
        .arg(&src)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let valid = std::fs::read(&src).unwrap();
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig {
        cases: 200,
        failure_persistence: None,
        ..ProptestConfig::default()
    });
    runner
        .run(&mutated(valid), |bytes| {
            let p = write(d.path(), "m.exr", &bytes);
            names_file(mmbm::io::images::read_exr(&p), "m.exr")
        })
        .unwrap();
}

/// Issue #23 item 4: sizes and values the CLI refused but other doors (Python)
/// passed to the library: a 65535 x 65535 flow field aborted on 34 GB, a
/// negative or NaN exposure or readout of a video frame panicked and a NaN
/// start time gave numbers, a negative resolution was an `OverflowError`
/// naming nothing. Each is now refused by the library function every door calls.
#[test]
fn library_doors_refuse_what_the_cli_refuses() {
    use mmbm::field::{flow_field, MAX_FIELD_PIXELS};
    use mmbm::io::frames::VideoFrame;
    use mmbm::metric::Scene;
    use mmbm::model::motion::Twist;
    let mut camera = Camera::thesis();
    (camera.width, camera.height) = (65535, 65535);
    let scene = Scene {
        camera,
        plane: None,
    };
    let tw = Twist::new(glam::DVec3::new(0.1, 0.2, 0.3), glam::DVec3::ZERO);
    let e = flow_field(
        &scene,
        &tw,
        0,
        0,
        mmbm::gpu::Backend::Cpu { threads: Some(1) },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("65535x65535") && e.contains(&MAX_FIELD_PIXELS.to_string()),
        "{e}"
    );
    // Python's resolution: integers checked by the library.
    let e = Camera::size_from(-1, 5).unwrap_err().to_string();
    assert!(e.contains("resolution") && e.contains("-1x5"), "{e}");
    assert!(Camera::size_from(1 << 33, 5).is_err());
    assert_eq!(Camera::size_from(640, 480).unwrap(), (640, 480));
    // Video frames with bad values, as Python passes them.
    let samples: Vec<_> = (0..200)
        .map(|k| mmbm::io::gyro::GyroSample {
            t: k as f64 * 0.005,
            omega: glam::DVec3::new(0.1, 0.2, 0.3),
            velocity: None,
            depth: None,
        })
        .collect();
    let opts = mmbm::series::SeriesOptions {
        scene: Scene {
            camera: Camera::thesis(),
            plane: None,
        },
        method: Default::default(),
        use_velocity: false,
    };
    let frame = |t_start: f64, exposure_s: f64, readout_s: Option<f64>| VideoFrame {
        t_start,
        exposure_s,
        readout_s,
    };
    let good = frame(0.1, 0.02, Some(0.01));
    let run = |f: VideoFrame| mmbm::series::frames::frame_mmbm(&samples, &opts, &[good, f]);
    assert!(run(good).is_ok());
    for (f, column) in [
        (frame(0.1, -0.5, None), "exposure_s"),
        (frame(0.1, f64::NAN, None), "exposure_s"),
        (frame(0.1, 0.02, Some(-0.5)), "readout_s"),
        (frame(0.1, 0.02, Some(f64::NAN)), "readout_s"),
        (frame(f64::NAN, 0.02, None), "t_start"),
    ] {
        let e = run(f).unwrap_err().to_string();
        assert!(e.contains("frame 1") && e.contains(column), "{f:?}: {e}");
    }
}

/// Issue #23 item 4: `simulate` wrote its log from one allocation of every
/// sample (8 GB at its cap of 1e8 samples, even into /dev/null); it streams
/// now, so 3e6 samples (240 MB held at once before) run in 150 MB of address
/// space.
#[cfg(unix)]
#[test]
fn simulate_streams_its_log() {
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 150000 && exec '{}' simulate --duration 30 --rate 100000 --out /dev/null",
            common::bin().display()
        ))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && err.contains("3000000 samples"),
        "{err}"
    );
}

/// Issue #23 item 3: every line reader holds a line of `MAX_LINE_BYTES` (not
/// counting its `\n`) and refuses one byte more, naming the file and line;
/// an image whose header claims more than `MAX_IMAGE_PIXELS` is refused
/// before decoding.
#[test]
fn line_and_image_caps_at_their_boundary() {
    use mmbm::io::input::{MAX_IMAGE_PIXELS, MAX_LINE_BYTES};
    let d = tempfile::tempdir().unwrap();
    // A line of exactly `len` bytes: a number field padded with zeros.
    let line = |prefix: &str, len: usize| {
        let mut s = prefix.to_string();
        s.push('1');
        s.push_str(&"0".repeat(len - prefix.len() - 1));
        s
    };
    let cases = [
        ("a.csv", "t,wx,wy,wz\n", "0,1,2,", "\n1,1,2,3\n", 2),
        (
            "a.gcsv",
            "GYROFLOW IMU LOG\ntscale,1\ngscale,1\nt,gx,gy,gz\n",
            "0,1,2,",
            "\n1,1,2,3\n",
            5,
        ),
        (
            "h.gcsv",
            "GYROFLOW IMU LOG\n",
            "note,",
            "\ntscale,1\ngscale,1\nt,gx,gy,gz\n0,1,2,3\n1,1,2,3\n",
            2,
        ),
    ];
    for (name, head, prefix, tail, no) in cases {
        for (len, over) in [(MAX_LINE_BYTES, false), (MAX_LINE_BYTES + 1, true)] {
            let text = format!("{head}{}{tail}", line(prefix, len));
            let p = write(d.path(), name, text.as_bytes());
            let r = read_log(&p, GyroOptions::default()).map(|_| ());
            let e = r.err().map(|e| e.to_string()).unwrap_or_default();
            let refused = e.contains("longer than");
            assert_eq!(refused, over, "{name}, a line of {len} bytes: {e}");
            if over {
                assert!(e.contains(&format!("{name}:{no}")), "{e}");
            }
        }
    }
    // The frame table.
    for (len, over) in [(MAX_LINE_BYTES, false), (MAX_LINE_BYTES + 1, true)] {
        let text = format!("t_start,exposure_s\n{}\n", line("0,", len));
        let p = write(d.path(), "frames.csv", text.as_bytes());
        let e = mmbm::io::frames::read_frames(&p)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert_eq!(e.contains("longer than"), over, "{e}");
    }
    // Images: read, and listed as a dataset texture.
    let side = (MAX_IMAGE_PIXELS as f64).sqrt() as u32;
    for (w, h, over) in [
        (side, side, false),
        (side, side + 1, true),
        (4 * side, 4 * side, true),
    ] {
        let p = write(d.path(), "big.png", &common::png_header(w, h));
        let e = mmbm::io::images::read_rgb8(&p).unwrap_err().to_string();
        assert_eq!(e.contains("the header declares"), over, "{w}x{h}: {e}");
        assert!(e.contains("big.png"), "{e}");
    }
}
