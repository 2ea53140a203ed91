//! The OpenXR session behind [`OpenXrHeadset`]: instance, system, Vulkan device,
//! swapchains, the frame loop and the session state machine.
//!
//! Frame loop (one frame per `wait_frame` + `submit`): xrWaitFrame → xrBeginFrame →
//! xrLocateViews at the predicted display time (the eye poses and fields of view the
//! application renders with) → the application renders → the swapchains are filled →
//! xrEndFrame with a projection layer (and each view's depth, with
//! XR_KHR_composition_layer_depth), or with no layer when the runtime said not to render.
//!
//! States (XrSessionState): IDLE waits; READY → xrBeginSession; SYNCHRONIZED, VISIBLE
//! and FOCUSED run frames (the runtime's shouldRender decides whether anything is drawn);
//! STOPPING → xrEndSession; EXITING ends the run (`wait_frame` returns `None`);
//! LOSS_PENDING, a pending instance loss or a failing runtime call tear the session down
//! and, when the options give one, continue on the simulated headset. Reprojection,
//! dropped and late frames are the runtime compositor's business: it does not report
//! them through OpenXR, so vrao's counters only say what was submitted.

use super::swapchain::{EyeSwapchains, FillError, SubImage};
use super::{application_info, load_entry, vulkan, InstanceSlot, OpenXrOptions, SessionPhase, Unavailable};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::headset::simulated::SimulatedHeadset;
use crate::headset::{FrameCounters, FrameRequest, Headset, SubmittedFrame};
use crate::stereo::{Eye, EyePair, EyeSide, Fov, HeadPose};
use glam::{DQuat, DVec3};
use openxr as xr;
use std::sync::Arc;
use std::time::{Duration, Instant};

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;
/// How long a session may stay before its first READY before vrao gives up on it.
const READY_TIMEOUT: Duration = Duration::from_secs(30);
/// How often an idle session (not running) is polled for events.
const IDLE_POLL: Duration = Duration::from_millis(5);
/// Latency samples kept for the counters' median and 95th percentile.
const LATENCY_SAMPLES: usize = 4096;

/// What the OpenXR headset did, beyond [`FrameCounters`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct OpenXrStats {
    /// Frames handed to the application (xrWaitFrame + xrBeginFrame).
    pub frames: u64,
    /// Frames the runtime asked not to render (shouldRender false).
    pub not_rendered: u64,
    /// Frames ended with the projection layer.
    pub layers: u64,
    /// Of those, frames whose views carried depth (XR_KHR_composition_layer_depth).
    pub layers_with_depth: u64,
    /// Frames ended without a layer (not rendered, or run while the session stopped).
    pub empty_frames: u64,
}

/// The OpenXR session objects. Fields drop in order: swapchains before the session,
/// the session before the instance, the instance before its process slot.
struct Xr {
    swapchains: EyeSwapchains,
    space: xr::Space,
    frame_stream: xr::FrameStream<xr::Vulkan>,
    frame_waiter: xr::FrameWaiter,
    session: xr::Session<xr::Vulkan>,
    instance: xr::Instance,
    _slot: InstanceSlot,
    blend_mode: xr::EnvironmentBlendMode,
    /// XR_KHR_convert_timespec_time: the runtime's clock can be read (for latency).
    clock: bool,
    /// Between xrBeginSession and xrEndSession.
    running: bool,
    exit_requested: bool,
}

/// A frame between `wait_frame` and `submit`.
struct Pending {
    index: u64,
    display_time: xr::Time,
    views: [xr::View; 2],
}

/// A real headset through an OpenXR runtime.
pub struct OpenXrHeadset {
    gpu: Arc<Gpu>,
    options: OpenXrOptions,
    xr: Option<Xr>,
    runtime: String,
    system: String,
    recommended: (u32, u32),
    /// The per-eye render and swapchain size (kept for the fall back after a loss).
    size: (u32, u32),
    /// Whether layers carry depth (XR_KHR_composition_layer_depth and a depth format).
    depth: bool,
    swapchain_text: String,
    phases: Vec<SessionPhase>,
    stats: OpenXrStats,
    counters: FrameCounters,
    latencies_ms: Vec<f64>,
    next_index: u64,
    pending: Option<Pending>,
    last_views: Option<[xr::View; 2]>,
    opened: Instant,
    ever_ready: bool,
    exited: bool,
    lost: Option<String>,
    fallback: Option<SimulatedHeadset>,
}

