//! The renderer: owns the passes and their targets. Each frame it asks the passes what
//! they read and write, lets the graph keep only what the requested outputs need, and
//! records the kept passes with a GPU timestamp span around each.
//!
//! Frames in flight: [`Renderer::render`] submits and returns without waiting for the
//! GPU; up to [`Renderer::set_frames_in_flight`] frames run at once (the oldest is
//! waited for before another is encoded) and each frame's GPU times come back a few
//! frames later in [`FrameReport::finished`]. Only pixel readbacks and
//! [`Renderer::render_and_wait`] (measurements) wait.

use crate::gpu::direct_readback::decode_direct;
use crate::gpu::scene::GpuScene;
use crate::lighting::ViewLighting;
use crate::passes;
use crate::scene::{Aabb, Scene};
use crate::settings::{Settings, StereoMode};
use glam::DVec3;
use std::collections::{BTreeMap, VecDeque};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;
use vrao_ao::plug::{
    ao_chain, read_layers, read_layers_f32, ChainLayout, ChainSettings, FrameMotion, FrameParams, FrameTiming, Gpu,
    GraphDriver, LayeredTarget, MoverBox, Pass, PassTimer, PixelTraffic, Resource, Submission,
};
use vrao_ao::{Error, Eye, Plan, Result, RightEyeTiles, VisibilityMask};

/// Frames the renderer lets the GPU work on at once unless told otherwise.
pub const DEFAULT_FRAMES_IN_FLIGHT: usize = 2;

/// What one frame did: the plan (passes run and left out) and how long each took.
#[derive(Clone, Debug)]
pub struct FrameReport {
    /// This frame's number (counts every frame the renderer submitted).
    pub frame: u64,
    /// The passes this frame ran and those left out, with the reason for each.
    pub plan: Plan,
    /// (span, GPU milliseconds) per pass of this frame, plus per-eye spans where a pass
    /// runs per eye: filled by [`Renderer::render_and_wait`]; after [`Renderer::render`]
    /// the frame is still on the GPU and its times arrive later in `finished`. Empty when
    /// the adapter has no timestamp queries.
    pub gpu_ms: Vec<(String, f64)>,
    /// CPU time spent encoding the frame's commands.
    pub cpu_encode_ms: f64,
    /// With [`Timing::Serial`] and [`Renderer::render_and_wait`]: (pass, wall-clock ms
    /// from submit to completion) per pass.
    pub wall_ms: Vec<(String, f64)>,
    /// Frames the GPU had not finished when this one was submitted, this one included.
    pub frames_in_flight: usize,
    /// Earlier frames whose GPU times came back while this one was recorded.
    pub finished: Vec<FrameTiming>,
}

/// How a frame's passes are submitted and timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Timing {
    /// One submission per frame, a timestamp pair around every pass (how frames run).
    #[default]
    Pipelined,
    /// One submission per pass. Lavapipe 22.x credits one pass's work to its neighbour
    /// within a submission, but finishes each submission before the next one's
    /// timestamps, so its per-pass times are true this way (and match the wall clock).
    /// The CPU still does not wait; [`Renderer::render_and_wait`] also waits for each
    /// pass and reports its wall-clock time.
    Serial,
}

/// A [`Timing`], or `Auto`: decided once the adapter is known ([`TimingChoice::resolve`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TimingChoice {
    /// Serial on CPU adapters, pipelined on GPUs.
    #[default]
    Auto,
    /// Always [`Timing::Pipelined`].
    Pipelined,
    /// Always [`Timing::Serial`].
    Serial,
}

vrao_ao::impl_choice!(TimingChoice);

impl TimingChoice {
    /// Every choice, the default first.
    pub const ALL: [TimingChoice; 3] = [TimingChoice::Auto, TimingChoice::Pipelined, TimingChoice::Serial];
    /// The choice's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            TimingChoice::Auto => "auto",
            TimingChoice::Pipelined => "pipelined",
            TimingChoice::Serial => "serial",
        }
    }

    /// `Auto` is serial on CPU adapters, whose timestamps between passes in one
    /// submission credit work to the wrong pass (lavapipe 22.x), and pipelined elsewhere.
    pub fn resolve(self, gpu: &Gpu) -> Timing {
        match self {
            TimingChoice::Pipelined => Timing::Pipelined,
            TimingChoice::Serial => Timing::Serial,
            TimingChoice::Auto if gpu.info.device_type == wgpu::DeviceType::Cpu => Timing::Serial,
            TimingChoice::Auto => Timing::Pipelined,
        }
    }
}

