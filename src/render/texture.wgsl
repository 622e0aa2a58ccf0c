// Closed-form pixel area for image textures: the `analytic` integrator on
// `image:` targets (mmbm::render). CPU twin: src/render/exact.rs (same names;
// the derivation is there). One invocation per pixel; for each instant k in
// [k0, k1) of the pixel's line, the footprint of the pixel centre through the
// instant's homography (affine part: a parallelogram whose marginals along
// the image's axes are trapezoids U(-p, p) + U(-q, q)), and the image's
// bilinear interpolant averaged over it exactly: sum over the nodes it
// touches of wx[m] wy[n] T[m, n], with wx, wy each node's hat averaged over
// the trapezoid, at the finest mip level where the footprint reaches at most
// MAX_REACH texels per axis. f32: every weight is computed relative to its
// node from values of a few texels, so nothing large cancels (no summed-area
// table: its f32 differences would). Bindings and Params: the renderer's
// prelude (src/render/prelude.wgsl; the same bind group layout).

// Params, Homography, the bindings, line_base and pixel_map:
// src/render/prelude.wgsl, joined with the lens module (src/gpu/lens.wgsl)
// in front of this file at build (src/render/gpu.rs).

const MAX_NODES: u32 = 8u;
const MAX_REACH: f32 = 2.5;
const TINY: f32 = 1e-3;

// Mean of max(z, 0)^2 / 2 over [z - q, z + q].
fn sq_mean(z: f32, q: f32) -> f32 {
    if (z >= q) {
        return 0.5 * z * z + q * q / 6.0;
    }
    if (z <= -q) {
        return 0.0;
    }
    let t = z + q;
    return t * t * t / (12.0 * q);
}

// Mean of max(z, 0) over [z - q, z + q].
fn lin_mean(z: f32, q: f32) -> f32 {
    if (z >= q) {
        return z;
    }
    if (z <= -q) {
        return 0.0;
    }
    let t = z + q;
    return t * t / (4.0 * q);
}

// E[max(c + X, 0)], X = U(-p, p) + U(-q, q), p >= q.
fn ramp(c: f32, p: f32, q: f32) -> f32 {
    if (c >= p + q) {
        return c;
    }
    if (c <= -(p + q)) {
        return 0.0;
    }
    if (p < TINY) {
        return max(c, 0.0);
    }
    if (q < TINY) {
        let a = max(c + p, 0.0);
        let b = max(c - p, 0.0);
        return (a * a - b * b) / (4.0 * p);
    }
    return (sq_mean(c + p, q) - sq_mean(c - p, q)) / (2.0 * p);
}

fn lin_or_point(z: f32, q: f32) -> f32 {
    if (q < TINY) {
        return max(z, 0.0);
    }
    return lin_mean(z, q);
}

// P(c + X > 0).
fn above(c: f32, p: f32, q: f32) -> f32 {
    if (c >= p + q) {
        return 1.0;
    }
    if (c <= -(p + q)) {
        return 0.0;
    }
    if (p < TINY) {
        return select(0.0, 1.0, c > 0.0);
    }
    return clamp((lin_or_point(c + p, q) - lin_or_point(c - p, q)) / (2.0 * p), 0.0, 1.0);
}

// One axis of n texels, footprint centred at texel coordinate x with
// half-widths p >= q (texels): first node, count, mass inside the image; the
// weights in w.
struct Axis {
    m0: u32,
    count: u32,
    inside: f32,
    w: array<f32, 8>,
}

fn axis_weights(x: f32, p: f32, q: f32, n: u32) -> Axis {
    var a: Axis;
    a.m0 = 0u;
    a.count = 0u;
    a.inside = 0.0;
    let lo = -0.5;
    let hi = f32(n) - 0.5;
    let out_lo = 1.0 - above(x - lo, p, q);
    let out_hi = above(x - hi, p, q);
    let inside = max(1.0 - out_lo - out_hi, 0.0);
    let s = p + q;
    let m0 = i32(max(ceil(x - s - 1.0), 0.0));
    let m1 = min(i32(floor(x + s + 1.0)), i32(n) - 1);
    if (inside <= 0.0 || m1 < m0) {
        return a;
    }
    let count = min(u32(m1 - m0 + 1), MAX_NODES);
    // r[k] = R(x - m0 + 1 - k): node m0 + k reads r[k], r[k + 1], r[k + 2].
    var r: array<f32, 10>;
    let t0 = x - f32(m0) + 1.0;
    for (var k = 0u; k < count + 2u; k = k + 1u) {
        r[k] = ramp(t0 - f32(k), p, q);
    }
    for (var k = 0u; k < count; k = k + 1u) {
        let m = m0 + i32(k);
        var wk: f32;
        if (n == 1u) {
            wk = inside;
        } else if (m == 0) {
            wk = 1.0 - r[k + 1u] + r[k + 2u] - out_lo;
        } else if (m == i32(n) - 1) {
            wk = r[k] - r[k + 1u] - out_hi;
        } else {
            wk = r[k] - 2.0 * r[k + 1u] + r[k + 2u];
        }
        a.w[k] = wk;
    }
    a.m0 = u32(m0);
    a.count = count;
    a.inside = inside;
    return a;
}

