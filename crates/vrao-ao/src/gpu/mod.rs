//! Device and adapter choice, layered targets, compute-kernel plumbing, GPU timing and
//! readback. Everything GPU-side that is not a technique lives here.

pub mod kernel;
pub mod layered_target;
#[cfg(any(test, feature = "layout-check"))]
#[doc(hidden)]
pub mod layout_check;
pub mod multiview_probe;
pub mod raster;
pub mod readback;
pub mod support;
pub mod timing;
pub mod uniforms;
pub mod visibility;

use crate::error::{Error, Result};
use std::fmt::Write as _;

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

/// What the chosen device can do that the renderer cares about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capabilities {
    /// The adapter offers multiview: one render pass writes both eye layers.
    pub multiview: bool,
    /// Multiview passed the start-up probe (clipped triangles reach every layer), so the
    /// `auto` stereo mode may use it.
    pub multiview_reliable: bool,
    /// Timestamp queries between passes (encoder-level writes).
    pub timestamps: bool,
}

/// The adapter, device and queue every pass shares.
pub struct Gpu {
    /// The wgpu instance the adapter came from (also makes window surfaces); `None` for a
    /// host's device ([`Gpu::from_host`]), which vrao did not open.
    pub instance: Option<wgpu::Instance>,
    /// The chosen adapter (`None` for a host's device).
    pub adapter: Option<wgpu::Adapter>,
    /// The adapter's name, backend, type and driver.
    pub info: wgpu::AdapterInfo,
    /// The logical device every resource is made on.
    pub device: wgpu::Device,
    /// The device's only queue.
    pub queue: wgpu::Queue,
    /// What the device can do that the renderer cares about.
    pub caps: Capabilities,
    /// The first wgpu error no scope caught (validation, out of memory, lost device):
    /// kept here instead of wgpu's default panic, and returned by [`Gpu::take_error`].
    uncaptured: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    /// The caller's cancellation token for building pipelines ([`Gpu::cancel_builds_on`]).
    build_interrupt: std::sync::OnceLock<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// Whether kernels compile on their first dispatch instead of when they are made
    /// ([`Gpu::set_lazy_pipelines`]).
    lazy_pipelines: bool,
    /// Compute pipelines compiled on this device so far.
    pipelines_built: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    /// The compute pipelines compiled so far, for kernels made again to reuse.
    pub(crate) compiled_pipelines: std::sync::Arc<kernel::CompiledPipelines>,
    /// Where shaders are read from instead of the compiled-in text ([`Gpu::set_shader_dir`]).
    shader_dir: Option<std::path::PathBuf>,
    /// The first shader file that could not be read ([`Gpu::take_shader_error`]).
    pub(crate) shader_error: std::sync::Arc<kernel::ErrorSlot>,
    /// Bumped whenever targets are made or dropped: every kernel made on this `Gpu` then
    /// forgets its bind groups, which would otherwise keep dropped textures alive.
    pub(crate) bind_group_epoch: std::sync::Arc<std::sync::atomic::AtomicU64>,
    /// Bind group 1 of every compute kernel: the visibility mask and foveation map
    /// ([`visibility::bind_group_layout`]).
    pub visibility_layout: wgpu::BindGroupLayout,
}

