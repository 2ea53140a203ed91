//! SSAO: normal-oriented hemisphere samples tested against the depth buffer
//! (seed 003 §3.2, seed 000 ch. 3). The technique itself is shaders/ssao.wgsl.

use super::{technique_decl, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::Technique;

pub struct SsaoPass {
    kernel: Kernel,
}

impl SsaoPass {
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
        SsaoPass { kernel: Kernel::new(gpu, "ssao", &["common.wgsl", "ssao.wgsl"], "main", &slots) }
    }
}

impl Pass for SsaoPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(PassDecl::new("ssao"), &[Technique::Ssao], setup)
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
