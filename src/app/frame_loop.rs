//! The `vrao run` frame loop: a headset (OpenXR when a runtime answers, the simulated one
//! otherwise; [`crate::app::open_headset`]) asks for frames; the renderer draws both
//! eyes; the headset gets colour and depth. The desktop window (`window.rs`) drives the
//! same loop one step per redraw.

use crate::app::completion::CompletionWatcher;
use crate::app::governor::{Governor, Observation};
use crate::app::{BufferView, PassHistory};
use crate::error::{Error, Result};
use crate::xr::{FrameRequest, Headset, SubmittedFrame};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use vrao_ao::plug::{FrameTiming, Gpu, DEPTH};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::renderer::{FrameReport, Renderer, Timing};
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;

/// What one step of the loop did.
pub struct Step {
    /// The frame the headset asked for.
    pub request: FrameRequest,
    /// The renderer's report, or `None` when the headset said not to render this frame.
    pub report: Option<FrameReport>,
}

/// The headset frame loop. Frames are submitted without waiting for the GPU; their GPU
/// times come back later and feed the history, the over-budget count and the governor.
pub struct FrameLoop {
    /// The device the renderer and headset share.
    pub gpu: Arc<Gpu>,
    /// The stereo renderer; the governor changes its AO settings between frames.
    pub renderer: Renderer,
    /// The simulated or OpenXR headset that paces the loop and takes the images.
    pub headset: Box<dyn Headset>,
    /// Recent per-pass GPU times for the panel and the run summary.
    pub history: PassHistory,
    /// Frames rendered (handed to the headset with an image).
    pub frames: u64,
    /// Stop after this many rendered frames.
    pub frame_limit: Option<u64>,
    /// The display's refresh period, which the frame must fit (ms): the headset's latest
    /// ([`FrameRequest::refresh_period_ms`]), never a predicted period the runtime
    /// stretched because frames were late; the profile's until the headset knows it.
    pub budget_ms: f64,
    /// The shortest and longest refresh period seen (ms).
    pub budget_range_ms: (f64, f64),
    /// How often the refresh period changed during the run.
    pub budget_changes: u64,
    /// Frames the headset predicted a display period for that spans more than one
    /// refresh ([`crate::xr::missed_refreshes`]): an OpenXR runtime stretches its period
    /// when frames are late, each one a missed refresh or more.
    pub stretched_frames: u64,
    /// The session state the run was interrupted in (Ctrl-C), once the loop saw it.
    pub interrupted_in: Option<String>,
    /// Whether the headset has given a refresh period yet.
    display_period_seen: bool,
    /// Frames whose GPU time exceeded `budget_ms`, and all frames whose time came back.
    pub over_budget_frames: u64,
    /// Frames whose GPU time has come back (the denominator of `over_budget_frames`).
    pub timed_frames: u64,
    /// Frames whose GPU work finished after their predicted display time on the headset's
    /// clock (when it was seen done, or else at the earliest:
    /// [`crate::xr::earliest_finish`]), of the timed frames the
    /// headset's clock was read for (`clocked_frames`): what the runtime shows late, or
    /// drops, whatever the GPU time against the budget.
    pub late_frames: u64,
    /// Timed frames whose submission was read on the headset's clock (the denominator of
    /// `late_frames`; 0 where the headset has no clock: [`Headset::now`]).
    pub clocked_frames: u64,
    /// The previous timed frame's earliest finish on the headset's clock (s).
    previous_finish: Option<f64>,
    /// Sees each frame's work done, where the headset has a clock to judge it by.
    completion: CompletionWatcher,
    /// Frames seen done and the instant, until their GPU times come back.
    done: VecDeque<(u64, std::time::Instant)>,
    /// Every frame's GPU time and CPU encode time (ms), for the run's medians.
    pub gpu_frame_ms: Vec<f64>,
    /// Every frame's CPU encode time (ms).
    pub cpu_encode_ms: Vec<f64>,
    /// Set (by the caller's Ctrl-C handler, say) to end the session cleanly after the
    /// current frame; the loop only reads it.
    pub exit_requested: Arc<AtomicBool>,
    exit_sent: bool,
    /// On a CPU adapter, every [`SERIAL_EVERY`]-th frame is submitted pass by pass.
    cpu_adapter: bool,
    /// Frames in flight: their number, whether they went pass by pass, and the passes
    /// whose time the governor's AO setting changes (the rest of the frame does not
    /// depend on it), as each frame's plan names them.
    in_flight: VecDeque<InFlight>,
    /// The first frame's display time: the scene's animation plays from there.
    scene_time_origin: Option<f64>,
    /// An AO pass whose span was missing has been reported (once per run).
    missing_span_reported: bool,
    /// Chooses the AO setting from the measured GPU times (`None`: settings fixed).
    pub governor: Option<Governor>,
    /// The buffer the window shows; every frame also produces it (an AO buffer the
    /// composite would otherwise fuse away, such as the upsampled AO, adds its pass).
    pub buffer_view: BufferView,
}

