//! `docs/limits.md` lists every cap with its value, and this test keeps the
//! list true: every `pub const` of `core/src/limits.rs` (a cap added there
//! without a line in the table fails here), and the caps elsewhere that the
//! table cites, must each have a row `` | `NAME` | VALUE ... | `` in the
//! table "Every cap" whose VALUE is the constant's value.
//!
//! Values are read from the source text (so a constant that is not public
//! can be cited too) by a small evaluator: literals (`1_000`, `1e12`,
//! `1000.0`), `A << B`, `A * B` and names of other constants of the same
//! file. In the table a VALUE is `2^N`, a number (`100`, `1,000,000`,
//! `1e12`) or either followed by `KiB`/`MiB`/`GiB` (bytes).

use std::collections::BTreeMap;

/// Caps outside `core/src/limits.rs` that the table cites: (name in the table,
/// source file, constant).
const ELSEWHERE: &[(&str, &str, &str)] = &[
    (
        "metric::MAX_GRID_POINTS",
        "core/src/metric/mod.rs",
        "MAX_GRID_POINTS",
    ),
    (
        "metric::MAX_GAUSS_NODES",
        "core/src/metric/mod.rs",
        "MAX_GAUSS_NODES",
    ),
    ("trigger::MAX_FPS", "src/trigger/parse.rs", "MAX_FPS"),
    ("sim::MAX_SAMPLES", "core/src/sim/gen.rs", "MAX_SAMPLES"),
    ("sim::MAX_STEP_HZ", "core/src/sim/mod.rs", "MAX_STEP_HZ"),
    ("render::MAX_SAMPLES", "src/render/mod.rs", "MAX_SAMPLES"),
    ("render::MAX_TABLE", "src/render/mod.rs", "MAX_TABLE"),
    (
        "render::texture::MAX_TEXTURE_SIDE",
        "src/render/texture.rs",
        "MAX_TEXTURE_SIDE",
    ),
    (
        "bounded::MAX_TEXT_BYTES",
        "core/src/bounded.rs",
        "MAX_TEXT_BYTES",
    ),
    (
        "io::input::MAX_LINE_BYTES",
        "core/src/io/input.rs",
        "MAX_LINE_BYTES",
    ),
    (
        "io::input::MAX_HEADER_BYTES",
        "core/src/io/input.rs",
        "MAX_HEADER_BYTES",
    ),
    (
        "io::mcap::MAX_RECORD_BYTES",
        "core/src/io/mcap.rs",
        "MAX_RECORD_BYTES",
    ),
    (
        "io::images::MAX_EXR_SAMPLES",
        "core/src/io/images.rs",
        "MAX_EXR_SAMPLES",
    ),
    (
        "camera::MAX_CAMERA_BYTES",
        "core/src/camera/file.rs",
        "MAX_CAMERA_BYTES",
    ),
    (
        "dataset::MAX_COUNT",
        "lab/src/dataset/config.rs",
        "MAX_COUNT",
    ),
    (
        "dataset::MAX_SHARDS",
        "lab/src/dataset/shard.rs",
        "MAX_SHARDS",
    ),
    ("error::MAX_MESSAGE", "core/src/error.rs", "MAX_MESSAGE"),
    ("error::MAX_SHOWN", "core/src/error.rs", "MAX_SHOWN"),
];

