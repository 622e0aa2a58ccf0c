//! Every shader parses and validates with naga (no GPU needed): each
//! kernel's joined source as the runner compiles it (the lens module or the
//! renderer's prelude, then the kernel's file), the shared modules alone,
//! and every other `.wgsl` file under `src/` alone.

use std::path::Path;

/// Parses and validates WGSL `src`, named `name` in errors.
fn validate_src(name: &str, src: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(src)
        .map_err(|e| format!("{name}: parse error:\n{}", e.emit_to_string(src)))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| format!("{name}: invalid:\n{}", e.emit_to_string(src)))?;
    Ok(())
}

fn validate(path: &Path) -> Result<(), String> {
    let src = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    validate_src(&path.display().to_string(), &src)
}

/// Each kernel's joined source, as its runner compiles it.
fn joined() -> [(&'static str, &'static str); 4] {
    [
        ("field (lens + field.wgsl)", mmbm::field::FIELD_WGSL),
        (
            "maps (lens + maps.wgsl)",
            mmbm::series::maps::gpu::MAPS_WGSL,
        ),
        ("render (prelude + render.wgsl)", mmbm::render::RENDER_WGSL),
        (
            "texture (prelude + texture.wgsl)",
            mmbm::render::TEXTURE_WGSL,
        ),
    ]
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
    for name in [
        "field.wgsl",
        "maps.wgsl",
        "render.wgsl",
        "texture.wgsl",
        "lens.wgsl",
        "prelude.wgsl",
    ] {
        assert!(
            files.iter().any(|p| p.ends_with(name)),
            "{name} not found under src/: {files:?}"
        );
    }
    let mut errors: Vec<String> = joined()
        .iter()
        .filter_map(|(name, src)| validate_src(name, src).err())
        .collect();
    // The shared modules are valid alone; a kernel's own file is valid
    // only joined (it uses the module), so it is checked above. Every other
    // file (a kernel without a shared part) is checked alone.
    for p in &files {
        let text = std::fs::read_to_string(p).unwrap();
        let module = p.ends_with("lens.wgsl") || p.ends_with("prelude.wgsl");
        let part = joined().iter().any(|(_, src)| src.contains(&text));
        if module || !part {
            errors.extend(validate(p).err());
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n\n"));
}

/// The shared lens module and the renderer's prelude are joined into their
/// kernels once, and their copies are gone from the kernels' own files.
#[test]
fn shared_modules_are_joined_not_copied() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let read = |p: &str| std::fs::read_to_string(src.join(p)).unwrap();
    let (lens, prelude) = (read("gpu/lens.wgsl"), read("render/prelude.wgsl"));
    for (joined, module, own) in [
        (mmbm::field::FIELD_WGSL, &lens, "field/field.wgsl"),
        (
            mmbm::series::maps::gpu::MAPS_WGSL,
            &lens,
            "series/maps/maps.wgsl",
        ),
        (mmbm::render::RENDER_WGSL, &prelude, "render/render.wgsl"),
        (mmbm::render::TEXTURE_WGSL, &prelude, "render/texture.wgsl"),
    ] {
        assert_eq!(joined, format!("{module}{}", read(own)), "{own}");
    }
    for (own, defs) in [
        (
            "field/field.wgsl",
            &["fn distort(", "fn jacobian(", "fn atan_poly("][..],
        ),
        (
            "series/maps/maps.wgsl",
            &["fn distort(", "fn jacobian(", "fn atan_poly("][..],
        ),
        (
            "render/render.wgsl",
            &["struct Params", "struct Homography", "fn line_base("][..],
        ),
        (
            "render/texture.wgsl",
            &["struct Params", "struct Homography", "fn line_base("][..],
        ),
    ] {
        let text = read(own);
        for d in defs {
            assert!(!text.contains(d), "{own} still defines {d}");
        }
    }
}

#[test]
fn validator_rejects_a_broken_shader() {
    // The check above can fail: a type error must be reported.
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("bad.wgsl");
    std::fs::write(&p, "fn f() -> f32 { return 1u; }").unwrap();
    assert!(validate(&p).is_err());
}

/// The size of WGSL struct `name` in `src` (naga's layout).
fn struct_size(src: &str, name: &str) -> usize {
    let m = naga::front::wgsl::parse_str(src).expect("parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(m.to_ctx()).expect("layout");
    let (h, _) = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"));
    layouter[h].size as usize
}

/// One host lens struct: every kernel that evaluates the lens holds the
/// lens module's `Lens` in its `Params`, and the WGSL sizes are the host's.
#[test]
fn host_structs_match_the_joined_shaders() {
    use mmbm::gpu::lens::{LensGpu, LENS_WGSL};
    use std::mem::size_of;
    let lens = size_of::<LensGpu>();
    assert_eq!(struct_size(LENS_WGSL, "Lens"), lens);
    for (src, params) in [
        (
            mmbm::field::FIELD_WGSL,
            size_of::<mmbm::field::FlowParams>(),
        ),
        (
            mmbm::series::maps::gpu::MAPS_WGSL,
            size_of::<mmbm::series::maps::kernel::MapsParams>(),
        ),
    ] {
        assert_eq!(struct_size(src, "Lens"), lens);
        assert_eq!(struct_size(src, "Params"), params);
        assert!(src.contains("    lens: Lens,"), "Params holds the Lens");
    }
}
