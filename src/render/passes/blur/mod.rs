//! The spatial denoise of the occlusion, at occlusion resolution, each layer alone, as a
//! horizontal then a vertical dispatch through `AoBlurH`: the default edge-aware box
//! matched to the 4×4 noise tile (shaders/denoise.wgsl), or the geometry-aware 11×11
//! bilateral blur (shaders/bilateral.wgsl).

use super::occlusion::layer_view;
use super::{occlusion_before_upsample, occlusion_source, FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use crate::render::settings::{Denoise, Technique};

/// Pixels per invocation of the tile denoise (`RUN` in shaders/denoise.wgsl).
const DENOISE_RUN: u32 = 4;

/// One denoise kind's pipelines: horizontal, vertical, and the right eye's vertical
/// dispatch that reuses the left eye (shaders/denoise_stereo.wgsl).
struct DenoiseKernels {
    horizontal: Kernel,
    vertical: Kernel,
    right_eye_vertical: Kernel,
}

impl DenoiseKernels {
    /// `constants`: the shader's pipeline constants besides `RIGHT_EYE`.
    fn new(gpu: &Gpu, shader: &str, horizontal: &str, vertical: &str, constants: &[(&str, f64)]) -> Self {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::AoBlurred.format()),
            Slot::Depth,
            Slot::Layers,
        ];
        let files = ["common.wgsl", "denoise_stereo.wgsl", shader];
        let kernel = |entry: &str, right_eye: bool| {
            let mut constants = constants.to_vec();
            constants.push(("RIGHT_EYE", f64::from(right_eye)));
            let label = if right_eye { format!("{entry} right eye") } else { entry.to_string() };
            Kernel::with_constants(gpu, &label, &files, entry, &slots, &constants)
        };
        DenoiseKernels {
            horizontal: kernel(horizontal, false),
            vertical: kernel(vertical, false),
            right_eye_vertical: kernel(vertical, true),
        }
    }
}

/// The spatial denoise of the occlusion: the tile denoise or the separable bilateral blur
/// (module docs).
pub struct BlurPass {
    /// The tile denoise by whether the occlusion carries light in rgb (SSDO) or AO alone.
    tile: [DenoiseKernels; 2],
    bilateral: DenoiseKernels,
}

impl BlurPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> Self {
        BlurPass {
            tile: [false, true].map(|carries_light| {
                let constants = [("CARRIES_LIGHT", f64::from(carries_light))];
                DenoiseKernels::new(gpu, "denoise.wgsl", "denoise_horizontal", "denoise_vertical", &constants)
            }),
            bilateral: DenoiseKernels::new(gpu, "bilateral.wgsl", "blur_horizontal", "blur_vertical", &[]),
        }
    }
}

impl Pass for BlurPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let ao = &setup.settings.ao;
        PassDecl::new("blur")
            .read(Resource::Depth)
            .read(Resource::AoGeometry)
            .read(occlusion_source(setup.settings))
            .write(Resource::AoBlurH)
            .write(Resource::AoBlurred)
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to blur")
            .disabled_if(ao.blur_radius == 0, "blur radius is 0")
    }

    fn record(&self, ctx: &mut FrameContext) {
        debug_assert_eq!(occlusion_before_upsample(ctx.setup.settings), Some(Resource::AoBlurred));
        let source = occlusion_source(ctx.setup.settings);
        let ao = &ctx.setup.settings.ao;
        let kernels = match ao.denoise {
            Denoise::Tile => &self.tile[usize::from(ao.technique.carries_light())],
            Denoise::Bilateral => &self.bilateral,
        };
        // The tile denoise filters runs of `DENOISE_RUN` pixels along each pass's axis.
        let (w, h, layers) = ctx.ao_extent();
        let (horizontal_grid, vertical_grid) = match ao.denoise {
            Denoise::Tile => ((w.div_ceil(DENOISE_RUN), h, layers), (w, h.div_ceil(DENOISE_RUN))),
            Denoise::Bilateral => ((w, h, layers), (w, h)),
        };
        // At half resolution only: there each eye upsamples from its own grid and the eyes
        // drifted apart (furnished, 540×600: 2.0 % of the points both see differ by more
        // than 0.02; 1.3 % with the reuse, at a cost within the timing noise; the right
        // eye's upsample reuses the left eye's too for AO-only techniques, and SSDO's
        // values feed the right eye's own upsample where the left eye does not see). At full
        // resolution they already agree (Sibenik 1080×1200: 0.5 %) and the reuse's lookups
        // cost a fifth of the denoise (80–101 against 64–84 ms per eye, lavapipe).
        let reuse = ao.stereo_reuse && ao.half_res && layers == 2;
        let device = &ctx.gpu.device;
        let horizontal = resources(ctx, source, Resource::AoBlurH);
        kernels.horizontal.dispatch(device, ctx.encoder, &horizontal, horizontal_grid);
        // The vertical pass: both eyes alike, or the left eye and then the right eye
        // reusing it.
        let mut vertical = resources(ctx, Resource::AoBlurH, Resource::AoBlurred);
        let filtered_layers = if reuse { 1 } else { layers };
        kernels.vertical.dispatch(device, ctx.encoder, &vertical, (vertical_grid.0, vertical_grid.1, filtered_layers));
        if reuse {
            let (right, left) = (layer_view(ctx, Resource::AoBlurred, 1), layer_view(ctx, Resource::AoBlurred, 0));
            vertical[4] = wgpu::BindingResource::TextureView(&right);
            vertical[6] = wgpu::BindingResource::TextureView(&left);
            kernels.right_eye_vertical.dispatch(device, ctx.encoder, &vertical, (vertical_grid.0, vertical_grid.1, 1));
        }
    }
}

/// Bindings of both denoise shaders: frame, AO parameters, geometry, input, output,
/// depth and, at 6, the output's left-eye layer for the right eye's vertical dispatch
/// (AoGeometry stands in before it).
fn resources<'a>(ctx: &FrameContext<'a>, input: Resource, output: Resource) -> [wgpu::BindingResource<'a>; 7] {
    [
        ctx.frame.frame.as_entire_binding(),
        ctx.frame.ao.as_entire_binding(),
        ctx.view(Resource::AoGeometry),
        ctx.view(input),
        ctx.view(output),
        ctx.view(Resource::Depth),
        ctx.view(Resource::AoGeometry),
    ]
}
