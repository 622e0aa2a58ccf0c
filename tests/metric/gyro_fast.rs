//! The gyro CSV's fast path (a regular file read in blocks by a one-pass parser while
//! its rows are plain numbers) against the exact `csv`-crate reader
//! (`GyroReader::open_exact`): the same samples to the bit, the same
//! warnings (they name lines), and on spoiled files the same error text.

use mmbm::io::gyro::{GyroOptions, GyroReader, GyroSample};
use rand::{Rng, SeedableRng};
use std::io::Write;
use std::path::Path;

/// Everything a reader gives: the samples' bits and warnings, or the error.
type Outcome = Result<(Vec<[u64; 8]>, Vec<String>), String>;

fn bits(s: &GyroSample) -> [u64; 8] {
    let v = s.velocity.map(|v| v.to_array());
    [
        s.t.to_bits(),
        s.omega.x.to_bits(),
        s.omega.y.to_bits(),
        s.omega.z.to_bits(),
        v.map_or(1, |v| v[0].to_bits()),
        v.map_or(2, |v| v[1].to_bits()),
        v.map_or(3, |v| v[2].to_bits()),
        s.depth.map_or(4, f64::to_bits),
    ]
}

fn read(path: &Path, exact: bool) -> Outcome {
    let opts = GyroOptions::default();
    let mut r = match exact {
        true => GyroReader::open_exact(path, opts),
        false => GyroReader::open(path, opts),
    }
    .map_err(|e| e.to_string())?;
    let samples = r
        .by_ref()
        .map(|s| s.map(|s| bits(&s)))
        .collect::<mmbm::Result<Vec<_>>>()
        .map_err(|e| e.to_string())?;
    Ok((samples, r.warnings().to_vec()))
}

fn file(bytes: &[u8]) -> tempfile::NamedTempFile {
    let mut f = tempfile::Builder::new().suffix(".csv").tempfile().unwrap();
    f.write_all(bytes).unwrap();
    f.flush().unwrap();
    f
}

/// Both readers on `bytes`; panics if they differ. Returns the outcome.
fn same(bytes: &[u8], what: &str) -> Outcome {
    let f = file(bytes);
    let fast = read(f.path(), false);
    let exact = read(f.path(), true);
    assert!(
        fast == exact,
        "{what}: fast {:?} vs exact {:?}",
        summary(&fast),
        summary(&exact)
    );
    fast
}

fn summary(o: &Outcome) -> String {
    match o {
        Ok((s, w)) => format!("{} samples, warnings {w:?}", s.len()),
        Err(e) => format!("error {e}"),
    }
}

/// A log of `n` rows: the header `cols` (a permutation of the columns
/// read plus unread ones), numbers written in several ways, line ends
/// `\r\n` if `crlf`, the last line ended unless `open_end`, and a few gaps
/// (warnings, which name lines).
fn log(
    rng: &mut rand::rngs::StdRng,
    n: usize,
    cols: &[&str],
    crlf: bool,
    open_end: bool,
) -> Vec<u8> {
    let end = if crlf { "\r\n" } else { "\n" };
    let mut s = cols.join(",");
    let mut t = 0.0f64;
    for i in 0..n {
        s += end;
        t += if i % 997 == 500 { 0.5 } else { 0.005 };
        let row: Vec<String> = cols
            .iter()
            .map(|&c| match c {
                "t" => format!("{t:.6}"),
                "note" => ["x", "", "a b", "a#1"][i % 4].to_string(),
                _ => {
                    let x: f64 = rng.gen_range(-3.0..3.0);
                    match rng.gen_range(0..6) {
                        0 => format!("{x:.9}"),
                        1 => format!("{x:.17}"),
                        2 => format!("{x}"),
                        3 => format!("{x:e}"),
                        4 => format!(" {x:.3} "),
                        _ => format!("{}", (x * 100.0).round() as i64),
                    }
                }
            })
            .collect();
        s += &row.join(",");
    }
    if !open_end {
        s += end;
    }
    s.into_bytes()
}

