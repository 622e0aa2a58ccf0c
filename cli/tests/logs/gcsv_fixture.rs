//! The `.gcsv` walk fixture (`tests/fixtures/gcsv/walk.gcsv`) and helpers to
//! spoil it, shared by `cli/tests/logs/gcsv.rs` and `cli/tests/logs/gcsv_gyroflow.rs`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub fn walk() -> PathBuf {
    crate::common::repo_root().join("tests/fixtures/gcsv/walk.gcsv")
}

pub fn walk_text() -> String {
    std::fs::read_to_string(walk()).unwrap()
}

pub const TSCALE: f64 = 0.001;
pub const GSCALE: f64 = 0.00122173047;
/// The fixture's column line is line 18; samples start on line 19.
pub const FIRST_ROW_LINE: usize = 19;

/// The fixture's raw rows: (t, gx, gy, gz) as written.
pub fn raw_rows(text: &str) -> Vec<[f64; 4]> {
    text.lines()
        .skip(FIRST_ROW_LINE - 1)
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [f[0], f[1], f[2], f[3]]
        })
        .collect()
}

/// `text` with line `n` (1-based) replaced.
pub fn with_line(text: &str, n: usize, new: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines[n - 1] = new;
    lines.join("\n") + "\n"
}

pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}
