//! Composite: direct light plus the ambient term, attenuated by the occlusion the graph
//! produced (or unoccluded when the technique is none), and the sky, one invocation per
//! quad of 2×2 pixels. Half-resolution occlusion is upsampled here (3×3 joint bilateral,
//! shared with the upsample pass), so a frame writes and reads no full-resolution
//! occlusion target. With reflective shadow maps, their half-resolution one-bounce
//! irradiance is upsampled the same way and added to the ambient. With the stereo reuse
//! of half-resolution AO (`reuses_left_eye_upsample`) the left eye is composited first
//! and the right eye, in a dispatch of its own, takes the left eye's AO from the output's
//! alpha wherever the left eye sees the same point; the quads it does not fully see are
//! listed on the GPU (a [`RightEyeList`], whose counts reports read) and composited by an
//! indirect dispatch over just them.

use super::direct::DIRECT;
use super::gbuffer::{ALBEDO, LIGHTING_NORMALS};
use super::rsm::{RSM_GEOMETRY, RSM_INDIRECT};
use super::shadow::rsm_active;
use super::{scene_of, settings_of};
use crate::gpu::kernel::wgsl;
use std::sync::Mutex;
use vrao_ao::plug::{
    reuses_left_eye_upsample, Bind, ChainLayout, DeclareContext, Gpu, Kernel, Pass, PassDecl, RecordContext, Resource,
    RightEyeList, Size, Slot, AO_GEOMETRY, COMMON, DEPTH, IRRADIANCE, JOINT_UPSAMPLE_WGSL, NORMALS, OCCLUSION,
    VISIBILITY,
};
use vrao_ao::{RightEyeTiles, Technique};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "composite";

/// Lit scene radiance before tone mapping.
pub const HDR: Resource = Resource::storage("hdr", Size::Full, wgpu::TextureFormat::Rgba16Float);

/// The composite: direct light plus the occluded ambient term in HDR, upsampling half-
/// resolution AO inline (module docs).
pub struct CompositePass {
    /// Variants by (half resolution, RSM bounce): pipeline constants, so a frame without
    /// them runs none of their code.
    /// By the AO chain's layout it reads (the scalar one only where the device has it),
    /// then half resolution and RSM.
    kernels: Vec<(ChainLayout, [[Kernel; 2]; 2])>,
    /// The right eye's half-resolution dispatches, by RSM bounce: reusing the left eye's
    /// AO (listing the quads it cannot), and over the listed quads.
    right_eye: [Kernel; 2],
    right_eye_fallback: [Kernel; 2],
    /// The list of right-eye quads the left eye does not fully see (composite.wgsl
    /// `FallbackQuads`).
    fallback: Mutex<RightEyeList>,
}

/// composite.wgsl's bindings: frame, AO parameters, the G-buffer, the direct light, the
/// occlusion, the environment, the HDR out, the occlusion's geometry, the RSM bounce and
/// its geometry and, for the right eye's dispatches, the output's left-eye layer and the
/// fallback list; the lighting's normals; the sampler of the right eye's gathers.
const BINDINGS: [Bind; 17] = [
    Bind::Frame,
    Bind::AoParams,
    Bind::Read(DEPTH),
    Bind::Read(NORMALS),
    Bind::Read(ALBEDO),
    Bind::Read(DIRECT),
    Bind::Read(OCCLUSION),
    Bind::Environment,
    Bind::EnvironmentSampler,
    Bind::Write(HDR),
    Bind::Read(AO_GEOMETRY),
    Bind::Read(RSM_INDIRECT),
    Bind::Read(RSM_GEOMETRY),
    Bind::Own(Slot::Layers),
    Bind::Own(Slot::ReadWriteBuffer),
    Bind::Read(LIGHTING_NORMALS),
    Bind::GatherSampler,
];

