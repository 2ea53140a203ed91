//! Direct diffuse light plus environment irradiance, in HDR. Occlusion will attenuate
//! the ambient term here.

use super::{FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};

pub struct LightingPass {
    kernel: Kernel,
}

impl LightingPass {
    pub fn new(gpu: &Gpu) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::ReadBuffer,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Texture2d,
            Slot::Sampler,
            Slot::Output(Resource::Hdr.format()),
        ];
        LightingPass { kernel: Kernel::new(gpu, "lighting", &["common.wgsl", "lighting.wgsl"], "main", &slots) }
    }
}

impl Pass for LightingPass {
    fn declare(&self, _: &FrameSetup) -> PassDecl {
        PassDecl::new("lighting")
            .read(Resource::Depth)
            .read(Resource::Normals)
            .read(Resource::Albedo)
            .read(Resource::Emission)
            .write(Resource::Hdr)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.lights.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::Albedo),
            ctx.view(Resource::Emission),
            wgpu::BindingResource::TextureView(&ctx.scene.environment),
            wgpu::BindingResource::Sampler(&ctx.scene.sampler),
            ctx.view(Resource::Hdr),
        ];
        let extent = ctx.extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
