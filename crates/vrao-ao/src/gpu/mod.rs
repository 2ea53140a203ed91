//! The device (a host's or a renderer's), layered targets, compute-kernel plumbing, GPU timing and
//! readback. Everything GPU-side that is not a technique lives here.

pub(crate) mod kernel;
pub(crate) mod layered_target;
#[cfg(any(test, feature = "layout-check"))]
pub mod layout_check;
pub(crate) mod raster;
pub(crate) mod readback;
pub(crate) mod support;
pub(crate) mod timing;
pub(crate) mod uniforms;
pub(crate) mod visibility;

use crate::error::{Error, Result};
use std::fmt::Write as _;

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
    /// The device writes `R16Float` storage textures (wgpu's
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`, which every desktop Vulkan GPU offers
    /// for it, and a probe): the AO chain of GTAO, SSAO and HBAO is then single-channel,
    /// 2 bytes a texel instead of 8. A renderer may turn it off to compare.
    pub scalar_chain: bool,
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
    /// A nearest, clamp-to-edge sampler for [`kernel::Bind::GatherSampler`]: kernels
    /// fetch a 2×2 block of texels with one `textureGather` through it.
    pub(crate) gather_sampler: wgpu::Sampler,
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
    /// (`bind_group_layout`).
    pub visibility_layout: wgpu::BindGroupLayout,
}

/// The sampler of [`Gpu::gather_sampler`]: nearest (a gather never filters, and depth and
/// unfilterable formats take only a non-filtering sampler), clamped to the edge as a
/// texel fetch clamped into the target is.
fn gather_sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor { label: Some("gather"), ..Default::default() })
}

impl Gpu {
    /// The `Gpu` for a device a renderer opened on `adapter` and hands over (vrao's
    /// renderer, or a device an OpenXR runtime created): the adapter is checked for what
    /// the kernels need (a refusal names what it lacks) and GPU errors are kept for
    /// [`Gpu::take_error`]. Multiview is marked unreliable until the renderer's probe says
    /// otherwise (`caps.multiview_reliable`).
    pub fn from_device(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Gpu> {
        Self::check_adapter(&adapter)?;
        let uncaptured = std::sync::Arc::new(std::sync::Mutex::new(None));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            log::error!("wgpu: {e}");
            let mut slot = sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| e.to_string());
        }));
        let info = adapter.get_info();
        let visibility_layout = visibility::bind_group_layout(&device);
        Ok(Gpu {
            visibility_layout,
            gather_sampler: gather_sampler(&device),
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
            shader_dir: None,
            shader_error: Default::default(),
            bind_group_epoch: Default::default(),
        })
    }

    /// What `adapter` lacks that the kernels need (empty when nothing), for a renderer
    /// choosing among adapters.
    pub fn missing_capabilities(adapter: &wgpu::Adapter) -> Vec<String> {
        support::missing_capabilities(&support::AdapterSupport::of(adapter))
    }

    /// `Error::Device` naming what `adapter` lacks, if anything.
    pub fn check_adapter(adapter: &wgpu::Adapter) -> Result<()> {
        refuse_missing(&adapter.get_info(), Self::missing_capabilities(adapter))
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
            gather_sampler: gather_sampler(device),
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
            scalar_chain: support::writes_scalar_chain(device),
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