impl Gpu {
    /// Opens the best adapter for `choice`: a discrete or integrated GPU when one exists,
    /// otherwise a CPU (lavapipe) adapter. No adapter at all is `Error::Device`.
    pub fn new(choice: BackendChoice) -> Result<Gpu> {
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
                Ok(adapter) => return Self::from_adapter(instance, adapter),
                Err(e) => last_error = Some(e),
            }
        }
        Err(last_error.unwrap_or_else(|| Error::Device("no backend was tried".into())))
    }

    fn from_adapter(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Gpu> {
        let desc = Self::device_descriptor(&adapter);
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| Error::Device(format!("{} refused a device: {e}", adapter.get_info().name)))?;
        Self::from_device(instance, adapter, device, queue)
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

    /// The `Gpu` for a device opened with [`Gpu::device_descriptor`] (by wgpu, or wrapped
    /// from a device an OpenXR runtime created): the adapter is checked for what the
    /// kernels need (a refusal names what it lacks), GPU errors are kept for
    /// [`Gpu::take_error`], and the multiview probe runs.
    pub fn from_device(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Gpu> {
        refuse_missing(&adapter.get_info(), support::missing_capabilities(&support::AdapterSupport::of(&adapter)))?;
        let uncaptured = std::sync::Arc::new(std::sync::Mutex::new(None));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            log::error!("wgpu: {e}");
            let mut slot = sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| e.to_string());
        }));
        let info = adapter.get_info();
        let visibility_layout = visibility::bind_group_layout(&device);
        let mut gpu = Gpu {
            visibility_layout,
            caps: Self::capabilities_of(&device),
            instance: Some(instance),
            adapter: Some(adapter),
            info,
            device,
            queue,
            uncaptured,
            build_interrupt: std::sync::OnceLock::new(),
            lazy_pipelines: false,
            pipelines_built: Default::default(),
            compiled_pipelines: Default::default(),
            // The application's override (the engine on a host's device reads no
            // environment: Gpu::from_host).
            shader_dir: std::env::var_os(kernel::SHADER_DIR_VAR).map(std::path::PathBuf::from),
            shader_error: Default::default(),
            bind_group_epoch: Default::default(),
        };
        gpu.caps.multiview_reliable = gpu.caps.multiview && multiview_probe::multiview_reaches_every_layer(&gpu);
        Ok(gpu)
    }

    /// The `Gpu` for a device a host application opened and keeps (the AO engine's):
    /// checked for what the kernels need from the device alone (its backend, limits and
    /// features; a refusal is one `Error::Device` naming what is missing), and the host's
    /// uncaptured-error handler is left alone. Multiview is not probed: the engine's
    /// passes are compute kernels that never draw.
    pub fn from_host(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Gpu> {
        let info = device.adapter_info();
        refuse_missing(&info, support::missing_device_capabilities(&support::DeviceSupport::of(device)))?;
        Ok(Gpu {
            visibility_layout: visibility::bind_group_layout(device),
            caps: Capabilities { multiview: false, ..Self::capabilities_of(device) },
            instance: None,
            adapter: None,
            info,
            device: device.clone(),
            queue: queue.clone(),
            uncaptured: std::sync::Arc::new(std::sync::Mutex::new(None)),
            build_interrupt: std::sync::OnceLock::new(),
            lazy_pipelines: false,
            pipelines_built: Default::default(),
            compiled_pipelines: Default::default(),
            shader_dir: None,
            shader_error: Default::default(),
            bind_group_epoch: Default::default(),
        })
    }

    fn capabilities_of(device: &wgpu::Device) -> Capabilities {
        let features = device.features();
        Capabilities {
            multiview: features.contains(wgpu::Features::MULTIVIEW),
            multiview_reliable: false,
            timestamps: features
                .contains(wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS),
        }
    }

    /// Lets `interrupt` (the caller's Ctrl-C flag) cut short the building of pipelines on
    /// this device: once it is set, each kernel compiles a stand-in of no work instead of
    /// its shader (a CPU adapter takes up to two seconds for a renderer's), and
    /// vrao-render's `Renderer::new` returns
    /// [`crate::error::Error::Interrupted`]. Only the first token given counts.
    pub fn cancel_builds_on(&self, interrupt: std::sync::Arc<std::sync::atomic::AtomicBool>) {
        let _ = self.build_interrupt.set(interrupt);
    }

    /// Makes kernels made from now on compile at their first dispatch (the AO engine: a
    /// host pays only for the technique it runs) instead of when they are made (the
    /// renderer, whose governor switches techniques mid-session and must not stall a
    /// frame compiling one).
    pub fn set_lazy_pipelines(&mut self, lazy: bool) {
        self.lazy_pipelines = lazy;
    }

    /// Whether kernels compile at their first dispatch ([`Gpu::set_lazy_pipelines`]).
    pub fn lazy_pipelines(&self) -> bool {
        self.lazy_pipelines
    }

    /// Reads this `Gpu`'s shaders from `dir` (the workspace root's layout, files named as
    /// in each [`kernel::Shader`]) instead of the compiled-in text, for passes made from
    /// now on; `None` returns to the compiled-in text.
    pub fn set_shader_dir(&mut self, dir: Option<std::path::PathBuf>) {
        self.shader_dir = dir;
    }

    /// The directory shaders are read from, if any ([`Gpu::set_shader_dir`]).
    pub fn shader_dir(&self) -> Option<&std::path::Path> {
        self.shader_dir.as_deref()
    }

    /// The first shader file that could not be read from the shader directory since the
    /// last call, as the `Error::Input` naming it (then cleared). Whoever makes passes
    /// through the infallible [`kernel::shader_module`] or [`kernel::Kernel::new`] checks
    /// this before using them.
    pub fn take_shader_error(&self) -> Result<()> {
        self.shader_error.take()
    }

    /// Makes every kernel on this `Gpu` forget its cached bind groups (call when targets
    /// are made or dropped).
    pub fn invalidate_bind_groups(&self) {
        self.bind_group_epoch.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// Compute pipelines compiled through this `Gpu` so far (kernels, eager or lazy).
    pub fn pipelines_built(&self) -> usize {
        self.pipelines_built.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The counter of [`Gpu::pipelines_built`], for kernels that compile later.
    pub(crate) fn pipeline_counter(&self) -> std::sync::Arc<std::sync::atomic::AtomicUsize> {
        self.pipelines_built.clone()
    }

    /// The token of [`Gpu::cancel_builds_on`], for builds that happen later (lazy kernels).
    pub(crate) fn build_interrupt(&self) -> Option<std::sync::Arc<std::sync::atomic::AtomicBool>> {
        self.build_interrupt.get().cloned()
    }

    /// Whether the token of [`Gpu::cancel_builds_on`] is set.
    pub fn builds_cancelled(&self) -> bool {
        self.build_interrupt.get().is_some_and(|flag| flag.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// The first GPU error since the last call, as `Error::Gpu` (then cleared).
    pub fn take_error(&self) -> Result<()> {
        match self.uncaptured.lock().unwrap_or_else(|p| p.into_inner()).take() {
            Some(message) => Err(Error::Gpu(message)),
            None => Ok(()),
        }
    }

    /// Blocks until all submitted work has finished.
    /// Runs the callbacks of submissions that have finished (completion callbacks,
    /// buffer mappings) without waiting for any.
    pub fn poll(&self) -> Result<()> {
        self.device.poll(wgpu::PollType::Poll).map_err(|e| Error::Gpu(format!("polling the device: {e}")))?;
        Ok(())
    }

    /// Blocks until all submitted work has finished, then returns the first uncaught wgpu error, if any.
    pub fn wait_idle(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
        self.take_error()
    }

    /// Human-readable description for `vrao info`.
    pub fn describe(&self) -> String {
        let info = &self.info;
        let limits = self.device.limits();
        let yes_no = |b: bool| if b { "yes" } else { "no" };
        let mut s = String::new();
        let _ = writeln!(s, "adapter:      {}", info.name);
        let _ = writeln!(s, "type:         {:?}", info.device_type);
        let _ = writeln!(s, "backend:      {:?}", info.backend);
        let _ = writeln!(s, "driver:       {} {}", info.driver, info.driver_info);
        let multiview = match (self.caps.multiview, self.caps.multiview_reliable) {
            (false, _) => "no (one G-buffer pass per eye)",
            (true, true) => "yes (stereo G-buffer in one pass)",
            (true, false) => {
                "yes, but unreliable: clipped triangles reach layer 0 only (probe failed); auto uses one pass per eye"
            }
        };
        let _ = writeln!(s, "multiview:    {multiview}");
        let _ = writeln!(s, "timestamps:   {} (per-pass GPU timing)", yes_no(self.caps.timestamps));
        let _ = writeln!(s, "limits:");
        let _ = writeln!(s, "  max_texture_dimension_2d          {}", limits.max_texture_dimension_2d);
        let _ = writeln!(s, "  max_texture_array_layers          {}", limits.max_texture_array_layers);
        let _ = writeln!(s, "  max_multiview_view_count          {}", limits.max_multiview_view_count);
        let _ = writeln!(s, "  max_compute_invocations_per_wg    {}", limits.max_compute_invocations_per_workgroup);
        let _ = writeln!(s, "  max_compute_workgroup_storage     {} B", limits.max_compute_workgroup_storage_size);
        let _ = writeln!(s, "  max_storage_textures_per_stage    {}", limits.max_storage_textures_per_shader_stage);
        let _ = writeln!(s, "  max_buffer_size                   {} B", limits.max_buffer_size);
        let _ = write!(s, "  timestamp_period                  {} ns", self.queue.get_timestamp_period());
        s
    }
}

/// `Error::Device` naming what `missing` lists, unless it is empty.
fn refuse_missing(info: &wgpu::AdapterInfo, missing: Vec<String>) -> Result<()> {
    if missing.is_empty() {
        return Ok(());
    }
    Err(Error::Device(format!(
        "the {:?} adapter {} lacks {}; use Vulkan (for a CPU fall-back: apt install mesa-vulkan-drivers)",
        info.backend,
        info.name,
        missing.join(" and ")
    )))
}

/// Prefers a hardware adapter; a CPU adapter (lavapipe) is the fall-back. Adapters that
/// lack something the renderer needs ([`support::missing_capabilities`]) are passed over;
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
            let missing = support::missing_capabilities(&support::AdapterSupport::of(&a));
            (a, missing)
        })
        .collect();
    ranked.sort_by_key(|(a, missing)| (!missing.is_empty(), rank(a)));
    match ranked.into_iter().next() {
        Some((adapter, missing)) if missing.is_empty() => Ok(adapter),
        Some((adapter, missing)) => {
            refuse_missing(&adapter.get_info(), missing)?;
            unreachable!("an adapter that lacks something is refused")
        }
        None => Err(Error::Device(format!(
            "no adapter on backends {backends:?}; install a Vulkan driver \
             (for a CPU fall-back: apt install mesa-vulkan-drivers)"
        ))),
    }
}
