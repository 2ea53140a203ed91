//! The screen-space occlusion techniques that share one binding layout
//! (shaders/occlusion.wgsl): SSAO (seed 003 §3.2, seed 000 ch. 3), HBAO (seed 003 §3.3),
//! GTAO with a visibility bitmask and the fetch-only benchmark baseline. Each technique itself is its WGSL file; SSDO,
//! which also reads the direct light, is `ssdo.rs`.

use super::{FrameContext, FrameSetup, Pass};
use crate::gpu::frame::gtao_inner_band;
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::Technique;

/// Bindings 0–6 of occlusion.wgsl: frame, AO parameters, sample kernel, depth,
/// normals, raw occlusion out, AO geometry out.
pub const SLOTS: [Slot; 7] = [
    Slot::Uniform,
    Slot::Uniform,
    Slot::ReadBuffer,
    Slot::Depth,
    Slot::Layers,
    Slot::Output(wgpu::TextureFormat::Rgba16Float),
    Slot::Output(wgpu::TextureFormat::Rgba32Float),
];

/// The resources for [`SLOTS`], in order.
pub fn bindings<'a>(ctx: &FrameContext<'a>) -> Vec<wgpu::BindingResource<'a>> {
    vec![
        ctx.frame.frame.as_entire_binding(),
        ctx.frame.ao.as_entire_binding(),
        ctx.frame.kernel.as_entire_binding(),
        ctx.view(Resource::Depth),
        ctx.view(Resource::Normals),
        ctx.view(Resource::AoRaw),
        ctx.view(Resource::AoGeometry),
    ]
}

/// Completes a technique pass's declaration: it reads the G-buffer, writes raw
/// occlusion and its geometry, and is left out unless the chosen technique is one of
/// `runs_for`.
pub fn technique_decl(decl: PassDecl, runs_for: &[Technique], setup: &FrameSetup) -> PassDecl {
    let chosen = setup.settings.ao.technique;
    let reason = if chosen == Technique::None {
        "technique is none: no occlusion pass".to_string()
    } else {
        format!("technique is {}", chosen.name())
    };
    decl.read(Resource::Depth)
        .read(Resource::Normals)
        .write(Resource::AoRaw)
        .write(Resource::AoGeometry)
        .disabled_if(!runs_for.contains(&chosen), reason)
}

/// One technique of the shared layout.
pub struct OcclusionPass {
    technique: Technique,
    kernel: Kernel,
    /// GTAO's second dispatch: the columns along each eye's inner border, compiled with
    /// the other-eye lookups (gtao.wgsl `INNER_BAND`); `kernel` runs the rest.
    inner_band: Option<Kernel>,
}

impl OcclusionPass {
    fn new(gpu: &Gpu, technique: Technique, shader: &str) -> Self {
        let kernel = Kernel::new(gpu, technique.name(), &["common.wgsl", "occlusion.wgsl", shader], "main", &SLOTS);
        OcclusionPass { technique, kernel, inner_band: None }
    }

    pub fn ssao(gpu: &Gpu) -> Self {
        Self::new(gpu, Technique::Ssao, "ssao.wgsl")
    }

    pub fn hbao(gpu: &Gpu) -> Self {
        Self::new(gpu, Technique::Hbao, "hbao.wgsl")
    }

    pub fn gtao(gpu: &Gpu) -> Self {
        let files = ["common.wgsl", "occlusion.wgsl", "gtao.wgsl"];
        let label = Technique::Gtao.name();
        let constants = |band: bool| [("INNER_BAND", if band { 1.0 } else { 0.0 })];
        OcclusionPass {
            technique: Technique::Gtao,
            kernel: Kernel::with_constants(gpu, label, &files, "main", &SLOTS, &constants(false)),
            inner_band: Some(Kernel::with_constants(gpu, label, &files, "main", &SLOTS, &constants(true))),
        }
    }

    /// SSAO's depth taps without the occlusion arithmetic (benchmark baseline).
    pub fn fetch_only(gpu: &Gpu) -> Self {
        Self::new(gpu, Technique::FetchOnly, "fetch.wgsl")
    }
}

impl Pass for OcclusionPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(PassDecl::new(self.technique.name()), &[self.technique], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let resources = bindings(ctx);
        let (width, height, layers) = ctx.ao_extent();
        match &self.inner_band {
            None => self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, (width, height, layers)),
            Some(band_kernel) => {
                let band = gtao_inner_band(width);
                self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, (width - band, height, layers));
                band_kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, (band, height, layers));
            }
        }
    }
}
