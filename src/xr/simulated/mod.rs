//! The simulated headset: a Vive-class display (1080×1200 per eye, 90 Hz, IPD 64 mm)
//! with a vsync clock in real or virtual time, scripted head motion, and a compositor
//! that re-presents the newest frame warped to the pose of each vsync it missed.
//!
//! The frame loop is OpenXR's: `wait_frame` returns at a vsync with the eye poses
//! predicted for the next one; the application renders and submits; the compositor
//! decides at each vsync what is shown (see `compositor.rs`). Of the vsyncs that pass
//! while the application renders, only the newest one's image is computed (the warp):
//! the others are counted, as nobody could look at them on a simulated panel.

pub mod compositor;
pub mod motion;
pub mod reproject;

use super::{FrameCounters, FrameRequest, Headset, SubmittedFrame};
use crate::error::{Error, Result};
use compositor::{Clock, Compositor, VsyncOutcome};
use motion::HeadMotion;
use reproject::{output_target, ReprojectionMode, Reprojector};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use vrao_ao::plug::{Gpu, LayeredTarget, DEPTH};
use vrao_ao::EyePair;
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::HeadPath;
use vrao_render::HeadsetProfile;

/// How time passes on the simulated headset.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeMode {
    /// Wall-clock time: `wait_frame` sleeps until the vsync.
    Real,
    /// Virtual time: each submitted frame takes the next of these render times (ms,
    /// cycled), so the same script always gives the same counters.
    Virtual {
        /// Render time of each frame in ms, cycled.
        render_ms: Vec<f64>,
    },
}

/// How the simulated headset is set up.
#[derive(Clone, Debug)]
pub struct SimulatedOptions {
    /// Display refresh rate, per-eye size, fields of view and eye separation.
    pub profile: HeadsetProfile,
    /// Near plane (m) of the eye projections.
    pub near: f64,
    /// The scene's head pose or scripted path.
    pub path: HeadPath,
    /// Motion added on top of `path`.
    pub motion: HeadMotion,
    /// Real or virtual time.
    pub time: TimeMode,
    /// How the compositor reprojects a late or repeated frame.
    pub reprojection: ReprojectionMode,
    /// Compute the display image (the compositor's output) for the mirror window.
    pub compose: bool,
    /// End the session after this many frames.
    pub frames: Option<u64>,
}

/// A submitted frame the compositor keeps: copies of its colour and depth.
struct HeldFrame {
    frame: u64,
    eyes: EyePair,
    color: LayeredTarget,
    depth: LayeredTarget,
}

/// How often, in real time, the headset looks whether a rendering frame has finished.
const COMPLETION_POLL_S: f64 = 0.005;

/// A frame handed over in real time whose GPU work has not been seen to finish: the
/// compositor gets it, with the time it finished, once it has.
struct Rendering {
    frame: u64,
    target_vsync: u64,
    pose_time: f64,
    finished_at: Arc<Mutex<Option<f64>>>,
}

/// The longest virtual render time of a frame (ms): a frame that late already misses
/// hundreds of vsyncs; a longer one would keep the compositor counting vsyncs for hours.
pub const VIRTUAL_RENDER_MS_MAX: f64 = 10_000.0;

/// Refuses a virtual render-time script that is empty or has a time outside
/// 0..=[`VIRTUAL_RENDER_MS_MAX`] ms (NaN included).
pub fn check_virtual_render_ms(render_ms: &[f64]) -> Result<()> {
    if render_ms.is_empty() {
        return Err(Error::input("virtual render times: give one or more milliseconds"));
    }
    match render_ms.iter().find(|ms| !(0.0..=VIRTUAL_RENDER_MS_MAX).contains(*ms)) {
        Some(ms) => {
            Err(Error::input(format!("virtual render time {ms:?} ms is not within 0..={VIRTUAL_RENDER_MS_MAX} ms")))
        }
        None => Ok(()),
    }
}

