//! 3×3 joint bilateral upsampling of half-resolution occlusion (the Czech SSDO thesis)
//! into a full-resolution target (upsample.wgsl, on joint_upsample.wgsl, which the
//! composite shares). Frames upsample inside the composite instead, so the graph runs
//! this pass only when the full-resolution AO itself is asked for (the final AO of the
//! outputs, the bench, the window's buffer view, tests).

use super::inputs::{DEPTH, NORMALS};
use super::occlusion::AO_GEOMETRY;
use super::right_eye_list::RightEyeList;
use super::{DeclareContext, Pass, RecordContext, RightEyeTiles};
use crate::gpu::kernel::{wgsl, Bind, ByChain, Kernel, Shader, Slot, COMMON, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, Size, FINAL_AO, OCCLUSION};
use crate::passes::ChainSettings;
use crate::resource::ChainLayout;
use crate::settings::Technique;
use std::sync::Mutex;

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "upsample";

/// The occlusion upsampled from half to full resolution.
pub const AO_FULL: Resource = Resource::chain_storage("ao-full", Size::Full);

/// joint_upsample.wgsl: the 3×3 joint bilateral weights and the right eye's reuse of the
/// left eye's result, shared with the composite.
pub const JOINT_UPSAMPLE_WGSL: Shader = wgsl!("src/passes/upsample/joint_upsample.wgsl");

/// upsample.wgsl's bindings: frame, AO parameters, the G-buffer and the occlusion's
/// geometry, the occlusion in, the full-resolution AO out and, for the right eye's
/// dispatches, at 7 its left-eye layer (the geometry stands in before them) and at 8 the
/// list of quads the left eye does not fully see; at 9 the sampler of its gathers.
const BINDINGS: [Bind; 10] = [
    Bind::Frame,
    Bind::AoParams,
    Bind::Read(DEPTH),
    Bind::Read(NORMALS),
    Bind::Read(AO_GEOMETRY),
    Bind::Read(OCCLUSION),
    Bind::Write(AO_FULL),
    Bind::Own(Slot::Layers),
    Bind::Own(Slot::ReadWriteBuffer),
    Bind::GatherSampler,
];

/// Whether the right eye takes the left eye's upsampled AO instead of upsampling its own
/// wherever the left eye sees the same point (joint_upsample.wgsl `left_eye_quad`): with
/// the stereo reuse, two views and half-resolution occlusion of an AO-only technique
/// (SSDO's rgb carries gathered light, which the composite's alpha, where the left eye's
/// AO waits for the right eye, cannot hold).
pub fn reuses_left_eye_upsample(settings: &ChainSettings, layers: u32) -> bool {
    let ao = &settings.ao;
    ao.stereo_reuse
        && ao.resolution.is_half()
        && layers == 2
        && ao.technique != Technique::None
        && !ao.technique.carries_light()
}

/// Joint bilateral upsampling of half-resolution occlusion to full resolution (module docs).
pub(crate) struct UpsamplePass {
    kernel: ByChain<Kernel>,
    /// The right eye's dispatch that reuses the left eye's result and lists the quads
    /// it cannot, and the indirect one over those: in the chain layout of the AO-only
    /// techniques, the only ones that reuse ([`reuses_left_eye_upsample`]).
    right_eye: Kernel,
    right_eye_fallback: Kernel,
    fallback: Mutex<RightEyeList>,
}

impl UpsamplePass {
    /// Builds the pass's pipelines.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, VISIBILITY, JOINT_UPSAMPLE_WGSL, wgsl!("src/passes/upsample/upsample.wgsl")];
        let kernel = |label: &str, right_eye: bool, fallback: bool, chain: ChainLayout| {
            let constants = [("RIGHT_EYE", f64::from(right_eye)), ("FALLBACK", f64::from(fallback))];
            Kernel::in_chain(gpu, label, &files, "main", &BINDINGS, &constants, chain)
        };
        let ao_only = ChainLayout::of(false, gpu.caps.scalar_chain);
        UpsamplePass {
            kernel: ByChain::new(gpu, |chain| kernel("upsample", false, false, chain)),
            right_eye: kernel("upsample right eye", true, false, ao_only),
            right_eye_fallback: kernel("upsample right eye fallback", true, true, ao_only),
            fallback: Mutex::new(RightEyeList::new(gpu, "upsample right-eye quads")),
        }
    }
}

impl Pass for UpsamplePass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let ao = &setup.settings.ao;
        PassDecl::new(NAME)
            .bindings(&BINDINGS)
            .provide(FINAL_AO, AO_FULL)
            .occlusion_cost()
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to upsample")
            .disabled_if(!ao.resolution.is_half(), "occlusion runs at full resolution")
    }

    fn record(&self, ctx: &mut RecordContext) {
        let mut fallback = self.fallback.lock().unwrap_or_else(|p| p.into_inner());
        let stand_in = fallback.stand_in();
        let resources = ctx.bind(&BINDINGS, &[ctx.view(AO_GEOMETRY), stand_in.as_entire_binding()]);
        // One invocation per quad of 2×2 full-res pixels (upsample.wgsl): both eyes
        // alike, or the left eye and then the right eye reusing it.
        let (w, h, layers) = ctx.quad_extent();
        let reuse = reuses_left_eye_upsample(ctx.setup.settings, layers);
        let device = &ctx.gpu.device;
        self.kernel.get(ctx.setup.chain).dispatch(
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
        fallback.record_right_eye_quads(ctx, &BINDINGS, AO_FULL, [&self.right_eye, &self.right_eye_fallback], (w, h));
    }

    fn right_eye_tiles(&self, gpu: &Gpu) -> Option<RightEyeTiles> {
        self.fallback.lock().unwrap_or_else(|p| p.into_inner()).read(gpu, NAME)
    }
}
