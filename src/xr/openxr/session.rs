//! The OpenXR session behind [`OpenXrHeadset`]: instance, system, Vulkan device,
//! swapchains, the frame loop and the session state machine.
//!
//! Frame loop (one frame per `wait_frame` + `submit`): xrWaitFrame → xrBeginFrame →
//! xrLocateViews at the predicted display time (the eye poses and fields of view the
//! application renders with) → the application renders → the swapchains are filled →
//! xrEndFrame with a projection layer (and each view's depth, with
//! XR_KHR_composition_layer_depth), or with no layer when the runtime said not to render.
//!
//! States (XrSessionState) are decided by the pure [`SessionMachine`] (`state.rs`); this
//! file makes the runtime calls it answers: READY → xrBeginSession; SYNCHRONIZED,
//! VISIBLE and FOCUSED run frames (the runtime's shouldRender decides whether anything
//! is drawn); STOPPING → xrEndSession, after which only events are polled; EXITING ends
//! the run (`wait_frame` returns `None`); LOSS_PENDING, a pending instance loss or a
//! failing runtime call tear the session down and, when the options give one, continue
//! on the simulated headset. Reprojection, dropped and late frames are the runtime
//! compositor's business: it does not report them through OpenXR, so vrao's counters
//! only say what was submitted.

