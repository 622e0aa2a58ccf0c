//! Helpers of the bad-input suites (cli/tests/refusals/robustness.rs, cli/tests/refusals/robustness_round3.rs,
//! cli/tests/refusals/output_guard.rs):
//! the input files every case may name, leftovers in a folder, and the runner
//! of a table of bad inputs.
#![allow(dead_code)]

use super::common::mmbm_in;
use std::path::Path;

/// A gyro log with a 5 s gap after its first second.
pub fn gap_log() -> String {
    let mut s = String::from("t,wx,wy,wz\n");
    for k in 0..600 {
        s += &format!("{},0.1,0.2,0.3\n", k as f64 * 0.002);
    }
    for k in 0..600 {
        s += &format!("{},0.1,0.2,0.3\n", 6.2 + k as f64 * 0.002);
    }
    s
}

/// Input files every case can name (relative to its working directory).
pub fn files(dir: &Path) {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    w(
        "good.csv",
        "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n0.02,0.1,0.2,0.3\n0.03,0.1,0.2,0.3\n",
    );
    w("dup.csv", "t,wx,wy,wz,wx\n0,1,2,3,4\n");
    w("nonum.csv", "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,abc,0.2,0.3\n");
    w("ragged.csv", "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,0.2\n");
    w("nan.csv", "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,NaN,0.3\n");
    w(
        "backwards.csv",
        "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.02,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n",
    );
    w("empty.csv", "t,wx,wy,wz\n");
    w("nocol.csv", "t,wx,wy\n0,1,2\n");
    w(
        "huge.csv",
        "t,wx,wy,wz\n0,1e308,1e308,0\n0.01,1e308,1e308,0\n",
    );
    w(
        "longfield.csv",
        &format!("t,wx,wy,wz\n0,{},0,0\n", "9".repeat(3_000_000) + "x"),
    );
    w("gap.csv", &gap_log());
    w("calm.csv", &{
        let mut s = String::from("t,wx,wy,wz\n");
        for k in 0..2000 {
            s += &format!("{},2,2,2\n", k as f64 * 0.002);
        }
        s
    });
    w("gait.toml", "step_hz = 1e9\n");
    w("gait_type.toml", "step_hz = \"fast\"\n");
    w(
        "camera0.toml",
        "focal_mm = 0\npitch_mm = 0.00465\nwidth = 640\nheight = 480\n",
    );
    w("camera_key.toml", "focal = 4.2\n");
    w("exp_key.toml", "walkz = [\"slow\"]\n");
    w("exp_val.toml", "policies = [\"fixed:0\"]\n");
    w("not.png", "this is not an image");
    std::fs::write(dir.join("one.png"), one_red_pixel_png()).unwrap();
}

/// A 1x1 red PNG, written with the `image` crate.
pub fn one_red_pixel_png() -> Vec<u8> {
    let img = image::RgbImage::from_pixel(1, 1, image::Rgb([255, 0, 0]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// Names in `dir` besides the input files.
pub fn leftovers(dir: &Path, before: &[String]) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !before.contains(n))
        .collect();
    v.sort();
    v
}

/// What is wrong with a refusal `o` of `mmbm ARGS`: an exit code outside
/// `codes`, or a word of `words` missing from stderr (empty when none).
pub fn refusal_faults(o: &std::process::Output, codes: &[i32], words: &[&str]) -> Vec<String> {
    let err = String::from_utf8_lossy(&o.stderr);
    let mut why = Vec::new();
    if !o.status.code().is_some_and(|c| codes.contains(&c)) {
        why.push(format!("exit code {:?}", o.status.code()));
    }
    for w in words {
        if !err.contains(w) {
            why.push(format!("error does not say '{w}'"));
        }
    }
    why
}

/// One line of a suite's failure list: the command, what is wrong, and
/// (indented, at most 2000 characters) what it printed on stderr.
pub fn failure(args: &str, why: &[String], o: &std::process::Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr);
    format!(
        "mmbm {args}: {}\n    {}",
        why.join("; "),
        err.chars().take(2000).collect::<String>().trim()
    )
}

/// Runs every case of `table` in `dir` and returns how each one that is not
/// a clear error leaving nothing behind fails (exit code, panic, words,
/// stderr size, leftovers).
pub fn unclear_errors(dir: &Path, table: &[(&str, &[&str])]) -> Vec<String> {
    let before = leftovers(dir, &[]);
    let mut failures = Vec::new();
    for (args, words) in table {
        let argv: Vec<&str> = args.split_whitespace().collect();
        let o = mmbm_in(dir, &argv);
        let err = String::from_utf8_lossy(&o.stderr);
        let mut why = refusal_faults(&o, &[1, 2], words);
        if !err.contains("error:") || err.contains("panicked") {
            why.push("no error line, or a panic".into());
        }
        if err.len() > 2000 {
            why.push(format!(
                "{} bytes on stderr (echoes must be clipped)",
                err.len()
            ));
        }
        let left = leftovers(dir, &before);
        if !left.is_empty() {
            why.push(format!("left {left:?}"));
            for n in left {
                let _ = std::fs::remove_file(dir.join(&n));
                let _ = std::fs::remove_dir_all(dir.join(&n));
            }
        }
        if !why.is_empty() {
            failures.push(failure(args, &why, &o));
        }
    }
    failures
}
