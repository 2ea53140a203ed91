//! The `vrao run` frame loop: a headset (OpenXR when a runtime answers, the simulated one
//! otherwise) asks for frames; the renderer draws both eyes; the headset gets colour and
//! depth. The desktop window (`display.rs`) drives the same loop one step per redraw.

use crate::app::governor::{Governor, GovernorChange};
use crate::render::error::{Error, Result};
use crate::render::gpu::timing::FrameTiming;
use crate::render::gpu::{BackendChoice, Gpu};
use crate::render::graph::{Resource, FINAL_AO};
use crate::render::passes::gbuffer::{DEPTH, NORMALS};
use crate::render::passes::occlusion::AO_RAW;
use crate::render::passes::tonemap::COLOR;
use crate::render::renderer::{FrameReport, Renderer, Timing};
use crate::render::scene::Scene;
use crate::render::settings::Settings;
use crate::xr::openxr::{self, OpenXrOptions, OpenedHeadset, Unavailable};
use crate::xr::simulated::{SimulatedHeadset, SimulatedOptions};
use crate::xr::{FrameRequest, Headset, SubmittedFrame};
use std::collections::{BTreeSet, VecDeque};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Which headset `vrao run` drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum HeadsetChoice {
    /// OpenXR when a runtime answers, the simulated headset otherwise.
    #[default]
    Auto,
    /// OpenXR or an error (exit 2).
    #[value(name = "openxr")]
    OpenXr,
    /// The simulated headset; OpenXR is never touched.
    Simulated,
}

/// What the desktop window shows of each eye (`vrao run --show`, the panel's "show"):
/// the eye images, or one of the buffers behind them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum BufferView {
    /// The eye images (or, in the mirror, what the headset's compositor shows).
    #[default]
    Eyes,
    /// The occlusion the composite applies (blurred, upsampled or accumulated), as grey.
    #[value(name = "ao")]
    FinalAo,
    /// The occlusion as the technique computed it, before any filter, as grey.
    RawAo,
    /// Reversed-Z depth as log-distance: near white, far dark, sky black.
    Depth,
    /// View-space normals, xyz mapped from [-1, 1] to colour.
    Normals,
}

impl BufferView {
    /// The renderer's resource that holds this view under `settings` (the final AO is
    /// the graph's named output); `None` for the eye images and for AO when no technique
    /// runs.
    pub fn resource(self, settings: &Settings) -> Option<Resource> {
        let any_ao = settings.ao.technique != crate::render::settings::Technique::None;
        match self {
            BufferView::Eyes => None,
            BufferView::FinalAo => any_ao.then_some(FINAL_AO),
            BufferView::RawAo => any_ao.then_some(AO_RAW),
            BufferView::Depth => Some(DEPTH),
            BufferView::Normals => Some(NORMALS),
        }
    }
}

/// Opens the chosen headset and the GPU to render for it; the message says which one
/// and, on fall back, why. An OpenXR session brings its own GPU (the runtime creates the
/// Vulkan device); the simulated headset renders on `Gpu::new(backend)`.
///
/// The OpenXR headset renders at the runtime's recommended per-eye size (and with its
/// views) unless `size` asks for another (`vrao run --width/--height`); the profile is
/// the simulated headset's only. It falls back to the simulated headset if its session
/// is lost.
pub fn open_headset(
    choice: HeadsetChoice,
    simulated: SimulatedOptions,
    size: Option<(u32, u32)>,
    backend: BackendChoice,
) -> Result<OpenedHeadset> {
    let simulated_headset = |why: String| -> Result<OpenedHeadset> {
        let headset = SimulatedHeadset::new(simulated.clone())?;
        let gpu = Arc::new(Gpu::new(backend)?);
        let message = format!("{why}: using the {}", headset.describe());
        Ok((Box::new(headset), gpu, message))
    };
    let openxr = || {
        if backend == BackendChoice::Gl {
            return Err(Unavailable::Unsupported("OpenXR sessions need the Vulkan backend, not --backend gl".into()));
        }
        openxr::open_headset(OpenXrOptions::from_simulated(&simulated, size))
    };
    match choice {
        HeadsetChoice::Simulated => simulated_headset("--headset simulated".into()),
        HeadsetChoice::Auto => match openxr() {
            Ok(opened) => Ok(opened),
            Err(why) => simulated_headset(why.to_string()),
        },
        HeadsetChoice::OpenXr => openxr().map_err(|why| Error::Device(format!("--headset openxr: {why}"))),
    }
}

