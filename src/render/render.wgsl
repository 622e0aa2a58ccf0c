// Ground-truth motion-blur renderer (mmbm::render). One invocation per pixel;
// for each of the pixel's samples k in [k0, k1) of a rank-1 lattice in
// (x, y, t) with a per-pixel Cranley-Patterson shift in x and y:
// map the sample point through the homography of its instant (pixel to
// target-plane coordinates, one table entry per instant, computed on the
// host), evaluate the target (procedural checker / blob board, or a
// mip-mapped linear-light image), and accumulate into out_rgb (sums; the host
// divides by N). Pixels outside the target's bounding box over the exposure
// add the background without sampling. Registers only, no barriers (barriers
// are slow on lavapipe). CPU twin: src/render/cpu.rs. Layouts:
// src/render/kernel.rs.
//
// Entry points: `main` supersamples area and time (any target; the only one
// for images); `analytic` (checker and blob board) takes one sample per
// instant at the pixel centre and integrates the pixel's area in closed form:
// the footprint is the parallelogram that the affine part of the homography
// makes of the pixel square, and the target is averaged over the
// footprint's marginal distributions along its two axes (each a trapezoid,
// the sum of two uniform variables), taken as independent. That is exact for
// footprints aligned with the target's axes and, in general, wherever one
// edge crosses the footprint; it is approximate only where two edges do (a
// corner inside a pixel). Formulas and their derivation: src/render/cpu.rs.

// Params, Homography, the bindings, line_base and pixel_map:
// src/render/prelude.wgsl, joined with the lens module (src/gpu/lens.wgsl)
// in front of this file at build (src/render/gpu.rs).

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
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

// The poster (src/render/poster.rs) at plane point (a, b), or the plain
// background without one.
fn poster_point(a: f32, b: f32) -> vec3<f32> {
    var c = P.background.xyz;
    let n = u32(P.lod.z);
    if (n == 0u || abs(a) > P.poster[1].w || abs(b) > P.poster[3].w) {
        return c;
    }
    for (var k = 0u; k < n; k = k + 1u) {
        let l = P.poster[2u * k];
        let s = i32(floor((a + l.z) * l.y)) + i32(floor((b + l.w) * l.y));
        c = c + select(-1.0, 1.0, (s & 1) == 0) * P.poster[2u * k + 1u].xyz;
    }
    return c;
}

fn shade(h: Homography, px: f32, py: f32) -> vec3<f32> {
    let bg = P.background.xyz;
    let w = h.h2.x * px + h.h2.y * py + h.h2.z;
    if (!(w > 0.0)) {
        return bg;
    }
    let r = 1.0 / w;
    let a = (h.h0.x * px + h.h0.y * py + h.h0.z) * r;
    let b = (h.h1.x * px + h.h1.y * py + h.h1.z) * r;
    let kind = P.dims.z;
    if (kind == 0u) {
        let inv_sz = P.tex.y;
        let k = i32(floor(a * inv_sz)) + i32(floor(b * inv_sz));
        return vec3<f32>(select(0.0, 1.0, (k & 1) == 0));
    }
    if (kind == 1u) {
        let sq = P.tex.x;
        let pitch = P.tex.y;
        let half = P.tex.z;
        if (abs(a) > half || abs(b) > half) {
            return poster_point(a, b);
        }
        let inv_pitch = P.tex.w;
        let ca = (clamp(floor(a * inv_pitch + 2.0), 0.0, 3.0) - 1.5) * pitch;
        let cb = (clamp(floor(b * inv_pitch + 2.0), 0.0, 3.0) - 1.5) * pitch;
        if (abs(a - ca) <= 0.5 * sq && abs(b - cb) <= 0.5 * sq) {
            return P.colour_a.xyz;
        }
        return P.colour_b.xyz;
    }
    let u = a / P.tex.x + 0.5;
    let v = b / P.tex.y + 0.5;
    if (u < 0.0 || u > 1.0 || v < 0.0 || v > 1.0) {
        return poster_point(a, b);
    }
    // Footprint side (m) = sqrt(|det H| / w^3); in texels of level 0.
    let tx = sqrt(h.h2.w * r * r * r) * P.tex.z;
    let lod = log2(max(tx * P.lod.x, 1.0));
    return trilinear(u, v, lod);
}

// Lens distortion (docs/spec.md section 9): sample (sx, sy) of a pixel
// through its map m (pixel_map, src/render/prelude.wgsl): p + L (sx - 1/2,
// sy - 1/2), first order in the pixel.
fn pixel_point(m: PixelMap, sx: f32, sy: f32) -> vec2<f32> {
    let dx = sx - 0.5;
    let dy = sy - 0.5;
    return vec2<f32>(m.p.x + m.l0.x * dx + m.l0.y * dy, m.p.y + m.l1.x * dx + m.l1.y * dy);
}

