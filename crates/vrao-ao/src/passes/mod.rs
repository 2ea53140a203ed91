//! One folder per pass: its Rust (`mod.rs`) and its WGSL. A pass declares, in one
//! builder chain, the textures it creates (constants with their size class and format),
//! what it reads and writes (its kernels' binding lists), what it provides under the
//! graph's named outputs, and whether it runs this frame; the graph decides which passes
//! run, and each records its GPU work when it does. [`ao_chain`] lists the engine's in
//! execution order; a renderer adds its own passes around them through the same [`Pass`]
//! trait (vrao-render's G-buffer, lights, SSDO and composite).

pub(crate) mod blur;
#[cfg(feature = "measurement")]
pub(crate) mod fetch_only;
pub(crate) mod gtao;
pub(crate) mod hbao;
pub(crate) mod indirect_list;
pub(crate) mod inputs;
pub(crate) mod occlusion;
pub(crate) mod right_eye_list;
pub(crate) mod ssao;
pub(crate) mod ssdo;
pub(crate) mod temporal;
pub(crate) mod upsample;

pub(crate) use crate::frame::{ChainSettings, DeclareContext, FrameMotion, MoverBox};
use crate::gpu::kernel::Bind;
use crate::gpu::layered_target::LayeredTarget;
use crate::gpu::timing::SpanRecorder;
use crate::gpu::uniforms::{ao_extent, FrameUniforms};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::technique::{Technique, TechniqueKind, TECHNIQUES};
use std::collections::{BTreeMap, HashMap};

/// The engine's pass of `technique` (the table says which have one:
/// `TechniqueEntry::engine_pass`).
fn engine_pass(gpu: &Gpu, technique: Technique) -> Option<Box<dyn Pass>> {
    let pass: Box<dyn Pass> = match technique {
        Technique::Ssao => Box::new(ssao::pass(gpu)),
        Technique::Hbao => Box::new(hbao::pass(gpu)),
        Technique::Gtao => Box::new(gtao::GtaoPass::new(gpu)),
        Technique::Ssdo | Technique::SsdoBounce => Box::new(ssdo::SsdoPass::new(gpu, technique)),
        #[cfg(feature = "measurement")]
        Technique::FetchOnly => Box::new(fetch_only::pass(gpu)),
        _ => return None,
    };
    debug_assert!(technique.entry().engine_pass, "{technique:?} has an engine pass the table does not list");
    Some(pass)
}

/// The AO chain, in execution order: each technique of the table that has a pass (one
/// runs; `TECHNIQUES`), then `light_gathering`
/// (a renderer's light-gathering technique, such as vrao-render's point-sampled SSDO), temporal
/// accumulation, the denoise and the upsampling to full resolution. It reads
/// [`inputs::DEPTH`] and [`inputs::NORMALS`] and provides [`crate::graph::OCCLUSION`] and
/// [`crate::graph::FINAL_AO`].
pub fn ao_chain(gpu: &Gpu, light_gathering: Vec<Box<dyn Pass>>) -> Vec<Box<dyn Pass>> {
    let mut chain: Vec<Box<dyn Pass>> = Vec::new();
    let mut light_gathering = Some(light_gathering);
    for entry in &TECHNIQUES {
        match engine_pass(gpu, entry.technique) {
            Some(pass) => chain.push(pass),
            // The renderer's light-gathering passes take the table's place for them.
            None if entry.kind == TechniqueKind::LightGathering => {
                chain.extend(light_gathering.take().into_iter().flatten())
            }
            None => {}
        }
    }
    chain.push(Box::new(temporal::TemporalPass::new(gpu)));
    chain.push(Box::new(blur::BlurPass::new(gpu)));
    chain.push(Box::new(upsample::UpsamplePass::new(gpu)));
    chain
}

