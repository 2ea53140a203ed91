//! Whether an adapter can run the renderer, decided from what it reports before any
//! pipeline is built: an adapter that cannot is refused with one line naming what it
//! lacks, instead of a screen of validation errors from the first frame.

/// Workgroup edge of every full-screen compute kernel (`@workgroup_size(8, 8, 1)`).
pub(crate) const TILE: u32 = 8;

/// Formats the compute kernels write as `texture_storage_2d_array<FORMAT, write>`
/// (`Slot::Output`): colour, the AO targets and history, world positions, and the
/// packed direct light. Checked when each kernel is made (`Kernel::with_constants`), so
/// a pass that writes another format fails every test until it is listed here.
pub(crate) const STORAGE_WRITE_FORMATS: [wgpu::TextureFormat; 4] = [
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rg32Uint,
];

/// Whether `device` can write the scalar chain's `R16Float` as a storage texture: not a
/// WebGPU core format for storage, so only with `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`
/// on an adapter that supports it, which a 1×1 texture made under an error scope tells
/// (the device alone does not say what its adapter's formats support).
pub(crate) fn writes_scalar_chain(device: &wgpu::Device) -> bool {
    if !device.features().contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
        return false;
    }
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let _probe = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("scalar chain probe"),
        size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: crate::resource::ChainLayout::Scalar.format(),
        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    pollster::block_on(scope.pop()).is_none()
}

/// What an adapter reports that the renderer depends on, as plain data so the decision
/// can be tested without one.
#[derive(Clone, Debug)]
pub(crate) struct AdapterSupport {
    /// The adapter's backend.
    pub backend: wgpu::Backend,
    /// The adapter's downlevel flags (compute, storage support).
    pub downlevel: wgpu::DownlevelFlags,
    /// The format features of each of [`STORAGE_WRITE_FORMATS`].
    pub formats: Vec<(wgpu::TextureFormat, wgpu::TextureFormatFeatureFlags)>,
}

impl AdapterSupport {
    /// Reads the support figures from a real adapter.
    pub(crate) fn of(adapter: &wgpu::Adapter) -> AdapterSupport {
        AdapterSupport {
            backend: adapter.get_info().backend,
            downlevel: adapter.get_downlevel_capabilities().flags,
            formats: STORAGE_WRITE_FORMATS.iter().map(|&f| (f, adapter.get_texture_format_features(f).flags)).collect(),
        }
    }
}

/// What the renderer needs that `support` lacks, one phrase each; empty when it can run.
pub(crate) fn missing_capabilities(support: &AdapterSupport) -> Vec<String> {
    let mut missing = Vec::new();
    if !support.downlevel.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) {
        missing.push("compute shaders (DownlevelFlags::COMPUTE_SHADERS)".to_string());
    }
    for &format in &STORAGE_WRITE_FORMATS {
        let flags = support
            .formats
            .iter()
            .find(|(f, _)| *f == format)
            .map_or(wgpu::TextureFormatFeatureFlags::empty(), |&(_, flags)| flags);
        if !flags.contains(wgpu::TextureFormatFeatureFlags::STORAGE_WRITE_ONLY) {
            missing.push(format!(
                "write-only {format:?} storage textures (TextureFormatFeatureFlags::STORAGE_WRITE_ONLY)"
            ));
        }
    }
    // Every AO pass reads depth with `textureLoad`, which naga's GLSL writer cannot
    // translate; no adapter flag says so, so the backend itself is the capability.
    if support.backend == wgpu::Backend::Gl {
        missing.push("textureLoad on depth textures (not translatable to GLSL)".to_string());
    }
    missing
}

/// What the kernels need that a device alone can say (a host's device, whose adapter
/// vrao never sees): its backend, and the limits a compute pass over layered targets uses.
#[derive(Clone, Debug)]
pub(crate) struct DeviceSupport {
    /// The backend the device runs on.
    pub backend: wgpu::Backend,
    /// The device's limits.
    pub limits: wgpu::Limits,
}

impl DeviceSupport {
    /// What `device` reports.
    pub(crate) fn of(device: &wgpu::Device) -> DeviceSupport {
        DeviceSupport { backend: device.adapter_info().backend, limits: device.limits() }
    }
}

