//! Stereo geometry on the GPU: parallax, depth reconstruction, multiview = multipass.

mod common;

use glam::DVec3;
use vrao::stereo::{view_position_from_depth, HeadsetProfile};
use vrao::{HeadPose, Renderer, Resource, Scene, Settings, StereoMode};

fn settings(width: u32, height: u32, stereo: StereoMode) -> Settings {
    Settings { profile: HeadsetProfile::with_size("test", width, height), stereo, ..Settings::default() }
}

/// Centroid (x, y in pixels, origin top-left corner of the image) of covered pixels.
fn coverage_centroid(depth: &[f32], width: u32) -> Option<(f64, f64)> {
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for (i, &d) in depth.iter().enumerate() {
        if d > 0.0 {
            sx += (i as u32 % width) as f64 + 0.5;
            sy += (i as u32 / width) as f64 + 0.5;
            n += 1.0;
        }
    }
    (n > 0.0).then(|| (sx / n, sy / n))
}

#[test]
fn a_point_lands_on_the_analytic_pixel_in_each_eye() {
    let (gpu, _guard) = common::gpu();
    let (w, h) = (216, 240);
    let s = settings(w, h, StereoMode::Auto);
    for distance in [0.4, 1.5, 6.0, 40.0] {
        // A marker about 8 pixels across at this distance, slightly off-centre.
        let center = DVec3::new(0.07 * distance, -0.05 * distance, -distance);
        let size = (distance * 0.04) as f32;
        let scene = common::bare_scene(vec![common::square("marker", center, size, 0)]);
        let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
        let eyes = s.profile.eyes(&HeadPose::IDENTITY, s.near);
        renderer.render(&eyes.eyes, &[Resource::Depth]).unwrap();
        let depth = renderer.read_f32(Resource::Depth).unwrap();
        let mut measured_x = [0.0; 2];
        for (layer, eye) in eyes.eyes.iter().enumerate() {
            let (uv, _) = eye.project(center, s.near).unwrap();
            let expected = (uv[0] * w as f64, uv[1] * h as f64);
            let got = coverage_centroid(&depth[layer], w).expect("marker visible");
            measured_x[layer] = got.0;
            let err = ((got.0 - expected.0).powi(2) + (got.1 - expected.1).powi(2)).sqrt();
            assert!(err < 0.5, "distance {distance} eye {layer}: pixel {got:?}, expected {expected:?} ({err:.3} px)");
        }
        // Disparity (left x − right x) against the analytic value.
        let (l, r) = (eyes.eyes[0].project(center, s.near).unwrap().0, eyes.eyes[1].project(center, s.near).unwrap().0);
        let expected_disparity = (l[0] - r[0]) * w as f64;
        let disparity = measured_x[0] - measured_x[1];
        assert!(
            (disparity - expected_disparity).abs() < 0.5,
            "distance {distance}: disparity {disparity:.3} px, expected {expected_disparity:.3} px"
        );
        assert!(expected_disparity > 0.0, "a point in front of both eyes appears further right in the left eye");
    }
}

