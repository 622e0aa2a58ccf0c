// Per-pixel blur fields of a video frame (`mmbm frames --maps`, docs/spec.md section
// 9): each pixel's image track over its own line's exposure (rolling
// shutter), its displacement, path length and start flow. The CPU twin of
// every function is in src/series/maps_kernel.rs, the f64 reference in
// src/series/maps.rs, the host structs in src/series/maps_kernel.rs.
//
// Per pixel the host gives the undistorted ray r = (x, y, 1) (normalised;
// once per camera) and per line the motion samples (q_k, b_k): the rotation
// from the line's start frame to instant k's (a unit quaternion) and the
// offset of the start's centre in instant k's frame (m), k = 0..steps. The
// scene point's inverse depth along the ray is s = plane . (x, y, 1) (zero
// for rotation only). The track is project(rot(q_k) r + b_k s) through the
// lens; the path is the sum of its chords, the displacement its end minus
// its start (px, +x right, +y down). Units: px for positions, px/s for the
// flow, the flow polynomial in mm/s at sensor points in mm.

// Camera, lines and lens. Must match `MapsParams` (96 bytes).
struct Params {
    width: u32,         // frame size, px
    height: u32,
    line_len: u32,      // pixels per line (width when lines are rows)
    rows: u32,          // 1: lines are rows, 0: columns
    first_line: u32,    // first line of this dispatch
    n_lines: u32,       // lines in this dispatch
    steps: u32,         // chords per line (steps + 1 motion samples)
    use_plane: u32,     // 1: a scene plane (s must be > 0)
    f_mm: f32,          // focal length, mm
    fx: f32,            // f / pitch_x: px per normalised unit
    fy: f32,            // f / pitch_y
    skew: f32,          // skew, px per normalised unit of y
    pitch_x: f32,       // pixel pitch, mm
    pitch_y: f32,
    skew_over_f: f32,   // skew (px) / f (mm)
    dist_model: u32,    // lens distortion: 0 none, 1 OpenCV (k1 k2 p1 p2 | k3), 2 fisheye (k1..k4)
    dist: vec4<f32>,    // OpenCV: k1, k2, p1, p2; fisheye: k1, k2, k3, k4
    dist_k3: f32,       // OpenCV: k3
    groups_x: u32,      // workgroups along x of the dispatch
    pad0: u32,
    pad1: u32,
}

// One line. Must match `LineGpu` (64 bytes).
struct Line {
    // The flow at the line's start (mm/s at sensor point (u, v) mm):
    // du = c0 + u (c1 + c3 u + c4 v) + v (c2 + c5 v), dv likewise with
    // d0..d5; packed as (c0 c1 c2 c3) (c4 c5 d0 d1) (d2 d3 d4 d5).
    poly: array<vec4<f32>, 3>,
    // Inverse depth along the ray (x, y, 1): plane.x x + plane.y y + plane.z (1/m).
    plane: vec4<f32>,
}