impl FrameReport {
    /// The GPU milliseconds of one span (a pass name, or "`<pass> left`"), if it was timed.
    pub fn gpu_ms_of(&self, span: &str) -> Option<f64> {
        self.gpu_ms.iter().find(|(s, _)| s == span).map(|(_, ms)| *ms)
    }
}

/// Renders stereo frames of one scene: owns the uploaded scene, the passes and their
/// targets, and the frames still on the GPU. Make it with [`Renderer::new`], render with
/// [`Renderer::render`] (frame loops) or [`Renderer::render_and_wait`] (measurements), and
/// read a target back with [`Renderer::read_f32`] or [`Renderer::read_bytes`].
pub struct Renderer {
    gpu: Arc<Gpu>,
    scene: Scene,
    settings: Settings,
    gpu_scene: GpuScene,
    /// What the passes consult each frame besides the driver's state.
    inputs: FrameInputs,
    passes: RendererPasses,
    /// The engine's frame driver: plan cache, targets, uniforms, record loop, timer.
    driver: GraphDriver<Settings>,
    timing: Timing,
    /// The scene time of the next frame (animation) and of the previous one.
    scene_time: f64,
    previous_scene_time: Option<f64>,
    /// Each moving object's node and its meshes' bounds in the node's frame.
    mover_bounds: Vec<(usize, Aabb)>,
    /// Submitted frames the GPU has not been seen to finish, oldest first.
    in_flight: VecDeque<InFlight>,
    frames_in_flight: usize,
    frames_in_flight_max: usize,
}

struct InFlight {
    submission: wgpu::SubmissionIndex,
    done: Arc<AtomicBool>,
}

impl Renderer {
    /// Uploads the scene and builds every pass for these settings (validated first). The
    /// stereo mode is fixed here: multiview when the adapter draws it reliably and
    /// [`StereoMode::Auto`] allows it.
    pub fn new(gpu: Arc<Gpu>, scene: &Scene, settings: &Settings) -> Result<Renderer> {
        settings.validate()?;
        // Refused here, naming the file, rather than as a wgpu validation error at upload.
        let max_side = gpu.device.limits().max_texture_dimension_2d;
        crate::scene::limits::check_texture_sizes(scene, max_side, &gpu.info.name)?;
        let multiview = match settings.stereo {
            StereoMode::Auto => gpu.caps.multiview_reliable,
            StereoMode::Multipass => false,
            StereoMode::Multiview if gpu.caps.multiview => {
                if !gpu.caps.multiview_reliable {
                    log::warn!(
                        "multiview on this adapter failed the start-up probe: clipped triangles may miss the right eye"
                    );
                }
                true
            }
            StereoMode::Multiview => {
                return Err(Error::input(format!(
                    "stereo mode multiview: adapter '{}' has no multiview; use the multipass mode",
                    gpu.info.name
                )))
            }
        };
        let gpu_scene = GpuScene::upload(&gpu, scene);
        let driver = GraphDriver::new(&gpu, PassTimer::new(&gpu)?);
        let passes = RendererPasses {
            scene: passes::scene_passes(&gpu, scene, &gpu_scene, driver.uniforms()),
            ao_chain: ao_chain(&gpu, vec![Box::new(passes::ssdo::SsdoPass::new(&gpu))]),
            output: passes::output_passes(&gpu),
        };
        if gpu.builds_cancelled() {
            return Err(Error::Interrupted);
        }
        // A shader file VRAO_SHADER_DIR names but that cannot be read is the error here.
        gpu.take_shader_error()?;
        gpu.take_error()?;
        let mover_bounds = mover_bounds(scene, &gpu_scene);
        let shell = crate::scene::shell::ConvexShell::of(scene);
        let inputs = FrameInputs {
            settings: chain_settings(settings),
            // The scene is fixed for the renderer's life, so are its materials.
            alpha_cards: scene.has_alpha_test(),
            shell: shell.clone(),
            // Until a frame's views say otherwise (plans made before the first frame),
            // the scene's own head at time 0.
            second_layer: second_layer_visible(
                shell.as_ref(),
                &settings.profile.eyes(&scene.head.pose_at(0.0), settings.near).eyes,
            ),
            anchor: gpu_scene.anchor,
            multiview,
            motion: FrameMotion { vectors: gpu_scene.has_moving_objects(), ..FrameMotion::STILL },
            mask: None,
            scalar_chain: gpu.caps.scalar_chain,
        };
        Ok(Renderer {
            gpu,
            scene: scene.clone(),
            settings: settings.clone(),
            gpu_scene,
            inputs,
            passes,
            driver,
            timing: Timing::Pipelined,
            scene_time: 0.0,
            previous_scene_time: None,
            mover_bounds,
            in_flight: VecDeque::new(),
            frames_in_flight: DEFAULT_FRAMES_IN_FLIGHT,
            frames_in_flight_max: 0,
        })
    }