/// Everything a pass records with.
pub struct RecordContext<'a> {
    /// The device and queue.
    pub gpu: &'a Gpu,
    /// The encoder the pass records into (with serial timing, a fresh one per pass).
    pub encoder: &'a mut wgpu::CommandEncoder,
    /// The targets the graph allocated for this frame.
    pub targets: &'a BTreeMap<Resource, LayeredTarget>,
    /// 1×1 stand-ins, by format, for what a binding list names but the pass does not
    /// read this frame ([`PassDecl::unbind`]).
    pub placeholders: &'a HashMap<wgpu::TextureFormat, LayeredTarget>,
    /// This pass's declaration for the frame, named outputs resolved.
    pub decl: &'a PassDecl,
    /// The frame's uniform and light buffers.
    pub frame: &'a FrameUniforms,
    /// The visibility mask and foveation map (bind group 1 of every kernel).
    pub visibility: &'a crate::gpu::visibility::VisibilityMaps,
    /// An environment map and its sampler for [`Bind::Environment`] and
    /// [`Bind::EnvironmentSampler`] (a renderer's; `None` in the AO engine).
    pub environment: Option<(&'a wgpu::TextureView, &'a wgpu::Sampler)>,
    /// Timestamp scopes around each pass.
    pub timer: &'a dyn SpanRecorder,
    /// What the passes were declared with.
    pub setup: &'a DeclareContext<'a>,
}

impl<'a> RecordContext<'a> {
    /// The environment a renderer bound ([`RecordContext::environment`]).
    fn environment(&self) -> (&'a wgpu::TextureView, &'a wgpu::Sampler) {
        self.environment.expect("only a renderer's passes bind an environment, and it provides one")
    }

    /// The target of a resource the graph allocated for this frame (a named output: the
    /// texture it stands for at this pass).
    pub fn target(&self, r: Resource) -> &'a LayeredTarget {
        let r = self.decl.resolve(r);
        self.targets.get(&r).unwrap_or_else(|| panic!("{} was not allocated; the pass did not declare it", r.name()))
    }

    /// The array view of a resource's target, for a bind group (a placeholder's when the
    /// pass does not read it this frame).
    pub fn view(&self, r: Resource) -> wgpu::BindingResource<'a> {
        if self.decl.unbound.contains(&r) {
            let placeholder = self
                .placeholders
                .get(&r.format_in(self.setup.chain))
                .expect("the renderer makes each unbound format's");
            return wgpu::BindingResource::TextureView(&placeholder.array_view);
        }
        wgpu::BindingResource::TextureView(&self.target(r).array_view)
    }

    /// The resources of a binding list, in its order; `own` fills its [`Bind::Own`]
    /// entries, in order.
    pub fn bind<'b>(&self, binds: &[Bind], own: &[wgpu::BindingResource<'b>]) -> Vec<wgpu::BindingResource<'b>>
    where
        'a: 'b,
    {
        self.bind_overriding(binds, own, &[])
    }

    /// [`RecordContext::bind`], with the entries that read or write a named resource
    /// bound to another view of it instead (the right eye's dispatch of the stereo reuse
    /// writes layer 1 alone). Every override must name a resource of the list.
    pub fn bind_overriding<'b>(
        &self,
        binds: &[Bind],
        own: &[wgpu::BindingResource<'b>],
        overrides: &[(Resource, wgpu::BindingResource<'b>)],
    ) -> Vec<wgpu::BindingResource<'b>>
    where
        'a: 'b,
    {
        debug_assert!(
            overrides
                .iter()
                .all(|(r, _)| binds.iter().any(|b| matches!(*b, Bind::Read(x) | Bind::Write(x) if x == *r))),
            "{}: an override names a resource the binding list does not",
            self.decl.name
        );
        let mut own = own.iter();
        let resources: Vec<_> = binds
            .iter()
            .map(|bind| match *bind {
                Bind::Read(r) | Bind::Write(r) if overrides.iter().any(|(x, _)| *x == r) => {
                    overrides.iter().find(|(x, _)| *x == r).expect("checked by the guard").1.clone()
                }
                Bind::Frame => self.frame.frame.as_entire_binding(),
                Bind::AoParams => self.frame.ao.as_entire_binding(),
                Bind::SampleKernel => self.frame.kernel.as_entire_binding(),
                Bind::Environment => wgpu::BindingResource::TextureView(self.environment().0),
                Bind::EnvironmentSampler => wgpu::BindingResource::Sampler(self.environment().1),
                Bind::GatherSampler => wgpu::BindingResource::Sampler(&self.gpu.gather_sampler),
                Bind::Read(r) | Bind::Write(r) => self.view(r),
                Bind::Own(_) => own.next().expect("one own resource per Bind::Own").clone(),
            })
            .collect();
        debug_assert!(own.next().is_none(), "{}: more own resources than Bind::Own entries", self.decl.name);
        resources
    }

    /// A one-layer array view of `layer` of a resource's target (the stereo reuse binds
    /// the left eye's layer for the right eye's dispatch).
    pub fn layer_view(&self, r: Resource, layer: u32) -> wgpu::TextureView {
        self.target(r).texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(r.name()),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            base_array_layer: layer,
            array_layer_count: Some(1),
            ..Default::default()
        })
    }

    /// Width × height × layers of this frame's full-resolution targets.
    pub fn extent(&self) -> (u32, u32, u32) {
        let s = self.setup.settings;
        (s.width, s.height, self.setup.views)
    }

    /// Width × height × layers of the quads of 2×2 full-res pixels (rounded up), for the
    /// passes that work one quad per invocation (upsample, composite).
    pub fn quad_extent(&self) -> (u32, u32, u32) {
        let (width, height, layers) = self.extent();
        (width.div_ceil(2), height.div_ceil(2), layers)
    }

    /// Width × height × layers of the occlusion targets (half size with half-res).
    pub fn ao_extent(&self) -> (u32, u32, u32) {
        let s = self.setup.settings;
        let (w, h) = ao_extent(s.width, s.height, s.ao.resolution.is_half());
        (w, h, self.setup.views)
    }
}

