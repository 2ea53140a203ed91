//! The wgpu plumbing written once: shader modules from `shaders/`, and compute kernels
//! whose bind-group layout, bind group and dispatch follow from a list of slots. A pass
//! names its slots and binds resources in the same order; binding `i` is slot `i`.

use super::Gpu;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Bumped whenever targets are made or dropped: every kernel then forgets its bind
/// groups, which would otherwise keep dropped textures alive.
static BIND_GROUP_EPOCH: AtomicU64 = AtomicU64::new(0);

/// Bind groups a kernel keeps before it starts over (a frame binds each kernel a few
/// times; more means the resources change every frame).
const MAX_CACHED_BIND_GROUPS: usize = 64;

/// Forgets every kernel's cached bind groups (call when targets are recreated).
pub fn invalidate_bind_groups() {
    BIND_GROUP_EPOCH.fetch_add(1, Ordering::Relaxed);
}

/// Workgroup edge of every full-screen compute kernel (`@workgroup_size(8, 8, 1)`).
pub const TILE: u32 = 8;

/// WGSL sources, compiled into the binary so it runs from any directory.
const SHADERS: &[(&str, &str)] = &[
    ("common.wgsl", include_str!("../../../shaders/common.wgsl")),
    ("occlusion.wgsl", include_str!("../../../shaders/occlusion.wgsl")),
    ("ssao.wgsl", include_str!("../../../shaders/ssao.wgsl")),
    ("hbao.wgsl", include_str!("../../../shaders/hbao.wgsl")),
    ("gtao.wgsl", include_str!("../../../shaders/gtao.wgsl")),
    ("ssdo.wgsl", include_str!("../../../shaders/ssdo.wgsl")),
    ("fetch.wgsl", include_str!("../../../shaders/fetch.wgsl")),
    ("bilateral.wgsl", include_str!("../../../shaders/bilateral.wgsl")),
    ("denoise.wgsl", include_str!("../../../shaders/denoise.wgsl")),
    ("denoise_stereo.wgsl", include_str!("../../../shaders/denoise_stereo.wgsl")),
    ("joint_upsample.wgsl", include_str!("../../../shaders/joint_upsample.wgsl")),
    ("upsample.wgsl", include_str!("../../../shaders/upsample.wgsl")),
    ("composite.wgsl", include_str!("../../../shaders/composite.wgsl")),
    ("irradiance.wgsl", include_str!("../../../shaders/irradiance.wgsl")),
    ("gbuffer.wgsl", include_str!("../../../shaders/gbuffer.wgsl")),
    ("gbuffer_multiview.wgsl", include_str!("../../../shaders/gbuffer_multiview.wgsl")),
    ("gbuffer_multipass.wgsl", include_str!("../../../shaders/gbuffer_multipass.wgsl")),
    ("peel.wgsl", include_str!("../../../shaders/peel.wgsl")),
    ("multiview_probe.wgsl", include_str!("../../../shaders/multiview_probe.wgsl")),
    ("direct.wgsl", include_str!("../../../shaders/direct.wgsl")),
    ("shadow.wgsl", include_str!("../../../shaders/shadow.wgsl")),
    ("shadow_map.wgsl", include_str!("../../../shaders/shadow_map.wgsl")),
    ("rsm.wgsl", include_str!("../../../shaders/rsm.wgsl")),
    ("tonemap.wgsl", include_str!("../../../shaders/tonemap.wgsl")),
    ("reproject.wgsl", include_str!("../../../shaders/reproject.wgsl")),
    ("mirror.wgsl", include_str!("../../../shaders/mirror.wgsl")),
    ("temporal.wgsl", include_str!("../../../shaders/temporal.wgsl")),
];

/// A shader module made of the named files, concatenated in order (common first), so
/// passes share `common.wgsl` without string formatting.
pub fn shader_module(device: &wgpu::Device, label: &str, files: &[&str]) -> wgpu::ShaderModule {
    // Shader development: `VRAO_SHADER_DIR=shaders` reads the files from disk, so an
    // edited shader runs without rebuilding the binary.
    let shader_dir = std::env::var_os("VRAO_SHADER_DIR").map(std::path::PathBuf::from);
    let mut source = String::new();
    for file in files {
        let text = SHADERS
            .iter()
            .find(|(name, _)| name == file)
            .map(|(_, text)| *text)
            .unwrap_or_else(|| panic!("shader {file} is not registered in SHADERS"));
        match &shader_dir {
            Some(dir) => match std::fs::read_to_string(dir.join(file)) {
                Ok(text) => source.push_str(&text),
                Err(error) => {
                    eprintln!("error: VRAO_SHADER_DIR: cannot read {}: {error}", dir.join(file).display());
                    std::process::exit(2);
                }
            },
            None => source.push_str(text),
        }
        source.push('\n');
    }
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// What a kernel binds at one binding index.
#[derive(Clone, Copy, Debug)]
pub enum Slot {
    /// `texture_depth_2d_array`, read with `textureLoad`.
    Depth,
    /// `texture_2d_array<f32>`, read with `textureLoad`.
    Layers,
    /// `texture_2d_array<u32>`, read with `textureLoad` (packed data such as `Direct`).
    UintLayers,
    /// `texture_2d_array<f32>`, filterable, read with a sampler.
    FilterableLayers,
    /// `texture_2d<f32>`, filterable (environment map).
    Texture2d,
    /// A filtering sampler.
    Sampler,
    /// A comparison sampler (`sampler_comparison`, shadow maps).
    ComparisonSampler,
    /// `texture_storage_2d_array<FORMAT, write>`.
    Output(wgpu::TextureFormat),
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    ReadBuffer,
    /// `var<storage, read_write>` (atomics).
    ReadWriteBuffer,
}

impl Slot {
    fn layout_entry(self, binding: u32) -> wgpu::BindGroupLayoutEntry {
        let ty = match self {
            Slot::Depth => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Slot::Layers => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Slot::UintLayers => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Slot::FilterableLayers => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Slot::Texture2d => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            Slot::Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            Slot::ComparisonSampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
            Slot::Output(format) => wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2Array,
            },
            Slot::Uniform => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            Slot::ReadBuffer => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            Slot::ReadWriteBuffer => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        };
        wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::COMPUTE, ty, count: None }
    }
}