fn failed(what: &str) -> impl Fn(xr::sys::Result) -> Unavailable + '_ {
    move |e| Unavailable::Failed(format!("{what}: {e}"))
}

impl OpenXrHeadset {
    /// Creates the instance (with XR_KHR_vulkan_enable2, and XR_KHR_composition_layer_depth
    /// and XR_KHR_convert_timespec_time when offered), finds the head-mounted display,
    /// has the runtime create the Vulkan instance and device, wraps them as the `Gpu`,
    /// and creates the session, a LOCAL reference space and the swapchains. The session
    /// begins at its READY state, from `wait_frame`.
    pub fn open(options: OpenXrOptions) -> std::result::Result<(OpenXrHeadset, Arc<Gpu>), Unavailable> {
        let entry = load_entry()?;
        let slot = InstanceSlot::take()?;
        let available = entry.enumerate_extensions().map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
        if !available.khr_vulkan_enable2 {
            return Err(Unavailable::Unsupported("no XR_KHR_vulkan_enable2".into()));
        }
        let mut extensions = xr::ExtensionSet::default();
        extensions.khr_vulkan_enable2 = true;
        extensions.khr_composition_layer_depth = available.khr_composition_layer_depth;
        extensions.khr_convert_timespec_time = available.khr_convert_timespec_time;
        let instance = entry
            .create_instance(&application_info(), &extensions, &[], &())
            .map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
        let props = instance.properties().map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
        let runtime = format!("{} {}", props.runtime_name, props.runtime_version);
        let system = instance
            .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
            .map_err(|e| Unavailable::NoHeadset(format!("{runtime}: xrGetSystem(HEAD_MOUNTED_DISPLAY): {e}")))?;
        let system_name =
            instance.system_properties(system).map(|p| p.system_name).unwrap_or_else(|_| "unnamed system".into());
        let view_types =
            instance.enumerate_view_configurations(system).map_err(failed("xrEnumerateViewConfigurations"))?;
        if !view_types.contains(&VIEW_TYPE) {
            return Err(Unavailable::Unsupported(format!("{system_name} has no PRIMARY_STEREO view configuration")));
        }
        let views = instance
            .enumerate_view_configuration_views(system, VIEW_TYPE)
            .map_err(failed("xrEnumerateViewConfigurationViews"))?;
        if views.len() != 2 {
            return Err(Unavailable::Unsupported(format!("PRIMARY_STEREO has {} views", views.len())));
        }
        // One size for both eyes (vrao renders them as two layers of one target).
        let recommended = (
            views.iter().map(|v| v.recommended_image_rect_width).max().unwrap_or(0).max(1),
            views.iter().map(|v| v.recommended_image_rect_height).max().unwrap_or(0).max(1),
        );
        let max = (
            views.iter().map(|v| v.max_image_rect_width).min().unwrap_or(0).max(1),
            views.iter().map(|v| v.max_image_rect_height).min().unwrap_or(0).max(1),
        );
        let wanted = options.size.unwrap_or(recommended);
        let size = (wanted.0.clamp(1, max.0), wanted.1.clamp(1, max.1));
        let blend_mode = instance
            .enumerate_environment_blend_modes(system, VIEW_TYPE)
            .ok()
            .and_then(|modes| modes.first().copied())
            .unwrap_or(xr::EnvironmentBlendMode::OPAQUE);

        let (gpu, binding) = vulkan::create_gpu(&instance, system).map_err(Unavailable::Failed)?;
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
        let swapchains =
            EyeSwapchains::create(&gpu, &session, size, extensions.khr_composition_layer_depth, options.layout)
                .map_err(Unavailable::Failed)?;
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
            running: false,
            exit_requested: false,
        };
        let headset = OpenXrHeadset {
            gpu: gpu.clone(),
            options,
            xr: Some(xr),
            runtime,
            system: system_name,
            recommended,
            size,
            depth,
            swapchain_text,
            phases: Vec::new(),
            stats: OpenXrStats::default(),
            counters: FrameCounters::default(),
            latencies_ms: Vec::new(),
            next_index: 0,
            pending: None,
            last_views: None,
            opened: Instant::now(),
            ever_ready: false,
            exited: false,
            lost: None,
            fallback: None,
        };
        Ok((headset, gpu))
    }

    /// The runtime's name and version.
    pub fn runtime(&self) -> &str {
        &self.runtime
    }

    /// The session states seen so far, in order.
    pub fn phases(&self) -> &[SessionPhase] {
        &self.phases
    }

    pub fn stats(&self) -> OpenXrStats {
        self.stats
    }

    /// Why the session was lost, if it was (the headset then runs the simulated one).
    pub fn lost(&self) -> Option<&str> {
        self.lost.as_deref()
    }

    /// Whether frames carry depth (the runtime has XR_KHR_composition_layer_depth and a
    /// depth format vrao can fill).
    pub fn submits_depth(&self) -> bool {
        self.depth
    }

    /// The swapchains: size, layout and formats.
    pub fn swapchains(&self) -> &str {
        &self.swapchain_text
    }

    /// Asks the runtime to end the session (xrRequestExitSession): the following
    /// `wait_frame` calls walk STOPPING → xrEndSession → EXITING and return `None`.
    /// Before READY, the request is made as soon as the session begins.
    pub fn request_exit(&mut self) -> Result<()> {
        self.ask_exit().map_err(Error::Gpu)
    }

    fn ask_exit(&mut self) -> std::result::Result<(), String> {
        let Some(xr) = self.xr.as_mut() else { return Ok(()) };
        if xr.exit_requested {
            return Ok(());
        }
        if xr.running {
            xr.session.request_exit().map_err(|e| format!("xrRequestExitSession: {e}"))?;
        }
        xr.exit_requested = true;
        self.note("exit requested");
        Ok(())
    }

    /// Tears the session down the way a lost one is (LOSS_PENDING): the headset goes on
    /// with the options' simulated fall back, or ends. Runtimes cannot be made to lose a
    /// session on demand, so tests use this to exercise that path.
    pub fn simulate_loss(&mut self, why: &str) {
        if self.xr.is_some() && self.fallback.is_none() {
            self.lose(why.to_string());
        }
    }

    fn note(&self, what: &str) {
        log::info!("OpenXR: {what}");
        if self.options.report {
            eprintln!("openxr: {what}");
        }
    }

    /// Handles the queued events: session state changes (beginning and ending the
    /// session as the states ask) and a pending instance loss.
    fn poll_events(&mut self) -> std::result::Result<(), String> {
        let Some(xr) = self.xr.as_ref() else { return Ok(()) };
        let mut states = Vec::new();
        let mut loss = None;
        let mut buffer = xr::EventDataBuffer::new();
        while let Some(event) = xr.instance.poll_event(&mut buffer).map_err(|e| format!("xrPollEvent: {e}"))? {
            match event {
                xr::Event::SessionStateChanged(change) => states.push(change.state()),
                xr::Event::InstanceLossPending(_) => loss = Some("the runtime is going away (instance loss pending)"),
                xr::Event::EventsLost(lost) => log::warn!("OpenXR: {} events lost", lost.lost_event_count()),
                _ => {}
            }
        }
        for state in states {
            self.on_state(state)?;
        }
        match loss {
            Some(why) => Err(why.into()),
            None => Ok(()),
        }
    }

    fn on_state(&mut self, state: xr::SessionState) -> std::result::Result<(), String> {
        let phase = match state {
            xr::SessionState::IDLE => SessionPhase::Idle,
            xr::SessionState::READY => SessionPhase::Ready,
            xr::SessionState::SYNCHRONIZED => SessionPhase::Synchronized,
            xr::SessionState::VISIBLE => SessionPhase::Visible,
            xr::SessionState::FOCUSED => SessionPhase::Focused,
            xr::SessionState::STOPPING => SessionPhase::Stopping,
            xr::SessionState::LOSS_PENDING => SessionPhase::LossPending,
            xr::SessionState::EXITING => SessionPhase::Exiting,
            other => {
                log::warn!("OpenXR: unknown session state {other:?}");
                return Ok(());
            }
        };
        self.phases.push(phase);
        self.note(&format!("session {phase}"));
        let xr = self.xr.as_mut().expect("events come from a live session");
        match phase {
            SessionPhase::Ready => {
                xr.session.begin(VIEW_TYPE).map_err(|e| format!("xrBeginSession: {e}"))?;
                xr.running = true;
                self.ever_ready = true;
                if xr.exit_requested {
                    // Asked to end before the session began: ask the runtime now.
                    xr.session.request_exit().map_err(|e| format!("xrRequestExitSession: {e}"))?;
                }
            }
            SessionPhase::Stopping => {
                xr.session.end().map_err(|e| format!("xrEndSession: {e}"))?;
                xr.running = false;
            }
            SessionPhase::Exiting => self.exited = true,
            SessionPhase::LossPending => return Err("the session is being lost (LOSS_PENDING)".into()),
            _ => {}
        }
        Ok(())
    }

    /// One turn of the session: events, then a frame if the session runs. `Ok(None)`
    /// when there is no frame for the application this turn.
    fn turn(&mut self) -> std::result::Result<Option<FrameRequest>, String> {
        self.poll_events()?;
        if self.exited {
            return Ok(None);
        }
        let xr = self.xr.as_mut().expect("turn needs a session");
        if !xr.running {
            if !self.ever_ready && self.opened.elapsed() > READY_TIMEOUT {
                return Err(format!("the session did not become READY within {} s", READY_TIMEOUT.as_secs()));
            }
            std::thread::sleep(IDLE_POLL);
            return Ok(None);
        }
        let state = xr.frame_waiter.wait().map_err(|e| format!("xrWaitFrame: {e}"))?;
        xr.frame_stream.begin().map_err(|e| format!("xrBeginFrame: {e}"))?;
        if xr.exit_requested {
            // Until the runtime says STOPPING, the session still runs frames; they show
            // nothing new.
            end_frame(xr, state.predicted_display_time, None).map_err(|e| format!("xrEndFrame: {e}"))?;
            self.stats.empty_frames += 1;
            return Ok(None);
        }
        let located = xr.session.locate_views(VIEW_TYPE, state.predicted_display_time, &xr.space);
        let sampled_at = if xr.clock { xr.instance.now().ok() } else { None };
        let (flags, views) = located.map_err(|e| format!("xrLocateViews: {e}"))?;
        let valid = flags.contains(xr::ViewStateFlags::ORIENTATION_VALID) && views.len() == 2;
        let views = if valid {
            let views = [views[0], views[1]];
            self.last_views = Some(views);
            views
        } else {
            // Tracking lost: keep the last known views (or look straight ahead).
            self.last_views.unwrap_or([default_view(-1.0), default_view(1.0)])
        };
        if let Some(now) = sampled_at {
            let ms = (state.predicted_display_time.as_nanos() - now.as_nanos()) as f64 / 1e6;
            if self.latencies_ms.len() == LATENCY_SAMPLES {
                self.latencies_ms.remove(0);
            }
            self.latencies_ms.push(ms);
        }
        let index = self.next_index;
        self.next_index += 1;
        self.stats.frames += 1;
        if !state.should_render {
            self.stats.not_rendered += 1;
        }
        self.pending = Some(Pending { index, display_time: state.predicted_display_time, views });
        Ok(Some(FrameRequest {
            index,
            display_time: state.predicted_display_time.as_nanos() as f64 / 1e9,
            eyes: self.eye_pair(&views),
            size: self.recommended_size(),
            should_render: state.should_render,
        }))
    }

    /// The views in vrao's world: the LOCAL space placed at the options' origin.
    fn eye_pair(&self, views: &[xr::View; 2]) -> EyePair {
        let origin = self.options.origin;
        let eye = |side: EyeSide, view: &xr::View| {
            let local = pose_from_xr(&view.pose);
            let pose = HeadPose {
                position: origin.position + origin.orientation * local.position,
                orientation: (origin.orientation * local.orientation).normalize(),
            };
            Eye { side, pose, fov: fov_from_xr(&view.fov) }
        };
        EyePair { eyes: [eye(EyeSide::Left, &views[0]), eye(EyeSide::Right, &views[1])], near: self.options.near }
    }

    /// Ends the session's frame with the projection layer for `frame`.
    fn present(&mut self, pending: &Pending, frame: &SubmittedFrame) -> std::result::Result<(), String> {
        let near = frame.near;
        let xr = self.xr.as_mut().expect("present needs a session");
        if !xr.running {
            return Ok(());
        }
        let sub_images = match xr.swapchains.fill(&self.gpu, frame.color, frame.depth) {
            Ok(sub_images) => sub_images,
            Err(FillError::Gpu(e)) => {
                // A GPU error in vrao's own copy: end the frame empty, report the error.
                end_frame(xr, pending.display_time, None).map_err(|e| format!("xrEndFrame: {e}"))?;
                return Err(format!("copying the eyes into the swapchains: {e}"));
            }
            Err(e @ FillError::Xr(_)) => return Err(e.to_string()),
        };
        let layer = Layer { views: pending.views, sub_images, near };
        end_frame(xr, pending.display_time, Some(&layer)).map_err(|e| format!("xrEndFrame: {e}"))?;
        self.stats.layers += 1;
        if xr.swapchains.has_depth() {
            self.stats.layers_with_depth += 1;
        }
        self.counters.presented += 1;
        Ok(())
    }

    /// Tears the session down after a loss or failure and continues on the simulated
    /// headset when the options give one.
    fn lose(&mut self, why: String) {
        self.teardown();
        let remaining = self.options.frames.map(|n| n.saturating_sub(self.next_index));
        let message = match self.options.fallback.clone() {
            Some(mut simulated) if remaining != Some(0) => {
                let (width, height) = self.recommended_size();
                simulated.profile.width = width;
                simulated.profile.height = height;
                simulated.frames = remaining;
                match SimulatedHeadset::new(simulated) {
                    Ok(headset) => {
                        let text = format!("OpenXR session lost ({why}): continuing on the {}", headset.describe());
                        self.fallback = Some(headset);
                        text
                    }
                    Err(e) => format!("OpenXR session lost ({why}); the simulated headset failed too ({e})"),
                }
            }
            _ => format!("OpenXR session lost ({why}): the run ends"),
        };
        self.lost = Some(why);
        // Always said, whatever `report` is: the user must know the headset went away.
        log::warn!("{message}");
        eprintln!("headset: {message}");
    }

    /// Destroys the session: waits for the GPU, destroys the wgpu side of the swapchain
    /// images, then the swapchains, space, session and instance.
    fn teardown(&mut self) {
        self.pending = None;
        if let Some(mut xr) = self.xr.take() {
            if let Err(e) = self.gpu.wait_idle() {
                log::warn!("OpenXR teardown: {e}");
            }
            xr.swapchains.destroy_textures();
            drop(xr);
        }
    }

    /// Ends the session cleanly: closes an open frame, requests exit and runs empty
    /// frames until EXITING (at most 5 s). A session that is not running has nothing to
    /// walk and is only torn down.
    fn finish(&mut self) -> std::result::Result<(), String> {
        if let (Some(pending), Some(xr)) = (self.pending.take(), self.xr.as_mut()) {
            end_frame(xr, pending.display_time, None).map_err(|e| format!("xrEndFrame: {e}"))?;
            self.stats.empty_frames += 1;
        }
        let Some(xr) = self.xr.as_ref() else { return Ok(()) };
        if self.exited || !(xr.running || xr.exit_requested && self.ever_ready) {
            return Ok(());
        }
        self.ask_exit()?;
        let deadline = Instant::now() + Duration::from_secs(5);
        while !self.exited {
            if Instant::now() > deadline {
                return Err("the runtime did not end the session within 5 s".into());
            }
            self.turn()?;
        }
        Ok(())
    }
}

