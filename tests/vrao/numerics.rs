//! DESIGN.md "Numerics" on stiff and extreme inputs, for every technique and every pass
//! after it (blur, upsample, composite, tone map) and for the compositor's reprojection:
//! no NaN or Inf anywhere, AO within [0, 1], small input changes give small output
//! changes, and the error against the reference does not explode where the reference is
//! well defined.

use crate::common;

use glam::{DQuat, DVec3, Vec3};
use std::sync::Arc;
use vrao::xr::simulated::reproject::{output_target, ReprojectionMode, Reprojector};
use vrao_ao::plug::{Gpu, LayeredTarget, AO_BLURRED, AO_RAW, DEPTH, FINAL_AO};
use vrao_ao::{AoSettings, Denoise, Fov, HeadPose, Technique};
use vrao_render::passes::composite::HDR;
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::{Light, Material, Scene};
use vrao_render::{HeadsetProfile, Renderer, Settings};

const TECHNIQUES: [Technique; 5] =
    [Technique::Ssao, Technique::Hbao, Technique::Ssdo, Technique::SsdoBounce, Technique::SsdoPointsBounce];

/// What one frame produced, per resource and layer (RGBA values; depth is checked as it is read).
struct Outputs {
    ao: Vec<Vec<f32>>,
    hdr: Vec<Vec<f32>>,
    color: Vec<Vec<u8>>,
}

fn settings(size: (u32, u32), ao: AoSettings) -> Settings {
    Settings { profile: HeadsetProfile::with_size("test", size.0, size.1), ao, ..Settings::default() }
}

/// Renders every pass of a frame and checks the rules on each output: finite values, AO
/// in [0, 1], radiance ≥ 0. Returns the outputs for further checks.
fn render_checked(gpu: &Arc<Gpu>, label: &str, scene: &Scene, s: &Settings, head: &HeadPose) -> Outputs {
    let mut renderer = Renderer::new(gpu.clone(), scene, s).unwrap_or_else(|e| panic!("{label}: {e}"));
    let eyes = s.profile.eyes(head, s.near);
    let mut intermediate = vec![AO_RAW];
    if s.ao.blur_radius > 0 {
        intermediate.push(AO_BLURRED);
    }
    let final_ao = FINAL_AO;
    // The occlusion chain (with the standalone upsample at half resolution) ...
    let mut wanted = intermediate.clone();
    wanted.push(final_ao);
    renderer.render(&eyes.eyes, &wanted).unwrap_or_else(|e| panic!("{label}: {e}"));
    for r in wanted.iter().copied().collect::<std::collections::BTreeSet<_>>() {
        for (layer, values) in renderer.read_f32(r).unwrap().iter().enumerate() {
            let bad = values.iter().filter(|v| !v.is_finite()).count();
            assert_eq!(bad, 0, "{label}: {} layer {layer} holds {bad} NaN/Inf", r.name());
            let outside = values.chunks(4).filter(|p| !(0.0..=1.0).contains(&p[3])).count();
            assert_eq!(outside, 0, "{label}: {} layer {layer}: {outside} AO values outside [0, 1]", r.name());
        }
    }
    let ao = renderer.read_f32(final_ao).unwrap();
    // ... and the whole frame (the composite upsamples half-resolution AO itself).
    renderer.render(&eyes.eyes, &[HDR, COLOR, DEPTH]).unwrap();
    let hdr = renderer.read_f32(HDR).unwrap();
    for (layer, values) in hdr.iter().enumerate() {
        let bad = values.iter().filter(|v| !v.is_finite() || **v < 0.0).count();
        assert_eq!(bad, 0, "{label}: hdr layer {layer} holds {bad} NaN/Inf/negative values");
    }
    let color = renderer.read_bytes(COLOR).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    assert!(depth.iter().flatten().all(|d| d.is_finite() && (0.0..=1.0).contains(d)), "{label}: depth");
    renderer.gpu().take_error().unwrap_or_else(|e| panic!("{label}: {e}"));
    Outputs { ao, hdr, color }
}

/// Every technique, full and half resolution.
fn every_technique(gpu: &Arc<Gpu>, label: &str, scene: &Scene, base: &Settings, head: &HeadPose) -> Vec<Outputs> {
    let mut all = Vec::new();
    for technique in TECHNIQUES {
        for half_res in [false, true] {
            let mut s = base.clone();
            s.ao.technique = technique;
            s.ao.resolution = vrao_ao::Resolution::from_half_res(half_res);
            all.push(render_checked(gpu, &format!("{label} / {} half={half_res}", technique.name()), scene, &s, head));
        }
    }
    all
}

