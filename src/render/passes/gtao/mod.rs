//! GTAO with a visibility bitmask (gtao.wgsl) on the shared occlusion layout, in three
//! pipelines of one shader: the rest of the image, the band along each eye's inner
//! border whose marches may look into the other eye, and the right eye reusing the left
//! eye's values where it sees the same point.

use super::occlusion::{self, technique_decl, AO_GEOMETRY, AO_RAW, OCCLUSION_WGSL};
use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{wgsl, Bind, Kernel, Slot, COMMON};
use crate::render::gpu::Gpu;
use crate::render::graph::PassDecl;
use crate::render::settings::Technique;

/// The shared bindings and, at 7 and 8, the raw occlusion's and its geometry's left-eye
/// layers for the right eye's dispatch (gtao.wgsl `left_occlusion`, `left_geometry`).
const BINDINGS: [Bind; 9] = [
    occlusion::BINDINGS[0],
    occlusion::BINDINGS[1],
    occlusion::BINDINGS[2],
    occlusion::BINDINGS[3],
    occlusion::BINDINGS[4],
    occlusion::BINDINGS[5],
    occlusion::BINDINGS[6],
    Bind::Own(Slot::Layers),
    Bind::Own(Slot::Layers),
];

/// GTAO's slices and steps per half-slice for a budget of `samples` depth taps
/// (slices × 2 × steps ≈ samples): 12 → 2×3, 24 → 2×6, 36 → 2×9, 64 → 2×16. Steps before
/// slices: the 4×4 noise tile turns each pixel's slices, so the denoise averages 16 × 2
/// directions anyway, while the occluders a sparse march steps over stay missed (a
/// bias, not noise). Measured at N = 24, half resolution, 540×600 (furnished, Sibenik,
/// Cornell): 3×4 gave RMSE 0.052 / 0.064 / 0.044 and bias where the reference is below
/// 0.8 of +0.11 / +0.15 / +0.06; 2×6 gave 0.047 / 0.059 / 0.037 and +0.08 / +0.12 / +0.04.
pub fn gtao_slices_steps(samples: u32) -> (u32, u32) {
    let slices = if samples < 128 { 2 } else { 4 };
    (slices, (samples / (2 * slices)).max(1))
}

/// GTAO's inner-border band for occlusion targets `width` pixels wide: a quarter of the
/// width (whole 8-pixel workgroups). Only marches from this band look past the inner
/// border into the other eye; one from further in that would cross it (its radius spans
/// more than a quarter of the image: a surface very near the eye) stops there instead.
pub fn gtao_inner_band(width: u32) -> u32 {
    (width / 4).next_multiple_of(8).min(width)
}

/// GTAO's three pipelines (module docs).
pub struct GtaoPass {
    interior: Kernel,
    inner_band: Kernel,
    right_eye: Kernel,
}

impl GtaoPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, OCCLUSION_WGSL, wgsl!("src/render/passes/gtao/gtao.wgsl")];
        let label = Technique::Gtao.name();
        let kernel = |band: bool, right: bool| {
            let constants = [
                ("INNER_BAND", f64::from(band)),
                ("RIGHT_EYE", f64::from(right)),
                ("SINGLE_LAYER_OUTPUT", f64::from(right)),
            ];
            Kernel::with_constants(gpu, label, &files, "main", &BINDINGS, &constants)
        };
        GtaoPass { interior: kernel(false, false), inner_band: kernel(true, false), right_eye: kernel(false, true) }
    }
}

impl Pass for GtaoPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(Technique::Gtao.name(), &BINDINGS, &[Technique::Gtao], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let (width, height, layers) = ctx.ao_extent();
        let device = &ctx.gpu.device;
        // The left eye (or the only view) marches every pixel, in two parts; with two
        // views and `stereo_reuse`, the right eye then reuses it, else it marches alike.
        // Bindings 7 and 8 are unused before the right eye's dispatch: the normals stand in.
        let normals = ctx.view(super::gbuffer::NORMALS);
        let mut resources = ctx.bind(&BINDINGS, &[normals.clone(), normals]);
        let reuse = ctx.setup.settings.ao.stereo_reuse && layers == 2;
        let marched_layers = if reuse { 1 } else { layers };
        let band = gtao_inner_band(width);
        self.interior.dispatch(device, ctx.encoder, &resources, (width - band, height, marched_layers));
        self.inner_band.dispatch(device, ctx.encoder, &resources, (band, height, marched_layers));
        if !reuse {
            return;
        }
        let (ao_right, geometry_right) = (ctx.layer_view(AO_RAW, 1), ctx.layer_view(AO_GEOMETRY, 1));
        let (ao_left, geometry_left) = (ctx.layer_view(AO_RAW, 0), ctx.layer_view(AO_GEOMETRY, 0));
        resources[5] = wgpu::BindingResource::TextureView(&ao_right);
        resources[6] = wgpu::BindingResource::TextureView(&geometry_right);
        resources[7] = wgpu::BindingResource::TextureView(&ao_left);
        resources[8] = wgpu::BindingResource::TextureView(&geometry_left);
        self.right_eye.dispatch(device, ctx.encoder, &resources, (width, height, 1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gtao_presets_spend_ssao_tap_counts() {
        for (samples, split) in [(12, (2, 3)), (24, (2, 6)), (36, (2, 9)), (64, (2, 16)), (1, (2, 1)), (256, (4, 32))] {
            assert_eq!(gtao_slices_steps(samples), split);
        }
    }
}
