//! End-to-end checks of the core CLI contract: `eval`, `series`, `tables`.

use crate::common;

use common::mmbm;
use std::path::Path;

fn json(args: &[&str]) -> serde_json::Value {
    let o = mmbm(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

#[test]
fn eval_json_contract() {
    let v = json(&["eval", "--omega", "1,1,1", "--json"]);
    assert_eq!(v["method"], "riemann:8x6");
    let mm = v["mmbm_mm_s"].as_f64().unwrap();
    assert!((mm - 6.2514).abs() < 2.5e-4, "{mm}");
    assert!((v["mmbm_px_s"].as_f64().unwrap() - mm / 0.00465).abs() < 1e-6);
    assert!(v.get("error_estimate").is_none());

    let v = json(&[
        "eval",
        "--omega",
        "1,1,1",
        "--method",
        "exact:1e-11",
        "--json",
    ]);
    assert!((v["mmbm_mm_s"].as_f64().unwrap() - 6.2563777263).abs() < 1e-8);
    assert!(v["error_estimate"].as_f64().unwrap() < 1e-9);

    // Table 4.4 row through the CLI: translation with a depth.
    let v = json(&[
        "eval",
        "--omega",
        "0,0,0",
        "--velocity",
        "0.25,0.125,-1",
        "--depth",
        "1",
        "--json",
    ]);
    assert!((v["mmbm_mm_s"].as_f64().unwrap() - 1.4329).abs() < 2.5e-4);
    // A tilted plane, negative numbers in the list.
    let v = json(&[
        "eval",
        "--omega",
        "-0.1,0.2,0",
        "--velocity",
        "0,0,1",
        "--plane",
        "0,-0.3,1,2",
        "--method",
        "gauss:8",
        "--json",
    ]);
    // Against an independent midpoint sum of docs/spec.md section 3 (thesis eq. 3.20) over the sensor
    // (1280 x 960 cells, f64), with the tilted plane's per-pixel depth.
    let (f, p, w, h) = (4.2548, 0.00465, 640.0, 480.0);
    let (wx, wy, wz, vx, vy, vz) = (-0.1, 0.2, 0.0, 0.0, 0.0, 1.0);
    let (n, d) = ([0.0, -0.3, 1.0], 2.0);
    let (nu, nv) = (1280, 960);
    let mut sum = 0.0;
    for j in 0..nv {
        for i in 0..nu {
            let u = ((i as f64 + 0.5) / nu as f64 - 0.5) * w * p;
            let v = ((j as f64 + 0.5) / nv as f64 - 0.5) * h * p;
            let z = d / (n[0] * u / f + n[1] * v / f + n[2]);
            let du =
                wz * v - wy * f - (wy / f) * u * u + (wx / f) * u * v - (f / z) * vx + (u / z) * vz;
            let dv = -wz * u + wx * f - (wy / f) * u * v + (wx / f) * v * v - (f / z) * vy
                + (v / z) * vz;
            sum += du.hypot(dv);
        }
    }
    let reference = sum / (nu * nv) as f64;
    let got = v["mmbm_mm_s"].as_f64().unwrap();
    assert!(
        (got - reference).abs() < 1e-5 * reference,
        "{got} vs {reference}"
    );
}

#[test]
fn eval_errors_are_clear_and_nonzero() {
    for (args, needle) in [
        (
            vec!["eval", "--omega", "0,0,0", "--velocity", "1,0,0"],
            "depth",
        ),
        (vec!["eval", "--omega", "1,0"], "three"),
        (vec!["eval", "--omega", "nan,0,0"], "finite"),
        (vec!["eval", "--omega", "1,0,0", "--focal", "0"], "focal"),
        (
            vec![
                "eval",
                "--omega",
                "0,0,0",
                "--velocity",
                "1,0,0",
                "--depth",
                "-2",
            ],
            "depth",
        ),
        (
            vec![
                "eval",
                "--omega",
                "0,0,0",
                "--velocity",
                "1,0,0",
                "--plane",
                "0,0,1,-3",
            ],
            "behind",
        ),
        (
            vec!["eval", "--omega", "1,0,0", "--method", "simpson"],
            "method",
        ),
        (
            vec![
                "eval",
                "--omega",
                "1,0,0",
                "--camera",
                "/nonexistent/cam.toml",
            ],
            "/nonexistent/cam.toml",
        ),
    ] {
        let o = mmbm(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn camera_file_is_used() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("cam.toml");
    std::fs::write(
        &p,
        "focal_mm = 8.5095\npitch_mm = 0.00465\nwidth = 640\nheight = 480\n",
    )
    .unwrap();
    // Lateral translation scales with f: 2x the thesis focal length, 2x Table 4.1's 8.5095.
    let v = json(&[
        "eval",
        "--omega",
        "0,0,0",
        "--velocity",
        "1,0,0",
        "--depth",
        "0.5",
        "--camera",
        p.to_str().unwrap(),
        "--json",
    ]);
    assert!((v["mmbm_mm_s"].as_f64().unwrap() - 2.0 * 8.5095).abs() < 1e-3);
    std::fs::write(&p, "focal_mm = 4\nwidth = 640\n").unwrap();
    let o = mmbm(&["eval", "--omega", "1,0,0", "--camera", p.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("cam.toml"));
}

fn write_log(dir: &Path, n: usize) -> std::path::PathBuf {
    let p = dir.join("gyro.csv");
    let mut s = String::from("# test log\nt,wx,wy,wz\n");
    for i in 0..n {
        let t = i as f64 / 600.0;
        s += &format!(
            "{t},{},{},{}\n",
            (7.0 * t).sin(),
            0.5 * (3.0 * t).cos(),
            0.1
        );
    }
    std::fs::write(&p, s).unwrap();
    p
}

#[test]
fn series_contract_round_trips_and_matches_eval() {
    let d = tempfile::tempdir().unwrap();
    let log = write_log(d.path(), 1000);
    let out = d.path().join("mmbm.csv");
    let o = mmbm(&[
        "series",
        "--gyro",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,mmbm_mm_s,mmbm_px_s");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 1000);
    // Spot-check a row against `eval` with the same angular velocity.
    let t: f64 = rows[123][0];
    let w = format!("{},{},{}", (7.0 * t).sin(), 0.5 * (3.0 * t).cos(), 0.1);
    let v = json(&["eval", "--omega", &w, "--json"]);
    assert!((rows[123][1] - v["mmbm_mm_s"].as_f64().unwrap()).abs() < 1e-7);
    assert!((rows[123][2] - rows[123][1] / 0.00465).abs() < 1e-6);
}

#[test]
fn series_bad_log_names_line_and_leaves_no_file() {
    let d = tempfile::tempdir().unwrap();
    let log = d.path().join("bad.csv");
    std::fs::write(&log, "t,wx,wy,wz\n0,0,0,0\n0.1,0,x,0\n").unwrap();
    let out = d.path().join("out.csv");
    let o = mmbm(&[
        "series",
        "--gyro",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.csv:3:wy"), "{err}");
    assert!(!out.exists(), "no half-written output");
    assert_eq!(
        std::fs::read_dir(d.path()).unwrap().count(),
        1,
        "no temp files left"
    );
}

#[test]
fn tables_print_all_and_json_parses() {
    let o = mmbm(&["tables"]);
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    for t in [
        "Table 4.1",
        "Table 4.2",
        "Table 4.3",
        "Table 4.4",
        "Table 4.5",
        "Fig. 4.6",
        "64x48",
    ] {
        assert!(s.contains(t), "missing {t}");
    }
    let v = json(&["tables", "--json"]);
    assert_eq!(v["tables"].as_array().unwrap().len(), 5);
    assert_eq!(v["grid_error"].as_array().unwrap().len(), 14);
}

/// Issue #22: `render` had both `--sensor` and its own `--resolution`; they
/// are one flag now (`--resolution` its alias), so giving both is a usage
/// error, and either gives the same image.
#[test]
fn render_resolution_is_the_sensor_flag() {
    let d = tempfile::tempdir().unwrap();
    let base =
        "render --omega 0.2,0.1,0 --exposure 0.02 --target checker:0.05 --distance 1 --backend cpu";
    let run = |extra: &str| {
        let args: Vec<String> = format!("{base} {extra}")
            .split_whitespace()
            .map(String::from)
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        common::mmbm_in(d.path(), &args)
    };
    let both = run("--sensor 32x24 --resolution 32x24 --out both.png");
    assert_eq!(
        both.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&both.stderr)
    );
    for (flag, out) in [("--sensor", "s.png"), ("--resolution", "r.png")] {
        let o = run(&format!("{flag} 32x24 --out {out}"));
        assert!(
            o.status.success(),
            "{flag}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let s = std::fs::read(d.path().join("s.png")).unwrap();
    assert_eq!(s, std::fs::read(d.path().join("r.png")).unwrap());
    assert_eq!(image::load_from_memory(&s).unwrap().width(), 32);
}
