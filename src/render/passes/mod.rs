//! One folder per pass: its Rust (`mod.rs`) and its WGSL. A pass declares, in one
//! builder chain, the textures it creates (constants with their size class and format),
//! what it reads and writes (its kernels' binding lists), what it provides under the
//! graph's named outputs, and whether it runs this frame; the graph decides which passes
//! run, and each records its GPU work when it does. [`scene_passes`], [`ao_chain`] and
//! [`output_passes`] list them in execution order.

pub mod blur;
pub mod composite;
pub mod direct;
pub mod fetch_only;
pub mod gbuffer;
pub mod gtao;
pub mod hbao;
pub mod occlusion;
pub mod peel;
pub mod rsm;
pub mod shadow;
pub mod ssao;
pub mod ssdo;
pub mod temporal;
pub mod tonemap;
pub mod upsample;

use crate::render::gpu::frame::ao_extent;
use crate::render::gpu::frame::FrameBuffers;
use crate::render::gpu::kernel::Bind;
use crate::render::gpu::scene::GpuScene;
use crate::render::gpu::targets::LayeredTarget;
use crate::render::gpu::timing::PassTimer;
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use crate::render::scene::Scene;
use crate::render::settings::Settings;
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

/// The renderer's passes before the AO chain, in execution order: the G-buffer, the
/// directional lights' maps and direct light, their bounce, and the second depth layer
/// SSDO may read. A new pass is its own folder, its `pub mod` line above and one entry
/// here, in [`ao_chain`] or in [`output_passes`]; a new technique also names itself in
/// `settings::Technique` (its command-line name).
pub fn scene_passes(gpu: &Gpu, scene: &Scene, gpu_scene: &GpuScene, frame: &FrameBuffers) -> Vec<Box<dyn Pass>> {
    // Directional lights' orthographic fits, shared by the shadow, direct and RSM passes.
    let light_space = Arc::new(shadow::LightSpace::new(gpu, scene, gpu_scene.anchor));
    vec![
        Box::new(gbuffer::GBufferPass::new(gpu, gpu_scene, frame)),
        Box::new(shadow::ShadowPass::new(gpu, gpu_scene, light_space.clone())),
        Box::new(direct::DirectLightPass::new(gpu, light_space.clone())),
        Box::new(rsm::RsmPass::new(gpu, light_space)),
        Box::new(peel::DepthPeelPass::new(gpu, gpu_scene, frame)),
    ]
}

/// The AO chain, in execution order: each technique (one runs), then `light_gathering`
/// (the renderer's SSDO, which reads the renderer's direct light), temporal accumulation,
/// the denoise and the upsampling to full resolution. It reads the depth and normals and
/// provides [`crate::render::graph::OCCLUSION`] and
/// [`crate::render::graph::FINAL_AO`]: the [`crate::render::ao::AoEngine`] owns it.
pub fn ao_chain(gpu: &Gpu, light_gathering: Vec<Box<dyn Pass>>) -> Vec<Box<dyn Pass>> {
    let mut chain: Vec<Box<dyn Pass>> =
        vec![Box::new(ssao::pass(gpu)), Box::new(hbao::pass(gpu)), Box::new(gtao::GtaoPass::new(gpu))];
    chain.extend(light_gathering);
    chain.push(Box::new(fetch_only::pass(gpu)));
    chain.push(Box::new(temporal::TemporalPass::new(gpu)));
    chain.push(Box::new(blur::BlurPass::new(gpu)));
    chain.push(Box::new(upsample::UpsamplePass::new(gpu)));
    chain
}

/// The renderer's passes after the AO chain: the HDR composite and the tone mapping.
pub fn output_passes(gpu: &Gpu) -> Vec<Box<dyn Pass>> {
    vec![Box::new(composite::CompositePass::new(gpu)), Box::new(tonemap::TonemapPass::new(gpu))]
}

/// What passes may consult when declaring themselves for a frame.
pub struct FrameSetup<'a> {
    /// The scene being rendered; `None` in the AO engine, which has none (its passes
    /// never ask: [`FrameSetup::scene`]).
    pub scene: Option<&'a Scene>,
    /// The f64 origin that view-from-anchored matrices start from (the scene's anchor;
    /// the world origin for a host's views).
    pub anchor: glam::DVec3,
    /// This frame's settings.
    pub settings: &'a Settings,
    /// 2 for stereo, 1 for a mono view.
    pub views: u32,
    /// Whether the G-buffer draws both layers in one multiview pass.
    pub multiview: bool,
    /// Frames this renderer has rendered before this one (turns sampling patterns).
    pub frame_index: u64,
    /// This frame's views (empty when only planning).
    pub current_views: &'a [crate::render::stereo::Eye],
    /// The previous frame's views, when it had as many as this one (temporal reuse).
    pub previous_views: Option<&'a [crate::render::stereo::Eye]>,
    /// What moves this frame ([`FrameMotion::STILL`] in a still scene).
    pub motion: &'a FrameMotion,
}

/// What moved since the previous frame, for temporal accumulation.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameMotion {
    /// Whether [`gbuffer::MOTION`] holds each pixel's motion this frame (the scene
    /// moves, or a host handed its motion vectors to the AO engine).
    pub vectors: bool,
    /// Boxes around every moving object, where it is and where it was in the previous
    /// frame: the AO of what lies within the AO radius of them changes although the
    /// surface itself does not move.
    pub movers: Vec<MoverBox>,
    /// What turns a motion texel's xy into the uv offset to the previous frame
    /// (1, 1 for the G-buffer's).
    pub uv_scale: [f32; 2],
    /// Whether the motion's z holds the change in distance and w its validity (the
    /// G-buffer's); a host's 2D vectors leave the distance to the eyes' motion.
    pub with_distance: bool,
}

