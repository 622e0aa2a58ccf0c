// The renderer's prelude, joined at build after the lens module
// (src/gpu/lens.wgsl) and in front of render.wgsl and texture.wgsl
// (src/render/gpu.rs): their Params, homography table entry, bindings (one
// bind group layout), line_base and pixel_map. Host structs:
// src/render/layout.rs (`RenderParams`, `GpuHomography`); CPU twins:
// src/render/cpu.rs and src/render/exact.rs.

struct Params {
    background: vec4<f32>,
    tex: vec4<f32>,        // image: width_m, height_m, texels per m (level 0), levels
    colour_a: vec4<f32>,
    colour_b: vec4<f32>,
    lod: vec4<f32>,        // LOD_SCALE, 1/N, poster layers (0: plain background), 0
    dims: vec4<u32>,       // width, height, kind, N
    lattice: vec4<u32>,    // g1, g2, distortion table offset (model 3; else 0), seed
    range: vec4<u32>,      // row0, k0, k1, (k0 g1) mod N
    range2: vec4<u32>,     // (k0 g2) mod N, rows, line mode, 0
    bbox: vec4<u32>,       // x0, y0, x1, y1 (end exclusive)
    lens: vec4<f32>,       // aperture radius (m; 0: pinhole), fx / s, fy / s, skew / s
    lens_gen: vec4<u32>,   // g3, g4, (k0 g3) mod N, (k0 g4) mod N
    poster: array<vec4<f32>, 8>, // per layer [S, 1/S, pa, pb], [r, g, b, 0] (src/render/poster.rs)
    pixel: vec4<f32>,      // cx, cy (px), pitch_x / f, pitch_y / f (normalised units per px)
    pixel2: vec4<f32>,     // skew (px), 0, 0, 0
    distortion: Lens,      // lens distortion (src/gpu/lens.wgsl); model 3: the table at lattice.z
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


// Lens distortion (docs/spec.md section 9): pixel (i, j)'s map, the pinhole
// pixel coordinates p of the ray through its centre and the rows l0, l1 of
// the Jacobian of undistortion (pixel to pinhole pixel) there. A sample at
// (sx, sy) in the pixel goes to p + L (sx - 1/2, sy - 1/2): first order in
// the pixel. Models 1 and 2: the lens module's undistort at the centre's
// normalised point, and L = A^-1 J^-1 A with J the distortion's Jacobian at
// the undistorted point and A the pixel-to-normalised map (like
// Camera::pixel_to_mm / f). Model 3 (every other model, and masked
// cameras): entry lattice.z + (j w + i) of the table, h0 = (p, L00, L01),
// h1 = (L10, L11, _, _), computed on the host in f64
// (src/render/homography.rs, `pixel_maps`). Call only with a lens (model != 0).
struct PixelMap {
    p: vec2<f32>,
    l0: vec2<f32>,
    l1: vec2<f32>,
}

fn pixel_map(i: u32, j: u32) -> PixelMap {
    if (P.distortion.model == 3u) {
        let m = homs[P.lattice.z + j * P.dims.x + i];
        return PixelMap(m.h0.xy, m.h0.zw, m.h1.xy);
    }
    let c = P.pixel;
    let skew = P.pixel2.x;
    let dy = f32(j) + 0.5 - c.y;
    let k = skew * c.w;
    let qd = vec2<f32>((f32(i) + 0.5 - c.x - k * dy) * c.z, dy * c.w);
    let q = undistort(P.distortion, qd);
    let jd = jacobian(P.distortion, q);
    let det = jd[0].x * jd[1].y - jd[0].y * jd[1].x;
    // J^-1 A, A = [[sx, -k sx], [0, sy]].
    let m00 = jd[1].y / det * c.z;
    let m01 = -jd[1].y / det * k * c.z - jd[0].y / det * c.w;
    let m10 = -jd[1].x / det * c.z;
    let m11 = jd[1].x / det * k * c.z + jd[0].x / det * c.w;
    // A^-1 = [[1 / sx, skew], [0, 1 / sy]].
    return PixelMap(
        vec2<f32>(c.x + q.x / c.z + skew * q.y, c.y + q.y / c.w),
        vec2<f32>(m00 / c.z + skew * m10, m01 / c.z + skew * m11),
        vec2<f32>(m10 / c.w, m11 / c.w));
}
