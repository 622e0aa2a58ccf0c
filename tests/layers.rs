//! The module graph of the workspace's three library crates (the core in
//! `core/src`, the library in `src`, the lab in `lab/src`, read as one tree
//! since the library re-exports the core and the lab imports the library at
//! the same paths): every top-level module imports only from its own layer or
//! the ones below it (the table in `src/lib.rs`), each module lives in the
//! crate its layer row names, and no two modules import each other, directly
//! or through others: neither between top-level modules nor between the files
//! of any folder at any depth. Across crates the compiler also enforces the
//! order (the core cannot name the library, the library cannot name the lab).
//!
//! Imports are read from the source text: `crate::` paths, `super::` and
//! `self::` paths and `use CHILD::` lines, resolved to module paths; circles
//! are looked for among the children of every folder, at every depth.
//! Test code (`#[cfg(test)]` onwards, files named `tests.rs`) is skipped.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The workspace's library crates, below to above: (folder of its `lib.rs`
/// from the workspace root, the name the table in `src/lib.rs` gives it).
const CRATES: &[(&str, &str)] = &[("core/src", "core"), ("src", "library"), ("lab/src", "lab")];

/// Layer and crate of each top-level library module (keep in step with the
/// table in `src/lib.rs`).
const LAYERS: &[(&str, u32, &str)] = &[
    ("error", 0, "core"),
    ("check", 0, "core"),
    ("limits", 0, "core"),
    ("bounded", 0, "core"),
    ("stats", 0, "core"),
    ("diagnostics", 0, "core"),
    ("cancel", 0, "core"),
    ("camera", 1, "core"),
    ("model", 1, "core"),
    ("io", 1, "core"),
    ("gpu", 1, "library"),
    ("metric", 2, "core"),
    ("board", 2, "library"),
    ("plot", 2, "lab"),
    ("sim", 2, "core"),
    ("assess", 2, "library"),
    ("telemetry", 2, "library"),
    ("video", 2, "library"),
    ("field", 3, "library"),
    ("tables", 3, "lab"),
    ("series", 4, "library"),
    ("render", 4, "library"),
    ("sync", 4, "library"),
    ("trigger", 5, "library"),
    ("augment", 5, "library"),
    ("prelude", 5, "library"),
    ("experiment", 6, "lab"),
    ("dataset", 6, "lab"),
    ("pickers", 6, "lab"),
];

fn layer(m: &str) -> Option<u32> {
    LAYERS.iter().find(|(n, ..)| *n == m).map(|&(_, l, _)| l)
}

fn crate_of(m: &str) -> Option<&'static str> {
    LAYERS.iter().find(|(n, ..)| *n == m).map(|&(.., c)| c)
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
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for (dir, _) in CRATES {
        let src = root.join(dir);
        let mut files = Vec::new();
        rust_files(&src, &mut files);
        out.extend(files.into_iter().filter_map(|p| {
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
                path: Path::new(dir).join(rel),
            })
        }));
    }
    out
}

#[test]
fn every_top_level_module_has_a_layer() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let table = std::fs::read_to_string(root.join("src/lib.rs")).expect("src/lib.rs");
    let mut seen = 0;
    for (dir, name) in CRATES {
        let lib = std::fs::read_to_string(root.join(dir).join("lib.rs")).expect("lib.rs");
        for line in lib.lines() {
            if let Some(m) = line.strip_prefix("pub mod ") {
                let m = m.trim_end_matches(';');
                seen += 1;
                assert!(
                    layer(m).is_some(),
                    "module `{m}` ({dir}) has no layer in tests/layers.rs"
                );
                assert_eq!(
                    crate_of(m),
                    Some(*name),
                    "module `{m}` lives in {dir}, but tests/layers.rs puts it elsewhere"
                );
                let row = table
                    .lines()
                    .find(|l| {
                        l.starts_with("//! |")
                            && (l.contains(&format!("[`{m}`]")) || l.contains(&format!("`{m}`")))
                    })
                    .unwrap_or_else(|| {
                        panic!("module `{m}` is missing from the layer table in src/lib.rs")
                    });
                let l = layer(m).unwrap();
                assert!(
                    row.starts_with(&format!("//! | {l} | {name} |")),
                    "the table in src/lib.rs puts `{m}` in another row than layer {l}, crate {name}: {row}"
                );
            }
        }
    }
    assert_eq!(
        seen,
        LAYERS.len(),
        "tests/layers.rs lists modules no crate declares"
    );
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

