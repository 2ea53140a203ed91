//! glTF as authored (issue 50): a glowing mesh keeps the default sun and its shadows, each
//! texture reads the texture coordinate set it names (G-buffer and reference tracer),
//! a model of a few millimetres is framed whole beyond the near plane, and single-sided
//! materials are culled from behind (mirrored nodes included) while double-sided ones
//! are not. Each file is written with the repository's glTF writer and loaded back.

use crate::common;

use glam::{DMat4, DVec3, Vec2, Vec3};
use vrao::measure::reference::{trace, world_position, ReferenceSettings};
use vrao::test_assets::gltf_write::{write, WriteOptions};
use vrao_ao::plug::DEPTH;
use vrao_ao::HeadPose;
use vrao_render::passes::gbuffer::ALBEDO;
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::{
    Filter, HeadPath, Interpolation, Light, Material, Mesh, Node, NodeTracks, Sampling, Texture, Track, Trs,
};
use vrao_render::{HeadsetProfile, Renderer, Scene, Settings};

const SIZE: (u32, u32) = (64, 72);

/// `scene` written as `NAME.glb` and loaded again (framed and lit by the loader).
fn round_trip(scene: &Scene, name: &str) -> Scene {
    let dir = common::temp_dir(&format!("as-authored-{name}"));
    let path = dir.join(format!("{name}.glb"));
    write(scene, &path, &WriteOptions::default()).unwrap();
    let loaded = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{name}: {e}"));
    std::fs::remove_dir_all(&dir).ok();
    loaded
}

fn settings() -> Settings {
    settings_at(SIZE)
}

fn settings_at(size: (u32, u32)) -> Settings {
    Settings { profile: HeadsetProfile::with_size("test", size.0, size.1), ..Settings::default() }
}

/// Both eyes' `resource` (one `Vec` per eye) of `scene` seen from `head`.
fn render(scene: &Scene, head: &HeadPose, resource: vrao_ao::plug::Resource) -> (vrao_ao::EyePair, Vec<Vec<f32>>) {
    render_at(scene, head, resource, SIZE)
}

fn render_at(
    scene: &Scene,
    head: &HeadPose,
    resource: vrao_ao::plug::Resource,
    size: (u32, u32),
) -> (vrao_ao::EyePair, Vec<Vec<f32>>) {
    let (gpu, _guard) = common::gpu();
    let settings = settings_at(size);
    let eyes = settings.profile.eyes(head, settings.near);
    let mut renderer = Renderer::new(gpu.clone(), scene, &settings).unwrap();
    renderer.render_and_wait(&eyes.eyes, &[resource]).unwrap();
    (eyes, renderer.read_f32(resource).unwrap())
}

/// How many pixels of each eye's depth show a surface (reversed-Z: 0 is the sky).
fn covered(depth: &[Vec<f32>]) -> Vec<usize> {
    depth.iter().map(|layer| layer.iter().filter(|&&d| d > 0.0).count()).collect()
}

fn scene_of(meshes: Vec<Mesh>, materials: Vec<Material>) -> Scene {
    let mut scene = common::bare_scene(meshes);
    scene.materials = materials;
    scene
}

/// `w` × `h` texels, all `fill` but texel 0, which is `first` (sRGB bytes), sampled nearest.
fn texels(w: u32, h: u32, first: [u8; 4], fill: [u8; 4]) -> Texture {
    let mut rgba8 = fill.repeat((w * h) as usize);
    rgba8[..4].copy_from_slice(&first);
    let sampling = Sampling { magnify: Filter::Nearest, minify: Filter::Nearest, mipmaps: None, ..Sampling::default() };
    Texture { width: w, height: h, rgba8: rgba8.into(), source: None, sampling }
}

