//! glTF materials as their authors made them, end to end: each case is written with the
//! repository's glTF writer, loaded by vrao's loader (which must give back what was
//! written) and traced by the reference: a tiled alpha-masked floor under each wrap mode
//! and a texture transform (its holes where the sampler puts them), vertex colours tinting
//! what a wall reflects, an emission texture limiting what it emits, and normal and
//! occlusion textures, which leave the AO reference as it is.
#![cfg(all(feature = "app", feature = "gltf"))]

use glam::{DVec3, Vec2, Vec3, Vec4};
use vrao::measure::reference::{trace, world_position, ReferenceImage, ReferencePixel, ReferenceSettings};
use vrao::test_assets::gltf_write::{write, WriteOptions};
use vrao_ao::plug::DEFAULT_NEAR;
use vrao_ao::{Eye, HeadPose};
use vrao_render::scene::texture::uv_transform;
use vrao_render::scene::{AlphaMode, Filter, HeadPath, Light, Material, Mesh, Sampling, Texture, Wrap};
use vrao_render::{HeadsetProfile, Scene};

/// A fresh, empty directory for one test's files, removed when the test passes.
fn temp_dir(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("gltf-materials-{name}"))
}

/// `scene` written as `NAME.glb` and loaded again, viewed from `head`.
fn round_trip(scene: &Scene, name: &str, head: HeadPose) -> Scene {
    let dir = temp_dir(name);
    let path = dir.join(format!("{name}.glb"));
    write(scene, &path, &WriteOptions::default()).unwrap();
    let mut loaded = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{name}: {e}"));
    std::fs::remove_dir_all(&dir).ok();
    loaded.head = HeadPath::fixed(head);
    loaded
}

/// A `side` × `side` square in the plane y = `height`, facing +y, with uvs running from
/// 0 to `tiles` along x and z.
fn floor(name: &str, height: f32, side: f32, tiles: f32, material: usize) -> Mesh {
    let h = side / 2.0;
    let positions =
        vec![Vec3::new(-h, height, h), Vec3::new(h, height, h), Vec3::new(h, height, -h), Vec3::new(-h, height, -h)];
    let uvs = positions.iter().map(|p| Vec2::new(p.x / side + 0.5, p.z / side + 0.5) * tiles).collect();
    Mesh {
        name: name.into(),
        origin: DVec3::ZERO,
        positions,
        normals: vec![Vec3::Y; 4],
        uvs,
        uvs1: Vec::new(),
        colors: Vec::new(),
        tangents: Vec::new(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        node: None,
    }
}

/// A 2 m wide, 2 m tall wall in the plane z = `z` from x = −1 to 1 and y = 0 to 2, facing
/// +z, with u running from 0 to 1 along x.
fn wall(z: f32, material: usize) -> Mesh {
    let positions =
        vec![Vec3::new(-1.0, 0.0, z), Vec3::new(1.0, 0.0, z), Vec3::new(1.0, 2.0, z), Vec3::new(-1.0, 2.0, z)];
    Mesh {
        name: "wall".into(),
        origin: DVec3::ZERO,
        positions,
        normals: vec![Vec3::Z; 4],
        uvs: vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ZERO],
        uvs1: Vec::new(),
        colors: Vec::new(),
        tangents: Vec::new(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        node: None,
    }
}

fn scene(meshes: Vec<Mesh>, materials: Vec<Material>, lights: Vec<Light>) -> Scene {
    Scene {
        name: "materials".into(),
        meshes,
        materials,
        lights,
        environment: None,
        head: HeadPath::fixed(HeadPose::IDENTITY),
        nodes: Vec::new(),
    }
}

fn eyes(scene: &Scene, size: (u32, u32)) -> Vec<Eye> {
    HeadsetProfile::with_size("test", size.0, size.1).eyes(&scene.head.pose_at(0.0), DEFAULT_NEAR).eyes.to_vec()
}

fn reference(scene: &Scene, size: (u32, u32), radius: f64, rays: u32) -> (Vec<Eye>, ReferenceImage) {
    let eyes = eyes(scene, size);
    let settings = ReferenceSettings { radius, rays_per_pixel: rays, stride: 1, near: DEFAULT_NEAR };
    let image = trace(scene, &eyes, size, &settings, &mut |_| {}).unwrap();
    (eyes, image)
}

/// Every hit pixel: its eye's position, the world point it sees, its values.
fn hits<'a>(eyes: &'a [Eye], image: &'a ReferenceImage) -> Vec<(DVec3, DVec3, ReferencePixel)> {
    let mut out = Vec::new();
    for (layer, eye) in eyes.iter().enumerate() {
        for j in 0..image.grid_size().1 {
            for i in 0..image.grid_size().0 {
                if let Some(p) = world_position(image, eye, layer, i, j) {
                    out.push((eye.pose.position, p, *image.get(layer, i, j)));
                }
            }
        }
    }
    out
}

