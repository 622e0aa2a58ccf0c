use super::*;

#[test]
fn orientations() {
    let g = DVec3::new(1.0, 2.0, 3.0);
    assert_eq!(orientation_matrix("XYZ").unwrap(), DMat3::IDENTITY);
    assert_eq!(
        orientation_matrix("YxZ").unwrap() * g,
        DVec3::new(2.0, -1.0, 3.0)
    );
    assert_eq!(
        orientation_matrix("zXy").unwrap() * g,
        DVec3::new(-3.0, 1.0, -2.0)
    );
    assert_eq!(
        camera_matrix("XYZ").unwrap() * g,
        DVec3::new(-2.0, -1.0, -3.0)
    );
    assert_eq!(
        camera_matrix("YxZ").unwrap() * g,
        DVec3::new(1.0, -2.0, -3.0)
    );
    for o in ["XXZ", "xyzw", "XY", "", "XYA", "xYx", "ÄYZ"] {
        let e = orientation_matrix(o).unwrap_err().to_string();
        assert!(e.contains("orientation"), "{o}: {e}");
    }
    // Every valid orientation: the signed-axis map is the matrix.
    for p in ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"] {
        for signs in 0..8u8 {
            let o: String = p
                .chars()
                .enumerate()
                .map(|(i, c)| {
                    if signs >> i & 1 == 1 {
                        c.to_ascii_lowercase()
                    } else {
                        c
                    }
                })
                .collect();
            let axes = camera_axes(&parse_orientation(&o).unwrap());
            let m = camera_matrix(&o).unwrap();
            assert_eq!(axes_matrix(&axes), m, "{o}");
            assert!(
                (m.determinant().abs() - 1.0).abs() < 1e-15,
                "{o}: a signed permutation"
            );
        }
    }
    assert_eq!(GYROFLOW_TO_CAMERA.determinant(), 1.0);
}

#[test]
fn magic_lines() {
    assert!(is_magic(b"GYROFLOW IMU LOG"));
    assert!(is_magic(b"\xEF\xBB\xBFCAMERA IMU LOG \r"));
    assert!(!is_magic(b"GYROFLOW IMU LOGS"));
    assert!(!is_magic(b"t,wx,wy,wz"));
    assert!(ReadoutDirection::from_gyroflow("4").is_none());
    assert_eq!(
        ReadoutDirection::from_gyroflow("90"),
        Some(ReadoutDirection::RightToLeft)
    );
}