fn mean_abs_ao_difference(a: &Outputs, b: &Outputs) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for (la, lb) in a.ao.iter().zip(&b.ao) {
        for (pa, pb) in la.chunks(4).zip(lb.chunks(4)) {
            sum += (pa[3] - pb[3]).abs() as f64;
            n += 1;
        }
    }
    sum / n as f64
}

fn room() -> Scene {
    Scene::load("builtin:room").unwrap()
}

fn room_head() -> HeadPose {
    room().head.pose_at(0.0)
}

const SMALL: (u32, u32) = (40, 36);

#[test]
fn near_plane_1e_minus_4_with_geometry_from_a_millimetre_to_a_thousand_kilometres() {
    let (gpu, _lock) = common::gpu();
    // Squares facing the eye at 1 mm, 1 m, 1 km and 1000 km, each filling part of the view.
    let mut meshes = Vec::new();
    for (i, distance) in [1e-3, 1.0, 1e3, 1e6].into_iter().enumerate() {
        let x = (i as f64 - 1.5) * 0.4 * distance;
        meshes.push(common::square(
            &format!("at {distance} m"),
            DVec3::new(x, 0.0, -distance),
            (0.5 * distance) as f32,
            0,
        ));
    }
    let scene = common::bare_scene(meshes);
    let head = HeadPose::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0)).unwrap();
    let mut s = settings(SMALL, AoSettings::default());
    s.near = 1e-4;
    every_technique(&gpu, "near 1e-4, 1e-3..1e6 m", &scene, &s, &head);
}

#[test]
fn a_scene_placed_1e5_m_from_the_origin_renders_as_at_the_origin() {
    let (gpu, _lock) = common::gpu();
    let offset = DVec3::splat(1e5);
    let mut far = room();
    far.meshes.iter_mut().for_each(|m| m.origin += offset);
    far.lights.iter_mut().for_each(|l| {
        if let Light::Point { position, .. } = l {
            *position += offset;
        }
    });
    let head = room_head();
    let far_head = HeadPose { position: head.position + offset, orientation: head.orientation };
    for technique in TECHNIQUES {
        let s = settings(SMALL, AoSettings { technique, ..AoSettings::default() });
        let near_origin = render_checked(&gpu, "room at the origin", &room(), &s, &head);
        let far_away = render_checked(&gpu, "room at 1e5 m", &far, &s, &far_head);
        // Positions are relative to the camera: moving everything changes next to nothing.
        let diff = mean_abs_ao_difference(&near_origin, &far_away);
        assert!(diff < 0.01, "{}: mean |ΔAO| {diff} between the origin and 1e5 m", technique.name());
    }
}

#[test]
fn a_plane_at_89_9_degrees_to_the_view_stays_unoccluded() {
    let (gpu, _lock) = common::gpu();
    let plane = Scene::load("builtin:plane").unwrap();
    // Looking along the floor, 0.1° down: the floor is seen at 89.9° from its normal.
    let eye = DVec3::new(0.0, 0.01, 0.0);
    let head = HeadPose::look_at(eye, eye + DVec3::new(0.0, -(0.1f64.to_radians().tan()), -1.0)).unwrap();
    let s = settings(SMALL, AoSettings::default());
    for out in every_technique(&gpu, "grazing plane", &plane, &s, &head) {
        // An open plane occludes nothing, even where one pixel spans metres of it.
        let min = out.ao.iter().flatten().skip(3).step_by(4).fold(1.0f32, |m, &a| m.min(a));
        assert!(min > 0.9, "grazing plane: AO down to {min}");
    }
}