// Defocus (docs/spec.md section 9, thin lens): a uniform point of the unit disc from a point
// of the unit square (Shirley-Chiu concentric map; sine and cosine as
// polynomials on [-pi/4, pi/4], like the twin's).
fn sin_p(x: f32) -> f32 {
    let x2 = x * x;
    return x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
}

fn cos_p(x: f32) -> f32 {
    let x2 = x * x;
    return 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
}

fn concentric(u: f32, v: f32) -> vec2<f32> {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if (a == 0.0 && b == 0.0) {
        return vec2<f32>(0.0);
    }
    let q = 0.7853982; // pi/4 in f32
    if (abs(a) > abs(b)) {
        let t = q * (b / a);
        return vec2<f32>(a * cos_p(t), a * sin_p(t));
    }
    let t = q * (a / b);
    return vec2<f32>(b * sin_p(t), b * cos_p(t));
}

// Defocus: the homography of the camera moved to lens point l (m) is
// H + l.x Gx + l.y Gy (entries e, e + 1, e + 2), seen through the pixel point
// shifted by -K l / s.
fn lens_sample(e: u32, l: vec2<f32>, q: vec2<f32>) -> vec3<f32> {
    let h = homs[e];
    let gx = homs[e + 1u];
    let gy = homs[e + 2u];
    let hl = Homography(
        h.h0 + l.x * gx.h0 + l.y * gy.h0,
        h.h1 + l.x * gx.h1 + l.y * gy.h1,
        vec4<f32>(h.h2.xyz + l.x * gx.h2.xyz + l.y * gy.h2.xyz, h.h2.w));
    let p = q - vec2<f32>(l.x * P.lens.y + l.y * P.lens.w, l.y * P.lens.z);
    return shade(hl, p.x, p.y);
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
    let o = j * w + i;
    let count = P.range.z - P.range.y;
    if (i < P.bbox.x || j < P.bbox.y || i >= P.bbox.z || j >= P.bbox.w) {
        out_rgb[o] = out_rgb[o] + vec4<f32>(P.background.xyz * f32(count), 0.0);
        return;
    }
    let g1 = P.lattice.x;
    let g2 = P.lattice.y;
    let h1 = pcg(i + pcg(j + pcg(P.lattice.w)));
    let h2 = pcg(h1);
    let shx = unit(h1);
    let shy = unit(h2);
    let inv_n = P.lod.y;
    var xi = P.range.w;
    var yi = P.range2.x;
    var acc = vec3<f32>(0.0);
    let fi = f32(i);
    let fj = f32(j);
    let base = line_base(i, j);
    // Lens distortion: the pixel's map (see pixel_point).
    let distorted = P.distortion.model != 0u;
    var m = PixelMap(vec2<f32>(0.0), vec2<f32>(0.0), vec2<f32>(0.0));
    if (distorted) {
        m = pixel_map(i, j);
    }
    // Defocus: two more lattice dimensions with their own per-pixel shifts.
    let h3 = pcg(h2);
    let h4 = pcg(h3);
    let shl = vec2<f32>(unit(h3), unit(h4));
    var xl = P.lens_gen.z;
    var yl = P.lens_gen.w;
    for (var k = P.range.y; k < P.range.z; k = k + 1u) {
        let sx = fract(f32(xi) * inv_n + shx);
        let sy = fract(f32(yi) * inv_n + shy);
        var q = vec2<f32>(fi + sx, fj + sy);
        if (distorted) {
            q = pixel_point(m, sx, sy);
        }
        if (P.lens.x > 0.0) {
            let d = concentric(fract(f32(xl) * inv_n + shl.x), fract(f32(yl) * inv_n + shl.y));
            acc = acc + lens_sample((base + k) * 3u, d * P.lens.x, q);
            xl = xl + P.lens_gen.x;
            if (xl >= n) {
                xl = xl - n;
            }
            yl = yl + P.lens_gen.y;
            if (yl >= n) {
                yl = yl - n;
            }
        } else {
            acc = acc + shade(homs[base + k], q.x, q.y);
        }
        xi = xi + g1;
        if (xi >= n) {
            xi = xi - n;
        }
        yi = yi + g2;
        if (yi >= n) {
            yi = yi - n;
        }
    }
    out_rgb[o] = out_rgb[o] + vec4<f32>(acc, 0.0);
}

// ---- analytic area integration (twin: src/render/cpu.rs, same names) ----

// Feature-relative width below which a footprint is a point.
const TINY: f32 = 0.001;

// Integral from 0 of the square wave s (+1 on [0, S), -1 on [S, 2S), period
// 2S): a triangle wave in [0, S]. `is` = 1/S.
fn tri(x: f32, sz: f32, is: f32) -> f32 {
    let y = x - floor(x * (0.5 * is)) * (2.0 * sz);
    return select(2.0 * sz - y, y, y < sz);
}