fn material<'a>(scene: &'a Scene, name: &str) -> &'a Material {
    scene.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}"))
}

fn mesh<'a>(scene: &'a Scene, name: &str) -> &'a Mesh {
    scene.meshes.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no mesh {name}"))
}

/// Asserts that the loaded texture is the written one: texels and sampling.
fn assert_same_texture(written: Option<&Texture>, loaded: Option<&Texture>, what: &str) {
    let (w, l) = (written.unwrap(), loaded.unwrap_or_else(|| panic!("{what}: not loaded")));
    assert_eq!((l.width, l.height, &l.rgba8), (w.width, w.height, &w.rgba8), "{what}: texels");
    let (ws, ls) = (w.sampling, l.sampling);
    assert_eq!(
        (ls.wrap_u, ls.wrap_v, ls.magnify, ls.minify, ls.mipmaps),
        (ws.wrap_u, ws.wrap_v, ws.magnify, ws.minify, ws.mipmaps),
        "{what}: sampler"
    );
    assert!(ls.transform.abs_diff_eq(ws.transform, 1e-5), "{what}: transform {:?} vs {:?}", ls.transform, ws.transform);
}

/// A 2×2 checker whose texels (1, 0) and (0, 1) are transparent, sampled nearest.
fn checker(sampling: Sampling) -> Texture {
    let solid = [200, 150, 100, 255];
    let hole = [20, 30, 40, 0];
    let rgba8 = [solid, hole, hole, solid].concat();
    Texture {
        width: 2,
        height: 2,
        rgba8: rgba8.into(),
        source: None,
        sampling: Sampling { magnify: Filter::Nearest, ..sampling },
    }
}

#[test]
fn a_tiled_masked_floor_has_its_holes_where_the_sampler_puts_them() {
    let wrapped = |wrap_u, wrap_v| Sampling { wrap_u, wrap_v, ..Sampling::default() };
    let cases = [
        ("repeat", wrapped(Wrap::Repeat, Wrap::Repeat)),
        ("mirrored-clamped", wrapped(Wrap::MirroredRepeat, Wrap::ClampToEdge)),
        ("clamped-mirrored", wrapped(Wrap::ClampToEdge, Wrap::MirroredRepeat)),
        (
            "transformed",
            Sampling {
                transform: uv_transform(Vec2::new(0.1, 0.3), 0.5, Vec2::new(1.5, 0.75)),
                ..wrapped(Wrap::Repeat, Wrap::MirroredRepeat)
            },
        ),
    ];
    let head = HeadPose::look_at(DVec3::new(0.0, 3.0, 1.5), DVec3::new(0.0, 0.0, -0.5)).unwrap();
    for (name, sampling) in cases {
        // A 4 m floor whose uvs run 0..4 (texels of half a metre) over a solid ground.
        let mut grille = Material::plain("grille", Vec3::splat(0.8));
        grille.diffuse_texture = Some(checker(sampling));
        grille.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
        let meshes = vec![floor("grille", 0.0, 4.0, 4.0, 0), floor("ground", -0.5, 40.0, 1.0, 1)];
        let source = scene(meshes, vec![grille, Material::plain("ground", Vec3::splat(0.5))], vec![]);
        let loaded = round_trip(&source, name, head);
        let texture = material(&loaded, "grille").diffuse_texture.as_ref();
        assert_same_texture(source.materials[0].diffuse_texture.as_ref(), texture, name);

        // Where the sampler puts a hole, the eye's ray goes through to the ground.
        let (eyes, image) = reference(&loaded, (48, 54), 0.2, 1);
        let (mut solid, mut holes) = (0, 0);
        for (eye, p, _) in hits(&eyes, &image) {
            // Where the ray crosses the grille's plane.
            let f = eye + (p - eye) * (eye.y / (eye.y - p.y));
            if f.x.abs() > 1.95 || f.z.abs() > 1.95 {
                continue;
            }
            let uv = Vec2::new(f.x as f32 / 4.0 + 0.5, f.z as f32 / 4.0 + 0.5) * 4.0;
            let texel = sampling.place(uv) * 2.0;
            // Not within a hair of a texel's edge.
            if (texel - texel.round()).abs().min_element() < 0.02 {
                continue;
            }
            let (x, y) =
                (sampling.wrap_u.texel(texel.x.floor() as i64, 2), sampling.wrap_v.texel(texel.y.floor() as i64, 2));
            let hole = x != y;
            let on_grille = p.y.abs() < 1e-3;
            assert_eq!(on_grille, !hole, "{name}: the ray through {f} (uv {uv}, texel ({x}, {y})) met {p}");
            if hole {
                holes += 1;
            } else {
                solid += 1;
            }
        }
        assert!(solid > 300 && holes > 300, "{name}: {solid} solid, {holes} holes");
    }
}