    /// How many frames may be on the GPU at once (at least 1: each frame waits for the
    /// previous one).
    pub fn set_frames_in_flight(&mut self, frames: usize) {
        self.frames_in_flight = frames.max(1);
    }

    /// How many frames may be on the GPU at once.
    pub fn frames_in_flight_limit(&self) -> usize {
        self.frames_in_flight
    }

    /// The most frames that were on the GPU at once so far.
    pub fn frames_in_flight_max(&self) -> usize {
        self.frames_in_flight_max
    }

    /// The submission that ends the last frame rendered, what was appended to it included
    /// (none before the first, or once [`Renderer::finish`] has waited for every frame):
    /// done when the frame is. A caller that waits on it elsewhere need not submit anything
    /// of its own, which on some drivers (lavapipe) would block until the frame is done.
    pub fn last_submission(&self) -> Option<&wgpu::SubmissionIndex> {
        self.in_flight.back().map(|frame| &frame.submission)
    }

    /// Frames rendered so far.
    pub fn frame_index(&self) -> u64 {
        self.driver.frame_index()
    }

    /// The GPU this renderer draws on.
    pub fn gpu(&self) -> &Arc<Gpu> {
        &self.gpu
    }

    /// The settings the next frame renders with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Switches to new settings (technique, quality, radius, …) for the next frame. The
    /// passes hold every variant, so nothing is rebuilt; targets follow the next plan.
    pub fn set_settings(&mut self, settings: &Settings) -> Result<()> {
        settings.validate()?;
        if settings.stereo != self.settings.stereo {
            return Err(Error::input("the stereo mode cannot change on a running renderer"));
        }
        if settings.ao != self.settings.ao {
            // Accumulated occlusion of other settings is not this one's history.
            self.driver.reset_history();
        }
        self.settings = settings.clone();
        self.inputs.settings = chain_settings(settings);
        Ok(())
    }

    /// The headset's visibility mask, one view mask per eye (the runtime's or the
    /// profile's), or `None`. With the AO settings' `mask` on, the G-buffer draws it into
    /// depth first and every pass leaves the hidden pixels out; they stay black.
    pub fn set_visibility_mask(&mut self, mask: Option<VisibilityMask>) {
        self.inputs.mask = mask;
    }

    /// The visibility mask given ([`Renderer::set_visibility_mask`]).
    pub fn visibility_mask(&self) -> Option<&VisibilityMask> {
        self.inputs.mask.as_ref()
    }

    /// The share of each view's pixels the mask hid in the last frame (zeros without
    /// one, empty before the first frame).
    pub fn hidden_share(&self) -> &[f64] {
        self.driver.visibility().hidden_share()
    }

    /// The scene time (seconds) of the next frame: where animated objects are. The frame
    /// after it moves them from there (motion vectors), unless the history is reset.
    pub fn set_scene_time(&mut self, seconds: f64) {
        self.scene_time = if seconds.is_finite() { seconds } else { 0.0 };
    }

    /// The scene time of the next frame.
    pub fn scene_time(&self) -> f64 {
        self.scene_time
    }

    /// How the next frames are submitted and timed.
    pub fn set_timing(&mut self, timing: Timing) {
        self.timing = timing;
    }

