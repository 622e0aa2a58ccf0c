// Per-pixel image-plane flow (docs/spec.md section 2, thesis eq. 3.20) and its mean
// over the sensor (MMBM, thesis eq. 3.11). The CPU twin of every function and
// entry point is in src/field/cpu.rs; the host structs in src/field/kernel.rs
// and src/field/table.rs.
//
// Units: sensor coordinates u, v in mm; focal length f in mm; angular
// velocity rad/s; linear velocity m/s; inverse depth 1/m. The flow is mm/s on
// the sensor; the field written out is px/s (+u right, +v down, skew included,
// like Camera::mm_to_px_velocity). Sums are of the speed in mm/s.

// Camera and sample grid. Must match `FlowParams` (96 bytes).
struct Params {
    f_mm: f32,          // focal length, mm
    pitch_x: f32,       // pixel pitch, mm
    pitch_y: f32,
    cx: f32,            // principal point, px
    cy: f32,
    skew_over_f: f32,   // skew (px) / f (mm)
    step_x: f32,        // grid cell size, px (1 at sensor resolution)
    step_y: f32,
    grid_w: u32,        // grid size (samples per row / rows)
    grid_h: u32,
    n_twists: u32,      // twists in this dispatch
    tiles: u32,         // tiles per twist (flow_tiles)
    tiles_x: u32,       // workgroups along x per dispatch row
    write_field: u32,   // 1: write the field (one twist only)
    pad0: u32,
    pad1: u32,
    lens: Lens,         // lens distortion (src/gpu/lens.wgsl); model 3: the lens table below
}

// One twist. Must match `TwistGpu` (48 bytes).
struct Twist {
    omega: vec4<f32>,     // xyz: angular velocity, rad/s
    velocity: vec4<f32>,  // xyz: linear velocity, m/s
    inv_depth: vec4<f32>, // 1/z = x + y*u + z*v (1/m; zero for rotation only)
}

// Lens table mode (lens model 3): per grid sample, its undistorted normalised
// point q and the rows of the distortion chain's Jacobian at q, computed on
// the host (src/field/table.rs; all zero for a masked sample, whose flow is
// then 0). Must match `LensSample` (24 bytes). One dummy entry otherwise.
struct LensSample {
    q: vec2<f32>,
    j0: vec2<f32>,
    j1: vec2<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> twists: array<Twist>;
@group(0) @binding(2) var<storage, read_write> field: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> partials: array<f32>;
@group(0) @binding(4) var<storage, read> lens_table: array<LensSample>;

// Workgroup size and samples per thread of flow_tiles: a tile is WG * CHUNK
// consecutive samples (row-major); sample k of thread t is tile*TILE + k*WG + t.
const WG: u32 = 64u;
const CHUNK: u32 = 32u;
const TILE: u32 = 2048u; // WG * CHUNK

// Sensor point (mm) at the centre of grid cell (i, j); like Camera::pixel_to_mm.
fn sensor_point(i: u32, j: u32) -> vec2<f32> {
    let x = (f32(i) + 0.5) * params.step_x;
    let y = (f32(j) + 0.5) * params.step_y;
    let v = (y - params.cy) * params.pitch_y;
    let u = (x - params.cx - params.skew_over_f * v) * params.pitch_x;
    return vec2<f32>(u, v);
}

// The flow (mm/s) at sensor point p (mm).
fn flow_mm(p: vec2<f32>, tw: Twist) -> vec2<f32> {
    let f = params.f_mm;
    let u = p.x;
    let v = p.y;
    let w = tw.omega;
    let t = tw.velocity;
    let iz = tw.inv_depth.x + tw.inv_depth.y * u + tw.inv_depth.z * v;
    let du = w.z * v - w.y * f - (w.y / f) * u * u + (w.x / f) * u * v - f * iz * t.x + u * iz * t.z;
    let dv = -w.z * u + w.x * f - (w.y / f) * u * v + (w.x / f) * v * v - f * iz * t.y + v * iz * t.z;
    return vec2<f32>(du, dv);
}

// Lens distortion: src/gpu/lens.wgsl (`Lens`, `distort`, `jacobian`,
// `undistort`), joined in front of this file at build (src/field/gpu.rs).

// The flow (mm/s on the distorted sensor) at the centre of grid cell (i, j):
// the pinhole flow of its undistorted point through the distortion's Jacobian.
// Table mode: the pinhole flow at the sample's q through its Jacobian.
fn sample_flow(i: u32, j: u32, tw: Twist) -> vec2<f32> {
    if (params.lens.model == 3u) {
        let s = lens_table[j * params.grid_w + i];
        let fl = flow_mm(s.q * params.f_mm, tw);
        return vec2<f32>(dot(s.j0, fl), dot(s.j1, fl));
    }
    let pd = sensor_point(i, j);
    if (params.lens.model == 0u) {
        return flow_mm(pd, tw);
    }
    let f = params.f_mm;
    let q = undistort(params.lens, pd / f);
    let fl = flow_mm(q * f, tw);
    let jm = jacobian(params.lens, q);
    return vec2<f32>(dot(jm[0], fl), dot(jm[1], fl));
}

// Sensor velocity (mm/s) to pixel velocity (px/s); like Camera::mm_to_px_velocity.
fn px_velocity(d: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(d.x / params.pitch_x + params.skew_over_f * d.y, d.y / params.pitch_y);
}

var<workgroup> wg_sums: array<f32, 64>;

// Field and partial sums: workgroup (x + z*tiles_x) covers one tile of twist
// y. Each thread sums CHUNK speeds in a register, then thread 0 adds the 64
// thread sums (one barrier). partials[twist * tiles + tile] = sum of speeds (mm/s).
@compute @workgroup_size(64)
fn flow_tiles(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tile = wg.z * params.tiles_x + wg.x;
    let twist_index = wg.y;
    let n = params.grid_w * params.grid_h;
    var acc = 0.0;
    if (tile < params.tiles) {
        let tw = twists[twist_index];
        let base = tile * TILE + lid;
        // Column and row of the thread's sample, stepped by WG without a division per sample.
        var i = base % params.grid_w;
        var j = base / params.grid_w;
        for (var k = 0u; k < CHUNK; k++) {
            let idx = base + k * WG;
            if (idx < n) {
                let d = sample_flow(i, j, tw);
                acc += length(d);
                if (params.write_field != 0u) {
                    field[idx] = px_velocity(d);
                }
            }
            i += WG;
            while (i >= params.grid_w) {
                i -= params.grid_w;
                j += 1u;
            }
        }
    }
    wg_sums[lid] = acc;
    workgroupBarrier();
    if (lid == 0u && tile < params.tiles) {
        var s = 0.0;
        for (var k = 0u; k < WG; k++) {
            s += wg_sums[k];
        }
        partials[twist_index * params.tiles + tile] = s;
    }
}

// Batched means for small grids: one thread per twist, no barrier.
// partials[twist * grid_h + j] = sum of the speeds (mm/s) of row j.
@compute @workgroup_size(64)
fn rows_per_twist(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = gid.x;
    if (t >= params.n_twists) {
        return;
    }
    let tw = twists[t];
    for (var j = 0u; j < params.grid_h; j++) {
        var row = 0.0;
        for (var i = 0u; i < params.grid_w; i++) {
            row += length(sample_flow(i, j, tw));
        }
        partials[t * params.grid_h + j] = row;
    }
}
