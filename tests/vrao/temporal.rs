//! Temporal accumulation: the noise falls as frames accumulate with a static head, a
//! jump to a new view discards the history instead of smearing it, a turning head
//! shortens the window, a history holding NaN is discarded, and the graph leaves the
//! pass out when it is off.

use crate::common;

use glam::{DQuat, DVec3};
use vrao_ao::plug::{Resource, AO_ACCUMULATED, AO_GEOMETRY, AO_RAW, HISTORY_POSITION, HISTORY_VALUE};
use vrao_ao::{AoSettings, HeadPose, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::{HeadsetProfile, Renderer, Scene, Settings};

const SIZE: (u32, u32) = (96, 80);

fn settings(temporal: bool, samples: u32) -> Settings {
    let mut ao = AoSettings { technique: Technique::Ssao, samples, blur_radius: 0, ..AoSettings::default() };
    ao.temporal.enabled = temporal;
    Settings { profile: HeadsetProfile::with_size("test", SIZE.0, SIZE.1), ao, ..Settings::default() }
}

fn ao_of(layers: &[Vec<f32>]) -> Vec<f32> {
    layers.iter().flat_map(|l| l.iter().skip(3).step_by(4).copied()).collect()
}

fn rmse(a: &[f32], b: &[f32]) -> f64 {
    vrao::measure::metrics::rmse(a, b, None).unwrap()
}

#[test]
fn with_a_static_head_the_noise_falls_as_frames_accumulate() {
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    // What the estimator converges to: many samples, no reuse, no blur.
    let mut converged = Renderer::new(gpu.clone(), &scene, &settings(false, 256)).unwrap();
    let eyes = settings(false, 256).profile.eyes(&head, settings(false, 256).near);
    converged.render(&eyes.eyes, &[AO_RAW]).unwrap();
    let target = ao_of(&converged.read_f32(AO_RAW).unwrap());
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings(true, 8)).unwrap();
    let mut noise = Vec::new();
    for _ in 0..8 {
        renderer.render(&eyes.eyes, &[AO_ACCUMULATED]).unwrap();
        let accumulated = renderer.read_f32(AO_ACCUMULATED).unwrap();
        assert!(accumulated.iter().flatten().all(|v| v.is_finite()));
        noise.push(rmse(&ao_of(&accumulated), &target));
    }
    // Eight independent patterns would divide the noise by √8 ≈ 2.8; ask for 2.
    assert!(noise[7] < 0.5 * noise[0], "noise per frame: {noise:?}");
    assert!(noise.windows(2).filter(|w| w[1] > w[0] * 1.05).count() <= 1, "not falling: {noise:?}");
}

