//! Direct light from the scene's point and directional lights, plus emission, as
//! outgoing radiance. The composite builds on it; SSDO's bounce reads it as L_pixel.
//! Directional lights are shadowed by their shadow maps (3×3 PCF, passes/shadow) when
//! shadows are on.

use super::gbuffer::{ALBEDO, EMISSION, LIGHTING_NORMALS};
use super::shadow::{shadows_active, LightSpace, SHADOW_MAP, SHADOW_WGSL};
use super::{gpu_scene_of, scene_of, settings_of};
use crate::gpu::kernel::wgsl;
use crate::lighting::LIGHTING_WGSL;
use std::sync::Arc;
use vrao_ao::plug::{
    Bind, DeclareContext, Gpu, Kernel, Pass, PassDecl, RecordContext, Resource, Slot, COMMON, DEPTH, VISIBILITY,
};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "direct";

/// Outgoing direct radiance (lights and emission) and the view distance, packed
/// (common.wgsl `pack_direct`: distance f32, radiance RGB9E5): the composite's base, and
/// the depth test plus sender radiance of SSDO's bounce in a single fetch.
pub const DIRECT: Resource = vrao_ao::plug::DIRECT_LIGHT;

/// direct.wgsl's bindings: the lights, the G-buffer in, the direct light out, the
/// shadows (their `Shadows` uniform, every light's map, the comparison sampler) and the
/// lights' count (`Shading`).
const BINDINGS: [Bind; 11] = [
    Bind::Frame,
    Bind::Own(Slot::ReadBuffer),
    Bind::Read(DEPTH),
    Bind::Read(LIGHTING_NORMALS),
    Bind::Read(ALBEDO),
    Bind::Read(EMISSION),
    Bind::Write(DIRECT),
    Bind::Own(Slot::Uniform),
    Bind::Read(SHADOW_MAP),
    Bind::Own(Slot::ComparisonSampler),
    Bind::Own(Slot::Uniform),
];

/// Direct light of every light, shadowed where shadow maps exist (module docs).
pub struct DirectLightPass {
    kernel: Kernel,
    light_space: Arc<LightSpace>,
}

impl DirectLightPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, light_space: Arc<LightSpace>) -> Self {
        let files = [COMMON, VISIBILITY, LIGHTING_WGSL, SHADOW_WGSL, wgsl!("src/passes/direct/direct.wgsl")];
        DirectLightPass { kernel: Kernel::new(gpu, "direct", &files, "main", &BINDINGS), light_space }
    }
}

impl Pass for DirectLightPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let decl = PassDecl::new(NAME).bindings(&BINDINGS);
        if shadows_active(scene_of(setup), settings_of(setup)) {
            decl.note("directional light shadowed: 3×3 PCF, bilinear compare, slope-scaled bias")
        } else {
            decl.unbind(SHADOW_MAP)
        }
    }

    fn record(&self, ctx: &mut RecordContext) {
        // Shadows (shadow.wgsl): every light's map, or no light and a placeholder map.
        let shadowed = shadows_active(scene_of(ctx.setup), settings_of(ctx.setup));
        let shadows = if shadowed { &self.light_space.uniform } else { &self.light_space.none };
        let shading = &gpu_scene_of(ctx.setup).shading;
        let own = [
            shading.lights.as_entire_binding(),
            shadows.as_entire_binding(),
            wgpu::BindingResource::Sampler(&self.light_space.comparison),
            shading.shading.as_entire_binding(),
        ];
        let resources = ctx.bind(&BINDINGS, &own);
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, ctx.visibility.bind_group(), &resources, ctx.extent());
    }
}