/// What the loop keeps of a submitted frame until its GPU times come back.
struct InFlight {
    frame: u64,
    /// The display's refresh period when the frame was rendered: its GPU time is judged
    /// against it.
    budget_ms: f64,
    /// The display period the headset predicted for the frame (the governor lowers on
    /// one stretched over several refreshes).
    predicted_period_ms: Option<f64>,
    /// The frame's predicted display time and when its work was submitted, both on the
    /// headset's clock (s), and the instant of the submission; `None` without a clock.
    deadline: Option<(f64, f64, std::time::Instant)>,
    serial: bool,
    occlusion_passes: Vec<&'static str>,
}

/// Submitted frames whose plans the loop keeps for their GPU times (far more than are
/// ever in flight).
const KEPT_IN_FLIGHT: usize = 64;

/// On a CPU adapter (lavapipe), timestamps within one submission credit work to the
/// wrong pass, and one submission per pass keeps frames from overlapping (each
/// submission waits for the previous one there). So one frame in this many is
/// submitted pass by pass for the profiler's true per-pass times; the others are
/// submitted whole and stay in flight.
pub const SERIAL_EVERY: u64 = 8;

impl FrameLoop {
    /// A loop rendering `scene` with `settings` at the headset's recommended size.
    pub fn new(gpu: Arc<Gpu>, scene: &Scene, settings: &Settings, headset: Box<dyn Headset>) -> Result<FrameLoop> {
        let renderer = Self::renderer_for(&gpu, scene, settings, headset.as_ref())?;
        Ok(Self::with_renderer(gpu, renderer, headset))
    }

    /// The renderer a loop for `headset` draws with: `settings` at its recommended size.
    pub fn renderer_for(gpu: &Arc<Gpu>, scene: &Scene, settings: &Settings, headset: &dyn Headset) -> Result<Renderer> {
        let mut settings = settings.clone();
        (settings.profile.width, settings.profile.height) = headset.recommended_size();
        Ok(Renderer::new(gpu.clone(), scene, &settings)?)
    }

    /// A loop drawing with `renderer` (made by [`FrameLoop::renderer_for`]) for `headset`.
    pub fn with_renderer(gpu: Arc<Gpu>, renderer: Renderer, headset: Box<dyn Headset>) -> FrameLoop {
        let settings = renderer.settings().clone();
        // A rate the headset already knows (an OpenXR runtime's reported refresh rate)
        // is the budget from the start; otherwise the profile's until the first frame.
        let budget_ms = headset.refresh_period_ms().filter(|ms| ms.is_finite() && *ms > 0.0);
        let display_period_seen = budget_ms.is_some();
        let budget_ms = budget_ms.unwrap_or(settings.profile.budget_ms());
        let cpu_adapter = gpu.info.device_type == wgpu::DeviceType::Cpu;
        let completion = CompletionWatcher::new(gpu.device.clone());
        FrameLoop {
            cpu_adapter,
            in_flight: VecDeque::new(),
            scene_time_origin: None,
            missing_span_reported: false,
            governor: None,
            buffer_view: BufferView::Eyes,
            gpu,
            renderer,
            headset,
            history: PassHistory::new(120),
            frames: 0,
            frame_limit: None,
            budget_ms,
            budget_range_ms: (budget_ms, budget_ms),
            budget_changes: 0,
            stretched_frames: 0,
            interrupted_in: None,
            display_period_seen,
            over_budget_frames: 0,
            timed_frames: 0,
            late_frames: 0,
            clocked_frames: 0,
            previous_finish: None,
            completion,
            done: VecDeque::new(),
            gpu_frame_ms: Vec::new(),
            cpu_encode_ms: Vec::new(),
            exit_requested: Arc::new(AtomicBool::new(false)),
            exit_sent: false,
        }
    }

    /// Whether the loop renders on a CPU adapter (lavapipe), where some frames go to
    /// the GPU pass by pass ([`SERIAL_EVERY`]).
    pub fn cpu_adapter(&self) -> bool {
        self.cpu_adapter
    }

