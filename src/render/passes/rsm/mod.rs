//! One bounce of directional light from reflective shadow maps (Lin's NCTU thesis §3.3,
//! shaders/rsm.wgsl): at half resolution per axis, each pixel gathers N virtual point
//! lights from the light-space pass's maps in a disk of radius R, with a pattern turned
//! per pixel and per frame. The composite upsamples the irradiance (3×3 joint
//! bilateral, shaders/rsm_upsample.wgsl) and adds irradiance × albedo/π to the ambient.

use super::shadow::{rsm_active, shadow_casters, LightSpace};
use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::frame::ao_extent;
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use bytemuck::{Pod, Zeroable};
use std::cell::Cell;
use std::sync::Arc;

/// `RsmParams` of shaders/rsm.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RsmParamsUniform {
    low_size: [u32; 2],
    samples: u32,
    frame: u32,
    radius: f32,
    _pad: [f32; 3],
}

/// One bounce of directional light from reflective shadow maps (module docs).
pub struct RsmPass {
    kernel: Kernel,
    light_space: Arc<LightSpace>,
    params: wgpu::Buffer,
    /// Frames this pass has gathered: turns the sampling pattern (Lin's NCTU thesis).
    frame: Cell<u32>,
}

impl RsmPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, light_space: Arc<LightSpace>) -> RsmPass {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Uniform,
            Slot::Depth,
            Slot::Layers,
            Slot::Depth,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::RsmIndirect.format()),
            Slot::Output(Resource::RsmGeometry.format()),
        ];
        let kernel = Kernel::new(gpu, "rsm", &["common.wgsl", "shadow.wgsl", "rsm.wgsl"], "main", &slots);
        let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rsm params"),
            size: std::mem::size_of::<RsmParamsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        RsmPass { kernel, light_space, params, frame: Cell::new(0) }
    }
}

impl Pass for RsmPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let s = &setup.settings.shadows;
        let lights = shadow_casters(setup.scene).len();
        PassDecl::new("rsm")
            .read(Resource::Depth)
            .read(Resource::Normals)
            .read(Resource::ShadowMap)
            .read(Resource::RsmNormal)
            .read(Resource::RsmFlux)
            .write(Resource::RsmIndirect)
            .write(Resource::RsmGeometry)
            .disabled_if(lights == 0, "no directional light to bounce (reflective shadow maps need one)")
            .disabled_if(!s.rsm, "reflective shadow maps are off (--rsm on adds one bounce of the sun)")
            .note(format!(
                "{} VPLs per pixel and light within {} m, half resolution, pattern turned per frame{}",
                s.rsm_samples,
                s.rsm_radius,
                if setup.settings.ao.bounce_active() { "; SSDO's bounce adds the sun's bounce too" } else { "" }
            ))
    }

    fn record(&self, ctx: &mut FrameContext) {
        debug_assert!(rsm_active(ctx.setup.scene, ctx.setup.settings));
        let p = &ctx.setup.settings.profile;
        let (w, h) = ao_extent(p.width, p.height, true);
        let s = &ctx.setup.settings.shadows;
        let frame = self.frame.get();
        self.frame.set(frame.wrapping_add(1));
        let params =
            RsmParamsUniform { low_size: [w, h], samples: s.rsm_samples, frame, radius: s.rsm_radius, _pad: [0.0; 3] };
        ctx.gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            self.light_space.uniform.as_entire_binding(),
            self.params.as_entire_binding(),
            ctx.view(Resource::Depth),
            ctx.view(Resource::Normals),
            ctx.view(Resource::ShadowMap),
            ctx.view(Resource::RsmNormal),
            ctx.view(Resource::RsmFlux),
            ctx.view(Resource::RsmIndirect),
            ctx.view(Resource::RsmGeometry),
        ];
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, (w, h, ctx.setup.views));
    }
}