impl CompositePass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, VISIBILITY, IRRADIANCE, JOINT_UPSAMPLE_WGSL, wgsl!("src/passes/composite/composite.wgsl")];
        let variant = |half_res: bool, rsm: bool, right_eye: bool, fallback: bool, chain: ChainLayout| {
            let constants = [
                ("HALF_RES", f64::from(half_res)),
                ("RSM", f64::from(rsm)),
                ("RIGHT_EYE", f64::from(right_eye)),
                ("FALLBACK", f64::from(fallback)),
            ];
            let label = match (right_eye, fallback) {
                (false, _) => "composite",
                (true, false) => "composite right eye",
                (true, true) => "composite right eye fallback",
            };
            Kernel::in_chain(gpu, label, &files, "main", &BINDINGS, &constants, chain)
        };
        // The right eye reuses the left eye's AO only for the techniques without light.
        let ao_only = ChainLayout::of(false, gpu.caps.scalar_chain);
        CompositePass {
            kernels: [ChainLayout::Rgba, ChainLayout::Scalar]
                .into_iter()
                .filter(|chain| *chain == ChainLayout::Rgba || gpu.caps.scalar_chain)
                .map(|chain| {
                    (
                        chain,
                        [false, true]
                            .map(|half_res| [false, true].map(|rsm| variant(half_res, rsm, false, false, chain))),
                    )
                })
                .collect(),
            right_eye: [false, true].map(|rsm| variant(true, rsm, true, false, ao_only)),
            right_eye_fallback: [false, true].map(|rsm| variant(true, rsm, true, true, ao_only)),
            fallback: Mutex::new(RightEyeList::new(gpu, "composite fallback quads")),
        }
    }
}

impl Pass for CompositePass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let settings = settings_of(setup);
        let mut decl = PassDecl::new(NAME).bindings(&BINDINGS);
        if settings.ao.technique == Technique::None {
            decl = decl.unbind(OCCLUSION).unbind(AO_GEOMETRY);
        } else if settings.ao.resolution.is_half() {
            decl = decl.note("upsamples the half-resolution occlusion inline (3×3 joint bilateral)");
        } else {
            decl = decl.unbind(AO_GEOMETRY);
        }
        if rsm_active(scene_of(setup), settings) {
            decl
        } else {
            decl.unbind(RSM_INDIRECT).unbind(RSM_GEOMETRY)
        }
    }

    fn record(&self, ctx: &mut RecordContext) {
        let half_res = settings_of(ctx.setup).ao.resolution.is_half();
        let rsm = rsm_active(scene_of(ctx.setup), settings_of(ctx.setup));
        // The output's left-eye layer is unused before the right eye's dispatch: the
        // geometry (or its placeholder) stands in.
        let mut fallback = self.fallback.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let stand_in = fallback.stand_in();
        let resources = ctx.bind(&BINDINGS, &[ctx.view(AO_GEOMETRY), stand_in.as_entire_binding()]);
        // One invocation per quad of 2×2 pixels (composite.wgsl): both eyes alike, or the
        // left eye, then the right eye reusing its AO, then the quads it listed.
        let (w, h, layers) = ctx.quad_extent();
        let reuse = reuses_left_eye_upsample(ctx.setup.settings, layers);
        let device = &ctx.gpu.device;
        let by_layout =
            self.kernels.iter().find(|(chain, _)| *chain == ctx.setup.chain).expect("the frame's chain layout");
        let kernel = &by_layout.1[half_res as usize][rsm as usize];
        kernel.dispatch(
            device,
            ctx.encoder,
            ctx.visibility.bind_group(),
            &resources,
            (w, h, if reuse { 1 } else { layers }),
        );
        if !reuse {
            fallback.skip();
            return;
        }
        // The right eye writes layer 1 alone, reads the left eye's layer 0 and lists the
        // quads it could not reuse.
        let kernels = [&self.right_eye[rsm as usize], &self.right_eye_fallback[rsm as usize]];
        fallback.record_right_eye_quads(ctx, &BINDINGS, HDR, kernels, (w, h));
    }

    fn right_eye_tiles(&self, gpu: &Gpu) -> Option<RightEyeTiles> {
        self.fallback.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).read(gpu, NAME)
    }
}
