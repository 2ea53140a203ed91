//! Every quality preset of GTAO, and every other technique at the default preset, on the
//! built-in scenes AO finds hard and on the public scenes: no final AO is exactly 0, and
//! AO turns no pixel black. A seen point always has the direction to the eye open, so
//! "fully occluded" is never the right answer, and 0 tone-maps to pure black wherever
//! no direct light falls. GTAO at ultra on a window seen through the furnished room's
//! slatted blind read 0 before the gap around the view direction was counted at its
//! width (gtao.wgsl `visible_sectors`); every AO now also keeps a floor of 1/256
//! (common.wgsl `AO_FLOOR`).
//!
//! `cargo test --release --test presets -- --nocapture` prints each case's least AO.

use crate::common;

use glam::DVec3;
use std::sync::Arc;
use vrao_ao::plug::{Gpu, DEPTH, FINAL_AO};
use vrao_ao::{AoSettings, HeadPose, Quality, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::Scene;
use vrao_render::{HeadsetProfile, Renderer, Settings};

/// Per-eye size of the scenes' own views.
const SIZE: (u32, u32) = (120, 135);

/// A scene, the head it is seen from and the per-eye size.
struct View {
    name: String,
    scene: Scene,
    head: HeadPose,
    size: (u32, u32),
}

impl View {
    fn own(name: &str, scene: Scene) -> View {
        let head = scene.head.pose_at(0.0);
        View { name: name.into(), scene, head, size: SIZE }
    }
}

/// The built-in scenes, and the public ones when they are there (skipped with a message
/// outside CI when not). The furnished room is also seen close up through its blind,
/// where GTAO's ultra preset found pixels fully occluded.
fn views() -> Vec<View> {
    let furnished = Scene::load("builtin:furnished").unwrap();
    // Close to the blind, the window behind its slats is seen through gaps a pixel or
    // two high: before the fix GTAO at ultra read AO exactly 0 on two of those pixels.
    let blind = HeadPose::look_at(DVec3::new(-0.9, 1.5, -5.5), DVec3::new(-0.9, 1.4, -6.2)).unwrap();
    let mut views = vec![
        View { name: "furnished, the blind".into(), scene: furnished.clone(), head: blind, size: (160, 180) },
        View::own("furnished", furnished),
        View::own("flipped-normals", Scene::load("builtin:flipped-normals").unwrap()),
    ];
    // Scene files name the public scenes through $VRAO_SCENES (cargo test sets it).
    let public = [
        ("cornell", "cornell_box/CornellBox-Original.obj", Some("assets/scenes/cornell.toml")),
        ("bunny", "bunny/bunny.obj", None),
        ("sibenik", "sibenik/sibenik.obj", Some("assets/scenes/sibenik.toml")),
    ];
    for (name, file, scene_file) in public {
        let Some(path) = common::public_scene(file) else { continue };
        if scene_file.is_some() && std::env::var_os("VRAO_SCENES").is_none() {
            std::env::set_var("VRAO_SCENES", common::public_scenes().unwrap());
        }
        let spec = scene_file
            .map(|f| format!("{}/{f}", env!("CARGO_MANIFEST_DIR")))
            .unwrap_or_else(|| path.display().to_string());
        views.push(View::own(name, Scene::load(&spec).unwrap_or_else(|e| panic!("{name}: {e}"))));
    }
    views
}

/// The cases of one view: GTAO at every preset (and its most occluding one at half
/// resolution, through the upsampling), every other technique at the default preset.
fn cases() -> Vec<AoSettings> {
    let defaults = AoSettings::default();
    let mut cases: Vec<AoSettings> = Quality::ALL
        .iter()
        .map(|&q| {
            let mut ao = AoSettings { technique: Technique::Gtao, ..defaults.clone() };
            q.apply(&mut ao);
            ao
        })
        .collect();
    let mut ultra_half =
        AoSettings { technique: Technique::Gtao, resolution: vrao_ao::Resolution::Half, ..defaults.clone() };
    Quality::Ultra.apply(&mut ultra_half);
    cases.push(ultra_half);
    for technique in Technique::estimators() {
        if technique != Technique::Gtao {
            cases.push(AoSettings { technique, ..defaults.clone() });
        }
    }
    cases
}

/// One frame's colour (RGBA8 per layer), final AO (RGBA per layer) and which pixels
/// see a surface.
struct Frame {
    color: Vec<Vec<u8>>,
    ao: Vec<Vec<f32>>,
    surface: Vec<Vec<bool>>,
}

fn render(renderer: &mut Renderer, view: &View, settings: &Settings) -> Frame {
    renderer.set_settings(settings).unwrap();
    let eyes = settings.profile.eyes(&view.head, settings.near);
    let mut outputs = vec![COLOR, DEPTH];
    if settings.ao.technique != Technique::None {
        outputs.push(FINAL_AO);
    }
    renderer.render_and_wait(&eyes.eyes, &outputs).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    Frame {
        color: renderer.read_bytes(COLOR).unwrap(),
        ao: if settings.ao.technique == Technique::None { Vec::new() } else { renderer.read_f32(FINAL_AO).unwrap() },
        surface: depth.iter().map(|layer| layer.iter().map(|&d| d > 0.0).collect()).collect(),
    }
}

/// Pixels (layer, index) that see a surface and are pure black.
fn black_surface_pixels(frame: &Frame) -> Vec<(usize, usize)> {
    let mut black = Vec::new();
    for (layer, (color, surface)) in frame.color.iter().zip(&frame.surface).enumerate() {
        for (i, rgba) in color.chunks_exact(4).enumerate() {
            if surface[i] && rgba[..3] == [0, 0, 0] {
                black.push((layer, i));
            }
        }
    }
    black
}

fn check_view(gpu: &Arc<Gpu>, view: &View) -> Vec<String> {
    let base = Settings {
        profile: HeadsetProfile::with_size("test", view.size.0, view.size.1),
        ao: vrao_render::settings::ao_fitted_to(&view.scene),
        ..Settings::default()
    };
    let none = Settings { ao: AoSettings { technique: Technique::None, ..base.ao.clone() }, ..base.clone() };
    let mut renderer = Renderer::new(gpu.clone(), &view.scene, &none).unwrap();
    // Unoccluded, a pixel is black only where neither direct nor ambient light reaches it
    // (the Cornell box has no environment: faces turned from its lamp are black). AO
    // must not add any.
    let unoccluded = render(&mut renderer, view, &none);
    let black_anyway = black_surface_pixels(&unoccluded);
    assert!(
        view.scene.environment.is_none() || black_anyway.is_empty(),
        "{}: {} pixels are black with no occlusion at all under an environment",
        view.name,
        black_anyway.len()
    );
    let mut failures = Vec::new();
    for ao in cases() {
        let settings = Settings { ao, ..base.clone() };
        let frame = render(&mut renderer, view, &settings);
        let case = format!(
            "{}: {} N={}{}",
            view.name,
            settings.ao.technique.name(),
            settings.ao.samples,
            if settings.ao.resolution.is_half() { " half" } else { "" }
        );
        let values = frame.ao.iter().flat_map(|layer| layer.iter().skip(3).step_by(4));
        let (zeros, least) = values.fold((0, f32::INFINITY), |(n, m), &a| (n + (a == 0.0) as usize, m.min(a)));
        let black: Vec<_> = black_surface_pixels(&frame).into_iter().filter(|p| !black_anyway.contains(p)).collect();
        println!("{case}: least AO {least:.5}, {zeros} exactly 0, {} black by AO", black.len());
        if zeros > 0 || !black.is_empty() {
            failures.push(format!("{case}: {zeros} AO values exactly 0, {} pixels black only with AO", black.len()));
        }
    }
    failures
}

#[test]
fn no_preset_of_any_technique_reads_ao_0_or_turns_a_pixel_black() {
    let (gpu, _lock) = common::gpu();
    let mut failures = Vec::new();
    for view in views() {
        failures.extend(check_view(&gpu, &view));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
