//! The wgpu plumbing written once: shader modules from WGSL files kept beside their
//! passes, and compute kernels whose bind-group layout follows from a binding list
//! ([`Bind`]); binding `i` is entry `i`.

use super::Gpu;
use crate::error::{Error, Result};
use crate::resource::{ChainLayout, Resource};
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};

/// Bind groups a kernel keeps before it starts over (a frame binds each kernel a few
/// times; more means the resources change every frame).
const MAX_CACHED_BIND_GROUPS: usize = 64;

/// Compute pipelines a device keeps before it starts over (a frame uses a few dozen; a
/// sweep over override constants makes more).
const MAX_KEPT_PIPELINES: usize = 512;

/// The compute pipelines compiled on one device ([`Gpu`]), by what they were compiled
/// from: the shader's text, entry, override constants and bindings. A chain made again
/// with settings seen before (the governor returning to a level, a bench's next round, a
/// resize that rebuilds) binds the pipelines compiled the first time instead of compiling
/// them again, which is a stall of milliseconds to a second per pipeline where the driver
/// compiles with LLVM. Kernels whose build was cancelled are never kept.
#[derive(Default)]
pub(crate) struct CompiledPipelines(Mutex<HashMap<u64, wgpu::ComputePipeline>>);

impl CompiledPipelines {
    /// The pipeline kept under `key`, or the one `compile` makes, kept from now on.
    fn get_or_compile(&self, key: u64, compile: impl FnOnce() -> wgpu::ComputePipeline) -> wgpu::ComputePipeline {
        if let Some(pipeline) = self.0.lock().expect("compiled pipelines").get(&key) {
            return pipeline.clone();
        }
        // Compiled outside the lock: two threads may compile the same pipeline once each.
        let pipeline = compile();
        let mut kept = self.0.lock().expect("compiled pipelines");
        if kept.len() >= MAX_KEPT_PIPELINES {
            kept.clear();
        }
        kept.insert(key, pipeline.clone());
        pipeline
    }
}

/// What a compute pipeline is compiled from, as the key of [`CompiledPipelines`].
fn pipeline_key(label: &str, source: &str, entry: &str, constants: &[(&str, f64)], slots: &[Slot]) -> u64 {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    (label, source, entry).hash(&mut hasher);
    for (name, value) in constants {
        (name, value.to_bits()).hash(&mut hasher);
    }
    // The slots decide the bind group layout; their Debug text names every field.
    format!("{slots:?}").hash(&mut hasher);
    hasher.finish()
}

pub(crate) use super::support::TILE;

/// One WGSL file, compiled into the binary so it runs from any directory; `path` is
/// relative to the workspace root (for a shader directory, [`Gpu::set_shader_dir`]). Made by a crate-internal
/// `wgsl!` macro from the path within its crate.
#[derive(Clone, Copy, Debug)]
pub struct Shader {
    /// The file, relative to the repository root.
    pub path: &'static str,
    /// Its text as compiled in.
    pub source: &'static str,
}

/// A [`Shader`] of a WGSL file named by its path within this crate; the file lives
/// beside the code that uses it (`src/passes/<pass>/<pass>.wgsl`).
macro_rules! wgsl {
    ($path:literal) => {
        $crate::gpu::kernel::Shader {
            path: concat!("crates/", env!("CARGO_PKG_NAME"), "/", $path),
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $path)),
        }
    };
}

pub(crate) use wgsl;

/// `common.wgsl`: the frame's uniforms and helpers every pass shares.
pub const COMMON: Shader = wgsl!("shaders/common.wgsl");

/// `irradiance.wgsl`: the environment's irradiance and radiance quadratics (SSDO, a
/// renderer's composite).
pub const IRRADIANCE: Shader = wgsl!("shaders/irradiance.wgsl");

/// `chain_rgba.wgsl`: the AO chain's texel as rgb light and a AO ([`ChainLayout::Rgba`]).
pub(crate) const CHAIN_RGBA: Shader = wgsl!("shaders/chain_rgba.wgsl");

/// `chain_scalar.wgsl`: the AO chain's texel as AO alone ([`ChainLayout::Scalar`]).
pub(crate) const CHAIN_SCALAR: Shader = wgsl!("shaders/chain_scalar.wgsl");

