//! The fetch-only benchmark baseline (shaders/fetch.wgsl): SSAO's depth taps without
//! the occlusion arithmetic, run as technique `fetch-only`.

use super::{technique_decl, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::Technique;

pub struct FetchOnlyPass {
    kernel: Kernel,
}

impl FetchOnlyPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::ReadBuffer,
            Slot::Depth,
            Slot::Layers,
            Slot::Output(Resource::AoRaw.format()),
            Slot::Output(Resource::AoGeometry.format()),
        ];
        FetchOnlyPass { kernel: Kernel::new(gpu, "fetch-only", &["common.wgsl", "fetch.wgsl"], "main", &slots) }
    }
}

impl Pass for FetchOnlyPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(PassDecl::new("fetch-only"), &[Technique::FetchOnly], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.ao.as_entire_binding(),
            ctx.frame.kernel.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::AoRaw),
            ctx.view(Resource::AoGeometry),
        ];
        let extent = ctx.ao_extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
