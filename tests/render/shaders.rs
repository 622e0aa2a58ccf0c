//! Every `.wgsl` file under `shaders/` parses and validates with naga (no GPU needed).

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

#[test]
fn all_shaders_validate() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .collect();
    files.sort();
    for name in ["field.wgsl", "maps.wgsl", "render.wgsl", "texture.wgsl"] {
        assert!(
            files.iter().any(|p| p.ends_with(name)),
            "shaders/{name} not found in {files:?}"
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
