//! GTAO with a visibility bitmask (gtao.wgsl) on the shared occlusion layout, in
//! pipelines of one shader: the rest of the image, the band along each eye's inner
//! border whose marches may look into the other eye (and, by an indirect dispatch, the
//! marches from the rest that would cross that border), and the right eye reusing the
//! left eye's values where it sees the same point. A scene with alpha-tested materials
//! gets the same taking samples on them as cards (gtao.wgsl `THIN_CARDS`).

use super::indirect_list::IndirectList;
use super::inputs::DEPTH_LAYER_2;
use super::occlusion::{self, technique_decl, OCCLUSION_WGSL, RIGHT_EYE_WGSL};
use super::right_eye_list::{RightEyeList, RightEyeViews};
use super::{DeclareContext, Pass, RecordContext, RightEyeTiles};
use crate::gpu::kernel::{wgsl, Bind, Kernel, Shader, Slot, COMMON, TILE, VISIBILITY};
use crate::gpu::Gpu;
use crate::graph::PassDecl;
use crate::resource::ChainLayout;
use crate::settings::Technique;
use bytemuck::{Pod, Zeroable};

/// The shared bindings with the right eye's at 7–10 (occlusion::REUSING_BINDINGS), at 11
/// GTAO's own parameters, at 12 the second depth layer (unbound with one layer) and at 13
/// the list of deferred marches (gtao.wgsl `deferred`). A march that gathers light (SSDO)
/// binds more after these ([`March::binds`]).
pub(crate) const BINDINGS: [Bind; 14] = occlusion::joined(
    occlusion::REUSING_BINDINGS,
    [Bind::Own(Slot::Uniform), Bind::Read(DEPTH_LAYER_2), Bind::Own(Slot::ReadWriteBuffer)],
);

/// Whether this frame's march reads the second depth layer: two asked for, a technique
/// that reads it, and one to be had (a renderer that peels it, a host that gave it).
pub(crate) fn reads_second_layer(setup: &DeclareContext) -> bool {
    let ao = &setup.settings.ao;
    ao.layers == 2 && ao.technique.reads_second_layer() && setup.second_layer
}

/// gtao.wgsl: the march over slices and sectors that GTAO and SSDO share.
pub(crate) const GTAO_WGSL: Shader = wgsl!("src/passes/gtao/gtao.wgsl");

/// GTAO's WGSL files, in order: gtao.wgsl's march and gtao_light.wgsl's light hooks.
const GTAO_FILES: [Shader; 6] =
    [COMMON, VISIBILITY, OCCLUSION_WGSL, RIGHT_EYE_WGSL, GTAO_WGSL, wgsl!("src/passes/gtao/gtao_light.wgsl")];

/// One technique built on gtao.wgsl's march: its name, its WGSL files (the march and,
/// after it, the file of its light hooks: gtao_light.wgsl for GTAO), its bindings
/// (`BINDINGS` and its own after them), its extra pipeline constants, and what it
/// adds to its declaration.
pub(crate) struct March {
    /// The technique (its pass runs when it is chosen).
    pub technique: Technique,
    /// The pipelines' label.
    pub label: &'static str,
    /// The WGSL files, in order.
    pub files: Vec<Shader>,
    /// The bindings: `BINDINGS` first.
    pub binds: &'static [Bind],
    /// Extra `override` values.
    pub constants: Vec<(&'static str, f64)>,
    /// Adjusts the pass's declaration (the resources it leaves unbound, notes).
    pub declare: fn(PassDecl, &DeclareContext) -> PassDecl,
    /// Whether the pipelines without cards compile when the pass is made (GTAO, the
    /// default) or at its first frame.
    pub eager: bool,
}

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
    footprint: f32,
    /// gtao.wgsl `right_eye_reuse`'s step: 0 lists, 1 copies.
    right_eye_step: u32,
}

