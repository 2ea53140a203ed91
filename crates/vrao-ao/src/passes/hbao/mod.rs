//! HBAO (Belonogov 2018 §3.3): horizons found by marching depth along screen directions
//! (hbao.wgsl), on the shared occlusion layout.

use super::occlusion::TechniquePass;
use crate::gpu::kernel::wgsl;
use crate::gpu::Gpu;
use crate::settings::Technique;

/// The occlusion pass of HBAO.
pub(crate) fn pass(gpu: &Gpu) -> TechniquePass {
    TechniquePass::reusing(gpu, Technique::Hbao, wgsl!("src/passes/hbao/hbao.wgsl"))
}
