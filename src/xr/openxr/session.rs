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

use super::mask::SessionMask;
use super::state::{Action, Event, FrameBudget, SessionMachine, Turn};
use super::swapchain::{EyeSwapchains, FillError, SubImage};
use super::{
    application_info, load_entry, vulkan, InstanceSlot, OpenXrOptions, OpenXrReport, RuntimeFailure, SessionPhase,
    Unavailable,
};
use crate::error::{Error, Result};
use crate::xr::simulated::SimulatedHeadset;
use crate::xr::{DisplayRate, FrameCounters, FrameRequest, Headset, SubmittedFrame};
use glam::{DQuat, DVec3, Quat, Vec3};
use layer::{end_frame, Layer};
use openxr as xr;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracking::{fov_from_xr, pose_from_xr, Tracking};
use vrao_ao::plug::Gpu;
use vrao_ao::{Eye, EyePair, EyeSide, Fov, HeadPose};

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
    /// Refreshes of the display the runtime skipped between frames it handed out: each
    /// gap between successive predicted display times beyond one refresh of the display
    /// ([`DisplayRate`]: the reported refresh rate, else the shortest predicted period),
    /// rounded to whole refreshes. A missed frame of the application, as far as OpenXR
    /// shows it; the compositor's own late or dropped frames are not visible.
    pub missed_display_periods: u64,
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
    /// Whether the runtime said to render this frame (shouldRender).
    should_render: bool,
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
    /// The display's refresh period (the budget) and the refreshes missed between frames.
    display: DisplayRate,
    /// The runtime's latest predicted display period (ms), 0 before the first frame.
    display_period_ms: f64,
    /// XR_FB_display_refresh_rate: the rates offered and the latest one reported.
    refresh_rates_hz: Vec<f32>,
    refresh_hz: Option<f32>,
    /// The lens's visibility mask: the runtime's (XR_KHR_visibility_mask), following its
    /// change events, else Monado's default from the views' fields of view.
    mask: SessionMask,
}

fn failed(what: &str) -> impl Fn(xr::sys::Result) -> Unavailable + '_ {
    move |e| Unavailable::Failed(format!("{what}: {e}"))
}

impl OpenXrHeadset {
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
            not_rendered: self.stats.not_rendered,
            missed_display_periods: self.stats.missed_display_periods,
            display_period_ms: self.display_period_ms,
            refresh_period_ms: self.display.period_ms(),
            interrupted_in: self.machine.interrupted_in(),
            display_refresh_rates_hz: self.refresh_rates_hz.clone(),
            display_refresh_rate_hz: self.refresh_hz,
            loss_reason: self.machine.loss_reason().map(str::to_string),
            ending: self.machine.ending().map(str::to_string),
            fell_back: self.fallback.is_some(),
            visibility_mask_from_runtime: self.mask.from_the_runtime(),
            visibility_mask_changes: self.mask.changes(),
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

    /// Feeds the caller's interrupt (Ctrl-C) to the machine the first time it is seen,
    /// in whatever state the session is: checked on every turn of the wait loops, so an
    /// interrupt before READY or while the runtime has the session stopped ends the run
    /// within one poll, not after the machine's timeouts.
    fn check_interrupt(&mut self) {
        let set = self.options.interrupt.as_ref().is_some_and(|flag| flag.load(Ordering::Relaxed));
        if set && self.machine.interrupted_in().is_none() && !self.machine.is_over() {
            let state = self.machine.states().last().map_or("before the first session state", |p| p.name());
            self.note(&format!("interrupted in {state}: ending the session"));
            self.feed(Event::Interrupted);
        }
    }

    /// A session event: at the info level when the options ask for reports, debug otherwise.
    fn note(&self, what: &str) {
        let level = if self.options.report { log::Level::Info } else { log::Level::Debug };
        log::log!(level, "OpenXR: {what}");
    }

    /// Feeds the state machine and makes the runtime calls it answers. A failing call
    /// is fed back, which settles the machine's verdict.
    fn feed(&mut self, event: Event) {
        let at = self.opened.elapsed();
        for action in self.machine.feed(event, at) {
            if let Err(why) = self.execute(action) {
                self.machine.feed(Event::Failed(why.0), at);
                return;
            }
        }
    }

