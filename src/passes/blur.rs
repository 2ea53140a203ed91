//! The spatial denoise of the occlusion, at occlusion resolution, each layer alone: the
//! default edge-aware 4×4 box matched to the noise tile, one dispatch per 2×2 quad
//! (shaders/denoise.wgsl), or the separable geometry-aware bilateral blur, a horizontal
//! then a vertical dispatch (shaders/bilateral.wgsl).

use super::{occlusion_before_upsample, occlusion_source, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::{Denoise, Technique};

pub struct BlurPass {
    tile: Kernel,
    horizontal: Kernel,
    vertical: Kernel,
}

impl BlurPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots =
            [Slot::Uniform, Slot::Uniform, Slot::Layers, Slot::Layers, Slot::Output(Resource::AoBlurred.format())];
        let files = ["common.wgsl", "bilateral.wgsl"];
        BlurPass {
            tile: Kernel::new(gpu, "denoise 4x4", &["common.wgsl", "denoise.wgsl"], "main", &slots),
            horizontal: Kernel::new(gpu, "blur horizontal", &files, "blur_horizontal", &slots),
            vertical: Kernel::new(gpu, "blur vertical", &files, "blur_vertical", &slots),
        }
    }
}

impl Pass for BlurPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let ao = &setup.settings.ao;
        let decl = PassDecl::new("blur").read(Resource::AoGeometry).read(occlusion_source(setup.settings));
        let decl = if ao.denoise == Denoise::Bilateral { decl.write(Resource::AoBlurH) } else { decl };
        decl.write(Resource::AoBlurred)
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to blur")
            .disabled_if(ao.blur_radius == 0, "blur radius is 0")
    }

    fn record(&self, ctx: &mut FrameContext) {
        debug_assert_eq!(occlusion_before_upsample(ctx.setup.settings), Some(Resource::AoBlurred));
        let extent = ctx.ao_extent();
        let source = occlusion_source(ctx.setup.settings);
        if ctx.setup.settings.ao.denoise == Denoise::Tile {
            let (w, h, layers) = extent;
            let resources = resources(ctx, source, Resource::AoBlurred);
            self.tile.dispatch(&ctx.gpu.device, ctx.encoder, &resources, (w.div_ceil(2), h.div_ceil(2), layers));
            return;
        }
        for (kernel, input, output) in
            [(&self.horizontal, source, Resource::AoBlurH), (&self.vertical, Resource::AoBlurH, Resource::AoBlurred)]
        {
            let resources = resources(ctx, input, output);
            kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
        }
    }
}

/// Bindings of both denoise shaders: frame, AO parameters, geometry, input, output.
fn resources<'a>(ctx: &FrameContext<'a>, input: Resource, output: Resource) -> [wgpu::BindingResource<'a>; 5] {
    [
        ctx.frame.frame.as_entire_binding(),
        ctx.frame.ao.as_entire_binding(),
        ctx.view(Resource::AoGeometry),
        ctx.view(input),
        ctx.view(output),
    ]
}