fn root() -> std::path::PathBuf {
    crate::common::repo_root()
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Every `pub const NAME: TYPE = EXPR;` (and `const`) of a source text, in
/// order: (name, expression), statements joined across lines, test code
/// (from `#[cfg(test)]`) left out.
fn consts(src: &str) -> Vec<(String, String, bool)> {
    let code = src.split("#[cfg(test)]").next().unwrap();
    let mut out = Vec::new();
    let mut stmt: Option<String> = None;
    for line in code.lines() {
        let t = line.trim();
        if stmt.is_none() && (t.starts_with("pub const ") || t.starts_with("const ")) {
            stmt = Some(String::new());
        }
        if let Some(s) = &mut stmt {
            s.push(' ');
            s.push_str(t);
            if t.ends_with(';') {
                let s = stmt.take().unwrap();
                let public = s.trim_start().starts_with("pub ");
                let (head, expr) = s.split_once('=').expect("const NAME: T = EXPR;");
                let name = head
                    .trim()
                    .trim_start_matches("pub ")
                    .trim_start_matches("const ")
                    .split(':')
                    .next()
                    .unwrap()
                    .trim()
                    .to_string();
                let expr = expr.trim().trim_end_matches(';').trim().to_string();
                out.push((name, expr, public));
            }
        }
    }
    out
}

/// A literal: `1_000`, `1e12`, `1000.0`, `65_535u32`.
fn literal(s: &str) -> Option<f64> {
    let s = s.replace('_', "");
    for suffix in ["u128", "u64", "u32", "usize", "f64", "f32", "i64", "i32"] {
        if let Some(x) = s.strip_suffix(suffix) {
            return x.parse().ok();
        }
    }
    s.parse().ok()
}

/// Evaluates `expr` (terms joined by `<<` or `*`, left to right; a term a
/// literal or a name in `known`).
fn eval(expr: &str, known: &BTreeMap<String, f64>) -> Result<f64, String> {
    let term = |t: &str| -> Result<f64, String> {
        let t = t.trim().trim_matches(|c| c == '(' || c == ')');
        literal(t)
            .or_else(|| known.get(t).copied())
            .ok_or_else(|| format!("cannot evaluate '{t}' in '{expr}'"))
    };
    let tokens: Vec<&str> = expr.split_whitespace().collect();
    let mut value = term(tokens.first().ok_or("empty")?)?;
    let mut k = 1;
    while k < tokens.len() {
        let rhs = term(
            tokens
                .get(k + 1)
                .ok_or_else(|| format!("dangling '{expr}'"))?,
        )?;
        value = match tokens[k] {
            "<<" => value * 2f64.powi(rhs as i32),
            "*" => value * rhs,
            op => {
                return Err(format!(
                    "operator '{op}' in '{expr}' (use <<, * or a literal)"
                ))
            }
        };
        k += 2;
    }
    Ok(value)
}

/// The values of every constant of a source file, by name.
fn values(rel: &str) -> BTreeMap<String, f64> {
    let mut known = BTreeMap::new();
    for (name, expr, _) in consts(&read(rel)) {
        if let Ok(v) = eval(&expr, &known) {
            known.insert(name, v);
        }
    }
    known
}

/// A value as the table writes it: `2^26`, `1,048,576`, `1e12`, `4 MiB`.
fn doc_value(cell: &str) -> Option<f64> {
    let mut words = cell.split_whitespace();
    let first = words.next()?.trim_end_matches(',');
    let v = if let Some((b, e)) = first.split_once('^') {
        b.parse::<f64>().ok()?.powf(e.parse().ok()?)
    } else {
        first.replace(',', "").parse::<f64>().ok()?
    };
    let scale = match words.next() {
        Some("KiB") => 1024.0,
        Some("MiB") => 1024.0 * 1024.0,
        Some("GiB") => 1024.0 * 1024.0 * 1024.0,
        _ => 1.0,
    };
    Some(v * scale)
}

/// The table's rows: name (the first cell, in backticks) to its value cell.
fn table() -> BTreeMap<String, String> {
    let doc = read("docs/limits.md");
    let start = doc
        .find("## Every cap")
        .expect("docs/limits.md has a section '## Every cap'");
    let mut rows = BTreeMap::new();
    for line in doc[start..].lines().skip(1) {
        if line.starts_with("## ") {
            break;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() > 3 && cells[1].starts_with('`') && cells[1].ends_with('`') {
            let name = cells[1].trim_matches('`').to_string();
            assert!(
                rows.insert(name.clone(), cells[2].to_string()).is_none(),
                "{name} has two rows"
            );
        }
    }
    rows
}

/// What is wrong with the row of cap `name` (value `v`, from `what`, e.g.
/// `NAME = EXPR`): missing, or a value other than `v`.
fn row_fault(rows: &BTreeMap<String, String>, name: &str, v: f64, what: &str) -> Option<String> {
    match rows.get(name) {
        None => Some(format!("{what}: no row `{name}` in docs/limits.md")),
        Some(cell) if doc_value(cell) != Some(v) => {
            Some(format!("{what} ({v}): docs/limits.md says '{cell}'"))
        }
        _ => None,
    }
}

#[test]
fn every_cap_in_limits_rs_is_in_the_table_with_its_value() {
    let src = read("core/src/limits.rs");
    let rows = table();
    let mut known = BTreeMap::new();
    let mut problems = Vec::new();
    let caps: Vec<_> = consts(&src).into_iter().filter(|c| c.2).collect();
    assert!(caps.len() >= 9, "{caps:?}");
    for (name, expr, _) in caps {
        let v = match eval(&expr, &known) {
            Ok(v) => v,
            Err(e) => {
                problems.push(format!("{name}: {e}"));
                continue;
            }
        };
        known.insert(name.clone(), v);
        problems.extend(row_fault(&rows, &name, v, &format!("{name} = {expr}")));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn caps_elsewhere_are_in_the_table_with_their_values() {
    let rows = table();
    let mut problems = Vec::new();
    for &(name, file, konst) in ELSEWHERE {
        let Some(&v) = values(file).get(konst) else {
            problems.push(format!("{name}: no evaluable const {konst} in {file}"));
            continue;
        };
        problems.extend(row_fault(&rows, name, v, name));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The evaluator reads the source as the compiler does (checked against
/// the constants themselves), and the table's value forms parse.
#[test]
fn the_reader_agrees_with_the_compiler() {
    let lim = values("core/src/limits.rs");
    assert_eq!(lim["MAX_MAP_PIXELS"], mmbm::limits::MAX_MAP_PIXELS as f64);
    assert_eq!(lim["MAX_LIGHT_E_PER_S"], mmbm::limits::MAX_LIGHT_E_PER_S);
    assert_eq!(
        lim["MAX_LIST_ENTRIES"],
        mmbm::limits::MAX_LIST_ENTRIES as f64
    );
    assert_eq!(
        lim["MAX_PIXEL_SAMPLES"],
        mmbm::render::MAX_PIXEL_SAMPLES as f64
    );
    assert_eq!(
        values("core/src/bounded.rs")["MAX_TEXT_BYTES"],
        mmbm::bounded::MAX_TEXT_BYTES as f64
    );
    assert_eq!(
        values("core/src/error.rs")["MAX_SHOWN"],
        mmbm::error::MAX_SHOWN as f64
    );
    assert_eq!(
        values("core/src/sim/gen.rs")["MAX_SAMPLES"],
        mmbm::sim::MAX_SAMPLES
    );
    assert_eq!(
        values("src/render/mod.rs")["MAX_SAMPLES"],
        mmbm::render::MAX_SAMPLES as f64
    );
    assert_eq!(
        values("lab/src/dataset/shard.rs")["MAX_SHARDS"],
        mmbm_lab::dataset::MAX_SHARDS as f64
    );
    for (cell, v) in [
        ("2^26 px", 67_108_864.0),
        ("67,108,864", 67_108_864.0),
        ("1e12 e-/s", 1e12),
        ("4 MiB", 4.0 * 1024.0 * 1024.0),
        ("100", 100.0),
    ] {
        assert_eq!(doc_value(cell), Some(v), "{cell}");
    }
    assert!(eval("1 + 2", &BTreeMap::new()).is_err());
}
