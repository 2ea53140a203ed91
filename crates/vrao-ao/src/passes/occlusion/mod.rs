//! What the screen-space occlusion techniques share: the textures they write
//! ([`AO_RAW`], [`AO_GEOMETRY`]), the binding layout of occlusion.wgsl, how a technique
//! declares itself, the right eye's reuse of the left eye (right_eye.wgsl), and
//! [`TechniquePass`], the pass of a technique that is one kernel of that layout (SSAO,
//! HBAO, the fetch-only baseline). GTAO and SSDO, which bind more, are passes of their
//! own in their folders.

use super::right_eye_list::RightEyeList;
use super::{DeclareContext, Pass, RecordContext, RightEyeTiles};
use crate::gpu::kernel::{wgsl, Bind, Kernel, Shader, Slot, COMMON, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, Size, OCCLUSION};
use crate::passes::inputs::{DEPTH, NORMALS};
use crate::resource::ChainLayout;
use crate::settings::{AoSettings, Technique};

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

/// right_eye.wgsl: the right eye's reuse of the left eye's raw occlusion, compiled after
/// occlusion.wgsl by every technique that reuses (its includer defines `reused_light`).
pub(crate) const RIGHT_EYE_WGSL: Shader = wgsl!("src/passes/occlusion/right_eye.wgsl");

/// `BINDINGS` and right_eye.wgsl's: at 7 and 8 the raw occlusion's and its geometry's
/// left-eye layers for the right eye's dispatches, at 9 its list of pixels to estimate,
/// at 10 the sampler its gathers of the left eye's values go through.
pub(crate) const REUSING_BINDINGS: [Bind; 11] = bindings_and([
    Bind::Own(Slot::Layers),
    Bind::Own(Slot::Layers),
    Bind::Own(Slot::ReadWriteBuffer),
    Bind::GatherSampler,
]);

/// `BINDINGS` followed by a technique's own bindings (from binding 7 on); `M` is the
/// total, checked when the constant is made.
pub const fn bindings_and<const N: usize, const M: usize>(own: [Bind; N]) -> [Bind; M] {
    joined(BINDINGS, own)
}

/// `first`'s bindings followed by `then`'s (a layout built on another); `K` is the
/// total, checked when the constant is made.
pub(crate) const fn joined<const N: usize, const M: usize, const K: usize>(
    first: [Bind; N],
    then: [Bind; M],
) -> [Bind; K] {
    assert!(K == N + M, "K must be N + M");
    let mut all = [Bind::Frame; K];
    let mut i = 0;
    while i < K {
        all[i] = if i < N { first[i] } else { then[i - N] };
        i += 1;
    }
    all
}

/// right_eye.wgsl's pipeline constants for the left eye's (or both eyes') dispatch
/// (false) or the right eye's two (true): its pixels listed, its outputs one layer.
pub(crate) fn right_eye_constants(right: bool) -> [(&'static str, f64); 3] {
    [("RIGHT_EYE", f64::from(right)), ("LISTED_PIXELS", f64::from(right)), ("SINGLE_LAYER_OUTPUT", f64::from(right))]
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
    let decl = PassDecl::new(name)
        .bindings(binds)
        .provide(OCCLUSION, AO_RAW)
        .occlusion_cost()
        .disabled_if(!runs_for.contains(&chosen), reason);
    match fold_right_eye_note(&setup.settings.ao, setup.views) {
        Some(note) if runs_for.contains(&chosen) => decl.note(note),
        _ => decl,
    }
}

/// What `--explain` says of `GtaoSettings::fold_right_eye` where it was asked for: folded,
/// or why it has no effect. It folds the stereo reuse's right eye into the march on GTAO's
/// bitmask (GTAO and SSDO: `Technique::reads_second_layer`'s set), so it needs both eyes,
/// the reuse and that march; said here, where every technique pass is declared, so no
/// technique drops it in silence.
fn fold_right_eye_note(ao: &AoSettings, views: u32) -> Option<&'static str> {
    if !ao.gtao.fold_right_eye {
        None
    } else if !ao.technique.reads_second_layer() {
        Some("fold-right-eye has no effect here: it folds GTAO's (and SSDO's) march alone")
    } else if views < 2 {
        Some("fold-right-eye has no effect: one view")
    } else if !ao.stereo_reuse {
        Some("fold-right-eye has no effect: the eyes are computed independently")
    } else {
        Some("the right eye's pixels the left eye cannot give march in the left eye's dispatch (fold-right-eye)")
    }
}

/// A technique that is one kernel of the shared layout: its WGSL defines the
/// occlusion of one pixel, occlusion.wgsl the rest. With two views and the stereo
/// reuse, the right eye copies what the left eye gives and estimates the rest by a list
/// (right_eye.wgsl), for the techniques made [`TechniquePass::reusing`].
pub(crate) struct TechniquePass {
    technique: Technique,
    /// Both eyes, or the left eye alone when the right eye reuses it.
    kernel: Kernel,
    /// The right eye's copy-and-list and listed dispatches.
    right_eye: Option<RightEyeKernels>,
}

