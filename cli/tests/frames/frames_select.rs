//! `mmbm frames`' choice of frames for the next tool (`--select`, `--gap`,
//! `--max-blur`, `--worst`) and what it writes (a COLMAP image list, an
//! ffmpeg `select` expression), on a synthetic log, against the table's own
//! blur column and an independent greedy choice; the expression is
//! evaluated here frame by frame as ffmpeg would.

use crate::common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// A fresh directory for one test.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-select-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 4 s gyro log at 200 Hz whose rates wander (so the blur varies from
/// frame to frame) and a 30 fps frame table inside it (2 frames outside).
fn fixture(d: &Path) -> (PathBuf, PathBuf) {
    let mut g = String::from("t,wx,wy,wz\n");
    for i in 0..=800 {
        let t = i as f64 / 200.0;
        let wx = 0.6 * (2.0 * std::f64::consts::PI * 0.7 * t).sin();
        let wy = 0.9 * (2.0 * std::f64::consts::PI * 1.3 * t + 0.4).cos();
        let wz = 0.2 * (5.0 * t).sin();
        g += &format!("{t},{wx},{wy},{wz}\n");
    }
    let mut f = String::from("t_start,exposure_s\n");
    for k in 0..112 {
        f += &format!("{},0.01\n", 0.05 + k as f64 / 30.0 - 0.1);
    }
    let (gp, fp) = (d.join("gyro.csv"), d.join("frames.csv"));
    std::fs::write(&gp, g).unwrap();
    std::fs::write(&fp, f).unwrap();
    (gp, fp)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// (frame, t_start, blur_px) of every row of a `frames` table with a value.
fn table(text: &str) -> Vec<(usize, f64, f64)> {
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            Some((
                c[0].parse().unwrap(),
                c[1].parse().unwrap(),
                c[3].parse().ok()?,
            ))
        })
        .collect()
}

/// The frames `0..n` an ffmpeg select expression of `eq(n\,K)` and
/// `between(n\,A\,B)` terms joined by `+` keeps (nonzero sum), or `0`.
fn ffmpeg_keeps(expr: &str, n: usize) -> BTreeSet<usize> {
    let expr = expr.strip_suffix('\n').expect("one line");
    assert!(!expr.contains('\n'));
    if expr == "0" {
        return BTreeSet::new();
    }
    let terms: Vec<Vec<usize>> = expr
        .split('+')
        .map(|t| {
            let (f, args) = t.split_once('(').unwrap();
            let args = args.strip_suffix(')').unwrap();
            let a: Vec<&str> = args.split("\\,").collect();
            assert_eq!(a[0], "n", "{t}");
            let nums: Vec<usize> = a[1..].iter().map(|x| x.parse().unwrap()).collect();
            match (f, nums.len()) {
                ("eq", 1) => vec![nums[0], nums[0]],
                ("between", 2) => nums,
                _ => panic!("term {t}"),
            }
        })
        .collect();
    (0..n)
        .filter(|&k| terms.iter().any(|r| r[0] <= k && k <= r[1]))
        .collect()
}

