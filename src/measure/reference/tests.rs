//! Expectations from analysis: an open plane, the 90° crease, a sphere over a plane, a
//! constant sky, a lit red wall; plus determinism and the cache.

use super::geometry::SceneGeometry;
use super::shading::{Estimator, Lighting, Rng};
use super::*;
use crate::measure::analytic::{crease_visibility, crease_visibility_falloff};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;
use vrao_ao::HeadPose;
use vrao_render::scene::builtin::{CREASE_HALF_WIDTH, CREASE_WALL_Z};
use vrao_render::scene::{Environment, HeadPath, Light, Material, Mesh, Texture};
use vrao_render::HeadsetProfile;

fn eyes_for(scene: &Scene, size: (u32, u32)) -> Vec<Eye> {
    HeadsetProfile::with_size("test", size.0, size.1).eyes(&scene.head.pose_at(0.0), DEFAULT_NEAR).eyes.to_vec()
}

fn settings(radius: f64, rays_per_pixel: u32) -> ReferenceSettings {
    ReferenceSettings { radius, rays_per_pixel, stride: 1, near: DEFAULT_NEAR }
}

fn run(scene: &Scene, size: (u32, u32), s: &ReferenceSettings) -> (Vec<Eye>, ReferenceImage) {
    let eyes = eyes_for(scene, size);
    let image = trace(scene, &eyes, size, s, &mut |_| {}).unwrap();
    (eyes, image)
}

/// Every hit cell of every layer with the world point it sees.
fn hit_cells<'a>(eyes: &'a [Eye], image: &'a ReferenceImage) -> impl Iterator<Item = (DVec3, ReferencePixel)> + 'a {
    let (gw, gh) = image.grid_size();
    (0..eyes.len()).flat_map(move |layer| {
        (0..gh).flat_map(move |j| {
            (0..gw).filter_map(move |i| {
                world_position(image, &eyes[layer], layer, i, j).map(|p| (p, *image.get(layer, i, j)))
            })
        })
    })
}

fn bits(image: &ReferenceImage) -> Vec<u32> {
    image
        .layers
        .iter()
        .flatten()
        .flat_map(|p| {
            let scalars = [p.hit as u32 as f32, p.depth, p.ao, p.ao_falloff, p.ao_std_error];
            let all: Vec<f32> =
                scalars.iter().chain(&p.environment_visible).chain(&p.bounce).chain(&p.unoccluded).copied().collect();
            all.into_iter().map(f32::to_bits)
        })
        .collect()
}

#[test]
fn open_plane_is_unoccluded_everywhere() {
    let scene = Scene::load("builtin:plane").unwrap();
    let size = (48, 54);
    let (eyes, image) = run(&scene, size, &settings(5.0, 64));
    assert_eq!(image.layers.len(), 2);
    assert_eq!(image.layers[0].len(), 48 * 54);
    let mut hits = 0;
    for (p, px) in hit_cells(&eyes, &image) {
        assert!(p.y.abs() < 1e-4, "the plane is at y = 0: {p}");
        assert_eq!((px.ao, px.ao_falloff, px.ao_std_error), (1.0, 1.0, 0.0), "at {p}");
        assert_eq!(px.bounce, [0.0; 3]);
        hits += 1;
    }
    let sky = image.layers.iter().flatten().filter(|p| !p.hit).count();
    assert!(hits > 2000 && sky > 100, "{hits} hit, {sky} sky");
    assert_eq!(image.stats.hit_pixels, hits as u64);
    assert_eq!(image.stats.noise, 0.0);
    // One primary ray per pixel and 64 per hit pixel.
    assert_eq!(image.stats.rays, 2 * 48 * 54 + 64 * hits as u64);
    assert!(image.layers.iter().flatten().filter(|p| !p.hit).all(|p| *p == ReferencePixel::SKY));
}

