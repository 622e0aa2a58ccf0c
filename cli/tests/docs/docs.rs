//! The README and the manuals in `docs/`: every relative link resolves (the
//! file, and the heading an anchor names), the README's Rust example is
//! `examples/twist.rs` (which cargo builds) and prints what the README says,
//! and its command-line example prints the lines the README quotes.

use crate::common;
use mmbm::{mmbm, Method, Scene, Twist};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    crate::common::repo_root()
}

fn read(rel: &Path) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{}: {e}", rel.display()))
}

/// README.md and every `docs/*.md`, as paths relative to the root.
fn pages() -> Vec<PathBuf> {
    let mut out = vec![PathBuf::from("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .map(|p| Path::new("docs").join(p.file_name().unwrap()))
        .collect();
    docs.sort();
    out.extend(docs);
    out
}

/// The text outside fenced code blocks, with inline code spans removed.
fn prose(text: &str) -> String {
    let mut fenced = false;
    let mut kept = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            kept.push(line);
        }
    }
    // Inline code may span lines; drop every `...` span.
    kept.join("\n")
        .split('`')
        .step_by(2)
        .collect::<Vec<_>>()
        .join(" ")
}

/// GitHub's anchor for a heading: lower case, punctuation other than `-` and
/// `_` dropped, each space a `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// Anchors of the headings of a Markdown page (outside code blocks).
fn anchors(text: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            let title = line.trim_start_matches('#');
            if title.starts_with(' ') {
                out.push(slug(title));
            }
        }
    }
    out
}

/// Targets of the inline links `[text](target)` in a page's prose.
fn links(text: &str) -> Vec<String> {
    let p = prose(text);
    p.match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &p[i + 2..];
            rest.find(')').map(|j| rest[..j].to_string())
        })
        .collect()
}

#[test]
fn slugs_follow_github() {
    assert_eq!(slug("The metric: methods"), "the-metric-methods");
    assert_eq!(
        slug("The headline over five seeds (mmbm demo --full, measured 2026-11-23)"),
        "the-headline-over-five-seeds-mmbm-demo---full-measured-2026-11-23"
    );
    assert_eq!(
        links("a [b](c.md#d) `[e](f)` g"),
        vec!["c.md#d".to_string()]
    );
}

#[test]
fn every_relative_link_resolves() {
    let mut checked = 0;
    for page in pages() {
        let text = read(&page);
        let dir = page.parent().unwrap_or(Path::new(""));
        for target in links(&text) {
            if target.starts_with("http://") || target.starts_with("https://") {
                continue;
            }
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let rel = if file.is_empty() {
                page.clone()
            } else {
                dir.join(file)
            };
            let abs = root().join(&rel);
            assert!(
                abs.exists(),
                "{}: link to {target}: {} does not exist",
                page.display(),
                rel.display()
            );
            if let Some(a) = anchor {
                let heads = anchors(&std::fs::read_to_string(&abs).unwrap());
                assert!(
                    heads.iter().any(|h| h == a),
                    "{}: link to {target}: no heading #{a} in {} (headings: {heads:?})",
                    page.display(),
                    rel.display()
                );
            }
            checked += 1;
        }
    }
    // The README links every manual, and the manuals link each other.
    assert!(checked >= 30, "only {checked} links found");
}

/// The first fenced block of `lang` after `after` in `text`.
fn block<'a>(text: &'a str, after: &str, lang: &str) -> &'a str {
    let from = text.find(after).unwrap_or_else(|| panic!("no '{after}'"));
    let open = format!("```{lang}\n");
    let start = from + text[from..].find(&open).expect("code block") + open.len();
    let len = text[start..].find("```").expect("closing fence");
    &text[start..start + len]
}

#[test]
fn readme_rust_example_is_examples_twist() {
    let readme = read(Path::new("README.md"));
    let example = read(Path::new("examples/twist.rs"));
    assert_eq!(block(&readme, "## Examples", "rust"), example);
    // What it prints, as the README quotes it.
    let scene = Scene::thesis();
    let twist = Twist::rotation(1.0, 1.0, 1.0);
    let exact = mmbm(&scene, &twist, Method::Exact { tol: 1e-9 }).unwrap();
    let thesis = mmbm(&scene, &twist, Method::default()).unwrap();
    let said = format!(
        "It prints `exact: {:.6} mm/s ({:.1} px/s, error estimate {:.1e} mm/s)` and `riemann:8x6: {:.6} mm/s`.",
        exact.mm_s,
        exact.px_s,
        exact.error_estimate.unwrap(),
        thesis.mm_s
    );
    assert!(readme.contains(&said), "README should say: {said}");
}

#[test]
fn readme_cli_example_prints_what_it_quotes() {
    let readme = read(Path::new("README.md"));
    let sh = block(&readme, "## Examples", "sh");
    let commands: Vec<Vec<&str>> = sh
        .lines()
        .filter_map(|l| l.strip_prefix("mmbm "))
        .map(|l| l.split("  #").next().unwrap().split_whitespace().collect())
        .collect();
    let quoted: Vec<&str> = sh
        .lines()
        .filter_map(|l| l.strip_prefix("# "))
        .map(str::trim)
        .collect();
    assert_eq!(commands.len(), 2, "{sh}");
    assert_eq!(quoted.len(), 4, "{sh}");
    let d = tempfile::tempdir().unwrap();
    let mut stdout = String::new();
    for args in &commands {
        let o = common::mmbm_cmd()
            .args(args)
            .current_dir(d.path())
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "mmbm {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr)
        );
        stdout = String::from_utf8(o.stdout).unwrap();
    }
    let printed: Vec<&str> = stdout.lines().map(str::trim).collect();
    for q in quoted {
        assert!(
            printed.contains(&q),
            "not printed: {q}\n--- stdout:\n{stdout}"
        );
    }
    assert!(d.path().join("frames.csv").exists());
}

/// The README's `<!-- full-map -->` block quotes the three opening lines of
/// the whole map's committed report (`demo --full`'s map, docs/results/) word
/// for word: where gyro-driven capture pays, ties and loses.
#[test]
fn readme_quotes_the_full_maps_three_lines() {
    let readme = read(Path::new("README.md"));
    let quoted: Vec<&str> = readme
        .lines()
        .skip_while(|l| *l != "<!-- full-map -->")
        .take_while(|l| *l != "<!-- /full-map -->")
        .filter(|l| l.starts_with("- "))
        .collect();
    let source = readme
        .lines()
        .skip_while(|l| *l != "<!-- /full-map -->")
        .find_map(|l| {
            l.split("](")
                .filter_map(|p| p.split(')').next())
                .find(|p| p.starts_with("docs/results/") && p.ends_with("/report.md"))
        })
        .expect("the README links the full map's report after the block");
    let report = read(Path::new(source));
    let opening: Vec<&str> = report
        .lines()
        .skip_while(|l| !l.starts_with("- "))
        .take_while(|l| l.starts_with("- "))
        .collect();
    assert_eq!(opening.len(), 3, "{source}: three opening lines");
    assert_eq!(
        quoted, opening,
        "README.md's full-map block against {source}"
    );
    for (line, start) in opening
        .iter()
        .zip(["- Gyro-driven capture", "- It ties", "- It loses"])
    {
        assert!(line.starts_with(start), "{line}");
    }
}
