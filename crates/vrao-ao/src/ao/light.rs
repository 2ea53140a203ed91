//! A host's light for SSDO ([`HostLight`]): its direct light, packed with the depth into
//! [`DIRECT_LIGHT`] by [`LightImportPass`] (light.wgsl) as vrao's renderer writes it, and
//! its environment as nine SH coefficients, turned into each view's quadratics
//! ([`crate::sh::view_quadratics`]).

use crate::gpu::kernel::{wgsl, Bind, Kernel, COMMON};
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource};
use crate::passes::inputs::{DEPTH, DIRECT_LIGHT};
use crate::passes::ssdo::LightInputs;
use crate::passes::{DeclareContext, Pass, RecordContext};

/// The pass's name, as `--explain` and the timings show it.
pub(crate) const NAME: &str = "ao-light-import";

/// The host's direct light (any float-sampled format).
pub(crate) const HOST_DIRECT: Resource = Resource::imported("host-direct", wgpu::TextureFormat::Rgba16Float);

/// What a host gives SSDO (`Technique::Ssdo`, `Technique::SsdoBounce`) besides depth.
/// Without it SSDO returns GTAO's AO and no light; other techniques ignore it.
#[derive(Clone, Copy, Debug)]
pub struct HostLight<'a> {
    /// The direct light leaving each pixel's surface towards the eye: outgoing radiance
    /// in linear RGB (albedo applied, emission included; what a diffuse surface sends
    /// every way), a float-sampled texture of the engine's size with one layer per view.
    /// `ssdo-bounce` sends it from the occluding surfaces; `None`: no bounce.
    pub direct: Option<&'a wgpu::Texture>,
    /// The environment's irradiance as nine SH coefficients (linear RGB) over directions
    /// in the host's world space (the frame's view matrices' world), in the basis order
    /// 1, y, z, x, xy, yz, 3z² − 1, xz, x² − y² with the usual normalisation (Ramamoorthi
    /// and Hanrahan 2001): E(n) = Σ c_k Y_k(n). `None`: no environment light.
    pub environment_sh: Option<[[f32; 3]; 9]>,
}

/// Packs the host's direct light with the view distance into [`DIRECT_LIGHT`].
pub(crate) struct LightImportPass {
    kernel: Kernel,
}

const BINDINGS: [Bind; 4] = [Bind::Frame, Bind::Read(DEPTH), Bind::Read(HOST_DIRECT), Bind::Write(DIRECT_LIGHT)];

impl LightImportPass {
    /// Builds the pass's pipeline.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        let files = [COMMON, wgsl!("src/ao/light.wgsl")];
        LightImportPass { kernel: Kernel::new(gpu, NAME, &files, "main", &BINDINGS) }
    }
}

impl Pass for LightImportPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let direct = setup.extension::<LightInputs>().is_some_and(|l| l.direct);
        PassDecl::new(NAME).bindings(&BINDINGS).disabled_if(!direct, "the host gave no direct light")
    }

    fn record(&self, ctx: &mut RecordContext) {
        let resources = ctx.bind(&BINDINGS, &[]);
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, ctx.visibility.bind_group(), &resources, ctx.extent());
    }
}
