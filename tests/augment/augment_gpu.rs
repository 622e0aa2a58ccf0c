//! The GPU path of the warp integrator (issue 37): `src/augment/warp.wgsl`
//! validates with naga (no GPU needed); its CPU twin (`warp_kernel`, the
//! same f32 formula) equals the CPU path within f32 rounding and meets the
//! image contract (mean 0.5/255, p99 3/255) against the exact integrator on
//! `tests/augment_api.rs`'s cases and a rolling shutter; on a GPU the kernel
//! equals the twin pixel by pixel within [`GPU_TOL`]; the backend choice.
//! GPU tests skip (reported on stderr) without an adapter, and fail under
//! `MMBM_REQUIRE_GPU=1`.

use crate::augment_fixture;
use crate::common;

use augment_fixture::{api_cases, err, f32_image, out_f32, rolling, texture, within_contract};
use glam::{DMat3, DVec3};
use mmbm::augment::warp::{Border, Maps, Src};
use mmbm::augment::{augment_image, augment_twin, gpu, warp, warp_kernel, Augment, Integrator};
use mmbm::gpu::Backend;

/// Largest |GPU - twin| of a linear value (0..1) per pixel and channel:
/// 1e-4, i.e. 0.026/255 (f32 rounding, a fused multiply-add or an
/// approximate division on the device move a sample point by about 1e-5 px).
const GPU_TOL: f32 = 1e-4;

/// Largest |twin - CPU path| (the same formula, the CPU path's map
/// hoisted out of the row loop): f32 rounding only.
const TWIN_TOL: f32 = 1e-5;

/// Synthetic maps: `n` instants (of each of `lines` lines) of a rotation
/// about the image centre by up to 0.1 rad, a shift of up to (25, -12) px
/// (crossing the borders) and a little perspective.
fn synthetic_maps(w: usize, h: usize, n: usize, mode: u32) -> Maps {
    let lines = match mode {
        1 => h,
        2 => w,
        _ => 1,
    };
    let (cx, cy) = (0.5 * w as f64, 0.5 * h as f64);
    let mut m = Vec::with_capacity(lines * n);
    for l in 0..lines {
        for k in 0..n {
            let t = (k as f64 + 0.5) / n as f64 + 0.3 * l as f64 / lines as f64;
            let (s, c) = (0.1 * t).sin_cos();
            let to = DMat3::from_cols(
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(cx + 25.0 * t, cy - 12.0 * t, 1.0),
            );
            let rot = DMat3::from_cols(
                DVec3::new(c, s, 0.0),
                DVec3::new(-s, c, 0.0),
                DVec3::new(0.0, 0.0, 1.0),
            );
            let persp = DMat3::from_cols(
                DVec3::new(1.0, 0.0, 2e-4 * t),
                DVec3::new(0.0, 1.0, -1e-4 * t),
                DVec3::new(-cx, -cy, 1.0),
            );
            m.push(warp::to_f32(&(to * rot * persp)));
        }
    }
    Maps { m, n, mode }
}

/// Every combination the kernel branches on: channels, borders, line modes.
fn synthetic_cases() -> Vec<(usize, Border, u32)> {
    let mut out = Vec::new();
    for c in [1, 3, 4] {
        for b in [Border::Reflect, Border::Replicate, Border::Constant] {
            for mode in [0, 1, 2] {
                out.push((c, b, mode));
            }
        }
    }
    out
}

fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

