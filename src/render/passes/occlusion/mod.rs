//! The screen-space occlusion techniques that share one binding layout
//! (shaders/occlusion.wgsl): SSAO (Belonogov 2018 §3.2, the Czech SSDO thesis ch. 3), HBAO
//! (Belonogov 2018 §3.3), GTAO with a visibility bitmask and the fetch-only benchmark baseline.
//! Each technique itself is its WGSL file; SSDO, which also reads the direct light, is
//! `ssdo.rs`.

use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::frame::gtao_inner_band;
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use crate::render::settings::Technique;

/// Bindings 0–6 of occlusion.wgsl: frame, AO parameters, sample kernel, depth,
/// normals, raw occlusion out, AO geometry out.
pub const SLOTS: [Slot; 7] = [
    Slot::Uniform,
    Slot::Uniform,
    Slot::ReadBuffer,
    Slot::Depth,
    Slot::Layers,
    Slot::Output(wgpu::TextureFormat::Rgba16Float),
    Slot::Output(wgpu::TextureFormat::Rgba32Float),
];

/// The resources for [`SLOTS`], in order.
pub fn bindings<'a>(ctx: &FrameContext<'a>) -> Vec<wgpu::BindingResource<'a>> {
    vec![
        ctx.frame.frame.as_entire_binding(),
        ctx.frame.ao.as_entire_binding(),
        ctx.frame.kernel.as_entire_binding(),
        ctx.view(Resource::Depth),
        ctx.view(Resource::Normals),
        ctx.view(Resource::AoRaw),
        ctx.view(Resource::AoGeometry),
    ]
}

/// Completes a technique pass's declaration: it reads the G-buffer, writes raw
/// occlusion and its geometry, and is left out unless the chosen technique is one of
/// `runs_for`.
pub fn technique_decl(decl: PassDecl, runs_for: &[Technique], setup: &FrameSetup) -> PassDecl {
    let chosen = setup.settings.ao.technique;
    let reason = if chosen == Technique::None {
        "technique is none: no occlusion pass".to_string()
    } else {
        format!("technique is {}", chosen.name())
    };
    decl.read(Resource::Depth)
        .read(Resource::Normals)
        .write(Resource::AoRaw)
        .write(Resource::AoGeometry)
        .disabled_if(!runs_for.contains(&chosen), reason)
}

/// GTAO's bindings: the shared ones and, at 7 and 8, AoRaw's and AoGeometry's left-eye
/// layers for the right eye's dispatch (gtao.wgsl `left_occlusion`, `left_geometry`).
const GTAO_SLOTS: [Slot; 9] =
    [SLOTS[0], SLOTS[1], SLOTS[2], SLOTS[3], SLOTS[4], SLOTS[5], SLOTS[6], Slot::Layers, Slot::Layers];

/// GTAO's three pipelines of one shader (gtao.wgsl): the rest of the image, the band
/// along the inner border with the other-eye lookups, and the right eye reusing the
/// left eye's values.
struct GtaoKernels {
    interior: Kernel,
    inner_band: Kernel,
    right_eye: Kernel,
}

/// A technique's pipelines: one, or GTAO's three. One value per pass, made once, so
/// the size difference between the variants costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
enum Kernels {
    One(Kernel),
    Gtao(GtaoKernels),
}

/// One technique of the shared layout.
pub struct OcclusionPass {
    technique: Technique,
    kernels: Kernels,
}

impl OcclusionPass {
    fn new(gpu: &Gpu, technique: Technique, shader: &str) -> Self {
        let kernel = Kernel::new(gpu, technique.name(), &["common.wgsl", "occlusion.wgsl", shader], "main", &SLOTS);
        OcclusionPass { technique, kernels: Kernels::One(kernel) }
    }

    /// The occlusion pass of SSAO (shaders/ssao.wgsl).
    pub fn ssao(gpu: &Gpu) -> Self {
        Self::new(gpu, Technique::Ssao, "ssao.wgsl")
    }

    /// The occlusion pass of HBAO (shaders/hbao.wgsl).
    pub fn hbao(gpu: &Gpu) -> Self {
        Self::new(gpu, Technique::Hbao, "hbao.wgsl")
    }

    /// The occlusion pass of GTAO (shaders/gtao.wgsl), its three pipelines.
    pub fn gtao(gpu: &Gpu) -> Self {
        let files = ["common.wgsl", "occlusion.wgsl", "gtao.wgsl"];
        let label = Technique::Gtao.name();
        let kernel = |band: bool, right: bool| {
            let constants = [
                ("INNER_BAND", f64::from(band)),
                ("RIGHT_EYE", f64::from(right)),
                ("SINGLE_LAYER_OUTPUT", f64::from(right)),
            ];
            Kernel::with_constants(gpu, label, &files, "main", &GTAO_SLOTS, &constants)
        };
        OcclusionPass {
            technique: Technique::Gtao,
            kernels: Kernels::Gtao(GtaoKernels {
                interior: kernel(false, false),
                inner_band: kernel(true, false),
                right_eye: kernel(false, true),
            }),
        }
    }

    /// SSAO's depth taps without the occlusion arithmetic (benchmark baseline).
    pub fn fetch_only(gpu: &Gpu) -> Self {
        Self::new(gpu, Technique::FetchOnly, "fetch.wgsl")
    }
}

/// A one-layer array view of `layer` of a resource's target.
pub fn layer_view(ctx: &FrameContext, r: Resource, layer: u32) -> wgpu::TextureView {
    ctx.target(r).texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some(r.name()),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

impl Pass for OcclusionPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        technique_decl(PassDecl::new(self.technique.name()), &[self.technique], setup)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let (width, height, layers) = ctx.ao_extent();
        let device = &ctx.gpu.device;
        let gtao = match &self.kernels {
            Kernels::One(kernel) => {
                kernel.dispatch(device, ctx.encoder, &bindings(ctx), (width, height, layers));
                return;
            }
            Kernels::Gtao(gtao) => gtao,
        };
        // The left eye (or the only view) marches every pixel, in two parts; with two
        // views and `stereo_reuse`, the right eye then reuses it, else it marches alike.
        // Slots 7 and 8 are unused before the right eye's dispatch: the normals stand in.
        let mut resources = bindings(ctx);
        resources.push(ctx.view(Resource::Normals));
        resources.push(ctx.view(Resource::Normals));
        let reuse = ctx.setup.settings.ao.stereo_reuse && layers == 2;
        let marched_layers = if reuse { 1 } else { layers };
        let band = gtao_inner_band(width);
        gtao.interior.dispatch(device, ctx.encoder, &resources, (width - band, height, marched_layers));
        gtao.inner_band.dispatch(device, ctx.encoder, &resources, (band, height, marched_layers));
        if !reuse {
            return;
        }
        let (ao_right, geometry_right) =
            (layer_view(ctx, Resource::AoRaw, 1), layer_view(ctx, Resource::AoGeometry, 1));
        let (ao_left, geometry_left) = (layer_view(ctx, Resource::AoRaw, 0), layer_view(ctx, Resource::AoGeometry, 0));
        resources[5] = wgpu::BindingResource::TextureView(&ao_right);
        resources[6] = wgpu::BindingResource::TextureView(&geometry_right);
        resources[7] = wgpu::BindingResource::TextureView(&ao_left);
        resources[8] = wgpu::BindingResource::TextureView(&geometry_left);
        gtao.right_eye.dispatch(device, ctx.encoder, &resources, (width, height, 1));
    }
}