/// The chain's WGSL prelude for `chain` (`ChainTarget`, `chain_value`, `chain_texel`):
/// the first file of every kernel.
pub(crate) fn chain_prelude(chain: ChainLayout) -> Shader {
    match chain {
        ChainLayout::Rgba => CHAIN_RGBA,
        ChainLayout::Scalar => CHAIN_SCALAR,
    }
}

/// One thing per AO chain layout a pass's frames may have (its kernels for each): the
/// four-channel layout always, the scalar one where the device writes it
/// ([`super::Capabilities::scalar_chain`]).
pub(crate) struct ByChain<T> {
    rgba: T,
    scalar: Option<T>,
}

impl<T> ByChain<T> {
    /// `make` for each layout the device can have.
    pub(crate) fn new(gpu: &Gpu, make: impl Fn(ChainLayout) -> T) -> ByChain<T> {
        ByChain { rgba: make(ChainLayout::Rgba), scalar: gpu.caps.scalar_chain.then(|| make(ChainLayout::Scalar)) }
    }

    /// The one for `chain` (a frame's `DeclareContext::chain`).
    pub(crate) fn get(&self, chain: ChainLayout) -> &T {
        match chain {
            ChainLayout::Rgba => &self.rgba,
            ChainLayout::Scalar => {
                self.scalar.as_ref().expect("a frame's chain is scalar only where the device writes it")
            }
        }
    }
}

/// `visibility.wgsl`: bind group 1 of every compute kernel, the visibility mask and
/// foveation map (`tile_rate`, `pixel_shown`), for the kernels that read it.
pub const VISIBILITY: Shader = wgsl!("shaders/visibility.wgsl");

/// The text of `files`, concatenated in order (common first) so passes share
/// `common.wgsl` without string formatting: as compiled in, or read from `gpu`'s shader
/// directory when it has one ([`Gpu::set_shader_dir`]). A file that cannot be read there
/// is `Error::Input` naming it.
pub(crate) fn shader_source(gpu: &Gpu, files: &[Shader]) -> Result<String> {
    source_from(gpu.shader_dir(), files)
}

/// [`shader_source`] with the shader directory given (`None`: the compiled-in text).
fn source_from(dir: Option<&Path>, files: &[Shader]) -> Result<String> {
    let mut source = String::new();
    for file in files {
        match dir {
            Some(dir) => {
                let path = dir.join(file.path);
                let text = read_shader(&path).map_err(|e| {
                    Error::in_file(&path, format!("cannot read this shader (from the shader directory): {e}"))
                })?;
                source.push_str(&text);
            }
            None => source.push_str(file.source),
        }
        source.push('\n');
    }
    Ok(source)
}

/// The most bytes a shader file from the shader directory may hold (16 MiB).
const MAX_SHADER_BYTES: u64 = 16 << 20;

/// A shader file's text: a regular file only (a FIFO would block the read, a device never
/// ends), at most [`MAX_SHADER_BYTES`] read.
fn read_shader(path: &Path) -> std::io::Result<String> {
    use std::io::{Error, ErrorKind, Read};
    if !std::fs::metadata(path)?.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file"));
    }
    let mut text = String::new();
    std::fs::File::open(path)?.take(MAX_SHADER_BYTES + 1).read_to_string(&mut text)?;
    if text.len() as u64 > MAX_SHADER_BYTES {
        return Err(Error::new(ErrorKind::InvalidData, format!("more than {MAX_SHADER_BYTES} bytes")));
    }
    Ok(text)
}

/// The first error kept until someone takes it (each `Gpu` has one for its shaders).
#[derive(Default)]
pub(crate) struct ErrorSlot(Mutex<Option<Error>>);

impl ErrorSlot {
    #[cfg(test)]
    const fn new() -> ErrorSlot {
        ErrorSlot(Mutex::new(None))
    }

    /// Keeps `error` unless an earlier one is waiting (then it is only logged, at debug:
    /// one missing directory fails every shader).
    pub(crate) fn record(&self, error: Error) {
        let mut slot = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if slot.is_some() {
            log::debug!("{error}");
        } else {
            log::error!("{error}");
            *slot = Some(error);
        }
    }

    pub(crate) fn take(&self) -> Result<()> {
        match self.0.lock().unwrap_or_else(|p| p.into_inner()).take() {
            Some(error) => Err(error),
            None => Ok(()),
        }
    }
}