/// The projection layer of one frame.
struct Layer {
    views: [xr::View; 2],
    sub_images: [SubImage; 2],
    near: f64,
}

/// xrEndFrame with the projection layer (and per-view depth when the swapchains have
/// it), or with no layer.
fn end_frame(xr: &mut Xr, display_time: xr::Time, layer: Option<&Layer>) -> std::result::Result<(), xr::sys::Result> {
    use xr::sys;
    let rect = |s: &SubImage| sys::Rect2Di {
        offset: sys::Offset2Di { x: 0, y: 0 },
        extent: sys::Extent2Di { width: s.width as i32, height: s.height as i32 },
    };
    let mut depth_infos = [None, None];
    let mut projection_views = Vec::with_capacity(2);
    let projection;
    let mut layers: Vec<*const sys::CompositionLayerBaseHeader> = Vec::new();
    if let Some(layer) = layer {
        for (eye, depth_info) in depth_infos.iter_mut().enumerate() {
            let s = &layer.sub_images[eye];
            if let Some(depth) = xr.swapchains.depth_swapchain(s.swapchain) {
                // Reversed-Z with an infinite far plane: window depth 0 is infinitely
                // far and 1 is the near plane. The extension's nearZ and farZ are the
                // distances of minDepth and maxDepth ("a nearZ greater than farZ means
                // reversed depth", "nearZ can be infinite"), so minDepth 0 ↔ nearZ = +∞
                // and maxDepth 1 ↔ farZ = the near plane.
                *depth_info = Some(sys::CompositionLayerDepthInfoKHR {
                    ty: sys::CompositionLayerDepthInfoKHR::TYPE,
                    next: std::ptr::null(),
                    sub_image: sys::SwapchainSubImage {
                        swapchain: depth.as_raw(),
                        image_rect: rect(s),
                        image_array_index: s.array_index,
                    },
                    min_depth: 0.0,
                    max_depth: 1.0,
                    near_z: f32::INFINITY,
                    far_z: layer.near as f32,
                });
            }
        }
        for (eye, view) in layer.views.iter().enumerate() {
            let s = &layer.sub_images[eye];
            projection_views.push(sys::CompositionLayerProjectionView {
                ty: sys::CompositionLayerProjectionView::TYPE,
                next: depth_infos[eye].as_ref().map_or(std::ptr::null(), |d| d as *const _ as *const _),
                pose: view.pose,
                fov: view.fov,
                sub_image: sys::SwapchainSubImage {
                    swapchain: xr.swapchains.color_swapchain(s.swapchain).as_raw(),
                    image_rect: rect(s),
                    image_array_index: s.array_index,
                },
            });
        }
        projection = sys::CompositionLayerProjection {
            ty: sys::CompositionLayerProjection::TYPE,
            next: std::ptr::null(),
            layer_flags: sys::CompositionLayerFlags::EMPTY,
            space: xr.space.as_raw(),
            view_count: projection_views.len() as u32,
            views: projection_views.as_ptr(),
        };
        layers.push(&projection as *const _ as *const sys::CompositionLayerBaseHeader);
    }
    let info = sys::FrameEndInfo {
        ty: sys::FrameEndInfo::TYPE,
        next: std::ptr::null(),
        display_time,
        environment_blend_mode: xr.blend_mode,
        layer_count: layers.len() as u32,
        layers: if layers.is_empty() { std::ptr::null() } else { layers.as_ptr() },
    };
    // SAFETY: every pointer in `info` (layers, views, depth infos) points at locals that
    // live until the call returns; the frame was begun with xrBeginFrame.
    let result = unsafe { (xr.instance.fp().end_frame)(xr.session.as_raw(), &info) };
    if result.into_raw() < 0 {
        Err(result)
    } else {
        Ok(())
    }
}