// Integral from 0 of tri, for y >= 0.
fn tri_int(y: f32, sz: f32, is: f32) -> f32 {
    let per = floor(y * (0.5 * is));
    let r = y - per * 2.0 * sz;
    var v = 0.5 * r * r;
    if (r >= sz) {
        v = 0.5 * sz * sz + 2.0 * sz * (r - sz) - 0.5 * (r * r - sz * sz);
    }
    return per * sz * sz + v;
}

// Mean of tri over [c - q, c + q].
fn tri_mean(c: f32, q: f32, sz: f32, is: f32) -> f32 {
    if (q < TINY * sz) {
        return tri(c, sz, is);
    }
    if (q < 0.25 * sz) {
        // One kink at most: the nearest multiple of S (slope change +2 at
        // even multiples, -2 at odd ones).
        let k = round(c * is);
        let d = abs(c - k * sz);
        var m = tri(c, sz, is);
        if (d < q) {
            let delta = select(-2.0, 2.0, (i32(k) & 1) == 0);
            m = m + delta * (q - d) * (q - d) / (4.0 * q);
        }
        return m;
    }
    let base = floor((c - q) * (0.5 * is)) * (2.0 * sz);
    return (tri_int(c + q - base, sz, is) - tri_int(c - q - base, sz, is)) / (2.0 * q);
}

// Mean of the square wave s over x + U(-p, p) + U(-q, q), p >= q.
fn square_mean(x: f32, p: f32, q: f32, sz: f32, is: f32) -> f32 {
    // No edge within reach (most footprints), or a point footprint: s(x).
    let k = round(x * is);
    if (abs(x - k * sz) >= p + q || p < TINY * sz) {
        return select(-1.0, 1.0, (i32(floor(x * is)) & 1) == 0);
    }
    return (tri_mean(x + p, q, sz, is) - tri_mean(x - p, q, sz, is)) / (2.0 * p);
}

// Mean of max(c, 0) over [c - q, c + q].
fn ramp_mean(c: f32, q: f32, tiny: f32) -> f32 {
    var m = max(c, 0.0);
    if (q >= tiny && abs(c) < q) {
        m = m + (q - abs(c)) * (q - abs(c)) / (4.0 * q);
    }
    return m;
}

// P(U(-p, p) + U(-q, q) <= x), p >= q.
fn trap_cdf(x: f32, p: f32, q: f32, tiny: f32) -> f32 {
    if (x >= p + q) {
        return 1.0;
    }
    if (x <= -(p + q)) {
        return 0.0;
    }
    if (p < tiny) {
        return select(0.0, 1.0, x >= 0.0);
    }
    return clamp((ramp_mean(x + p, q, tiny) - ramp_mean(x - p, q, tiny)) / (2.0 * p), 0.0, 1.0);
}

// P(lo <= c + U(-p, p) + U(-q, q) <= hi).
fn trap_in(lo: f32, hi: f32, c: f32, p: f32, q: f32, tiny: f32) -> f32 {
    return trap_cdf(hi - c, p, q, tiny) - trap_cdf(lo - c, p, q, tiny);
}

// The poster averaged over a footprint with marginal half-widths (pa, qa)
// along a and (pb, qb) along b (each layer a product of square waves).
fn poster_mean(a: f32, b: f32, pa: f32, qa: f32, pb: f32, qb: f32) -> vec3<f32> {
    let bg = P.background.xyz;
    let ha = P.poster[1].w;
    let hb = P.poster[3].w;
    // The poster's coverage of the footprint (independent axes, as the board's).
    let cover = trap_in(-ha, ha, a, pa, qa, TINY * ha) * trap_in(-hb, hb, b, pb, qb, TINY * hb);
    if (cover <= 0.0) {
        return bg;
    }
    var c = bg;
    let n = u32(P.lod.z);
    for (var k = 0u; k < n; k = k + 1u) {
        let l = P.poster[2u * k];
        let m = square_mean(a + l.z, pa, qa, l.x, l.y) * square_mean(b + l.w, pb, qb, l.x, l.y);
        c = c + m * P.poster[2u * k + 1u].xyz;
    }
    return bg + (c - bg) * cover;
}

// Board and blob-column (or row) coverage along one axis: (board, blobs).
fn board_axis(c: f32, p: f32, q: f32) -> vec2<f32> {
    let sq = P.tex.x;
    let pitch = P.tex.y;
    let half = P.tex.z;
    let tiny = TINY * sq;
    let board = trap_in(-half, half, c, p, q, tiny);
    var blobs = 0.0;
    for (var k = 0; k < 4; k = k + 1) {
        let cc = (f32(k) - 1.5) * pitch;
        blobs = blobs + trap_in(cc - 0.5 * sq, cc + 0.5 * sq, c, p, q, tiny);
    }
    return vec2<f32>(board, blobs);
}