/// AO of the pixels that see geometry (sky pixels hold 1 whatever happens).
fn surface_ao(renderer: &Renderer, r: Resource) -> Vec<f32> {
    let geometry = renderer.read_f32(AO_GEOMETRY).unwrap();
    let values = renderer.read_f32(r).unwrap();
    geometry
        .iter()
        .zip(&values)
        .flat_map(|(g, v)| {
            g.chunks(4).zip(v.chunks(4)).filter(|(g, _)| g[3] > 0.0).map(|(_, v)| v[3]).collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn a_jump_to_a_new_view_discards_the_history_instead_of_smearing_it() {
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let s = settings(true, 8);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
    // Looking at the back wall, then from the left side at the right wall: none of the
    // surfaces now seen sat at the same place in the previous frame's view.
    let back = HeadPose::look_at(DVec3::new(0.0, 1.6, -0.5), DVec3::new(0.0, 1.2, -4.0)).unwrap();
    let side = HeadPose::look_at(DVec3::new(-1.8, 1.6, -2.0), DVec3::new(2.0, 1.0, -2.0)).unwrap();
    let outputs = [AO_ACCUMULATED, AO_RAW, AO_GEOMETRY];
    for _ in 0..6 {
        renderer.render(&s.profile.eyes(&back, s.near).eyes, &outputs).unwrap();
    }
    renderer.render(&s.profile.eyes(&side, s.near).eyes, &outputs).unwrap();
    let raw = surface_ao(&renderer, AO_RAW);
    let accumulated = surface_ao(&renderer, AO_ACCUMULATED);
    // Only points seen in both views (parts of the floor and ceiling) may reuse their
    // history; what they reuse must be their own (it brings them closer to the converged
    // value), never another surface's (which would pull them away).
    let mut converged = Renderer::new(gpu.clone(), &scene, &settings(false, 256)).unwrap();
    converged.render(&s.profile.eyes(&side, s.near).eyes, &[AO_RAW, AO_GEOMETRY]).unwrap();
    let target = surface_ao(&converged, AO_RAW);
    let mean_error = |v: &[f32]| v.iter().zip(&target).map(|(a, b)| (a - b).abs() as f64).sum::<f64>() / v.len() as f64;
    let fresh = raw.iter().zip(&accumulated).filter(|(a, b)| (*a - *b).abs() < 1e-3).count();
    assert!(fresh as f64 > 0.7 * raw.len() as f64, "{fresh} of {} surface pixels started afresh", raw.len());
    assert!(
        mean_error(&accumulated) <= mean_error(&raw) + 1e-3,
        "{} vs {}",
        mean_error(&accumulated),
        mean_error(&raw)
    );
    // A 1 cm step keeps the history of nearly every surface pixel.
    let stepped = HeadPose { position: side.position + DVec3::new(0.0, 0.0, 0.01), orientation: side.orientation };
    renderer.render(&s.profile.eyes(&stepped, s.near).eyes, &outputs).unwrap();
    let raw = surface_ao(&renderer, AO_RAW);
    let accumulated = surface_ao(&renderer, AO_ACCUMULATED);
    // Reused pixels hold the mean of two frames' patterns, which differ.
    let reused = raw.iter().zip(&accumulated).filter(|(a, b)| (*a - *b).abs() > 1e-4).count();
    let occluded = raw.iter().filter(|a| **a < 0.999).count();
    assert!(reused as f64 > 0.5 * occluded as f64, "only {reused} of {occluded} occluded pixels reused their history");
}

/// The largest accumulated frame count over both history buffers (one holds this
/// frame's counts, the other the last frame's), on surface pixels.
fn largest_count(renderer: &Renderer) -> f32 {
    [HISTORY_POSITION[0], HISTORY_POSITION[1]]
        .iter()
        .flat_map(|&r| renderer.read_f32(r).unwrap().into_iter().flatten().skip(3).step_by(4))
        .fold(0.0, f32::max)
}

#[test]
fn a_turning_head_shortens_the_window_and_a_still_one_keeps_it() {
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    // 6° of yaw per frame: 4–6 occlusion pixels of motion at 96 px over the test
    // profile's field of view, but under 1 px near the point the image turns about (the
    // head looks down, so world-vertical converges inside the view): windows of
    // 16 / (1 + m / 0.5) from the shortest allowed (4) to about 5.5 frames.
    let turned = |k: u32| HeadPose {
        position: head.position,
        orientation: DQuat::from_rotation_y((6.0 * k as f64).to_radians()) * head.orientation,
    };
    for motion_px in [0.5f32, 0.0] {
        let mut s = settings(true, 8);
        s.ao.temporal.motion_px = motion_px;
        let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
        for _ in 0..20 {
            renderer.render(&s.profile.eyes(&head, s.near).eyes, &[AO_ACCUMULATED]).unwrap();
        }
        let still = largest_count(&renderer);
        for k in 1..=8 {
            renderer.render(&s.profile.eyes(&turned(k), s.near).eyes, &[AO_ACCUMULATED]).unwrap();
            let values = renderer.read_f32(AO_ACCUMULATED).unwrap();
            assert!(values.iter().flatten().all(|v| v.is_finite()));
        }
        let turning = largest_count(&renderer);
        eprintln!("motion_px {motion_px}: largest count still {still}, after 8 turning frames {turning}");
        assert_eq!(still, 16.0, "a still head keeps the whole window (motion_px {motion_px})");
        if motion_px > 0.0 {
            assert!(turning <= 6.0, "the window did not shorten while turning: {turning}");
        } else {
            // Without the motion term a turn only loses what leaves the view or fails ε.
            assert_eq!(turning, 16.0, "with motion_px 0 a rotation keeps the whole window");
        }
    }
}

#[test]
fn a_history_holding_nan_is_discarded() {
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let s = settings(true, 8);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    renderer.render(&eyes.eyes, &[AO_ACCUMULATED]).unwrap();
    // Poison both history pairs: NaN values (f16 0x7E00) and NaN positions.
    for r in [HISTORY_VALUE[0], HISTORY_VALUE[1], HISTORY_POSITION[0], HISTORY_POSITION[1]] {
        let target = renderer.kept_target(r).expect("the temporal pass keeps its history");
        let texel: Vec<u8> = if r.format() == wgpu::TextureFormat::Rgba16Float {
            std::iter::repeat_n(0x7E00u16.to_le_bytes(), 4).flatten().collect()
        } else {
            std::iter::repeat_n(f32::NAN.to_le_bytes(), 4).flatten().collect()
        };
        let bytes: Vec<u8> = texel
            .iter()
            .copied()
            .cycle()
            .take(texel.len() * (target.width * target.height * target.layers) as usize)
            .collect();
        gpu.queue.write_texture(
            target.texture.as_image_copy(),
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(texel.len() as u32 * target.width),
                rows_per_image: Some(target.height),
            },
            target.texture.size(),
        );
    }
    renderer.render(&eyes.eyes, &[AO_ACCUMULATED, AO_RAW]).unwrap();
    let accumulated = renderer.read_f32(AO_ACCUMULATED).unwrap();
    assert!(accumulated.iter().flatten().all(|v| v.is_finite()), "NaN history leaked into the output");
    assert_eq!(ao_of(&accumulated), ao_of(&renderer.read_f32(AO_RAW).unwrap()), "NaN history was reused");
}

#[test]
fn the_graph_leaves_the_temporal_pass_out_when_it_is_off() {
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let off = Renderer::new(gpu.clone(), &scene, &settings(false, 8)).unwrap();
    let plan = off.plan(2, &[COLOR]).unwrap();
    assert!(!plan.names.contains(&"temporal"));
    assert!(
        plan.left_out.iter().any(|(name, why)| *name == "temporal" && why.contains("temporal accumulation is off")),
        "{plan}"
    );
    let on = Renderer::new(gpu, &scene, &settings(true, 8)).unwrap();
    assert!(on.plan(2, &[COLOR]).unwrap().names.contains(&"temporal"));
}