/// Storage textures the busiest AO kernel writes at once (temporal accumulation: the
/// accumulated AO and the two history targets).
const STORAGE_TEXTURES_PER_KERNEL: u32 = 3;

/// What a host's device lacks for the AO engine's kernels. The formats the kernels write
/// ([`STORAGE_WRITE_FORMATS`]) are write-only storage formats of every non-GL backend's
/// baseline (WebGPU's core set), so the backend and the limits decide.
pub(crate) fn missing_device_capabilities(support: &DeviceSupport) -> Vec<String> {
    let mut missing = Vec::new();
    let limits = &support.limits;
    let tile = TILE;
    if limits.max_compute_workgroups_per_dimension == 0 || limits.max_compute_invocations_per_workgroup < tile * tile {
        missing.push(format!("compute shaders with {tile}×{tile} workgroups"));
    }
    if limits.max_storage_textures_per_shader_stage < STORAGE_TEXTURES_PER_KERNEL {
        missing.push(format!(
            "{STORAGE_TEXTURES_PER_KERNEL} storage textures per shader stage (the device allows {})",
            limits.max_storage_textures_per_shader_stage
        ));
    }
    if limits.max_texture_array_layers < 2 {
        missing.push("2-layer array textures (one layer per eye)".to_string());
    }
    if support.backend == wgpu::Backend::Gl {
        missing.push("textureLoad on depth textures and storage formats beyond GL's (the GL backend)".to_string());
    }
    missing
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::TextureFormatFeatureFlags as F;

    fn support(backend: wgpu::Backend, rg32uint: F) -> AdapterSupport {
        let all = F::STORAGE_READ_ONLY | F::STORAGE_WRITE_ONLY | F::STORAGE_READ_WRITE;
        AdapterSupport {
            backend,
            downlevel: wgpu::DownlevelFlags::all(),
            formats: STORAGE_WRITE_FORMATS
                .iter()
                .map(|&f| (f, if f == wgpu::TextureFormat::Rg32Uint { rg32uint } else { all }))
                .collect(),
        }
    }

    #[test]
    fn a_host_device_is_checked_by_its_limits_and_backend() {
        let vulkan = DeviceSupport { backend: wgpu::Backend::Vulkan, limits: wgpu::Limits::default() };
        assert!(missing_device_capabilities(&vulkan).is_empty());
        let no_compute =
            DeviceSupport { backend: wgpu::Backend::Vulkan, limits: wgpu::Limits::downlevel_webgl2_defaults() };
        let missing = missing_device_capabilities(&no_compute);
        assert!(missing.iter().any(|m| m.contains("compute")), "{missing:?}");
        let gl = DeviceSupport { backend: wgpu::Backend::Gl, limits: wgpu::Limits::default() };
        assert_eq!(missing_device_capabilities(&gl).len(), 1);
    }

    #[test]
    fn a_full_vulkan_adapter_lacks_nothing() {
        assert!(missing_capabilities(&support(wgpu::Backend::Vulkan, F::STORAGE_WRITE_ONLY)).is_empty());
    }

    #[test]
    fn gl_as_mesa_reports_it_lacks_rg32uint_storage_and_depth_loads() {
        // What llvmpipe's GL 4.5 adapter reports: Rg32Uint is renderable but not storage.
        let gl = support(wgpu::Backend::Gl, F::MULTISAMPLE_X4 | F::MULTISAMPLE_RESOLVE);
        let missing = missing_capabilities(&gl);
        assert_eq!(missing.len(), 2, "{missing:?}");
        assert!(missing[0].contains("Rg32Uint") && missing[0].contains("STORAGE_WRITE_ONLY"), "{missing:?}");
        assert!(missing[1].contains("textureLoad on depth"), "{missing:?}");
    }

    #[test]
    fn no_compute_and_unreported_formats_are_named() {
        let mut s = support(wgpu::Backend::Vulkan, F::STORAGE_WRITE_ONLY);
        s.downlevel = wgpu::DownlevelFlags::empty();
        s.formats.clear();
        let missing = missing_capabilities(&s);
        assert!(missing[0].contains("COMPUTE_SHADERS"), "{missing:?}");
        assert_eq!(missing.len(), 1 + STORAGE_WRITE_FORMATS.len(), "{missing:?}");
    }
}