    /// Waits for the headset's next frame, renders it and submits it; `None` when the
    /// session has ended (or the frame limit is reached, or exit was requested).
    pub fn step(&mut self) -> Result<Option<Step>> {
        if self.frame_limit.is_some_and(|n| self.frames >= n) {
            return Ok(None);
        }
        // An interrupt asks the headset to end the session; OpenXR then walks the session
        // through STOPPING to EXITING over the next calls.
        if self.exit_requested.load(Ordering::Relaxed) && !self.exit_sent {
            self.exit_sent = true;
            self.interrupted_in = Some(self.headset.session_state());
            self.headset.request_exit();
        }
        let Some(request) = self.headset.wait_frame(&self.gpu)? else { return Ok(None) };
        if let Some(refresh_ms) = request.refresh_period_ms.or(request.display_period_ms) {
            self.follow_display_period(refresh_ms);
        }
        if let Some(predicted_ms) = request.display_period_ms {
            if crate::xr::missed_refreshes(predicted_ms, self.budget_ms) > 0 {
                self.stretched_frames += 1;
            }
        }
        if !request.should_render {
            self.headset.submit(&self.gpu, &request, None)?;
            return Ok(Some(Step { request, report: None }));
        }
        let serial = self.cpu_adapter && self.renderer.frame_index().is_multiple_of(SERIAL_EVERY);
        self.renderer.set_timing(if serial { Timing::Serial } else { Timing::Pipelined });
        let report = self.render(&request)?;
        // The frame's work is on the GPU's queue from here (submitted, not waited for).
        let submitted_at = self.headset.now().filter(|t| t.is_finite());
        let submitted_instant = std::time::Instant::now();
        let color = self.renderer.target(COLOR).ok_or_else(|| Error::gpu("no eye colour"))?;
        let depth = self.renderer.target(DEPTH).ok_or_else(|| Error::gpu("no eye depth"))?;
        let frame = SubmittedFrame { color, depth, eyes: &request.eyes, near: request.eyes.near };
        self.headset.submit(&self.gpu, &request, Some(frame))?;
        // The frame's own submission (the headset's copy of the eyes is in it): an empty
        // one of ours would, on lavapipe, block until the frame is done and keep a second
        // frame from ever being in flight.
        if let (Some(_), Some(last)) = (submitted_at, self.renderer.last_submission()) {
            self.completion.watch(report.frame, last.clone());
        }
        self.frames += 1;
        self.cpu_encode_ms.push(report.cpu_encode_ms);
        self.history.push_cpu_encode(report.cpu_encode_ms);
        // Times come back a few frames late, or never without timestamp queries: keep
        // what a late timing could still need, not every frame of the run.
        if self.in_flight.len() == KEPT_IN_FLIGHT {
            self.in_flight.pop_front();
        }
        self.in_flight.push_back(InFlight {
            frame: report.frame,
            budget_ms: self.budget_ms,
            predicted_period_ms: request.display_period_ms,
            deadline: submitted_at.map(|at| (request.display_time, at, submitted_instant)),
            serial,
            occlusion_passes: report.plan.occlusion_passes(),
        });
        self.take_timings(report.finished.clone());
        Ok(Some(Step { request, report: Some(report) }))
    }

    /// Renders the eyes, the buffer view's buffer and the headset's copy of the frame.
    fn render(&mut self, request: &FrameRequest) -> Result<FrameReport> {
        let mut outputs = vec![COLOR, DEPTH];
        outputs.extend(self.buffer_view.resource(self.renderer.settings()));
        // Animated objects are where they are at the frame's display time.
        let origin = *self.scene_time_origin.get_or_insert(request.display_time);
        self.renderer.set_scene_time(request.display_time - origin);
        // The lens's mask: the headset's from the first frame, and again whenever the
        // runtime changes it.
        if self.renderer.visibility_mask() != self.headset.visibility_mask() {
            self.renderer.set_visibility_mask(self.headset.visibility_mask().cloned());
        }
        let (headset, gpu) = (&mut self.headset, &self.gpu);
        Ok(self.renderer.render_with(&request.eyes.eyes, &outputs, |encoder, targets| {
            if let (Some(color), Some(depth)) = (targets.get(&COLOR), targets.get(&DEPTH)) {
                headset.record_frame(gpu, encoder, request, color, depth);
            }
        })?)
    }

    /// Takes the display's refresh period the headset gives this frame as the budget, and
    /// hands it to the governor, so that both follow the display from this frame on (a
    /// runtime changing its rate). Never give it a predicted period the runtime stretched
    /// because frames were late ([`FrameRequest::refresh_period_ms`]).
    pub fn follow_display_period(&mut self, period_ms: f64) {
        if !(period_ms.is_finite() && period_ms > 0.0) {
            return;
        }
        // The first period the headset gives replaces the profile's outright.
        if !std::mem::replace(&mut self.display_period_seen, true) {
            self.budget_range_ms = (period_ms, period_ms);
        } else if period_ms != self.budget_ms {
            log::info!("display refresh period {:.2} ms -> {period_ms:.2} ms: the budget follows", self.budget_ms);
            self.budget_changes += 1;
        }
        self.budget_ms = period_ms;
        self.budget_range_ms = (self.budget_range_ms.0.min(period_ms), self.budget_range_ms.1.max(period_ms));
        if let Some(governor) = &mut self.governor {
            governor.set_period_ms(period_ms);
        }
    }

