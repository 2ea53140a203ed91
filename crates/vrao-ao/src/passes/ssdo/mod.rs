//! SSDO on GTAO's visibility bitmask (Ritschel et al. 2009 eqs. 1 and 2 with the sectors of
//! Therrien, Levesque and Gilet 2023 in place of point samples): GTAO's march
//! (passes/gtao, gtao.wgsl: its slices, sectors, thickness, the other eye's layer and the
//! alpha-tested cards), with ssdo.wgsl's light hooks after it. Per pixel it returns the
//! occlusion exactly as GTAO's, the environment light through the unoccluded sectors and,
//! for `ssdo-bounce`, the direct light each newly covered sector's sender surface sends
//! towards the pixel, in colour (rgb: the irradiance the composite multiplies by albedo/π).
//!
//! The environment comes from the frame's SH quadratics (`frame.environment_quadratics`,
//! a renderer's environment or a host's [`crate::HostLight`]); the bounce's senders
//! from [`DIRECT_LIGHT`] (the renderer's direct-light pass, or the host's radiance packed
//! by the engine). Without either, SSDO is GTAO's AO with no light in rgb.

use super::gtao::{GtaoPass, March, BINDINGS as GTAO_BINDINGS, GTAO_WGSL};
use super::inputs::DIRECT_LIGHT;
use super::occlusion::{self, OCCLUSION_WGSL, RIGHT_EYE_WGSL};
use super::{DeclareContext, Pass, RecordContext, RightEyeTiles};
use crate::gpu::kernel::{wgsl, Bind, COMMON, IRRADIANCE, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::PassDecl;
use crate::settings::Technique;

/// GTAO's bindings and, at 14, the packed direct light (ssdo.wgsl `direct_layers`).
const BINDINGS: [Bind; 15] = occlusion::joined(GTAO_BINDINGS, [Bind::Read(DIRECT_LIGHT)]);

/// What a host's frame gives SSDO beyond depth (the AO engine puts it among the frame's
/// extensions; vrao's renderer, which always has its direct light, puts none).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct LightInputs {
    /// Whether [`DIRECT_LIGHT`] holds the host's direct light this frame.
    pub direct: bool,
}

/// Whether this frame has direct light for the bounce.
fn has_direct(setup: &DeclareContext) -> bool {
    setup.extension::<LightInputs>().is_none_or(|l| l.direct)
}

/// SSDO or SSDO with the bounce: GTAO's march with the light hooks, its pipelines built
/// at the first frame that runs it.
pub(crate) struct SsdoPass {
    technique: Technique,
    /// The march without the bounce (`ssdo`, or `ssdo-bounce` at bounce strength 0).
    plain: GtaoPass,
    /// The march with the bounce (`ssdo-bounce` only).
    bounce: Option<GtaoPass>,
}

impl SsdoPass {
    /// The pass of `technique` ([`Technique::Ssdo`] or [`Technique::SsdoBounce`]).
    pub(crate) fn new(gpu: &Gpu, technique: Technique) -> Self {
        let march = |label: &'static str, bounce: bool| {
            GtaoPass::with_march(
                gpu,
                March {
                    technique,
                    label,
                    files: vec![
                        COMMON,
                        VISIBILITY,
                        IRRADIANCE,
                        OCCLUSION_WGSL,
                        RIGHT_EYE_WGSL,
                        GTAO_WGSL,
                        wgsl!("src/passes/ssdo/ssdo.wgsl"),
                    ],
                    binds: &BINDINGS,
                    constants: vec![("BOUNCE", f64::from(bounce))],
                    declare: if bounce { declare_bounce } else { declare_plain },
                    eager: false,
                },
            )
        };
        let bounce = (technique == Technique::SsdoBounce).then(|| march(Technique::SsdoBounce.name(), true));
        SsdoPass { technique, plain: march(Technique::Ssdo.name(), false), bounce }
    }

    /// The march this frame runs.
    fn march(&self, setup: &DeclareContext) -> &GtaoPass {
        match &self.bounce {
            // Left out, it is named for its technique.
            Some(bounce) if setup.settings.ao.bounce_active() || setup.settings.ao.technique != self.technique => {
                bounce
            }
            _ => &self.plain,
        }
    }
}

fn declare_plain(decl: PassDecl, setup: &DeclareContext) -> PassDecl {
    let decl = decl.unbind(DIRECT_LIGHT);
    if setup.settings.ao.technique == Technique::SsdoBounce {
        decl.note("bounce left out: bounce strength is 0")
    } else {
        decl
    }
}

fn declare_bounce(decl: PassDecl, setup: &DeclareContext) -> PassDecl {
    if has_direct(setup) {
        decl
    } else {
        decl.unbind(DIRECT_LIGHT).note("no bounce: the host gave no direct light")
    }
}

impl Pass for SsdoPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        debug_assert!(matches!(self.technique, Technique::Ssdo | Technique::SsdoBounce));
        self.march(setup).declare(setup)
    }

    fn record(&self, ctx: &mut RecordContext) {
        self.march(ctx.setup).record(ctx)
    }

    /// The count of whichever march recorded last (each keeps its frame's index).
    fn right_eye_tiles(&self, gpu: &Gpu) -> Option<RightEyeTiles> {
        let marches = std::iter::once(&self.plain).chain(&self.bounce);
        marches.filter_map(|m| m.right_eye_tiles(gpu)).max_by_key(|t| t.frame)
    }

    fn right_eye_listed(&self, gpu: &Gpu) -> Option<(RightEyeTiles, Vec<[u32; 2]>)> {
        let marches = std::iter::once(&self.plain).chain(&self.bounce);
        marches.filter_map(|m| m.right_eye_listed(gpu)).max_by_key(|(t, _)| t.frame)
    }
}
