//! The README's first command, end to end: `mmbm demo` (about 5 minutes on
//! 2 idle cores). Its report must lead with the benefit map, the README's
//! headline must quote that map (and its goals) as the demo computes it, and
//! the seed-1 table of `docs/experiment.md` ("What the demo finds") must be
//! what the demo measures.

use crate::common;

use std::collections::HashMap;

/// Cells of the Markdown table rows starting with `prefix`.
fn rows<'a>(text: &'a str, prefix: &str) -> Vec<Vec<&'a str>> {
    text.lines()
        .filter(|l| l.starts_with(prefix))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect()
}

fn num(s: &str) -> f64 {
    s.trim_end_matches(" %")
        .parse()
        .unwrap_or_else(|_| panic!("'{s}' is not a number"))
}

#[test]
#[ignore = "slow tier (mmbm demo, minutes): the README's test command runs it with --ignored"]
fn demo_report_matches_the_docs() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("report");
    let o = common::mmbm_cmd()
        .args(["demo", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    let frames = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    // The report leads with the benefit map, the headline of sharp frames
    // per second after it.
    let first = report.find("## ").unwrap();
    assert!(report[first..].starts_with("## Benefit map"), "{report}");
    assert!(report.contains("## Headline: sharp frames per second"));
    // The README's headline quotes the map's table and goals line for line.
    let readme = std::fs::read_to_string(crate::common::repo_root().join("README.md")).unwrap();
    let quoted: Vec<&str> = readme
        .lines()
        .skip_while(|l| *l != "<!-- map -->")
        .take_while(|l| *l != "<!-- /map -->")
        .filter(|l| l.starts_with("| ") || l.starts_with("- "))
        .collect();
    assert!(quoted.len() >= 4, "README quotes no map");
    for l in &quoted {
        assert!(
            report.lines().any(|r| r == *l),
            "README.md: '{l}' is not in the demo's report"
        );
    }
    assert!(report.contains("so no policy at that rate can exceed"));
    // The map's goals state the frame-rate ceiling against the baseline.
    assert!(report.contains("frames/s no policy can get more than"));
    assert!(report.contains("`phase:0.4` recovers"));
    assert!(report.contains("## Image metrics against the ground truth"));
    // Every kept frame of the demo's policies rendered, with the new columns.
    let header = frames.lines().next().unwrap();
    assert!(
        header.ends_with(
            "blur_h_px,blur_v_px,jnbm_2d,cpbd_2d,gain,family,blobs_false,corner_repeatability"
        ),
        "{header}"
    );
    let rendered = header.split(',').position(|c| c == "rendered").unwrap();
    let cells = |l: &str| l.split(',').nth(rendered).map(str::to_string);
    let n = frames
        .lines()
        .skip(1)
        .filter(|l| cells(l).as_deref() == Some("1"))
        .count();
    let kept = header.split(',').position(|c| c == "kept").unwrap();
    let n_kept = frames
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(kept) == Some("1"))
        .count();
    assert!(n > 0 && n == n_kept, "{n} rendered of {n_kept} kept");

    // Table 6 of the report: policy -> cells.
    let header6: Vec<&str> = rows(&report, "| walk | policy | frames kept")[0].clone();
    let col = |name: &str| header6.iter().position(|h| *h == name).unwrap();
    let t6: HashMap<&str, Vec<&str>> = rows(&report, "| moderate |")
        .into_iter()
        .filter(|r| r.len() == header6.len())
        .map(|r| (r[1], r))
        .collect();
    let doc =
        std::fs::read_to_string(crate::common::repo_root().join("docs/experiment.md")).unwrap();
    let section = &doc[doc.find("## What the demo finds").unwrap()..];
    let start = section.find("| policy |").unwrap();
    let section = &section[start..start + section[start..].find("\n\n").unwrap()];
    let quoted = rows(section, "| ");
    // The header and the demo's policies (the |---| rule does not start with "| ").
    assert_eq!(
        quoted.len(),
        1 + mmbm_lab::experiment::DEMO_POLICIES.len(),
        "{section}"
    );
    for r in quoted.iter().skip(1) {
        let got = &t6[r[0]];
        let cmp = |doc_cell: &str, name: &str, tol: f64| {
            let (a, b) = (num(doc_cell), num(got[col(name)]));
            assert!(
                (a - b).abs() <= tol,
                "{}: docs/experiment.md {a} vs demo {b} ({name})",
                r[0]
            );
        };
        cmp(r[1], "frames kept", 0.0);
        cmp(r[2], "success %", 0.051);
        cmp(r[3], "success % fixed threshold", 0.051);
        cmp(r[4], "mean blur px", 0.051);
        cmp(r[5], "p95 blur px", 0.051);
        cmp(r[6], "mean blur effect", 0.0006);
        cmp(r[7], "mean JNBM", 0.0006);
    }
}
