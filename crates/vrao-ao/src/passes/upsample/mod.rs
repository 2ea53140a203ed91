//! 3×3 joint bilateral upsampling of half-resolution occlusion (the Czech SSDO thesis)
//! into a full-resolution target (upsample.wgsl, on joint_upsample.wgsl, which the
//! composite shares). Frames upsample inside the composite instead, so the graph runs
//! this pass only when the full-resolution AO itself is asked for (the final AO of the
//! outputs, the bench, the window's buffer view, tests).

use super::inputs::{DEPTH, NORMALS};
use super::occlusion::AO_GEOMETRY;
use super::{DeclareContext, Pass, RecordContext};
use crate::gpu::kernel::{wgsl, Bind, Kernel, Shader, Slot, COMMON, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, Size, FINAL_AO, OCCLUSION};
use crate::passes::ChainSettings;
use crate::settings::Technique;

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "upsample";

/// The occlusion upsampled from half to full resolution.
pub const AO_FULL: Resource = Resource::storage("ao-full", Size::Full, wgpu::TextureFormat::Rgba16Float);

/// joint_upsample.wgsl: the 3×3 joint bilateral weights and the right eye's reuse of the
/// left eye's result, shared with the composite.
pub const JOINT_UPSAMPLE_WGSL: Shader = wgsl!("src/passes/upsample/joint_upsample.wgsl");

/// upsample.wgsl's bindings: frame, AO parameters, the G-buffer and the occlusion's
/// geometry, the occlusion in, the full-resolution AO out and, at 7, its left-eye layer
/// for the right eye's dispatch (the geometry stands in before it).
const BINDINGS: [Bind; 8] = [
    Bind::Frame,
    Bind::AoParams,
    Bind::Read(DEPTH),
    Bind::Read(NORMALS),
    Bind::Read(AO_GEOMETRY),
    Bind::Read(OCCLUSION),
    Bind::Write(AO_FULL),
    Bind::Own(Slot::Layers),
];

/// Whether the right eye takes the left eye's upsampled AO instead of upsampling its own
/// wherever the left eye sees the same point (joint_upsample.wgsl `right_eye_quad`): with
/// the stereo reuse, two views and half-resolution occlusion of an AO-only technique
/// (SSDO's rgb carries gathered light, which the composite's alpha, where the left eye's
/// AO waits for the right eye, cannot hold).
pub fn reuses_left_eye_upsample(settings: &ChainSettings, layers: u32) -> bool {
    let ao = &settings.ao;
    ao.stereo_reuse
        && ao.resolution.is_half()
        && layers == 2
        && ao.technique != Technique::None
        && !ao.technique.carries_light()
}

/// Joint bilateral upsampling of half-resolution occlusion to full resolution (module docs).
pub(crate) struct UpsamplePass {
    kernel: Kernel,
    /// The right eye's dispatch that reuses the left eye's result.
    right_eye: Kernel,
}

impl UpsamplePass {
    /// Builds the pass's pipelines.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, VISIBILITY, JOINT_UPSAMPLE_WGSL, wgsl!("src/passes/upsample/upsample.wgsl")];
        let kernel = |label: &str, right_eye: bool| {
            Kernel::with_constants(gpu, label, &files, "main", &BINDINGS, &[("RIGHT_EYE", f64::from(right_eye))])
        };
        UpsamplePass { kernel: kernel("upsample", false), right_eye: kernel("upsample right eye", true) }
    }
}

impl Pass for UpsamplePass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let ao = &setup.settings.ao;
        PassDecl::new(NAME)
            .bindings(&BINDINGS)
            .provide(FINAL_AO, AO_FULL)
            .occlusion_cost()
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to upsample")
            .disabled_if(!ao.resolution.is_half(), "occlusion runs at full resolution")
    }

    fn record(&self, ctx: &mut RecordContext) {
        let resources = ctx.bind(&BINDINGS, &[ctx.view(AO_GEOMETRY)]);
        // One invocation per quad of 2×2 full-res pixels (upsample.wgsl): both eyes
        // alike, or the left eye and then the right eye reusing it.
        let (w, h, layers) = ctx.quad_extent();
        let reuse = reuses_left_eye_upsample(ctx.setup.settings, layers);
        let device = &ctx.gpu.device;
        self.kernel.dispatch(
            device,
            ctx.encoder,
            ctx.visibility.bind_group(),
            &resources,
            (w, h, if reuse { 1 } else { layers }),
        );
        if reuse {
            // The right eye writes layer 1 alone and reads the left eye's layer 0.
            let (right, left) = (ctx.layer_view(AO_FULL, 1), ctx.layer_view(AO_FULL, 0));
            let resources = ctx.bind_overriding(
                &BINDINGS,
                &[wgpu::BindingResource::TextureView(&left)],
                &[(AO_FULL, wgpu::BindingResource::TextureView(&right))],
            );
            self.right_eye.dispatch(device, ctx.encoder, ctx.visibility.bind_group(), &resources, (w, h, 1));
        }
    }
}
