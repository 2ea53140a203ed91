//! The `vrao run` frame loop: a headset (OpenXR when a runtime answers, the simulated one
//! otherwise) asks for frames; the renderer draws both eyes; the headset gets colour and
//! depth. The desktop window (`display.rs`) drives the same loop one step per redraw.

use crate::error::{Error, Result};
use crate::gpu::{BackendChoice, Gpu};
use crate::graph::Resource;
use crate::headset::openxr::{self, OpenXrOptions, OpenedHeadset, Unavailable};
use crate::headset::simulated::{SimulatedHeadset, SimulatedOptions};
use crate::headset::{FrameRequest, Headset, SubmittedFrame};
use crate::renderer::{FrameReport, Renderer};
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stereo::HeadsetProfile;
use std::collections::VecDeque;
use std::sync::Arc;

/// Which headset `vrao run` drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum HeadsetChoice {
    /// OpenXR when a runtime answers, the simulated headset otherwise.
    #[default]
    Auto,
    /// OpenXR or an error (exit 2).
    OpenXr,
    /// The simulated headset; OpenXR is never touched.
    Simulated,
}

impl std::str::FromStr for HeadsetChoice {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "auto" => Ok(HeadsetChoice::Auto),
            "openxr" => Ok(HeadsetChoice::OpenXr),
            "simulated" => Ok(HeadsetChoice::Simulated),
            other => Err(format!("unknown headset '{other}' (expected auto, openxr or simulated)")),
        }
    }
}

/// Opens the chosen headset and the GPU to render for it; the message says which one
/// and, on fall back, why. An OpenXR session brings its own GPU (the runtime creates the
/// Vulkan device); the simulated headset renders on `Gpu::new(backend)`.
///
/// The OpenXR headset renders at the runtime's recommended per-eye size unless the
/// simulated profile asks for another size than the Vive-class default (`vrao run
/// --width/--height`); it falls back to the simulated headset if its session is lost.
pub fn open_headset(
    choice: HeadsetChoice,
    simulated: SimulatedOptions,
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
        let vive = HeadsetProfile::vive();
        let size = (simulated.profile.width, simulated.profile.height);
        let size = (size != (vive.width, vive.height)).then_some(size);
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

/// Per-pass GPU times of recent frames, for the profiler graph.
#[derive(Clone, Debug, Default)]
pub struct PassHistory {
    pub frames: VecDeque<Vec<(String, f64)>>,
    pub capacity: usize,
}

impl PassHistory {
    pub fn new(capacity: usize) -> PassHistory {
        PassHistory { frames: VecDeque::with_capacity(capacity), capacity }
    }

    pub fn push(&mut self, spans: Vec<(String, f64)>) {
        if self.frames.len() == self.capacity {
            self.frames.pop_front();
        }
        self.frames.push_back(spans);
    }
}

/// What one step of the loop did.
pub struct Step {
    pub request: FrameRequest,
    pub report: Option<FrameReport>,
}

/// The headset frame loop.
pub struct FrameLoop {
    pub gpu: Arc<Gpu>,
    pub renderer: Renderer,
    pub headset: Box<dyn Headset>,
    pub history: PassHistory,
    pub frames: u64,
}

impl FrameLoop {
    /// A loop rendering `scene` with `settings` at the headset's recommended size.
    pub fn new(gpu: Arc<Gpu>, scene: &Scene, settings: &Settings, headset: Box<dyn Headset>) -> Result<FrameLoop> {
        let mut settings = settings.clone();
        (settings.profile.width, settings.profile.height) = headset.recommended_size();
        let renderer = Renderer::new(gpu.clone(), scene, &settings)?;
        Ok(FrameLoop { gpu, renderer, headset, history: PassHistory::new(120), frames: 0 })
    }

    /// Waits for the headset's next frame, renders it and submits it; `None` when the
    /// session has ended.
    pub fn step(&mut self) -> Result<Option<Step>> {
        let Some(request) = self.headset.wait_frame(&self.gpu)? else { return Ok(None) };
        if !request.should_render {
            self.headset.submit(&self.gpu, &request, None)?;
            return Ok(Some(Step { request, report: None }));
        }
        let report = self.renderer.render(&request.eyes.eyes, &[Resource::Color, Resource::Depth])?;
        let color = self.renderer.target(Resource::Color).ok_or_else(|| Error::Gpu("no eye colour".into()))?;
        let depth = self.renderer.target(Resource::Depth).ok_or_else(|| Error::Gpu("no eye depth".into()))?;
        let frame = SubmittedFrame { color, depth, eyes: &request.eyes, near: request.eyes.near };
        self.headset.submit(&self.gpu, &request, Some(frame))?;
        self.history.push(report.gpu_ms.clone());
        self.frames += 1;
        Ok(Some(Step { request, report: Some(report) }))
    }

    pub fn end(&mut self) -> Result<()> {
        self.headset.end(&self.gpu)
    }
}

/// What a run did: frames rendered, the headset's counters and per-pass medians.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunSummary {
    pub headset: String,
    pub frames: u64,
    pub counters: crate::headset::FrameCounters,
    /// (pass, median GPU ms for both eyes) over the recent frames.
    pub pass_medians_ms: Vec<(String, f64)>,
}

impl RunSummary {
    pub fn of(frame_loop: &FrameLoop) -> RunSummary {
        let frames: Vec<Vec<(String, f64)>> = frame_loop.history.frames.iter().cloned().collect();
        RunSummary {
            headset: frame_loop.headset.describe(),
            frames: frame_loop.frames,
            counters: frame_loop.headset.counters(),
            pass_medians_ms: crate::gpu::timing::summarize(&frames)
                .into_iter()
                .map(|s| (s.label, s.median_ms))
                .collect(),
        }
    }

    pub fn to_text(&self) -> String {
        let c = &self.counters;
        let passes: Vec<String> = self.pass_medians_ms.iter().map(|(p, ms)| format!("{p} {ms:.2}")).collect();
        format!(
            "frames: {} rendered, {} submitted; vsyncs: {} presented, {} reprojected; {} dropped; latency median {:.1} ms, p95 {:.1} ms\npass medians (ms, both eyes): {}",
            self.frames,
            c.submitted,
            c.presented,
            c.reprojected,
            c.dropped,
            c.latency_median_ms,
            c.latency_p95_ms,
            passes.join(", ")
        )
    }
}
