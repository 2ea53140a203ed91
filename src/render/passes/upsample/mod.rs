//! 3×3 joint bilateral upsampling of half-resolution occlusion (the Czech SSDO thesis) into a
//! full-resolution target (shaders/upsample.wgsl). Frames upsample inside the composite
//! instead, so the graph runs this pass only when AoFull itself is asked for (debug
//! images, tests).

use super::occlusion::layer_view;
use super::{occlusion_before_upsample, reuses_left_eye_upsample, FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};

/// Joint bilateral upsampling of half-resolution occlusion to full resolution (module docs).
pub struct UpsamplePass {
    kernel: Kernel,
    /// The right eye's dispatch that reuses the left eye's result.
    right_eye: Kernel,
}

impl UpsamplePass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::AoFull.format()),
            Slot::Layers,
        ];
        let files = ["common.wgsl", "joint_upsample.wgsl", "upsample.wgsl"];
        let kernel = |label: &str, right_eye: bool| {
            Kernel::with_constants(gpu, label, &files, "main", &slots, &[("RIGHT_EYE", f64::from(right_eye))])
        };
        UpsamplePass { kernel: kernel("upsample", false), right_eye: kernel("upsample right eye", true) }
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
        let mut resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.ao.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::AoGeometry),
            ctx.view(input),
            ctx.view(Resource::AoFull),
            // The left eye's layer for the right eye's dispatch; AoGeometry stands in.
            ctx.view(Resource::AoGeometry),
        ];
        // One invocation per quad of 2×2 full-res pixels (upsample.wgsl): both eyes
        // alike, or the left eye and then the right eye reusing it.
        let (w, h, layers) = ctx.quad_extent();
        let reuse = reuses_left_eye_upsample(ctx.setup.settings, layers);
        let device = &ctx.gpu.device;
        self.kernel.dispatch(device, ctx.encoder, &resources, (w, h, if reuse { 1 } else { layers }));
        if reuse {
            let (right, left) = (layer_view(ctx, Resource::AoFull, 1), layer_view(ctx, Resource::AoFull, 0));
            resources[6] = wgpu::BindingResource::TextureView(&right);
            resources[7] = wgpu::BindingResource::TextureView(&left);
            self.right_eye.dispatch(device, ctx.encoder, &resources, (w, h, 1));
        }
    }
}
