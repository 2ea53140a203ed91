//! Reinhard tone mapping with a white point (the Czech SSDO thesis, eq. 2.4) and sRGB encoding.

use super::composite::HDR;
use crate::gpu::kernel::wgsl;
use vrao_ao::plug::{Bind, DeclareContext, Gpu, Kernel, Pass, PassDecl, RecordContext, Resource, Size, COMMON};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "tonemap";

/// Tone-mapped, sRGB-encoded eye colour.
pub const COLOR: Resource = Resource::storage("color", Size::Full, wgpu::TextureFormat::Rgba8Unorm);

const BINDINGS: [Bind; 3] = [Bind::Frame, Bind::Read(HDR), Bind::Write(COLOR)];

/// Tone mapping of the HDR radiance into the eye colour (module docs).
pub struct TonemapPass {
    kernel: Kernel,
}

impl TonemapPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, wgsl!("src/passes/tonemap/tonemap.wgsl")];
        TonemapPass { kernel: Kernel::new(gpu, "tonemap", &files, "main", &BINDINGS) }
    }
}

impl Pass for TonemapPass {
    fn declare(&self, _: &DeclareContext) -> PassDecl {
        PassDecl::new(NAME).bindings(&BINDINGS)
    }

    fn record(&self, ctx: &mut RecordContext) {
        let resources = ctx.bind(&BINDINGS, &[]);
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, ctx.visibility.bind_group(), &resources, ctx.extent());
    }
}
