// Per-pixel blur fields of a video frame (`mmbm frames --maps`, docs/spec.md section
// 9): each pixel's image track over its own line's exposure (rolling
// shutter), its displacement, path length and start flow. The CPU twin of
// every function is in src/series/maps_kernel.rs (the lens table's in
// src/series/maps/table.rs), the f64 reference in
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

// Camera, lines and lens. Must match `MapsParams` (128 bytes).
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
    groups_x: u32,      // workgroups along x of the dispatch
    lens: Lens,         // lens distortion (src/gpu/lens.wgsl); model 3: the lens table
    table: vec4<f32>,   // lens table: node (0, 0) at (x, y) (normalised), 1 / spacing, spacing
    table_n: vec4<u32>, // lens table: nodes along x, along y, 0, 0
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

// Lens table mode (lens model 3, every model without a formula in the lens
// module): the distortion map on a regular grid of the undistorted
// normalised plane covering the camera's rays with a margin, computed on the
// host (src/series/maps/table.rs, f64): per node its distorted point and
// its derivatives, d/dx and d/dy times the spacing and d2/dxdy times its
// square. The kernel interpolates bicubically (Hermite), continuing the
// border cells' cubics beyond the grid. The Jacobian at each pixel's ray
// (for its flow) is the host's too (`ray_jac`, as the field kernel's lens
// table). Must match `NodeGpu` (32 bytes).
struct Node {
    d: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
    dxy: vec2<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> rays: array<vec4<f32>>;   // per pixel (x, y, ok, 0)
@group(0) @binding(2) var<storage, read> lines: array<Line>;       // this dispatch's lines
@group(0) @binding(3) var<storage, read> steps: array<Step>;       // steps + 1 per line
@group(0) @binding(4) var<storage, read_write> out: array<f32>;    // 5 planes of width * height
@group(0) @binding(5) var<storage, read> nodes: array<Node>;       // lens table (one dummy node otherwise)
@group(0) @binding(6) var<storage, read> ray_jac: array<vec4<f32>>; // table mode: per pixel the Jacobian's rows at its ray (one dummy otherwise)

const WG: u32 = 64u;

// Lens distortion: src/gpu/lens.wgsl (`Lens`, `distort`, `jacobian`), joined
// in front of this file at build (src/series/maps_gpu.rs).

// Cubic Hermite basis at s: h00, h10, h01, h11.
fn hermite(s: f32) -> vec4<f32> {
    let s2 = s * s;
    let s3 = s2 * s;
    return vec4<f32>(2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, 3.0 * s2 - 2.0 * s3, s3 - s2);
}

// The table cell of q: its first node's column and row in xy (clamped to
// the grid's cells) and q's place in it in zw (in spacings; outside [0, 1]
// beyond the grid).
fn table_cell(q: vec2<f32>) -> vec4<f32> {
    let u = (q.x - params.table.x) * params.table.z;
    let v = (q.y - params.table.y) * params.table.z;
    let i = clamp(floor(u), 0.0, f32(params.table_n.x - 2u));
    let j = clamp(floor(v), 0.0, f32(params.table_n.y - 2u));
    return vec4<f32>(i, j, u - i, v - j);
}

// The table cell of the ray r + e from r's cell c: the offset is added to
// the place within the cell (small numbers, so a track's points keep their
// digits relative to each other), then the cell moved by whole spacings.
fn table_move(c: vec4<f32>, e: vec2<f32>) -> vec4<f32> {
    let s = c.z + e.x * params.table.z;
    let t = c.w + e.y * params.table.z;
    let i = clamp(c.x + floor(s), 0.0, f32(params.table_n.x - 2u));
    let j = clamp(c.y + floor(t), 0.0, f32(params.table_n.y - 2u));
    return vec4<f32>(i, j, s - (i - c.x), t - (j - c.y));
}

// The index of cell c's first node.
fn table_node(c: vec4<f32>) -> u32 {
    return u32(c.y) * params.table_n.x + u32(c.x);
}

// The interpolant's sum over cell c's four nodes with weights ws (in x)
// and wt (in y), less the first node's value (the value weights sum to 1,
// the derivative weights to 0: the differences keep the digits).
fn table_sum(c: vec4<f32>, ws: vec4<f32>, wt: vec4<f32>) -> vec2<f32> {
    let k = table_node(c);
    let a = nodes[k];
    let b = nodes[k + 1u];
    let e = nodes[k + params.table_n.x];
    let g = nodes[k + params.table_n.x + 1u];
    return ws.y * wt.x * a.dx + ws.x * wt.y * a.dy + ws.y * wt.y * a.dxy
        + ws.z * wt.x * (b.d - a.d) + ws.w * wt.x * b.dx + ws.z * wt.y * b.dy + ws.w * wt.y * b.dxy
        + ws.x * wt.z * (e.d - a.d) + ws.y * wt.z * e.dx + ws.x * wt.w * e.dy + ws.y * wt.w * e.dxy
        + ws.z * wt.z * (g.d - a.d) + ws.w * wt.z * g.dx + ws.z * wt.w * g.dy + ws.w * wt.w * g.dxy;
}

// Table mode: the distorted point of the ray r + e less that of r's cell's
// first node (positions enter only as differences), from r's cell c.
fn table_distort(c: vec4<f32>, e: vec2<f32>) -> vec2<f32> {
    let m = table_move(c, e);
    return (nodes[table_node(m)].d - nodes[table_node(c)].d) + table_sum(m, hermite(m.z), hermite(m.w));
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

// Pixel position (less a point fixed per pixel) of the ray r + e: without
// distortion that of e alone, in table mode from r's cell c (positions
// enter only as differences).
fn position(r: vec2<f32>, c: vec4<f32>, e: vec2<f32>) -> vec2<f32> {
    var q = e;
    if (params.lens.model == 3u) {
        q = table_distort(c, e);
    } else if (params.lens.model != 0u) {
        q = distort(params.lens, r + e);
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
    var c = vec4<f32>(0.0);
    if (params.lens.model == 3u) {
        c = table_cell(r.xy);
    }
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
        let p = position(r.xy, c, t.xy);
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
    if (params.lens.model != 0u) {
        var jm: array<vec2<f32>, 2>;
        if (params.lens.model == 3u) {
            let g = ray_jac[pix];
            jm = array<vec2<f32>, 2>(g.xy, g.zw);
        } else {
            jm = jacobian(params.lens, r.xy);
        }
        fl = vec2<f32>(dot(jm[0], fl), dot(jm[1], fl));
    }
    let fv = px_velocity(fl);
    out[pix] = prev.x - first.x;
    out[n + pix] = prev.y - first.y;
    out[2u * n + pix] = path;
    out[3u * n + pix] = fv.x;
    out[4u * n + pix] = fv.y;
}