    /// Whether the G-buffer draws both eyes in one multiview pass.
    pub fn uses_multiview(&self) -> bool {
        self.inputs.multiview
    }

    /// The plan for a frame of `views` layers that must produce `outputs`.
    pub fn plan(&self, views: u32, outputs: &[Resource]) -> Result<Plan> {
        let extensions: [&dyn std::any::Any; 3] = [&self.scene, &self.gpu_scene, &self.settings];
        self.driver.plan_uncached(&self.passes.all(), &self.inputs.params(&extensions), views, outputs, &[])
    }

    /// Renders one frame for `views` (two eyes, or one mono view) producing `outputs`
    /// and submits it without waiting for the GPU (see the module's notes on frames in
    /// flight). Only the passes the outputs need are recorded.
    pub fn render(&mut self, views: &[Eye], outputs: &[Resource]) -> Result<FrameReport> {
        self.record_and_submit(views, outputs, false, |_, _| {})
    }

    /// [`Renderer::render`], with `append` recording more commands (a headset's copy of
    /// the eyes, say) into the frame's last encoder, so that they go to the GPU in the
    /// frame's submission: a second submission would wait for the first on lavapipe.
    pub fn render_with(
        &mut self,
        views: &[Eye],
        outputs: &[Resource],
        append: impl FnOnce(&mut wgpu::CommandEncoder, &BTreeMap<Resource, LayeredTarget>),
    ) -> Result<FrameReport> {
        self.record_and_submit(views, outputs, false, append)
    }

    /// Renders one frame and waits for it: its GPU times are in [`FrameReport::gpu_ms`]
    /// (and with [`Timing::Serial`] each pass's wall-clock time in `wall_ms`). For
    /// measurements; frame loops use [`Renderer::render`].
    pub fn render_and_wait(&mut self, views: &[Eye], outputs: &[Resource]) -> Result<FrameReport> {
        let mut report = self.record_and_submit(views, outputs, true, |_, _| {})?;
        report.finished.extend(self.finish()?);
        if let Some(own) = report.finished.iter().find(|t| t.frame == report.frame) {
            report.gpu_ms = own.spans.clone();
        }
        Ok(report)
    }

    /// Waits until the GPU has finished every submitted frame and returns the GPU times
    /// that had not come back yet.
    pub fn finish(&mut self) -> Result<Vec<FrameTiming>> {
        self.gpu.wait_idle()?;
        self.in_flight.clear();
        Ok(self.driver.timer().finished())
    }

    /// Forgets the frames the GPU has finished (a non-blocking poll runs their
    /// completion callbacks).
    fn forget_finished_frames(&mut self) -> Result<()> {
        self.gpu.poll()?;
        self.in_flight.retain(|f| !f.done.load(Ordering::Acquire));
        Ok(())
    }

    /// Forgets frames the GPU has finished, then waits for the oldest ones until fewer
    /// than the allowed number are in flight.
    fn throttle(&mut self) -> Result<()> {
        self.forget_finished_frames()?;
        while self.in_flight.len() >= self.frames_in_flight {
            let oldest = self.in_flight.pop_front().expect("non-empty");
            self.gpu
                .device
                .poll(wgpu::PollType::Wait { submission_index: Some(oldest.submission), timeout: None })
                .map_err(|e| Error::Gpu(format!("waiting for frame: {e}")))?;
        }
        Ok(())
    }

    fn record_and_submit(
        &mut self,
        views: &[Eye],
        outputs: &[Resource],
        wait_each_pass: bool,
        append: impl FnOnce(&mut wgpu::CommandEncoder, &BTreeMap<Resource, LayeredTarget>),
    ) -> Result<FrameReport> {
        let plan = self.begin_frame(views, outputs)?;
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        let (cpu_encode_ms, mut wall_ms) = self.record_passes(&plan, views, &mut encoder, wait_each_pass)?;
        append(&mut encoder, &self.driver.targets().targets);
        let (frames_in_flight, last_wall_ms) = self.submit(encoder, wait_each_pass)?;
        if let (Some(ms), Some(last)) = (last_wall_ms, plan.names.last()) {
            wall_ms.push((last.to_string(), ms));
        }
        let frame = self.driver.frame_index();
        self.driver.end_frame(views);
        self.previous_scene_time = Some(self.scene_time);
        let finished = self.driver.timer().finished();
        self.gpu.take_error()?;
        Ok(FrameReport { frame, plan, gpu_ms: Vec::new(), cpu_encode_ms, wall_ms, frames_in_flight, finished })
    }