/// A reusing technique's right-eye pipelines and its list.
struct RightEyeKernels {
    classify: Kernel,
    listed: Kernel,
    list: std::sync::Mutex<RightEyeList>,
}

impl TechniquePass {
    /// The pass of `technique`, whose WGSL is `shader`, both eyes estimated alike (the
    /// fetch-only baseline, whose cost stays that of two eyes).
    #[cfg(feature = "measurement")]
    pub(crate) fn new(gpu: &Gpu, technique: Technique, shader: Shader) -> Self {
        let files = [COMMON, VISIBILITY, OCCLUSION_WGSL, shader];
        let chain = ChainLayout::of(technique.carries_light(), gpu.caps.scalar_chain);
        let kernel = Kernel::in_chain(gpu, technique.name(), &files, "main", &BINDINGS, &[], chain);
        TechniquePass { technique, kernel, right_eye: None }
    }

    /// The pass of `technique`, whose WGSL (`shader`, compiled after right_eye.wgsl)
    /// takes its pixel from `estimated_pixel` and writes through `store_occlusion`: the
    /// right eye reuses the left eye.
    pub(crate) fn reusing(gpu: &Gpu, technique: Technique, shader: Shader) -> Self {
        let files = [COMMON, VISIBILITY, OCCLUSION_WGSL, RIGHT_EYE_WGSL, shader];
        // The technique decides the chain's layout (technique.carries_light()).
        let chain = ChainLayout::of(technique.carries_light(), gpu.caps.scalar_chain);
        let kernel = |entry: &str, right: bool| {
            let constants = right_eye_constants(right);
            Kernel::in_chain(gpu, technique.name(), &files, entry, &REUSING_BINDINGS, &constants, chain)
        };
        TechniquePass {
            technique,
            kernel: kernel("main", false),
            right_eye: Some(RightEyeKernels {
                classify: kernel("classify_right_eye", true),
                listed: kernel("main", true),
                list: std::sync::Mutex::new(RightEyeList::new(gpu, technique.name())),
            }),
        }
    }
}

impl Pass for TechniquePass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let binds: &[Bind] = if self.right_eye.is_some() { &REUSING_BINDINGS } else { &BINDINGS };
        technique_decl(self.technique.name(), binds, &[self.technique], setup)
    }

    fn record(&self, ctx: &mut RecordContext) {
        let (width, height, layers) = ctx.ao_extent();
        let device = &ctx.gpu.device;
        let Some(right_eye) = &self.right_eye else {
            let resources = ctx.bind(&BINDINGS, &[]);
            self.kernel.dispatch(device, ctx.encoder, ctx.visibility.bind_group(), &resources, (width, height, layers));
            return;
        };
        let mut list = right_eye.list.lock().unwrap_or_else(|p| p.into_inner());
        // Bindings 7 to 9 are unused before the right eye's dispatches: the normals and
        // the list's header stand in.
        let normals = ctx.view(NORMALS);
        let header = list.stand_in();
        let resources = ctx.bind(&REUSING_BINDINGS, &[normals.clone(), normals, header.as_entire_binding()]);
        let reuse = ctx.setup.settings.ao.stereo_reuse && layers == 2;
        let estimated_layers = if reuse { 1 } else { layers };
        self.kernel.dispatch(
            device,
            ctx.encoder,
            ctx.visibility.bind_group(),
            &resources,
            (width, height, estimated_layers),
        );
        if reuse {
            let kernels = [&right_eye.classify, &right_eye.listed];
            list.record_right_eye(ctx, &REUSING_BINDINGS, &[], kernels, None, (width, height));
        } else {
            list.skip();
        }
    }

    fn right_eye_tiles(&self, gpu: &Gpu) -> Option<RightEyeTiles> {
        let right_eye = self.right_eye.as_ref()?;
        let list = right_eye.list.lock().unwrap_or_else(|p| p.into_inner());
        list.read(gpu, self.technique.name())
    }

    fn right_eye_listed(&self, gpu: &Gpu) -> Option<(RightEyeTiles, Vec<[u32; 2]>)> {
        let right_eye = self.right_eye.as_ref()?;
        let list = right_eye.list.lock().unwrap_or_else(|p| p.into_inner());
        list.read_items(gpu, self.technique.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--explain` says whether the fold asked for happens, and why not where it cannot.
    #[test]
    fn the_plan_says_whether_the_right_eye_folds() {
        let mut ao = AoSettings::default();
        assert_eq!(fold_right_eye_note(&ao, 2), None, "not asked for: nothing said");
        ao.gtao.fold_right_eye = true;
        assert!(fold_right_eye_note(&ao, 2).unwrap().contains("left eye's dispatch"));
        assert!(fold_right_eye_note(&ao, 1).unwrap().contains("no effect: one view"));
        ao.technique = Technique::Hbao;
        assert!(fold_right_eye_note(&ao, 2).unwrap().contains("no effect here"));
        ao.technique = Technique::Gtao;
        ao.stereo_reuse = false;
        assert!(fold_right_eye_note(&ao, 2).unwrap().contains("no effect: the eyes are computed independently"));
    }
}