/// Per-pass GPU times of recent frames (as they come back from the GPU, a few frames
/// after they were submitted), for the profiler graph.
#[derive(Clone, Debug, Default)]
pub struct PassHistory {
    /// The most recent frames' GPU times, oldest first, at most `capacity`.
    pub frames: VecDeque<FrameTiming>,
    /// CPU time spent encoding each recent frame (ms), newest last.
    pub cpu_encode_ms: VecDeque<f64>,
    /// How many frames (and CPU encode times) are kept.
    pub capacity: usize,
}

impl PassHistory {
    /// An empty history keeping the last `capacity` frames.
    pub fn new(capacity: usize) -> PassHistory {
        PassHistory { frames: VecDeque::with_capacity(capacity), cpu_encode_ms: VecDeque::new(), capacity }
    }

    /// Adds a frame's GPU times, dropping the oldest when full.
    pub fn push(&mut self, timing: FrameTiming) {
        if self.frames.len() == self.capacity {
            self.frames.pop_front();
        }
        self.frames.push_back(timing);
    }

    /// Adds a frame's CPU encode time (ms), dropping the oldest when full.
    pub fn push_cpu_encode(&mut self, ms: f64) {
        if self.cpu_encode_ms.len() == self.capacity {
            self.cpu_encode_ms.pop_front();
        }
        self.cpu_encode_ms.push_back(ms);
    }
}

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
    /// The display period the frame must fit (ms).
    pub budget_ms: f64,
    /// Frames whose GPU time exceeded `budget_ms`, and all frames whose time came back.
    pub over_budget_frames: u64,
    /// Frames whose GPU time has come back (the denominator of `over_budget_frames`).
    pub timed_frames: u64,
    /// Every frame's GPU time and CPU encode time (ms), for the run's medians.
    pub gpu_frame_ms: Vec<f64>,
    /// Every frame's CPU encode time (ms).
    pub cpu_encode_ms: Vec<f64>,
    /// Set (by Ctrl-C) to end the session cleanly after the current frame.
    pub exit_requested: Arc<AtomicBool>,
    exit_sent: bool,
    /// On a CPU adapter, every [`SERIAL_EVERY`]-th frame is submitted pass by pass.
    cpu_adapter: bool,
    serial_frames: VecDeque<u64>,
    /// Spans of the passes the governor's AO setting changes (the rest of the frame does
    /// not depend on it), as the frames' plans name them.
    occlusion_passes: BTreeSet<&'static str>,
    /// Chooses the AO setting from the measured GPU times (`None`: settings fixed).
    pub governor: Option<Governor>,
    /// The buffer the window shows; every frame also produces it (an AO buffer the
    /// composite would otherwise fuse away, such as the upsampled AO, adds its pass).
    pub buffer_view: BufferView,
}

/// On a CPU adapter (lavapipe), timestamps within one submission credit work to the
/// wrong pass, and one submission per pass keeps frames from overlapping (each
/// submission waits for the previous one there). So one frame in this many is
/// submitted pass by pass for the profiler's true per-pass times; the others are
/// submitted whole and stay in flight.
pub const SERIAL_EVERY: u64 = 8;

impl FrameLoop {
    /// A loop rendering `scene` with `settings` at the headset's recommended size.
    pub fn new(gpu: Arc<Gpu>, scene: &Scene, settings: &Settings, headset: Box<dyn Headset>) -> Result<FrameLoop> {
        let mut settings = settings.clone();
        (settings.profile.width, settings.profile.height) = headset.recommended_size();
        let renderer = Renderer::new(gpu.clone(), scene, &settings)?;
        let cpu_adapter = gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        Ok(FrameLoop {
            cpu_adapter,
            serial_frames: VecDeque::new(),
            occlusion_passes: BTreeSet::new(),
            governor: None,
            buffer_view: BufferView::Eyes,
            gpu,
            renderer,
            headset,
            history: PassHistory::new(120),
            frames: 0,
            frame_limit: None,
            budget_ms: settings.profile.budget_ms(),
            over_budget_frames: 0,
            timed_frames: 0,
            gpu_frame_ms: Vec::new(),
            cpu_encode_ms: Vec::new(),
            exit_requested: Arc::new(AtomicBool::new(false)),
            exit_sent: false,
        })
    }

