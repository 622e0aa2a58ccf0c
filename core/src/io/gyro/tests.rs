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

#[test]
fn a_reflection_names_its_determinant_and_the_proper_rotation() {
    // Not orthonormal: the determinant is named, no rotation suggested.
    let e = parse_rotation("1,0,0,0,1,0,0,0,2").unwrap_err().to_string();
    assert!(e.contains("determinant 2") && !e.contains("negated"), "{e}");
    // A reflection of x: negating row 1 gives the identity (the smallest rotation).
    let e = parse_rotation("-1,0,0,0,1,0,0,0,1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("determinant is -1"), "{e}");
    assert!(e.contains("row 1 negated it is '1,0,0,0,1,0,0,0,1'"), "{e}");
    // An axis swap (x <-> y): rows 1 and 2 both give a 90 degree turn; row 1 is named.
    let e = parse_rotation("0,1,0,1,0,0,0,0,1").unwrap_err().to_string();
    assert!(
        e.contains("row 1 negated it is '0,-1,0,1,0,0,0,0,1'"),
        "{e}"
    );
    // Every suggestion is accepted, for every signed permutation with det -1.
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut reflections = 0;
    for p in perms {
        for signs in 0..8 {
            let mut v = [0.0f64; 9];
            for r in 0..3 {
                v[3 * r + p[r]] = if signs >> r & 1 == 1 { -1.0 } else { 1.0 };
            }
            let text: Vec<String> = v.iter().map(|x| x.to_string()).collect();
            let text = text.join(",");
            let m = glam::DMat3::from_cols_array(&v).transpose();
            if m.determinant() > 0.0 {
                assert!(parse_rotation(&text).is_ok(), "{text}");
                continue;
            }
            reflections += 1;
            let e = parse_rotation(&text).unwrap_err().to_string();
            let suggested = e.split("negated it is '").nth(1).unwrap();
            let suggested = &suggested[..suggested.find('\'').unwrap()];
            let r = parse_rotation(suggested).unwrap();
            // Exactly one row differs, by its sign.
            let diff = (0..3)
                .filter(|&i| (r.row(i) - m.row(i)).length() > 1e-12)
                .collect::<Vec<_>>();
            assert_eq!(diff.len(), 1, "{text} -> {suggested}");
            assert!((r.row(diff[0]) + m.row(diff[0])).length() < 1e-12);
        }
    }
    assert_eq!(reflections, 24);
}

/// The records of `text` by the fast path with `block` and `piece` bytes,
/// as (line, values) — `Err` where it hands over to the exact reader.
fn fast_records(
    text: &[u8],
    block: usize,
    piece: usize,
) -> std::result::Result<Vec<String>, fast::Unusual> {
    let f = log(std::str::from_utf8(text).unwrap());
    let exact =
        CsvSource::open_file(std::fs::File::open(f.path()).unwrap(), f.path(), false).unwrap();
    let file = std::fs::File::open(f.path()).unwrap();
    let mut rows = fast::FastRows::with_sizes(file, exact.layout(), block, piece);
    let mut out = Vec::new();
    while let Some(r) = rows.next_raw()? {
        out.push(format!("{r:?}"));
    }
    Ok(out)
}

/// The same by the exact reader.
fn exact_records(text: &[u8]) -> Vec<String> {
    let f = log(std::str::from_utf8(text).unwrap());
    let mut exact =
        CsvSource::open_file(std::fs::File::open(f.path()).unwrap(), f.path(), false).unwrap();
    let mut out = Vec::new();
    while let Some(r) = exact.next_raw().unwrap() {
        out.push(format!("{r:?}"));
    }
    out
}

#[test]
fn fast_path_at_every_block_and_piece_boundary() {
    // Mixed line ends (the exact reader numbers a record after a `\r\n`
    // line one lower), spaces, an unread column, every number form.
    let texts = [
        "t,wx,wy,wz,note\r\n0,0.1,-2,3e-3,a\n0.5, 1 ,.5,-0,\r\n1,2,3,4,x y\r\n1.5,1,2,3,z\n2,-1.25,0.000001,7,w",
        "wz,t,depth,wy,vx,vy,wx,vz\n1,0,2,3,4,5,6,7\n1,1,2,3,4,5,6,7\r\n1,2,2,3,4,5,6,7\n",
    ];
    for text in texts {
        let text = text.as_bytes();
        let want = exact_records(text);
        assert!(want.len() >= 3, "{want:?}");
        for block in 1..=text.len() + 1 {
            for piece in [1, 2, 3, 5, 8, 13, 21, 34, 1000] {
                let got = fast_records(text, block, piece);
                assert_eq!(got.as_ref(), Ok(&want), "block {block}, piece {piece}");
            }
        }
    }
    // What the fast path leaves to the exact reader.
    for text in [
        "t,wx,wy,wz\n0,1,2,3\n\n1,1,2,3\n",
        "t,wx,wy,wz\n0,1,2,3\n#c\n1,1,2,3\n",
        "t,wx,wy,wz\n0,1,2,\"3\"\n",
        "t,wx,wy,wz\n0,1,2,3\r1,1,2,3\n",
        "t,wx,wy,wz\n0,1,2\n",
        "t,wx,wy,wz\n0,1,2,x\n",
        "t,wx,wy,wz\n0,1,2,inf\n",
        "# c\nt,wx,wy,wz\n0,1,2,3\n",
        "t,wx,wy,wz\n",
    ] {
        for block in [1, 4, 1000] {
            assert_eq!(
                fast_records(text.as_bytes(), block, 3),
                Err(fast::Unusual),
                "{text:?}"
            );
        }
    }
}
