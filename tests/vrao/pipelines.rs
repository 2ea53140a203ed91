//! The device keeps the compute pipelines it compiled: a renderer made again with settings
//! seen before (the governor returning to a level) compiles none and draws the same AO.

use crate::common;

use vrao_ao::plug::FINAL_AO;
use vrao_render::{HeadsetProfile, Renderer, Scene, Settings};

#[test]
fn a_renderer_made_again_with_the_same_settings_compiles_no_compute_pipeline() {
    let (gpu, _one_at_a_time) = common::own_gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let settings = Settings { profile: HeadsetProfile::with_size("test", 48, 40), ..Settings::default() };
    let ao_of = |settings: &Settings| {
        let mut renderer = Renderer::new(gpu.clone(), &scene, settings).unwrap();
        let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
        renderer.render_and_wait(&eyes.eyes, &[FINAL_AO]).unwrap();
        renderer.read_f32(FINAL_AO).unwrap()
    };
    let first = ao_of(&settings);
    let compiled = gpu.pipelines_built();
    assert!(compiled > 0, "the first renderer compiles its kernels");
    let again = ao_of(&settings);
    assert_eq!(gpu.pipelines_built(), compiled, "the same settings again compile nothing");
    assert_eq!(first, again, "the kept pipelines draw the same AO");
    assert!(first[0].chunks(4).any(|texel| texel[3] < 0.9), "the room is occluded somewhere");
    gpu.take_error().unwrap();
}
