//! 3×3 joint bilateral upsampling of half-resolution occlusion (seed 000) into a
//! full-resolution target (shaders/upsample.wgsl). Frames upsample inside the composite
//! instead, so the graph runs this pass only when AoFull itself is asked for (debug
//! images, tests).

use super::{occlusion_before_upsample, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};

pub struct UpsamplePass {
    kernel: Kernel,
}

impl UpsamplePass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::AoFull.format()),
        ];
        UpsamplePass {
            kernel: Kernel::new(
                gpu,
                "upsample",
                &["common.wgsl", "joint_upsample.wgsl", "upsample.wgsl"],
                "main",
                &slots,
            ),
        }
    }
}

impl Pass for UpsamplePass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let decl = PassDecl::new("upsample")
            .read(Resource::Depth)
            .read(Resource::Normals)
            .read(Resource::AoGeometry)
            .write(Resource::AoFull);
        match occlusion_before_upsample(setup.settings) {
            None => decl.disabled_if(true, "technique is none: nothing to upsample"),
            Some(input) => {
                decl.read(input).disabled_if(!setup.settings.ao.half_res, "occlusion runs at full resolution")
            }
        }
    }

    fn record(&self, ctx: &mut FrameContext) {
        let input = occlusion_before_upsample(ctx.setup.settings).expect("upsample runs only with a technique");
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.ao.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::AoGeometry),
            ctx.view(input),
            ctx.view(Resource::AoFull),
        ];
        // One invocation per quad of 2×2 full-res pixels (upsample.wgsl).
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, ctx.quad_extent());
    }
}
