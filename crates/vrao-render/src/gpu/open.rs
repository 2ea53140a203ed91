//! Opening the renderer's device: the backend and adapter choice, the features and
//! limits vrao asks for, the multiview probe and the shader directory. The engine's
//! [`Gpu`] wraps the device; a host that embeds the engine opens its own instead.

use super::multiview_probe::multiview_reaches_every_layer;
use vrao_ao::plug::Gpu;
use vrao_ao::{Error, Result};

/// The environment variable that makes vrao's shaders load from disk
/// (`VRAO_SHADER_DIR=.`, the workspace root, runs an edited shader without rebuilding).
pub const SHADER_DIR_VAR: &str = "VRAO_SHADER_DIR";

/// Which wgpu backend to use. `Auto` prefers a real GPU and falls back to lavapipe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BackendChoice {
    /// Whichever backend has a real GPU, falling back to lavapipe (software Vulkan).
    #[default]
    Auto,
    /// Vulkan only.
    Vulkan,
    /// OpenGL (ES) only, for machines without Vulkan.
    Gl,
}

vrao_ao::impl_choice!(BackendChoice);

impl BackendChoice {
    /// Every choice, the default first.
    pub const ALL: [BackendChoice; 3] = [BackendChoice::Auto, BackendChoice::Vulkan, BackendChoice::Gl];
    /// The choice's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            BackendChoice::Auto => "auto",
            BackendChoice::Vulkan => "vulkan",
            BackendChoice::Gl => "gl",
        }
    }
}

/// Opens the best adapter for `choice`: a discrete or integrated GPU when one exists,
/// otherwise a CPU (lavapipe) adapter. No adapter at all is `Error::Device`.
pub fn open(choice: BackendChoice) -> Result<Gpu> {
    // Auto tries the native APIs first and OpenGL only when they found nothing, so a
    // machine with Vulkan never initialises (and hears from) the GL/EGL stack.
    let attempts: &[wgpu::Backends] = match choice {
        BackendChoice::Auto => &[wgpu::Backends::PRIMARY, wgpu::Backends::GL],
        BackendChoice::Vulkan => &[wgpu::Backends::VULKAN],
        BackendChoice::Gl => &[wgpu::Backends::GL],
    };
    let mut last_error = None;
    for &backends in attempts {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends;
        let instance = wgpu::Instance::new(desc);
        match pick_adapter(&instance, backends) {
            Ok(adapter) => {
                let desc = device_descriptor(&adapter);
                let (device, queue) = pollster::block_on(adapter.request_device(&desc))
                    .map_err(|e| Error::Device(format!("{} refused a device: {e}", adapter.get_info().name)))?;
                return from_device(instance, adapter, device, queue);
            }
            Err(e) => last_error = Some(e),
        }
    }
    Err(last_error.unwrap_or_else(|| Error::Device("no backend was tried".into())))
}

/// The engine's [`Gpu`] over a device opened with [`device_descriptor`] (by [`open`], or
/// wrapped from a device an OpenXR runtime created), with the multiview probe run and
/// the shader directory of [`SHADER_DIR_VAR`] applied.
pub fn from_device(
    instance: wgpu::Instance,
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
) -> Result<Gpu> {
    let mut gpu = Gpu::from_device(instance, adapter, device, queue)?;
    gpu.set_shader_dir(std::env::var_os(SHADER_DIR_VAR).map(std::path::PathBuf::from));
    gpu.caps.multiview_reliable = gpu.caps.multiview && multiview_reaches_every_layer(&gpu);
    Ok(gpu)
}

/// The features and limits vrao asks of `adapter`: multiview and timestamp queries
/// when offered, and limits large enough for full-size layered targets. Devices that
/// others create for us (the OpenXR runtime's) are opened with the same descriptor.
pub fn device_descriptor(adapter: &wgpu::Adapter) -> wgpu::DeviceDescriptor<'static> {
    let available = adapter.features();
    let adapter_limits = adapter.limits();
    let multiview = available.contains(wgpu::Features::MULTIVIEW) && adapter_limits.max_multiview_view_count >= 2;
    let timestamps =
        available.contains(wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
    let mut features = wgpu::Features::empty();
    if multiview {
        features |= wgpu::Features::MULTIVIEW;
    }
    if timestamps {
        features |= wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
    }
    // R16Float storage lets the AO chain of the techniques without light keep 2 bytes a
    // texel instead of 8 (the engine probes for it: Capabilities::scalar_chain).
    let scalar_storage = adapter
        .get_texture_format_features(wgpu::TextureFormat::R16Float)
        .flags
        .contains(wgpu::TextureFormatFeatureFlags::STORAGE_WRITE_ONLY);
    if scalar_storage && available.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
        features |= wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
    }
    // Ask for what the adapter has so full-size layered targets fit; keep the
    // downlevel defaults otherwise.
    let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter_limits.clone());
    limits.max_texture_array_layers = adapter_limits.max_texture_array_layers.min(256);
    limits.max_storage_textures_per_shader_stage = adapter_limits.max_storage_textures_per_shader_stage.min(8);
    limits.max_storage_buffers_per_shader_stage = adapter_limits.max_storage_buffers_per_shader_stage.min(8);
    limits.max_compute_workgroup_storage_size = adapter_limits.max_compute_workgroup_storage_size;
    // A moving, normal-textured scene's G-buffer writes five targets (36 bytes a pixel).
    limits.max_color_attachments = adapter_limits.max_color_attachments.min(8);
    limits.max_color_attachment_bytes_per_sample = adapter_limits.max_color_attachment_bytes_per_sample.min(64);
    limits.max_buffer_size = adapter_limits.max_buffer_size;
    limits.max_storage_buffer_binding_size = adapter_limits.max_storage_buffer_binding_size;
    if multiview {
        limits.max_multiview_view_count = 2;
    }
    wgpu::DeviceDescriptor {
        label: Some("vrao"),
        required_features: features,
        required_limits: limits,
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }
}

/// Prefers a hardware adapter; a CPU adapter (lavapipe) is the fall-back. Adapters that
/// lack something the renderer needs ([`Gpu::missing_capabilities`]) are passed over;
/// when only such adapters exist, the best one is refused with what it lacks.
fn pick_adapter(instance: &wgpu::Instance, backends: wgpu::Backends) -> Result<wgpu::Adapter> {
    let adapters = pollster::block_on(instance.enumerate_adapters(backends));
    let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let mut ranked: Vec<(wgpu::Adapter, Vec<String>)> = adapters
        .into_iter()
        .map(|a| {
            let missing = Gpu::missing_capabilities(&a);
            (a, missing)
        })
        .collect();
    ranked.sort_by_key(|(a, missing)| (!missing.is_empty(), rank(a)));
    match ranked.into_iter().next() {
        Some((adapter, missing)) if missing.is_empty() => Ok(adapter),
        Some((adapter, missing)) => {
            Gpu::check_adapter(&adapter)?;
            unreachable!("an adapter that lacks something is refused: {missing:?}")
        }
        None => Err(Error::Device(format!(
            "no adapter on backends {backends:?}; install a Vulkan driver \
             (for a CPU fall-back: apt install mesa-vulkan-drivers)"
        ))),
    }
}
