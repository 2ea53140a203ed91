//! The renderer's own passes, one folder each, written against the engine's plug
//! ([`vrao_ao::plug`]):
//! [`scene_passes`] run before the AO chain and [`output_passes`] after it. The
//! renderer's passes read its scene, uploaded scene and settings as the frame's
//! extensions ([`scene_of`], [`gpu_scene_of`], [`settings_of`]).

pub mod composite;
pub mod direct;
pub mod gbuffer;
pub mod peel;
pub mod rsm;
pub mod shadow;
pub mod ssdo;
pub mod tonemap;

use crate::gpu::scene::GpuScene;
use crate::scene::Scene;
use crate::settings::Settings;
use std::sync::Arc;
use vrao_ao::plug::{DeclareContext, FrameUniforms, Gpu, Pass};

/// The renderer's passes before the AO chain, in execution order: the G-buffer, the
/// directional lights' maps and direct light, their bounce, and the second depth layer
/// SSDO may read. A new pass is its own folder, its `pub mod` line above and one entry
/// here or in [`output_passes`].
pub fn scene_passes(gpu: &Gpu, scene: &Scene, gpu_scene: &GpuScene, frame: &FrameUniforms) -> Vec<Box<dyn Pass>> {
    // Directional lights' orthographic fits, shared by the shadow, direct and RSM passes.
    let light_space = Arc::new(shadow::LightSpace::new(gpu, scene, gpu_scene.anchor));
    vec![
        Box::new(gbuffer::GBufferPass::new(gpu, gpu_scene, frame)),
        Box::new(shadow::ShadowPass::new(gpu, gpu_scene, light_space.clone())),
        Box::new(direct::DirectLightPass::new(gpu, light_space.clone())),
        Box::new(rsm::RsmPass::new(gpu, light_space)),
        Box::new(peel::DepthPeelPass::new(gpu, gpu_scene, frame)),
    ]
}

/// The renderer's passes after the AO chain: the HDR composite and the tone mapping.
pub fn output_passes(gpu: &Gpu) -> Vec<Box<dyn Pass>> {
    vec![Box::new(composite::CompositePass::new(gpu)), Box::new(tonemap::TonemapPass::new(gpu))]
}

/// The scene being rendered, for the renderer's own passes.
pub fn scene_of<'a>(setup: &DeclareContext<'a>) -> &'a Scene {
    setup.extension::<Scene>().expect("the renderer's passes run in the renderer, which puts its scene in the frame")
}

/// The scene as uploaded to the GPU, for the renderer's raster passes.
pub fn gpu_scene_of<'a>(setup: &DeclareContext<'a>) -> &'a GpuScene {
    setup.extension::<GpuScene>().expect("the renderer puts its uploaded scene in the frame")
}

/// The renderer's settings (tone mapping, shadows, stereo path), for its own passes.
pub fn settings_of<'a>(setup: &DeclareContext<'a>) -> &'a Settings {
    setup.extension::<Settings>().expect("the renderer puts its settings in the frame")
}
