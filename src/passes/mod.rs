//! One file per pass. A pass declares what it reads and writes for this frame (the
//! graph decides whether it runs) and records its GPU work when it does.

pub mod gbuffer;
pub mod lighting;
pub mod tonemap;

use crate::gpu::frame::FrameBuffers;
use crate::gpu::scene::GpuScene;
use crate::gpu::targets::LayeredTarget;
use crate::gpu::timing::GpuTimer;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::scene::Scene;
use crate::settings::Settings;
use std::collections::BTreeMap;

/// What passes may consult when declaring themselves for a frame.
pub struct FrameSetup<'a> {
    pub scene: &'a Scene,
    pub settings: &'a Settings,
    /// 2 for stereo, 1 for a mono view.
    pub views: u32,
    /// Whether the G-buffer draws both layers in one multiview pass.
    pub multiview: bool,
}

/// Everything a pass records with.
pub struct FrameContext<'a> {
    pub gpu: &'a Gpu,
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub targets: &'a BTreeMap<Resource, LayeredTarget>,
    pub frame: &'a FrameBuffers,
    pub scene: &'a GpuScene,
    pub timer: &'a mut GpuTimer,
    pub setup: &'a FrameSetup<'a>,
}

impl<'a> FrameContext<'a> {
    /// The target of a resource the graph allocated for this frame.
    pub fn target(&self, r: Resource) -> &'a LayeredTarget {
        self.targets.get(&r).unwrap_or_else(|| panic!("{} was not allocated; the pass did not declare it", r.name()))
    }

    pub fn view(&self, r: Resource) -> wgpu::BindingResource<'a> {
        wgpu::BindingResource::TextureView(&self.target(r).array_view)
    }

    /// Width × height × layers of this frame's targets.
    pub fn extent(&self) -> (u32, u32, u32) {
        let p = &self.setup.settings.profile;
        (p.width, p.height, self.setup.views)
    }
}

pub trait Pass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl;
    fn record(&self, ctx: &mut FrameContext);
}