/// A headset without hardware: vsyncs on a real or virtual clock, a compositor that reprojects late frames, frame counters as SteamVR reports them.
pub struct SimulatedHeadset {
    options: SimulatedOptions,
    rendering: VecDeque<Rendering>,
    /// The frame whose hold copy went into its own submission ([`Headset::record_frame`]).
    recorded: Option<u64>,
    clock: Clock,
    compositor: Compositor,
    next_frame: u64,
    /// The vsync the current frame started at, and when its pose was sampled.
    started: Option<(u64, f64)>,
    held: Vec<HeldFrame>,
    shown: Option<u64>,
    reprojector: Option<Reprojector>,
    output: Option<LayeredTarget>,
    last_outcome: Option<(u64, VsyncOutcome)>,
    /// `request_exit` was called: no more frames.
    exit_requested: bool,
    ended: bool,
    /// The profile's lens ([`crate::xr::profiles::visibility_mask`]).
    mask: vrao_ao::VisibilityMask,
}

impl SimulatedHeadset {
    /// A headset with `options`; fails on an empty virtual render-time script or one with
    /// a time outside 0..=[`VIRTUAL_RENDER_MS_MAX`].
    pub fn new(options: SimulatedOptions) -> Result<SimulatedHeadset> {
        if let TimeMode::Virtual { render_ms } = &options.time {
            check_virtual_render_ms(render_ms)?;
        }
        let clock = match options.time {
            TimeMode::Real => Clock::real(),
            TimeMode::Virtual { .. } => Clock::Virtual { now: 0.0 },
        };
        Ok(SimulatedHeadset {
            mask: crate::xr::profiles::visibility_mask(&options.profile),
            rendering: VecDeque::new(),
            recorded: None,
            compositor: Compositor::new(options.profile.refresh_hz),
            options,
            clock,
            next_frame: 0,
            started: None,
            held: Vec::new(),
            shown: None,
            reprojector: None,
            output: None,
            last_outcome: None,
            exit_requested: false,
            ended: false,
        })
    }

    fn eyes_at(&self, t: f64) -> EyePair {
        self.options.profile.eyes(&self.options.motion.pose_at(&self.options.path, t), self.options.near)
    }

    /// Hands the compositor the frames whose GPU work has finished, with when it did.
    fn collect_finished(&mut self, gpu: &Gpu) -> Result<()> {
        if self.rendering.is_empty() {
            return Ok(());
        }
        gpu.poll()?;
        while let Some(front) = self.rendering.front() {
            let Some(finished) = *front.finished_at.lock().expect("finish time") else { break };
            self.compositor.submit(front.frame, front.target_vsync, finished, front.pose_time);
            self.rendering.pop_front();
        }
        Ok(())
    }

    /// Waits until time `t` on the headset's clock. In real time, while frames are
    /// rendering, it looks every [`COMPLETION_POLL_S`] whether they have finished, so
    /// that each one's finishing time is seen then, not at the next vsync.
    fn wait_until(&mut self, gpu: &Gpu, t: f64) -> Result<()> {
        loop {
            self.collect_finished(gpu)?;
            let now = self.clock.now();
            if now >= t || !matches!(self.clock, Clock::Real { .. }) {
                break;
            }
            if self.rendering.is_empty() {
                self.clock.wait_until(t);
            } else {
                // Naps between non-blocking polls. Lavapipe makes polls and timed waits
                // costly: polling often (or a blocking wait with a timeout) slowed its
                // frames several-fold (docs/records/2026-11-29/measurements-in-code.md, completion-poll); a
                // finish is seen at most this late.
                self.clock.wait_until(t.min(now + COMPLETION_POLL_S));
            }
        }
        self.clock.wait_until(t);
        Ok(())
    }

    /// Processes the vsyncs up to now and, when composing, computes the newest one's image.
    fn advance(&mut self, gpu: &Gpu) -> Result<()> {
        self.collect_finished(gpu)?;
        let outcomes = self.compositor.advance_to(self.clock.now());
        for (_, outcome) in &outcomes {
            if let VsyncOutcome::Presented { frame } | VsyncOutcome::Reprojected { frame } = outcome {
                self.shown = Some(*frame);
            }
        }
        if let Some(&last) = outcomes.last() {
            self.last_outcome = Some(last);
            if self.options.compose {
                self.compose(gpu, last)?;
            }
        }
        Ok(())
    }

