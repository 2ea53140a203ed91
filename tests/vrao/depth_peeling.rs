//! Depth peeling for SSDO (Ritschel et al. 2009 §4): a second depth layer per eye, and a sample
//! occludes only between the first and second layer. Checked against the reference
//! tracer: a thin board floating in front of a wall casts no halo onto the wall with
//! peeling; a closed box still darkens the floor beside it; the pass runs only when
//! SSDO runs with peeling on.

use crate::common;

use glam::{DVec3, Vec3};
use vrao::measure::bench::error_figures;
use vrao::measure::reference::{trace, ReferenceImage, ReferenceSettings};
use vrao_ao::plug::{Resource, DEPTH, DEPTH_LAYER_2, FINAL_AO};
use vrao_ao::{AoSettings, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::{HeadsetProfile, PointSsdoSettings, Renderer, Scene, Settings};

const SIZE: (u32, u32) = (128, 144);
const RADIUS: f32 = 0.5;
const WALL_Z: f64 = -3.0;

fn settings(ao: AoSettings, depth_peeling: bool) -> Settings {
    let point_ssdo = PointSsdoSettings { depth_peeling, ..PointSsdoSettings::default() };
    Settings { profile: HeadsetProfile::with_size("test", SIZE.0, SIZE.1), ao, point_ssdo, ..Settings::default() }
}

fn ssdo() -> AoSettings {
    AoSettings { technique: Technique::SsdoPoints, samples: 36, radius: RADIUS, ..AoSettings::default() }
}

/// A 1.2 m × 1.2 m board, 2 cm thick, whose back face is `gap` metres in front of a
/// 10 m wall at z = −3, seen head-on from the origin.
fn board_scene(gap: f64) -> Scene {
    let board_z = WALL_Z + gap + 0.01;
    common::bare_scene(vec![
        common::square("wall", DVec3::new(0.0, 0.0, WALL_Z), 10.0, 0),
        common::cuboid("board", DVec3::new(0.0, 0.0, board_z), Vec3::new(1.2, 1.2, 0.02), 0),
    ])
}

/// Renders one frame and returns the final occlusion per eye (RGBA), after checking
/// that every value is finite and the AO within [0, 1].
fn render(scene: &Scene, s: &Settings) -> Vec<Vec<f32>> {
    let (gpu, _one_at_a_time) = common::gpu();
    let output = FINAL_AO;
    let mut renderer = Renderer::new(gpu, scene, s).unwrap();
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    let report = renderer.render(&eyes.eyes, &[output]).unwrap();
    assert_eq!(report.plan.runs("depth-peel"), s.point_ssdo.depth_peeling, "{}", report.plan);
    let layers = renderer.read_f32(output).unwrap();
    for (layer, image) in layers.iter().enumerate() {
        for (i, px) in image.chunks(4).enumerate() {
            assert!(px.iter().all(|v| v.is_finite()), "layer {layer} pixel {i}: {px:?}");
            assert!((0.0..=1.0).contains(&px[3]), "layer {layer} pixel {i}: AO {}", px[3]);
        }
    }
    layers
}

fn trace_reference(scene: &Scene, stride: u32) -> ReferenceImage {
    let s = settings(ssdo(), false);
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    let rs = ReferenceSettings { radius: RADIUS as f64, rays_per_pixel: 256, stride, near: s.near };
    trace(scene, &eyes.eyes, SIZE, &rs, &mut |_| {}).unwrap()
}

/// Mean GPU AO and mean reference AO over the grid cells `select` picks, both eyes.
fn mean_over(
    gpu: &[Vec<f32>],
    reference: &ReferenceImage,
    select: impl Fn(usize, u32, u32) -> bool,
) -> (f64, f64, usize) {
    let (gw, gh) = reference.grid_size();
    let (mut ours, mut truth, mut n) = (0.0, 0.0, 0);
    for (layer, image) in gpu.iter().enumerate() {
        for j in 0..gh {
            for i in 0..gw {
                if select(layer, i, j) {
                    let (x, y) = reference.pixel_of(i, j);
                    ours += image[((y * SIZE.0 + x) * 4 + 3) as usize] as f64;
                    truth += reference.get(layer, i, j).ao as f64;
                    n += 1;
                }
            }
        }
    }
    assert!(n > 0, "no cell selected");
    (ours / n as f64, truth / n as f64, n)
}

/// Wall cells within `reach` grid cells of a board cell: where a halo would show.
fn halo_band(reference: &ReferenceImage, reach: i64) -> impl Fn(usize, u32, u32) -> bool + '_ {
    let (gw, gh) = reference.grid_size();
    let on_wall = |p: &vrao::measure::reference::ReferencePixel| p.hit && p.depth > (-WALL_Z as f32) - 0.05;
    let on_board = |p: &vrao::measure::reference::ReferencePixel| p.hit && p.depth < (-WALL_Z as f32) - 0.05;
    move |layer, i, j| {
        if !on_wall(reference.get(layer, i, j)) {
            return false;
        }
        for dj in -reach..=reach {
            for di in -reach..=reach {
                let (x, y) = (i as i64 + di, j as i64 + dj);
                if x >= 0
                    && y >= 0
                    && x < gw as i64
                    && y < gh as i64
                    && on_board(reference.get(layer, x as u32, y as u32))
                {
                    return true;
                }
            }
        }
        false
    }
}