#[test]
fn shader_parses_and_validates_without_a_gpu() {
    let m = naga::front::wgsl::parse_str(gpu::SHADER)
        .unwrap_or_else(|e| panic!("warp.wgsl: {}", e.emit_to_string(gpu::SHADER)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&m)
    .unwrap_or_else(|e| panic!("warp.wgsl: {}", e.emit_to_string(gpu::SHADER)));
    // The host's workgroup size is the shader's.
    let ep = m
        .entry_points
        .iter()
        .find(|e| e.name == "main")
        .expect("main");
    assert_eq!(ep.workgroup_size, [warp_kernel::WG, warp_kernel::WG, 1]);
}

#[test]
fn twin_equals_the_cpu_path_on_every_branch() {
    let (w, h, n) = (37usize, 23usize, 6usize);
    for (c, border, mode) in synthetic_cases() {
        let v = texture(w, h, c);
        let fill = [0.2f32, 0.7, 0.4, 1.0];
        let src = Src {
            w,
            h,
            c,
            v: &v,
            border,
            fill: &fill[..c],
        };
        let maps = synthetic_maps(w, h, n, mode);
        let d = max_diff(
            &warp_kernel::twin(&src, &maps),
            &warp::integrate(&src, &maps),
        );
        assert!(d < TWIN_TOL, "{c} channels, {border:?}, mode {mode}: {d}");
    }
}

#[test]
fn twin_meets_the_contract_against_the_exact_integrator() {
    let (w, h) = (128u32, 96u32);
    let img = texture(w as usize, h as usize, 3);
    let image = f32_image(w, h, 3, &img);
    let mut cases = api_cases();
    cases.push(rolling(w, h));
    for mut a in cases {
        a.backend = Backend::Cpu { threads: None };
        let twin = augment_twin(&image, &a).unwrap();
        let cpu = augment_image(&image, &a).unwrap();
        assert_eq!(twin.samples, cpu.samples);
        let (twin, cpu) = (out_f32(twin.pixels), out_f32(cpu.pixels));
        let d = max_diff(&twin, &cpu);
        assert!(d < TWIN_TOL, "{}: twin vs CPU path {d}", a.seed);
        a.integrator = Integrator::Exact;
        let exact = out_f32(augment_image(&image, &a).unwrap().pixels);
        let e = err(&twin, &exact);
        eprintln!("twin vs exact: mean {:.3}, p99 {:.3} /255", e.0, e.1);
        assert!(within_contract(e), "twin vs exact: {e:?}");
    }
}

#[test]
fn gpu_equals_its_twin_per_pixel() {
    let Some(ctx) = common::gpu() else {
        return;
    };
    let (w, h, n) = (37usize, 23usize, 6usize);
    for (c, border, mode) in synthetic_cases() {
        let v = texture(w, h, c);
        let fill = [0.2f32, 0.7, 0.4, 1.0];
        let src = Src {
            w,
            h,
            c,
            v: &v,
            border,
            fill: &fill[..c],
        };
        let maps = synthetic_maps(w, h, n, mode);
        let got = gpu::integrate(ctx, &src, &maps).unwrap();
        let d = max_diff(&got, &warp_kernel::twin(&src, &maps));
        assert!(d <= GPU_TOL, "{c} channels, {border:?}, mode {mode}: {d}");
    }
}

#[test]
fn gpu_path_equals_the_twin_and_meets_the_contract() {
    if common::gpu().is_none() {
        return;
    }
    let (w, h) = (128u32, 96u32);
    let img = texture(w as usize, h as usize, 3);
    let image = f32_image(w, h, 3, &img);
    let mut cases = api_cases();
    cases.push(rolling(w, h));
    for mut a in cases {
        a.backend = Backend::Gpu;
        let got = augment_image(&image, &a).unwrap();
        let twin = augment_twin(&image, &a).unwrap();
        assert_eq!(got.samples, twin.samples);
        let got = out_f32(got.pixels);
        let d = max_diff(&got, &out_f32(twin.pixels));
        assert!(d <= GPU_TOL, "{}: GPU vs twin {d}", a.seed);
        a.integrator = Integrator::Exact;
        a.backend = Backend::Cpu { threads: None };
        let exact = out_f32(augment_image(&image, &a).unwrap().pixels);
        let e = err(&got, &exact);
        eprintln!("GPU vs exact: mean {:.3}, p99 {:.3} /255", e.0, e.1);
        assert!(within_contract(e), "GPU vs exact: {e:?}");
    }
}

#[test]
fn backend_is_bulk_by_default_and_a_bad_name_is_refused() {
    let a = Augment::new(augment_fixture::twist(DVec3::new(0.0, 0.5, 0.0)), 0.03);
    assert_eq!(a.backend, Backend::Bulk);
    let e = "gpus".parse::<Backend>().unwrap_err().to_string();
    assert!(e.contains("backend") && e.contains("gpus"), "{e}");
    // Without a hardware GPU `bulk` is the CPU path: outputs unchanged.
    let hardware =
        mmbm::gpu::gpu().is_ok_and(|c| c.adapter.get_info().device_type != wgpu::DeviceType::Cpu);
    if !hardware {
        let (w, h) = (48u32, 32u32);
        let img = texture(w as usize, h as usize, 3);
        let image = f32_image(w, h, 3, &img);
        let bulk = augment_image(&image, &a).unwrap();
        let mut cpu = a.clone();
        cpu.backend = Backend::Cpu { threads: None };
        assert_eq!(bulk.pixels, augment_image(&image, &cpu).unwrap().pixels);
    }
}

/// Time per 640 x 480 RGB image with a 20 px yaw (`fast`), on the CPU and
/// (with an adapter) on the GPU: `cargo test --release --test augment_gpu
/// -- --ignored --nocapture`. The numbers of `docs/performance.md`.
#[test]
#[ignore]
fn time_a_640x480_image_with_20_px_of_blur() {
    let (w, h) = (640u32, 480u32);
    let img = texture(w as usize, h as usize, 3);
    let image = f32_image(w, h, 3, &img);
    let a = Augment::new(
        augment_fixture::twist(DVec3::new(0.0, augment_fixture::yaw_for(20.0, 0.03), 0.0)),
        0.03,
    );
    let mut backends = vec![("cpu", Backend::Cpu { threads: None })];
    if let Some(ctx) = common::gpu() {
        eprintln!("adapter: {}", ctx.description);
        backends.push(("gpu", Backend::Gpu));
    }
    for (name, b) in backends {
        let mut a = a.clone();
        a.backend = b;
        let first = std::time::Instant::now();
        let out = augment_image(&image, &a).unwrap();
        let first = first.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let reps = 5;
        for _ in 0..reps {
            augment_image(&image, &a).unwrap();
        }
        eprintln!(
            "{name}: {} instants, first call {first:.3} s, then {:.3} s per image",
            out.samples,
            t.elapsed().as_secs_f64() / reps as f64
        );
    }
}