#[test]
fn crease_matches_the_closed_forms_within_the_stated_noise() {
    let scene = Scene::load("builtin:crease").unwrap();
    let r = 1.0;
    let (eyes, image) = run(&scene, (64, 72), &settings(r, 256));
    assert!(image.stats.noise > 0.0 && image.stats.noise < 0.05, "noise {}", image.stats.noise);
    let (mut floor, mut wall, mut bias, mut variance) = (0, 0, 0.0, 0.0);
    for (p, px) in hit_cells(&eyes, &image) {
        if p.x.abs() > CREASE_HALF_WIDTH - r {
            continue; // near the wall's side edges the wall is not infinite
        }
        // A floor point x from the wall, or a wall point x above the floor: the same crease.
        let x = if p.y.abs() < 1e-4 {
            floor += 1;
            p.z - CREASE_WALL_Z
        } else if (p.z - CREASE_WALL_Z).abs() < 1e-4 {
            wall += 1;
            p.y
        } else {
            panic!("a point on neither plane: {p}")
        };
        if x < 0.01 {
            continue; // the crease line itself, where a pixel straddles both planes
        }
        let (v, f) = (crease_visibility(x, r), crease_visibility_falloff(x, r));
        // A pixel's own estimate of its error is 0 when none of its rays happens to hit a
        // sliver of wall; the binomial error of the exact value covers that case.
        let binomial = (v * (1.0 - v) / 256.0).sqrt();
        let tolerance = 4.0 * (px.ao_std_error as f64).max(binomial) + 0.003;
        assert!((px.ao as f64 - v).abs() <= tolerance, "x = {x}: ao {} vs {v} (± {tolerance})", px.ao);
        assert!((px.ao_falloff as f64 - f).abs() <= tolerance, "x = {x}: falloff {} vs {f}", px.ao_falloff);
        if x >= r {
            assert_eq!((px.ao, px.ao_falloff), (1.0, 1.0), "x = {x} is out of reach");
        }
        bias += px.ao as f64 - v;
        variance += (px.ao_std_error as f64).powi(2);
    }
    assert!(floor > 1000 && wall > 500, "{floor} floor and {wall} wall pixels");
    // No systematic error: the mean error is within 4 standard errors of the mean.
    let n = (floor + wall) as f64;
    let mean_tolerance = 4.0 * variance.sqrt() / n + 2e-4;
    assert!((bias / n).abs() < mean_tolerance, "mean error {} (± {mean_tolerance})", bias / n);
}

/// A UV sphere (rings × segments) for the sphere test, counter-clockwise from outside.
fn sphere_mesh(centre: DVec3, radius: f64, rings: u32, segments: u32) -> Mesh {
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..=rings {
        let theta = PI * i as f64 / rings as f64;
        for j in 0..=segments {
            let phi = 2.0 * PI * j as f64 / segments as f64;
            let n = DVec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
            positions.push((n * radius).as_vec3());
            normals.push(n.as_vec3());
        }
    }
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let a = i * row + j;
            indices.extend([a, a + row, a + row + 1, a, a + row + 1, a + 1]);
        }
    }
    let uvs = vec![Vec2::ZERO; positions.len()];
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: "ball".into(),
        origin: centre,
        positions,
        normals,
        uvs,
        uvs1: Vec::new(),
        indices,
        material: 0,
        node: None,
    }
}

fn floor_mesh(half: f32) -> Mesh {
    let positions = vec![
        Vec3::new(-half, 0.0, -half),
        Vec3::new(-half, 0.0, half),
        Vec3::new(half, 0.0, half),
        Vec3::new(half, 0.0, -half),
    ];
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: "floor".into(),
        origin: DVec3::ZERO,
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO; 4],
        uvs1: Vec::new(),
        positions,
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
        node: None,
    }
}

fn custom_scene(meshes: Vec<Mesh>, materials: Vec<Material>, lights: Vec<Light>, env: Option<Environment>) -> Scene {
    Scene {
        name: "test".into(),
        meshes,
        materials,
        lights,
        environment: env,
        head: HeadPath::fixed(HeadPose::look_at(DVec3::new(0.0, 1.0, 3.0), DVec3::ZERO).unwrap()),
        nodes: Vec::new(),
    }
}