#[test]
fn a_glowing_mesh_keeps_the_sun_its_shadow_pass_and_glows_by_its_texture() {
    // A box on a floor; the box's emissive map is black but for one texel in 100.
    let floor = common::cuboid("floor", DVec3::new(0.0, -0.05, 0.0), Vec3::new(4.0, 0.1, 4.0), 0);
    let lamp = common::cuboid("lamp", DVec3::new(0.0, 0.5, 0.0), Vec3::splat(1.0), 1);
    let glowing = |map: Texture| {
        let mut m = Material::plain("glow", Vec3::splat(0.5));
        m.emissive = Vec3::new(2.0, 1.0, 0.5);
        m.emissive_texture = Some(map);
        m
    };
    let light_of = |map: Texture, name: &str| {
        let source =
            scene_of(vec![floor.clone(), lamp.clone()], vec![Material::plain("floor", Vec3::ONE), glowing(map)]);
        round_trip(&source, name).lights
    };
    let white = [255, 255, 255, 255];
    let dim = light_of(texels(10, 10, white, [0, 0, 0, 255]), "dim");
    let full = light_of(texels(1, 1, white, white), "full");
    let dark = light_of(texels(2, 2, [0, 0, 0, 255], [0, 0, 0, 255]), "dark");
    // The sun stays first in each; the emitter adds a point light weighted by its map's mean.
    for lights in [&dim, &full, &dark] {
        assert_eq!(lights[0], Light::default_sun(), "{lights:?}");
    }
    assert_eq!(dark.len(), 1, "an all-black map adds no light: {dark:?}");
    let intensity = |lights: &[Light]| match lights {
        [_, Light::Point { intensity, .. }] => *intensity,
        other => panic!("expected the sun and one point light: {other:?}"),
    };
    let ratio = intensity(&dim) / intensity(&full);
    assert!((ratio - 0.01).abs() < 1e-4, "one white texel in 100 gives 1 % of the light: {ratio}");

    // The file's frame has the sun's shadow pass.
    let mut source = scene_of(
        vec![floor, lamp],
        vec![Material::plain("floor", Vec3::ONE), glowing(texels(10, 10, white, [0, 0, 0, 255]))],
    );
    source.lights.clear();
    let scene = round_trip(&source, "plan");
    let (gpu, _guard) = common::gpu();
    let plan = Renderer::new(gpu.clone(), &scene, &settings()).unwrap().plan(2, &[COLOR]).unwrap();
    assert!(plan.runs("shadow"), "{plan}");
}

/// A 4 m quad in z = 0 centred on (2, 2, 0), facing +z, whose set-0 coordinates all read
/// one point (0.1, 0.1) and whose set-1 coordinates run u = x / 4, v = 1 − y / 4.
fn two_set_quad(material: usize) -> Mesh {
    let mut mesh = common::square("quad", DVec3::new(2.0, 2.0, 0.0), 4.0, material);
    mesh.uvs = vec![Vec2::splat(0.1); 4];
    mesh.uvs1 = mesh.positions.iter().map(|p| Vec2::new((p.x + 2.0) / 4.0, (2.0 - p.y) / 4.0)).collect();
    mesh
}

/// 2×1 texels, `left` and `right`, read through texture coordinate set 1.
fn halves_on_set_1(left: [u8; 4], right: [u8; 4]) -> Texture {
    let mut t = texels(2, 1, left, right);
    t.sampling.tex_coord = 1;
    t
}

#[test]
fn an_occlusion_and_a_base_colour_texture_on_texcoord_1_read_set_1_in_the_gbuffer() {
    let mut material = Material::plain("two sets", Vec3::ONE);
    // Occlusion red 51 (0.2) on the left, 255 on the right, strength 1; base colour red | blue.
    material.occlusion_texture = Some((halves_on_set_1([51, 0, 0, 255], [255, 0, 0, 255]), 1.0));
    material.diffuse_texture = Some(halves_on_set_1([255, 0, 0, 255], [0, 0, 255, 255]));
    let scene = round_trip(&scene_of(vec![two_set_quad(0)], vec![material]), "texcoord1");
    let loaded = &scene.materials[0];
    assert_eq!(loaded.occlusion_texture.as_ref().map(|(t, _)| t.sampling.tex_coord), Some(1));
    assert_eq!(loaded.diffuse_texture.as_ref().map(|t| t.sampling.tex_coord), Some(1));
    assert_eq!(scene.meshes[0].uvs1.len(), 4, "TEXCOORD_1 is read");

    let head = HeadPose::look_at(DVec3::new(2.0, 2.0, 2.2), DVec3::new(2.0, 2.0, 0.0)).unwrap();
    let (eyes, albedo) = render(&scene, &head, ALBEDO);
    let at = |p: DVec3| {
        let (uv, _) = eyes.eyes[0].project(p, eyes.near).unwrap();
        let (x, y) = ((uv[0] * SIZE.0 as f64) as usize, (uv[1] * SIZE.1 as f64) as usize);
        let i = 4 * (y * SIZE.0 as usize + x);
        [albedo[0][i], albedo[0][i + 1], albedo[0][i + 2], albedo[0][i + 3]]
    };
    // Set 0 would read the left texel everywhere; set 1 reads the right one at x > 2.
    for y in [0.5, 2.0, 3.5] {
        let left = at(DVec3::new(0.7, y, 0.0));
        let right = at(DVec3::new(3.3, y, 0.0));
        assert!((left[3] - 0.2).abs() < 2.0 / 255.0 && left[0] > 0.9 && left[2] < 0.05, "left at y {y}: {left:?}");
        assert!((right[3] - 1.0).abs() < 2.0 / 255.0 && right[2] > 0.9 && right[0] < 0.05, "right at y {y}: {right:?}");
    }
}

