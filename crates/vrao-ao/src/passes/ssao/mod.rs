//! SSAO (Belonogov 2018 §3.2, the Czech SSDO thesis ch. 3): the hemisphere kernel's
//! samples tested against the depth buffer (ssao.wgsl), on the shared occlusion layout.

use super::occlusion::TechniquePass;
use crate::gpu::kernel::wgsl;
use crate::gpu::Gpu;
use crate::settings::Technique;

/// The occlusion pass of SSAO.
pub(crate) fn pass(gpu: &Gpu) -> TechniquePass {
    TechniquePass::reusing(gpu, Technique::Ssao, wgsl!("src/passes/ssao/ssao.wgsl"))
}