#[test]
fn radius_1e_minus_6_and_1e6_and_one_or_256_samples() {
    let (gpu, _lock) = common::gpu();
    let scene = room();
    for (radius, samples) in [(1e-6, 1), (1e-6, 256), (1e6, 1), (1e6, 256)] {
        let s = settings(SMALL, AoSettings { radius, samples, ..AoSettings::default() });
        let label = format!("r = {radius} m, N = {samples}");
        let outs = every_technique(&gpu, &label, &scene, &s, &room_head());
        if radius < 1e-3 {
            // Nothing lies within a micrometre: no occlusion.
            for out in &outs {
                let min = out.ao.iter().flatten().skip(3).step_by(4).fold(1.0f32, |m, &a| m.min(a));
                assert!(min > 0.98, "{label}: AO down to {min}");
            }
        }
    }
    // Continuity in the radius: 0.5 m and 0.5005 m give nearly the same AO.
    let a = render_checked(
        &gpu,
        "r 0.5",
        &scene,
        &settings(SMALL, AoSettings { radius: 0.5, ..AoSettings::default() }),
        &room_head(),
    );
    let b = render_checked(
        &gpu,
        "r 0.5005",
        &scene,
        &settings(SMALL, AoSettings { radius: 0.5005, ..AoSettings::default() }),
        &room_head(),
    );
    let diff = mean_abs_ao_difference(&a, &b);
    assert!(diff < 0.01, "radius +0.1 % changed AO by {diff}");
}

#[test]
fn a_blur_sigma_near_zero_keeps_the_centre_value() {
    let (gpu, _lock) = common::gpu();
    let scene = room();
    for technique in TECHNIQUES {
        // The bilateral blur keeps the centre; the default tile denoise blends in its
        // window's plain mean instead (denoise.wgsl), so this checks the bilateral.
        let ao =
            AoSettings { technique, blur_plane_sigma: 1e-30, denoise: Denoise::Bilateral, ..AoSettings::default() };
        let s = settings(SMALL, ao);
        let label = format!("{} blur sigma 1e-30", technique.name());
        let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
        let eyes = s.profile.eyes(&room_head(), s.near);
        renderer.render(&eyes.eyes, &[AO_RAW, AO_BLURRED]).unwrap();
        let raw = renderer.read_f32(AO_RAW).unwrap();
        let blurred = renderer.read_f32(AO_BLURRED).unwrap();
        // Every neighbour lies off the centre's plane by more than 1e-30 of its distance
        // (rounding alone does that), so its weight underflows and the centre stays.
        let (mut same, mut total) = (0, 0);
        for (lr, lb) in raw.iter().zip(&blurred) {
            for (pr, pb) in lr.chunks(4).zip(lb.chunks(4)) {
                assert!(pb.iter().all(|v| v.is_finite()) && (0.0..=1.0).contains(&pb[3]), "{label}");
                same += ((pr[3] - pb[3]).abs() < 2e-3) as usize;
                total += 1;
            }
        }
        // Neighbours exactly on the centre's plane (a wall facing the eye) keep weight 1;
        // all others drop out.
        assert!(same as f64 > 0.8 * total as f64, "{label}: only {same} of {total} pixels kept their value");
        render_checked(&gpu, &label, &scene, &s, &room_head());
    }
}

#[test]
fn sizes_1x1_3x5_and_1081x1199_at_half_resolution() {
    let (gpu, _lock) = common::gpu();
    let scene = room();
    for size in [(1, 1), (3, 5)] {
        every_technique(
            &gpu,
            &format!("{}x{}", size.0, size.1),
            &scene,
            &settings(size, AoSettings::default()),
            &room_head(),
        );
    }
    for technique in TECHNIQUES {
        let s = settings(
            (1081, 1199),
            AoSettings { technique, resolution: vrao_ao::Resolution::Half, samples: 8, ..AoSettings::default() },
        );
        render_checked(&gpu, &format!("1081x1199 half {}", technique.name()), &scene, &s, &room_head());
    }
}

#[test]
fn zero_length_and_nan_normals_and_degenerate_triangles() {
    let (gpu, _lock) = common::gpu();
    let mut floor = common::square("floor", DVec3::new(0.0, 0.0, -2.0), 4.0, 0);
    floor.normals = vec![Vec3::ZERO, Vec3::NAN, Vec3::new(0.0, 0.0, 1e-30), Vec3::new(f32::INFINITY, 0.0, 0.0)];
    let mut sliver = common::square("sliver", DVec3::new(0.0, 0.0, -1.5), 1.0, 0);
    // Two zero-area triangles: a repeated vertex and three collinear points.
    sliver.positions[1] = sliver.positions[0];
    sliver.positions[3] = (sliver.positions[0] + sliver.positions[2]) * 0.5;
    let scene = common::bare_scene(vec![floor, sliver]);
    let head = HeadPose::look_at(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -2.0)).unwrap();
    every_technique(&gpu, "bad normals, degenerate triangles", &scene, &settings(SMALL, AoSettings::default()), &head);
}