#[test]
fn a_base_colour_texture_on_texcoord_1_tints_the_reference_bounce_by_set_1() {
    // A white floor before a wall whose base colour, read through set 1, is red; set 0
    // would read green. The floor's one-bounce light from the wall is then red.
    let wall_mesh = {
        let mut m = common::square("wall", DVec3::new(0.0, 1.0, -1.0), 2.0, 1);
        m.uvs = vec![Vec2::splat(0.75); 4];
        m.uvs1 = vec![Vec2::splat(0.25); 4];
        m
    };
    let floor = common::cuboid("floor", DVec3::new(0.0, -0.05, 0.0), Vec3::new(6.0, 0.1, 6.0), 0);
    let mut wall = Material::plain("wall", Vec3::ONE);
    let mut map = texels(2, 1, [255, 0, 0, 255], [0, 255, 0, 255]);
    map.sampling.tex_coord = 1;
    wall.diffuse_texture = Some(map);
    let mut scene =
        round_trip(&scene_of(vec![floor, wall_mesh], vec![Material::plain("floor", Vec3::ONE), wall]), "bounce");
    let head = HeadPose::look_at(DVec3::new(0.0, 1.2, 1.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
    scene.head = HeadPath::fixed(head);
    scene.lights = vec![Light::Directional { direction: Vec3::new(0.0, -0.6, -0.8), color: Vec3::ONE, intensity: 2.0 }];
    let eyes = HeadsetProfile::with_size("test", 40, 45).eyes(&head, settings().near).eyes;
    let reference = ReferenceSettings { radius: 0.5, rays_per_pixel: 64, stride: 1, near: settings().near };
    let image = trace(&scene, &eyes, (40, 45), &reference, &mut |_| {}).unwrap();
    let mut tinted = 0;
    for (layer, eye) in eyes.iter().enumerate() {
        for j in 0..45 {
            for i in 0..40 {
                let Some(p) = world_position(&image, eye, layer, i, j) else { continue };
                let px = image.get(layer, i, j);
                if p.y.abs() > 1e-3 || p.x.abs() > 0.4 || p.z < -0.99 || px.ao == 1.0 {
                    continue;
                }
                let [r, g, _] = px.bounce;
                assert!(r > 0.0 && g == 0.0, "bounce {:?} at {p}: set 0 read", px.bounce);
                tinted += 1;
            }
        }
    }
    assert!(tinted > 20, "{tinted}");
}

#[test]
fn a_seven_millimetre_model_is_framed_whole_beyond_the_near_plane_with_a_radius_to_suit() {
    // A 7 mm box with a 2 mm bump on top, somewhere off the origin.
    let centre = DVec3::new(0.3, 1.1, -0.2);
    let model = vec![
        common::cuboid("bead", centre, Vec3::splat(0.007), 0),
        common::cuboid("bump", centre + DVec3::new(0.0, 0.0045, 0.0), Vec3::splat(0.002), 0),
    ];
    let scene = round_trip(&scene_of(model, vec![Material::plain("grey", Vec3::splat(0.5))]), "bead");
    let head = scene.head.pose_at(0.0);
    let settings = settings();
    let eyes = settings.profile.eyes(&head, settings.near);
    // Every vertex lies in both eyes' views, beyond the near plane.
    for eye in &eyes.eyes {
        for mesh in &scene.meshes {
            for p in &mesh.positions {
                let world = mesh.origin + p.as_dvec3();
                let depth = -eye.view_from_world().transform_point3(world).z;
                assert!(depth > settings.near * 1.2, "{world} is {depth} m from the eye");
                let (uv, _) = eye.project(world, settings.near).unwrap();
                assert!(uv.iter().all(|c| (0.02..0.98).contains(c)), "{world} at {uv:?}");
            }
        }
    }
    // About 5° across at 256 pixels over ~100°: some 150 pixels in each eye.
    let (_, depth) = render_at(&scene, &head, DEPTH, (256, 288));
    for (eye, count) in covered(&depth).into_iter().enumerate() {
        assert!(count > 60, "eye {eye} sees the model on {count} pixels");
    }
    let radius = scene.suggested_ao_radius();
    assert!(radius > 0.0 && radius < 0.003, "radius {radius} m for a 7 mm model");
    // A 6 cm model keeps its framing, in front of the near plane too.
    let avocado = round_trip(
        &scene_of(
            vec![common::cuboid("avocado", centre, Vec3::new(0.04, 0.06, 0.04), 0)],
            vec![Material::plain("green", Vec3::Y)],
        ),
        "avocado",
    );
    let eye = settings.profile.eyes(&avocado.head.pose_at(0.0), settings.near).eyes[0];
    for p in &avocado.meshes[0].positions {
        let depth = -eye.view_from_world().transform_point3(avocado.meshes[0].origin + p.as_dvec3()).z;
        assert!(depth > settings.near, "the avocado is cut open at {p}: {depth} m");
    }
}

/// A 1 m quad at the origin facing +z, of material `double_sided` or not; with `mirror`,
/// under a node scaled by −1 in x, which turns its winding clockwise on screen but leaves
/// its front facing +z (as engines read glTF's mirrored nodes).
fn quad_scene(double_sided: bool, mirror: bool) -> Scene {
    let mut material = Material::plain("quad", Vec3::splat(0.5));
    material.double_sided = double_sided;
    let mut quad = common::square("quad", DVec3::ZERO, 1.0, 0);
    let mut scene = scene_of(vec![], vec![material]);
    if mirror {
        quad.node = Some(0);
        let still = Track { interpolation: Interpolation::Linear, times: vec![0.0, 1.0], values: vec![DVec3::ZERO; 2] };
        scene.nodes = vec![Node {
            name: "mirror".into(),
            parent: None,
            base: DMat4::IDENTITY,
            rest: Trs { scale: DVec3::new(-1.0, 1.0, 1.0), ..Trs::IDENTITY },
            tracks: NodeTracks { translation: Some(still), ..NodeTracks::default() },
        }];
    }
    scene.meshes = vec![quad];
    scene
}

#[test]
fn single_sided_quads_are_culled_from_behind_in_the_gbuffer_and_the_tracer_mirrored_or_not() {
    let front = HeadPose::look_at(DVec3::new(0.0, 0.0, 1.5), DVec3::ZERO).unwrap();
    let behind = HeadPose::look_at(DVec3::new(0.0, 0.0, -1.5), DVec3::ZERO).unwrap();
    let cases = [
        ("double-sided", quad_scene(true, false), true),
        ("single-sided", quad_scene(false, false), false),
        ("mirrored single-sided", quad_scene(false, true), false),
    ];
    for (label, source, seen_from_behind) in cases {
        let scene = round_trip(&source, &label.replace(' ', "-"));
        assert_eq!(scene.materials[0].double_sided, source.materials[0].double_sided, "{label}");
        assert_eq!(scene.nodes.is_empty(), source.nodes.is_empty(), "{label}: the node is kept");
        for (side, head, seen) in [("front", &front, true), ("behind", &behind, seen_from_behind)] {
            let (_, depth) = render(&scene, head, DEPTH);
            let count = covered(&depth);
            let what = format!("{label} from {side}: {count:?} pixels");
            assert!(count.iter().all(|&c| if seen { c > 100 } else { c == 0 }), "{what}");
            let eyes = settings().profile.eyes(head, settings().near).eyes;
            let reference = ReferenceSettings { radius: 0.2, rays_per_pixel: 1, stride: 4, near: settings().near };
            let image = trace(&scene.at_time(0.0), &eyes, SIZE, &reference, &mut |_| {}).unwrap();
            let (w, h) = image.grid_size();
            let hits =
                (0..w).flat_map(|i| (0..h).map(move |j| (i, j))).filter(|&(i, j)| image.get(0, i, j).hit).count();
            assert_eq!(hits > 0, seen, "{what}; the tracer hits {hits}");
        }
    }
}
