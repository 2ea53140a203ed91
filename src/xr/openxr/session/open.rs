//! Opening the OpenXR headset: instance, system, the runtime-created Vulkan device
//! wrapped as the `Gpu`, the session and its swapchains.

use super::*;

impl OpenXrHeadset {
    /// Creates the instance (with XR_KHR_vulkan_enable2, and XR_KHR_composition_layer_depth,
    /// XR_KHR_convert_timespec_time and XR_KHR_visibility_mask when offered), finds the
    /// head-mounted display, has the runtime create the Vulkan instance and device, wraps
    /// them as the `Gpu`, and creates the session, a LOCAL reference space, the swapchains
    /// and reads each view's visibility mask. The session begins at its READY state, from
    /// `wait_frame`.
    pub fn open(options: OpenXrOptions) -> std::result::Result<(OpenXrHeadset, Arc<Gpu>), Unavailable> {
        let entry = load_entry()?;
        let slot = InstanceSlot::take()?;
        let (instance, extensions) = create_instance(&entry)?;
        let system = HeadsetSystem::find(&instance)?;
        let views = stereo_views(&instance, &system)?;
        let (recommended, size) = eye_sizes(&views, options.size);
        let blend_mode = blend_mode(&instance, system.id);

        let SessionParts { gpu, session, frame_waiter, frame_stream, space, refresh_rates_hz, refresh_hz, swapchains } =
            SessionParts::create(&instance, system.id, size, &extensions, &options)?;
        let mask = mask::initial(&session, extensions.khr_visibility_mask);
        let swapchain_text = swapchains.describe();
        let depth = swapchains.has_depth();
        let xr = Xr {
            swapchains,
            space,
            frame_stream,
            frame_waiter,
            session,
            instance,
            _slot: slot,
            blend_mode,
            clock: extensions.khr_convert_timespec_time,
        };
        let budget = FrameBudget::new(options.frames);
        let headset = OpenXrHeadset {
            gpu: gpu.clone(),
            options,
            xr: Some(xr),
            runtime: system.runtime,
            system: system.name,
            recommended,
            size,
            depth,
            swapchain_text,
            machine: SessionMachine::new(),
            budget,
            stats: OpenXrStats::default(),
            counters: FrameCounters::default(),
            latencies_ms: Vec::new(),
            next_index: 0,
            pending: None,
            tracking: Tracking::default(),
            opened: Instant::now(),
            fallback: None,
            display: {
                let mut display = crate::xr::DisplayRate::new();
                display.set_reported_hz(refresh_hz);
                display
            },
            refresh_rates_hz,
            refresh_hz,
            display_period_ms: 0.0,
            mask,
        };
        Ok((headset, gpu))
    }
}

/// Creates the OpenXR instance with XR_KHR_vulkan_enable2 and the optional extensions
/// the runtime offers; returns it and the extensions it was created with.
fn create_instance(entry: &xr::Entry) -> std::result::Result<(xr::Instance, xr::ExtensionSet), Unavailable> {
    let available = entry.enumerate_extensions().map_err(|e| {
        super::super::no_runtime(&super::super::xr_call_failed("xrEnumerateInstanceExtensionProperties", e))
    })?;
    if !available.khr_vulkan_enable2 {
        return Err(Unavailable::Unsupported("no XR_KHR_vulkan_enable2".into()));
    }
    let mut extensions = xr::ExtensionSet::default();
    extensions.khr_vulkan_enable2 = true;
    extensions.khr_composition_layer_depth = available.khr_composition_layer_depth;
    extensions.khr_convert_timespec_time = available.khr_convert_timespec_time;
    extensions.fb_display_refresh_rate = available.fb_display_refresh_rate;
    extensions.khr_visibility_mask = available.khr_visibility_mask;
    let instance = entry
        .create_instance(&application_info(), &extensions, &[], &())
        .map_err(|e| super::super::no_runtime(&super::super::xr_call_failed("xrCreateInstance", e)))?;
    Ok((instance, extensions))
}

/// The head-mounted display of an instance, with the names the headset reports.
struct HeadsetSystem {
    id: xr::SystemId,
    /// The runtime's name and version.
    runtime: String,
    /// The system's name ("unnamed system" when the runtime gives none).
    name: String,
}

impl HeadsetSystem {
    /// Names the runtime and finds its head-mounted display.
    fn find(instance: &xr::Instance) -> std::result::Result<HeadsetSystem, Unavailable> {
        let props = instance.properties().map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
        let runtime = format!("{} {}", props.runtime_name, props.runtime_version);
        let system = instance
            .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
            .map_err(|e| Unavailable::NoHeadset(format!("{runtime}: xrGetSystem(HEAD_MOUNTED_DISPLAY): {e}")))?;
        let system_name =
            instance.system_properties(system).map(|p| p.system_name).unwrap_or_else(|_| "unnamed system".into());
        Ok(HeadsetSystem { id: system, runtime, name: system_name })
    }
}