#[test]
fn nan_or_inf_in_vertex_data_is_rejected_at_load_naming_the_line() {
    let dir = common::temp_dir("nan-vertex");
    for (text, bad) in [("v 0 0 0\nv 1 0 0\nv 0 inf 1\nf 1 2 3\n", "inf"), ("v 0 0 0\nvn nan 0 1\nv 1 0 0\n", "nan")] {
        let path = dir.join("bad.obj");
        std::fs::write(&path, text).unwrap();
        let err = Scene::load(path.to_str().unwrap()).unwrap_err();
        let message = err.to_string();
        assert_eq!(vrao::Error::from(err).exit_code(), 2);
        assert!(message.contains("bad.obj:") && message.contains(bad), "{message}");
    }
}

#[test]
fn light_and_emission_of_1e30_stay_finite_through_tone_mapping() {
    let (gpu, _lock) = common::gpu();
    let mut scene = room();
    scene.lights.push(Light::Point { position: DVec3::new(0.0, 2.0, -2.0), color: Vec3::ONE, intensity: 1e30 });
    scene.materials.push(Material { emissive: Vec3::splat(1e30), ..Material::plain("sun-hot", Vec3::ONE) });
    let hot = scene.materials.len() - 1;
    scene.meshes.push(common::square("hot", DVec3::new(0.5, 1.5, -3.9), 0.5, hot));
    for out in
        every_technique(&gpu, "1e30 light and emission", &scene, &settings(SMALL, AoSettings::default()), &room_head())
    {
        // The hottest pixels saturate to white instead of overflowing.
        assert!(out.color.iter().flatten().any(|&c| c == 255), "no saturated pixel");
        assert!(out.hdr.iter().flatten().all(|v| *v <= 65504.0));
    }
}

#[test]
fn ipd_0_and_0_3_m_and_extreme_asymmetric_fields_of_view() {
    let (gpu, _lock) = common::gpu();
    let scene = room();
    for ipd in [0.0, 0.3] {
        let mut s = settings(SMALL, AoSettings::default());
        s.profile.ipd = ipd;
        let outs = every_technique(&gpu, &format!("ipd {ipd}"), &scene, &s, &room_head());
        if ipd == 0.0 {
            // Both eyes at one point with mirrored frusta: the left eye's image is the right
            // eye's mirrored only for symmetric content, so compare AO statistics instead.
            for out in outs {
                let mean =
                    |l: &Vec<f32>| l.iter().skip(3).step_by(4).map(|&a| a as f64).sum::<f64>() / (l.len() / 4) as f64;
                assert!((mean(&out.ao[0]) - mean(&out.ao[1])).abs() < 0.1);
            }
        }
    }
    // 80° outward, 10° inward, 60° up, 45° down.
    let left = Fov {
        left: -(80f32.to_radians()),
        right: 10f32.to_radians(),
        up: 60f32.to_radians(),
        down: -(45f32.to_radians()),
    };
    let mut s = settings(SMALL, AoSettings::default());
    s.profile.fov_left = left;
    s.profile.fov_right = left.mirrored();
    every_technique(&gpu, "fov 80° out, 10° in", &scene, &s, &room_head());
}

#[test]
fn a_head_pose_with_an_unnormalised_quaternion_renders_as_the_normalised_one() {
    let (gpu, _lock) = common::gpu();
    let scene = room();
    let head = room_head();
    let scaled = HeadPose {
        position: head.position,
        orientation: DQuat::from_xyzw(
            head.orientation.x * 3.7,
            head.orientation.y * 3.7,
            head.orientation.z * 3.7,
            head.orientation.w * 3.7,
        ),
    };
    let s = settings(SMALL, AoSettings::default());
    let a = render_checked(&gpu, "normalised", &scene, &s, &head);
    let b = render_checked(&gpu, "quaternion × 3.7", &scene, &s, &scaled);
    assert!(mean_abs_ao_difference(&a, &b) < 1e-3);
    assert_eq!(a.color, b.color);
}

