//! One file per pass. A pass declares what it reads and writes for this frame (the
//! graph decides whether it runs) and records its GPU work when it does.

pub mod blur;
pub mod composite;
pub mod direct;
pub mod gbuffer;
pub mod occlusion;
pub mod peel;
pub mod rsm;
pub mod shadow;
pub mod ssdo;
pub mod temporal;
pub mod tonemap;
pub mod upsample;

use crate::render::gpu::frame::ao_extent;
use crate::render::gpu::frame::FrameBuffers;
use crate::render::gpu::scene::GpuScene;
use crate::render::gpu::targets::LayeredTarget;
use crate::render::gpu::timing::PassTimer;
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use crate::render::scene::Scene;
use crate::render::settings::{Settings, Technique};
use std::collections::BTreeMap;

/// What passes may consult when declaring themselves for a frame.
pub struct FrameSetup<'a> {
    /// The scene being rendered.
    pub scene: &'a Scene,
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
}

/// Everything a pass records with.
pub struct FrameContext<'a> {
    /// The device and queue.
    pub gpu: &'a Gpu,
    /// The encoder the pass records into (with serial timing, a fresh one per pass).
    pub encoder: &'a mut wgpu::CommandEncoder,
    /// The targets the graph allocated for this frame.
    pub targets: &'a BTreeMap<Resource, LayeredTarget>,
    /// The frame's uniform and light buffers.
    pub frame: &'a FrameBuffers,
    /// The scene uploaded to the GPU.
    pub scene: &'a GpuScene,
    /// Timestamp scopes around each pass.
    pub timer: &'a PassTimer,
    /// What the passes were declared with.
    pub setup: &'a FrameSetup<'a>,
}

impl<'a> FrameContext<'a> {
    /// The target of a resource the graph allocated for this frame.
    pub fn target(&self, r: Resource) -> &'a LayeredTarget {
        self.targets.get(&r).unwrap_or_else(|| panic!("{} was not allocated; the pass did not declare it", r.name()))
    }

    /// The array view of a resource's target, for a bind group.
    pub fn view(&self, r: Resource) -> wgpu::BindingResource<'a> {
        wgpu::BindingResource::TextureView(&self.target(r).array_view)
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

/// The occlusion the blur reads: the technique's own, or its temporal accumulation.
pub fn occlusion_source(settings: &Settings) -> Resource {
    if settings.ao.temporal.enabled {
        Resource::AoAccumulated
    } else {
        Resource::AoRaw
    }
}

/// The occlusion the blur-and-upsample chain starts from, if any technique runs.
pub fn occlusion_before_upsample(settings: &Settings) -> Option<Resource> {
    match (settings.ao.technique, settings.ao.blur_radius) {
        (Technique::None, _) => None,
        (_, 0) => Some(occlusion_source(settings)),
        _ => Some(Resource::AoBlurred),
    }
}

/// The full-resolution occlusion the composite reads, if any technique runs.
pub fn final_occlusion(settings: &Settings) -> Option<Resource> {
    let ao = occlusion_before_upsample(settings)?;
    Some(if settings.ao.half_res { Resource::AoFull } else { ao })
}

/// Whether the right eye takes the left eye's upsampled AO instead of upsampling its own
/// wherever the left eye sees the same point (shaders/joint_upsample.wgsl
/// `right_eye_quad`): with the stereo reuse, two views and half-resolution occlusion of
/// an AO-only technique (SSDO's rgb carries gathered light, which the composite's alpha,
/// where the left eye's AO waits for the right eye, cannot hold).
pub fn reuses_left_eye_upsample(settings: &Settings, layers: u32) -> bool {
    let ao = &settings.ao;
    ao.stereo_reuse && ao.half_res && layers == 2 && ao.technique != Technique::None && !ao.technique.carries_light()
}

/// One pass of the frame graph: declares what it reads and writes for a frame, and
/// records its GPU work when the plan keeps it.
pub trait Pass {
    /// What the pass reads and writes this frame, and whether it runs at all.
    fn declare(&self, setup: &FrameSetup) -> PassDecl;
    /// Records the pass's commands into the frame's encoder.
    fn record(&self, ctx: &mut FrameContext);
}