// The image averaged over a footprint centred at target point (a, b) (m)
// with axis extents |da/dx|, |da/dy|, |db/dx|, |db/dy| (m per px).
fn footprint_eval(a: f32, b: f32, dax: f32, day: f32, dbx: f32, dby: f32) -> vec3<f32> {
    let bg = P.background.xyz;
    let wm = P.tex.x;
    let hm = P.tex.y;
    let u = a / wm + 0.5;
    let v = b / hm + 0.5;
    let pa = 0.5 * max(dax, day) / wm;
    let qa = 0.5 * min(dax, day) / wm;
    let pb = 0.5 * max(dbx, dby) / hm;
    let qb = 0.5 * min(dbx, dby) / hm;
    let last = u32(P.tex.w) - 1u;
    var l = 0u;
    loop {
        if (l >= last) {
            break;
        }
        let info = levels[l];
        if ((pa + qa) * f32(info.y) <= MAX_REACH && (pb + qb) * f32(info.z) <= MAX_REACH) {
            break;
        }
        l = l + 1u;
    }
    let info = levels[l];
    let sw = f32(info.y);
    let sh = f32(info.z);
    var ax = axis_weights(u * sw - 0.5, pa * sw, qa * sw, info.y);
    var ay = axis_weights(v * sh - 0.5, pb * sh, qb * sh, info.z);
    var acc = bg * (1.0 - ax.inside * ay.inside);
    for (var jy = 0u; jy < ay.count; jy = jy + 1u) {
        let row = (ay.m0 + jy) * info.y;
        var r = vec3<f32>(0.0);
        for (var jx = 0u; jx < ax.count; jx = jx + 1u) {
            let o = info.x + (row + ax.m0 + jx) * 3u;
            r = r + vec3<f32>(texels[o], texels[o + 1u], texels[o + 2u]) * ax.w[jx];
        }
        acc = acc + r * ay.w[jy];
    }
    return acc;
}

// The image averaged over the footprint of pinhole pixel point (px, py)
// through h, the pixel's axes mapped by the rows l0, l1 (identity without
// distortion; else the undistortion Jacobian, as in render.wgsl).
fn texture_mean(h: Homography, px: f32, py: f32, l0: vec2<f32>, l1: vec2<f32>) -> vec3<f32> {
    let w = h.h2.x * px + h.h2.y * py + h.h2.z;
    if (!(w > 0.0)) {
        return P.background.xyz;
    }
    let r = 1.0 / w;
    let a = (h.h0.x * px + h.h0.y * py + h.h0.z) * r;
    let b = (h.h1.x * px + h.h1.y * py + h.h1.z) * r;
    let sax = (h.h0.x - a * h.h2.x) * r;
    let say = (h.h0.y - a * h.h2.y) * r;
    let sbx = (h.h1.x - b * h.h2.x) * r;
    let sby = (h.h1.y - b * h.h2.y) * r;
    return footprint_eval(a, b, abs(sax * l0.x + say * l1.x), abs(sax * l0.y + say * l1.y),
        abs(sbx * l0.x + sby * l1.x), abs(sbx * l0.y + sby * l1.y));
}

@compute @workgroup_size(8, 8, 1)
fn texture(@builtin(global_invocation_id) gid: vec3<u32>) {
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
    var px = f32(i) + 0.5;
    var py = f32(j) + 0.5;
    var l0 = vec2<f32>(1.0, 0.0);
    var l1 = vec2<f32>(0.0, 1.0);
    if (P.distortion.model != 0u) {
        let m = pixel_map(i, j);
        px = m.p.x;
        py = m.p.y;
        l0 = m.l0;
        l1 = m.l1;
    }
    let base = line_base(i, j);
    var acc = vec3<f32>(0.0);
    for (var k = P.range.y; k < P.range.z; k = k + 1u) {
        acc = acc + texture_mean(homs[base + k], px, py, l0, l1);
    }
    out_rgb[o] = out_rgb[o] + vec4<f32>(acc, 0.0);
}