/// A shader module of `files` (`shader_source`); an unreadable file is the error.
pub fn try_shader_module(gpu: &Gpu, label: &str, files: &[Shader]) -> Result<wgpu::ShaderModule> {
    Ok(module_of(&gpu.device, label, shader_source(gpu, files)?))
}

/// The text of `files` ([`shader_source`]) that always comes: a file that cannot be read
/// is recorded for [`Gpu::take_shader_error`] and the compiled-in text stands in.
fn source_or_recorded(gpu: &Gpu, files: &[Shader]) -> String {
    shader_source(gpu, files).unwrap_or_else(|error| {
        gpu.shader_error.record(error);
        source_from(None, files).expect("the compiled-in text needs no file")
    })
}

/// A shader module of `files` (`shader_source`) that always succeeds, for the passes'
/// constructors: a file that cannot be read is recorded for [`Gpu::take_shader_error`]
/// and the compiled-in text stands in, so the module is valid until the error is returned.
pub fn shader_module(gpu: &Gpu, label: &str, files: &[Shader]) -> wgpu::ShaderModule {
    module_of(&gpu.device, label, source_or_recorded(gpu, files))
}

fn module_of(device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// One binding of a kernel, in binding order. A pass's binding list is the one place
/// that says what the kernel binds: the bind group layout, the pass's reads and writes
/// (`PassDecl::bindings`) and the resources
/// bound each frame all follow from it.
#[derive(Clone, Copy, Debug)]
pub enum Bind {
    /// The frame's uniforms (`Frame` of common.wgsl).
    Frame,
    /// The occlusion parameters (`AoParams` of common.wgsl).
    AoParams,
    /// The occlusion's hemisphere kernel (storage, read).
    SampleKernel,
    /// The scene's environment map (`texture_2d<f32>`, filterable).
    Environment,
    /// The environment's filtering sampler.
    EnvironmentSampler,
    /// A nearest sampler for `textureGather` (2×2 texels in one fetch), clamped to the edge.
    GatherSampler,
    /// A texture of the graph the pass reads: `texture_depth_2d_array` for depth,
    /// `texture_2d_array<u32>` for unsigned formats, `texture_2d_array<f32>` otherwise.
    Read(Resource),
    /// A texture of the graph the pass writes: `texture_storage_2d_array<format, write>`.
    Write(Resource),
    /// Something the pass binds itself (its own uniform, a layer view, …), given at dispatch.
    Own(Slot),
}

impl Bind {
    /// The slot type this binding has in the layout of a kernel whose AO chain is laid out
    /// as `chain` (what a chain target's storage binding is written as).
    pub fn slot_in(self, chain: ChainLayout) -> Slot {
        match self {
            Bind::Frame | Bind::AoParams => Slot::Uniform,
            Bind::SampleKernel => Slot::ReadBuffer,
            Bind::Environment => Slot::Texture2d,
            Bind::EnvironmentSampler => Slot::Sampler,
            Bind::GatherSampler => Slot::NonFilteringSampler,
            Bind::Read(r) if r.format().is_depth_stencil_format() => Slot::Depth,
            Bind::Read(r) if r.format().sample_type(None, None) == Some(wgpu::TextureSampleType::Uint) => {
                Slot::UintLayers
            }
            Bind::Read(_) => Slot::Layers,
            Bind::Write(r) => Slot::Output(r.format_in(chain)),
            Bind::Own(slot) => slot,
        }
    }
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
    /// A non-filtering sampler (gathers from depth and unfilterable textures).
    NonFilteringSampler,
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
    /// How this slot binds (its layout entry's type).
    pub fn binding_type(self) -> wgpu::BindingType {
        self.layout_entry(0, wgpu::ShaderStages::COMPUTE).ty
    }

    /// The layout entry of this slot at `binding`, seen by the `visibility` stages.
    pub fn layout_entry(self, binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
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
            Slot::NonFilteringSampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
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
        wgpu::BindGroupLayoutEntry { binding, visibility, ty, count: None }
    }
}

/// A full-screen compute kernel over layered targets: one dispatch covers every layer
/// (`global_id.z` is the layer). Compiled when made, or at its first dispatch on a
/// [`Gpu`] with lazy pipelines ([`Gpu::set_lazy_pipelines`]).
pub struct Kernel {
    label: String,
    pipeline: OnceLock<wgpu::ComputePipeline>,
    /// What compiles the pipeline at the first dispatch, for a lazy kernel.
    recipe: Option<Recipe>,
    layout: wgpu::BindGroupLayout,
    slots: Vec<Slot>,
    /// Bind groups made so far, by the identity of what they bind, with the epoch they
    /// were made in: a frame binds what the last one did, so none is made again.
    bind_groups: Mutex<(u64, HashMap<u64, wgpu::BindGroup>)>,
    /// The `Gpu`'s bind-group epoch ([`Gpu::invalidate_bind_groups`]).
    epoch: std::sync::Arc<AtomicU64>,
}

/// A lazy kernel's shader and how to compile it.
struct Recipe {
    source: String,
    entry: String,
    constants: Vec<(String, f64)>,
    pipeline_layout: wgpu::PipelineLayout,
    /// The caller's cancellation token ([`Gpu::cancel_builds_on`]): set, the kernel
    /// compiles as a stand-in of no work.
    interrupt: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// The device's count of compiled pipelines ([`Gpu::pipelines_built`]).
    built: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    /// The device's compiled pipelines, and this kernel's key among them.
    compiled: std::sync::Arc<CompiledPipelines>,
    key: u64,
}

/// The module of a kernel whose build was cancelled: no work (more bindings in the layout
/// than the shader uses is valid).
fn stand_in_module(device: &wgpu::Device, label: &str, entry: &str) -> wgpu::ShaderModule {
    let source = format!("@compute @workgroup_size({TILE}, {TILE}, 1) fn {entry}() {{}}");
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

impl Recipe {
    /// The pipeline: the device's kept one when it compiled the same before, else
    /// compiled now (a stand-in of no work, never kept, once the build is cancelled).
    fn compile(&self, device: &wgpu::Device, label: &str) -> wgpu::ComputePipeline {
        if self.interrupt.as_ref().is_some_and(|flag| flag.load(Ordering::Relaxed)) {
            let module = stand_in_module(device, label, &self.entry);
            self.built.fetch_add(1, Ordering::Relaxed);
            return compute_pipeline(device, label, &self.pipeline_layout, &module, &self.entry, &[]);
        }
        self.compiled.get_or_compile(self.key, || {
            let module = module_of(device, label, self.source.clone());
            let constants: Vec<(&str, f64)> =
                self.constants.iter().map(|(name, value)| (name.as_str(), *value)).collect();
            self.built.fetch_add(1, Ordering::Relaxed);
            compute_pipeline(device, label, &self.pipeline_layout, &module, &self.entry, &constants)
        })
    }
}

fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
        cache: None,
    })
}

