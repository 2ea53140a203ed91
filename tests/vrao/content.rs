//! Real content on the GPU: alpha-tested holes for every pass and for the reference
//! (`builtin:grille`), moving objects placed by their transforms on the GPU, and the
//! G-buffer's motion vectors against the objects' analytic motion (`builtin:moving`).

use crate::common;

use glam::DVec3;
use vrao::measure::reference::{trace, world_position, ReferenceSettings};
use vrao_ao::plug::{DEPTH, FINAL_AO, MOTION, NORMALS};
use vrao_ao::HeadPose;
use vrao_render::scene::content::{grille_solid_at, BALL_RADIUS, GRILLE_HEIGHT};
use vrao_render::scene::HeadPath;
use vrao_render::{HeadsetProfile, Renderer, Scene, Settings};

fn settings(scene: &Scene, width: u32, height: u32) -> Settings {
    let mut settings = Settings { profile: HeadsetProfile::with_size("test", width, height), ..Settings::default() };
    settings.ao.radius = scene.suggested_ao_radius();
    settings
}

/// The grille as an OBJ: floor and plate quads, the plate's MTL material alpha-tested by
/// a `map_d` greyscale checker (255 solid, 0 hole) laid out as `builtin:grille`'s mask.
fn grille_obj(dir: &std::path::Path) -> std::path::PathBuf {
    use vrao_render::scene::content::{GRILLE_CELLS, GRILLE_HALF_SIZE, GRILLE_HEIGHT};
    let side = GRILLE_CELLS * 8;
    let mask =
        image::GrayImage::from_fn(side, side, |x, y| image::Luma([if (x / 8 + y / 8) % 2 == 0 { 255 } else { 0 }]));
    mask.save(dir.join("mask.png")).unwrap();
    std::fs::write(
        dir.join("grille.mtl"),
        "newmtl white\nKd 0.8 0.8 0.8\nnewmtl grille\nKd 0.8 0.8 0.8\nmap_d mask.png\n",
    )
    .unwrap();
    let (h, y) = (GRILLE_HALF_SIZE, GRILLE_HEIGHT);
    // OBJ's v runs bottom-up (vrao flips it at load): vt v = 1 − the mask's row fraction.
    let obj = format!(
        "mtllib grille.mtl\n\
         v -3 0 -3\nv -3 0 3\nv 3 0 3\nv 3 0 -3\n\
         v {n} {y} {n}\nv {h} {y} {n}\nv {h} {y} {h}\nv {n} {y} {h}\n\
         vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nvn 0 1 0\n\
         usemtl white\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n\
         usemtl grille\nf 5/1/1 7/3/1 6/2/1\nf 5/1/1 8/4/1 7/3/1\n",
        n = -h
    );
    let path = dir.join("grille.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// The grille's holes are holes for the G-buffer and for the reference: through a hole the
/// G-buffer's depth is the floor's, the floor under holes is brighter than under solid
/// cells in both, and GTAO's mean floor AO under holes and under solid cells is each
/// within 0.03 of the reference's (the plate's samples are cards, gtao.wgsl
/// `THIN_CARDS`); the same for the grille written as glTF and loaded back, and as an OBJ
/// alpha-tested by `map_d`.
#[test]
fn floor_ao_under_the_grille_holes_and_solid_cells_against_the_reference() {
    let dir = common::temp_dir("grille");
    let builtin = Scene::load("builtin:grille").unwrap();
    let glb = dir.join("grille.glb");
    vrao::test_assets::gltf_write::write(&builtin, &glb, &Default::default()).unwrap();
    let mut obj = Scene::load(grille_obj(&dir).to_str().unwrap()).unwrap();
    obj.head = builtin.head.clone();
    let mut from_glb = Scene::load(glb.to_str().unwrap()).unwrap();
    from_glb.head = builtin.head.clone();
    assert!(obj.has_alpha_test() && from_glb.has_alpha_test());
    let radius = builtin.suggested_ao_radius();
    for scene in [builtin, from_glb, obj] {
        let means = grille_floor_means(&scene, radius);
        println!(
            "{}: floor AO (GPU, reference): under holes {:?}, under solid cells {:?}",
            scene.name, means[0], means[1]
        );
        // The holes let the sky through, for the reference and for the GPU's estimate.
        assert!(means[0].1 > means[1].1 + 0.05, "{}: reference: {means:?}", scene.name);
        assert!(means[0].0 > means[1].0 + 0.05, "{}: GPU: {means:?}", scene.name);
        for (gpu, reference) in means {
            assert!((gpu - reference).abs() <= 0.03, "{}: GPU against reference: {means:?}", scene.name);
        }
    }
}

/// The grille's cards hold beyond its own view: from three head poses, with the card 25
/// and 12 cm over the floor, at half and twice the scene's radius, GTAO's mean floor AO
/// under holes is within 0.05 of the reference's and under solid cells within −0.05..0.16
/// (light where the card is close and the radius wide: 24 samples are sparse there). As
/// slabs `thickness` × r deep the plate read up to 0.34 too dark.
#[test]
fn grille_cards_from_other_poses_heights_and_radii() {
    let radius = Scene::load("builtin:grille").unwrap().suggested_ao_radius();
    for eye in [DVec3::new(1.3, 0.9, 1.0), DVec3::new(0.3, 0.7, 1.6), DVec3::new(0.0, 1.3, 1.5)] {
        for height in [GRILLE_HEIGHT, 0.12] {
            let mut scene = Scene::load("builtin:grille").unwrap();
            scene.meshes[1].origin.y += height - GRILLE_HEIGHT;
            scene.head = HeadPath::fixed(HeadPose::look_at(eye, DVec3::ZERO).unwrap());
            for scale in [0.5, 2.0] {
                let [holes, solid] = grille_floor_means(&scene, radius * scale);
                let what = format!("eye {eye}, card at {height} m, radius {}", radius * scale);
                println!("{what}: floor AO (GPU, reference) under holes {holes:?}, under solid cells {solid:?}");
                assert!((holes.0 - holes.1).abs() <= 0.05, "{what}: under holes {holes:?}");
                assert!((-0.05..=0.16).contains(&(solid.0 - solid.1)), "{what}: under solid cells {solid:?}");
            }
        }
    }
}

/// [under holes, under solid cells]: the mean floor AO (GPU, reference) of `scene` (the
/// grille in any form) with AO radius `radius`, asserting that the G-buffer sees the floor
/// wherever the reference does.
fn grille_floor_means(scene: &Scene, radius: f32) -> [(f64, f64); 2] {
    let (w, h) = (160, 180);
    let mut settings = settings(scene, w, h);
    settings.ao.radius = radius;
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let reference_settings =
        ReferenceSettings { radius: settings.ao.radius as f64, rays_per_pixel: 256, stride: 2, near: settings.near };
    let reference = trace(scene, &eyes.eyes, (w, h), &reference_settings, &mut |_| {}).unwrap();
    let (gpu, _one_at_a_time) = common::gpu();
    let mut renderer = Renderer::new(gpu, scene, &settings).unwrap();
    renderer.render_and_wait(&eyes.eyes, &[FINAL_AO, DEPTH]).unwrap();
    let ao = renderer.read_f32(FINAL_AO).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    let gpu_worlds = common::world_positions(&depth, &eyes.eyes, w, h, settings.near);
    // [under holes, under solid cells]: (GPU sum, reference sum, count).
    let mut classes = [(0.0f64, 0.0f64, 0usize); 2];
    let (gw, gh) = reference.grid_size();
    for (layer, eye) in eyes.eyes.iter().enumerate() {
        for j in 0..gh {
            for i in 0..gw {
                let Some(p) = world_position(&reference, eye, layer, i, j) else { continue };
                // Floor points seen through a hole, away from the cell edges (where a
                // pixel straddles floor and plate).
                let cell = 0.25;
                let inner = |v: f64| ((v + 1.0) / cell).fract().min(1.0 - ((v + 1.0) / cell).fract()) > 0.15;
                if p.y.abs() > 1e-3 || !inner(p.x) || !inner(p.z) {
                    continue;
                }
                let Some(solid) = grille_solid_at(p.x, p.z) else { continue };
                let (x, y) = reference.pixel_of(i, j);
                // The G-buffer sees the floor there too (under a hole: through it).
                let seen = gpu_worlds[layer][(y * w + x) as usize].expect("the G-buffer sees the floor");
                assert!(
                    seen.y.abs() < 0.01,
                    "layer {layer} pixel ({x}, {y}): the G-buffer sees {seen}, the reference {p}"
                );
                let class = &mut classes[solid as usize];
                class.0 += ao[layer][4 * (y * w + x) as usize + 3] as f64;
                class.1 += reference.get(layer, i, j).ao as f64;
                class.2 += 1;
            }
        }
    }
    classes.map(|(gpu, reference, n)| {
        assert!(n > 20, "too few floor pixels in a class: {classes:?}");
        (gpu / n as f64, reference / n as f64)
    })
}

/// Depth and normals of the moving scene at `time`, rendered animated, and of the same
/// scene frozen at that time (static geometry).
#[test]
fn moving_objects_are_where_the_frozen_scene_has_them() {
    let scene = Scene::load("builtin:moving").unwrap();
    let (w, h) = (96, 108);
    let settings = settings(&scene, w, h);
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let (gpu, _one_at_a_time) = common::gpu();
    for time in [0.3, 1.7, 2.9] {
        let mut animated = Renderer::new(gpu.clone(), &scene, &settings).unwrap();
        animated.set_scene_time(time);
        animated.render_and_wait(&eyes.eyes, &[DEPTH, NORMALS]).unwrap();
        let mut frozen = Renderer::new(gpu.clone(), &scene.at_time(time), &settings).unwrap();
        frozen.render_and_wait(&eyes.eyes, &[DEPTH, NORMALS]).unwrap();
        let (a, b) = (animated.read_f32(DEPTH).unwrap(), frozen.read_f32(DEPTH).unwrap());
        let (na, nb) = (animated.read_f32(NORMALS).unwrap(), frozen.read_f32(NORMALS).unwrap());
        let mut differing = 0;
        for layer in 0..2 {
            for i in 0..(w * h) as usize {
                let normal_gap =
                    (0..3).map(|c| (na[layer][4 * i + c] - nb[layer][4 * i + c]).abs()).fold(0.0, f32::max);
                if (a[layer][i] - b[layer][i]).abs() > 1e-5 * a[layer][i].abs().max(1e-3) || normal_gap > 1e-3 {
                    differing += 1;
                }
            }
        }
        // Silhouette pixels may round either way between the two transforms.
        assert!(differing <= (2 * w * h) as usize / 200, "t = {time}: {differing} pixels differ");
    }
}

#[test]
fn motion_vectors_follow_the_ball_and_the_eyes() {
    let scene = Scene::load("builtin:moving").unwrap();
    let (w, h) = (128, 144);
    let settings = settings(&scene, w, h);
    let (gpu, _one_at_a_time) = common::gpu();
    let (t0, t1) = (0.8, 0.8 + 1.0 / 90.0);
    let head0 = scene.head.pose_at(0.0);
    // The head moves too: 2 cm sideways between the frames.
    let head1 = vrao_ao::HeadPose { position: head0.position + DVec3::new(0.02, 0.0, 0.0), ..head0 };
    let eyes0 = settings.profile.eyes(&head0, settings.near);
    let eyes1 = settings.profile.eyes(&head1, settings.near);
    let mut renderer = Renderer::new(gpu, &scene, &settings).unwrap();
    renderer.set_scene_time(t0);
    renderer.render_and_wait(&eyes0.eyes, &[MOTION]).unwrap();
    renderer.set_scene_time(t1);
    renderer.render_and_wait(&eyes1.eyes, &[MOTION, DEPTH]).unwrap();
    let motion = renderer.read_f32(MOTION).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    let worlds = common::world_positions(&depth, &eyes1.eyes, w, h, settings.near);
    let ball_now = scene.node_transforms(t1)[0];
    let ball_before = scene.node_transforms(t0)[0];
    let (mut ball_pixels, mut still_pixels, mut worst_px) = (0, 0, 0.0f64);
    for layer in 0..2 {
        for i in 0..(w * h) as usize {
            let Some(p1) = worlds[layer][i] else { continue };
            let centre = ball_now.transform_point3(DVec3::ZERO);
            let on_ball = (p1.distance(centre) - BALL_RADIUS).abs() < 0.01;
            let on_static = p1.y.abs() < 1e-3 && p1.distance(centre) > 2.0 * BALL_RADIUS;
            let p0 = if on_ball {
                ball_before.transform_point3(ball_now.inverse().transform_point3(p1))
            } else if on_static {
                p1
            } else {
                continue;
            };
            let Some((uv0, _)) = eyes0.eyes[layer].project(p0, settings.near) else { continue };
            let uv1 = [((i as u32 % w) as f64 + 0.5) / w as f64, ((i as u32 / w) as f64 + 0.5) / h as f64];
            let m = &motion[layer][4 * i..4 * i + 4];
            assert_eq!(m[3], 1.0, "pixel {i} of layer {layer}: motion marked invalid");
            let gap_px =
                ((m[0] as f64 - (uv0[0] - uv1[0])) * w as f64).hypot((m[1] as f64 - (uv0[1] - uv1[1])) * h as f64);
            worst_px = worst_px.max(gap_px);
            if on_ball {
                ball_pixels += 1;
            } else {
                still_pixels += 1;
            }
        }
    }
    println!("{ball_pixels} ball and {still_pixels} floor pixels; worst motion error {worst_px:.3} px");
    assert!(ball_pixels > 50 && still_pixels > 500, "{ball_pixels} ball, {still_pixels} floor pixels");
    assert!(worst_px < 0.2, "worst motion error {worst_px} px");
}

#[test]
fn a_still_opaque_scene_adds_no_motion_or_alpha_work() {
    let (gpu, _one_at_a_time) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let mut settings = settings(&scene, 64, 72);
    settings.ao.temporal.enabled = true;
    let renderer = Renderer::new(gpu.clone(), &scene, &settings).unwrap();
    let plan = renderer.plan(2, &[FINAL_AO]).unwrap();
    let gbuffer = &plan.decls.iter().find(|d| d.name == "gbuffer").unwrap();
    assert!(!gbuffer.writes.contains(&MOTION), "a still scene writes no motion");
    let note = gbuffer.note.clone().unwrap_or_default();
    assert!(note.contains("motion vectors left out") && note.contains("alpha test left out"), "{note}");
    // The moving scene writes it and the temporal pass reads it.
    let moving = Scene::load("builtin:moving").unwrap();
    let renderer = Renderer::new(gpu, &moving, &settings).unwrap();
    let plan = renderer.plan(2, &[FINAL_AO]).unwrap();
    let gbuffer = plan.decls.iter().find(|d| d.name == "gbuffer").unwrap();
    assert!(gbuffer.writes.contains(&MOTION));
    let temporal = plan.decls.iter().find(|d| d.name == "temporal").unwrap();
    assert!(!temporal.unbound.contains(&vrao_ao::plug::PIXEL_MOTION));
    assert_eq!(plan.resolve(vrao_ao::plug::PIXEL_MOTION), Some(MOTION));
}
