//! The spatial denoise of the occlusion, at occlusion resolution, each layer alone, as a
//! horizontal then a vertical dispatch through [`AO_BLUR_H`]: the default edge-aware box
//! matched to the 4×4 noise tile (denoise.wgsl), or the geometry-aware 11×11 bilateral
//! blur (bilateral.wgsl). Both share denoise_stereo.wgsl, the right eye's reuse of the
//! left eye.

use super::inputs::DEPTH;
use super::occlusion::AO_GEOMETRY;
use super::{DeclareContext, Pass, RecordContext};
use crate::gpu::kernel::{wgsl, Bind, ByChain, Kernel, Shader, Slot, COMMON, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, Size, OCCLUSION};
use crate::resource::ChainLayout;
use crate::settings::{Denoise, Technique};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "blur";

/// Horizontally denoised occlusion (first half of the separable filter).
pub(crate) const AO_BLUR_H: Resource = Resource::chain_storage("ao-blur-h", Size::Occlusion);

/// The denoised occlusion, at AO resolution.
pub const AO_BLURRED: Resource = Resource::chain_storage("ao-blurred", Size::Occlusion);

/// Bindings of both denoise shaders with the occlusion in and the horizontal result
/// out: frame, AO parameters, geometry, input, output, depth and, at 6, the output's
/// left-eye layer for the right eye's vertical dispatch (the geometry stands in before it)
/// and at 7 the sampler its gathers go through.
const HORIZONTAL: [Bind; 8] = [
    Bind::Frame,
    Bind::AoParams,
    Bind::Read(AO_GEOMETRY),
    Bind::Read(OCCLUSION),
    Bind::Write(AO_BLUR_H),
    Bind::Read(DEPTH),
    Bind::Own(Slot::Layers),
    Bind::GatherSampler,
];

/// [`HORIZONTAL`] with the horizontal result in and the denoised occlusion out.
const VERTICAL: [Bind; 8] = [
    HORIZONTAL[0],
    HORIZONTAL[1],
    HORIZONTAL[2],
    Bind::Read(AO_BLUR_H),
    Bind::Write(AO_BLURRED),
    HORIZONTAL[5],
    HORIZONTAL[6],
    HORIZONTAL[7],
];

/// Pixels per invocation of the tile denoise (`RUN` in denoise.wgsl).
const DENOISE_RUN: u32 = 4;

/// One denoise kind's pipelines: horizontal, vertical, and the right eye's vertical
/// dispatch that reuses the left eye (denoise_stereo.wgsl).
struct DenoiseKernels {
    horizontal: Kernel,
    vertical: Kernel,
    right_eye_vertical: Kernel,
}

impl DenoiseKernels {
    /// `constants`: the shader's pipeline constants besides `RIGHT_EYE`; `chain`: the
    /// layout of the occlusion it filters.
    fn new(
        gpu: &Gpu,
        shader: Shader,
        (horizontal, vertical): (&str, &str),
        constants: &[(&str, f64)],
        chain: ChainLayout,
    ) -> Self {
        let files = [COMMON, VISIBILITY, wgsl!("src/passes/blur/denoise_stereo.wgsl"), shader];
        let kernel = |entry: &str, binds: &[Bind], right_eye: bool| {
            let mut constants = constants.to_vec();
            constants.push(("RIGHT_EYE", f64::from(right_eye)));
            let label = if right_eye { format!("{entry} right eye") } else { entry.to_string() };
            Kernel::in_chain(gpu, &label, &files, entry, binds, &constants, chain)
        };
        DenoiseKernels {
            horizontal: kernel(horizontal, &HORIZONTAL, false),
            vertical: kernel(vertical, &VERTICAL, false),
            right_eye_vertical: kernel(vertical, &VERTICAL, true),
        }
    }
}

/// The spatial denoise of the occlusion: the tile denoise or the separable bilateral blur
/// (module docs).
pub(crate) struct BlurPass {
    /// The tile denoise by whether the occlusion carries light in rgb (SSDO) or AO alone,
    /// each in the chain layout such a technique has.
    tile: [DenoiseKernels; 2],
    bilateral: ByChain<DenoiseKernels>,
}

