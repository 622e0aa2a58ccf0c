//! Every ffmpeg and ffprobe line the user is shown, run on the ffmpeg
//! installed (issue 36: the documented line used an option ffmpeg 7
//! removed): the lines of the `sh` blocks and the code spans of
//! `docs/*.md` and the README, the code spans and example lines of every
//! subcommand's `--help`, and the code spans of `src/series/select/`'s
//! documentation. Each runs by bash in a fresh folder holding a 10-frame
//! test video under every name the lines use (`video.mp4`, `clip.mp4`,
//! `in.mp4`), `select` files of four frames (`sharp.select`,
//! `blurry.select`, `FILE`) and the output folders they write into; it
//! must exit 0 and write what it names. A span without an input (`ffmpeg
//! -encoders`, `ffprobe -show_frames`) is a fragment of prose, not run; no
//! text anywhere may name ffmpeg's removed `-vsync`.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The select expression of frames 1, 4, 6 and 7 (mmbm's form).
const SELECT: &str = "eq(n\\,1)+eq(n\\,4)+between(n\\,6\\,7)";
/// Frames the expression selects.
const SELECTED: usize = 4;
/// Frames of the test video.
const FRAMES: usize = 10;
const REMOVED: &str = "-vsync";

/// The `sh` block lines (continuations joined) and the single-backtick code
/// spans of a Markdown text.
fn markdown_lines(text: &str) -> (Vec<String>, Vec<String>) {
    let (mut block, mut spans) = (Vec::new(), Vec::new());
    let mut prose = String::new();
    let mut in_block = false;
    let mut cur = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            continue;
        }
        if !in_block {
            prose += line;
            prose.push('\n');
            continue;
        }
        let l = line.trim();
        if let Some(head) = l.strip_suffix('\\') {
            cur += head;
            continue;
        }
        cur += l;
        block.push(std::mem::take(&mut cur));
    }
    spans.extend(code_spans(&prose));
    (block, spans)
}

/// The single-backtick spans of `text` (a line break inside one is a space).
fn code_spans(text: &str) -> Vec<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .map(|s| s.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect()
}

fn is_tool_line(s: &str) -> bool {
    s.starts_with("ffmpeg ") || s.starts_with("ffprobe ")
}

/// A line that runs on a file (not a fragment of prose).
fn has_input(s: &str) -> bool {
    s.split_whitespace()
        .any(|w| w.ends_with(".mp4") || w.ends_with(".mkv"))
}

/// Every ffmpeg / ffprobe line shown to the user, with where it is.
fn shown_lines() -> Vec<(String, String)> {
    let root = common::repo_root();
    let mut out = Vec::new();
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.push(root.join("README.md"));
    files.sort();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        assert!(!text.contains(REMOVED), "{} names {REMOVED}", f.display());
        let (block, spans) = markdown_lines(&text);
        for l in block.into_iter().chain(spans) {
            out.push((f.display().to_string(), l));
        }
    }
    // The library's documentation of the select expression.
    for e in std::fs::read_dir(root.join("src/series/select")).unwrap() {
        let p = e.unwrap().path();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(!text.contains(REMOVED), "{} names {REMOVED}", p.display());
        let doc: String = text
            .lines()
            .filter_map(|l| {
                let l = l.trim_start();
                l.strip_prefix("//!").or_else(|| l.strip_prefix("///"))
            })
            .collect::<Vec<_>>()
            .join("\n");
        for s in code_spans(&doc) {
            out.push((p.display().to_string(), s));
        }
    }
    // Every subcommand's --help: its code spans and its example lines.
    for sub in subcommands() {
        let o = common::mmbm(&[&sub, "--help"]);
        assert!(o.status.success(), "mmbm {sub} --help");
        let help = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(!help.contains(REMOVED), "mmbm {sub} --help names {REMOVED}");
        let lines = help.lines().map(|l| l.trim().to_string());
        for l in code_spans(&help).into_iter().chain(lines) {
            out.push((format!("mmbm {sub} --help"), l));
        }
    }
    out.retain(|(_, l)| is_tool_line(l));
    out.sort();
    out.dedup();
    out
}

/// The subcommands `mmbm --help` lists.
fn subcommands() -> Vec<String> {
    let o = common::mmbm(&["--help"]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let list = text
        .split("Commands:")
        .nth(1)
        .expect("a Commands: section")
        .split("\n\n")
        .next()
        .unwrap();
    list.lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|&n| n != "help")
        .map(String::from)
        .collect()
}

/// A fresh folder with the inputs every line names.
fn folder(base: &Path, k: usize) -> PathBuf {
    let d = base.join(format!("line{k}"));
    std::fs::create_dir_all(&d).unwrap();
    for name in ["video.mp4", "clip.mp4", "in.mp4"] {
        std::fs::copy(base.join("src.mp4"), d.join(name)).unwrap();
    }
    for name in ["sharp.select", "blurry.select", "FILE"] {
        std::fs::write(d.join(name), SELECT).unwrap();
    }
    for dir in ["frames", "sharp", "blurry"] {
        std::fs::create_dir_all(d.join(dir)).unwrap();
    }
    d
}

/// Files in `d` and its folders (not the inputs).
fn written(d: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in [
        d.to_path_buf(),
        d.join("frames"),
        d.join("sharp"),
        d.join("blurry"),
    ] {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let input = [
                "video.mp4",
                "clip.mp4",
                "in.mp4",
                "sharp.select",
                "blurry.select",
                "FILE",
            ]
            .contains(&name.as_str());
            if p.is_file() && !input {
                out.push(p);
            }
        }
    }
    out
}

#[test]
fn every_shown_ffmpeg_line_runs_on_the_installed_ffmpeg() {
    if !common::ffmpeg() {
        return;
    }
    let lines = shown_lines();
    let runnable: Vec<&(String, String)> = lines.iter().filter(|(_, l)| has_input(l)).collect();
    // The lines known to be shown today must be among them (the scan works).
    for want in [
        "ffmpeg -i video.mp4 -vf \"select=$(cat sharp.select)\" -fps_mode passthrough sharp/out_%04d.png",
        "ffmpeg -i in.mp4 -vf \"select=$(cat FILE)\" -fps_mode passthrough out_%04d.png",
        "ffprobe -v error -select_streams v:0 -show_frames -of csv video.mp4 > probe.csv",
    ] {
        assert!(
            runnable.iter().any(|(_, l)| l == want),
            "not found: {want}\n{runnable:#?}"
        );
    }
    let base = tempfile::tempdir().unwrap();
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-f", "lavfi", "-i"])
        .arg(format!(
            "testsrc=size=128x96:rate=10:duration={}",
            FRAMES / 10
        ))
        .args(["-pix_fmt", "yuv420p", "src.mp4"])
        .current_dir(base.path())
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (k, (place, line)) in runnable.iter().enumerate() {
        let d = folder(base.path(), k);
        let o = Command::new("bash")
            .args(["-c", &format!("set -eo pipefail; {line}")])
            .current_dir(&d)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{place}: `{line}` fails on the installed ffmpeg: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let files = written(&d);
        assert!(
            files
                .iter()
                .all(|p| std::fs::metadata(p).unwrap().len() > 0),
            "{place}: `{line}` wrote an empty file: {files:?}"
        );
        let want = if line.contains("select=") {
            SELECTED
        } else if line.contains('%') {
            FRAMES
        } else {
            1
        };
        assert_eq!(
            files.len(),
            want,
            "{place}: `{line}` wrote {files:?}, expected {want} file(s)"
        );
    }
}
