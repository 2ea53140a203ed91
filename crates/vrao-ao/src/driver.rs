//! The one frame driver: what runs a frame graph, for the AO engine and for vrao's
//! renderer alike. It keeps the plan while nothing it depends on changes, allocates the
//! plan's targets, writes the frame's uniforms, records the kept passes (each in its
//! timestamp span) and remembers the views a frame had for the next one's temporal reuse.
//! Its owner decides what the passes are, what they may consult ([`FrameParams`]) and
//! when the encoder is submitted.

use crate::error::Result;
use crate::gpu::timing::{PassTimer, SpanRecorder};
use crate::gpu::uniforms::{FrameLighting, FrameUniforms};
use crate::gpu::visibility::VisibilityMaps;
use crate::gpu::Gpu;
use crate::graph::{self, Plan, Resource};
use crate::graph_targets::GraphTargets;
use crate::passes::{self, ChainSettings, DeclareContext, FrameMotion, Pass, RecordContext};
use crate::resource::ChainLayout;
use crate::stereo::Eye;
use glam::DVec3;
use std::any::Any;
use std::time::Instant;

/// What a frame's passes may consult besides the driver's own state (its frame number and
/// the previous frame's views).
#[derive(Clone, Copy)]
pub struct FrameParams<'a> {
    /// The chain's settings: each view's size, the near plane, the AO settings.
    pub settings: &'a ChainSettings,
    /// What the owner's own passes read, found by type ([`DeclareContext::extension`]).
    pub extensions: &'a [&'a dyn Any],
    /// Whether the normals' w marks alpha-tested cards ([`DeclareContext::alpha_cards`]).
    pub alpha_cards: bool,
    /// Whether a second depth layer can be had ([`DeclareContext::second_layer`]).
    pub second_layer: bool,
    /// The f64 origin of the anchored frame.
    pub anchor: DVec3,
    /// Whether a raster pass draws both layers at once.
    pub multiview: bool,
    /// What moves this frame.
    pub motion: &'a FrameMotion,
    /// The views' visibility mask (a headset's lens), applied when the settings' `mask`
    /// is on and it has one mask per view.
    pub mask: Option<&'a crate::visibility::VisibilityMask>,
    /// Whether the device writes `R16Float` storage textures
    /// ([`Capabilities::scalar_chain`](crate::gpu::Capabilities::scalar_chain)): then the
    /// chain of a technique without light is single-channel.
    pub scalar_chain: bool,
}

/// How the passes of one frame reach the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Submission {
    /// Every pass into the caller's encoder, which the caller submits.
    OneEncoder,
    /// Each pass but the last submitted on its own (true per-pass times where the device
    /// finishes one submission before the next one's timestamps, as lavapipe does), and
    /// waited for when `wait` is set (then its wall-clock time is reported). A measurement
    /// tool's (the `measurement` feature), never a host's: it stalls the frame.
    #[cfg(feature = "measurement")]
    PerPass {
        /// Wait for each pass and report its wall-clock milliseconds.
        wait: bool,
    },
}

/// What recording a frame cost on the CPU, and the passes' wall-clock times when
/// `Submission::PerPass` (the `measurement` feature) waited for them.
#[derive(Clone, Debug, Default)]
pub struct Recorded {
    /// CPU milliseconds spent encoding the passes.
    pub cpu_encode_ms: f64,
    /// (pass, wall-clock ms from its submission to its completion).
    pub wall_ms: Vec<(String, f64)>,
}

/// What a frame's plan depends on besides the passes: the owner's settings `K`, the
/// layers, the outputs and imports, and the temporal pass's state.
#[derive(Clone, PartialEq)]
struct PlanKey<K> {
    settings: K,
    layers: u32,
    outputs: Vec<Resource>,
    imported: Vec<Resource>,
    /// The temporal pass swaps its history targets every frame and reads them only with
    /// a previous frame of as many views.
    odd_frame: bool,
    has_history: bool,
    /// Whether a second depth layer can be had (the renderer's views may leave a convex
    /// scene's inside from one frame to the next).
    second_layer: bool,
}

/// Runs one frame graph frame after frame: plan cache, targets, uniforms, record loop and
/// timer. `K` is what the owner's plan depends on (its settings).
pub struct GraphDriver<K> {
    targets: GraphTargets,
    uniforms: FrameUniforms,
    visibility: VisibilityMaps,
    timer: PassTimer,
    plan_cache: Option<(PlanKey<K>, Plan)>,
    frame_index: u64,
    previous_views: Vec<Eye>,
}

impl<K: Clone + PartialEq> GraphDriver<K> {
    /// A driver timing its passes with `timer`.
    pub fn new(gpu: &Gpu, timer: PassTimer) -> Self {
        GraphDriver {
            targets: GraphTargets::default(),
            uniforms: FrameUniforms::new(&gpu.device),
            visibility: VisibilityMaps::new(gpu),
            timer,
            plan_cache: None,
            frame_index: 0,
            previous_views: Vec::new(),
        }
    }

    /// Frames driven so far.
    pub fn frame_index(&self) -> u64 {
        self.frame_index
    }

    /// The previous frame's views, when it had `layers` of them (temporal reuse).
    pub fn previous_views(&self, layers: u32) -> Option<&[Eye]> {
        (self.previous_views.len() == layers as usize).then_some(&self.previous_views[..])
    }

    /// Forgets the previous frame: temporal accumulation starts afresh.
    pub fn reset_history(&mut self) {
        self.previous_views.clear();
    }

    /// The frame's uniform buffers (a raster pass binds them when it is made).
    pub fn uniforms(&self) -> &FrameUniforms {
        &self.uniforms
    }

    /// The visibility mask and foveation map of the last prepared frame.
    pub fn visibility(&self) -> &VisibilityMaps {
        &self.visibility
    }