// The target averaged over the footprint of pixel centre (px, py) at one instant.
fn footprint_mean(h: Homography, px: f32, py: f32) -> vec3<f32> {
    let bg = P.background.xyz;
    let w = h.h2.x * px + h.h2.y * py + h.h2.z;
    if (!(w > 0.0)) {
        return bg;
    }
    let r = 1.0 / w;
    let a = (h.h0.x * px + h.h0.y * py + h.h0.z) * r;
    let b = (h.h1.x * px + h.h1.y * py + h.h1.z) * r;
    // Half-widths of the footprint's extent along a and b (affine part of H).
    let dax = abs((h.h0.x - a * h.h2.x) * r);
    let day = abs((h.h0.y - a * h.h2.y) * r);
    let dbx = abs((h.h1.x - b * h.h2.x) * r);
    let dby = abs((h.h1.y - b * h.h2.y) * r);
    return footprint_eval(a, b, dax, day, dbx, dby);
}

// Lens distortion: (px, py) are the pinhole pixel coordinates of the pixel
// centre's ray and (l0, l1) the rows of the Jacobian of undistortion there,
// so the footprint's axes are the homography's derivatives times it.
fn footprint_mean_l(h: Homography, px: f32, py: f32, l0: vec2<f32>, l1: vec2<f32>) -> vec3<f32> {
    let bg = P.background.xyz;
    let w = h.h2.x * px + h.h2.y * py + h.h2.z;
    if (!(w > 0.0)) {
        return bg;
    }
    let r = 1.0 / w;
    let a = (h.h0.x * px + h.h0.y * py + h.h0.z) * r;
    let b = (h.h1.x * px + h.h1.y * py + h.h1.z) * r;
    let sax = (h.h0.x - a * h.h2.x) * r;
    let say = (h.h0.y - a * h.h2.y) * r;
    let sbx = (h.h1.x - b * h.h2.x) * r;
    let sby = (h.h1.y - b * h.h2.y) * r;
    let dax = abs(sax * l0.x + say * l1.x);
    let day = abs(sax * l0.y + say * l1.y);
    let dbx = abs(sbx * l0.x + sby * l1.x);
    let dby = abs(sbx * l0.y + sby * l1.y);
    return footprint_eval(a, b, dax, day, dbx, dby);
}

fn footprint_eval(a: f32, b: f32, dax: f32, day: f32, dbx: f32, dby: f32) -> vec3<f32> {
    let bg = P.background.xyz;
    let pa = 0.5 * max(dax, day);
    let qa = 0.5 * min(dax, day);
    let pb = 0.5 * max(dbx, dby);
    let qb = 0.5 * min(dbx, dby);
    if (P.dims.z == 0u) {
        let sz = P.tex.x;
        let is = P.tex.y;
        let m = square_mean(a, pa, qa, sz, is) * square_mean(b, pb, qb, sz, is);
        return vec3<f32>(0.5 + 0.5 * m);
    }
    let ca = board_axis(a, pa, qa);
    let cb = board_axis(b, pb, qb);
    let white = P.colour_b.xyz;
    let red = P.colour_a.xyz;
    // Behind the board: the poster where there is one (not needed where the
    // board covers the whole footprint).
    let board = ca.x * cb.x;
    var back = bg;
    if (P.lod.z > 0.0 && board < 1.0) {
        back = poster_mean(a, b, pa, qa, pb, qb);
    }
    return back + (white - back) * board + (red - white) * (ca.y * cb.y);
}

@compute @workgroup_size(8, 8, 1)
fn analytic(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = P.dims.x;
    let i = gid.x;
    let j = gid.y + P.range.x;
    if (i >= w || gid.y >= P.range2.y || j >= P.dims.y) {
        return;
    }
    let o = j * w + i;
    let count = P.range.z - P.range.y;
    if (i < P.bbox.x || j < P.bbox.y || i >= P.bbox.z || j >= P.bbox.w) {
        out_rgb[o] = out_rgb[o] + vec4<f32>(P.background.xyz * f32(count), 0.0);
        return;
    }
    let px = f32(i) + 0.5;
    let py = f32(j) + 0.5;
    var acc = vec3<f32>(0.0);
    let base = line_base(i, j);
    if (P.distortion.model != 0u) {
        let m = pixel_map(i, j);
        for (var k = P.range.y; k < P.range.z; k = k + 1u) {
            acc = acc + footprint_mean_l(homs[base + k], m.p.x, m.p.y, m.l0, m.l1);
        }
    } else {
        for (var k = P.range.y; k < P.range.z; k = k + 1u) {
            acc = acc + footprint_mean(homs[base + k], px, py);
        }
    }
    out_rgb[o] = out_rgb[o] + vec4<f32>(acc, 0.0);
}
