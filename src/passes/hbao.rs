//! HBAO: horizon search along D screen directions × S steps in the depth buffer
//! (seed 003 §3.3). The technique itself is shaders/hbao.wgsl.

use super::{technique_decl, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::Technique;

pub struct HbaoPass {
    kernel: Kernel,
}

impl HbaoPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Depth,
            Slot::Layers,
            Slot::Output(Resource::AoRaw.format()),
            Slot::Output(Resource::AoGeometry.format()),
        ];
        HbaoPass { kernel: Kernel::new(gpu, "hbao", &["common.wgsl", "hbao.wgsl"], "main", &slots) }
    }
}

impl Pass for HbaoPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(PassDecl::new("hbao"), &[Technique::Hbao], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.ao.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::AoRaw),
            ctx.view(Resource::AoGeometry),
        ];
        let extent = ctx.ao_extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