#[test]
fn point_below_a_sphere_sees_the_cap_closed_form() {
    // A sphere of radius R centred at height h over the floor covers a cone of half-angle
    // α, sin α = R / h, about the normal of the point below it: cosine-weighted, sin²α.
    let (radius, h, r) = (0.5, 1.5, 2.0);
    let scene = custom_scene(
        vec![floor_mesh(20.0), sphere_mesh(DVec3::new(0.0, h, 0.0), radius, 96, 192)],
        vec![Material::plain("white", Vec3::splat(0.8))],
        vec![],
        None,
    );
    let geometry = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    let lighting = Lighting::new(&scene, DVec3::ZERO);
    let m = 16_384;
    let estimator = Estimator { geometry: &geometry, lighting: &lighting, radius: r, rays_per_pixel: m };
    // Look at the floor point (0, 0, 0) from low in front, under the sphere.
    let eye = Vec3::new(0.0, 0.3, 3.0);
    let dir = (Vec3::ZERO - eye).normalize();
    let hit = geometry.closest(eye, dir, 0.0, 10.0, u32::MAX).unwrap();
    let surface = geometry.surface(&hit);
    assert!(surface.position.length() < 1e-5);
    let e = estimator.estimate(&surface, dir, &mut Rng::new(1), &mut Vec::new());
    let expected = 1.0 - (radius / h).powi(2);
    assert!(r >= (h * h - radius * radius).sqrt(), "every hit is within r");
    let tolerance = 4.0 * e.ao_std_error + 1e-3;
    assert!((e.ao - expected).abs() < tolerance, "ao {} vs {expected} (± {tolerance})", e.ao);
    // Falloff: the near side of the sphere is d(θ) = h cos θ − √(R² − h² sin² θ) away;
    // O = 2 ∫₀^α (1 − d/r) cos θ sin θ dθ, by the midpoint rule.
    let alpha = (radius / h).asin();
    let n = 100_000;
    let occlusion: f64 = (0..n)
        .map(|k| {
            let theta = alpha * (k as f64 + 0.5) / n as f64;
            let d = h * theta.cos() - (radius * radius - (h * theta.sin()).powi(2)).max(0.0).sqrt();
            2.0 * (1.0 - d / r) * theta.cos() * theta.sin() * alpha / n as f64
        })
        .sum();
    assert!((e.ao_falloff - (1.0 - occlusion)).abs() < tolerance, "falloff {} vs {}", e.ao_falloff, 1.0 - occlusion);
    assert_eq!(e.bounce, [0.0; 3], "no lights, nothing to bounce");
    assert_eq!(e.environment_visible, [0.0; 3], "no environment");
}

fn constant_sky(radiance: [f32; 3]) -> Environment {
    Environment::from_texels(16, 8, vec![radiance; 16 * 8], 1.0).unwrap()
}

#[test]
fn constant_environment_gives_pi_l_on_an_open_plane_and_pi_l_ao_in_the_crease() {
    let l = [0.5f32, 1.0, 2.0];
    let mut plane = Scene::load("builtin:plane").unwrap();
    plane.environment = Some(constant_sky(l));
    let (eyes, image) = run(&plane, (24, 27), &settings(2.0, 16));
    for (_, px) in hit_cells(&eyes, &image) {
        for ((visible, unoccluded), radiance) in px.environment_visible.iter().zip(px.unoccluded).zip(l) {
            let exact = PI as f32 * radiance;
            assert!((visible - exact).abs() < 1e-5 * exact, "{:?}", px.environment_visible);
            assert!((unoccluded - exact).abs() < 0.02 * exact, "SH irradiance {:?}", px.unoccluded);
        }
    }
    // In the crease, each unblocked direction sees L: environment_visible = π L · ao.
    let mut crease = Scene::load("builtin:crease").unwrap();
    crease.environment = Some(constant_sky(l));
    let (eyes, image) = run(&crease, (24, 27), &settings(1.0, 16));
    let mut darker = 0;
    for (_, px) in hit_cells(&eyes, &image) {
        let exact = PI as f32 * l[2] * px.ao;
        assert!((px.environment_visible[2] - exact).abs() < 1e-5 * (1.0 + exact), "{px:?}");
        darker += (px.ao < 1.0) as usize;
    }
    assert!(darker > 50);
    // Without an environment there is no ambient light at all.
    crease.environment = None;
    let (_, image) = run(&crease, (8, 9), &settings(1.0, 4));
    assert!(image.layers.iter().flatten().all(|p| p.environment_visible == [0.0; 3] && p.unoccluded == [0.0; 3]));
}

/// The crease with a red wall lit by a directional light.
fn red_wall_crease() -> (Scene, [f32; 3]) {
    let mut scene = Scene::load("builtin:crease").unwrap();
    let red = Vec3::new(0.8, 0.1, 0.05);
    scene.materials.push(Material::plain("red", red));
    let wall = scene.meshes.iter_mut().find(|m| m.name == "wall").unwrap();
    wall.material = 1;
    let direction = Vec3::new(0.0, -0.6, -0.8);
    scene.lights = vec![Light::Directional { direction, color: Vec3::ONE, intensity: 2.0 }];
    // The wall faces +Z: irradiance 2 · 0.8, radiance albedo / π · 1.6.
    let wall_radiance = (red / std::f32::consts::PI * 1.6).to_array();
    (scene, wall_radiance)
}