#[test]
fn vertex_colours_tint_what_a_wall_reflects() {
    // The crease: a floor and a wall at z = −1 lit by a sun from the front; the wall is
    // white, tinted red by its vertex colours (VEC3), so the floor before it gets red light.
    let tint = Vec4::new(0.8, 0.1, 0.05, 1.0);
    let mut red = wall(-1.0, 1);
    red.colors = vec![tint; 4];
    // A second wall, off to the side, with translucent vertex colours (VEC4).
    let mut fading = wall(-1.0, 1);
    fading.name = "fading".into();
    fading.positions.iter_mut().for_each(|p| p.x += 5.0);
    fading.colors = vec![Vec4::new(0.0, 1.0, 0.0, 0.25), Vec4::ONE, Vec4::new(0.0, 0.0, 1.0, 1.0), Vec4::W];
    let sun = Light::Directional { direction: Vec3::new(0.0, -0.6, -0.8), color: Vec3::ONE, intensity: 2.0 };
    let materials = vec![Material::plain("floor", Vec3::splat(0.5)), Material::plain("white", Vec3::ONE)];
    let source = scene(vec![floor("floor", 0.0, 6.0, 1.0, 0), red.clone(), fading.clone()], materials, vec![sun]);
    let head = HeadPose::look_at(DVec3::new(0.0, 1.2, 1.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
    let loaded = round_trip(&source, "colours", head);
    assert_eq!(mesh(&loaded, "wall").colors, red.colors);
    assert_eq!(mesh(&loaded, "fading").colors, fading.colors);
    assert!(mesh(&loaded, "floor").colors.is_empty());

    let (eyes, image) = reference(&loaded, (40, 45), 0.5, 64);
    let mut tinted = 0;
    for (_, p, px) in hits(&eyes, &image) {
        // Floor points before the wall, well inside its width, whose occluded directions
        // all meet the wall's front.
        if p.y.abs() > 1e-4 || p.x.abs() > 0.4 || p.z < -0.99 || px.ao == 1.0 {
            continue;
        }
        let [r, g, b] = px.bounce;
        assert!((r / g - 8.0).abs() < 1e-3 && (g / b - 2.0).abs() < 1e-3, "{:?} at {p}", px.bounce);
        tinted += 1;
    }
    assert!(tinted > 20, "{tinted}");
}

#[test]
fn an_emission_texture_limits_what_a_wall_emits() {
    // A black wall emitting 2 where its texture is white (the right half) and nothing
    // where it is black (the left half); no lights.
    let mut glow = Material::plain("glow", Vec3::ZERO);
    glow.emissive = Vec3::splat(2.0);
    let half = [[0u8, 0, 0, 255], [255, 255, 255, 255]].concat();
    let nearest = Sampling { magnify: Filter::Nearest, ..Sampling::default() };
    glow.emissive_texture = Some(Texture { width: 2, height: 1, rgba8: half.into(), source: None, sampling: nearest });
    let materials = vec![Material::plain("floor", Vec3::splat(0.5)), glow];
    let source = scene(vec![floor("floor", 0.0, 6.0, 1.0, 0), wall(-1.0, 1)], materials, vec![]);
    let head = HeadPose::look_at(DVec3::new(0.0, 1.2, 1.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
    let loaded = round_trip(&source, "emission", head);
    let (w, l) = (&source.materials[1], material(&loaded, "glow"));
    assert_eq!(l.emissive, w.emissive);
    assert_same_texture(w.emissive_texture.as_ref(), l.emissive_texture.as_ref(), "emission");

    let r = 0.3;
    let (eyes, image) = reference(&loaded, (96, 108), r, 16);
    let (mut dark, mut lit) = (0, 0);
    for (_, p, px) in hits(&eyes, &image) {
        // Floor points within reach of the wall, each side well clear of the middle.
        if p.y.abs() > 1e-4 || p.z > -1.0 + r - 0.01 || p.z < -0.99 || px.ao == 1.0 {
            continue;
        }
        if (-0.65..-0.35).contains(&p.x) {
            assert_eq!(px.bounce, [0.0; 3], "at {p}");
            dark += 1;
        } else if (0.35..0.65).contains(&p.x) {
            // Every occluded direction meets an emission of 2: π · 2 · (1 − ao).
            let exact = std::f32::consts::PI * 2.0 * (1.0 - px.ao);
            assert!(px.bounce.iter().all(|b| (b - exact).abs() < 1e-4 * (1.0 + exact)), "{:?} vs {exact}", px.bounce);
            lit += 1;
        }
    }
    assert!(dark > 20 && lit > 20, "{dark} dark, {lit} lit");
}

#[test]
fn normal_and_occlusion_textures_leave_the_ao_reference_as_it_is() {
    // The crease again, every surface normal-mapped (tilted towards +u) and with a baked
    // occlusion texture.
    let texel = |rgba: [u8; 4]| Texture {
        width: 1,
        height: 1,
        rgba8: rgba.to_vec().into(),
        source: None,
        sampling: Sampling::default(),
    };
    let mut bumpy = Material::plain("bumpy", Vec3::splat(0.7));
    bumpy.normal_texture = Some((texel([230, 128, 200, 255]), 0.8));
    bumpy.occlusion_texture = Some((texel([100, 100, 100, 255]), 0.6));
    let tangent = Vec4::new(1.0, 0.0, 0.0, 1.0);
    let mut ground = floor("floor", 0.0, 6.0, 1.0, 0);
    ground.tangents = vec![tangent; 4];
    let mut upright = wall(-1.0, 0);
    upright.tangents = vec![tangent; 4];
    let sun =
        Light::Directional { direction: Vec3::new(0.3, -0.6, -0.8).normalize(), color: Vec3::ONE, intensity: 2.0 };
    let source = scene(vec![ground, upright], vec![bumpy.clone()], vec![sun]);
    let head = HeadPose::look_at(DVec3::new(0.0, 1.2, 1.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
    let loaded = round_trip(&source, "bumpy", head);
    let l = material(&loaded, "bumpy");
    let (normal, scale) = l.normal_texture.as_ref().expect("the normal texture is loaded");
    assert_eq!(*scale, 0.8);
    assert_same_texture(bumpy.normal_texture.as_ref().map(|(t, _)| t), Some(normal), "normal");
    let (occlusion, strength) = l.occlusion_texture.as_ref().expect("the occlusion texture is loaded");
    assert_eq!(*strength, 0.6);
    assert_same_texture(bumpy.occlusion_texture.as_ref().map(|(t, _)| t), Some(occlusion), "occlusion");
    assert_eq!(mesh(&loaded, "floor").tangents, vec![tangent; 4]);

    // Without the two textures: the same AO, bit for bit; the bounce changes, as the
    // normal texture turns the wall towards or away from the sun.
    let mut flat = loaded.clone();
    flat.materials.iter_mut().for_each(|m| (m.normal_texture, m.occlusion_texture) = (None, None));
    let (_, mapped) = reference(&loaded, (32, 36), 0.5, 16);
    let (_, plain) = reference(&flat, (32, 36), 0.5, 16);
    let pairs: Vec<_> = mapped.layers.iter().flatten().zip(plain.layers.iter().flatten()).collect();
    assert!(pairs.iter().all(|(a, b)| (a.hit, a.depth, a.ao, a.ao_falloff) == (b.hit, b.depth, b.ao, b.ao_falloff)));
    assert!(pairs.iter().all(|(a, b)| a.unoccluded == b.unoccluded && a.environment_visible == b.environment_visible));
    assert!(pairs.iter().any(|(a, b)| a.bounce != b.bounce), "the normal texture lights the bounce's senders");
}
