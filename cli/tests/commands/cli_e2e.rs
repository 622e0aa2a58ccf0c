//! End-to-end runs of the commands other tests drive through the library:
//! `simulate`, `trigger`, `render --maps --psf --sharp`, `tables --plot`, and
//! the blur length of `eval`/`series --exposure`.

use crate::common;

use common::mmbm_ok_in;

#[test]
fn simulate_then_trigger() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    for out in ["a.csv", "b.csv"] {
        let args = "simulate --gait fast --duration 4 --rate 500 --seed 3 --out";
        let mut argv: Vec<&str> = args.split(' ').collect();
        argv.push(out);
        mmbm_ok_in(p, &argv);
    }
    let a = std::fs::read_to_string(p.join("a.csv")).unwrap();
    assert_eq!(
        a,
        std::fs::read_to_string(p.join("b.csv")).unwrap(),
        "same seed, same bytes"
    );
    let rows: Vec<&str> = a.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(rows[0], "t,wx,wy,wz,vx,vy,vz");
    assert_eq!(rows.len() - 1, 2000, "4 s at 500 Hz");
    let o = mmbm_ok_in(
        p,
        &[
            "trigger",
            "--gyro",
            "a.csv",
            "--policy",
            "fixed:5",
            "--policy",
            "threshold:0.8",
            "--exposure",
            "0.05",
        ],
    );
    let out = String::from_utf8(o.stdout).unwrap();
    let mut lines = out.lines();
    assert_eq!(
        lines.next().unwrap(),
        "policy,trigger_t,exposure_start,exposure_end,mmbm_trigger_mm_s,mmbm_exposure_mm_s,kept,gain"
    );
    let fixed = lines.clone().filter(|l| l.starts_with("fixed:5,")).count();
    assert!((18..=20).contains(&fixed), "{fixed} fixed frames in 4 s");
    for l in lines {
        let f: Vec<f64> = l.split(',').skip(1).map(|x| x.parse().unwrap()).collect();
        assert!(
            (f[1] - f[0] - 0.0025).abs() < 1e-12 && (f[2] - f[1] - 0.05).abs() < 1e-12,
            "{l}"
        );
    }
    let o = mmbm_ok_in(
        p,
        &[
            "trigger",
            "--gyro",
            "a.csv",
            "--policy",
            "fixed:5",
            "--exposure",
            "0.05",
            "--summary",
            "--out",
            "summary-frames.csv",
        ],
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("fixed:5:"));
}

#[test]
fn render_writes_image_maps_psf_and_sharp() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    mmbm_ok_in(
        p,
        &[
            "render",
            "--omega",
            "0.2,-0.1,0.8",
            "--exposure",
            "0.05",
            "--target",
            "checker:0.02",
            "--distance",
            "1",
            "--resolution",
            "64x48",
            "--backend",
            "cpu",
            "--out",
            "b.png",
            "--maps",
            "m.exr",
            "--psf",
            "32,24:psf.exr",
            "--sharp",
            "s.exr",
        ],
    );
    let img = image::open(p.join("b.png")).unwrap();
    assert_eq!((img.width(), img.height()), (64, 48));
    let (w, h, maps) = mmbm::io::images::read_exr(&p.join("m.exr")).unwrap();
    assert_eq!((w, h), (64, 48));
    let names: Vec<&str> = maps.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["disp_px", "path_px", "speed_px_s"]);
    let path = &maps[1].1;
    let disp = &maps[0].1;
    assert!(path
        .iter()
        .zip(disp)
        .all(|(p, d)| *p >= *d - 1e-4 && *d >= 0.0));
    let (_, _, psf) = mmbm::io::images::read_exr(&p.join("psf.exr")).unwrap();
    let total: f64 = psf[0].1.iter().map(|&x| x as f64).sum();
    assert!((total - 1.0).abs() < 1e-4, "PSF weights sum to {total}");
    let (_, _, sharp) = mmbm::io::images::read_exr(&p.join("s.exr")).unwrap();
    assert_eq!(sharp.len(), 3);
}

#[test]
fn tables_plot_is_a_png() {
    let d = tempfile::tempdir().unwrap();
    mmbm_ok_in(d.path(), &["tables", "--plot", "fig.png"]);
    let img = image::open(d.path().join("fig.png")).unwrap();
    assert!(img.width() >= 400 && img.height() >= 300);
}

#[test]
fn exposure_gives_the_blur_length() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let o = mmbm_ok_in(
        p,
        &["eval", "--omega", "1,1,1", "--exposure", "0.05", "--json"],
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let px = v["mmbm_px_s"].as_f64().unwrap();
    assert_eq!(v["blur_px"].as_f64().unwrap(), px * 0.05);
    mmbm_ok_in(p, &["simulate", "--duration", "1", "--out", "w.csv"]);
    let o = mmbm_ok_in(p, &["series", "--gyro", "w.csv", "--exposure", "0.07"]);
    let out = String::from_utf8(o.stdout).unwrap();
    let mut lines = out.lines();
    assert_eq!(lines.next().unwrap(), "t,mmbm_mm_s,mmbm_px_s,blur_px");
    for l in lines {
        let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        assert_eq!(f[3], f[1] / 0.00465 * 0.07, "{l}");
    }
}
