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
use bytemuck::{Pod, Zeroable};

/// The shared bindings, at 7 and 8 the raw occlusion's and its geometry's left-eye
/// layers for the right eye's dispatch (gtao.wgsl `left_occlusion`, `left_geometry`),
/// and at 9 GTAO's own parameters.
const BINDINGS: [Bind; 10] =
    occlusion::bindings_and([Bind::Own(Slot::Layers), Bind::Own(Slot::Layers), Bind::Own(Slot::Uniform)]);

/// `GtaoParams` of gtao.wgsl: what GTAO reads besides the shared `AoParams`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GtaoUniform {
    slices: u32,
    steps: u32,
    thickness: f32,
    step_power: f32,
    connect: f32,
    inner_band: u32,
    /// A uniform struct's size is a multiple of 16 bytes.
    padding: [u32; 2],
}

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

/// GTAO's three pipelines (module docs) and its parameters.
pub struct GtaoPass {
    interior: Kernel,
    inner_band: Kernel,
    right_eye: Kernel,
    params: wgpu::Buffer,
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
        let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("gtao params"),
            size: std::mem::size_of::<GtaoUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        GtaoPass {
            interior: kernel(false, false),
            inner_band: kernel(true, false),
            right_eye: kernel(false, true),
            params,
        }
    }
}

impl Pass for GtaoPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(Technique::Gtao.name(), &BINDINGS, &[Technique::Gtao], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let (width, height, layers) = ctx.ao_extent();
        let device = &ctx.gpu.device;
        let ao = &ctx.setup.settings.ao;
        let (slices, steps) = gtao_slices_steps(ao.samples);
        let band = gtao_inner_band(width);
        let params = GtaoUniform {
            slices,
            steps,
            thickness: ao.thickness,
            step_power: ao.step_power,
            connect: ao.connect,
            inner_band: band,
            padding: [0; 2],
        };
        ctx.gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        // The left eye (or the only view) marches every pixel, in two parts; with two
        // views and `stereo_reuse`, the right eye then reuses it, else it marches alike.
        // Bindings 7 and 8 are unused before the right eye's dispatch: the normals stand in.
        let normals = ctx.view(super::gbuffer::NORMALS);
        let mut resources = ctx.bind(&BINDINGS, &[normals.clone(), normals, self.params.as_entire_binding()]);
        let reuse = ao.stereo_reuse && layers == 2;
        let marched_layers = if reuse { 1 } else { layers };
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