    /// Checks the views, waits until another frame may be in flight, plans the frame,
    /// allocates its targets and writes its uniforms.
    fn begin_frame(&mut self, views: &[Eye], outputs: &[Resource]) -> Result<Plan> {
        if views.is_empty() || views.len() > 2 {
            return Err(Error::input(format!("a frame has 1 or 2 views, not {}", views.len())));
        }
        self.throttle()?;
        let layers = views.len() as u32;
        self.update_motion(layers);
        self.inputs.second_layer = second_layer_visible(self.inputs.shell.as_ref(), views);
        // Borrowed field by field: the driver is changed while the passes and what they
        // consult are read.
        let Renderer { gpu, scene, gpu_scene, settings, driver, inputs, passes, .. } = self;
        let extensions: [&dyn std::any::Any; 3] = [&*scene, &*gpu_scene, &*settings];
        let params = inputs.params(&extensions);
        let plan = driver.plan(settings, &passes.all(), &params, layers, outputs, &[])?;
        let lighting = ViewLighting::new(scene, gpu_scene.anchor, views, settings);
        lighting.write(&gpu.queue, &gpu_scene.shading, views.len());
        driver.prepare(gpu, &plan, &params, &lighting.frame_lighting(), views);
        Ok(plan)
    }

    /// Records the plan's passes, each in a timestamp span; with [`Timing::Serial`] each
    /// pass but the last is submitted on its own (and with `wait_each_pass` waited for).
    /// Returns the CPU encode time and the wall-clock times of the passes waited for.
    fn record_passes(
        &mut self,
        plan: &Plan,
        views: &[Eye],
        encoder: &mut wgpu::CommandEncoder,
        wait_each_pass: bool,
    ) -> Result<(f64, Vec<(String, f64)>)> {
        let extensions: [&dyn std::any::Any; 3] = [&self.scene, &self.gpu_scene, &self.settings];
        let params = self.inputs.params(&extensions);
        let submission = match self.timing {
            Timing::Pipelined => Submission::OneEncoder,
            Timing::Serial => Submission::PerPass { wait: wait_each_pass },
        };
        let environment = Some((&self.gpu_scene.environment, &self.gpu_scene.sampler));
        let passes = self.passes.all();
        let recorded =
            self.driver.record(&self.gpu, encoder, &passes, plan, &params, views, environment, None, submission)?;
        let resolve_start = Instant::now();
        self.driver.timer().resolve(encoder);
        Ok((recorded.cpu_encode_ms + resolve_start.elapsed().as_secs_f64() * 1e3, recorded.wall_ms))
    }

    /// Submits the frame's last encoder without waiting for the GPU (unless serial timing
    /// waits for each pass: then also the wall-clock ms of the last one) and tracks it
    /// as in flight. Returns the frames in flight, this one included.
    fn submit(&mut self, encoder: wgpu::CommandEncoder, wait_each_pass: bool) -> Result<(usize, Option<f64>)> {
        // In flight: the frames the GPU has not finished as this one is handed over
        // (counted before the submit call, which on lavapipe returns only once the
        // previous submission has finished: wgpu chains submissions with semaphores
        // that Mesa 22.3 waits for on the CPU).
        self.forget_finished_frames()?;
        let frames_in_flight = self.in_flight.len() + 1;
        let submitted = Instant::now();
        let submission = self.gpu.queue.submit([encoder.finish()]);
        let mut last_wall_ms = None;
        if self.timing == Timing::Serial && wait_each_pass {
            self.gpu.wait_idle()?;
            last_wall_ms = Some(submitted.elapsed().as_secs_f64() * 1e3);
        }
        let done = Arc::new(AtomicBool::new(false));
        let signal = done.clone();
        self.gpu.queue.on_submitted_work_done(move || signal.store(true, Ordering::Release));
        self.in_flight.push_back(InFlight { submission, done });
        let frame = self.driver.frame_index();
        self.driver.timer().end_frame(frame)?;
        self.frames_in_flight_max = self.frames_in_flight_max.max(frames_in_flight);
        // Collect the times of earlier frames that finished meanwhile (never waits).
        self.gpu.poll()?;
        Ok((frames_in_flight, last_wall_ms))
    }