/// GTAO's slices and steps per half-slice for a budget of `samples` depth taps
/// (slices × 2 × steps ≈ samples): 12 → 2×3, 24 → 2×6, 36 → 2×9, 64 → 2×16. Steps before
/// slices: the 4×4 noise tile turns each pixel's slices, so the denoise averages 16 × 2
/// directions anyway, while the occluders a sparse march steps over stay missed (a
/// bias, not noise): at N = 24, 2×6 gave less error and bias than 3×4
/// (docs/records/2026-11-29/measurements-in-code.md, gtao-slices-steps).
/// Reading a second layer (`two_layers`), under 32 taps take one slice: the layer's spans
/// are objects' own depths, thinner than the slab, and twice the steps miss fewer of
/// them (1×12 against 2×6: less error and dark bias on all three public scenes, more
/// halos and stereo disagreement; one layer keeps two slices for those:
/// docs/records/2026-11-29/two-layers.md, one slice).
pub(crate) fn gtao_slices_steps(samples: u32, two_layers: bool) -> (u32, u32) {
    let slices = match samples {
        0..32 if two_layers => 1,
        0..128 => 2,
        _ => 4,
    };
    (slices, (samples / (2 * slices)).max(1))
}

/// GTAO's inner-border band for occlusion targets `width` pixels wide: a quarter of the
/// width (whole 8-pixel workgroups). Only marches from this band look past the inner
/// border into the other eye; one from further in that would cross it (its radius spans
/// more than a quarter of the image: a surface near the eye) is deferred to the band's
/// pipeline by an indirect dispatch.
pub(crate) fn gtao_inner_band(width: u32) -> u32 {
    (width / 4).next_multiple_of(8).min(width)
}

/// GTAO's pipelines (module docs) of one variant: solid occluders only, or with
/// alpha-tested surfaces taken as thin cards (gtao.wgsl `THIN_CARDS`); one depth layer,
/// or two (gtao.wgsl `SECOND_LAYER`).
struct Kernels {
    interior: Kernel,
    inner_band: Kernel,
    /// The band's march over the marches the rest deferred (an indirect dispatch), of
    /// either eye.
    crossing: Kernel,
    /// The right eye's copy of what the left eye gives, listing the pixels left to march.
    right_classify: Kernel,
    /// The right eye's march over the listed pixels (an indirect dispatch).
    right_listed: Kernel,
    /// The band's march over the right eye's listed marches that it deferred.
    right_crossing: Kernel,
    /// With `GtaoSettings::fold_right_eye`: built on its first frame.
    fold: std::sync::OnceLock<FoldKernels>,
}

/// The right eye folded into the left eye's dispatch (`GtaoSettings::fold_right_eye`).
struct FoldKernels {
    /// Before the march, the right eye's pixels the left eye cannot give, listed from
    /// the depth; after it, the copies of the rest (one pipeline for both, gtao.wgsl
    /// `right_eye_reuse`).
    right_reuse: Kernel,
    /// The left eye's interior and then the right eye's listed pixels, in one indirect
    /// dispatch.
    folded: Kernel,
}

impl Kernels {
    fn new(gpu: &Gpu, march: &March, variant: Variant) -> Self {
        let kernel = |entry: &str, band: bool, right: bool, crossing: bool| {
            Self::kernel(gpu, march, variant, entry, [band, right, crossing, false])
        };
        Kernels {
            interior: kernel("main", false, false, false),
            inner_band: kernel("main", true, false, false),
            crossing: kernel("main", true, false, true),
            right_classify: kernel("classify_right_eye", false, true, false),
            right_listed: kernel("main", false, true, false),
            right_crossing: kernel("main", true, true, true),
            fold: std::sync::OnceLock::new(),
        }
    }

    /// The fold's kernels, built on first use.
    fn fold(&self, gpu: &Gpu, march: &March, variant: Variant) -> &FoldKernels {
        self.fold.get_or_init(|| FoldKernels {
            right_reuse: Self::kernel(gpu, march, variant, "right_eye_reuse", [false, true, false, false]),
            folded: Self::kernel(gpu, march, variant, "main", [false, false, false, true]),
        })
    }