/// The paths a source's code imports, as module paths from the crate root
/// (each cut to the longest prefix that is a module in `known`): `crate::`
/// paths, `super::` and `self::` paths resolved against the source's own
/// module, and `use NAME::` where `NAME` is a child module of the source.
/// A braced list (`use super::{a, b::C}`) gives each of its members.
fn imports(s: &Source, known: &BTreeSet<Vec<String>>) -> BTreeSet<Vec<String>> {
    let ident = |t: &str| -> String {
        t.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    // The path segments after a prefix, expanding one level of braces.
    fn tails(rest: &str, ident: &dyn Fn(&str) -> String) -> Vec<Vec<String>> {
        let mut path = Vec::new();
        let mut r = rest;
        loop {
            if let Some(inner) = r.strip_prefix('{') {
                let close = inner.find('}').unwrap_or(inner.len());
                let mut out = Vec::new();
                for member in inner[..close].split(',') {
                    let m = member.trim();
                    if m.is_empty() || m == "self" {
                        out.push(path.clone());
                        continue;
                    }
                    for t in tails(m, ident) {
                        let mut p = path.clone();
                        p.extend(t);
                        out.push(p);
                    }
                }
                return out;
            }
            let id = ident(r);
            if id.is_empty() {
                break;
            }
            path.push(id.clone());
            match r[id.len()..].strip_prefix("::") {
                Some(next) => r = next,
                None => break,
            }
        }
        vec![path]
    }
    let resolve = |mut p: Vec<String>| -> Option<Vec<String>> {
        while !p.is_empty() && !known.contains(&p) {
            p.pop();
        }
        (!p.is_empty()).then_some(p)
    };
    let mut out = BTreeSet::new();
    // A re-export (`pub use ...;`) is the folder's public face, not a use:
    // it counts only where the module's own code names what it re-exports.
    let is_reexport = |l: &str| l.trim_start().starts_with("pub use ");
    let scanned: String = s
        .code
        .lines()
        .filter(|l| !is_reexport(l))
        .collect::<Vec<_>>()
        .join("\n");
    let code = &scanned;
    let bounded = |i: usize| {
        !code[..i]
            .chars()
            .last()
            .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':')
    };
    for (i, _) in code.match_indices("crate::") {
        if bounded(i) {
            for t in tails(&code[i + 7..], &ident) {
                out.extend(resolve(t));
            }
        }
    }
    for prefix in ["super::", "self::"] {
        for (i, _) in code.match_indices(prefix) {
            if !bounded(i) {
                continue;
            }
            let mut base = s.module.clone();
            let mut rest = &code[i..];
            while let Some(r) = rest.strip_prefix("super::") {
                base.pop();
                rest = r;
            }
            if let Some(r) = rest.strip_prefix("self::") {
                rest = r;
            }
            for t in tails(rest, &ident) {
                let mut p = base.clone();
                p.extend(t);
                out.extend(resolve(p));
            }
        }
    }
    let body: String = code
        .lines()
        .filter(|l| !l.trim_start().starts_with("use "))
        .collect::<Vec<_>>()
        .join("\n");
    let names_word = |name: &str| {
        body.match_indices(name).any(|(i, _)| {
            let before = body[..i].chars().last();
            let after = body[i + name.len()..].chars().next();
            !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
                && !after.is_some_and(|c| c.is_alphanumeric() || c == '_')
        })
    };
    for line in s.code.lines() {
        let l = line.trim_start();
        let reexport = is_reexport(l);
        let l = l.strip_prefix("pub ").unwrap_or(l);
        let Some(rest) = l.strip_prefix("use ") else {
            continue;
        };
        let bare = !["crate::", "super::", "self::"]
            .iter()
            .any(|p| rest.starts_with(p));
        if !reexport && !bare {
            continue; // read by the scans above
        }
        let mut base = s.module.clone();
        let mut rest = rest;
        if let Some(r) = rest.strip_prefix("crate::") {
            base.clear();
            rest = r;
        }
        while let Some(r) = rest.strip_prefix("super::") {
            base.pop();
            rest = r;
        }
        if let Some(r) = rest.strip_prefix("self::") {
            rest = r;
        }
        let mut first = base.clone();
        first.push(ident(rest));
        if base == s.module && !known.contains(&first) {
            continue; // an outside crate
        }
        for t in tails(rest, &ident) {
            let name = t.last().cloned().unwrap_or_default();
            let mut p = base.clone();
            p.extend(t);
            let Some(m) = resolve(p) else { continue };
            if !reexport || names_word(&name) {
                out.insert(m);
            }
        }
    }
    out.remove(&s.module);
    out
}