/// A full-screen compute kernel over layered targets: one dispatch covers every layer
/// (`global_id.z` is the layer).
pub struct Kernel {
    label: String,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    slots: Vec<Slot>,
    /// Bind groups made so far, by the identity of what they bind, with the epoch they
    /// were made in: a frame binds what the last one did, so none is made again.
    bind_groups: Mutex<(u64, HashMap<u64, wgpu::BindGroup>)>,
}

impl Kernel {
    /// Compiles `entry` of the WGSL `files` (concatenated) into a compute kernel binding `slots`.
    pub fn new(gpu: &Gpu, label: &str, files: &[&str], entry: &str, slots: &[Slot]) -> Kernel {
        Self::with_constants(gpu, label, files, entry, slots, &[])
    }

    /// A kernel whose WGSL `override` constants take the given values.
    pub fn with_constants(
        gpu: &Gpu,
        label: &str,
        files: &[&str],
        entry: &str,
        slots: &[Slot],
        constants: &[(&str, f64)],
    ) -> Kernel {
        let device = &gpu.device;
        let entries: Vec<_> = slots.iter().enumerate().map(|(i, s)| s.layout_entry(i as u32)).collect();
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shader_module(device, label, files);
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
            cache: None,
        });
        Kernel {
            label: label.to_string(),
            pipeline,
            layout,
            slots: slots.to_vec(),
            bind_groups: Mutex::new((BIND_GROUP_EPOCH.load(Ordering::Relaxed), HashMap::new())),
        }
    }

    /// Binds `resources` (one per slot, in slot order) and dispatches over
    /// `width × height × layers` invocations.
    pub fn dispatch(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        resources: &[wgpu::BindingResource],
        (width, height, layers): (u32, u32, u32),
    ) {
        let bind_group = self.bind_group(device, resources);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(&self.label), timestamp_writes: None });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(width.div_ceil(TILE), height.div_ceil(TILE), layers);
    }

    /// Binds `resources` and dispatches the workgroup counts that an earlier dispatch
    /// wrote into `args` at `offset` (three u32: x, y, z), for work only the GPU knows
    /// the size of.
    pub fn dispatch_indirect(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        resources: &[wgpu::BindingResource],
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        let bind_group = self.bind_group(device, resources);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(&self.label), timestamp_writes: None });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups_indirect(args, offset);
    }

    /// The bind group of `resources`: the kept one when these resources were bound
    /// before, a new one otherwise.
    fn bind_group(&self, device: &wgpu::Device, resources: &[wgpu::BindingResource]) -> wgpu::BindGroup {
        assert_eq!(resources.len(), self.slots.len(), "kernel {}: one resource per slot", self.label);
        let key = identity(resources);
        let epoch = BIND_GROUP_EPOCH.load(Ordering::Relaxed);
        let mut cache = self.bind_groups.lock().expect("bind group cache");
        if cache.0 != epoch || cache.1.len() >= MAX_CACHED_BIND_GROUPS {
            *cache = (epoch, HashMap::new());
        }
        if let Some(key) = key {
            if let Some(group) = cache.1.get(&key) {
                return group.clone();
            }
        }
        let group = self.make_bind_group(device, resources);
        if let Some(key) = key {
            cache.1.insert(key, group.clone());
        }
        group
    }

    fn make_bind_group(&self, device: &wgpu::Device, resources: &[wgpu::BindingResource]) -> wgpu::BindGroup {
        let entries: Vec<_> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupEntry { binding: i as u32, resource: r.clone() })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// A hash of which buffers (and ranges), views and samplers are bound where; `None` for
/// kinds of binding it does not know (those are never cached).
fn identity(resources: &[wgpu::BindingResource]) -> Option<u64> {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    for (slot, resource) in resources.iter().enumerate() {
        slot.hash(&mut hasher);
        match resource {
            wgpu::BindingResource::Buffer(b) => {
                (0u8, b.buffer, b.offset, b.size).hash(&mut hasher);
            }
            wgpu::BindingResource::TextureView(view) => (1u8, *view).hash(&mut hasher),
            wgpu::BindingResource::Sampler(sampler) => (2u8, *sampler).hash(&mut hasher),
            _ => return None,
        }
    }
    Some(hasher.finish())
}