    fn compose(&mut self, gpu: &Gpu, (vsync, outcome): (u64, VsyncOutcome)) -> Result<()> {
        let frame = match outcome {
            VsyncOutcome::Presented { frame } | VsyncOutcome::Reprojected { frame } => frame,
            VsyncOutcome::Empty => return Ok(()),
        };
        let Some(held) = self.held.iter().find(|h| h.frame == frame) else { return Ok(()) };
        let extent = held.color.extent();
        if self.output.as_ref().is_none_or(|o| o.extent() != extent) {
            self.output = Some(output_target(gpu, extent));
        }
        let output = self.output.as_ref().expect("allocated above");
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("compositor") });
        match outcome {
            VsyncOutcome::Presented { .. } => encoder.copy_texture_to_texture(
                held.color.texture.as_image_copy(),
                output.texture.as_image_copy(),
                held.color.texture.size(),
            ),
            _ => {
                let target = self.eyes_at(self.compositor.vsync_time(vsync));
                let reprojector = match &mut self.reprojector {
                    Some(reprojector) => reprojector,
                    none => none.insert(Reprojector::new(gpu)?),
                };
                reprojector.record(
                    gpu,
                    &mut encoder,
                    self.options.reprojection,
                    &held.color,
                    &held.depth,
                    &held.eyes.eyes,
                    &target.eyes,
                    self.options.near,
                    output,
                );
            }
        }
        gpu.queue.submit([encoder.finish()]);
        Ok(gpu.take_error()?)
    }

    /// The outcome of the newest processed vsync.
    pub fn last_outcome(&self) -> Option<(u64, VsyncOutcome)> {
        self.last_outcome
    }

    /// Seconds on the headset's clock.
    pub fn now(&self) -> f64 {
        self.clock.now()
    }

    /// Copies the submitted frame into a held slot that is not the one on display, in
    /// its own submission.
    fn hold(&mut self, gpu: &Gpu, index: u64, frame: &SubmittedFrame) {
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("hold frame") });
        self.record_hold(gpu, &mut encoder, index, frame.eyes, frame.color, frame.depth);
        gpu.queue.submit([encoder.finish()]);
    }

    /// Records the copy of a frame's eyes into a held slot that is not the one on display.
    fn record_hold(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        index: u64,
        eyes: &EyePair,
        color: &LayeredTarget,
        depth: &LayeredTarget,
    ) {
        let extent = color.extent();
        let shown = self.shown;
        let reusable = self.held.iter().position(|h| Some(h.frame) != shown && h.color.extent() == extent);
        let slot = match reusable {
            Some(i) => i,
            None => {
                self.held.retain(|h| Some(h.frame) == shown);
                let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
                self.held.push(HeldFrame {
                    frame: index,
                    eyes: *eyes,
                    color: LayeredTarget::new(&gpu.device, "held colour", COLOR.format(), extent, usage),
                    depth: LayeredTarget::new(&gpu.device, "held depth", DEPTH.format(), extent, usage),
                });
                self.held.len() - 1
            }
        };
        let held = &mut self.held[slot];
        held.frame = index;
        held.eyes = *eyes;
        for (from, to) in [(color, &held.color), (depth, &held.depth)] {
            encoder.copy_texture_to_texture(
                from.texture.as_image_copy(),
                to.texture.as_image_copy(),
                from.texture.size(),
            );
        }
        self.recorded = Some(index);
    }
}

impl Headset for SimulatedHeadset {
    fn visibility_mask(&self) -> Option<&vrao_ao::VisibilityMask> {
        Some(&self.mask)
    }

    fn describe(&self) -> String {
        let p = &self.options.profile;
        let time = match &self.options.time {
            TimeMode::Real => "real time".to_string(),
            TimeMode::Virtual { render_ms } => format!("virtual time, render times {render_ms:?} ms"),
        };
        format!(
            "simulated headset ({}: {}x{} per eye, {} Hz, IPD {} mm; {}; {} motion; {} reprojection)",
            p.name,
            p.width,
            p.height,
            p.refresh_hz,
            p.ipd * 1e3,
            time,
            self.options.motion.name(),
            self.options.reprojection.name()
        )
    }

    fn recommended_size(&self) -> (u32, u32) {
        (self.options.profile.width, self.options.profile.height)
    }