#[test]
fn lists_and_expressions_hold_the_chosen_frames() {
    let d = dir("lists");
    let (gyro, frames) = fixture(&d);
    let base = ["frames", "--gyro", s(&gyro), "--frames", s(&frames)];
    let all = common::mmbm_ok_in(&d, &base);
    let rows = table(&String::from_utf8_lossy(&all.stdout));
    assert_eq!(rows.len(), 110, "2 of 112 frames leave the log");
    let blur = |k: usize| rows.iter().find(|r| r.0 == k).unwrap().2;

    let out = common::mmbm_ok_in(
        &d,
        &[
            &base[..],
            &[
                "--select",
                "8",
                "--gap",
                "0.2",
                "--image-list",
                "sharp.txt",
                "--ffmpeg-select",
                "sharp.sel",
                "--worst",
                "--worst-list",
                "worst.txt",
                "--worst-ffmpeg-select",
                "worst.sel",
                "--frame-name",
                "img_%04d.jpg",
                "--frame-start",
                "0",
                "--out",
                "chosen.csv",
            ],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    // The independent greedy choice: sharpest first, 0.2 s apart.
    let mut order = rows.clone();
    order.sort_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)));
    let mut expect: Vec<(usize, f64)> = Vec::new();
    for &(k, t, _) in &order {
        if expect.len() < 8 && expect.iter().all(|&(_, u)| (u - t).abs() >= 0.2) {
            expect.push((k, t));
        }
    }
    let mut expect: Vec<usize> = expect.iter().map(|e| e.0).collect();
    expect.sort_unstable();
    let read = |n: &str| std::fs::read_to_string(d.join(n)).unwrap();
    let chosen: Vec<usize> = table(&read("chosen.csv")).iter().map(|r| r.0).collect();
    assert_eq!(chosen, expect, "{err}");
    let names: Vec<String> = expect.iter().map(|k| format!("img_{k:04}.jpg")).collect();
    assert_eq!(read("sharp.txt").lines().collect::<Vec<_>>(), names);
    assert_eq!(
        ffmpeg_keeps(&read("sharp.sel"), 112),
        expect.iter().copied().collect()
    );
    // The blurriest 10 %, rounded up: 11 of 110, none sharper than any other frame.
    let worst: Vec<usize> = read("worst.txt")
        .lines()
        .map(|l| {
            l.strip_prefix("img_")
                .and_then(|x| x.strip_suffix(".jpg"))
                .unwrap()
                .parse()
                .unwrap()
        })
        .collect();
    assert_eq!(worst.len(), 11);
    assert!(worst.windows(2).all(|w| w[0] < w[1]), "frame order");
    let least = worst.iter().map(|&k| blur(k)).fold(f64::INFINITY, f64::min);
    for r in &rows {
        if !worst.contains(&r.0) {
            assert!(
                r.2 <= least,
                "frame {} ({} px) is not in the list",
                r.0,
                r.2
            );
        }
    }
    assert_eq!(
        ffmpeg_keeps(&read("worst.sel"), 112),
        worst.iter().copied().collect()
    );
    assert!(
        err.contains("chosen: 8 frames") && err.contains("blurriest: 11 frames"),
        "{err}"
    );

    // A blur budget: every frame under it, and no other (the default names, from 1).
    let budget = {
        let mut b: Vec<f64> = rows.iter().map(|r| r.2).collect();
        b.sort_by(f64::total_cmp);
        b[40]
    };
    let budget_s = budget.to_string();
    common::mmbm_ok_in(
        &d,
        &[
            &base[..],
            &[
                "--max-blur",
                &budget_s,
                "--image-list",
                "budget.txt",
                "--worst",
                "3",
                "--worst-list",
                "w3.txt",
            ],
        ]
        .concat(),
    );
    let under: Vec<String> = rows
        .iter()
        .filter(|r| r.2 <= budget)
        .map(|r| format!("frame_{:06}.png", r.0 + 1))
        .collect();
    assert_eq!(under.len(), 41);
    assert_eq!(read("budget.txt").lines().collect::<Vec<_>>(), under);
    assert_eq!(read("w3.txt").lines().count(), 3);
    // --select with --max-blur: the N sharpest under the budget.
    common::mmbm_ok_in(
        &d,
        &[
            &base[..],
            &[
                "--max-blur",
                &budget_s,
                "--select",
                "500",
                "--ffmpeg-select",
                "b.sel",
            ],
        ]
        .concat(),
    );
    assert_eq!(ffmpeg_keeps(&read("b.sel"), 112).len(), 41);
    // A budget nothing meets: empty lists, an expression that keeps nothing.
    common::mmbm_ok_in(
        &d,
        &[
            &base[..],
            &[
                "--max-blur",
                "0",
                "--image-list",
                "none.txt",
                "--ffmpeg-select",
                "none.sel",
            ],
        ]
        .concat(),
    );
    assert_eq!(read("none.txt"), "");
    assert_eq!(read("none.sel"), "0\n");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_choices_are_refused_before_anything_is_written() {
    let d = dir("bad");
    let (gyro, frames) = fixture(&d);
    let base = ["frames", "--gyro", s(&gyro), "--frames", s(&frames)];
    let cases: [(&[&str], &str); 8] = [
        (&["--worst"], "--worst-list"),
        (&["--worst", "5", "--out", "t.csv"], "--worst-list"),
        (&["--image-list", "a.txt"], "--select N and/or --max-blur"),
        (&["--gap", "0.5"], "--select N and/or --max-blur"),
        (&["--select", "3", "--gap=-1"], "--gap"),
        (&["--max-blur=-1", "--out", "t.csv"], "--max-blur"),
        (
            &[
                "--select",
                "3",
                "--frame-name",
                "frame.png",
                "--image-list",
                "a.txt",
            ],
            "no %d",
        ),
        (
            &[
                "--select",
                "3",
                "--image-list",
                "a.txt",
                "--worst-list",
                "a.txt",
                "--out",
                "t.csv",
            ],
            "are one file",
        ),
    ];
    for (extra, want) in cases {
        let o = common::mmbm_in(&d, &[&base[..], extra].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(want),
            "{extra:?}: {err}"
        );
        for f in ["t.csv", "a.txt"] {
            assert!(!d.join(f).exists(), "{extra:?} wrote {f}");
        }
    }
    // An output that cannot be written: none of the others appears either.
    let o = common::mmbm_in(
        &d,
        &[
            &base[..],
            &[
                "--select",
                "3",
                "--out",
                "t.csv",
                "--image-list",
                "a.txt",
                "--ffmpeg-select",
                "missing/dir/x.sel",
            ],
        ]
        .concat(),
    );
    assert!(!o.status.success());
    for f in ["t.csv", "a.txt"] {
        assert!(!d.join(f).exists(), "wrote {f}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