    /// Waits for the headset's next frame, renders it and submits it; `None` when the
    /// session has ended (or the frame limit is reached, or exit was requested).
    pub fn step(&mut self) -> Result<Option<Step>> {
        if self.frame_limit.is_some_and(|n| self.frames >= n) {
            return Ok(None);
        }
        // Ctrl-C: ask the headset to end the session; OpenXR then walks the session
        // through STOPPING to EXITING over the next calls.
        if self.exit_requested.load(Ordering::Relaxed) && !self.exit_sent {
            self.exit_sent = true;
            self.headset.request_exit();
        }
        let Some(request) = self.headset.wait_frame(&self.gpu)? else { return Ok(None) };
        if !request.should_render {
            self.headset.submit(&self.gpu, &request, None)?;
            return Ok(Some(Step { request, report: None }));
        }
        let serial = self.cpu_adapter && self.renderer.frame_index().is_multiple_of(SERIAL_EVERY);
        self.renderer.set_timing(if serial { Timing::Serial } else { Timing::Pipelined });
        if serial {
            self.serial_frames.push_back(self.renderer.frame_index());
        }
        let mut outputs = vec![COLOR, DEPTH];
        outputs.extend(self.buffer_view.resource(self.renderer.settings()));
        let (headset, gpu) = (&mut self.headset, &self.gpu);
        let report = self.renderer.render_with(&request.eyes.eyes, &outputs, |encoder, targets| {
            if let (Some(color), Some(depth)) = (targets.get(&COLOR), targets.get(&DEPTH)) {
                headset.record_frame(gpu, encoder, &request, color, depth);
            }
        })?;
        let color = self.renderer.target(COLOR).ok_or_else(|| Error::Gpu("no eye colour".into()))?;
        let depth = self.renderer.target(DEPTH).ok_or_else(|| Error::Gpu("no eye depth".into()))?;
        let frame = SubmittedFrame { color, depth, eyes: &request.eyes, near: request.eyes.near };
        self.headset.submit(&self.gpu, &request, Some(frame))?;
        self.frames += 1;
        self.cpu_encode_ms.push(report.cpu_encode_ms);
        self.occlusion_passes.extend(report.plan.occlusion_passes());
        self.history.push_cpu_encode(report.cpu_encode_ms);
        self.take_timings(report.finished.clone());
        Ok(Some(Step { request, report: Some(report) }))
    }

    /// Books the GPU times of frames that came back.
    fn take_timings(&mut self, finished: Vec<FrameTiming>) {
        for mut timing in finished {
            while self.serial_frames.front().is_some_and(|&f| f < timing.frame) {
                self.serial_frames.pop_front();
            }
            timing.serial = self.serial_frames.front() == Some(&timing.frame);
            self.timed_frames += 1;
            if timing.total_ms > self.budget_ms {
                self.over_budget_frames += 1;
            }
            self.gpu_frame_ms.push(timing.total_ms);
            if let Some(governor) = &mut self.governor {
                let ao_ms: f64 = timing
                    .spans
                    .iter()
                    .filter(|(pass, _)| self.occlusion_passes.contains(pass.as_str()))
                    .map(|(_, ms)| ms)
                    .sum();
                if let Some(change) = governor.observe_with_ao(timing.frame, timing.total_ms, ao_ms) {
                    log::info!(
                        "governor, frame {}: {} -> {} ({})",
                        change.frame,
                        change.from,
                        change.to,
                        change.reason
                    );
                    let mut settings = self.renderer.settings().clone();
                    settings.ao = governor.current().apply(&settings.ao);
                    if let Err(e) = self.renderer.set_settings(&settings) {
                        log::warn!("governor: {e}");
                    }
                }
            }
            self.history.push(timing);
        }
    }

    /// Lets `governor` choose the AO setting from now on, starting at its current level.
    pub fn set_governor(&mut self, governor: Governor) -> Result<()> {
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

fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    crate::render::gpu::timing::quantile(&sorted, 0.5)
}

/// What a run did (`vrao run --report`): frames rendered and in flight, the frame budget
/// and how often it was missed, the headset's counters and per-pass medians.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunSummary {
    /// The headset's name (simulated profile or OpenXR runtime and system).
    pub headset: String,
    /// The GPU adapter's name.
    pub adapter: String,
    /// Frames rendered and handed to the headset.
    pub frames_rendered: u64,
    /// The most frames the GPU worked on at once, and the limit.
    pub frames_in_flight_max: usize,
    /// The renderer's limit on frames in flight.
    pub frames_in_flight_limit: usize,
    /// The display period (ms) and the frames whose GPU time exceeded it (of those timed).
    pub budget_ms: f64,
    /// Timed frames whose GPU time exceeded `budget_ms`.
    pub over_budget_frames: u64,
    /// Frames whose GPU time came back.
    pub timed_frames: u64,
    /// Medians over the run: GPU time per frame (both eyes), CPU encode time per frame,
    /// and their ratio.
    pub gpu_frame_ms_median: f64,
    /// Median CPU encode time per frame (ms).
    pub cpu_encode_ms_median: f64,
    /// `cpu_encode_ms_median` / `gpu_frame_ms_median`.
    pub cpu_encode_share_of_gpu: f64,
    /// How the passes were timed: pipelined, and on a CPU adapter every
    /// [`SERIAL_EVERY`]th frame serial (one submission per pass).
    pub timing: String,
    /// The headset's frame counters: submitted, presented, reprojected, dropped, latency.
    pub counters: crate::xr::FrameCounters,
    /// (pass, median GPU ms for both eyes) over the recent frames.
    pub pass_medians_ms: Vec<(String, f64)>,
    /// Whether Ctrl-C ended the run.
    pub interrupted: bool,
    /// The budget governor: on or off, every change it made, and the AO setting the run
    /// ended with.
    pub governor: String,
    /// Every change the governor made, in order.
    pub governor_changes: Vec<GovernorChange>,
    /// The AO setting of the last frame, e.g. `gtao N=24 r=0.3 m half`.
    pub final_ao_setting: String,
    /// The OpenXR session's states, layers and loss reason (OpenXR headsets only).
    pub openxr: Option<crate::xr::openxr::OpenXrReport>,
}

