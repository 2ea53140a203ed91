//! Composite: direct light plus the ambient term, attenuated by the occlusion the graph
//! produced (or unoccluded when the technique is none), and the sky. Half-resolution
//! occlusion is upsampled here, per pixel (3×3 joint bilateral, shared with the
//! upsample pass), so a frame writes and reads no full-resolution occlusion target.

use super::{occlusion_before_upsample, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::targets::LayeredTarget;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};

pub struct CompositePass {
    full_res: Kernel,
    half_res: Kernel,
    /// Bound in place of occlusion or its geometry where the shader does not read them.
    unused: LayeredTarget,
}

const SLOTS: [Slot; 11] = [
    Slot::Uniform,
    Slot::Uniform,
    Slot::Depth,
    Slot::Layers,
    Slot::Layers,
    Slot::Layers,
    Slot::Layers,
    Slot::Texture2d,
    Slot::Sampler,
    Slot::Output(wgpu::TextureFormat::Rgba16Float),
    Slot::Layers,
];

impl CompositePass {
    pub fn new(gpu: &Gpu) -> Self {
        let files = ["common.wgsl", "joint_upsample.wgsl", "composite.wgsl"];
        let unused = LayeredTarget::placeholder(&gpu.device, "unused occlusion", wgpu::TextureFormat::Rgba16Float);
        CompositePass {
            full_res: Kernel::with_constants(gpu, "composite", &files, "main", &SLOTS, &[("HALF_RES", 0.0)]),
            half_res: Kernel::with_constants(gpu, "composite half-res", &files, "main", &SLOTS, &[("HALF_RES", 1.0)]),
            unused,
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
        match occlusion_before_upsample(setup.settings) {
            None => decl,
            Some(occlusion) if setup.settings.ao.half_res => decl
                .read(occlusion)
                .read(Resource::AoGeometry)
                .note("upsamples the half-resolution occlusion inline (3×3 joint bilateral)"),
            Some(occlusion) => decl.read(occlusion),
        }
    }

    fn record(&self, ctx: &mut FrameContext) {
        let unused = || wgpu::BindingResource::TextureView(&self.unused.array_view);
        let half_res = ctx.setup.settings.ao.half_res;
        let (occlusion, geometry) = match occlusion_before_upsample(ctx.setup.settings) {
            Some(occlusion) if half_res => (ctx.view(occlusion), ctx.view(Resource::AoGeometry)),
            Some(occlusion) => (ctx.view(occlusion), unused()),
            None => (unused(), unused()),
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
            geometry,
        ];
        let extent = ctx.extent();
        let kernel = if half_res { &self.half_res } else { &self.full_res };
        kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