    /// One pipeline of `entry`: a deferred march runs the band's code (`band`) over the
    /// list (`crossing`); `right`: a right-eye dispatch; `folded`: gtao.wgsl `FOLDED`.
    fn kernel(
        gpu: &Gpu,
        march: &March,
        variant: Variant,
        entry: &str,
        [band, right, crossing, folded]: [bool; 4],
    ) -> Kernel {
        let Variant { thin_cards, second_layer, footprint } = variant;
        {
            let mut constants = vec![
                ("INNER_BAND", f64::from(band)),
                ("CROSSING", f64::from(crossing)),
                ("FOLDED", f64::from(folded)),
                ("THIN_CARDS", f64::from(thin_cards)),
                ("SECOND_LAYER", f64::from(second_layer)),
                ("FOOTPRINT", f64::from(footprint)),
            ];
            constants.extend_from_slice(&occlusion::right_eye_constants(right));
            constants.extend_from_slice(&march.constants);
            let chain = ChainLayout::of(march.technique.carries_light(), gpu.caps.scalar_chain);
            Kernel::in_chain(gpu, march.label, &march.files, entry, march.binds, &constants, chain)
        }
    }
}

/// Which of the march's pipelines: its compile-time switches.
#[derive(Clone, Copy)]
struct Variant {
    /// Alpha-tested samples are cards (gtao.wgsl `THIN_CARDS`).
    thin_cards: bool,
    /// The march reads a second depth layer (`SECOND_LAYER`).
    second_layer: bool,
    /// Solid samples block their footprint (`FOOTPRINT`, `GtaoSettings::footprint` > 0).
    footprint: bool,
}

impl Variant {
    /// The index of the solid or card kernels of this variant.
    fn slot(self) -> usize {
        usize::from(self.second_layer) + 2 * usize::from(self.footprint)
    }
}

/// GTAO's pipelines and its parameters; with another [`March`], a technique that
/// marches the same slices (SSDO).
pub(crate) struct GtaoPass {
    march: March,
    /// By [`Variant::slot`] (one layer or two, with or without the footprint): the
    /// defaults' built when the pass is made for an eager [`March`], the others on the
    /// first frame that runs them.
    solid: [std::sync::OnceLock<Kernels>; 4],
    /// By [`Variant::slot`]: built on the first frame of a scene with alpha-tested
    /// materials.
    thin_cards: [std::sync::OnceLock<Kernels>; 4],
    params: wgpu::Buffer,
    /// `params` with the right eye's copying step (gtao.wgsl `right_eye_reuse`).
    copy_params: wgpu::Buffer,
    right_eye: std::sync::Mutex<RightEyeList>,
    /// The marches deferred to the band's pipeline (gtao.wgsl `deferred`), the left eye's
    /// (or both eyes' without the reuse) and then the right eye's.
    deferred: std::sync::Mutex<IndirectList>,
}

impl GtaoPass {
    /// Builds the pass's pipelines.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        Self::with_march(
            gpu,
            March {
                technique: Technique::Gtao,
                label: Technique::Gtao.name(),
                files: GTAO_FILES.to_vec(),
                binds: &BINDINGS,
                constants: Vec::new(),
                declare: |decl, _| decl,
                eager: true,
            },
        )
    }

    /// The pass of another technique on GTAO's march.
    pub(crate) fn with_march(gpu: &Gpu, march: March) -> Self {
        let uniform = |label| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<GtaoUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (params, copy_params) = (uniform("gtao params"), uniform("gtao right-eye copy params"));
        let solid: [std::sync::OnceLock<Kernels>; 4] = Default::default();
        if march.eager {
            let footprint = crate::GtaoSettings::default().footprint > 0.0;
            let variant = Variant { thin_cards: false, second_layer: false, footprint };
            let _ = solid[variant.slot()].set(Kernels::new(gpu, &march, variant));
        }
        let right_eye = std::sync::Mutex::new(RightEyeList::new(gpu, "gtao right-eye pixels"));
        let thin_cards = Default::default();
        let deferred = std::sync::Mutex::new(IndirectList::new(gpu, "gtao deferred marches"));
        GtaoPass { march, solid, thin_cards, params, copy_params, right_eye, deferred }
    }

    /// The kernels of `variant` for this frame, built on first use, and the variant they
    /// are: with cards where the scene has alpha-tested materials. The AO engine has no
    /// scene, and a host's normals mark no cards. Once the caller's interrupt cuts builds
    /// short, kernels built now would be stand-ins for good: the last frames of an ending
    /// session take samples as solid instead.
    fn kernels(&self, ctx: &RecordContext, variant: Variant) -> (&Kernels, Variant) {
        let slot = variant.slot();
        let cards = Variant { thin_cards: true, ..variant };
        match self.thin_cards[slot].get() {
            Some(kernels) if ctx.setup.alpha_cards => (kernels, cards),
            None if ctx.setup.alpha_cards && !ctx.gpu.builds_cancelled() => {
                (self.thin_cards[slot].get_or_init(|| Kernels::new(ctx.gpu, &self.march, cards)), cards)
            }
            _ => (self.solid[slot].get_or_init(|| Kernels::new(ctx.gpu, &self.march, variant)), variant),
        }
    }
}