#[test]
fn red_wall_bleeds_red_onto_the_floor_within_reach_only() {
    let (scene, wall_radiance) = red_wall_crease();
    let r = 1.0;
    let (eyes, image) = run(&scene, (40, 45), &settings(r, 64));
    let mut bled = 0;
    for (p, px) in hit_cells(&eyes, &image) {
        // (Skipping the crease line, where f32 rounding may put a point a hair behind the wall.)
        if p.y.abs() > 1e-4 || p.x.abs() > CREASE_HALF_WIDTH - r || p.z - CREASE_WALL_Z < 1e-3 {
            continue;
        }
        // Every occluded direction from the floor meets the evenly lit wall's front:
        // bounce = π L_wall (1 − ao) exactly for the same samples.
        for (bounce, radiance) in px.bounce.iter().zip(wall_radiance) {
            let exact = PI as f32 * radiance * (1.0 - px.ao);
            assert!((bounce - exact).abs() <= 1e-5 * (1.0 + exact), "{:?} vs {exact} at {p}", px.bounce);
        }
        if px.ao < 1.0 {
            assert!(px.bounce[0] > px.bounce[1] && px.bounce[1] > 0.0, "{:?}", px.bounce);
            bled += 1;
        }
    }
    assert!(bled > 100);
    // With r shorter than the distance to the wall nothing reaches it.
    let short = 0.2;
    let (eyes, image) = run(&scene, (40, 45), &settings(short, 64));
    let mut checked = 0;
    for (p, px) in hit_cells(&eyes, &image) {
        if p.y.abs() < 1e-4 && p.z - CREASE_WALL_Z > short + 1e-3 {
            assert_eq!(px.bounce, [0.0; 3], "at {p}");
            checked += 1;
        }
    }
    assert!(checked > 500);
}

#[test]
fn a_sender_in_a_directional_lights_shadow_gets_none_of_it() {
    // The unit box on the floor under a sun travelling +X and down at 45°: a floor point
    // 0.2 m beside its +X face has the box between it and the sun, one 2 m away does not.
    let mut scene = Scene::load("builtin:box").unwrap();
    let direction = Vec3::new(1.0, -1.0, 0.0).normalize();
    scene.lights = vec![
        Light::Directional { direction, color: Vec3::ONE, intensity: 2.0 },
        Light::Point { position: DVec3::new(0.7, 3.0, 0.0), color: Vec3::ONE, intensity: 9.0 },
    ];
    let geometry = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    let lighting = Lighting::new(&scene, DVec3::ZERO);
    let floor_at = |x: f32| {
        let hit = geometry.closest(Vec3::new(x, 5.0, 0.0), Vec3::NEG_Y, 0.0, 10.0, u32::MAX).unwrap();
        geometry.surface(&hit)
    };
    let sun = 2.0 * std::f32::consts::FRAC_1_SQRT_2;
    let point = |x: f32| 9.0 * 3.0 / ((0.7 - x) * (0.7 - x) + 9.0f32).powf(1.5);
    let shadowed = lighting.shadowed_irradiance(&geometry, &floor_at(0.7));
    assert!((shadowed - Vec3::splat(point(0.7))).abs().max_element() < 1e-4, "{shadowed}: only the point light");
    let lit = lighting.shadowed_irradiance(&geometry, &floor_at(2.7));
    assert!((lit - Vec3::splat(sun + point(2.7))).abs().max_element() < 1e-4, "{lit}");
}

#[test]
fn a_spot_light_follows_gltfs_cone_falloff() {
    // A spot 3 m above the box's floor pointing down: full on the axis, the squared ramp
    // between the cones, nothing outside.
    let mut scene = Scene::load("builtin:box").unwrap();
    let (inner, outer) = (0.1f32, 0.7f32);
    scene.lights = vec![Light::Spot {
        position: DVec3::new(2.0, 3.0, 0.0),
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 9.0,
        inner_cone: inner,
        outer_cone: outer,
    }];
    let geometry = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    let lighting = Lighting::new(&scene, DVec3::ZERO);
    let floor_at = |x: f32| {
        let hit = geometry.closest(Vec3::new(x, 5.0, 0.0), Vec3::NEG_Y, 0.0, 10.0, u32::MAX).unwrap();
        geometry.surface(&hit)
    };
    for angle in [0.0f32, 0.4, 0.9] {
        let x = 2.0 + 3.0 * angle.tan();
        let e = lighting.shadowed_irradiance(&geometry, &floor_at(x)).x;
        let d2 = 9.0 / (angle.cos() * angle.cos());
        let expected = 9.0 * vrao_render::scene::spot_falloff(angle.cos(), inner, outer) * angle.cos() / d2;
        assert!((e - expected).abs() < 1e-4, "{angle} rad: {e}, expected {expected}");
    }
    assert!(lighting.shadowed_irradiance(&geometry, &floor_at(2.0 + 3.0 * 0.4f32.tan())).x > 0.1);
}

