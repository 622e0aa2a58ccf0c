//! One wgpu device per process. The instance's backends come from the
//! environment (`WGPU_BACKEND`, e.g. `vulkan`); CPU adapters (Mesa lavapipe)
//! are accepted. `MMBM_ADAPTER=substring` restricts the choice by name.

use crate::error::{Error, Result};
use std::sync::OnceLock;

/// The process-wide GPU device and queue.
pub struct GpuContext {
    /// The adapter in use.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// `name (backend, type)` of the adapter in use.
    pub description: String,
    /// True when the device supports f64 in shaders.
    pub has_f64: bool,
}

/// Describes an adapter as `name (backend, device type)`.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

fn instance() -> wgpu::Instance {
    // No "XDG_RUNTIME_DIR is invalid" noise from the loader on stderr.
    super::runtime_dir::ensure();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    wgpu::Instance::new(desc)
}

/// Every adapter the instance can see, described.
pub fn list_adapters() -> Vec<String> {
    let inst = instance();
    pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| describe(&a.get_info()))
        .collect()
}

fn create() -> Result<GpuContext> {
    let inst = instance();
    let adapters = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
    let filter = std::env::var("MMBM_ADAPTER").ok().filter(|s| !s.is_empty());
    let found: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
    // Prefer discrete > integrated > virtual > CPU > other, then Vulkan/Metal/DX12 over GL.
    let rank = |a: &wgpu::Adapter| {
        let i = a.get_info();
        let t = match i.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        let b = if i.backend == wgpu::Backend::Gl { 1 } else { 0 };
        (b, t)
    };
    let adapter = adapters
        .into_iter()
        .filter(|a| {
            filter
                .as_ref()
                .is_none_or(|f| a.get_info().name.to_lowercase().contains(&f.to_lowercase()))
        })
        .min_by_key(rank)
        .ok_or_else(|| {
            Error::Gpu(format!(
                "no GPU adapter found{} (WGPU_BACKEND={}); adapters seen: [{}]. \
                 On Debian/Ubuntu install Mesa's software Vulkan driver: \
                 apt-get install mesa-vulkan-drivers libvulkan1",
                filter
                    .as_ref()
                    .map_or(String::new(), |f| format!(" matching MMBM_ADAPTER='{f}'")),
                std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "<unset>".into()),
                found.join("; ")
            ))
        })?;
    let info = adapter.get_info();
    let has_f64 = adapter.features().contains(wgpu::Features::SHADER_F64);
    let mut limits = wgpu::Limits::default().using_resolution(adapter.limits());
    limits.max_storage_buffer_binding_size = adapter.limits().max_storage_buffer_binding_size;
    limits.max_buffer_size = adapter.limits().max_buffer_size;
    limits.max_compute_workgroup_storage_size = adapter.limits().max_compute_workgroup_storage_size;
    limits.max_storage_buffers_per_shader_stage =
        adapter.limits().max_storage_buffers_per_shader_stage;
    let features = if has_f64 {
        wgpu::Features::SHADER_F64
    } else {
        wgpu::Features::empty()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("mmbm"),
        required_features: features,
        required_limits: limits,
        ..Default::default()
    }))
    .map_err(|e| Error::Gpu(format!("request_device on {}: {e}", describe(&info))))?;
    Ok(GpuContext {
        description: describe(&info),
        adapter,
        device,
        queue,
        has_f64,
    })
}

static CONTEXT: OnceLock<std::result::Result<GpuContext, String>> = OnceLock::new();

/// The shared device, created on first use. Errors (no adapter) are cached
/// and returned to every caller.
pub fn gpu() -> Result<&'static GpuContext> {
    CONTEXT
        .get_or_init(|| create().map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| Error::Gpu(e.trim_start_matches("GPU: ").to_string()))
}