impl Kernel {
    /// Compiles `entry` of the WGSL `files` (concatenated) into a compute kernel binding
    /// `binds`. A shader file that cannot be read is recorded for [`Gpu::take_shader_error`]
    /// ([`shader_module`]).
    pub fn new(gpu: &Gpu, label: &str, files: &[Shader], entry: &str, binds: &[Bind]) -> Kernel {
        Self::with_constants(gpu, label, files, entry, binds, &[])
    }

    /// A kernel whose WGSL `override` constants take the given values (a file that
    /// cannot be read is recorded as by [`Kernel::new`]).
    pub fn with_constants(
        gpu: &Gpu,
        label: &str,
        files: &[Shader],
        entry: &str,
        binds: &[Bind],
        constants: &[(&str, f64)],
    ) -> Kernel {
        Self::in_chain(gpu, label, files, entry, binds, constants, ChainLayout::Rgba)
    }

    /// A kernel as [`Kernel::with_constants`] for a frame whose AO chain is laid out as
    /// `chain`: its chain targets bind in that format and its WGSL starts with that
    /// layout's prelude (shaders/chain_rgba.wgsl, chain_scalar.wgsl).
    pub fn in_chain(
        gpu: &Gpu,
        label: &str,
        files: &[Shader],
        entry: &str,
        binds: &[Bind],
        constants: &[(&str, f64)],
        chain: ChainLayout,
    ) -> Kernel {
        if gpu.builds_cancelled() {
            // The caller gave up on this build: a stand-in of no work compiles at once.
            let module = stand_in_module(&gpu.device, label, entry);
            return Self::from_module_in(gpu, label, &module, entry, binds, &[], chain);
        }
        // The files are read now, so an unreadable one is the error of whoever makes the
        // kernel; a lazy kernel waits only for the compilation.
        let files: Vec<Shader> = std::iter::once(chain_prelude(chain)).chain(files.iter().copied()).collect();
        let source = source_or_recorded(gpu, &files);
        let (layout, pipeline_layout, slots) = Self::layouts(gpu, label, binds, chain);
        let key = pipeline_key(label, &source, entry, constants, &slots);
        let recipe = Recipe {
            source,
            entry: entry.to_string(),
            constants: constants.iter().map(|(name, value)| (name.to_string(), *value)).collect(),
            pipeline_layout,
            interrupt: gpu.build_interrupt(),
            built: gpu.pipeline_counter(),
            compiled: gpu.compiled_pipelines.clone(),
            key,
        };
        // An eager kernel compiles now and needs its recipe no more.
        let pipeline = OnceLock::new();
        let recipe = if gpu.lazy_pipelines() {
            Some(recipe)
        } else {
            let _ = pipeline.set(recipe.compile(&gpu.device, label));
            None
        };
        Kernel {
            label: label.to_string(),
            pipeline,
            recipe,
            layout,
            slots,
            bind_groups: Mutex::new((gpu.bind_group_epoch.load(Ordering::Relaxed), HashMap::new())),
            epoch: gpu.bind_group_epoch.clone(),
        }
    }