/// The two views of the system's PRIMARY_STEREO view configuration; refuses a system
/// without it.
fn stereo_views(
    instance: &xr::Instance,
    system: &HeadsetSystem,
) -> std::result::Result<Vec<xr::ViewConfigurationView>, Unavailable> {
    let view_types =
        instance.enumerate_view_configurations(system.id).map_err(failed("xrEnumerateViewConfigurations"))?;
    if !view_types.contains(&VIEW_TYPE) {
        return Err(Unavailable::Unsupported(format!("{} has no PRIMARY_STEREO view configuration", system.name)));
    }
    let views = instance
        .enumerate_view_configuration_views(system.id, VIEW_TYPE)
        .map_err(failed("xrEnumerateViewConfigurationViews"))?;
    if views.len() != 2 {
        return Err(Unavailable::Unsupported(format!("PRIMARY_STEREO has {} views", views.len())));
    }
    Ok(views)
}

/// The per-eye size the views recommend and the one to render at: `wanted` (else the
/// recommended one), scaled down to the views' maximum with its aspect kept (one warning
/// line naming the request and the limit).
fn eye_sizes(views: &[xr::ViewConfigurationView], wanted: Option<(u32, u32)>) -> ((u32, u32), (u32, u32)) {
    // One size for both eyes (vrao renders them as two layers of one target).
    let recommended = (
        views.iter().map(|v| v.recommended_image_rect_width).max().unwrap_or(0).max(1),
        views.iter().map(|v| v.recommended_image_rect_height).max().unwrap_or(0).max(1),
    );
    let max = (
        views.iter().map(|v| v.max_image_rect_width).min().unwrap_or(0).max(1),
        views.iter().map(|v| v.max_image_rect_height).min().unwrap_or(0).max(1),
    );
    let wanted = wanted.unwrap_or(recommended);
    let size = super::super::fit_within(wanted, max);
    if size != wanted {
        log::warn!(
            "OpenXR: {}x{} per eye is above the runtime's maximum {}x{}: rendering at {}x{} (aspect kept)",
            wanted.0,
            wanted.1,
            max.0,
            max.1,
            size.0,
            size.1
        );
    }
    (recommended, size)
}

/// The runtime's first environment blend mode for PRIMARY_STEREO, else OPAQUE.
fn blend_mode(instance: &xr::Instance, system: xr::SystemId) -> xr::EnvironmentBlendMode {
    instance
        .enumerate_environment_blend_modes(system, VIEW_TYPE)
        .ok()
        .and_then(|modes| modes.first().copied())
        .unwrap_or(xr::EnvironmentBlendMode::OPAQUE)
}

/// The GPU, the session and what is made with it, before they join `Xr`.
struct SessionParts {
    gpu: Arc<Gpu>,
    session: xr::Session<xr::Vulkan>,
    frame_waiter: xr::FrameWaiter,
    frame_stream: xr::FrameStream<xr::Vulkan>,
    space: xr::Space,
    refresh_rates_hz: Vec<f32>,
    refresh_hz: Option<f32>,
    swapchains: EyeSwapchains,
}

impl SessionParts {
    /// Has the runtime create the `Gpu`, then creates the session on it, the LOCAL
    /// reference space, the display refresh rate (when offered) and the swapchains.
    fn create(
        instance: &xr::Instance,
        system: xr::SystemId,
        size: (u32, u32),
        extensions: &xr::ExtensionSet,
        options: &OpenXrOptions,
    ) -> std::result::Result<SessionParts, Unavailable> {
        let (gpu, binding) = vulkan::create_gpu(instance, system)?;
        let gpu = Arc::new(gpu);
        // SAFETY: the binding names the instance, physical device and device the runtime
        // created for this system, and one queue of the family the device was made with;
        // wgpu and the runtime only use that queue from this thread.
        let (session, frame_waiter, frame_stream) =
            unsafe { instance.create_session::<xr::Vulkan>(system, &binding.session_create_info()) }
                .map_err(failed("xrCreateSession"))?;
        let space = session
            .create_reference_space(xr::ReferenceSpaceType::LOCAL, xr::Posef::IDENTITY)
            .map_err(failed("xrCreateReferenceSpace(LOCAL)"))?;
        let (refresh_rates_hz, refresh_hz) = if extensions.fb_display_refresh_rate {
            display_refresh_rate(&session, options.preferred_refresh_hz)
        } else {
            (Vec::new(), None)
        };
        let swapchains =
            EyeSwapchains::create(&gpu, &session, size, extensions.khr_composition_layer_depth, options.layout)?;
        Ok(SessionParts { gpu, session, frame_waiter, frame_stream, space, refresh_rates_hz, refresh_hz, swapchains })
    }
}

/// XR_FB_display_refresh_rate: the rates the runtime offers, and the rate it runs at
/// after asking for `preferred` when offered (within 0.5 Hz). A failing call only loses
/// the information: the budget comes from the predicted display period regardless.
fn display_refresh_rate(session: &xr::Session<xr::Vulkan>, preferred: Option<f64>) -> (Vec<f32>, Option<f32>) {
    let offered = session.enumerate_display_refresh_rates().unwrap_or_default();
    let current = session.get_display_refresh_rate().ok();
    let wanted = preferred.and_then(|hz| offered.iter().copied().find(|&r| (r as f64 - hz).abs() < 0.5));
    match wanted {
        Some(rate) if current != Some(rate) => match session.request_display_refresh_rate(rate) {
            Ok(()) => (offered, Some(rate)),
            Err(e) => {
                log::warn!("OpenXR: {}", super::super::xr_call_failed("xrRequestDisplayRefreshRateFB", e));
                (offered, current)
            }
        },
        _ => (offered, current),
    }
}
