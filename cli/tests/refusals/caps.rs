//! Caps checked before the work (issue 35): the blur maps' pixels, the
//! light of a sensor (and shot noise bounded for every mean), the lists of an
//! experiment config, `assess`'s pixels; and the first hour of a new user
//! (no loader noise on stderr, `trigger --summary` keeps the CSV, the
//! policy forms in `trigger --help`). Each reproducer must end quickly with
//! a clear one-line error (exit 1) or a result, never abort or spin.

use crate::common;

use common::{mmbm_in, mmbm_within};
use std::path::Path;
use std::time::{Duration, Instant};

/// Runs `mmbm ARGS` in `dir` (stdin empty), failing if it takes over `secs` s.
fn quick(dir: &Path, args: &[&str], secs: u64) -> std::process::Output {
    mmbm_within(dir, args, Vec::new(), secs)
}

/// Asserts a refusal: exit 1, one `error:` line containing every word.
fn refused(o: &std::process::Output, words: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    for w in words {
        assert!(lines[0].contains(w), "'{w}' not in {err}");
    }
}

/// A 1 s gyro log at 600 Hz, a one-frame table and a camera file of `w` x `h`.
fn frames_inputs(dir: &Path, w: u64, h: u64) {
    let mut log = String::from("t,wx,wy,wz\n");
    for i in 0..=600 {
        log += &format!("{},0.3,0.2,0.1\n", i as f64 / 600.0);
    }
    std::fs::write(dir.join("g.csv"), log).unwrap();
    std::fs::write(dir.join("f.csv"), "t_start,exposure_s\n0.1,0.02\n").unwrap();
    std::fs::write(
        dir.join("cam.toml"),
        format!("focal_mm = 4.0\npitch_mm = 0.0014\nwidth = {w}\nheight = {h}\n"),
    )
    .unwrap();
}

#[test]
fn maps_refuse_a_huge_camera_on_every_backend_before_any_work() {
    let d = tempfile::tempdir().unwrap();
    let cap = mmbm::limits::MAX_MAP_PIXELS;
    for (w, h) in [
        (100_000u64, 100_000u64),
        (8193, 8192),
        (1 << 13, (1 << 12) + 1),
    ] {
        assert!(w * h > cap);
        frames_inputs(d.path(), w, h);
        for backend in ["bulk", "cpu", "gpu", "auto"] {
            let t = Instant::now();
            let o = quick(
                d.path(),
                &[
                    "frames",
                    "--gyro",
                    "g.csv",
                    "--frames",
                    "f.csv",
                    "--camera",
                    "cam.toml",
                    "--maps",
                    "maps",
                    "--backend",
                    backend,
                ],
                20,
            );
            refused(&o, &["camera", &format!("{w}x{h}"), &cap.to_string()]);
            assert!(t.elapsed() < Duration::from_secs(10), "{backend}");
            assert!(!d.path().join("maps").exists(), "nothing made");
        }
    }
    // The library's doors: the rays (Python's `frames(maps=True)`) and the writer.
    let cam = mmbm::Camera::new(4.0, 0.0014, 100_000, 100_000);
    let e = mmbm::series::maps::MapRays::new(&cam)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("100000x100000") && e.contains(&cap.to_string()),
        "{e}"
    );
    // At the cap exactly the size is accepted (only the check is run here).
    let at = mmbm::Camera::new(4.0, 0.0014, 1 << 13, 1 << 12);
    assert!(mmbm::series::maps::check_size(&at).is_ok());
}

#[test]
fn absurd_light_is_refused_through_every_door() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let render = [
        "render",
        "--omega",
        "0,0,0",
        "--resolution",
        "32x24",
        "--target",
        "checker:0.02",
        "--distance",
        "1",
        "--exposure",
        "0.05",
        "--out",
        "r.png",
    ];
    // The flag.
    let mut args = render.to_vec();
    args.extend(["--light", "1e308"]);
    refused(&quick(p, &args, 20), &["--light", "1e308", "1e12"]);
    // A camera file.
    std::fs::write(
        p.join("cam.toml"),
        "focal_mm = 4.0\npitch_mm = 0.0014\nwidth = 32\nheight = 24\n\
         [noise]\nphi_e_per_s = 1e308\n",
    )
    .unwrap();
    let mut args = render.to_vec();
    args.extend(["--camera", "cam.toml"]);
    refused(&quick(p, &args, 20), &["noise.phi_e_per_s", "1e12"]);
    assert!(!p.join("r.png").exists());
    // An experiment's map and its camera.
    for (section, key) in [
        (
            "[map]\nlights_e_per_s = [1000.0, 1e305]\n",
            "map.lights_e_per_s",
        ),
        ("[camera.noise]\nphi_e_per_s = 1e308\n", "noise.phi_e_per_s"),
    ] {
        std::fs::write(p.join("x.toml"), section).unwrap();
        let o = quick(p, &["experiment", "--config", "x.toml", "--out", "xo"], 20);
        refused(&o, &[key, "1e12", "x.toml"]);
        assert!(!p.join("xo").exists());
    }
    // A dataset's camera.
    std::fs::write(
        p.join("ds.toml"),
        "count = 2\n[camera.noise]\nphi_e_per_s = 1e306\n",
    )
    .unwrap();
    let o = quick(
        p,
        &["dataset", "--quiet", "--config", "ds.toml", "--out", "ds"],
        20,
    );
    refused(&o, &["phi_e_per_s", "1e12"]);
    // A task policy's stated light.
    let o = quick(
        p,
        &["trigger", "--gyro", "-", "--policy", "task:5:light=1e308"],
        20,
    );
    assert_eq!(o.status.code(), Some(2), "clap parses the policy");
    assert!(String::from_utf8_lossy(&o.stderr).contains("1e12"));
}