#[test]
fn back_faces_send_no_bounce() {
    // Seen from behind the wall (z < wall), the wall's back faces the floor behind it.
    let (mut scene, _) = red_wall_crease();
    scene.meshes[0].origin.z -= 8.0 - 1e-3; // the floor now lies behind the wall
    let geometry = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    let lighting = Lighting::new(&scene, DVec3::ZERO);
    let estimator = Estimator { geometry: &geometry, lighting: &lighting, radius: 1.0, rays_per_pixel: 64 };
    let eye = Vec3::new(0.0, 1.0, CREASE_WALL_Z as f32 - 3.0);
    let target = Vec3::new(0.0, 0.0, CREASE_WALL_Z as f32 - 0.2);
    let dir = (target - eye).normalize();
    let surface = geometry.surface(&geometry.closest(eye, dir, 0.0, 10.0, u32::MAX).unwrap());
    assert!(surface.position.y.abs() < 1e-4);
    let e = estimator.estimate(&surface, dir, &mut Rng::new(3), &mut Vec::new());
    assert!(e.ao < 0.9, "the wall occludes from behind too: {}", e.ao);
    assert_eq!(e.bounce, [0.0; 3]);
}

#[test]
fn tracing_is_deterministic_and_independent_of_stride() {
    let (scene, _) = red_wall_crease();
    let size = (33, 37);
    let s = settings(1.0, 16);
    let (eyes, a) = run(&scene, size, &s);
    let b = trace(&scene, &eyes, size, &s, &mut |_| {}).unwrap();
    assert_eq!(bits(&a), bits(&b));
    // Every 4th pixel: the same values at the same pixels.
    let strided = trace(&scene, &eyes, size, &ReferenceSettings { stride: 4, ..s }, &mut |_| {}).unwrap();
    assert_eq!(strided.grid_size(), (9, 10));
    for layer in 0..2 {
        for j in 0..10 {
            for i in 0..9 {
                let (x, y) = strided.pixel_of(i, j);
                assert!(x < 33 && y < 37);
                assert_eq!(strided.get(layer, i, j), a.get(layer, x, y), "cell ({i}, {j}) = pixel ({x}, {y})");
            }
        }
    }
    assert_eq!(strided.pixel_of(8, 9), (32, 36), "clamped to the image");
}

#[test]
fn progress_reaches_the_total_on_the_calling_thread() {
    let scene = Scene::load("builtin:crease").unwrap();
    let size = (16, 18);
    let eyes = eyes_for(&scene, size);
    let caller = std::thread::current().id();
    let mut calls = Vec::new();
    let image = trace(&scene, &eyes, size, &settings(1.0, 4), &mut |p| {
        assert_eq!(std::thread::current().id(), caller);
        calls.push(p);
    })
    .unwrap();
    let last = calls.last().unwrap();
    assert_eq!((last.done, last.total), (2 * 16 * 18, 2 * 16 * 18));
    assert_eq!(last.rays, image.stats.rays);
    assert!(calls.windows(2).all(|w| w[0].done <= w[1].done));
}

