//! The seeds' point-sampled SSDO (`ssdo-points`), with the optional bounce gathered in the
//! same loop (`ssdo-points-bounce`; Ritschel et al. 2009 eqs. 1–2, Belonogov 2018 §4.1–4.2),
//! kept as a measured baseline beside the engine's SSDO on GTAO's bitmask
//! (vrao_ao::passes::ssdo). The technique itself is ssdo.wgsl on the shared occlusion
//! layout; a bounce strength of 0 selects the pipeline compiled without bounce work,
//! which also does not read the direct light, so the graph need not produce it for an
//! occlusion-only frame.

use super::direct::DIRECT;
use super::settings_of;
use crate::gpu::kernel::wgsl;
use crate::settings::BounceForm;
use vrao_ao::plug::{
    bindings_and, technique_decl, Bind, DeclareContext, Gpu, Kernel, Pass, PassDecl, RecordContext, COMMON,
    DEPTH_LAYER_2, IRRADIANCE, OCCLUSION_WGSL, VISIBILITY,
};
use vrao_ao::Technique;

/// The shared occlusion bindings plus the direct light (binding 7, the bounce's senders)
/// and the second depth layer (binding 8, depth peeling).
const BINDINGS: [Bind; 9] = bindings_and([Bind::Read(DIRECT), Bind::Read(DEPTH_LAYER_2)]);

/// SSDO, with its bounce when the technique asks for it (module docs).
pub struct SsdoPass {
    /// Pipelines by [depth peeling][bounce: none, direction form, patch form]: pipeline
    /// constants, so a frame runs no code of what it left out.
    kernels: [[Kernel; 3]; 2],
}

impl SsdoPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, VISIBILITY, IRRADIANCE, OCCLUSION_WGSL, wgsl!("src/passes/ssdo/ssdo.wgsl")];
        let labels = [
            ["ssdo-points", "ssdo-points-bounce", "ssdo-points-bounce patch"],
            ["ssdo-points peeled", "ssdo-points-bounce peeled", "ssdo-points-bounce patch peeled"],
        ];
        let kernels = [0, 1].map(|peel| {
            [0, 1, 2].map(|bounce| {
                let constants = [
                    ("PEEL", peel as f64),
                    ("BOUNCE", f64::from(bounce > 0)),
                    ("BOUNCE_PATCH", f64::from(bounce == 2)),
                ];
                Kernel::with_constants(gpu, labels[peel][bounce], &files, "main", &BINDINGS, &constants)
            })
        });
        SsdoPass { kernels }
    }
}

impl Pass for SsdoPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let settings = settings_of(setup);
        let ao = &settings.ao;
        let runs_for = [Technique::SsdoPoints, Technique::SsdoPointsBounce];
        let name = if ao.bounce_active() { Technique::SsdoPointsBounce.name() } else { Technique::SsdoPoints.name() };
        let mut decl = technique_decl(name, &BINDINGS, &runs_for, setup);
        if !ao.bounce_active() {
            decl = decl.unbind(DIRECT);
            if ao.technique == Technique::SsdoPointsBounce {
                decl = decl.note("bounce left out: bounce strength is 0");
            }
        }
        if settings.point_ssdo.depth_peeling {
            decl.note("depth peeling: occluders only between the first and second depth layer")
        } else {
            decl.unbind(DEPTH_LAYER_2)
        }
    }

    fn record(&self, ctx: &mut RecordContext) {
        let settings = settings_of(ctx.setup);
        let point_ssdo = settings.point_ssdo;
        let form = match (settings.ao.bounce_active(), point_ssdo.bounce_form) {
            (false, _) => 0,
            (true, BounceForm::Direction) => 1,
            (true, BounceForm::Patch) => 2,
        };
        let kernel = &self.kernels[point_ssdo.depth_peeling as usize][form];
        let resources = ctx.bind(&BINDINGS, &[]);
        kernel.dispatch(&ctx.gpu.device, ctx.encoder, ctx.visibility.bind_group(), &resources, ctx.ao_extent());
    }
}