    /// A kernel of `entry` in a module made already (say by [`try_shader_module`], which
    /// returns a shader file it cannot read as the error), its `override` constants set;
    /// compiled now.
    pub fn from_module(
        gpu: &Gpu,
        label: &str,
        module: &wgpu::ShaderModule,
        entry: &str,
        binds: &[Bind],
        constants: &[(&str, f64)],
    ) -> Kernel {
        Self::from_module_in(gpu, label, module, entry, binds, constants, ChainLayout::Rgba)
    }

    /// [`Kernel::from_module`] for a frame whose AO chain is laid out as `chain` (the
    /// module was made with its prelude).
    fn from_module_in(
        gpu: &Gpu,
        label: &str,
        module: &wgpu::ShaderModule,
        entry: &str,
        binds: &[Bind],
        constants: &[(&str, f64)],
        chain: ChainLayout,
    ) -> Kernel {
        let (layout, pipeline_layout, slots) = Self::layouts(gpu, label, binds, chain);
        let pipeline = compute_pipeline(&gpu.device, label, &pipeline_layout, module, entry, constants);
        gpu.pipeline_counter().fetch_add(1, Ordering::Relaxed);
        Kernel {
            label: label.to_string(),
            pipeline: OnceLock::from(pipeline),
            recipe: None,
            layout,
            slots,
            bind_groups: Mutex::new((gpu.bind_group_epoch.load(Ordering::Relaxed), HashMap::new())),
            epoch: gpu.bind_group_epoch.clone(),
        }
    }