#[test]
fn scene_far_from_the_origin_gives_the_same_reference() {
    let scene = Scene::load("builtin:crease").unwrap();
    let size = (24, 27);
    let s = settings(1.0, 16);
    let (eyes, near) = run(&scene, size, &s);
    let shift = DVec3::new(1e5, -3e4, 2e5);
    let mut far_scene = scene.clone();
    far_scene.meshes.iter_mut().for_each(|m| m.origin += shift);
    let far_eyes: Vec<Eye> =
        eyes.iter().map(|e| Eye { pose: HeadPose { position: e.pose.position + shift, ..e.pose }, ..*e }).collect();
    let far = trace(&far_scene, &far_eyes, size, &s, &mut |_| {}).unwrap();
    let pairs: Vec<(&ReferencePixel, &ReferencePixel)> =
        near.layers.iter().flatten().zip(far.layers.iter().flatten()).collect();
    assert!(pairs.iter().all(|(a, b)| a.hit == b.hit));
    let mean_diff = pairs.iter().map(|(a, b)| (a.ao - b.ao).abs() as f64).sum::<f64>() / pairs.len() as f64;
    assert!(mean_diff < 1e-3, "mean |Δao| = {mean_diff}");
    let depth_diff = pairs.iter().map(|(a, b)| ((a.depth - b.depth) / a.depth.max(1e-3)).abs()).fold(0f32, f32::max);
    assert!(depth_diff < 1e-5, "relative depth difference {depth_diff}");
}

fn temp_dir(name: &str) -> vrao_render::test_dir::TestDir {
    vrao_render::test_dir::TestDir::new(&format!("reference-{name}"))
}