    /// Moves the animated objects to this frame's scene time (from the previous frame's,
    /// when there is a history of as many views) and finds the boxes around them.
    fn update_motion(&mut self, layers: u32) {
        if self.mover_bounds.is_empty() {
            return;
        }
        let has_history = self.driver.previous_views(layers).is_some();
        let previous = self.previous_scene_time.filter(|_| has_history);
        self.gpu_scene.set_time(&self.gpu.queue, &self.scene, self.scene_time, previous);
        let anchor = self.gpu_scene.anchor;
        let now = self.scene.node_transforms(self.scene_time);
        let before = previous.map(|t| self.scene.node_transforms(t));
        let mut movers = Vec::new();
        for (node, local) in &self.mover_bounds {
            for transforms in std::iter::once(&now).chain(before.as_ref()) {
                movers.push(MoverBox::of((local.min, local.max), &transforms[*node], anchor));
            }
        }
        self.inputs.motion.movers = movers;
    }

    /// The plan of the last frame, if one was rendered.
    pub fn last_plan(&self) -> Option<&Plan> {
        self.driver.last_plan()
    }

    /// The bytes per pixel the last frame's occlusion passes wrote and read, from their
    /// declared textures in the layout the chain had ([`Plan::occlusion_traffic`]).
    pub fn occlusion_traffic(&self) -> Option<PixelTraffic> {
        let ao = &self.settings.ao;
        let chain = ChainLayout::of(ao.technique.carries_light(), self.gpu.caps.scalar_chain);
        Some(self.last_plan()?.occlusion_traffic(chain, ao.resolution.is_half()))
    }

    /// Per pass, the right eye's tiles the AO chain and the composite computed rather than
    /// copied from the left eye in the last frame, read back from the GPU after it
    /// finished (blocking: for reports); empty when the right eye reuses nothing.
    pub fn right_eye_tiles(&self) -> Vec<RightEyeTiles> {
        RightEyeTiles::latest(&self.passes.all(), &self.gpu)
    }

    /// The right eye's occlusion pixels the last frame's march computed rather than
    /// copied from the left eye, (x, y) at occlusion resolution, with the march's counts
    /// (blocking: for debug images); `None` when the right eye reused nothing.
    pub fn right_eye_marched(&self) -> Option<(RightEyeTiles, Vec<[u32; 2]>)> {
        let listed = self.passes.ao_chain.iter().filter_map(|p| p.right_eye_listed(&self.gpu));
        listed.max_by_key(|(t, _)| t.frame)
    }

    /// The target a previous frame wrote, if that frame needed it (a named output: its
    /// texture as the last frame resolved it).
    pub fn target(&self, r: Resource) -> Option<&LayeredTarget> {
        let r = if r.is_alias() { self.last_plan()?.resolve(r)? } else { r };
        self.driver.targets().targets.get(&r)
    }

    /// A target a pass keeps itself from frame to frame (the temporal history), or one
    /// the graph allocated ([`Renderer::target`]).
    pub fn kept_target(&self, r: Resource) -> Option<LayeredTarget> {
        self.target(r).cloned().or_else(|| self.passes.all().iter().find_map(|p| p.kept_target(r)))
    }

    /// Raw bytes per layer of a resource the last frame produced.
    pub fn read_bytes(&self, r: Resource) -> Result<Vec<Vec<u8>>> {
        let target = self.kept_target(r).ok_or_else(|| Error::Gpu(format!("{} was not rendered", r.name())))?;
        read_layers(&self.gpu, &target)
    }

    /// Values per layer (channels interleaved) of a float or depth resource; the packed
    /// direct light decodes to rgba radiance (a = 0), and a target of a scalar AO chain
    /// reads as the four-channel one would (rgb 0, a AO).
    pub fn read_f32(&self, r: Resource) -> Result<Vec<Vec<f32>>> {
        let target = self.kept_target(r).ok_or_else(|| Error::Gpu(format!("{} was not rendered", r.name())))?;
        if target.format == passes::direct::DIRECT.format() {
            return Ok(decode_direct(read_layers(&self.gpu, &target)?));
        }
        let layers = read_layers_f32(&self.gpu, &target)?;
        if r.is_chain() && target.format == ChainLayout::Scalar.format() {
            return Ok(layers
                .into_iter()
                .map(|ao| ao.into_iter().flat_map(|a| [0.0, 0.0, 0.0, a]).collect())
                .collect());
        }
        Ok(layers)
    }
}