/// An oriented box around a moving object (`MoverBox` of temporal.wgsl): a point p of
/// the anchored frame lies inside when |rows · (p, 1)| ≤ half_extents on each axis.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MoverBox {
    /// The box's frame from the anchored world frame: three rows of an affine map whose
    /// rotation is orthonormal, so distances stay in metres.
    pub box_from_anchored: [[f32; 4]; 3],
    /// Half the box's size along its axes (metres); w unused.
    pub half_extents: [f32; 4],
}

impl MoverBox {
    /// The box `local` (bounds in a node's frame) placed by `world` (world from local,
    /// rotation and scale without shear), relative to `anchor`.
    pub fn of(local: &crate::render::scene::Aabb, world: &glam::DMat4, anchor: glam::DVec3) -> MoverBox {
        let m = glam::DMat3::from_mat4(*world);
        let axes = [m.x_axis, m.y_axis, m.z_axis];
        let half = local.size() * 0.5;
        let centre = world.transform_point3(local.center()) - anchor;
        let mut rows = [[0.0f32; 4]; 3];
        let mut half_extents = [0.0f32; 4];
        for (i, axis) in axes.iter().enumerate() {
            let length = axis.length();
            let unit = if length > 0.0 && length.is_finite() { *axis / length } else { glam::DVec3::ZERO };
            rows[i] = [unit.x as f32, unit.y as f32, unit.z as f32, -unit.dot(centre) as f32];
            half_extents[i] = (half[i] * length) as f32;
        }
        MoverBox { box_from_anchored: rows, half_extents }
    }
}

impl FrameMotion {
    /// Nothing moves but the eyes.
    pub const STILL: FrameMotion =
        FrameMotion { vectors: false, movers: Vec::new(), uv_scale: [1.0; 2], with_distance: true };
}

impl Default for FrameMotion {
    fn default() -> Self {
        FrameMotion::STILL
    }
}

/// Everything a pass records with.
pub struct FrameContext<'a> {
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
    pub frame: &'a FrameBuffers,
    /// The scene uploaded to the GPU (`None` in the AO engine: [`FrameContext::gpu_scene`]).
    pub scene: Option<&'a GpuScene>,
    /// Timestamp scopes around each pass.
    pub timer: &'a PassTimer,
    /// What the passes were declared with.
    pub setup: &'a FrameSetup<'a>,
}

impl<'a> FrameSetup<'a> {
    /// The scene, for the renderer's own passes (G-buffer, lights, composite), which run
    /// only in the renderer, where there is one.
    pub fn scene(&self) -> &'a Scene {
        self.scene.expect("a scene pass runs only in the renderer, which has a scene")
    }
}

impl<'a> FrameContext<'a> {
    /// The uploaded scene, for the renderer's raster passes (see [`FrameSetup::scene`]).
    pub fn gpu_scene(&self) -> &'a GpuScene {
        self.scene.expect("a scene pass runs only in the renderer, which has a scene")
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
            let placeholder = self.placeholders.get(&r.format()).expect("the renderer makes each unbound format's");
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

    /// [`FrameContext::bind`], with the entries that read or write a named resource
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
                Bind::Lights => self.frame.lights.as_entire_binding(),
                Bind::Environment => wgpu::BindingResource::TextureView(&self.gpu_scene().environment),
                Bind::EnvironmentSampler => wgpu::BindingResource::Sampler(&self.gpu_scene().sampler),
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
        let p = &self.setup.settings.profile;
        (p.width, p.height, self.setup.views)
    }

    /// Width × height × layers of the quads of 2×2 full-res pixels (rounded up), for the
    /// passes that work one quad per invocation (upsample, composite).
    pub fn quad_extent(&self) -> (u32, u32, u32) {
        let (width, height, layers) = self.extent();
        (width.div_ceil(2), height.div_ceil(2), layers)
    }

    /// Width × height × layers of the occlusion targets (half size with half-res).
    pub fn ao_extent(&self) -> (u32, u32, u32) {
        let p = &self.setup.settings.profile;
        let (w, h) = ao_extent(p.width, p.height, self.setup.settings.ao.half_res);
        (w, h, self.setup.views)
    }
}

/// Records one pass inside its timestamp span.
pub fn record(pass: &dyn Pass, ctx: &mut FrameContext) {
    let span = ctx.timer.begin(ctx.encoder, ctx.decl.name);
    pass.record(ctx);
    ctx.timer.end(ctx.encoder, span);
}

/// One pass of the frame graph: declares what it reads and writes for a frame, and
/// records its GPU work when the plan keeps it. Send and Sync, so that an embedder may
/// keep the AO engine in a multi-threaded app's state.
pub trait Pass: Send + Sync {
    /// What the pass reads and writes this frame, and whether it runs at all.
    fn declare(&self, setup: &FrameSetup) -> PassDecl;
    /// Records the pass's commands into the frame's encoder.
    fn record(&self, ctx: &mut FrameContext);
    /// A target the pass keeps itself from one frame to the next (the temporal
    /// history), for inspection; the graph allocates every other target.
    fn kept_target(&self, _r: Resource) -> Option<LayeredTarget> {
        None
    }
}