impl Pass for GtaoPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let technique = self.march.technique;
        let decl = technique_decl(self.march.label, self.march.binds, &[technique], setup);
        let decl = (self.march.declare)(decl, setup);
        let ao = &setup.settings.ao;
        let decl = if reads_second_layer(setup) {
            decl.note(
                "two depth layers: a sample blocks the span to the second layer (the thickness where it has none)",
            )
        } else if ao.layers == 2 && ao.technique.reads_second_layer() {
            decl.unbind(DEPTH_LAYER_2)
                .note("one depth layer: no second layer this frame (depth-peel or ao-import says why)")
        } else {
            decl.unbind(DEPTH_LAYER_2)
        };
        if setup.alpha_cards {
            decl.note("alpha-tested samples are cards: each blocks its footprint on the card, not a slab")
        } else {
            decl
        }
    }

    fn record(&self, ctx: &mut RecordContext) {
        let (width, height, layers) = ctx.ao_extent();
        let device = &ctx.gpu.device;
        let ao = &ctx.setup.settings.ao;
        let second = reads_second_layer(ctx.setup);
        let (slices, steps) = gtao_slices_steps(ao.samples, second);
        let own = &ao.gtao;
        let band = gtao_inner_band(width);
        let params = GtaoUniform {
            slices,
            steps,
            thickness: own.thickness,
            step_power: own.step_power,
            connect: if second { own.connect_two_layers } else { own.connect },
            inner_band: band,
            footprint: own.footprint,
            right_eye_step: 0,
        };
        let variant = Variant { thin_cards: false, second_layer: second, footprint: own.footprint > 0.0 };
        let (kernels, variant) = self.kernels(ctx, variant);
        ctx.gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        // The left eye (or the only view) marches every pixel, in two parts and the marches
        // the first part deferred. With two views and `stereo_reuse` the right eye then
        // copies what the left eye gives and marches the rest in a dispatch of its own;
        // or, folded (`GtaoSettings::fold_right_eye`), its pixels the left eye cannot give
        // are listed first, marched in the left eye's interior dispatch (gtao.wgsl
        // `FOLDED`), and the rest copied last. Without the reuse both eyes march alike.
        // Bindings 7 to 9 are unused outside the right eye's dispatches: the normals and
        // the list's header stand in.
        let normals = ctx.view(super::inputs::NORMALS);
        let mut right_eye = self.right_eye.lock().unwrap_or_else(|p| p.into_inner());
        let header = right_eye.stand_in();
        let mut deferred = self.deferred.lock().unwrap_or_else(|p| p.into_inner());
        let reuse = ao.stereo_reuse && layers == 2;
        let marched_layers = if reuse { 1 } else { layers };
        // Room for every pixel of both eyes: the deferred marches of either.
        let deferred_list = deferred.start(ctx, width * height * layers);
        let after_list = [self.params.as_entire_binding(), deferred_list.as_entire_binding()];
        let resources = ctx.bind(self.march.binds, &own_bindings(&normals, &header, &after_list));
        let visibility = ctx.visibility.bind_group();
        let band_pass = |ctx: &mut RecordContext, deferred: &IndirectList| {
            kernels.inner_band.dispatch(device, ctx.encoder, visibility, &resources, (band, height, marched_layers));
            deferred.take_arguments(ctx.encoder);
            kernels.crossing.dispatch_indirect(device, ctx.encoder, visibility, &resources, deferred.arguments(), 0);
        };
        if !reuse {
            right_eye.skip();
            kernels.interior.dispatch(device, ctx.encoder, visibility, &resources, (width - band, height, layers));
            band_pass(ctx, &deferred);
            return;
        }
        if !own.fold_right_eye {
            // Copied first, the rest marched in a dispatch of its own, which defers its
            // crossing marches to a list of their own.
            kernels.interior.dispatch(device, ctx.encoder, visibility, &resources, (width - band, height, 1));
            band_pass(ctx, &deferred);
            let right_deferred = deferred.start(ctx, width * height);
            let after_list = [self.params.as_entire_binding(), right_deferred.as_entire_binding()];
            let right_kernels = [&kernels.right_classify, &kernels.right_listed];
            let then = Some((&kernels.right_crossing, &*deferred));
            right_eye.record_right_eye(ctx, self.march.binds, &after_list, right_kernels, then, (width, height));
            return;
        }
        let fold = kernels.fold(ctx.gpu, &self.march, variant);
        let copy_params = GtaoUniform { right_eye_step: 1, ..params };
        ctx.gpu.queue.write_buffer(&self.copy_params, 0, bytemuck::bytes_of(&copy_params));
        let interior_tiles = (width - band).div_ceil(TILE) * height.div_ceil(TILE);
        let list = right_eye.start_folded(ctx, (width, height), interior_tiles);
        let views = RightEyeViews::new(ctx);
        let listing = views.bind(ctx, self.march.binds, &list, &after_list);
        fold.right_reuse.dispatch(device, ctx.encoder, visibility, &listing, (width, height, 1));
        right_eye.take_arguments(ctx.encoder);
        let folded = ctx.bind(self.march.binds, &own_bindings(&normals, &list, &after_list));
        fold.folded.dispatch_indirect(device, ctx.encoder, visibility, &folded, right_eye.arguments(), 0);
        band_pass(ctx, &deferred);
        let copy_after = [self.copy_params.as_entire_binding(), deferred_list.as_entire_binding()];
        let copying = views.bind(ctx, self.march.binds, &list, &copy_after);
        fold.right_reuse.dispatch(device, ctx.encoder, visibility, &copying, (width, height, 1));
    }

    fn right_eye_tiles(&self, gpu: &Gpu) -> Option<RightEyeTiles> {
        let right_eye = self.right_eye.lock().unwrap_or_else(|p| p.into_inner());
        right_eye.read(gpu, self.march.label)
    }

    fn right_eye_listed(&self, gpu: &Gpu) -> Option<(RightEyeTiles, Vec<[u32; 2]>)> {
        let right_eye = self.right_eye.lock().unwrap_or_else(|p| p.into_inner());
        right_eye.read_items(gpu, self.march.label)
    }
}

