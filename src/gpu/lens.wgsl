// Lens distortion (docs/spec.md section 9) in normalised coordinates q = (x, y),
// the one lens module of the kernels: joined at build in front of every
// kernel that evaluates a lens, src/field/field.wgsl,
// src/series/maps/maps.wgsl and the renderer's src/render/render.wgsl and
// texture.wgsl (with the renderer's prelude between), each holding a `Lens`
// in its Params (src/gpu/lens.rs: the joined sources, the host struct
// `LensGpu` and the CPU twin of every function here, with the same names
// and operations).
//
// The distortion map, its Jacobian at q and its inverse by Newton's method
// (a fixed UNDISTORT_STEPS steps from the distorted point), for the two
// analytic models. The fisheye model needs atan; WGSL's built-in is only
// specified to 4096 ULP, so the kernels use their own polynomial
// (Abramowitz & Stegun 4.4.49, |error| <= 2e-8 on [0, 1]) that the twin
// evaluates with the same operations. Every other model is table mode
// (model 3): the host computes the lens's values with the library's f64
// camera code and the kernel reads them (each kernel's table is its own:
// src/field/table.rs, src/series/maps/table.rs, the renderer's per-pixel
// maps in src/render/homography.rs). One strategy in every kernel: formula
// for models 1-2, host table for model 3.

// The lens of a kernel's Params. Must match `LensGpu` (32 bytes).
struct Lens {
    dist: vec4<f32>,    // OpenCV: k1, k2, p1, p2; fisheye: k1, k2, k3, k4
    k3: f32,            // OpenCV: k3
    model: u32,         // 0 none, 1 OpenCV (k1 k2 p1 p2 | k3), 2 fisheye (k1..k4), 3 lens table
    pad0: u32,
    pad1: u32,
}

const UNDISTORT_STEPS: u32 = 16u;

// atan(x) for x >= 0.
fn atan_poly(x: f32) -> f32 {
    let inv = x > 1.0;
    var z = x;
    if (inv) {
        z = 1.0 / x;
    }
    let z2 = z * z;
    let p = 1.0 + z2 * (-0.3333314528 + z2 * (0.1999355085 + z2 * (-0.1420889944
        + z2 * (0.1065626393 + z2 * (-0.0752896400 + z2 * (0.0429096138
        + z2 * (-0.0161657367 + z2 * 0.0028662257)))))));
    let a = z * p;
    if (inv) {
        return 1.5707964 - a; // pi/2 in f32, as the twin's FRAC_PI_2
    }
    return a;
}

// Fisheye: theta_d(theta) and its derivative.
fn fisheye_theta_d(lens: Lens, th: f32) -> vec2<f32> {
    let k = lens.dist;
    let t2 = th * th;
    let poly = 1.0 + t2 * (k.x + t2 * (k.y + t2 * (k.z + t2 * k.w)));
    let d = 1.0 + t2 * (3.0 * k.x + t2 * (5.0 * k.y + t2 * (7.0 * k.z + t2 * 9.0 * k.w)));
    return vec2<f32>(th * poly, d);
}

// Fisheye: s = theta_d / r and (ds/dr) / r at q (series near the axis).
fn fisheye_scale(lens: Lens, q: vec2<f32>) -> vec2<f32> {
    let k = lens.dist;
    let r2 = q.x * q.x + q.y * q.y;
    if (r2 < 1e-4) {
        let c = k.x - 1.0 / 3.0;
        let e = 0.2 - k.x + k.y;
        return vec2<f32>(1.0 + r2 * (c + r2 * e), 2.0 * c + 4.0 * e * r2);
    }
    let r = sqrt(r2);
    let th = atan_poly(r);
    let td = fisheye_theta_d(lens, th);
    let s = td.x / r;
    return vec2<f32>(s, (td.y / (1.0 + r2) - s) / r2);
}

// The distorted point of q (model 1 or 2).
fn distort(lens: Lens, q: vec2<f32>) -> vec2<f32> {
    if (lens.model == 1u) {
        let k = lens.dist;
        let r2 = q.x * q.x + q.y * q.y;
        let radial = 1.0 + r2 * (k.x + r2 * (k.y + r2 * lens.k3));
        return vec2<f32>(
            q.x * radial + 2.0 * k.z * q.x * q.y + k.w * (r2 + 2.0 * q.x * q.x),
            q.y * radial + k.z * (r2 + 2.0 * q.y * q.y) + 2.0 * k.w * q.x * q.y);
    }
    return fisheye_scale(lens, q).x * q;
}

// Rows of the Jacobian at q: (dxd/dx, dxd/dy), (dyd/dx, dyd/dy) (model 1 or 2).
fn jacobian(lens: Lens, q: vec2<f32>) -> array<vec2<f32>, 2> {
    if (lens.model == 1u) {
        let k = lens.dist;
        let r2 = q.x * q.x + q.y * q.y;
        let radial = 1.0 + r2 * (k.x + r2 * (k.y + r2 * lens.k3));
        let drad = k.x + r2 * (2.0 * k.y + r2 * 3.0 * lens.k3);
        let off = 2.0 * q.x * q.y * drad + 2.0 * k.z * q.x + 2.0 * k.w * q.y;
        return array<vec2<f32>, 2>(
            vec2<f32>(radial + 2.0 * q.x * q.x * drad + 2.0 * k.z * q.y + 6.0 * k.w * q.x, off),
            vec2<f32>(off, radial + 2.0 * q.y * q.y * drad + 6.0 * k.z * q.y + 2.0 * k.w * q.x));
    }
    let sg = fisheye_scale(lens, q);
    let off = sg.y * q.x * q.y;
    return array<vec2<f32>, 2>(
        vec2<f32>(sg.x + sg.y * q.x * q.x, off),
        vec2<f32>(off, sg.x + sg.y * q.y * q.y));
}

// The undistorted point of qd (model 1 or 2).
fn undistort(lens: Lens, qd: vec2<f32>) -> vec2<f32> {
    if (lens.model == 2u) {
        let rd = length(qd);
        if (rd == 0.0) {
            return qd;
        }
        // Newton on r: theta_d(atan(r)) = r_d, d/dr = theta_d'(theta) / (1 + r^2).
        var r = rd;
        for (var k = 0u; k < UNDISTORT_STEPS; k++) {
            let td = fisheye_theta_d(lens, atan_poly(r));
            r = max(r - (td.x - rd) * (1.0 + r * r) / td.y, 0.0);
        }
        return qd * (r / rd);
    }
    var q = qd;
    for (var k = 0u; k < UNDISTORT_STEPS; k++) {
        let e = distort(lens, q) - qd;
        let j = jacobian(lens, q);
        let det = j[0].x * j[1].y - j[0].y * j[1].x;
        q -= vec2<f32>(j[1].y * e.x - j[0].y * e.y, -j[1].x * e.x + j[0].x * e.y) / det;
    }
    return q;
}