// One motion sample. Must match `StepGpu` (32 bytes).
struct Step {
    q: vec4<f32>,   // rotation from the line's start frame, quaternion (x, y, z, w)
    b: vec4<f32>,   // xyz: offset of the start's centre, m
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> rays: array<vec4<f32>>;   // per pixel (x, y, ok, 0)
@group(0) @binding(2) var<storage, read> lines: array<Line>;       // this dispatch's lines
@group(0) @binding(3) var<storage, read> steps: array<Step>;       // steps + 1 per line
@group(0) @binding(4) var<storage, read_write> out: array<f32>;    // 5 planes of width * height

const WG: u32 = 64u;

// Lens distortion (docs/spec.md section 9) in normalised coordinates: copied from
// shaders/field.wgsl (a test keeps the copies equal); twins in src/field/cpu.rs.
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
fn fisheye_theta_d(th: f32) -> vec2<f32> {
    let k = params.dist;
    let t2 = th * th;
    let poly = 1.0 + t2 * (k.x + t2 * (k.y + t2 * (k.z + t2 * k.w)));
    let d = 1.0 + t2 * (3.0 * k.x + t2 * (5.0 * k.y + t2 * (7.0 * k.z + t2 * 9.0 * k.w)));
    return vec2<f32>(th * poly, d);
}

// Fisheye: s = theta_d / r and (ds/dr) / r at q (series near the axis).
fn fisheye_scale(q: vec2<f32>) -> vec2<f32> {
    let k = params.dist;
    let r2 = q.x * q.x + q.y * q.y;
    if (r2 < 1e-4) {
        let c = k.x - 1.0 / 3.0;
        let e = 0.2 - k.x + k.y;
        return vec2<f32>(1.0 + r2 * (c + r2 * e), 2.0 * c + 4.0 * e * r2);
    }
    let r = sqrt(r2);
    let th = atan_poly(r);
    let td = fisheye_theta_d(th);
    let s = td.x / r;
    return vec2<f32>(s, (td.y / (1.0 + r2) - s) / r2);
}

fn distort(q: vec2<f32>) -> vec2<f32> {
    if (params.dist_model == 1u) {
        let k = params.dist;
        let r2 = q.x * q.x + q.y * q.y;
        let radial = 1.0 + r2 * (k.x + r2 * (k.y + r2 * params.dist_k3));
        return vec2<f32>(
            q.x * radial + 2.0 * k.z * q.x * q.y + k.w * (r2 + 2.0 * q.x * q.x),
            q.y * radial + k.z * (r2 + 2.0 * q.y * q.y) + 2.0 * k.w * q.x * q.y);
    }
    return fisheye_scale(q).x * q;
}

// Rows of the Jacobian: (dxd/dx, dxd/dy), (dyd/dx, dyd/dy).
fn jacobian(q: vec2<f32>) -> array<vec2<f32>, 2> {
    if (params.dist_model == 1u) {
        let k = params.dist;
        let r2 = q.x * q.x + q.y * q.y;
        let radial = 1.0 + r2 * (k.x + r2 * (k.y + r2 * params.dist_k3));
        let drad = k.x + r2 * (2.0 * k.y + r2 * 3.0 * params.dist_k3);
        let off = 2.0 * q.x * q.y * drad + 2.0 * k.z * q.x + 2.0 * k.w * q.y;
        return array<vec2<f32>, 2>(
            vec2<f32>(radial + 2.0 * q.x * q.x * drad + 2.0 * k.z * q.y + 6.0 * k.w * q.x, off),
            vec2<f32>(off, radial + 2.0 * q.y * q.y * drad + 6.0 * k.z * q.y + 2.0 * k.w * q.x));
    }
    let sg = fisheye_scale(q);
    let off = sg.y * q.x * q.y;
    return array<vec2<f32>, 2>(
        vec2<f32>(sg.x + sg.y * q.x * q.x, off),
        vec2<f32>(off, sg.x + sg.y * q.y * q.y));
}

// The flow (mm/s, undistorted sensor) of line l at sensor point (u, v) mm.
fn line_flow(l: Line, u: f32, v: f32) -> vec2<f32> {
    let a = l.poly[0];
    let b = l.poly[1];
    let c = l.poly[2];
    let du = a.x + u * (a.y + a.w * u + b.x * v) + v * (a.z + b.y * v);
    let dv = b.z + u * (b.w + c.y * u + c.z * v) + v * (c.x + c.w * v);
    return vec2<f32>(du, dv);
}

// The track point of ray r (z = 1) with inverse depth s at motion sample st:
// xy its normalised pinhole point minus r's, z the depth ratio (> 0 in
// front). The rotation in difference form, rot(q) r - r = 2 w (v x r) +
// 2 v x (v x r), keeps the digits of small motions.
fn moved(st: Step, r: vec3<f32>, s: f32) -> vec3<f32> {
    let v = st.q.xyz;
    let c = cross(v, r);
    let d = 2.0 * st.q.w * c + 2.0 * cross(v, c) + st.b.xyz * s;
    let z = 1.0 + d.z;
    return vec3<f32>((d.x - r.x * d.z) / z, (d.y - r.y * d.z) / z, z);
}

// Pixel position (less the principal point) of the ray r + e: without
// distortion that of e alone (positions enter only as differences).
fn position(r: vec2<f32>, e: vec2<f32>) -> vec2<f32> {
    var q = e;
    if (params.dist_model != 0u) {
        q = distort(r + e);
    }
    return vec2<f32>(params.fx * q.x + params.skew * q.y, params.fy * q.y);
}

// Sensor velocity (mm/s) to pixel velocity (px/s); like Camera::mm_to_px_velocity.
fn px_velocity(d: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(d.x / params.pitch_x + params.skew_over_f * d.y, d.y / params.pitch_y);
}

// One thread per pixel of the dispatch's lines. Writes disp.u, disp.v,
// path_px, flow.u, flow.v to planes 0..4; a pixel without a value (no ray,
// scene point behind the camera or off the plane) gets path -1.
@compute @workgroup_size(64)
fn maps(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let idx = (wg.y * params.groups_x + wg.x) * WG + lid;
    if (idx >= params.n_lines * params.line_len) {
        return;
    }
    let ll = idx / params.line_len;
    let m = idx % params.line_len;
    let line = params.first_line + ll;
    var i = m;
    var j = line;
    if (params.rows == 0u) {
        i = line;
        j = m;
    }
    let n = params.width * params.height;
    let pix = j * params.width + i;
    let ray = rays[pix];
    let l = lines[ll];
    let r = vec3<f32>(ray.x, ray.y, 1.0);
    let s = l.plane.x * r.x + l.plane.y * r.y + l.plane.z;
    var ok = ray.z != 0.0 && (params.use_plane == 0u || s > 0.0);
    var first = vec2<f32>(0.0, 0.0);
    var prev = vec2<f32>(0.0, 0.0);
    var path = 0.0;
    let base = ll * (params.steps + 1u);
    for (var k = 0u; ok && k <= params.steps; k++) {
        let t = moved(steps[base + k], r, s);
        if (!(t.z > 1e-12)) {
            ok = false;
            break;
        }
        let p = position(r.xy, t.xy);
        if (k == 0u) {
            first = p;
        } else {
            let d = p - prev;
            path += sqrt(d.x * d.x + d.y * d.y);
        }
        prev = p;
    }
    if (!ok) {
        out[2u * n + pix] = -1.0;
        return;
    }
    var fl = line_flow(l, params.f_mm * r.x, params.f_mm * r.y);
    if (params.dist_model != 0u) {
        let jm = jacobian(r.xy);
        fl = vec2<f32>(dot(jm[0], fl), dot(jm[1], fl));
    }
    let fv = px_velocity(fl);
    out[pix] = prev.x - first.x;
    out[n + pix] = prev.y - first.y;
    out[2u * n + pix] = path;
    out[3u * n + pix] = fv.x;
    out[4u * n + pix] = fv.y;
}
