//! The spatial denoise of the occlusion, at occlusion resolution, each layer alone, as a
//! horizontal then a vertical dispatch through `AoBlurH`: the default edge-aware box
//! matched to the 4×4 noise tile (shaders/denoise.wgsl), or the geometry-aware 11×11
//! bilateral blur (shaders/bilateral.wgsl).

use super::{occlusion_before_upsample, occlusion_source, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::{Denoise, Technique};

/// Pixels per invocation of the tile denoise (`RUN` in shaders/denoise.wgsl).
const DENOISE_RUN: u32 = 4;

pub struct BlurPass {
    tile_horizontal: Kernel,
    tile_vertical: Kernel,
    bilateral_horizontal: Kernel,
    bilateral_vertical: Kernel,
}

impl BlurPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots =
            [Slot::Uniform, Slot::Uniform, Slot::Layers, Slot::Layers, Slot::Output(Resource::AoBlurred.format())];
        let tile = ["common.wgsl", "denoise.wgsl"];
        let bilateral = ["common.wgsl", "bilateral.wgsl"];
        BlurPass {
            tile_horizontal: Kernel::new(gpu, "denoise horizontal", &tile, "denoise_horizontal", &slots),
            tile_vertical: Kernel::new(gpu, "denoise vertical", &tile, "denoise_vertical", &slots),
            bilateral_horizontal: Kernel::new(gpu, "blur horizontal", &bilateral, "blur_horizontal", &slots),
            bilateral_vertical: Kernel::new(gpu, "blur vertical", &bilateral, "blur_vertical", &slots),
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
        let source = occlusion_source(ctx.setup.settings);
        let (horizontal, vertical) = match ctx.setup.settings.ao.denoise {
            Denoise::Tile => (&self.tile_horizontal, &self.tile_vertical),
            Denoise::Bilateral => (&self.bilateral_horizontal, &self.bilateral_vertical),
        };
        // The tile denoise filters runs of `DENOISE_RUN` pixels along each pass's axis.
        let (w, h, layers) = extent;
        let (horizontal_grid, vertical_grid) = match ctx.setup.settings.ao.denoise {
            Denoise::Tile => ((w.div_ceil(DENOISE_RUN), h, layers), (w, h.div_ceil(DENOISE_RUN), layers)),
            Denoise::Bilateral => (extent, extent),
        };
        for (kernel, input, output, grid) in [
            (horizontal, source, Resource::AoBlurH, horizontal_grid),
            (vertical, Resource::AoBlurH, Resource::AoBlurred, vertical_grid),
        ] {
            let resources = resources(ctx, input, output);
            kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, grid);
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