/// A 2-layer depth target cleared to `value` (Depth32Float cannot be written by copies;
/// a render pass clear is the one way to fill it without rasterising).
fn depth_target(gpu: &Gpu, (w, h): (u32, u32), value: f32) -> LayeredTarget {
    let target = LayeredTarget::new(
        &gpu.device,
        "history depth",
        DEPTH.format(),
        (w, h, 2),
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for view in &target.layer_views {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear history depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(value), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
    }
    gpu.queue.submit([encoder.finish()]);
    target
}

#[test]
fn a_reprojection_history_without_usable_depth_falls_back_to_the_rotational_warp() {
    let (gpu, _lock) = common::gpu();
    let scene = room();
    let s = settings(SMALL, AoSettings::default());
    let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
    let head = room_head();
    let source = s.profile.eyes(&head, s.near);
    renderer.render(&source.eyes, &[COLOR]).unwrap();
    let color = renderer.target(COLOR).unwrap();
    let moved = HeadPose {
        position: head.position + DVec3::new(0.05, 0.0, 0.0),
        orientation: DQuat::from_rotation_y(0.05) * head.orientation,
    };
    let target = s.profile.eyes(&moved, s.near);
    let mut reprojector = Reprojector::new(&gpu).unwrap();
    let mut warp = |depth: &LayeredTarget, mode| {
        let output = output_target(&gpu, color.extent());
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        reprojector.record(&gpu, &mut encoder, mode, color, depth, &source.eyes, &target.eyes, s.near, &output);
        gpu.queue.submit([encoder.finish()]);
        gpu.take_error().unwrap();
        vrao_ao::plug::read_layers(&gpu, &output).unwrap()
    };
    // NaN cannot reach a Depth32Float history (copies into it are forbidden and
    // rasterisation clamps depth to [0, 1]); the shader still treats anything outside
    // (0, 1] as no depth. A history whose depth is all sky is warped rotationally,
    // pixel for pixel.
    let sky = depth_target(&gpu, SMALL, 0.0);
    let rotational = warp(&sky, ReprojectionMode::Rotational);
    assert_eq!(warp(&sky, ReprojectionMode::Depth), rotational);
    // A history at the near plane everywhere warps without NaN (all bytes are colours).
    let at_near = depth_target(&gpu, SMALL, 1.0);
    let warped = warp(&at_near, ReprojectionMode::Depth);
    assert!(warped.iter().flatten().skip(3).step_by(4).all(|&a| a == 255));
}

#[test]
fn error_against_the_reference_does_not_grow_when_the_scene_moves_1e5_m_out() {
    use vrao::measure::reference::{trace, ReferenceSettings};
    let (gpu, _lock) = common::gpu();
    let size = (96, 80);
    let crease = Scene::load("builtin:crease").unwrap();
    let offset = DVec3::new(1e5, 0.0, -1e5);
    let mut far = crease.clone();
    far.meshes.iter_mut().for_each(|m| m.origin += offset);
    let head = crease.head.pose_at(0.0);
    let far_head = HeadPose { position: head.position + offset, orientation: head.orientation };
    let mut errors = Vec::new();
    for (scene, head) in [(&crease, head), (&far, far_head)] {
        let s = settings(size, AoSettings { radius: 0.5, ..AoSettings::default() });
        let eyes = s.profile.eyes(&head, s.near);
        let reference = trace(
            scene,
            &eyes.eyes,
            size,
            &ReferenceSettings { radius: 0.5, rays_per_pixel: 64, stride: 2, near: s.near },
            &mut |_| {},
        )
        .unwrap();
        for technique in TECHNIQUES {
            let s = settings(size, AoSettings { technique, radius: 0.5, ..AoSettings::default() });
            let output = FINAL_AO;
            let mut renderer = Renderer::new(gpu.clone(), scene, &s).unwrap();
            renderer.render(&eyes.eyes, &[output]).unwrap();
            let e = vrao::measure::bench::error_figures(technique, &renderer.read_f32(output).unwrap(), &reference);
            errors.push((technique, e.ao_rmse));
        }
    }
    let (near_origin, far_away) = errors.split_at(TECHNIQUES.len());
    for ((t, a), (_, b)) in near_origin.iter().zip(far_away) {
        assert!(a.is_finite() && b.is_finite() && *a < 0.1, "{}: {a} {b}", t.name());
        assert!((a - b).abs() < 0.01, "{}: AO RMSE {a} at the origin, {b} at 1e5 m", t.name());
    }
}
