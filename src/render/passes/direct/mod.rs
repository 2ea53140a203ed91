//! Direct light from the scene's point and directional lights, plus emission, as
//! outgoing radiance. The composite builds on it; SSDO's bounce reads it as L_pixel.
//! Directional lights are shadowed by their shadow maps (3×3 PCF, passes/shadow.rs)
//! when shadows are on.

use super::shadow::{shadows_active, LightSpace};
use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use std::sync::Arc;

/// Direct light of every light, shadowed where shadow maps exist (module docs).
pub struct DirectLightPass {
    kernel: Kernel,
    light_space: Arc<LightSpace>,
}

impl DirectLightPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, light_space: Arc<LightSpace>) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::ReadBuffer,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::Direct.format()),
            Slot::Uniform,
            Slot::Depth,
            Slot::ComparisonSampler,
        ];
        let kernel = Kernel::new(gpu, "direct", &["common.wgsl", "shadow.wgsl", "direct.wgsl"], "main", &slots);
        DirectLightPass { kernel, light_space }
    }
}

impl Pass for DirectLightPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let decl = PassDecl::new("direct")
            .read(Resource::Depth)
            .read(Resource::Normals)
            .read(Resource::Albedo)
            .read(Resource::Emission)
            .write(Resource::Direct);
        if shadows_active(setup.scene, setup.settings) {
            decl.read(Resource::ShadowMap)
                .note("directional light shadowed: 3×3 PCF, bilinear compare, slope-scaled bias")
        } else {
            decl
        }
    }

    fn record(&self, ctx: &mut FrameContext) {
        let shadowed = shadows_active(ctx.setup.scene, ctx.setup.settings);
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.lights.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::Albedo),
            ctx.view(Resource::Emission),
            ctx.view(Resource::Direct),
            // Shadows (shaders/shadow.wgsl): every light's map, or no light and a placeholder.
            if shadowed {
                self.light_space.uniform.as_entire_binding()
            } else {
                self.light_space.none.as_entire_binding()
            },
            if shadowed {
                ctx.view(Resource::ShadowMap)
            } else {
                wgpu::BindingResource::TextureView(&self.light_space.placeholder_depth.array_view)
            },
            wgpu::BindingResource::Sampler(&self.light_space.comparison),
        ];
        let extent = ctx.extent();
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
