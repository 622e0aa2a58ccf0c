//! The module graph of the library: every top-level module imports only from
//! its own layer or the ones below it (the table in `src/lib.rs`), and no two
//! modules import each other, directly or through others: neither between
//! top-level modules nor between the files of one folder.
//!
//! Imports are read from the source text: `crate::NAME` paths (top level)
//! and `super::NAME` / `crate::FOLDER::NAME` paths (siblings in a folder).
//! Test code (`#[cfg(test)]` onwards, files named `tests.rs`) is skipped.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Layer of each top-level library module (keep in step with `src/lib.rs`).
const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("check", 0),
    ("limits", 0),
    ("bounded", 0),
    ("stats", 0),
    ("diagnostics", 0),
    ("cancel", 0),
    ("camera", 1),
    ("model", 1),
    ("io", 1),
    ("gpu", 1),
    ("metric", 2),
    ("board", 2),
    ("plot", 2),
    ("sim", 2),
    ("assess", 2),
    ("field", 3),
    ("tables", 3),
    ("series", 4),
    ("render", 4),
    ("trigger", 5),
    ("experiment", 6),
    ("dataset", 6),
    ("augment", 5),
];

fn layer(m: &str) -> Option<u32> {
    LAYERS.iter().find(|(n, _)| *n == m).map(|&(_, l)| l)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("dir entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The file's code without its test module and without comment lines.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("read source");
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => &text[..],
    };
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The identifiers that follow each `prefix` in `code` (e.g. `crate::` -> `model`).
fn after(code: &str, prefix: &str) -> Vec<(String, String)> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    for (i, _) in code.match_indices(prefix) {
        let before = code[..i].chars().last();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &code[i + prefix.len()..];
        let first = ident(rest);
        let second = rest[first.len()..]
            .strip_prefix("::")
            .map(ident)
            .unwrap_or_default();
        out.push((first, second));
    }
    out
}

/// Nodes on a cycle of `g`, if any (depth-first search).
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in g.get(n).into_iter().flatten() {
            match state.get(m.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|s| s == m).unwrap_or(0);
                    let mut c = stack[at..].to_vec();
                    c.push(m.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(m, g, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in g.keys() {
        if state.get(n.as_str()).copied().unwrap_or(0) == 0 {
            let mut stack = Vec::new();
            if let Some(c) = visit(n, g, &mut state, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

struct Source {
    /// Path components under `src/`, without `.rs` (`mod.rs` -> its folder).
    module: Vec<String>,
    code: String,
    path: PathBuf,
}

fn library_sources() -> Vec<Source> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files
        .into_iter()
        .filter_map(|p| {
            let rel = p.strip_prefix(&src).ok()?.to_path_buf();
            let mut parts: Vec<String> = rel
                .iter()
                .map(|c| c.to_string_lossy().trim_end_matches(".rs").to_string())
                .collect();
            let top = parts.first()?.clone();
            if top == "cli" || top == "main" || top == "lib" || parts.last()? == "tests" {
                return None;
            }
            if parts.last()? == "mod" {
                parts.pop();
            }
            Some(Source {
                module: parts,
                code: code(&p),
                path: rel,
            })
        })
        .collect()
}

#[test]
fn every_top_level_module_has_a_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("lib.rs");
    for line in lib.lines() {
        if let Some(m) = line.strip_prefix("pub mod ") {
            let m = m.trim_end_matches(';');
            assert!(
                layer(m).is_some(),
                "module `{m}` has no layer in tests/layers.rs"
            );
            assert!(
                lib.contains(&format!("[`{m}`]")),
                "module `{m}` is missing from the layer table in src/lib.rs"
            );
        }
    }
}

#[test]
fn no_module_imports_a_higher_layer() {
    let mut bad = Vec::new();
    for s in library_sources() {
        let me = &s.module[0];
        let Some(mine) = layer(me) else {
            bad.push(format!("{}: module `{me}` has no layer", s.path.display()));
            continue;
        };
        for (dep, _) in after(&s.code, "crate::") {
            if let Some(theirs) = layer(&dep) {
                if theirs > mine {
                    bad.push(format!(
                        "{}: `{me}` (layer {mine}) imports `crate::{dep}` (layer {theirs})",
                        s.path.display()
                    ));
                }
            }
        }
    }
    assert!(bad.is_empty(), "upward imports:\n{}", bad.join("\n"));
}

#[test]
fn no_import_circles() {
    let sources = library_sources();
    // Top level.
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for s in &sources {
        let me = s.module[0].clone();
        let e = g.entry(me.clone()).or_default();
        for (dep, _) in after(&s.code, "crate::") {
            if dep != me && layer(&dep).is_some() {
                e.insert(dep);
            }
        }
    }
    assert_eq!(
        find_cycle(&g),
        None,
        "import circle between top-level modules"
    );
    // Inside each folder: files import siblings through `super::` or the
    // folder's full path. A folder's `mod.rs` only declares and re-exports
    // (its own code counts as the node named after the folder).
    let mut folders: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for s in &sources {
        if s.module.len() != 2 {
            continue;
        }
        let (folder, me) = (&s.module[0], &s.module[1]);
        let mut deps = BTreeSet::new();
        for (dep, _) in after(&s.code, "super::") {
            deps.insert(dep);
        }
        for (top, dep) in after(&s.code, "crate::") {
            if &top == folder && !dep.is_empty() {
                deps.insert(dep);
            }
        }
        deps.remove(me);
        folders
            .entry(folder.clone())
            .or_default()
            .entry(me.clone())
            .or_default()
            .extend(deps);
    }
    for (folder, g) in &folders {
        // Keep edges to files of this folder only.
        let names: BTreeSet<String> = g.keys().cloned().collect();
        let g: BTreeMap<String, BTreeSet<String>> = g
            .iter()
            .map(|(k, v)| (k.clone(), v.intersection(&names).cloned().collect()))
            .collect();
        assert_eq!(
            find_cycle(&g),
            None,
            "import circle between the files of src/{folder}/"
        );
    }
}

#[test]
fn the_checker_sees_circles_and_upward_imports() {
    // The cycle finder on a known circle and a known tree.
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    assert!(find_cycle(&g).is_some());
    g.get_mut("c").expect("c").clear();
    assert_eq!(find_cycle(&g), None);
    // The path reader.
    let code = "use crate::render::{self, Backend};\nlet x = super::walk::Walk;\nfoo_crate::x";
    assert_eq!(
        after(code, "crate::"),
        vec![("render".to_string(), String::new())]
    );
    assert_eq!(
        after(code, "super::"),
        vec![("walk".to_string(), "Walk".to_string())]
    );
}