#[test]
fn a_thin_board_far_in_front_of_a_wall_casts_a_halo_only_without_peeling() {
    // The board is 1 m in front of the wall, twice the radius: nothing on the wall is
    // occluded (the reference says AO = 1 there). With the range check off, plain SSDO
    // takes every sample hidden behind the board for a blocker and darkens the wall
    // around its silhouette; peeling knows the board is 2 cm thick and leaves it open.
    let scene = board_scene(1.0);
    let reference = trace_reference(&scene, 2);
    let band = halo_band(&reference, 1);
    let mut results = Vec::new();
    for (peel, range_check) in [(false, false), (true, false), (true, true)] {
        let ao = render(&scene, &settings(AoSettings { range_check, ..ssdo() }, peel));
        let (ours, truth, n) = mean_over(&ao, &reference, &band);
        let e = error_figures(Technique::SsdoPoints, &ao, &reference);
        println!(
            "board 1 m in front, peel={peel} range check={range_check}: wall beside the board AO {ours:.3} \
             (reference {truth:.3}, {n} cells); AO RMSE {:.4}",
            e.ao_rmse
        );
        results.push((ours, truth, e.ao_rmse));
    }
    let (plain, peeled) = (results[0], results[1]);
    assert!(plain.1 > 0.99, "the reference sees an open wall: {results:?}");
    assert!(plain.0 < 0.93, "plain SSDO should darken the wall around the board (the halo): {results:?}");
    for peeled in &results[1..] {
        assert!((peeled.0 - peeled.1).abs() < 0.02, "with peeling the wall beside the board stays open: {results:?}");
    }
    assert!(peeled.2 < plain.2, "peeling must bring the image closer to the reference: {results:?}");
}

