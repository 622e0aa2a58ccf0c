//! Every `.wgsl` file under `src/` (each shader beside its kernel) parses and
//! validates with naga (no GPU needed).

use std::path::Path;

fn validate(path: &Path) -> Result<(), String> {
    let src = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let module = naga::front::wgsl::parse_str(&src).map_err(|e| {
        format!(
            "{}: parse error:\n{}",
            path.display(),
            e.emit_to_string(&src)
        )
    })?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| format!("{}: invalid:\n{}", path.display(), e.emit_to_string(&src)))?;
    Ok(())
}

/// Every `.wgsl` file under `dir`, recursively.
fn wgsl_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let p = e.expect("directory entry").path();
        if p.is_dir() {
            wgsl_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "wgsl") {
            out.push(p);
        }
    }
}

#[test]
fn all_shaders_validate() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    wgsl_files(&dir, &mut files);
    files.sort();
    for name in ["field.wgsl", "maps.wgsl", "render.wgsl", "texture.wgsl"] {
        assert!(
            files.iter().any(|p| p.ends_with(name)),
            "{name} not found under src/: {files:?}"
        );
    }
    let errors: Vec<String> = files.iter().filter_map(|p| validate(p).err()).collect();
    assert!(errors.is_empty(), "{}", errors.join("\n\n"));
}

#[test]
fn validator_rejects_a_broken_shader() {
    // The check above can fail: a type error must be reported.
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("bad.wgsl");
    std::fs::write(&p, "fn f() -> f32 { return 1u; }").unwrap();
    assert!(validate(&p).is_err());
}