use super::state::{Action, Event, FrameBudget, SessionMachine, Turn};
use super::swapchain::{EyeSwapchains, FillError, SubImage};
use super::{
    application_info, load_entry, vulkan, InstanceSlot, OpenXrOptions, OpenXrReport, SessionPhase, Unavailable,
};
use crate::render::error::{Error, Result};
use crate::render::gpu::Gpu;
use crate::render::stereo::{Eye, EyePair, EyeSide, Fov, HeadPose};
use crate::xr::simulated::SimulatedHeadset;
use crate::xr::{FrameCounters, FrameRequest, Headset, SubmittedFrame};
use glam::{DQuat, DVec3, Quat, Vec3};
use openxr as xr;
use std::sync::Arc;
use std::time::{Duration, Instant};

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;
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
    machine: SessionMachine,
    /// Rendered frames, for `--frames`.
    budget: FrameBudget,
    stats: OpenXrStats,
    counters: FrameCounters,
    latencies_ms: Vec<f64>,
    /// The next frame's `FrameRequest::index` (frames handed to the application).
    next_index: u64,
    pending: Option<Pending>,
    tracking: Tracking,
    opened: Instant,
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
        };
        let budget = FrameBudget::new(options.frames);
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
        };
        Ok((headset, gpu))
    }

    /// The runtime's name and version.
    pub fn runtime(&self) -> &str {
        &self.runtime
    }

    /// The session states seen so far, in order (consecutive repeats dropped).
    pub fn phases(&self) -> &[SessionPhase] {
        self.machine.states()
    }

    /// Frame and layer counts beyond the common [`FrameCounters`].
    pub fn stats(&self) -> OpenXrStats {
        self.stats
    }

    /// Why the session was lost, if it was (the headset then runs the simulated one,
    /// unless the run was ending anyway).
    pub fn lost(&self) -> Option<&str> {
        self.machine.loss_reason()
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

    /// What the session did so far.
    pub fn report(&self) -> OpenXrReport {
        OpenXrReport {
            runtime: self.runtime.clone(),
            states_seen: self.machine.states().iter().map(|p| p.name().to_string()).collect(),
            frames_rendered: self.budget.rendered,
            layers_submitted: self.stats.layers,
            depth_layers_submitted: self.stats.layers_with_depth,
            empty_frames: self.stats.empty_frames,
            loss_reason: self.machine.loss_reason().map(str::to_string),
            ending: self.machine.ending().map(str::to_string),
            fell_back: self.fallback.is_some(),
        }
    }

    /// Tears the session down the way a lost one is (LOSS_PENDING): the headset goes on
    /// with the options' simulated fall back, or ends. Runtimes cannot be made to lose a
    /// session on demand, so tests use this to exercise that path.
    pub fn simulate_loss(&mut self, why: &str) {
        if self.xr.is_some() && self.fallback.is_none() {
            self.feed(Event::Failed(why.to_string()));
            self.conclude();
        }
    }

    fn note(&self, what: &str) {
        log::info!("OpenXR: {what}");
        if self.options.report {
            eprintln!("openxr: {what}");
        }
    }

    /// Feeds the state machine and makes the runtime calls it answers. A failing call
    /// is fed back, which settles the machine's verdict.
    fn feed(&mut self, event: Event) {
        let at = self.opened.elapsed();
        for action in self.machine.feed(event, at) {
            if let Err(why) = self.execute(action) {
                self.machine.feed(Event::Failed(why), at);
                return;
            }
        }
    }

    fn execute(&mut self, action: Action) -> std::result::Result<(), String> {
        let Some(xr) = self.xr.as_ref() else { return Ok(()) };
        match action {
            Action::BeginSession => xr.session.begin(VIEW_TYPE).map(drop).map_err(|e| format!("xrBeginSession: {e}")),
            Action::EndSession => xr.session.end().map(drop).map_err(|e| format!("xrEndSession: {e}")),
            Action::RequestExit => xr.session.request_exit().map_err(|e| format!("xrRequestExitSession: {e}")),
        }
    }

    /// Once the machine has its verdict: tears the session down and, after a loss,
    /// continues on the fall back. Returns whether the run was over.
    fn conclude(&mut self) -> bool {
        if !self.machine.is_over() || self.xr.is_none() {
            return self.machine.is_over();
        }
        match self.machine.turn(self.opened.elapsed()) {
            Turn::Lose(why) => self.lose(why),
            _ => {
                if let Some(why) = self.machine.loss_reason() {
                    log::warn!("OpenXR: the session ended after a failure: {why}");
                }
                self.note(&format!("session over ({})", self.machine.ending().unwrap_or("left")));
                self.teardown();
            }
        }
        true
    }

    /// Feeds the queued events to the machine: session state changes and a pending
    /// instance loss.
    fn poll_events(&mut self) {
        let Some(xr) = self.xr.as_ref() else { return };
        let mut events = Vec::new();
        let mut buffer = xr::EventDataBuffer::new();
        loop {
            match xr.instance.poll_event(&mut buffer) {
                Ok(Some(xr::Event::SessionStateChanged(change))) => match phase_of(change.state()) {
                    Some(phase) => events.push(Event::State(phase)),
                    None => log::warn!("OpenXR: unknown session state {:?}", change.state()),
                },
                Ok(Some(xr::Event::InstanceLossPending(_))) => events.push(Event::InstanceLossPending),
                Ok(Some(xr::Event::EventsLost(lost))) => {
                    log::warn!("OpenXR: {} events lost", lost.lost_event_count())
                }
                Ok(Some(_)) => {}
                Ok(None) => break,
                Err(e) => {
                    events.push(Event::Failed(format!("xrPollEvent: {e}")));
                    break;
                }
            }
        }
        for event in events {
            if let Event::State(phase) = &event {
                self.note(&format!("session {phase}"));
            }
            self.feed(event);
        }
    }

    /// Ends an open frame with no layer (a failure goes to the machine).
    fn end_empty(&mut self, display_time: xr::Time) {
        let Some(xr) = self.xr.as_mut() else { return };
        match end_frame(xr, display_time, None) {
            Ok(()) => self.stats.empty_frames += 1,
            Err(e) => self.feed(Event::Failed(format!("xrEndFrame: {e}"))),
        }
    }

    /// One frame of the running session: xrWaitFrame and xrBeginFrame, then the
    /// located views for the application (`render`), or at once an empty xrEndFrame.
    /// A failing call goes to the machine and gives `None`.
    fn frame(&mut self, render: bool) -> Option<FrameRequest> {
        match self.try_frame(render) {
            Ok(request) => request,
            Err(why) => {
                self.feed(Event::Failed(why));
                None
            }
        }
    }

    fn try_frame(&mut self, render: bool) -> std::result::Result<Option<FrameRequest>, String> {
        let xr = self.xr.as_mut().expect("frames need a session");
        let state = xr.frame_waiter.wait().map_err(|e| format!("xrWaitFrame: {e}"))?;
        xr.frame_stream.begin().map_err(|e| format!("xrBeginFrame: {e}"))?;
        if !render {
            // Leaving: until the runtime says STOPPING the session still runs frames;
            // they show nothing new.
            end_frame(xr, state.predicted_display_time, None).map_err(|e| format!("xrEndFrame: {e}"))?;
            self.stats.empty_frames += 1;
            return Ok(None);
        }
        let located = xr.session.locate_views(VIEW_TYPE, state.predicted_display_time, &xr.space);
        let sampled_at = if xr.clock { xr.instance.now().ok() } else { None };
        let (flags, views) = located.map_err(|e| format!("xrLocateViews: {e}"))?;
        let (views, warning) = self.tracking.merge(flags, &views);
        if let Some(warning) = warning {
            log::warn!("OpenXR: {warning}");
            if self.options.report {
                eprintln!("openxr: {warning}");
            }
        }
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
        let Some(xr) = self.xr.as_mut() else { return Ok(()) };
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
    /// headset when the options give one and frames remain.
    fn lose(&mut self, why: String) {
        self.teardown();
        let remaining = self.budget.remaining();
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

    /// Ends the session cleanly: closes an open frame, asks to exit and runs empty
    /// frames until EXITING (the machine bounds the wait). A session that is not running
    /// has nothing to walk and is only left.
    fn finish(&mut self) {
        if self.xr.is_none() {
            return;
        }
        if let Some(pending) = self.pending.take() {
            self.end_empty(pending.display_time);
        }
        self.feed(Event::ExitRequested);
        loop {
            self.poll_events();
            match self.machine.turn(self.opened.elapsed()) {
                Turn::Frame | Turn::EmptyFrame => {
                    self.frame(false);
                }
                Turn::Poll => std::thread::sleep(IDLE_POLL),
                Turn::Leave | Turn::Lose(_) => break,
            }
        }
        if let Some(why) = self.machine.loss_reason() {
            log::warn!("OpenXR: ending the session: {why}");
        }
    }
}

/// The session state an XrSessionState names (`None`: one OpenXR 1.0 does not define).
fn phase_of(state: xr::SessionState) -> Option<SessionPhase> {
    Some(match state {
        xr::SessionState::IDLE => SessionPhase::Idle,
        xr::SessionState::READY => SessionPhase::Ready,
        xr::SessionState::SYNCHRONIZED => SessionPhase::Synchronized,
        xr::SessionState::VISIBLE => SessionPhase::Visible,
        xr::SessionState::FOCUSED => SessionPhase::Focused,
        xr::SessionState::STOPPING => SessionPhase::Stopping,
        xr::SessionState::LOSS_PENDING => SessionPhase::LossPending,
        xr::SessionState::EXITING => SessionPhase::Exiting,
        _ => return None,
    })
}

/// The views frames are rendered with, when tracking is partial or lost too.
#[derive(Default)]
struct Tracking {
    /// The last views with a valid orientation: used whole when orientation is lost.
    last: Option<[xr::View; 2]>,
    /// The last views with a valid position as well: where the head is held while only
    /// orientation is tracked.
    anchor: Option<[xr::View; 2]>,
    /// Within a position-loss episode (warned about at its start only).
    position_lost: bool,
}

impl Tracking {
    /// The views to render with, from what xrLocateViews answered; and a warning when a
    /// position-loss episode begins (not every frame of it).
    fn merge(&mut self, flags: xr::ViewStateFlags, located: &[xr::View]) -> ([xr::View; 2], Option<&'static str>) {
        let orientation = flags.contains(xr::ViewStateFlags::ORIENTATION_VALID) && located.len() == 2;
        // Without POSITION_VALID the located positions are undefined.
        let position = orientation && flags.contains(xr::ViewStateFlags::POSITION_VALID);
        let views = if position {
            self.anchor = Some([located[0], located[1]]);
            [located[0], located[1]]
        } else if orientation {
            orientation_only(&[located[0], located[1]], &self.anchor.unwrap_or(default_views()))
        } else {
            self.last.unwrap_or(default_views())
        };
        if orientation {
            self.last = Some(views);
        }
        let warning = (!position && !self.position_lost).then_some(if orientation {
            "position tracking lost: orientation only, the head held at its last position"
        } else {
            "tracking lost: the last pose is held"
        });
        self.position_lost = !position;
        (views, warning)
    }
}

/// Orientation-only tracking: each located view's orientation and field of view, with
/// the head held where `anchor` (the last views with a valid position) had it. The eyes
/// keep their offsets from the head's centre, turned with the head, so the stereo
/// baseline follows the head.
fn orientation_only(located: &[xr::View; 2], anchor: &[xr::View; 2]) -> [xr::View; 2] {
    let vec = |v: xr::Vector3f| Vec3::new(v.x, v.y, v.z);
    let quat = |q: xr::Quaternionf| Quat::from_xyzw(q.x, q.y, q.z, q.w).normalize();
    let center = (vec(anchor[0].pose.position) + vec(anchor[1].pose.position)) * 0.5;
    std::array::from_fn(|i| {
        let offset = quat(anchor[i].pose.orientation).inverse() * (vec(anchor[i].pose.position) - center);
        let p = center + quat(located[i].pose.orientation) * offset;
        xr::View {
            pose: xr::Posef {
                orientation: located[i].pose.orientation,
                position: xr::Vector3f { x: p.x, y: p.y, z: p.z },
            },
            fov: located[i].fov,
        }
    })
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
                // reversed depth"), so minDepth 0 ↔ nearZ = far and maxDepth 1 ↔ farZ =
                // the near plane. nearZ is f32::MAX, not +∞: a runtime linearising depth
                // with ∞ gets NaN (∞/∞, ∞·0), and no depth value tells the two apart.
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
                    near_z: f32::MAX,
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

/// Both views before tracking.
fn default_views() -> [xr::View; 2] {
    [default_view(-1.0), default_view(1.0)]
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
        match (&self.fallback, self.machine.loss_reason()) {
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
        if self.xr.is_none() {
            return Ok(None);
        }
        if let Some(pending) = self.pending.take() {
            // The application skipped submit: close the frame it left open.
            self.end_empty(pending.display_time);
        }
        if self.budget.reached() && !self.machine.exit_wanted() && !self.machine.is_over() {
            self.note(&format!("{} frames rendered: exit requested", self.budget.rendered));
            self.feed(Event::FramesReached);
        }
        loop {
            if self.conclude() {
                // Left (the session is gone) or lost (the fall back, if any, goes on).
                return self.wait_frame(gpu);
            }
            self.poll_events();
            match self.machine.turn(self.opened.elapsed()) {
                Turn::Frame => {
                    if let Some(request) = self.frame(true) {
                        return Ok(Some(request));
                    }
                }
                Turn::EmptyFrame => {
                    self.frame(false);
                }
                // Not running (before READY, or stopped): no xrWaitFrame, which would
                // block or fail; the machine bounds how long this lasts.
                Turn::Poll => std::thread::sleep(IDLE_POLL),
                Turn::Leave | Turn::Lose(_) => {}
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
        match frame {
            Some(frame) if request.should_render => {
                self.budget.submitted(true);
                if let Err(why) = self.present(&pending, &frame) {
                    self.feed(Event::Failed(why));
                }
            }
            _ => {
                self.budget.submitted(false);
                self.end_empty(pending.display_time);
            }
        }
        // A failure: tear down (and fall back) now rather than at the next wait_frame.
        self.conclude();
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

    fn openxr_report(&self) -> Option<OpenXrReport> {
        Some(self.report())
    }

    /// xrRequestExitSession when the session runs (the following `wait_frame` calls
    /// walk STOPPING → xrEndSession → EXITING and return `None`); before READY or while
    /// stopped the next `wait_frame` returns `None` at once. After a loss, the fall
    /// back is asked instead.
    fn request_exit(&mut self) {
        if let Some(simulated) = self.fallback.as_mut() {
            return simulated.request_exit();
        }
        if self.xr.is_some() && !self.machine.exit_wanted() && !self.machine.is_over() {
            self.note("exit requested");
            self.feed(Event::ExitRequested);
        }
    }

    fn end(&mut self, gpu: &Gpu) -> Result<()> {
        if let Some(simulated) = self.fallback.as_mut() {
            return simulated.end(gpu);
        }
        self.finish();
        self.teardown();
        Ok(())
    }
}

impl Drop for OpenXrHeadset {
    fn drop(&mut self) {
        self.teardown();
    }
}

#[cfg(test)]
mod tests;