#[test]
fn cache_round_trips_and_recovers_from_a_truncated_file() {
    let scene = Scene::load("builtin:crease").unwrap();
    let size = (20, 22);
    let eyes = eyes_for(&scene, size);
    let s = ReferenceSettings { stride: 2, ..settings(1.0, 9) };
    let dir = temp_dir("cache");
    let first = trace_cached(&dir, &scene, &eyes, size, &s, &mut |_| {}).unwrap();
    assert!(!first.stats.from_cache);
    let path = cache_file(&dir, cache_key(&scene, &eyes, size, &s));
    assert!(path.is_file());
    let second = trace_cached(&dir, &scene, &eyes, size, &s, &mut |_| {}).unwrap();
    assert!(second.stats.from_cache);
    assert_eq!(bits(&first), bits(&second));
    assert_eq!(ReferenceStats { from_cache: false, ..second.stats }, first.stats);

    // A truncated file is traced again (with a warning) and rewritten whole.
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let third = trace_cached(&dir, &scene, &eyes, size, &s, &mut |_| {}).unwrap();
    assert!(!third.stats.from_cache);
    assert_eq!(bits(&first), bits(&third));
    assert_eq!(std::fs::read(&path).unwrap().len(), bytes.len());

    // Any change to the inputs changes the key.
    let key = cache_key(&scene, &eyes, size, &s);
    assert_ne!(key, cache_key(&scene, &eyes, size, &ReferenceSettings { radius: 1.01, ..s }));
    assert_ne!(key, cache_key(&scene, &eyes[..1], size, &s));
    let mut moved = scene.clone();
    moved.meshes[1].positions[0].y += 1e-6;
    assert_ne!(key, cache_key(&moved, &eyes, size, &s));
    let mut renamed = scene.clone();
    renamed.name = "another name".into();
    assert_eq!(key, cache_key(&renamed, &eyes, size, &s), "names do not change the result");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_and_unwritable_cache_are_errors() {
    let scene = Scene::load("builtin:plane").unwrap();
    let size = (8, 9);
    let eyes = eyes_for(&scene, size);
    let mut none = |_: Progress| {};
    for bad in [
        ReferenceSettings { radius: 0.0, ..settings(1.0, 4) },
        ReferenceSettings { radius: f64::NAN, ..settings(1.0, 4) },
        ReferenceSettings { rays_per_pixel: 0, ..settings(1.0, 4) },
        ReferenceSettings { stride: 0, ..settings(1.0, 4) },
        ReferenceSettings { near: -1.0, ..settings(1.0, 4) },
    ] {
        assert!(
            matches!(trace(&scene, &eyes, size, &bad, &mut none), Err(Error::Engine(vrao_ao::Error::Input { .. }))),
            "{bad:?}"
        );
    }
    assert!(trace(&scene, &eyes, (0, 9), &settings(1.0, 4), &mut none).is_err());
    assert!(trace(&scene, &[], size, &settings(1.0, 4), &mut none).is_err());
    // A file where the cache directory should be.
    let dir = temp_dir("unwritable");
    std::fs::create_dir_all(&dir).unwrap();
    let blocker = dir.join("not-a-dir");
    std::fs::write(&blocker, b"x").unwrap();
    let err = trace_cached(&blocker, &scene, &eyes, size, &settings(1.0, 4), &mut none).unwrap_err();
    assert!(matches!(err, Error::Output { .. }), "{err}");
    assert!(err.to_string().contains("not-a-dir"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn extreme_radii_stay_finite_and_in_range() {
    let scene = Scene::load("builtin:crease").unwrap();
    for r in [1e-6, 1e6] {
        let (_, image) = run(&scene, (12, 14), &settings(r, 4));
        for p in image.layers.iter().flatten() {
            assert!((0.0..=1.0).contains(&p.ao) && (0.0..=1.0).contains(&p.ao_falloff), "r = {r}: {p:?}");
            let rgb = p.environment_visible.iter().chain(&p.bounce).chain(&p.unoccluded);
            assert!(rgb.copied().all(f32::is_finite), "r = {r}: {p:?}");
        }
    }
}

/// [`floor_mesh`] with u running from 0 at x = −half to 1 at x = half, and v likewise along z.
fn floor_with_uvs(half: f32) -> Mesh {
    let mut floor = floor_mesh(half);
    floor.uvs = floor.positions.iter().map(|p| Vec2::new(p.x / (2.0 * half) + 0.5, p.z / (2.0 * half) + 0.5)).collect();
    floor
}

/// The surface straight below (x, 1, z), if a ray from there meets one.
fn surface_below(g: &SceneGeometry, x: f32, z: f32) -> Option<super::geometry::Surface> {
    g.closest(Vec3::new(x, 1.0, z), -Vec3::Y, 0.0, 10.0, u32::MAX).map(|hit| g.surface(&hit))
}

#[test]
fn vertex_colours_interpolate_tint_the_albedo_and_cut_alpha_tested_holes() {
    use glam::Vec4;
    use vrao_render::scene::AlphaMode;
    let mut floor = floor_mesh(1.0);
    // Corners (x, z): (−1, −1) red, (−1, 1) green, (1, 1) blue, (1, −1) black.
    floor.colors =
        vec![Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 1.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0), Vec4::W];
    let grey = Material::plain("grey", Vec3::splat(0.8));
    let scene = custom_scene(vec![floor.clone()], vec![grey.clone()], vec![], None);
    let g = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    // (−0.5, 0.5) weighs red ¼, green ½, blue ¼ in its triangle (0, 1, 2).
    let s = surface_below(&g, -0.5, 0.5).unwrap();
    assert!((s.color - Vec4::new(0.25, 0.5, 0.25, 1.0)).abs().max_element() < 1e-6, "{}", s.color);
    let albedo = super::shading::albedo(&g, &s);
    assert!((albedo - Vec3::new(0.2, 0.4, 0.2)).abs().max_element() < 1e-6, "{albedo}");
    // (0.5, −0.5) in triangle (0, 2, 3): red ¼, blue ¼, black ½.
    let s = surface_below(&g, 0.5, -0.5).unwrap();
    assert!((s.color - Vec4::new(0.25, 0.0, 0.25, 1.0)).abs().max_element() < 1e-6, "{}", s.color);

    // Alpha from the vertex colours alone (0 at x = −1, 1 at x = 1) under an alpha test
    // at ½: a hole for x < 0, solid beyond, though neither factor nor texture is below it.
    floor.colors.iter_mut().zip([0.0, 0.0, 1.0, 1.0]).for_each(|(c, a)| c.w = a);
    let masked = Material { alpha_mode: AlphaMode::Mask { cutoff: 0.5 }, ..grey };
    let scene = custom_scene(vec![floor], vec![masked], vec![], None);
    let g = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    for x in [-0.9, -0.5, -0.1] {
        assert!(surface_below(&g, x, 0.3).is_none(), "a hole at x = {x}");
    }
    for x in [0.1, 0.5, 0.9] {
        assert!(surface_below(&g, x, 0.3).is_some(), "solid at x = {x}");
    }
}

/// A texture of one row of sRGB grey levels, sampled nearest.
fn grey_row(levels: &[u8]) -> Texture {
    use vrao_render::scene::{Filter, Sampling};
    Texture {
        width: levels.len() as u32,
        height: 1,
        rgba8: levels.iter().flat_map(|&l| [l, l, l, 255]).collect::<Vec<u8>>().into(),
        source: None,
        sampling: Sampling { magnify: Filter::Nearest, ..Sampling::default() },
    }
}

#[test]
fn the_emission_texture_limits_the_emissive_factor_and_vertex_colours_do_not_tint_it() {
    use glam::Vec4;
    let mut floor = floor_with_uvs(1.0);
    floor.colors = vec![Vec4::new(0.0, 1.0, 0.0, 1.0); 4];
    let mut glow = Material::plain("glow", Vec3::splat(0.5));
    glow.emissive = Vec3::new(2.0, 1.0, 0.5);
    // Dark on the left half of u, full on the right.
    glow.emissive_texture = Some(grey_row(&[0, 255]));
    let scene = custom_scene(vec![floor], vec![glow], vec![], None);
    let g = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    let lighting = Lighting::new(&scene, DVec3::ZERO);
    let out = |x: f32| super::shading::direct_out(&g, &lighting, &surface_below(&g, x, 0.2).unwrap(), -Vec3::Y);
    assert_eq!(out(-0.5), Vec3::ZERO);
    assert_eq!(out(0.5), Vec3::new(2.0, 1.0, 0.5));
    // It repeats as its sampler says: u = 1.25 is u = 0.25 again.
    let s = surface_below(&g, 0.5, 0.2).unwrap();
    let shifted = super::geometry::Surface { uvs: [Vec2::new(1.25, s.uvs[0].y); 2], ..s };
    assert_eq!(super::shading::emission(&g, &shifted), Vec3::ZERO);
}

#[test]
fn a_normal_texture_tilts_the_light_a_sender_reflects_but_not_its_occlusion() {
    use glam::Vec4;
    let mut floor = floor_with_uvs(20.0);
    // +u is +x; the bitangent's sign flips with w.
    floor.tangents = vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 4];
    let texel = |rgb: [u8; 3]| Texture { rgba8: vec![rgb[0], rgb[1], rgb[2], 255].into(), ..grey_row(&[0]) };
    let mut bumpy = Material::plain("bumpy", Vec3::splat(0.5));
    // Tilted all the way towards +u.
    bumpy.normal_texture = Some((texel([255, 128, 128]), 1.0));
    // A sun grazing the floor from +x: the flat floor gets none of it.
    let sun = Light::Directional { direction: -Vec3::X, color: Vec3::ONE, intensity: 2.0 };
    let scene = custom_scene(vec![floor.clone()], vec![bumpy.clone()], vec![sun.clone()], None);
    let g = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    let s = surface_below(&g, 0.3, 0.4).unwrap();
    assert_eq!(s.shading, Vec3::Y);
    let n = g.lighting_normal(&s);
    assert!((n - Vec3::X).length() < 0.01, "{n}");
    let e = Lighting::new(&scene, DVec3::ZERO).shadowed_irradiance(&g, &s);
    assert!((e - Vec3::splat(2.0)).abs().max_element() < 0.01, "{e}");

    // Scale 0 leaves the vertex normal; green tilts along the bitangent, (N × T)·w.
    for (rgb, scale, w, expected) in [
        ([255, 128, 128], 0.0, 1.0, Vec3::Y),
        ([128, 255, 128], 1.0, 1.0, -Vec3::Z),
        ([128, 255, 128], 1.0, -1.0, Vec3::Z),
    ] {
        let mut floor = floor.clone();
        floor.tangents.iter_mut().for_each(|t| t.w = w);
        let material = Material { normal_texture: Some((texel(rgb), scale)), ..bumpy.clone() };
        let scene = custom_scene(vec![floor], vec![material], vec![], None);
        let g = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
        let n = g.lighting_normal(&surface_below(&g, 0.3, 0.4).unwrap());
        assert!((n - expected).length() < 0.01, "{rgb:?} × {scale}, w = {w}: {n}");
    }
    // Without tangents the vertex normal lights it.
    let mut bare = floor.clone();
    bare.tangents.clear();
    let scene = custom_scene(vec![bare], vec![bumpy.clone()], vec![], None);
    let g = SceneGeometry::build(&scene, DVec3::ZERO).unwrap();
    assert_eq!(g.lighting_normal(&surface_below(&g, 0.3, 0.4).unwrap()), Vec3::Y);

    // The occlusion stays the geometry's: the open floor is unoccluded everywhere though
    // its normal texture tilts every normal by 90°.
    let scene = custom_scene(vec![floor], vec![bumpy], vec![sun], None);
    let (eyes, image) = run(&scene, (16, 18), &settings(1.0, 16));
    let mut hits = 0;
    for (p, px) in hit_cells(&eyes, &image) {
        assert_eq!((px.ao, px.ao_falloff), (1.0, 1.0), "at {p}");
        hits += 1;
    }
    assert!(hits > 100);
}
