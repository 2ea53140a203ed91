//! Direct light from the scene's point and directional lights, plus emission, as
//! outgoing radiance. The composite builds on it; SSDO's bounce reads it as L_pixel.

use super::{FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};

pub struct DirectLightPass {
    kernel: Kernel,
}

impl DirectLightPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::ReadBuffer,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::Direct.format()),
        ];
        DirectLightPass { kernel: Kernel::new(gpu, "direct", &["common.wgsl", "direct.wgsl"], "main", &slots) }
    }
}

impl Pass for DirectLightPass {
    fn declare(&self, _: &FrameSetup) -> PassDecl {
        PassDecl::new("direct")
            .read(Resource::Depth)
            .read(Resource::Normals)
            .read(Resource::Albedo)
            .read(Resource::Emission)
            .write(Resource::Direct)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.lights.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::Albedo),
            ctx.view(Resource::Emission),
            ctx.view(Resource::Direct),
        ];
        let extent = ctx.extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