/// GTAO's own bindings (from 7 on) outside the right eye's dispatches: the normals stand
/// in for the left eye's targets at 7 and 8, `list` at 9, then `after_list`.
fn own_bindings<'b>(
    normals: &wgpu::BindingResource<'b>,
    list: &'b wgpu::Buffer,
    after_list: &[wgpu::BindingResource<'b>],
) -> Vec<wgpu::BindingResource<'b>> {
    let mut own = vec![normals.clone(), normals.clone(), list.as_entire_binding()];
    own.extend_from_slice(after_list);
    own
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::{self, mirror};

    #[test]
    fn the_gtao_uniform_matches_gtao_wgsl() {
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(GtaoUniform, GTAO_FILES, "GtaoParams", [slices, steps, thickness, step_power, connect, inner_band, footprint, right_eye_step]),
        ]);
    }

    #[test]
    fn gtao_presets_spend_ssao_tap_counts() {
        for (samples, split) in [(12, (2, 3)), (24, (2, 6)), (36, (2, 9)), (64, (2, 16)), (1, (2, 1)), (256, (4, 32))] {
            assert_eq!(gtao_slices_steps(samples, false), split);
        }
        for (samples, split) in [(12, (1, 6)), (24, (1, 12)), (31, (1, 15)), (36, (2, 9)), (64, (2, 16)), (1, (1, 1))] {
            assert_eq!(gtao_slices_steps(samples, true), split, "{samples} taps reading two layers");
        }
    }
}
