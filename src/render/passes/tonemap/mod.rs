//! Reinhard tone mapping with a white point (the Czech SSDO thesis, eq. 2.4) and sRGB encoding.

use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};

/// Tone mapping of the HDR radiance into the eye colour (module docs).
pub struct TonemapPass {
    kernel: Kernel,
}

impl TonemapPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [Slot::Uniform, Slot::Layers, Slot::Output(Resource::Color.format())];
        TonemapPass { kernel: Kernel::new(gpu, "tonemap", &["common.wgsl", "tonemap.wgsl"], "main", &slots) }
    }
}

impl Pass for TonemapPass {
    fn declare(&self, _: &FrameSetup) -> PassDecl {
        PassDecl::new("tonemap").read(Resource::Hdr).write(Resource::Color)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let resources = [ctx.frame.frame.as_entire_binding(), ctx.view(Resource::Hdr), ctx.view(Resource::Color)];
        let extent = ctx.extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
