//! Composite: direct light plus the ambient term, attenuated by the occlusion the graph
//! produced (or unoccluded when the technique is none), and the sky, one invocation per
//! quad of 2×2 pixels. Half-resolution occlusion is upsampled here (3×3 joint bilateral,
//! shared with the upsample pass), so a frame writes and reads no full-resolution
//! occlusion target. With reflective shadow maps, their half-resolution one-bounce
//! irradiance is upsampled the same way and added to the ambient. With the stereo reuse
//! of half-resolution AO (`reuses_left_eye_upsample`) the left eye is composited first
//! and the right eye, in a dispatch of its own, takes the left eye's AO from the output's
//! alpha wherever the left eye sees the same point.

use super::occlusion::layer_view;
use super::shadow::rsm_active;
use super::{occlusion_before_upsample, reuses_left_eye_upsample, FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::targets::LayeredTarget;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};

pub struct CompositePass {
    /// Variants by (half resolution, RSM bounce): pipeline constants, so a frame without
    /// them runs none of their code.
    kernels: [[Kernel; 2]; 2],
    /// The right eye's half-resolution dispatch that reuses the left eye's AO, by RSM bounce.
    right_eye: [Kernel; 2],
    /// Bound in place of occlusion or its geometry where the shader does not read them.
    unused: LayeredTarget,
}

const SLOTS: [Slot; 14] = [
    Slot::Uniform,
    Slot::Uniform,
    Slot::Depth,
    Slot::Layers,
    Slot::Layers,
    Slot::UintLayers,
    Slot::Layers,
    Slot::Texture2d,
    Slot::Sampler,
    Slot::Output(wgpu::TextureFormat::Rgba16Float),
    Slot::Layers,
    Slot::Layers,
    Slot::Layers,
    Slot::Layers,
];

impl CompositePass {
    pub fn new(gpu: &Gpu) -> Self {
        let files = ["common.wgsl", "irradiance.wgsl", "joint_upsample.wgsl", "composite.wgsl"];
        let unused = LayeredTarget::placeholder(&gpu.device, "unused occlusion", wgpu::TextureFormat::Rgba16Float);
        let variant = |half_res: bool, rsm: bool, right_eye: bool| {
            let constants =
                [("HALF_RES", f64::from(half_res)), ("RSM", f64::from(rsm)), ("RIGHT_EYE", f64::from(right_eye))];
            let label = if right_eye { "composite right eye" } else { "composite" };
            Kernel::with_constants(gpu, label, &files, "main", &SLOTS, &constants)
        };
        CompositePass {
            kernels: [false, true].map(|half_res| [false, true].map(|rsm| variant(half_res, rsm, false))),
            right_eye: [false, true].map(|rsm| variant(true, rsm, true)),
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
        let decl = match occlusion_before_upsample(setup.settings) {
            None => decl,
            Some(occlusion) if setup.settings.ao.half_res => decl
                .read(occlusion)
                .read(Resource::AoGeometry)
                .note("upsamples the half-resolution occlusion inline (3×3 joint bilateral)"),
            Some(occlusion) => decl.read(occlusion),
        };
        if rsm_active(setup.scene, setup.settings) {
            decl.read(Resource::RsmIndirect).read(Resource::RsmGeometry)
        } else {
            decl
        }
    }

    fn record(&self, ctx: &mut FrameContext) {
        let unused = || wgpu::BindingResource::TextureView(&self.unused.array_view);
        let half_res = ctx.setup.settings.ao.half_res;
        let rsm = rsm_active(ctx.setup.scene, ctx.setup.settings);
        let (occlusion, geometry) = match occlusion_before_upsample(ctx.setup.settings) {
            Some(occlusion) if half_res => (ctx.view(occlusion), ctx.view(Resource::AoGeometry)),
            Some(occlusion) => (ctx.view(occlusion), unused()),
            None => (unused(), unused()),
        };
        let mut resources = [
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
            // One bounce from reflective shadow maps (passes/rsm.rs), when on.
            if rsm { ctx.view(Resource::RsmIndirect) } else { unused() },
            if rsm { ctx.view(Resource::RsmGeometry) } else { unused() },
            // The output's left-eye layer for the right eye's dispatch.
            unused(),
        ];
        // One invocation per quad of 2×2 pixels (composite.wgsl): both eyes alike, or the
        // left eye and then the right eye reusing its AO.
        let (w, h, layers) = ctx.quad_extent();
        let reuse = reuses_left_eye_upsample(ctx.setup.settings, layers);
        let device = &ctx.gpu.device;
        let kernel = &self.kernels[half_res as usize][rsm as usize];
        kernel.dispatch(device, ctx.encoder, &resources, (w, h, if reuse { 1 } else { layers }));
        if reuse {
            let (right, left) = (layer_view(ctx, Resource::Hdr, 1), layer_view(ctx, Resource::Hdr, 0));
            resources[9] = wgpu::BindingResource::TextureView(&right);
            resources[13] = wgpu::BindingResource::TextureView(&left);
            self.right_eye[rsm as usize].dispatch(device, ctx.encoder, &resources, (w, h, 1));
        }
    }
}
