// The renderer's prelude, joined at build in front of render.wgsl and
// texture.wgsl (src/render/gpu.rs): their Params, homography table entry,
// bindings (one bind group layout) and line_base. Host structs:
// src/render/layout.rs (`RenderParams`, `GpuHomography`); CPU twins:
// src/render/cpu.rs and src/render/exact.rs.

struct Params {
    background: vec4<f32>,
    tex: vec4<f32>,        // image: width_m, height_m, texels per m (level 0), levels
    colour_a: vec4<f32>,
    colour_b: vec4<f32>,
    lod: vec4<f32>,        // LOD_SCALE, 1/N, poster layers (0: plain background), 0
    dims: vec4<u32>,       // width, height, kind, N
    lattice: vec4<u32>,    // g1, g2, distortion map offset (0: none), seed
    range: vec4<u32>,      // row0, k0, k1, (k0 g1) mod N
    range2: vec4<u32>,     // (k0 g2) mod N, rows, line mode, 0
    bbox: vec4<u32>,       // x0, y0, x1, y1 (end exclusive)
    lens: vec4<f32>,       // aperture radius (m; 0: pinhole), fx / s, fy / s, skew / s
    lens_gen: vec4<u32>,   // g3, g4, (k0 g3) mod N, (k0 g4) mod N
    poster: array<vec4<f32>, 8>, // per layer [S, 1/S, pa, pb], [r, g, b, 0] (src/render/poster.rs)
}

struct Homography {
    h0: vec4<f32>,
    h1: vec4<f32>,
    h2: vec4<f32>,         // row 2, |det H|
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> homs: array<Homography>;
@group(0) @binding(2) var<storage, read> texels: array<f32>;
@group(0) @binding(3) var<storage, read> levels: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read_write> out_rgb: array<vec4<f32>>;

// Rolling shutter (docs/spec.md section 9): the first table entry of pixel (i, j)'s line.
// Line mode range2.z: 0 one set of N instants for every pixel, 1 one set per
// row, 2 one per column (each line's own exposure window).
fn line_base(i: u32, j: u32) -> u32 {
    if (P.range2.z == 1u) {
        return j * P.dims.w;
    }
    if (P.range2.z == 2u) {
        return i * P.dims.w;
    }
    return 0u;
}