    fn wait_frame(&mut self, gpu: &Gpu) -> Result<Option<FrameRequest>> {
        if self.ended || self.exit_requested || self.options.frames.is_some_and(|n| self.next_frame >= n) {
            return Ok(None);
        }
        // Like xrWaitFrame: return at the next vsync, with poses predicted one period on.
        let start_vsync = self.compositor.vsync_after(self.clock.now() - 1e-9).max(1);
        self.wait_until(gpu, self.compositor.vsync_time(start_vsync))?;
        self.advance(gpu)?;
        let display_time = self.compositor.vsync_time(start_vsync + 1);
        self.started = Some((start_vsync, self.clock.now()));
        let request = FrameRequest {
            index: self.next_frame,
            display_time,
            eyes: self.eyes_at(display_time),
            size: self.recommended_size(),
            should_render: true,
            display_period_ms: Some(self.options.profile.budget_ms()),
            refresh_period_ms: Some(self.options.profile.budget_ms()),
        };
        self.next_frame += 1;
        Ok(Some(request))
    }

    fn submit(&mut self, gpu: &Gpu, request: &FrameRequest, frame: Option<SubmittedFrame>) -> Result<()> {
        let (start_vsync, pose_time) =
            self.started.take().ok_or_else(|| Error::gpu("submit without a frame from wait_frame"))?;
        if let TimeMode::Virtual { render_ms } = &self.options.time {
            let ms = if frame.is_some() { render_ms[(request.index % render_ms.len() as u64) as usize] } else { 0.0 };
            self.clock.advance(ms / 1e3);
        }
        if let Some(frame) = frame {
            if self.recorded.take() != Some(request.index) {
                self.hold(gpu, request.index, &frame);
            }
            match &self.clock {
                // In real time the frame is still on the GPU (frames in flight): the
                // compositor learns when it finishes.
                Clock::Real { start } => {
                    let start = *start;
                    let finished_at = Arc::new(Mutex::new(None));
                    let slot = finished_at.clone();
                    gpu.queue.on_submitted_work_done(move || {
                        *slot.lock().expect("finish time") = Some(start.elapsed().as_secs_f64());
                    });
                    self.rendering.push_back(Rendering {
                        frame: request.index,
                        target_vsync: start_vsync + 1,
                        pose_time,
                        finished_at,
                    });
                }
                Clock::Virtual { .. } => {
                    self.compositor.submit(request.index, start_vsync + 1, self.clock.now(), pose_time)
                }
            }
        }
        self.advance(gpu)
    }

    fn record_frame(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        request: &FrameRequest,
        color: &LayeredTarget,
        depth: &LayeredTarget,
    ) {
        self.record_hold(gpu, encoder, request.index, &request.eyes, color, depth);
    }

    fn display_image(&self) -> Option<&LayeredTarget> {
        self.output.as_ref()
    }

    fn counters(&self) -> FrameCounters {
        self.compositor.counters()
    }

    fn session_state(&self) -> String {
        if self.ended || self.exit_requested { "ending" } else { "running" }.into()
    }

    fn display_rate_source(&self) -> String {
        let p = &self.options.profile;
        format!("the simulated headset's refresh rate ({} Hz, profile '{}' or --refresh)", p.refresh_hz, p.name)
    }

    fn refresh_period_ms(&self) -> Option<f64> {
        Some(self.options.profile.budget_ms())
    }

    fn now(&self) -> Option<f64> {
        // Virtual time runs apart from the GPU's real milliseconds.
        matches!(self.clock, Clock::Real { .. }).then(|| self.clock.now())
    }

    fn no_clock_reason(&self) -> String {
        "virtual time: the simulated compositor's counters say which frames it reprojected".into()
    }

    fn request_exit(&mut self) {
        self.exit_requested = true;
    }

    fn end(&mut self, gpu: &Gpu) -> Result<()> {
        if !self.ended {
            gpu.wait_idle()?;
            self.collect_finished(gpu)?;
            // The display shows what was submitted last before the session closes.
            let last = self.compositor.vsync_after(self.clock.now()) + 1;
            self.clock.wait_until(self.compositor.vsync_time(last));
            self.compositor.advance_to(self.clock.now());
            self.compositor.finish();
            self.ended = true;
        }
        Ok(())
    }
}
