//! What the screen-space occlusion techniques share: the textures they write
//! ([`AO_RAW`], [`AO_GEOMETRY`]), the binding layout of occlusion.wgsl, how a technique
//! declares itself, and [`TechniquePass`], the pass of a technique that is one kernel
//! of that layout (SSAO, HBAO, the fetch-only baseline). GTAO and SSDO, which bind more,
//! are passes of their own in their folders.

use super::{DeclareContext, Pass, RecordContext};
use crate::gpu::kernel::{wgsl, Bind, Kernel, Shader, COMMON, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, Size, OCCLUSION};
use crate::passes::inputs::{DEPTH, NORMALS};
use crate::resource::ChainLayout;
use crate::settings::Technique;

/// Occlusion as computed (at AO resolution): rgb = SSDO's gathered irradiance
/// (environment through unblocked directions plus the bounce), a = AO.
pub const AO_RAW: Resource = Resource::chain_storage("ao-raw", Size::Occlusion);

/// Normal (xyz) and view distance (w, 0 on the sky) at each occlusion pixel, written by
/// the technique so the denoise and upsample need one fetch per tap instead of depth,
/// normal and a reconstruction. Half floats: 8 bytes a tap instead of 16 for the
/// denoise's and the upsampling's fetches; their tests are relative to the distance
/// (2 % and more) and f16 keeps it to 0.05 %. Distances clamp at 65504 m
/// (occlusion.wgsl `begin_receiver`), far beyond any radius a pixel there resolves.
pub const AO_GEOMETRY: Resource = Resource::storage("ao-geometry", Size::Occlusion, wgpu::TextureFormat::Rgba16Float);

/// occlusion.wgsl: the layout and helpers every technique's WGSL builds on.
pub const OCCLUSION_WGSL: Shader = wgsl!("src/passes/occlusion/occlusion.wgsl");

/// Bindings 0–6 of occlusion.wgsl: frame, AO parameters, sample kernel, depth, normals,
/// raw occlusion out, AO geometry out.
pub(crate) const BINDINGS: [Bind; 7] = [
    Bind::Frame,
    Bind::AoParams,
    Bind::SampleKernel,
    Bind::Read(DEPTH),
    Bind::Read(NORMALS),
    Bind::Write(AO_RAW),
    Bind::Write(AO_GEOMETRY),
];

/// `BINDINGS` followed by a technique's own bindings (from binding 7 on); `M` is the
/// total, checked when the constant is made.
pub const fn bindings_and<const N: usize, const M: usize>(own: [Bind; N]) -> [Bind; M] {
    assert!(M == BINDINGS.len() + N, "M must be 7 + N");
    let mut all = [Bind::Frame; M];
    let mut i = 0;
    while i < M {
        all[i] = if i < BINDINGS.len() { BINDINGS[i] } else { own[i - BINDINGS.len()] };
        i += 1;
    }
    all
}

/// A technique pass's declaration: its bindings (the G-buffer in, the raw occlusion and
/// its geometry out), the raw occlusion provided as the AO chain's start, counted as the
/// occlusion's cost, and left out unless the chosen technique is one of `runs_for`.
pub fn technique_decl(name: &'static str, binds: &[Bind], runs_for: &[Technique], setup: &DeclareContext) -> PassDecl {
    let chosen = setup.settings.ao.technique;
    let reason = if chosen == Technique::None {
        "technique is none: no occlusion pass".to_string()
    } else {
        format!("technique is {}", chosen.name())
    };
    PassDecl::new(name)
        .bindings(binds)
        .provide(OCCLUSION, AO_RAW)
        .occlusion_cost()
        .disabled_if(!runs_for.contains(&chosen), reason)
}

/// A technique that is one kernel of the shared layout: its WGSL defines the
/// occlusion of one pixel, occlusion.wgsl the rest.
pub(crate) struct TechniquePass {
    technique: Technique,
    kernel: Kernel,
}

impl TechniquePass {
    /// The pass of `technique`, whose WGSL is `shader`.
    pub(crate) fn new(gpu: &Gpu, technique: Technique, shader: Shader) -> Self {
        let files = [COMMON, VISIBILITY, OCCLUSION_WGSL, shader];
        // The technique decides the chain's layout (technique.carries_light()).
        let chain = ChainLayout::of(technique.carries_light(), gpu.caps.scalar_chain);
        let kernel = Kernel::in_chain(gpu, technique.name(), &files, "main", &BINDINGS, &[], chain);
        TechniquePass { technique, kernel }
    }
}

impl Pass for TechniquePass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        technique_decl(self.technique.name(), &BINDINGS, &[self.technique], setup)
    }

    fn record(&self, ctx: &mut RecordContext) {
        let resources = ctx.bind(&BINDINGS, &[]);
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, ctx.visibility.bind_group(), &resources, ctx.ao_extent());
    }
}