const PLAIN: &[&str] = &["t", "wx", "wy", "wz"];
const FULL: &[&str] = &["note", "wz", "vx", "t", "depth", "vy", "wy", "vz", "wx"];

#[test]
fn fast_path_gives_the_exact_readers_samples_and_warnings() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(24);
    // Sizes around the 2 MB block (about 45 bytes a plain row).
    for n in [1, 2, 7, 1000, 46_000, 120_000] {
        for cols in [PLAIN, FULL] {
            for crlf in [false, true] {
                for open_end in [false, true] {
                    if n > 10_000 && (cols == FULL || open_end) {
                        continue;
                    }
                    let text = log(&mut rng, n, cols, crlf, open_end);
                    let what = format!("{n} rows of {cols:?}, crlf {crlf}, open end {open_end}");
                    let (samples, warnings) = same(&text, &what).unwrap();
                    assert_eq!(samples.len(), n, "{what}");
                    assert_eq!(warnings.is_empty(), n < 600, "{what}: {warnings:?}");
                }
            }
        }
    }
}

/// `text` with row `row` (0: the header) replaced by `with`.
fn spoil(text: &[u8], row: usize, with: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    for (i, line) in text.split_inclusive(|&b| b == b'\n').enumerate() {
        if i == row {
            out.extend_from_slice(with);
        } else {
            out.extend_from_slice(line);
        }
    }
    out
}

#[test]
fn spoiled_logs_fail_or_pass_as_the_exact_reader() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(25);
    let spoils: &[&[u8]] = &[
        b"0.1,1,abc,3\n",
        b"9,1,NaN,3\n",
        b"9,1,inf,3\n",
        b"9,1,2\n",
        b"9,1,2,3,4\n",
        b"\n",
        b"\r\n",
        b"# a comment\n",
        b"\"9\",1,2,3\n",
        b"9,\"1\",2,3\n",
        b"9,1,2,3\r",
        b"9,1\r,2,3\n",
        b"9,1,2,3\r\r\n",
        b"9,1,\xff,3\n",
        b"9,1,\xc2\xa02,3\n",
        b"0,1,2,3\n",
        b"1e9,1,2,3\n",
        b" ,1,2,3\n",
        b"9,1,2,3",
    ];
    for n in [3, 60_000] {
        for crlf in [false, true] {
            let text = log(&mut rng, n, PLAIN, crlf, false);
            for row in [1, 2, n / 2, n - 1, n] {
                for &s in spoils {
                    let bad = spoil(&text, row, s);
                    let what = format!(
                        "{n} rows, crlf {crlf}, row {row} = {:?}",
                        String::from_utf8_lossy(s)
                    );
                    let _ = same(&bad, &what);
                }
            }
        }
    }
    // The header line itself, and what comes before it; tiny files.
    let text = log(&mut rng, 5, PLAIN, false, false);
    let heads: &[&[u8]] = &[
        b"# c\nt,wx,wy,wz\n",
        b"\nt,wx,wy,wz\n",
        b"\"t\",wx,wy,wz\n",
        b"t,wx,wy,wz\r\n",
        b"t,wx,wy\n",
    ];
    let tiny: &[&[u8]] = &[
        b"",
        b"t,wx,wy,wz",
        b"t,wx,wy,wz\n",
        b"t,wx,wy,wz\r\n",
        b"t,wx,wy,wz\n\n",
        b"t,wx,wy,wz\n0,1,2,3",
    ];
    let files = heads
        .iter()
        .map(|h| spoil(&text, 0, h))
        .chain(tiny.iter().map(|t| t.to_vec()));
    for bytes in files {
        let _ = same(&bytes, &format!("{:?}", String::from_utf8_lossy(&bytes)));
    }
}

#[test]
fn a_line_over_the_cap_after_clean_blocks_is_the_exact_readers_error() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(26);
    let text = log(&mut rng, 60_000, PLAIN, false, false);
    let mut long = b"9,1,2,".to_vec();
    long.resize(5 << 20, b'3');
    long.push(b'\n');
    let e = same(&spoil(&text, 50_000, &long), "a 5 MB line").unwrap_err();
    assert!(e.contains(":50001:") && e.contains("longer than"), "{e}");
}
