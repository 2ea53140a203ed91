//! Reinhard tone mapping with a white point (the Czech SSDO thesis, eq. 2.4) and sRGB encoding.

use super::composite::HDR;
use super::gpu_scene_of;
use crate::gpu::kernel::wgsl;
use crate::lighting::LIGHTING_WGSL;
use vrao_ao::plug::{Bind, DeclareContext, Gpu, Kernel, Pass, PassDecl, RecordContext, Resource, Size, Slot, COMMON};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "tonemap";

/// Tone-mapped, sRGB-encoded eye colour.
pub const COLOR: Resource = Resource::storage("color", Size::Full, wgpu::TextureFormat::Rgba8Unorm);

/// The frame, the HDR in, the colour out, and the exposure and white point (`Shading`).
const BINDINGS: [Bind; 4] = [Bind::Frame, Bind::Read(HDR), Bind::Write(COLOR), Bind::Own(Slot::Uniform)];

/// Tone mapping of the HDR radiance into the eye colour (module docs).
pub struct TonemapPass {
    kernel: Kernel,
}

impl TonemapPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, LIGHTING_WGSL, wgsl!("src/passes/tonemap/tonemap.wgsl")];
        TonemapPass { kernel: Kernel::new(gpu, "tonemap", &files, "main", &BINDINGS) }
    }
}

impl Pass for TonemapPass {
    fn declare(&self, _: &DeclareContext) -> PassDecl {
        PassDecl::new(NAME).bindings(&BINDINGS)
    }

    fn record(&self, ctx: &mut RecordContext) {
        let shading = gpu_scene_of(ctx.setup).shading.shading.as_entire_binding();
        let resources = ctx.bind(&BINDINGS, &[shading]);
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, ctx.visibility.bind_group(), &resources, ctx.extent());
    }
}