    fn execute(&mut self, action: Action) -> std::result::Result<(), RuntimeFailure> {
        let Some(xr) = self.xr.as_ref() else { return Ok(()) };
        let (call, result) = match action {
            Action::BeginSession => ("xrBeginSession", xr.session.begin(VIEW_TYPE).map(drop)),
            Action::EndSession => ("xrEndSession", xr.session.end().map(drop)),
            Action::RequestExit => ("xrRequestExitSession", xr.session.request_exit()),
        };
        result.map_err(|e| RuntimeFailure(super::xr_call_failed(call, e)))
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
    /// instance loss; a view's changed visibility mask is read again.
    fn poll_events(&mut self) {
        let Some(xr) = self.xr.as_ref() else { return };
        let mut events = Vec::new();
        let mut refresh_changes = Vec::new();
        let mut mask_changes = Vec::new();
        let mut buffer = xr::EventDataBuffer::new();
        loop {
            match xr.instance.poll_event(&mut buffer) {
                Ok(Some(xr::Event::SessionStateChanged(change))) => match phase_of(change.state()) {
                    Some(phase) => events.push(Event::State(phase)),
                    None => log::warn!("OpenXR: unknown session state {:?}", change.state()),
                },
                Ok(Some(xr::Event::InstanceLossPending(_))) => events.push(Event::InstanceLossPending),
                Ok(Some(xr::Event::DisplayRefreshRateChangedFB(change))) => {
                    // The budget follows the predicted display period anyway; this says why.
                    let (from, to) = (change.from_display_refresh_rate(), change.to_display_refresh_rate());
                    refresh_changes.push((from, to));
                }
                Ok(Some(xr::Event::VisibilityMaskChangedKHR(change))) => {
                    mask_changes.push((change.view_configuration_type() == VIEW_TYPE, change.view_index()));
                }
                Ok(Some(xr::Event::EventsLost(lost))) => {
                    log::warn!("OpenXR: {} events lost", lost.lost_event_count())
                }
                Ok(Some(_)) => {}
                Ok(None) => break,
                Err(e) => {
                    events.push(Event::Failed(super::xr_call_failed("xrPollEvent", e)));
                    break;
                }
            }
        }
        // Read after the queue is drained: the event buffer is reused by each poll.
        let mask_lines: Vec<String> = mask_changes
            .into_iter()
            .map(|(ours, view)| self.mask.changed(ours, view, || mask::read_view(&xr.session, view)))
            .collect();
        for line in mask_lines {
            self.note(&line);
        }
        for (from, to) in refresh_changes {
            self.note(&format!("display refresh rate {from} Hz -> {to} Hz"));
            self.refresh_hz = Some(to);
            self.display.set_reported_hz(Some(to));
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
            Err(e) => self.feed(Event::Failed(super::xr_call_failed("xrEndFrame", e))),
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
        let state = xr.frame_waiter.wait().map_err(|e| super::xr_call_failed("xrWaitFrame", e))?;
        xr.frame_stream.begin().map_err(|e| super::xr_call_failed("xrBeginFrame", e))?;
        let period_ns = state.predicted_display_period.as_nanos();
        if period_ns > 0 {
            self.display_period_ms = period_ns as f64 / 1e6;
        }
        // Missed refreshes of the display, not of the period the runtime predicts: that
        // one stretches when frames are late (Monado: 100 ms on a 50 ms display).
        self.stats.missed_display_periods += self.display.frame(state.predicted_display_time.as_nanos(), period_ns);
        if !render {
            // Leaving: until the runtime says STOPPING the session still runs frames;
            // they show nothing new.
            end_frame(xr, state.predicted_display_time, None).map_err(|e| super::xr_call_failed("xrEndFrame", e))?;
            self.stats.empty_frames += 1;
            return Ok(None);
        }
        let located = xr.session.locate_views(VIEW_TYPE, state.predicted_display_time, &xr.space);
        let sampled_at = if xr.clock { xr.instance.now().ok() } else { None };
        let (flags, views) = located.map_err(|e| super::xr_call_failed("xrLocateViews", e))?;
        let (views, warning) = self.tracking.merge(flags, &views);
        if let Some(warning) = warning {
            log::warn!("OpenXR: {warning}");
        }
        // Without XR_KHR_visibility_mask: Monado's default mask for the rendered views.
        if self.mask.follow_fov([fov_from_xr(&views[0].fov), fov_from_xr(&views[1].fov)]) {
            log::debug!("OpenXR: visibility mask from the views' fields of view");
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
        self.pending = Some(Pending {
            index,
            should_render: state.should_render,
            display_time: state.predicted_display_time,
            views,
        });
        Ok(Some(FrameRequest {
            index,
            display_time: state.predicted_display_time.as_nanos() as f64 / 1e9,
            // The display's refresh period is the budget (before it is known, the
            // profile's); the predicted period says whether frames were late.
            display_period_ms: (self.display_period_ms > 0.0).then_some(self.display_period_ms),
            refresh_period_ms: self.display.period_ms(),
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
    fn present(&mut self, pending: &Pending, frame: &SubmittedFrame) -> std::result::Result<(), RuntimeFailure> {
        let near = frame.near;
        let Some(xr) = self.xr.as_mut() else { return Ok(()) };
        let sub_images = match xr.swapchains.fill(&self.gpu, frame.color, frame.depth) {
            Ok(sub_images) => sub_images,
            Err(FillError::Gpu(e)) => {
                // A GPU error in vrao's own copy: end the frame empty, report the error.
                end_frame(xr, pending.display_time, None).map_err(|e| super::xr_call_failed("xrEndFrame", e))?;
                return Err(RuntimeFailure(format!("copying the eyes into the swapchains: {e}")));
            }
            Err(e @ FillError::Xr(..)) => return Err(RuntimeFailure(e.to_string())),
        };
        let layer = Layer { views: pending.views, sub_images, near };
        end_frame(xr, pending.display_time, Some(&layer)).map_err(|e| super::xr_call_failed("xrEndFrame", e))?;
        self.stats.layers += 1;
        if xr.swapchains.has_depth() {
            self.stats.layers_with_depth += 1;
        }
        // Not "presented": OpenXR does not say whether the compositor showed the layer.
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
        // A warning whatever `report` is: the user must know the headset went away.
        log::warn!("headset: {message}");
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
            // xr imports only the leaves, so not formats::output::count.
            let frames = self.budget.rendered;
            self.note(&format!("{frames} frame{} rendered: exit requested", if frames == 1 { "" } else { "s" }));
            self.feed(Event::FramesReached);
        }
        loop {
            self.check_interrupt();
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
            return Err(Error::gpu(format!(
                "submit for frame {} while OpenXR frame {} is open",
                request.index, pending.index
            )));
        }
        match frame {
            Some(frame) if pending.should_render => match self.present(&pending, &frame) {
                // A frame counts as rendered once its layer reached the runtime: a frame
                // lost on the way is not (frames rendered = layers submitted).
                Ok(()) => self.budget.submitted(true),
                Err(why) => self.feed(Event::Failed(why.0)),
            },
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
        counters.set_latency(&self.latencies_ms);
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

    fn visibility_mask(&self) -> Option<&vrao_ao::VisibilityMask> {
        match &self.fallback {
            Some(simulated) => simulated.visibility_mask(),
            None => self.mask.mask(),
        }
    }

    fn display_rate_source(&self) -> String {
        match (&self.fallback, self.display.source()) {
            (Some(simulated), _) => format!("{} (after the OpenXR session was lost)", simulated.display_rate_source()),
            (None, Some(source)) => format!("the OpenXR runtime: {source}"),
            (None, None) => {
                let profile = self.options.fallback.as_ref().map(|s| &s.profile);
                let rate = match (profile, self.options.preferred_refresh_hz) {
                    (Some(p), _) => format!("the '{}' profile's {} Hz", p.name, p.refresh_hz),
                    (None, Some(hz)) => format!("the profile's {hz} Hz"),
                    (None, None) => "the profile's rate".into(),
                };
                format!("{rate} (no frame from the runtime yet, and it reports no refresh rate)")
            }
        }
    }

    fn refresh_period_ms(&self) -> Option<f64> {
        match &self.fallback {
            Some(simulated) => simulated.refresh_period_ms(),
            None => self.display.period_ms(),
        }
    }

    fn now(&self) -> Option<f64> {
        match (&self.fallback, &self.xr) {
            (Some(simulated), _) => Headset::now(simulated),
            // The runtime's XrTime, the clock of its predicted display times.
            (None, Some(xr)) if xr.clock => xr.instance.now().ok().map(|t| t.as_nanos() as f64 / 1e9),
            _ => None,
        }
    }

    fn no_clock_reason(&self) -> String {
        match &self.fallback {
            Some(simulated) => simulated.no_clock_reason(),
            None => "the OpenXR runtime offers no XR_KHR_convert_timespec_time to read its clock".into(),
        }
    }

    fn session_state(&self) -> String {
        match (&self.fallback, self.machine.states().last()) {
            (Some(simulated), _) => format!("{} (after the OpenXR session was lost)", simulated.session_state()),
            (None, Some(phase)) => phase.name().to_string(),
            (None, None) => "before the first session state".to_string(),
        }
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

mod layer;
mod mask;
mod open;
#[cfg(test)]
mod tests;
mod tracking;
