//! SSAO (Belonogov 2018 §3.2, the Czech SSDO thesis ch. 3): the hemisphere kernel's
//! samples tested against the depth buffer (ssao.wgsl), on the shared occlusion layout.

use super::occlusion::TechniquePass;
use crate::render::gpu::kernel::wgsl;
use crate::render::gpu::Gpu;
use crate::render::settings::Technique;

/// The occlusion pass of SSAO.
pub fn pass(gpu: &Gpu) -> TechniquePass {
    TechniquePass::new(gpu, Technique::Ssao, wgsl!("src/render/passes/ssao/ssao.wgsl"))
}