#[test]
fn absurd_means_under_the_cap_finish_with_a_saturated_image() {
    // 1e12 e-/s over 1e294 s: a mean of about 1e305 e-, where the exact
    // Poisson sampler spins; the bounded one saturates the frame at once.
    let d = tempfile::tempdir().unwrap();
    let o = quick(
        d.path(),
        &[
            "render",
            "--omega",
            "0,0,0",
            "--resolution",
            "32x24",
            "--target",
            "checker:0.02",
            "--distance",
            "1",
            "--exposure",
            "1e294",
            "--light",
            "1e12",
            "--backend",
            "cpu",
            "--out",
            "r.png",
        ],
        30,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(d.path().join("r.png")).unwrap().to_luma8();
    let white = img.pixels().filter(|p| p.0[0] == 255).count();
    // The checker's white squares (about half the frame) are saturated.
    assert!(white * 4 > img.len(), "{white} of {}", img.len());
}

/// An experiment config whose `key` (in `section`) lists `n` entries.
fn long_list(section: &str, key: &str, value: &str, n: usize) -> String {
    let list = vec![value; n].join(", ");
    format!("{section}{key} = [{list}]\n")
}

#[test]
fn experiment_lists_are_capped_naming_the_key() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let n = 100_000;
    for (section, key, value, name) in [
        ("", "sweep_exposures_s", "0.01", "sweep_exposures_s"),
        ("", "policies", "\"fixed:5\"", "policies"),
        ("[map]\n", "lights_e_per_s", "1000.0", "map.lights_e_per_s"),
        (
            "[map]\nlights_e_per_s = [1000.0]\n",
            "grid_ms",
            "3.0",
            "map.grid_ms",
        ),
    ] {
        std::fs::write(p.join("x.toml"), long_list(section, key, value, n)).unwrap();
        let t = Instant::now();
        let o = quick(p, &["experiment", "--config", "x.toml", "--out", "xo"], 20);
        refused(&o, &[name, "100000 entries", "at most 100", "x.toml"]);
        assert!(t.elapsed() < Duration::from_secs(10), "{name}");
        assert!(!p.join("xo").exists());
    }
    // At the cap a list is accepted (validation only).
    let mut cfg = mmbm_lab::experiment::ExperimentConfig {
        sweep_exposures_s: vec![0.01; mmbm::limits::MAX_LIST_ENTRIES],
        ..Default::default()
    };
    assert!(cfg.validate().is_ok());
    cfg.sweep_exposures_s.push(0.01);
    assert!(cfg.validate().is_err());
}

/// A real, decodable `side` x `side` all-black 8-bit grey PNG, made cheaply:
/// its zlib stream is written by hand (fixed Huffman codes: one literal 0,
/// then matches of 258 bytes at distance 1, 13 bits each), about 1 MB for
/// 13000 x 13000 (169 MB of pixels).
fn black_png(side: u32) -> Vec<u8> {
    struct Bits {
        out: Vec<u8>,
        acc: u64,
        n: u32,
    }
    impl Bits {
        /// `len` bits of `v`, least significant first (deflate's order).
        fn put(&mut self, v: u64, len: u32) {
            self.acc |= v << self.n;
            self.n += len;
            while self.n >= 8 {
                self.out.push(self.acc as u8);
                self.acc >>= 8;
                self.n -= 8;
            }
        }
        /// A Huffman code of `len` bits, most significant first.
        fn code(&mut self, c: u64, len: u32) {
            let rev = (0..len).fold(0, |r, i| r | (((c >> i) & 1) << (len - 1 - i)));
            self.put(rev, len);
        }
    }
    let n = side as u64 * (side as u64 + 1); // a filter byte (0) per row
    let mut b = Bits {
        out: vec![0x78, 0x01],
        acc: 0,
        n: 0,
    };
    b.put(1, 1); // the last block
    b.put(1, 2); // fixed Huffman codes
    b.code(0b0011_0000, 8); // literal 0
    let (matches, rest) = ((n - 1) / 258, (n - 1) % 258);
    for _ in 0..matches {
        b.code(0b1100_0101, 8); // length 258 (code 285)
        b.code(0, 5); // distance 1
    }
    for _ in 0..rest {
        b.code(0b0011_0000, 8);
    }
    b.code(0, 7); // end of block
    if b.n > 0 {
        b.out.push(b.acc as u8); // the last bits, to a byte boundary
    }
    let mut z = b.out;
    let adler = (((n % 65521) << 16) | 1) as u32; // a = 1, b = n: all zeros
    z.extend_from_slice(&adler.to_be_bytes());
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        let body = [kind, data].concat();
        c.extend_from_slice(&body);
        c.extend_from_slice(&crc32(&body).to_be_bytes());
        c
    };
    let mut ihdr = side.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&side.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8-bit grey
    [
        b"\x89PNG\r\n\x1a\n".to_vec(),
        chunk(b"IHDR", &ihdr),
        chunk(b"IDAT", &z),
        chunk(b"IEND", &[]),
    ]
    .concat()
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 == 1 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn black_png_is_a_real_image() {
    // The generator, checked by the image crate's decoder on a small one.
    let img = image::load_from_memory(&black_png(300)).unwrap().to_luma8();
    assert_eq!(img.dimensions(), (300, 300));
    assert!(img.pixels().all(|p| p.0[0] == 0));
}