    /// Books the GPU times of frames that came back.
    fn take_timings(&mut self, finished: Vec<FrameTiming>) {
        self.done.extend(self.completion.done());
        // Without timestamps no timing comes back to take them: keep the recent ones.
        while self.done.len() > KEPT_IN_FLIGHT {
            self.done.pop_front();
        }
        for mut timing in finished {
            while self.in_flight.front().is_some_and(|f| f.frame < timing.frame) {
                self.in_flight.pop_front();
            }
            let sent = self.in_flight.front().filter(|f| f.frame == timing.frame);
            timing.serial = sent.is_some_and(|f| f.serial);
            let budget_ms = sent.map_or(self.budget_ms, |f| f.budget_ms);
            let predicted_ms = sent.and_then(|f| f.predicted_period_ms);
            let deadline = sent.and_then(|f| f.deadline);
            let passes = sent.map(|f| f.occlusion_passes.clone());
            let ao_ms = passes.and_then(|passes| self.occlusion_ms(&timing, &passes));
            self.timed_frames += 1;
            if timing.total_ms > budget_ms {
                self.over_budget_frames += 1;
            }
            while self.done.front().is_some_and(|&(frame, _)| frame < timing.frame) {
                self.done.pop_front();
            }
            let seen_done = self.done.front().filter(|&&(frame, _)| frame == timing.frame).map(|&(_, at)| at);
            let late_ms = deadline.map(|(display_time, submitted_at, submitted_instant)| {
                let earliest = crate::xr::earliest_finish(submitted_at, self.previous_finish, timing.total_ms);
                // Seen done: the instant on the headset's clock, from the submission's.
                let finish = seen_done.map_or(earliest, |at| {
                    submitted_at + at.saturating_duration_since(submitted_instant).as_secs_f64()
                });
                self.previous_finish = Some(finish);
                (finish - display_time) * 1e3
            });
            if let Some(late_ms) = late_ms {
                log::debug!(
                    "frame {}: finished {late_ms:+.2} ms from its predicted display time ({})",
                    timing.frame,
                    if seen_done.is_some() { "seen done" } else { "estimated" }
                );
                self.clocked_frames += 1;
                self.late_frames += u64::from(late_ms > 0.0);
            }
            self.gpu_frame_ms.push(timing.total_ms);
            let observation =
                Observation { gpu_ms: timing.total_ms, ao_ms, predicted_period_ms: predicted_ms, late_ms };
            self.govern(timing.frame, observation);
            self.history.push(timing);
        }
    }

    /// The AO passes' share of a frame's time, or `None` (reported once) when one of
    /// them has no span: the governor then estimates the share from its frontier rather
    /// than taking the pass as free.
    fn occlusion_ms(&mut self, timing: &FrameTiming, passes: &[&'static str]) -> Option<f64> {
        match FrameTiming::passes_ms(&timing.spans, passes) {
            Ok(ms) => Some(ms),
            Err(pass) => {
                if !std::mem::replace(&mut self.missing_span_reported, true) {
                    log::warn!("frame {}: pass '{pass}' ran but no GPU span is named after it", timing.frame);
                }
                None
            }
        }
    }

    /// Feeds what is known of a frame (its times, the display period the headset predicted
    /// for it, whether it was late) to the governor and applies the level it picks.
    fn govern(&mut self, frame: u64, observation: Observation) {
        let Some(governor) = &mut self.governor else { return };
        let change = governor.observe_frame(frame, observation);
        let Some(change) = change else { return };
        log::debug!("governor, frame {}: {} -> {} ({})", change.frame, change.from, change.to, change.reason);
        let mut settings = self.renderer.settings().clone();
        settings.ao = governor.current().apply(&settings.ao);
        if let Err(e) = self.renderer.set_settings(&settings) {
            log::warn!("governor: {e}");
        }
    }

    /// Lets `governor` choose the AO setting from now on, starting at its current level.
    pub fn set_governor(&mut self, mut governor: Governor) -> Result<()> {
        governor.set_period_ms(self.budget_ms);
        let mut settings = self.renderer.settings().clone();
        settings.ao = governor.current().apply(&settings.ao);
        self.renderer.set_settings(&settings)?;
        self.governor = Some(governor);
        Ok(())
    }

    /// Ends the session: waits for the frames in flight (their times are booked too).
    pub fn end(&mut self) -> Result<()> {
        let finished = self.renderer.finish()?;
        self.take_timings(finished);
        self.headset.end(&self.gpu)
    }
}