    /// The targets, placeholders and imported textures.
    pub fn targets(&self) -> &GraphTargets {
        &self.targets
    }

    /// The targets, to import a host's textures into.
    pub fn targets_mut(&mut self) -> &mut GraphTargets {
        &mut self.targets
    }

    /// The timestamp spans of the frames in flight.
    pub fn timer(&mut self) -> &mut PassTimer {
        &mut self.timer
    }

    /// The last frame's plan.
    pub fn last_plan(&self) -> Option<&Plan> {
        self.plan_cache.as_ref().map(|(_, plan)| plan)
    }

    /// What the passes consult this frame: `params` with the driver's frame number and
    /// history, for `views` (empty when only planning) of `layers` layers.
    pub fn setup<'a>(&'a self, params: &FrameParams<'a>, views: &'a [Eye], layers: u32) -> DeclareContext<'a> {
        DeclareContext {
            extensions: params.extensions,
            alpha_cards: params.alpha_cards,
            second_layer: params.second_layer,
            anchor: params.anchor,
            settings: params.settings,
            views: layers,
            multiview: params.multiview,
            frame_index: self.frame_index,
            current_views: views,
            previous_views: self.previous_views(layers),
            motion: params.motion,
            chain: ChainLayout::of(params.settings.ao.technique.carries_light(), params.scalar_chain),
        }
    }

    /// A plan for `passes` that produces `outputs` from `imported`, not cached.
    pub fn plan_uncached(
        &self,
        passes: &[&dyn Pass],
        params: &FrameParams,
        layers: u32,
        outputs: &[Resource],
        imported: &[Resource],
    ) -> Result<Plan> {
        let setup = self.setup(params, &[], layers);
        let decls: Vec<_> = passes.iter().map(|p| p.declare(&setup)).collect();
        graph::plan(&decls, outputs, imported)
    }

    /// This frame's plan: the last one while `settings`, the layers, outputs and imports
    /// and the temporal state are as they were, a new one otherwise.
    pub fn plan(
        &mut self,
        settings: &K,
        passes: &[&dyn Pass],
        params: &FrameParams,
        layers: u32,
        outputs: &[Resource],
        imported: &[Resource],
    ) -> Result<Plan> {
        let key = PlanKey {
            settings: settings.clone(),
            layers,
            outputs: outputs.to_vec(),
            imported: imported.to_vec(),
            odd_frame: self.frame_index % 2 == 1,
            second_layer: params.second_layer,
            has_history: self.previous_views(layers).is_some(),
        };
        if let Some((cached, plan)) = &self.plan_cache {
            if *cached == key {
                return Ok(plan.clone());
            }
        }
        let plan = self.plan_uncached(passes, params, layers, outputs, imported)?;
        self.plan_cache = Some((key, plan.clone()));
        Ok(plan)
    }

    /// Allocates the plan's targets at this frame's sizes and writes the frame's uniforms.
    pub fn prepare(&mut self, gpu: &Gpu, plan: &Plan, params: &FrameParams, lighting: &FrameLighting, views: &[Eye]) {
        let layers = views.len() as u32;
        let mut targets = std::mem::take(&mut self.targets);
        targets.allocate(gpu, plan, &self.setup(params, &[], layers));
        self.targets = targets;
        self.uniforms.update(&gpu.queue, lighting, views, params.settings);
        self.uniforms.update_ao(&gpu.queue, params.settings, self.frame_index);
        self.visibility.update(gpu, params.mask, params.settings, views);
    }

    /// Records the plan's passes into `encoder`, each in a span of `spans` (the driver's
    /// own timer when `None`); `environment` is what [`crate::gpu::kernel::Bind::Environment`]
    /// binds. With `Submission::PerPass` (the `measurement` feature) each pass but the last
    /// is submitted on its own.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        passes: &[&dyn Pass],
        plan: &Plan,
        params: &FrameParams,
        views: &[Eye],
        environment: Option<(&wgpu::TextureView, &wgpu::Sampler)>,
        spans: Option<&dyn SpanRecorder>,
        submission: Submission,
    ) -> Result<Recorded> {
        let setup = self.setup(params, views, views.len() as u32);
        let spans = spans.unwrap_or(&self.timer);
        let mut recorded = Recorded::default();
        for (step, (&index, name)) in plan.run.iter().zip(&plan.names).enumerate() {
            let encode_start = Instant::now();
            let mut ctx = RecordContext {
                gpu,
                encoder: &mut *encoder,
                targets: &self.targets.targets,
                placeholders: &self.targets.placeholders,
                decl: &plan.decls[step],
                frame: &self.uniforms,
                visibility: &self.visibility,
                environment,
                timer: spans,
                setup: &setup,
            };
            passes::record(passes[index], &mut ctx);
            recorded.cpu_encode_ms += encode_start.elapsed().as_secs_f64() * 1e3;
            // Without the measurement feature every pass goes into the caller's encoder.
            #[cfg(not(feature = "measurement"))]
            let _ = (submission, name);
            #[cfg(feature = "measurement")]
            if let (Submission::PerPass { wait }, false) = (submission, step + 1 == plan.run.len()) {
                let finished = std::mem::replace(encoder, gpu.device.create_command_encoder(&Default::default()));
                let submitted = Instant::now();
                gpu.queue.submit([finished.finish()]);
                if wait {
                    gpu.wait_idle()?;
                    recorded.wall_ms.push((name.to_string(), submitted.elapsed().as_secs_f64() * 1e3));
                }
            }
        }
        Ok(recorded)
    }

    /// Closes the frame: the next one counts on from it and reuses its `views`.
    pub fn end_frame(&mut self, views: &[Eye]) {
        self.frame_index += 1;
        self.previous_views = views.to_vec();
    }
}
