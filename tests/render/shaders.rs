//! Every shader parses and validates with naga (no GPU needed): each
//! kernel's joined source as the runner compiles it (the lens module, the
//! renderer's prelude for the render kernels, then the kernel's file), the
//! shared modules (the lens module alone, the prelude after it), and every
//! other `.wgsl` file under `src/` alone.

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
fn joined() -> [(&'static str, &'static str); 5] {
    [
        ("field (lens + field.wgsl)", mmbm::field::FIELD_WGSL),
        (
            "maps (lens + maps.wgsl)",
            mmbm::series::maps::gpu::MAPS_WGSL,
        ),
        ("prelude (lens + prelude.wgsl)", mmbm::render::PRELUDE_WGSL),
        (
            "render (lens + prelude + render.wgsl)",
            mmbm::render::RENDER_WGSL,
        ),
        (
            "texture (lens + prelude + texture.wgsl)",
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
    // The lens module is valid alone, the prelude after it; a kernel's own
    // file is valid only joined (it uses the modules), so it is checked
    // above. Every other file (a kernel without a shared part) is checked
    // alone.
    for p in &files {
        let text = std::fs::read_to_string(p).unwrap();
        let module = p.ends_with("lens.wgsl");
        let part = joined().iter().any(|(_, src)| src.contains(&text));
        if module || !part {
            errors.extend(validate(p).err());
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n\n"));
}

/// The shared lens module (every kernel) and the renderer's prelude (the
/// render kernels, after the lens module) are joined into their kernels
/// once, and no kernel's own file (nor the prelude) redefines their items.
#[test]
fn shared_modules_are_joined_not_copied() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let read = |p: &str| std::fs::read_to_string(src.join(p)).unwrap();
    let (lens, prelude) = (read("gpu/lens.wgsl"), read("render/prelude.wgsl"));
    let lens_prelude = format!("{lens}{prelude}");
    assert_eq!(mmbm::render::PRELUDE_WGSL, lens_prelude);
    for (joined, module, own) in [
        (mmbm::field::FIELD_WGSL, &lens, "field/field.wgsl"),
        (
            mmbm::series::maps::gpu::MAPS_WGSL,
            &lens,
            "series/maps/maps.wgsl",
        ),
        (
            mmbm::render::RENDER_WGSL,
            &lens_prelude,
            "render/render.wgsl",
        ),
        (
            mmbm::render::TEXTURE_WGSL,
            &lens_prelude,
            "render/texture.wgsl",
        ),
    ] {
        assert_eq!(joined, format!("{module}{}", read(own)), "{own}");
    }
    let lens_items = [
        "struct Lens {",
        "fn distort(",
        "fn jacobian(",
        "fn undistort(",
        "fn atan_poly(",
    ];
    let prelude_items = [
        "struct Params",
        "struct Homography",
        "fn line_base(",
        "struct PixelMap",
        "fn pixel_map(",
    ];
    for (own, defs) in [
        ("field/field.wgsl", &lens_items[..]),
        ("series/maps/maps.wgsl", &lens_items[..]),
        ("render/prelude.wgsl", &lens_items[..]),
        ("render/render.wgsl", &lens_items[..]),
        ("render/render.wgsl", &prelude_items[..]),
        ("render/texture.wgsl", &lens_items[..]),
        ("render/texture.wgsl", &prelude_items[..]),
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
    // The render kernels' Params hold it as `distortion` (their `lens` is
    // the defocus aperture); their Params size is asserted in
    // src/render/gpu.rs's unit tests (the host struct is private).
    for src in [mmbm::render::RENDER_WGSL, mmbm::render::TEXTURE_WGSL] {
        assert_eq!(struct_size(src, "Lens"), lens);
        assert!(
            src.contains("    distortion: Lens,"),
            "Params holds the Lens"
        );
    }
}
