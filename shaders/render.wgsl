// Ground-truth motion-blur renderer (mmbm::render). One invocation per pixel;
// for each of the pixel's samples k in [k0, k1) of a rank-1 lattice in
// (x, y, t) with a per-pixel Cranley-Patterson shift: interpolate the camera
// pose at time t from the pose table, intersect the ray through (x, y) with
// the target plane, evaluate the target (procedural checker / blob board, or a
// mip-mapped linear-light image), and accumulate into out_rgb (sums; the host
// divides by N). Registers only, no barriers (barriers are slow on lavapipe).
// CPU twin: src/render/cpu.rs. Layouts: src/render/kernel.rs.

struct Params {
    cam: vec4<f32>,        // fx, fy, cx, cy (px)
    cam2: vec4<f32>,       // skew, 1/sqrt(fx fy), LOD scale, 0
    origin: vec4<f32>,     // plane origin (m), n.O
    e1: vec4<f32>,
    e2: vec4<f32>,
    normal: vec4<f32>,
    background: vec4<f32>,
    tex: vec4<f32>,
    colour_a: vec4<f32>,
    colour_b: vec4<f32>,
    dims: vec4<u32>,       // width, height, kind, N
    lattice: vec4<u32>,    // g1, g2, K, seed
    range: vec4<u32>,      // row0, k0, k1, (k0 g1) mod N
    range2: vec4<u32>,     // (k0 g2) mod N, rows, 0, 0
}

struct Pose {
    q: vec4<f32>,
    c: vec4<f32>,
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> poses: array<Pose>;
@group(0) @binding(2) var<storage, read> texels: array<f32>;
@group(0) @binding(3) var<storage, read> levels: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read_write> out_rgb: array<vec4<f32>>;

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let u = q.xyz;
    let t = cross(u, v) + v * q.w;
    return v + 2.0 * cross(u, t);
}

fn texel(l: u32, x: u32, y: u32) -> vec3<f32> {
    let info = levels[l];
    let i = info.x + (y * info.y + x) * 3u;
    return vec3<f32>(texels[i], texels[i + 1u], texels[i + 2u]);
}

fn bilinear(l: u32, u: f32, v: f32) -> vec3<f32> {
    let info = levels[l];
    let x = clamp(u * f32(info.y) - 0.5, 0.0, f32(info.y - 1u));
    let y = clamp(v * f32(info.z) - 0.5, 0.0, f32(info.z - 1u));
    let x0 = u32(floor(x));
    let y0 = u32(floor(y));
    let x1 = min(x0 + 1u, info.y - 1u);
    let y1 = min(y0 + 1u, info.z - 1u);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let a = texel(l, x0, y0) * (1.0 - fx) + texel(l, x1, y0) * fx;
    let b = texel(l, x0, y1) * (1.0 - fx) + texel(l, x1, y1) * fx;
    return a * (1.0 - fy) + b * fy;
}

fn trilinear(u: f32, v: f32, lod_in: f32) -> vec3<f32> {
    let maxl = P.tex.w - 1.0;
    let lod = clamp(lod_in, 0.0, maxl);
    let l0 = floor(lod);
    let f = lod - l0;
    let a = bilinear(u32(l0), u, v);
    if (f == 0.0) {
        return a;
    }
    let b = bilinear(u32(l0) + 1u, u, v);
    return a + (b - a) * f;
}

fn shade(q: vec4<f32>, c: vec3<f32>, px: f32, py: f32) -> vec3<f32> {
    let bg = P.background.xyz;
    let yc = (py - P.cam.w) / P.cam.y;
    let dc = vec3<f32>((px - P.cam.z - P.cam2.x * yc) / P.cam.x, yc, 1.0);
    let dw = rotate(q, dc);
    let n = P.normal.xyz;
    let den = dot(n, dw);
    let s = (P.origin.w - dot(n, c)) / den;
    if (abs(den) < 1e-12 || !(s > 0.0)) {
        return bg;
    }
    let d = c + dw * s - P.origin.xyz;
    let a = dot(d, P.e1.xyz);
    let b = dot(d, P.e2.xyz);
    let kind = P.dims.z;
    if (kind == 0u) {
        let sz = P.tex.x;
        let k = i32(floor(a / sz)) + i32(floor(b / sz));
        return vec3<f32>(select(0.0, 1.0, (k & 1) == 0));
    }
    if (kind == 1u) {
        let sq = P.tex.x;
        let pitch = P.tex.y;
        let half = P.tex.z;
        if (abs(a) > half || abs(b) > half) {
            return bg;
        }
        let ca = (clamp(floor(a / pitch + 2.0), 0.0, 3.0) - 1.5) * pitch;
        let cb = (clamp(floor(b / pitch + 2.0), 0.0, 3.0) - 1.5) * pitch;
        if (abs(a - ca) <= 0.5 * sq && abs(b - cb) <= 0.5 * sq) {
            return P.colour_a.xyz;
        }
        return P.colour_b.xyz;
    }
    let u = a / P.tex.x + 0.5;
    let v = b / P.tex.y + 0.5;
    if (u < 0.0 || u > 1.0 || v < 0.0 || v > 1.0) {
        return bg;
    }
    let len = length(dw);
    let cosv = abs(den) / len;
    let tx = s * len * P.cam2.y / sqrt(cosv) * P.tex.z;
    let lod = log2(max(tx * P.cam2.z, 1.0));
    return trilinear(u, v, lod);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = P.dims.x;
    let i = gid.x;
    let j = gid.y + P.range.x;
    if (i >= w || gid.y >= P.range2.y || j >= P.dims.y) {
        return;
    }
    let n = P.dims.w;
    let nf = f32(n);
    let g1 = P.lattice.x;
    let g2 = P.lattice.y;
    let segs = P.lattice.z;
    let h1 = pcg(i + pcg(j + pcg(P.lattice.w)));
    let h2 = pcg(h1);
    let h3 = pcg(h2);
    let shx = unit(h1);
    let shy = unit(h2);
    let sht = unit(h3);
    var xi = P.range.w;
    var yi = P.range2.x;
    var acc = vec3<f32>(0.0);
    for (var k = P.range.y; k < P.range.z; k = k + 1u) {
        let sx = fract(f32(xi) / nf + shx);
        let sy = fract(f32(yi) / nf + shy);
        let st = fract(f32(k) / nf + sht);
        let tt = st * f32(segs);
        let idx = min(u32(tt), segs - 1u);
        let f = tt - f32(idx);
        let pa = poses[idx];
        let pb = poses[idx + 1u];
        let q = normalize(mix(pa.q, pb.q, f));
        let c = mix(pa.c.xyz, pb.c.xyz, f);
        acc = acc + shade(q, c, f32(i) + sx, f32(j) + sy);
        xi = xi + g1;
        if (xi >= n) {
            xi = xi - n;
        }
        yi = yi + g2;
        if (yi >= n) {
            yi = yi - n;
        }
    }
    let o = j * w + i;
    out_rgb[o] = out_rgb[o] + vec4<f32>(acc, 0.0);
}