impl BlurPass {
    /// Builds the pass's pipelines.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        BlurPass {
            tile: [false, true].map(|carries_light| {
                let constants = [("CARRIES_LIGHT", f64::from(carries_light))];
                let shader = wgsl!("src/passes/blur/denoise.wgsl");
                let chain = ChainLayout::of(carries_light, gpu.caps.scalar_chain);
                DenoiseKernels::new(gpu, shader, ("denoise_horizontal", "denoise_vertical"), &constants, chain)
            }),
            bilateral: ByChain::new(gpu, |chain| {
                let shader = wgsl!("src/passes/blur/bilateral.wgsl");
                DenoiseKernels::new(gpu, shader, ("blur_horizontal", "blur_vertical"), &[], chain)
            }),
        }
    }
}

impl Pass for BlurPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let ao = &setup.settings.ao;
        PassDecl::new(NAME)
            .bindings(&HORIZONTAL)
            .bindings(&VERTICAL)
            .provide(OCCLUSION, AO_BLURRED)
            .occlusion_cost()
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to blur")
            .disabled_if(ao.blur_radius == 0, "blur radius is 0")
    }

    fn record(&self, ctx: &mut RecordContext) {
        let ao = &ctx.setup.settings.ao;
        let kernels = match ao.denoise {
            Denoise::Tile => &self.tile[usize::from(ao.technique.carries_light())],
            Denoise::Bilateral => self.bilateral.get(ctx.setup.chain),
        };
        // The tile denoise filters runs of `DENOISE_RUN` pixels along each pass's axis.
        let (w, h, layers) = ctx.ao_extent();
        let (horizontal_grid, vertical_grid) = match ao.denoise {
            Denoise::Tile => ((w.div_ceil(DENOISE_RUN), h, layers), (w, h.div_ceil(DENOISE_RUN))),
            Denoise::Bilateral => ((w, h, layers), (w, h)),
        };
        // At half resolution only, and only for SSDO: there each eye upsamples from its
        // own grid and the eyes drifted apart, which this reuse reduces. For the AO-only
        // techniques the upsampling reuses the left eye's final AO where it sees the same
        // point (upsample::reuses_left_eye_upsample), which makes this reuse redundant:
        // it barely changes how many points differ, and its extra right-eye dispatch makes
        // the stereo denoise costlier. At full resolution the eyes already agree and the
        // reuse's lookups add to the denoise's cost (docs/records/2026-11-29/measurements-in-code.md,
        // blur-stereo-reuse).
        let reuse = ao.stereo_reuse
            && ao.resolution.is_half()
            && layers == 2
            && !super::upsample::reuses_left_eye_upsample(ctx.setup.settings, layers);
        let device = &ctx.gpu.device;
        // Binding 6 is unused before the right eye's vertical dispatch: the geometry stands in.
        let stand_in = [ctx.view(AO_GEOMETRY)];
        let horizontal = ctx.bind(&HORIZONTAL, &stand_in);
        kernels.horizontal.dispatch(device, ctx.encoder, ctx.visibility.bind_group(), &horizontal, horizontal_grid);
        // The vertical pass: both eyes alike, or the left eye and then the right eye
        // reusing it.
        let mut vertical = ctx.bind(&VERTICAL, &stand_in);
        let filtered_layers = if reuse { 1 } else { layers };
        kernels.vertical.dispatch(
            device,
            ctx.encoder,
            ctx.visibility.bind_group(),
            &vertical,
            (vertical_grid.0, vertical_grid.1, filtered_layers),
        );
        if reuse {
            let (right, left) = (ctx.layer_view(AO_BLURRED, 1), ctx.layer_view(AO_BLURRED, 0));
            vertical[4] = wgpu::BindingResource::TextureView(&right);
            vertical[6] = wgpu::BindingResource::TextureView(&left);
            kernels.right_eye_vertical.dispatch(
                device,
                ctx.encoder,
                ctx.visibility.bind_group(),
                &vertical,
                (vertical_grid.0, vertical_grid.1, 1),
            );
        }
    }
}
