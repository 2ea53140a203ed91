//! The library without the CLI: load a scene, render both eyes headless and read the
//! ambient occlusion back.
//!
//! ```text
//! cargo run --release --example headless [SCENE]
//! ```
//!
//! SCENE is `builtin:NAME`, a `.toml` scene file or an `.obj` (default `builtin:room`).
//! It prints each eye's mean AO (the fraction of ambient light that reaches a pixel: 1 is
//! open, 0 fully occluded) and exits non-zero if any value is outside [0, 1] or not a
//! number. Small eyes (160×144) keep it to seconds on a CPU adapter (lavapipe).

use std::sync::Arc;

use vrao_ao::plug::FINAL_AO;
use vrao_ao::{AoSettings, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::{BackendChoice, HeadsetProfile, Renderer, Scene, Settings};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    // Mesa's Vulkan drivers probe for a Wayland display and print "error: XDG_RUNTIME_DIR
    // is invalid" on headless machines although nothing is wrong; give the probe a
    // directory to look in (the vrao binary does the same).
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let spec = std::env::args().nth(1).unwrap_or_else(|| "builtin:room".into());
    let scene = Scene::load(&spec)?;

    // A Vive-class frustum at a small per-eye size; GTAO with the radius the scene suggests.
    let settings = Settings {
        profile: HeadsetProfile::with_size("vive", 160, 144),
        ao: AoSettings { technique: Technique::Gtao, radius: scene.suggested_ao_radius(), ..AoSettings::default() },
        ..Settings::default()
    };
    settings.validate()?;

    let gpu = Arc::new(vrao_render::open(BackendChoice::Auto)?);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings)?;

    // Both eyes from the scene's head pose at t = 0.
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    // The final AO: denoised and, at half resolution, upsampled to full resolution.
    let ao = FINAL_AO;
    renderer.render_and_wait(&eyes.eyes, &[COLOR, ao])?;

    println!(
        "'{}' ({} triangles) on {}, {}x{} per eye, {}:",
        scene.name,
        scene.triangle_count(),
        gpu.info.name,
        settings.profile.width,
        settings.profile.height,
        settings.ao.technique.name(),
    );
    // One Vec per eye (layer), rgba interleaved; the AO is the alpha channel.
    for (name, layer) in ["left", "right"].iter().zip(renderer.read_f32(ao)?) {
        let values: Vec<f32> = layer.chunks_exact(4).map(|p| p[3]).collect();
        let bad = values.iter().filter(|v| !(0.0..=1.0).contains(*v)).count();
        assert!(bad == 0, "{name} eye: {bad} AO values outside [0, 1] or NaN");
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64;
        let min = values.iter().copied().fold(f32::INFINITY, f32::min);
        println!("  {name:>5} eye: mean AO {mean:.3}, darkest {min:.3} over {} pixels", values.len());
    }
    Ok(())
}