#[test]
fn depth_reconstructs_view_position_from_5cm_to_10km() {
    let (gpu, _guard) = common::gpu();
    let (w, h) = (64, 72);
    let mut s = settings(w, h, StereoMode::Auto);
    s.near = 0.01;
    for distance in [0.05, 0.2, 1.0, 10.0, 100.0, 1e3, 1e4] {
        // A wall facing the eyes that fills both views.
        let scene = common::bare_scene(vec![common::square("wall", DVec3::new(0.0, 0.0, -distance), (distance * 8.0) as f32, 0)]);
        let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
        let eyes = s.profile.eyes(&HeadPose::IDENTITY, s.near);
        renderer.render(&eyes.eyes, &[Resource::Depth]).unwrap();
        let depth = renderer.read_f32(Resource::Depth).unwrap();
        let mut worst: f64 = 0.0;
        for (layer, eye) in eyes.eyes.iter().enumerate() {
            let eye_to_wall = distance; // the eyes are offset along x only, the wall is z = −distance
            for y in 0..h {
                for x in 0..w {
                    let d = depth[layer][(y * w + x) as usize] as f64;
                    assert!(d > 0.0, "wall at {distance} m missing at ({x}, {y})");
                    let uv = [(x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64];
                    let p = view_position_from_depth(uv, d, &eye.fov, s.near);
                    // The exact hit of this pixel's ray with the wall plane.
                    let [l, r, u, dn] = eye.fov.tangents();
                    let exact = DVec3::new(l + (r - l) * uv[0], u + (dn - u) * uv[1], -1.0) * eye_to_wall;
                    worst = worst.max((p - exact).length() / exact.length());
                }
            }
        }
        assert!(worst < 1e-4, "distance {distance} m: worst relative error {worst:e}");
    }
}

fn render_all(gpu: &std::sync::Arc<vrao::Gpu>, scene: &Scene, stereo: StereoMode) -> Vec<Vec<Vec<u8>>> {
    let s = settings(128, 144, stereo);
    let mut renderer = Renderer::new(gpu.clone(), scene, &s).unwrap();
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    let outputs = [Resource::Color, Resource::Depth, Resource::Normals, Resource::Albedo];
    renderer.render(&eyes.eyes, &outputs).unwrap();
    outputs.iter().map(|&r| renderer.read_bytes(r).unwrap()).collect()
}

#[test]
fn multiview_and_multipass_give_the_same_pixels() {
    let (gpu, _guard) = common::gpu();
    if !gpu.caps.multiview {
        eprintln!("skipped: adapter '{}' has no multiview", gpu.adapter.get_info().name);
        return;
    }
    let scene = Scene::load("builtin:room").unwrap();
    let multiview = render_all(&gpu, &scene, StereoMode::Multiview);
    let multipass = render_all(&gpu, &scene, StereoMode::Multipass);
    for (i, name) in ["color", "depth", "normals", "albedo"].iter().enumerate() {
        for layer in 0..2 {
            let (a, b) = (&multiview[i][layer], &multipass[i][layer]);
            let differing = a.iter().zip(b).filter(|(x, y)| x != y).count();
            assert_eq!(differing, 0, "{name} layer {layer}: {differing} bytes differ");
        }
    }
    // And the eyes really differ from each other (parallax), so the comparison means something.
    assert_ne!(multiview[0][0], multiview[0][1]);
}

#[test]
fn the_graph_runs_only_what_the_requested_outputs_need() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let s = settings(64, 72, StereoMode::Auto);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    let report = renderer.render(&eyes.eyes, &[Resource::Normals]).unwrap();
    assert_eq!(report.plan.names, vec!["gbuffer"]);
    let left_out: Vec<_> = report.plan.left_out.iter().map(|(n, _)| *n).collect();
    assert_eq!(left_out, vec!["lighting", "tonemap"]);
    assert!(renderer.target(Resource::Hdr).is_none(), "no HDR target is allocated when nothing needs it");
    if gpu.caps.timestamps {
        assert!(report.gpu_ms_of("gbuffer").is_some() && report.gpu_ms_of("lighting").is_none());
    }
    let report = renderer.render(&eyes.eyes, &[Resource::Color]).unwrap();
    assert_eq!(report.plan.names, vec!["gbuffer", "lighting", "tonemap"]);
}

#[test]
fn lit_room_is_finite_and_not_flat() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let s = settings(96, 108, StereoMode::Auto);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &s).unwrap();
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    renderer.render(&eyes.eyes, &[Resource::Color, Resource::Hdr]).unwrap();
    for layer in renderer.read_f32(Resource::Hdr).unwrap() {
        assert!(layer.iter().all(|v| v.is_finite() && *v >= 0.0), "HDR holds a non-finite or negative value");
    }
    for layer in renderer.read_bytes(Resource::Color).unwrap() {
        let lum: Vec<f64> = layer.chunks_exact(4).map(|p| p[0] as f64 + p[1] as f64 + p[2] as f64).collect();
        let mean = lum.iter().sum::<f64>() / lum.len() as f64;
        let var = lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64;
        assert!(mean > 30.0 && var.sqrt() > 10.0, "room image is dark or flat (mean {mean}, std {})", var.sqrt());
    }
}