    /// The bind group layout, the pipeline layout and the slots of `binds`.
    fn layouts(
        gpu: &Gpu,
        label: &str,
        binds: &[Bind],
        chain: ChainLayout,
    ) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout, Vec<Slot>) {
        let device = &gpu.device;
        let slots: Vec<Slot> = binds.iter().map(|b| b.slot_in(chain)).collect();
        // The start-up check refuses adapters that cannot write these formats; a kernel
        // writing another would fail on them only at its first frame. The scalar chain's
        // format is written only where the device said it can (`Capabilities::scalar_chain`).
        for slot in &slots {
            if let Slot::Output(format) = slot {
                assert!(
                    super::support::STORAGE_WRITE_FORMATS.contains(format) || *format == ChainLayout::Scalar.format(),
                    "kernel {label} writes {format:?}: add it to support::STORAGE_WRITE_FORMATS"
                );
            }
        }
        let entries: Vec<_> =
            slots.iter().enumerate().map(|(i, s)| s.layout_entry(i as u32, wgpu::ShaderStages::COMPUTE)).collect();
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            // Group 1: the visibility mask and foveation map every kernel may read.
            bind_group_layouts: &[Some(&layout), Some(&gpu.visibility_layout)],
            immediate_size: 0,
        });
        (layout, pipeline_layout, slots)
    }

    /// Whether the pipeline has been compiled.
    pub fn is_compiled(&self) -> bool {
        self.pipeline.get().is_some()
    }

    /// The pipeline, compiled now if it has not been.
    fn pipeline(&self, device: &wgpu::Device) -> &wgpu::ComputePipeline {
        self.pipeline.get_or_init(|| {
            let recipe = self.recipe.as_ref().expect("a kernel without a pipeline has a recipe");
            recipe.compile(device, &self.label)
        })
    }

    /// Binds `resources` (one per slot, in slot order) and the frame's `visibility` maps
    /// (group 1) and dispatches over `width × height × layers` invocations.
    pub fn dispatch(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        visibility: &wgpu::BindGroup,
        resources: &[wgpu::BindingResource],
        (width, height, layers): (u32, u32, u32),
    ) {
        let bind_group = self.bind_group(device, resources);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(&self.label), timestamp_writes: None });
        pass.set_pipeline(self.pipeline(device));
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_bind_group(1, visibility, &[]);
        pass.dispatch_workgroups(width.div_ceil(TILE), height.div_ceil(TILE), layers);
    }

    /// Binds `resources` and dispatches the workgroup counts that an earlier dispatch
    /// wrote into `args` at `offset` (three u32: x, y, z), for work only the GPU knows
    /// the size of.
    pub fn dispatch_indirect(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        visibility: &wgpu::BindGroup,
        resources: &[wgpu::BindingResource],
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        let bind_group = self.bind_group(device, resources);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(&self.label), timestamp_writes: None });
        pass.set_pipeline(self.pipeline(device));
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_bind_group(1, visibility, &[]);
        pass.dispatch_workgroups_indirect(args, offset);
    }

    /// The bind group of `resources`: the kept one when these resources were bound
    /// before, a new one otherwise.
    fn bind_group(&self, device: &wgpu::Device, resources: &[wgpu::BindingResource]) -> wgpu::BindGroup {
        assert_eq!(resources.len(), self.slots.len(), "kernel {}: one resource per slot", self.label);
        let key = identity(resources);
        let epoch = self.epoch.load(Ordering::Relaxed);
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

#[cfg(test)]
mod tests {
    use super::*;

    const COMMON_AND_MISSING: [Shader; 2] =
        [COMMON, Shader { path: "crates/vrao-ao/shaders/no-such-file.wgsl", source: "" }];

    #[test]
    fn compiled_in_sources_are_concatenated_in_order() {
        let other = Shader { path: "other.wgsl", source: "// other" };
        let text = source_from(None, &[COMMON, other]).unwrap();
        assert_eq!(text, format!("{}\n{}\n", COMMON.source, other.source));
    }

    #[test]
    fn a_shader_directory_is_read_from_and_a_missing_file_is_an_input_error_naming_it() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let dir = dir.as_path();
        assert_eq!(source_from(Some(dir), &[COMMON]).unwrap(), format!("{}\n", COMMON.source));
        let error = source_from(Some(dir), &COMMON_AND_MISSING).unwrap_err();
        match &error {
            Error::Input { file: Some(file), .. } => {
                assert_eq!(file, &dir.join("crates/vrao-ao/shaders/no-such-file.wgsl"))
            }
            other => panic!("not an input error naming the file: {other:?}"),
        }
        assert!(error.to_string().contains("no-such-file.wgsl"));
    }

    #[test]
    fn a_shader_path_that_is_a_folder_or_a_fifo_is_refused_without_blocking() {
        let dir = std::env::temp_dir().join(format!("vrao-shader-dir-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("a-folder.wgsl")).unwrap();
        let folder = Shader { path: "a-folder.wgsl", source: "" };
        let error = source_from(Some(&dir), &[folder]).unwrap_err().to_string();
        assert!(error.contains("a-folder.wgsl") && error.contains("not a regular file"), "{error}");
        let made_fifo = std::process::Command::new("mkfifo").arg(dir.join("a-fifo.wgsl")).status();
        if made_fifo.is_ok_and(|s| s.success()) {
            let fifo = Shader { path: "a-fifo.wgsl", source: "" };
            let error = source_from(Some(&dir), &[fifo]).unwrap_err().to_string();
            assert!(error.contains("not a regular file"), "{error}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_first_recorded_error_is_returned_once() {
        let slot = ErrorSlot::new();
        assert!(slot.take().is_ok());
        slot.record(Error::input("first"));
        slot.record(Error::input("second"));
        assert_eq!(slot.take().unwrap_err().to_string(), "first");
        assert!(slot.take().is_ok());
    }
}