#[test]
fn assess_refuses_a_huge_image_under_a_3_gb_limit() {
    // A real 13000 x 13000 PNG (its pixels decode): refused from its header
    // under a 3 GB address-space limit, where decoding it would abort.
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("big.png"), black_png(13_000)).unwrap();
    let bin = common::bin();
    let t = Instant::now();
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 3000000 && exec '{}' assess big.png",
            bin.display()
        ))
        .current_dir(d.path())
        .output()
        .unwrap();
    refused(&o, &["big.png", "13000 x 13000", "assess takes at most"]);
    assert!(t.elapsed() < Duration::from_secs(10));
}

#[test]
fn assess_refuses_a_huge_image_from_its_header() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    // 13000 x 13000 declared (under the decoder's 2^28, over assess's cap).
    std::fs::write(p.join("huge.png"), common::png_header(13_000, 13_000)).unwrap();
    let t = Instant::now();
    let o = quick(p, &["assess", "huge.png"], 20);
    refused(
        &o,
        &[
            "huge.png",
            "13000 x 13000",
            &mmbm::limits::MAX_ASSESS_PIXELS.to_string(),
        ],
    );
    assert!(t.elapsed() < Duration::from_secs(5));
    // The library's door too.
    let e = mmbm::assess::load_grey(&p.join("huge.png"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("assess takes at most"), "{e}");
}

#[test]
fn gpu_commands_print_no_loader_noise() {
    let d = tempfile::tempdir().unwrap();
    for bad in [None, Some("relative/dir"), Some("")] {
        let mut cmd = common::mmbm_cmd();
        cmd.arg("info").current_dir(d.path());
        match bad {
            None => cmd.env_remove("XDG_RUNTIME_DIR"),
            Some(v) => cmd.env("XDG_RUNTIME_DIR", v),
        };
        let o = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert!(!err.contains("XDG_RUNTIME_DIR"), "{bad:?}: {err}");
    }
}

#[test]
fn trigger_summary_keeps_the_csv() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let mut log = String::from("t,wx,wy,wz\n");
    for i in 0..=1200 {
        log += &format!("{},0.01,0.02,0.01\n", i as f64 / 600.0);
    }
    std::fs::write(p.join("calm.csv"), log).unwrap();
    let base = ["trigger", "--gyro", "calm.csv", "--policy", "fixed:5"];
    let plain = mmbm_in(p, &base);
    assert!(plain.status.success() && plain.stdout.len() > 100);
    let mut args = base.to_vec();
    args.push("--summary");
    let o = mmbm_in(p, &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The CSV on stdout as without --summary; the summary on stderr.
    assert_eq!(o.stdout, plain.stdout);
    assert!(String::from_utf8_lossy(&o.stderr).contains("fixed:5: 10 frames"));
    // With --out FILE the summary takes stdout.
    args.extend(["--out", "f.csv"]);
    let o = mmbm_in(p, &args);
    assert!(String::from_utf8_lossy(&o.stdout).contains("fixed:5: 10 frames"));
    assert_eq!(std::fs::read(p.join("f.csv")).unwrap(), plain.stdout);
}

#[test]
fn trigger_help_lists_every_policy_form() {
    let o = common::mmbm(&["trigger", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    for form in [
        "fixed:FPS[@PHASE]@Tms",
        "ae:FPS[@PHASE][:cap=Tms][:target=F][:damp=F][:scene=F]",
        "task:FPS:light=E[:read=E][:tmin=Tms]",
        "--policy fixed:5@10ms",
        "--policy ae:5:cap=10ms",
        "--policy task:5:light=20000",
    ] {
        assert!(help.contains(form), "{form} not in trigger --help");
    }
}