/// The import graphs of every folder at every depth: for folder `P`, the
/// nodes are its children (files and subfolders) and `(self)`, the folder's
/// own code (its `mod.rs` or `NAME.rs`); an import from a source under child
/// `A` of `P` of a module under child `B` of `P` is the edge `A -> B`.
fn folder_graphs(sources: &[Source]) -> BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> {
    let known: BTreeSet<Vec<String>> = sources.iter().map(|s| s.module.clone()).collect();
    let mut graphs: BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for s in sources {
        let m = &s.module;
        for t in imports(s, &known) {
            let lp = m.iter().zip(&t).take_while(|(a, b)| a == b).count();
            let from = m.get(lp).cloned().unwrap_or_else(|| "(self)".into());
            let to = t.get(lp).cloned().unwrap_or_else(|| "(self)".into());
            if from != to {
                graphs
                    .entry(m[..lp].to_vec())
                    .or_default()
                    .entry(from)
                    .or_default()
                    .insert(to);
            }
        }
    }
    graphs
}

#[test]
fn no_import_circles() {
    let sources = library_sources();
    let graphs = folder_graphs(&sources);
    assert!(
        graphs.contains_key(&vec!["io".to_string(), "gyro".to_string()]),
        "the checker no longer sees the files of core/src/io/gyro/"
    );
    let mut bad = Vec::new();
    for (folder, g) in &graphs {
        if let Some(c) = find_cycle(g) {
            bad.push(format!("src/{}/: {}", folder.join("/"), c.join(" -> ")));
        }
    }
    assert!(bad.is_empty(), "import circles:\n{}", bad.join("\n"));
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
    // A circle three levels down (as core/src/io/gyro/fast.rs <-> plain.rs once was),
    // through a braced `super::` list and a `use CHILD::` line.
    let src = |m: &str, code: &str| Source {
        module: m.split('/').map(String::from).collect(),
        code: code.to_string(),
        path: PathBuf::from(m),
    };
    let mut files = vec![
        src("a", "use crate::a::b::c::T;"),
        src("a/b", "use c::T;"),
        src("a/b/c", "use super::{d::U, e};"),
        src("a/b/d", "use super::c::T;"),
        src("a/b/e", ""),
    ];
    let g = folder_graphs(&files);
    let ab = vec!["a".to_string(), "b".to_string()];
    assert!(find_cycle(&g[&ab]).is_some(), "{g:?}");
    assert!(g[&ab]["(self)"].contains("c"), "{g:?}");
    files[3] = src("a/b/d", "use super::e;");
    assert_eq!(find_cycle(&folder_graphs(&files)[&ab]), None);
}