/// Records one pass inside its timestamp span.
pub fn record(pass: &dyn Pass, ctx: &mut RecordContext) {
    let span = ctx.timer.begin(ctx.encoder, ctx.decl.name);
    pass.record(ctx);
    ctx.timer.end(ctx.encoder, span);
}

/// One pass of the frame graph: declares what it reads and writes for a frame, and
/// records its GPU work when the plan keeps it. Send and Sync, so that an embedder may
/// keep the AO engine in a multi-threaded app's state.
pub trait Pass: Send + Sync {
    /// What the pass reads and writes this frame, and whether it runs at all.
    fn declare(&self, setup: &DeclareContext) -> PassDecl;
    /// Records the pass's commands into the frame's encoder.
    fn record(&self, ctx: &mut RecordContext);
    /// A target the pass keeps itself from one frame to the next (the temporal
    /// history), for inspection; the graph allocates every other target.
    fn kept_target(&self, _r: Resource) -> Option<LayeredTarget> {
        None
    }
    /// The right eye's tiles the pass computed in the last frame it recorded, read back
    /// from the GPU (blocking; for reports, never inside a frame): `None` for a pass
    /// whose right eye does not reuse the left eye's work through a list.
    fn right_eye_tiles(&self, _gpu: &Gpu) -> Option<RightEyeTiles> {
        None
    }
    /// [`Pass::right_eye_tiles`] with the items the right eye computed, (x, y) at
    /// occlusion resolution (blocking; for the debug image of what the right eye marched).
    fn right_eye_listed(&self, _gpu: &Gpu) -> Option<(RightEyeTiles, Vec<[u32; 2]>)> {
        None
    }
}

/// How much of the right eye a pass computed rather than copied from the left eye, in
/// tiles (workgroups of 64 occlusion pixels): the same count on every machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RightEyeTiles {
    /// The pass (its span's name).
    pub pass: &'static str,
    /// Tiles the right eye's indirect dispatch ran: its listed items (the pixels, or
    /// quads of 2×2, the left eye cannot give), 64 to a tile.
    pub computed: u32,
    /// Tiles of the right eye's image (8×8 items each): what the left eye dispatches.
    pub total: u32,
    /// The items the right eye computed (pixels, or quads for the upsampling).
    pub items: u32,
    /// The frame they were counted in (`DeclareContext::frame_index`): of several
    /// passes, the one that ran last counted the frame's.
    pub frame: u64,
}

impl RightEyeTiles {
    /// The counts of the passes in `passes` that ran in the latest frame any of them
    /// counted (older counts are of passes a later frame left out).
    pub fn latest(passes: &[&dyn Pass], gpu: &Gpu) -> Vec<RightEyeTiles> {
        let all: Vec<RightEyeTiles> = passes.iter().filter_map(|p| p.right_eye_tiles(gpu)).collect();
        let latest = all.iter().map(|t| t.frame).max();
        all.into_iter().filter(|t| Some(t.frame) == latest).collect()
    }

    /// `computed` as a share of `total` (0..=1).
    pub fn share(&self) -> f64 {
        f64::from(self.computed) / f64::from(self.total.max(1))
    }
}