impl RunSummary {
    /// Summarizes the loop as it stands (call it when the loop has ended).
    pub fn of(frame_loop: &FrameLoop) -> RunSummary {
        // On a CPU adapter the per-pass medians come from the frames timed pass by pass.
        let serial_only = frame_loop.history.frames.iter().any(|f| f.serial);
        let frames: Vec<Vec<(String, f64)>> =
            frame_loop.history.frames.iter().filter(|f| !serial_only || f.serial).map(|f| f.spans.clone()).collect();
        let gpu_frame_ms_median = median(&frame_loop.gpu_frame_ms);
        let cpu_encode_ms_median = median(&frame_loop.cpu_encode_ms);
        RunSummary {
            headset: frame_loop.headset.describe(),
            adapter: frame_loop.gpu.adapter.get_info().name,
            frames_rendered: frame_loop.frames,
            frames_in_flight_max: frame_loop.renderer.frames_in_flight_max(),
            frames_in_flight_limit: frame_loop.renderer.frames_in_flight_limit(),
            budget_ms: frame_loop.budget_ms,
            over_budget_frames: frame_loop.over_budget_frames,
            timed_frames: frame_loop.timed_frames,
            gpu_frame_ms_median,
            cpu_encode_ms_median,
            cpu_encode_share_of_gpu: if gpu_frame_ms_median > 0.0 {
                cpu_encode_ms_median / gpu_frame_ms_median
            } else {
                0.0
            },
            timing: if frame_loop.cpu_adapter {
                format!("pipelined; every {SERIAL_EVERY}th frame serial for the per-pass medians (CPU adapter)")
            } else {
                "pipelined".into()
            },
            counters: frame_loop.headset.counters(),
            pass_medians_ms: crate::render::gpu::timing::summarize(&frames)
                .into_iter()
                .map(|s| (s.label, s.median_ms))
                .collect(),
            interrupted: frame_loop.exit_requested.load(Ordering::Relaxed),
            governor: if frame_loop.governor.is_some() { "on" } else { "off" }.into(),
            governor_changes: frame_loop.governor.as_ref().map(|g| g.changes().to_vec()).unwrap_or_default(),
            final_ao_setting: {
                let ao = &frame_loop.renderer.settings().ao;
                let resolution = if ao.half_res { "half" } else { "full" };
                let temporal = if ao.temporal.enabled { " temporal" } else { "" };
                let r = crate::render::output::significant(ao.radius as f64, 3);
                format!("{}{temporal} N={} r={r} m {resolution}", ao.technique.name(), ao.samples)
            },
            openxr: frame_loop.headset.openxr_report(),
        }
    }

    /// The summary as the few lines `vrao run` prints.
    pub fn to_text(&self) -> String {
        let c = &self.counters;
        let passes: Vec<String> = self.pass_medians_ms.iter().map(|(p, ms)| format!("{p} {ms:.2}")).collect();
        format!(
            "governor {}: {} changes, AO setting at the end: {}\nframes: {} rendered (up to {} in flight), {} submitted; vsyncs: {} presented, {} reprojected; {} dropped; latency median {:.1} ms, p95 {:.1} ms\nGPU per frame: median {:.2} ms against a {:.2} ms budget, {} of {} timed frames over; CPU encode median {:.3} ms ({:.1} % of the GPU time)\npass medians (ms, both eyes, {} timing): {}",
            self.governor,
            self.governor_changes.len(),
            self.final_ao_setting,
            self.frames_rendered,
            self.frames_in_flight_max,
            c.submitted,
            c.presented,
            c.reprojected,
            c.dropped,
            c.latency_median_ms,
            c.latency_p95_ms,
            self.gpu_frame_ms_median,
            self.budget_ms,
            self.over_budget_frames,
            self.timed_frames,
            self.cpu_encode_ms_median,
            100.0 * self.cpu_encode_share_of_gpu,
            self.timing,
            passes.join(", ")
        )
    }
}
