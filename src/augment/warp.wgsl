// The warp integrator (src/augment/gpu.rs runs it; its CPU twin, function by
// function, is src/augment/warp_kernel.rs). Per output pixel (i, j), centre
// (i + 0.5, j + 0.5): the mean over the n instants of its line's exposure of
// the image's bilinear interpolant (linear light, texel x's centre at x + 0.5)
// at H_k(line) * centre; beyond the image the border mode. One invocation per
// pixel, the instants summed in registers (no barriers).

struct Params {
    // width, height (px), instants per line n, line mode (0 global, 1 per row, 2 per column)
    dims: vec4<u32>,
    // border (0 reflect, 1 replicate, 2 constant), first row, rows, 0
    range: vec4<u32>,
    // the constant border's linear value per channel
    fill: vec4<f32>,
};

// Rows of one frame-px-to-image-px map (w unused).
struct WarpMap {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
};

// Largest |coordinate| (px) before the texel index is taken (warp_kernel::FAR_PX).
const FAR_PX: f32 = 1.0e7;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> maps: array<WarpMap>;
@group(0) @binding(2) var<storage, read> img: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out: array<vec4<f32>>;

// Index i of a line of n texels under the border (-1: the constant border).
fn wrap(i: i32, n: i32, border: u32) -> i32 {
    if (i >= 0 && i < n) {
        return i;
    }
    if (border == 1u) {
        return clamp(i, 0, n - 1);
    }
    if (border == 0u) {
        if (n == 1) {
            return 0;
        }
        let p = 2 * (n - 1);
        var m = i % p;
        if (m < 0) {
            m = m + p;
        }
        if (m < n) {
            return m;
        }
        return p - m;
    }
    return -1;
}

fn texel(x: i32, y: i32) -> vec4<f32> {
    let w = i32(params.dims.x);
    let h = i32(params.dims.y);
    let xx = wrap(x, w, params.range.x);
    let yy = wrap(y, h, params.range.x);
    if (xx < 0 || yy < 0) {
        return params.fill;
    }
    return img[yy * w + xx];
}

fn lerp4(a: vec4<f32>, b: vec4<f32>, t: f32) -> vec4<f32> {
    return a + t * (b - a);
}

// The bilinear interpolant at texel coordinates (u, v) (texel x's centre at x).
fn bilinear(u_in: f32, v_in: f32) -> vec4<f32> {
    let u = clamp(u_in, -FAR_PX, FAR_PX);
    let v = clamp(v_in, -FAR_PX, FAR_PX);
    let x0 = floor(u);
    let y0 = floor(v);
    let fx = u - x0;
    let fy = v - y0;
    let x = i32(x0);
    let y = i32(y0);
    let w = i32(params.dims.x);
    let h = i32(params.dims.y);
    var t00: vec4<f32>;
    var t10: vec4<f32>;
    var t01: vec4<f32>;
    var t11: vec4<f32>;
    if (x >= 0 && y >= 0 && x + 1 < w && y + 1 < h) {
        // Inside: the four texels directly (what texel() gives there).
        let a = y * w + x;
        t00 = img[a];
        t10 = img[a + 1];
        t01 = img[a + w];
        t11 = img[a + w + 1];
    } else {
        t00 = texel(x, y);
        t10 = texel(x + 1, y);
        t01 = texel(x, y + 1);
        t11 = texel(x + 1, y + 1);
    }
    let top = lerp4(t00, t10, fx);
    let bot = lerp4(t01, t11, fx);
    return lerp4(top, bot, fy);
}

fn pixel(i: u32, j: u32) -> vec4<f32> {
    let n = params.dims.z;
    var line = 0u;
    if (params.dims.w == 1u) {
        line = j;
    } else if (params.dims.w == 2u) {
        line = i;
    }
    let x = f32(i) + 0.5;
    let y = f32(j) + 0.5;
    var acc = vec4<f32>(0.0);
    for (var k = 0u; k < n; k = k + 1u) {
        let g = maps[line * n + k];
        let z = g.r2.x * x + g.r2.y * y + g.r2.z;
        if (z <= 0.0) {
            acc = acc + params.fill;
        } else {
            let r = 1.0 / z;
            let u = (g.r0.x * x + g.r0.y * y + g.r0.z) * r - 0.5;
            let v = (g.r1.x * x + g.r1.y * y + g.r1.z) * r - 0.5;
            acc = acc + bilinear(u, v);
        }
    }
    return acc * (1.0 / f32(n));
}

// 8 x 8 pixels per workgroup (warp_kernel::WG).
@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let j = params.range.y + gid.y;
    if (i >= params.dims.x || gid.y >= params.range.z || j >= params.dims.y) {
        return;
    }
    out[j * params.dims.x + i] = pixel(i, j);
}
