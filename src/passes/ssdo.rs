//! SSDO, with the optional bounce gathered in the same loop (seed 002 eqs. 1–2,
//! seed 003 §4.1–4.2). The technique itself is shaders/ssdo.wgsl; a bounce strength of
//! 0 selects the pipeline compiled without bounce work, which also does not read the
//! direct light, so the graph need not produce it for an occlusion-only frame.

use super::occlusion::{self, technique_decl};
use super::{FrameContext, FrameSetup, Pass};
use crate::gpu::kernel::{Kernel, Slot};
use crate::gpu::targets::LayeredTarget;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::settings::Technique;

pub struct SsdoPass {
    without_bounce: Kernel,
    with_bounce: Kernel,
    /// Bound in place of the direct light when the bounce is off (never read then).
    no_direct: LayeredTarget,
}

/// The shared occlusion bindings plus the direct light (binding 7, the bounce's senders).
const SLOTS: [Slot; 8] = [
    occlusion::SLOTS[0],
    occlusion::SLOTS[1],
    occlusion::SLOTS[2],
    occlusion::SLOTS[3],
    occlusion::SLOTS[4],
    occlusion::SLOTS[5],
    occlusion::SLOTS[6],
    Slot::Layers,
];

impl SsdoPass {
    pub fn new(gpu: &Gpu) -> Self {
        let files = ["common.wgsl", "occlusion.wgsl", "ssdo.wgsl"];
        let no_direct = LayeredTarget::placeholder(&gpu.device, "no direct light", Resource::Direct.format());
        SsdoPass {
            without_bounce: Kernel::with_constants(gpu, "ssdo", &files, "main", &SLOTS, &[("BOUNCE", 0.0)]),
            with_bounce: Kernel::with_constants(gpu, "ssdo-bounce", &files, "main", &SLOTS, &[("BOUNCE", 1.0)]),
            no_direct,
        }
    }
}

impl Pass for SsdoPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let ao = &setup.settings.ao;
        let chosen = ao.technique;
        let mut decl = PassDecl::new(if ao.bounce_active() { "ssdo-bounce" } else { "ssdo" });
        if ao.bounce_active() {
            decl = decl.read(Resource::Direct);
        } else if chosen == Technique::SsdoBounce {
            decl = decl.note("bounce left out: bounce strength is 0");
        }
        technique_decl(decl, &[Technique::Ssdo, Technique::SsdoBounce], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let bounce = ctx.setup.settings.ao.bounce_active();
        let direct = if bounce {
            ctx.view(Resource::Direct)
        } else {
            wgpu::BindingResource::TextureView(&self.no_direct.array_view)
        };
        let mut resources = occlusion::bindings(ctx);
        resources.push(direct);
        let extent = ctx.ao_extent();
        let kernel = if bounce { &self.with_bounce } else { &self.without_bounce };
        kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
