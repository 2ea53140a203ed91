//! Composite: direct light plus the ambient term, attenuated by the occlusion the graph
//! produced (or unoccluded when the technique is none), and the sky.

use super::{final_occlusion, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::targets::LayeredTarget;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};

pub struct CompositePass {
    kernel: Kernel,
    /// Bound in place of occlusion when no technique runs (the shader ignores it then).
    no_occlusion: LayeredTarget,
}

impl CompositePass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Texture2d,
            Slot::Sampler,
            Slot::Output(Resource::Hdr.format()),
        ];
        let no_occlusion = LayeredTarget::new(
            &gpu.device,
            "no occlusion",
            wgpu::TextureFormat::Rgba16Float,
            (1, 1, 2),
            wgpu::TextureUsages::TEXTURE_BINDING,
        );
        CompositePass {
            kernel: Kernel::new(gpu, "composite", &["common.wgsl", "composite.wgsl"], "main", &slots),
            no_occlusion,
        }
    }
}

impl Pass for CompositePass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let decl = PassDecl::new("composite")
            .read(Resource::Depth)
            .read(Resource::Normals)
            .read(Resource::Albedo)
            .read(Resource::Direct)
            .write(Resource::Hdr);
        match final_occlusion(setup.settings) {
            Some(ao) => decl.read(ao),
            None => decl,
        }
    }

    fn record(&self, ctx: &mut FrameContext) {
        let occlusion = match final_occlusion(ctx.setup.settings) {
            Some(ao) => ctx.view(ao),
            None => wgpu::BindingResource::TextureView(&self.no_occlusion.array_view),
        };
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.ao.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::Albedo),
            ctx.view(Resource::Direct),
            occlusion,
            wgpu::BindingResource::TextureView(&ctx.scene.environment),
            wgpu::BindingResource::Sampler(&ctx.scene.sampler),
            ctx.view(Resource::Hdr),
        ];
        let extent = ctx.extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
