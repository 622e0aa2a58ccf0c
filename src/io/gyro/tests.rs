use super::*;
use std::io::Write;

fn log(text: &str) -> tempfile::NamedTempFile {
    let mut f = tempfile::Builder::new().suffix(".csv").tempfile().unwrap();
    f.write_all(text.as_bytes()).unwrap();
    f
}

fn err(text: &str) -> String {
    let f = log(text);
    match read_log(f.path(), GyroOptions::default()) {
        Ok(v) => panic!("expected an error, got {} samples", v.len()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn reads_valid_log_with_comments_units_and_rotation() {
    let f = log("# a comment\nt,wx,wy,wz,vx,vy,vz\n1000,90,0,0,1,2,3\n# mid\n2000,0,180,0,0,0,0\n");
    let opts = GyroOptions {
        time_unit: TimeUnit::Ms,
        angle_unit: AngleUnit::Deg,
        imu_to_camera: parse_rotation("0,-1,0,1,0,0,0,0,1").unwrap(),
        time_offset: 0.5,
        topic: None,
        gyroflow_rotation: None,
    };
    let v = read_log(f.path(), opts).unwrap();
    assert_eq!(v.len(), 2);
    assert!((v[0].t - 1.5).abs() < 1e-12 && (v[1].t - 2.5).abs() < 1e-12);
    let w = v[0].omega;
    assert!(
        (w - DVec3::new(0.0, std::f64::consts::FRAC_PI_2, 0.0)).length() < 1e-12,
        "{w}"
    );
    assert!((v[0].velocity.unwrap() - DVec3::new(-2.0, 1.0, 3.0)).length() < 1e-12);
}

#[test]
fn errors_name_file_line_and_column() {
    let e = err("t,wx,wy\n0,1,2\n");
    assert!(e.contains("wz") && e.contains("missing"), "{e}");
    let e = err("t,wx,wy,wz\n0,1,2,3\n0.1,1,abc,3\n");
    assert!(e.contains(":3:wy:") && e.contains("abc"), "{e}");
    let e = err("t,wx,wy,wz\n0,1,2,3\n0.1,1,NaN,3\n");
    assert!(e.contains(":3:wy:") && e.contains("not finite"), "{e}");
    let e = err("t,wx,wy,wz\n0,1,2,3\n0,1,2,3\n");
    assert!(
        e.contains(":3:t:") && e.contains("strictly increase"),
        "{e}"
    );
    let e = err("t,wx,wy,wz\n");
    assert!(e.contains("no samples"), "{e}");
    let e = err("t,wx,wy,wz\n0,1,2,3\n0.1,1,2\n");
    assert!(e.contains(":3:") && e.contains("field count"), "{e}");
    let e = err("t,wx,wy,wz,vx\n0,1,2,3,4\n");
    assert!(e.contains("vx,vy,vz"), "{e}");
    let missing = read_log(Path::new("/nonexistent/gyro.csv"), GyroOptions::default()).unwrap_err();
    assert!(missing.to_string().contains("/nonexistent/gyro.csv"));
}

#[test]
fn long_gap_is_a_warning_not_an_error() {
    let mut s = String::from("t,wx,wy,wz\n");
    for i in 0..200 {
        let t = if i < 150 {
            i as f64 * 0.01
        } else {
            10.0 + i as f64 * 0.01
        };
        s += &format!("{t},0,0,0\n");
    }
    let f = log(&s);
    let mut r = GyroReader::open(f.path(), GyroOptions::default()).unwrap();
    let n = r.by_ref().inspect(|x| assert!(x.is_ok())).count();
    assert_eq!(n, 200);
    assert_eq!(r.warnings().len(), 1, "{:?}", r.warnings());
    assert!(r.warnings()[0].contains("gap"));
}

#[test]
fn rejects_non_rotations() {
    assert!(parse_rotation("1,0,0,0,1,0,0,0,2").is_err());
    assert!(parse_rotation("1,0,0").is_err());
    assert!(parse_rotation("-1,0,0,0,1,0,0,0,1").is_err());
}
