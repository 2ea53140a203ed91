//! Separable geometry-aware bilateral blur of the occlusion, at occlusion resolution:
//! a horizontal then a vertical dispatch (shaders/bilateral.wgsl), each layer alone.

use super::{occlusion_before_upsample, occlusion_source, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::Technique;

pub struct BlurPass {
    horizontal: Kernel,
    vertical: Kernel,
}

impl BlurPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots =
            [Slot::Uniform, Slot::Uniform, Slot::Layers, Slot::Layers, Slot::Output(Resource::AoBlurred.format())];
        let files = ["common.wgsl", "bilateral.wgsl"];
        BlurPass {
            horizontal: Kernel::new(gpu, "blur horizontal", &files, "blur_horizontal", &slots),
            vertical: Kernel::new(gpu, "blur vertical", &files, "blur_vertical", &slots),
        }
    }
}

impl Pass for BlurPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let ao = &setup.settings.ao;
        PassDecl::new("blur")
            .read(Resource::AoGeometry)
            .read(occlusion_source(setup.settings))
            .write(Resource::AoBlurH)
            .write(Resource::AoBlurred)
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to blur")
            .disabled_if(ao.blur_radius == 0, "blur radius is 0")
    }

    fn record(&self, ctx: &mut FrameContext) {
        debug_assert_eq!(occlusion_before_upsample(ctx.setup.settings), Some(Resource::AoBlurred));
        let extent = ctx.ao_extent();
        for (kernel, input, output) in [
            (&self.horizontal, occlusion_source(ctx.setup.settings), Resource::AoBlurH),
            (&self.vertical, Resource::AoBlurH, Resource::AoBlurred),
        ] {
            let resources = [
                ctx.frame.frame.as_entire_binding(),
                ctx.frame.ao.as_entire_binding(),
                ctx.view(Resource::AoGeometry),
                ctx.view(input),
                ctx.view(output),
            ];
            kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
        }
    }
}
