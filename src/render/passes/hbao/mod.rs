//! HBAO (Belonogov 2018 §3.3): horizons found by marching depth along screen directions
//! (hbao.wgsl), on the shared occlusion layout.

use super::occlusion::TechniquePass;
use crate::render::gpu::kernel::wgsl;
use crate::render::gpu::Gpu;
use crate::render::settings::Technique;

/// The occlusion pass of HBAO.
pub fn pass(gpu: &Gpu) -> TechniquePass {
    TechniquePass::new(gpu, Technique::Hbao, wgsl!("src/render/passes/hbao/hbao.wgsl"))
}