/// Each moving object's node with the bounds of its meshes in the node's frame.
fn mover_bounds(scene: &Scene, gpu_scene: &GpuScene) -> Vec<(usize, Aabb)> {
    gpu_scene
        .object_nodes
        .iter()
        .map(|&node| {
            let mut bounds = Aabb::EMPTY;
            for mesh in scene.meshes.iter().filter(|m| m.node == Some(node)) {
                mesh.positions.iter().filter(|p| p.is_finite()).for_each(|p| bounds.extend(mesh.origin + p.as_dvec3()));
            }
            if bounds.is_empty() {
                bounds.extend(DVec3::ZERO);
            }
            (node, bounds)
        })
        .collect()
}

/// The renderer's passes in their three groups.
struct RendererPasses {
    /// Before the AO chain (G-buffer, lights): [`passes::scene_passes`].
    scene: Vec<Box<dyn Pass>>,
    /// The engine's AO chain ([`ao_chain`]) over the G-buffer's depth and normals,
    /// with the renderer's SSDO among its techniques.
    ao_chain: Vec<Box<dyn Pass>>,
    /// After the AO chain (composite, tone mapping): [`passes::output_passes`].
    output: Vec<Box<dyn Pass>>,
}

impl RendererPasses {
    /// Every pass in execution order: the scene's, the AO chain, the outputs'.
    fn all(&self) -> Vec<&dyn Pass> {
        self.scene.iter().chain(&self.ao_chain).chain(&self.output).map(|p| p.as_ref()).collect()
    }
}

/// What the passes consult each frame besides the driver's frame number and history.
struct FrameInputs {
    /// What the engine's chain reads of the renderer's settings.
    settings: ChainSettings,
    /// Whether the scene has alpha-tested materials (GTAO's cards).
    alpha_cards: bool,
    /// The convex shell the scene's triangles bound, if they do: from inside it nothing
    /// lies behind the first depth layer (scene/shell.rs).
    shell: Option<crate::scene::shell::ConvexShell>,
    /// Whether this frame's views can see a surface behind another (not both inside
    /// `shell`): the depth peel runs only then.
    second_layer: bool,
    /// Where the scene's geometry was uploaded relative to.
    anchor: DVec3,
    /// Whether the G-buffer draws both eyes in one multiview pass.
    multiview: bool,
    /// What moves in the frame being rendered.
    motion: FrameMotion,
    /// The headset's visibility mask ([`Renderer::set_visibility_mask`]).
    mask: Option<VisibilityMask>,
    /// Whether the device writes the scalar chain's `R16Float` storage.
    scalar_chain: bool,
}

impl FrameInputs {
    /// The frame's parameters; the renderer's own passes find the scene, the uploaded
    /// scene and the settings in `extensions`.
    fn params<'a>(&'a self, extensions: &'a [&'a dyn std::any::Any]) -> FrameParams<'a> {
        FrameParams {
            settings: &self.settings,
            extensions,
            alpha_cards: self.alpha_cards,
            second_layer: self.second_layer,
            anchor: self.anchor,
            multiview: self.multiview,
            motion: &self.motion,
            mask: self.mask.as_ref(),
            scalar_chain: self.scalar_chain,
        }
    }
}

/// Whether `views` may see a surface behind another: not every eye inside the scene's
/// convex shell (scene/shell.rs), or the scene is none.
fn second_layer_visible(shell: Option<&crate::scene::shell::ConvexShell>, views: &[Eye]) -> bool {
    shell.is_none_or(|shell| !views.iter().all(|eye| shell.contains(eye.pose.position)))
}

/// What the engine's chain reads of the renderer's settings.
fn chain_settings(settings: &Settings) -> ChainSettings {
    ChainSettings {
        width: settings.profile.width,
        height: settings.profile.height,
        near: settings.near,
        ao: settings.ao.clone(),
    }
}