#[test]
fn a_closed_box_still_occludes_the_floor_beside_it_with_peeling() {
    let scene = Scene::load("builtin:box").unwrap();
    let reference = trace_reference(&scene, 2);
    let s = settings(ssdo(), false);
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    // Floor cells between `near` and `far` metres from the unit box's centre line (its
    // sides stand at x, z = ±0.5).
    let floor = |near: f64, far: f64| {
        let eyes = &eyes;
        let reference = &reference;
        move |layer: usize, i: u32, j: u32| {
            vrao::measure::reference::world_position(reference, &eyes.eyes[layer], layer, i, j).is_some_and(|p| {
                let out = p.x.abs().max(p.z.abs());
                p.y.abs() < 0.01 && out > near && out < far
            })
        }
    };
    let mut results = Vec::new();
    for peel in [false, true] {
        let ao = render(&scene, &settings(ssdo(), peel));
        let (beside, truth, n) = mean_over(&ao, &reference, floor(0.5, 0.75));
        let (open, _, _) = mean_over(&ao, &reference, floor(3.0, 6.0));
        let e = error_figures(Technique::SsdoPoints, &ao, &reference);
        println!(
            "box, peel={peel}: floor beside AO {beside:.3} (reference {truth:.3}, {n} cells), open floor {open:.3}; \
             AO RMSE {:.4}",
            e.ao_rmse
        );
        results.push((beside, truth, open, e.ao_rmse));
    }
    let (plain, peeled) = (results[0], results[1]);
    assert!(peeled.1 < 0.85, "the reference darkens the floor beside the box: {results:?}");
    assert!(peeled.0 < 0.95 && peeled.2 > 0.99, "with peeling the box still occludes the floor: {results:?}");
    assert!((peeled.0 - plain.0).abs() < 0.02, "a closed box occludes about as much either way: {results:?}");
    assert!(peeled.3 < plain.3 + 0.005, "{results:?}");
}

#[test]
fn the_peel_pass_runs_only_for_ssdo_with_peeling_on() {
    let (gpu, _one_at_a_time) = common::gpu();
    let scene = board_scene(1.0);
    let plan = |technique, depth_peeling, outputs: &[Resource]| {
        let s = settings(AoSettings { technique, ..AoSettings::default() }, depth_peeling);
        Renderer::new(gpu.clone(), &scene, &s).unwrap().plan(2, outputs).unwrap()
    };
    let reason = |p: &vrao_ao::Plan| p.left_out.iter().find(|(n, _)| *n == "depth-peel").map(|(_, r)| r.clone());
    for technique in [Technique::SsdoPoints, Technique::SsdoPointsBounce] {
        let on = plan(technique, true, &[COLOR]);
        assert!(on.runs("depth-peel"), "{on}");
        let order: Vec<_> = on
            .names
            .iter()
            .filter(|n| ["gbuffer", "depth-peel", "ssdo-points", "ssdo-points-bounce"].contains(n))
            .collect();
        assert_eq!(order[..2], [&"gbuffer", &"depth-peel"], "{on}");
        assert!(on.resources.contains(&DEPTH_LAYER_2));
        let off = plan(technique, false, &[COLOR]);
        assert!(!off.runs("depth-peel") && !off.resources.contains(&DEPTH_LAYER_2), "{off}");
        assert!(reason(&off).unwrap().contains("depth peeling is off"), "{off}");
        // Only depth asked for: nothing reads the second layer.
        let depth_only = plan(technique, true, &[DEPTH]);
        assert!(!depth_only.runs("depth-peel"), "{depth_only}");
    }
    for technique in [Technique::None, Technique::Ssao, Technique::Hbao, Technique::Ssdo] {
        let p = plan(technique, true, &[COLOR]);
        assert!(!p.runs("depth-peel"), "{p}");
        let why = reason(&p).unwrap();
        assert!(why.contains(&format!("technique is {}", technique.name())), "{why}");
    }
}

#[test]
fn peeling_at_half_resolution_with_the_bounce_stays_finite() {
    let scene = Scene::load("builtin:room").unwrap();
    for technique in [Technique::SsdoPoints, Technique::SsdoPointsBounce] {
        let s = settings(AoSettings { resolution: vrao_ao::Resolution::Half, technique, ..ssdo() }, true);
        render(&scene, &s);
    }
}

#[test]
fn peeling_with_extreme_radii_and_sample_counts_stays_finite() {
    let scene = board_scene(0.3);
    for (radius, samples) in [(1e-6, 1), (1e-6, 256), (1e6, 1), (1e6, 256), (0.5, 1)] {
        for range_check in [false, true] {
            render(&scene, &settings(AoSettings { radius, samples, range_check, ..ssdo() }, true));
        }
    }
}
