//! SSDO, with the optional bounce gathered in the same loop (Ritschel et al. 2009 eqs. 1–2,
//! Belonogov 2018 §4.1–4.2). The technique itself is shaders/ssdo.wgsl; a bounce strength of
//! 0 selects the pipeline compiled without bounce work, which also does not read the
//! direct light, so the graph need not produce it for an occlusion-only frame.

use super::occlusion::{self, technique_decl};
use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::targets::LayeredTarget;
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use crate::render::settings::{BounceForm, Technique};

/// SSDO, with its bounce when the technique asks for it (module docs).
pub struct SsdoPass {
    /// Pipelines by [depth peeling][bounce: none, direction form, patch form]: pipeline
    /// constants, so a frame runs no code of what it left out.
    kernels: [[Kernel; 3]; 2],
    /// Bound in place of the direct light when the bounce is off (never read then).
    no_direct: LayeredTarget,
    /// Bound in place of the second depth layer when peeling is off (never read then).
    no_second_layer: LayeredTarget,
}

/// The shared occlusion bindings plus the direct light (binding 7, the bounce's senders)
/// and the second depth layer (binding 8, depth peeling).
const SLOTS: [Slot; 9] = [
    occlusion::SLOTS[0],
    occlusion::SLOTS[1],
    occlusion::SLOTS[2],
    occlusion::SLOTS[3],
    occlusion::SLOTS[4],
    occlusion::SLOTS[5],
    occlusion::SLOTS[6],
    Slot::UintLayers,
    Slot::Depth,
];

impl SsdoPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let files = ["common.wgsl", "irradiance.wgsl", "occlusion.wgsl", "ssdo.wgsl"];
        let no_direct = LayeredTarget::placeholder(&gpu.device, "no direct light", Resource::Direct.format());
        let labels = [
            ["ssdo", "ssdo-bounce", "ssdo-bounce patch"],
            ["ssdo peeled", "ssdo-bounce peeled", "ssdo-bounce patch peeled"],
        ];
        let kernels = [0, 1].map(|peel| {
            [0, 1, 2].map(|bounce| {
                let constants = [
                    ("PEEL", peel as f64),
                    ("BOUNCE", f64::from(bounce > 0)),
                    ("BOUNCE_PATCH", f64::from(bounce == 2)),
                ];
                Kernel::with_constants(gpu, labels[peel][bounce], &files, "main", &SLOTS, &constants)
            })
        });
        SsdoPass {
            kernels,
            no_direct,
            no_second_layer: LayeredTarget::placeholder(
                &gpu.device,
                "no second depth layer",
                Resource::DepthLayer2.format(),
            ),
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
        if ao.depth_peeling {
            decl = decl.read(Resource::DepthLayer2);
            let peel = "depth peeling: occluders only between the first and second depth layer";
            decl.note = Some(decl.note.map_or(peel.to_string(), |n| format!("{n}; {peel}")));
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
        let peel = ctx.setup.settings.ao.depth_peeling;
        let second = if peel {
            ctx.view(Resource::DepthLayer2)
        } else {
            wgpu::BindingResource::TextureView(&self.no_second_layer.array_view)
        };
        let mut resources = occlusion::bindings(ctx);
        resources.push(direct);
        resources.push(second);
        let extent = ctx.ao_extent();
        let form = match (bounce, ctx.setup.settings.ao.bounce_form) {
            (false, _) => 0,
            (true, BounceForm::Direction) => 1,
            (true, BounceForm::Patch) => 2,
        };
        let kernel = &self.kernels[peel as usize][form];
        kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, extent);
    }
}