fn pose_from_xr(pose: &xr::Posef) -> HeadPose {
    let o = pose.orientation;
    let p = pose.position;
    HeadPose {
        position: DVec3::new(p.x as f64, p.y as f64, p.z as f64),
        orientation: DQuat::from_xyzw(o.x as f64, o.y as f64, o.z as f64, o.w as f64),
    }
    .sanitized()
}

/// OpenXR's XrFovf and vrao's `Fov` are the same four angles with the same signs (left
/// and down negative).
fn fov_from_xr(fov: &xr::Fovf) -> Fov {
    Fov { left: fov.angle_left, right: fov.angle_right, up: fov.angle_up, down: fov.angle_down }
}

/// A view before tracking: 32 mm to the side, 45° each way.
fn default_view(side: f32) -> xr::View {
    let a = std::f32::consts::FRAC_PI_4;
    xr::View {
        pose: xr::Posef {
            orientation: xr::Quaternionf::IDENTITY,
            position: xr::Vector3f { x: side * 0.032, y: 0.0, z: 0.0 },
        },
        fov: xr::Fovf { angle_left: -a, angle_right: a, angle_up: a, angle_down: -a },
    }
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

impl Headset for OpenXrHeadset {
    fn describe(&self) -> String {
        let base = format!(
            "OpenXR headset ({} on {}: {}; recommended {}x{}; LOCAL space; reprojection is the runtime's and not \
             counted by vrao)",
            self.system, self.runtime, self.swapchain_text, self.recommended.0, self.recommended.1
        );
        match (&self.fallback, &self.lost) {
            (Some(simulated), Some(why)) => {
                format!("{} after the OpenXR session was lost ({why}); before that: {base}", simulated.describe())
            }
            _ => base,
        }
    }

    fn recommended_size(&self) -> (u32, u32) {
        match &self.fallback {
            Some(simulated) => simulated.recommended_size(),
            None => self.size,
        }
    }

    fn wait_frame(&mut self, gpu: &Gpu) -> Result<Option<FrameRequest>> {
        if let Some(simulated) = self.fallback.as_mut() {
            return simulated.wait_frame(gpu);
        }
        if self.xr.is_none() || self.exited {
            return Ok(None);
        }
        if let Some(pending) = self.pending.take() {
            // The application skipped submit: close the frame it left open.
            let xr = self.xr.as_mut().expect("checked above");
            if let Err(e) = end_frame(xr, pending.display_time, None) {
                self.lose(format!("xrEndFrame: {e}"));
                return self.wait_frame(gpu);
            }
            self.stats.empty_frames += 1;
        }
        if self.options.frames.is_some_and(|n| self.next_index >= n) {
            if let Err(why) = self.ask_exit() {
                self.lose(why);
                return self.wait_frame(gpu);
            }
        }
        loop {
            match self.turn() {
                Ok(Some(request)) => return Ok(Some(request)),
                Ok(None) if self.exited => {
                    self.teardown();
                    return Ok(None);
                }
                Ok(None) => {}
                Err(why) => {
                    self.lose(why);
                    return self.wait_frame(gpu);
                }
            }
        }
    }

    fn submit(&mut self, gpu: &Gpu, request: &FrameRequest, frame: Option<SubmittedFrame>) -> Result<()> {
        if let Some(simulated) = self.fallback.as_mut() {
            return simulated.submit(gpu, request, frame);
        }
        if frame.is_some() {
            self.counters.submitted += 1;
        }
        let Some(pending) = self.pending.take() else {
            // The session went away since wait_frame (nothing to end).
            return Ok(());
        };
        if pending.index != request.index {
            return Err(Error::Gpu(format!(
                "submit for frame {} while OpenXR frame {} is open",
                request.index, pending.index
            )));
        }
        let outcome = match frame {
            Some(frame) if request.should_render => self.present(&pending, &frame),
            _ => {
                let xr = self.xr.as_mut().expect("a pending frame has a session");
                self.stats.empty_frames += 1;
                end_frame(xr, pending.display_time, None).map_err(|e| format!("xrEndFrame: {e}"))
            }
        };
        if let Err(why) = outcome {
            self.lose(why);
        }
        Ok(())
    }

    fn counters(&self) -> FrameCounters {
        let mut counters = self.counters;
        let mut sorted = self.latencies_ms.clone();
        sorted.sort_by(f64::total_cmp);
        counters.latency_median_ms = percentile(&sorted, 0.5);
        counters.latency_p95_ms = percentile(&sorted, 0.95);
        if let Some(simulated) = &self.fallback {
            let after = simulated.counters();
            counters.presented += after.presented;
            counters.reprojected += after.reprojected;
            counters.dropped += after.dropped;
            counters.submitted += after.submitted;
        }
        counters
    }

    fn end(&mut self, gpu: &Gpu) -> Result<()> {
        if let Some(simulated) = self.fallback.as_mut() {
            return simulated.end(gpu);
        }
        let outcome = self.finish();
        self.teardown();
        if let Err(why) = outcome {
            log::warn!("OpenXR: ending the session: {why}");
        }
        Ok(())
    }
}

impl Drop for OpenXrHeadset {
    fn drop(&mut self) {
        self.teardown();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xr_fov_keeps_its_signs() {
        let fov = fov_from_xr(&xr::Fovf { angle_left: -0.8, angle_right: 0.7, angle_up: 0.9, angle_down: -0.85 });
        assert_eq!((fov.left, fov.right, fov.up, fov.down), (-0.8, 0.7, 0.9, -0.85));
        assert!(fov.validate().is_ok());
    }

    #[test]
    fn xr_pose_becomes_a_normalised_head_pose() {
        let pose = xr::Posef {
            orientation: xr::Quaternionf { x: 0.0, y: 2.0, z: 0.0, w: 0.0 },
            position: xr::Vector3f { x: 1.0, y: 1.5, z: -2.0 },
        };
        let p = pose_from_xr(&pose);
        assert_eq!(p.position, DVec3::new(1.0, 1.5, -2.0));
        // 180° about +Y: looking down +Z.
        assert!((p.orientation * -DVec3::Z - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn percentiles_of_latency_samples() {
        let sorted = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile(&sorted, 0.5), 3.0);
        assert_eq!(percentile(&sorted, 0.95), 5.0);
        assert_eq!(percentile(&[], 0.5), 0.0);
    }
}
