//! The caller's cancellation token cuts a renderer's build short (`Gpu::cancel_builds_on`):
//! a Ctrl-C during start-up need not wait for every pipeline to compile. A token is
//! attached to a GPU for good, so this test takes a GPU of its own, not the shared one.

use crate::common;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use vrao_ao::Error;
use vrao_render::{HeadsetProfile, Renderer, Scene, Settings};

#[test]
fn a_set_token_interrupts_the_renderer_build_and_a_clear_one_does_not() {
    let (gpu, _one_at_a_time) = common::own_gpu();
    let scene = Scene::load("builtin:grille").unwrap();
    let settings = Settings { profile: HeadsetProfile::with_size("test", 32, 32), ..Settings::default() };
    let interrupt = Arc::new(AtomicBool::new(false));
    gpu.cancel_builds_on(interrupt.clone());
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings).expect("a clear token builds as usual");
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    renderer.render_and_wait(&eyes.eyes, &[vrao_ao::plug::FINAL_AO]).unwrap();
    let ao = renderer.read_f32(vrao_ao::plug::FINAL_AO).unwrap();
    assert!(
        ao[0].chunks(4).any(|texel| texel[3] > 0.0 && texel[3] < 1.0),
        "the renderer built with a clear token draws AO"
    );
    interrupt.store(true, Ordering::Relaxed);
    assert!(gpu.builds_cancelled());
    match Renderer::new(gpu.clone(), &scene, &settings) {
        Err(Error::Interrupted) => {}
        Err(other) => panic!("expected Error::Interrupted, got {other}"),
        Ok(_) => panic!("a set token must interrupt the build"),
    }
    assert_eq!(vrao::Error::from(Error::Interrupted).exit_code(), 130);
}
