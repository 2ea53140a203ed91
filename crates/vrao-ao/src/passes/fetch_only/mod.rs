//! The benchmark baseline: SSAO's depth taps without the occlusion arithmetic
//! (fetch_only.wgsl), on the shared occlusion layout, so the bench can tell memory from
//! arithmetic.

use super::occlusion::TechniquePass;
use crate::gpu::kernel::wgsl;
use crate::gpu::Gpu;
use crate::settings::Technique;

/// The fetch-only pass.
pub(crate) fn pass(gpu: &Gpu) -> TechniquePass {
    TechniquePass::new(gpu, Technique::FetchOnly, wgsl!("src/passes/fetch_only/fetch_only.wgsl"))
}
