//! The G-buffer reads materials as glTF authors make them: samplers (wrap per axis,
//! filters), `KHR_texture_transform`, vertex colours (colour and alpha), emissive,
//! normal and occlusion textures. Each is checked on the GPU against the value its
//! definition gives at known points of a quad facing the eye.

use crate::common;

use glam::{DVec3, Vec2, Vec3, Vec4};
use vrao_ao::plug::{DEPTH, NORMALS};
use vrao_ao::HeadPose;
use vrao_render::passes::gbuffer::{ALBEDO, EMISSION, SHADING_NORMALS};
use vrao_render::scene::{uv_transform, AlphaMode, Filter, Sampling, Scene, Texture, Wrap};
use vrao_render::{HeadsetProfile, Renderer, Settings};

const SIZE: (u32, u32) = (96, 108);

/// A 4 m square in z = 0 from (0, 0) to (4, 4), facing +z, its texture coordinates
/// u = x and v = 4 − y (v = 0 at the top, as glTF's are).
fn quad() -> vrao_render::scene::Mesh {
    let mut mesh = common::square("quad", DVec3::new(2.0, 2.0, 0.0), 4.0, 0);
    mesh.uvs = mesh.positions.iter().map(|p| Vec2::new(p.x + 2.0, 2.0 - p.y)).collect();
    mesh
}

/// The texture coordinates of world point `p` on [`quad`].
fn uv_of(p: DVec3) -> Vec2 {
    Vec2::new(p.x as f32, 4.0 - p.y as f32)
}

/// 2×2 texels: red, green / blue, grey (sRGB bytes), sampled nearest without mipmaps.
fn four_texels(wrap_u: Wrap, wrap_v: Wrap) -> Texture {
    let rgba8 = [[200, 0, 0, 255], [0, 200, 0, 255], [0, 0, 200, 255], [200, 200, 200, 255]].concat();
    let sampling = Sampling {
        wrap_u,
        wrap_v,
        magnify: Filter::Nearest,
        minify: Filter::Nearest,
        mipmaps: None,
        ..Default::default()
    };
    Texture { width: 2, height: 2, rgba8: rgba8.into(), source: None, sampling }
}

/// The texel of [`four_texels`] that `uv` (already placed) reads, as the sampler's wrap
/// addresses it.
fn texel_at(texture: &Texture, uv: Vec2) -> [u8; 3] {
    let x = texture.sampling.wrap_u.texel((uv.x * 2.0).floor() as i64, 2);
    let y = texture.sampling.wrap_v.texel((uv.y * 2.0).floor() as i64, 2);
    let i = 4 * (y * 2 + x) as usize;
    [texture.rgba8[i], texture.rgba8[i + 1], texture.rgba8[i + 2]]
}

/// Renders `scene` seen from 2.2 m in front of the quad's centre and reads `resources`
/// back; with a lookup of the left eye's pixel (4 floats per texel) at a world point.
struct Frame {
    eyes: vrao_ao::EyePair,
    near: f64,
    images: Vec<Vec<f32>>,
}

impl Frame {
    fn render(scene: &Scene, resources: &[vrao_ao::plug::Resource]) -> Frame {
        let (gpu, _guard) = common::gpu();
        let settings = Settings { profile: HeadsetProfile::with_size("test", SIZE.0, SIZE.1), ..Settings::default() };
        let head = HeadPose::look_at(DVec3::new(2.0, 2.0, 2.2), DVec3::new(2.0, 2.0, 0.0)).unwrap();
        let eyes = settings.profile.eyes(&head, settings.near);
        let mut renderer = Renderer::new(gpu.clone(), scene, &settings).unwrap();
        renderer.render_and_wait(&eyes.eyes, resources).unwrap();
        let images = resources.iter().map(|&r| renderer.read_f32(r).unwrap().swap_remove(0)).collect();
        Frame { eyes, near: settings.near, images }
    }

    /// Image `k`'s channels (up to 4) at the left eye's pixel showing `p`.
    fn at(&self, k: usize, p: DVec3) -> [f32; 4] {
        let (uv, _) = self.eyes.eyes[0].project(p, self.near).expect("the point is in view");
        let (x, y) = ((uv[0] * SIZE.0 as f64) as usize, (uv[1] * SIZE.1 as f64) as usize);
        let channels = self.images[k].len() / (SIZE.0 * SIZE.1) as usize;
        let i = channels * (y * SIZE.0 as usize + x);
        let mut texel = [0.0; 4];
        texel[..channels].copy_from_slice(&self.images[k][i..i + channels]);
        texel
    }
}

fn scene_of(mesh: vrao_render::scene::Mesh, material: vrao_render::scene::Material) -> Scene {
    let mut scene = common::bare_scene(vec![mesh]);
    scene.materials = vec![material];
    scene
}

/// Points of the quad at the centres of a 0.25 m grid, away from its edges.
fn grid() -> Vec<DVec3> {
    (0..16)
        .flat_map(|i| (0..16).map(move |j| DVec3::new(0.125 + 0.25 * i as f64, 0.125 + 0.25 * j as f64, 0.0)))
        .collect()
}

fn assert_albedo_is(frame: &Frame, p: DVec3, expected: [u8; 3], what: &str) {
    let got = frame.at(0, p);
    for c in 0..3 {
        let diff = (got[c] * 255.0 - expected[c] as f32).abs();
        assert!(diff <= 2.0, "{what} at {p}: albedo {:?}, expected {expected:?}", got.map(|v| (v * 255.0).round()));
    }
}

#[test]
fn each_wrap_mode_on_each_axis_addresses_texels_as_gltf_says() {
    let combinations = [
        (Wrap::Repeat, Wrap::MirroredRepeat),
        (Wrap::MirroredRepeat, Wrap::ClampToEdge),
        (Wrap::ClampToEdge, Wrap::Repeat),
    ];
    for (wrap_u, wrap_v) in combinations {
        let mut material = vrao_render::scene::Material::plain("tiled", Vec3::ONE);
        material.diffuse_texture = Some(four_texels(wrap_u, wrap_v));
        let texture = material.diffuse_texture.clone().unwrap();
        let frame = Frame::render(&scene_of(quad(), material), &[ALBEDO]);
        for p in grid() {
            // Texel centres: u and v at odd multiples of 0.25, each texel 0.5 wide in uv.
            let uv = uv_of(p);
            assert_albedo_is(&frame, p, texel_at(&texture, uv), &format!("{wrap_u:?}/{wrap_v:?}"));
        }
    }
}

#[test]
fn texture_transform_moves_where_the_texture_is_read() {
    let mut texture = four_texels(Wrap::Repeat, Wrap::Repeat);
    texture.sampling.transform = uv_transform(Vec2::new(0.25, 0.5), 0.3, Vec2::new(1.5, 0.75));
    let mut material = vrao_render::scene::Material::plain("placed", Vec3::ONE);
    material.diffuse_texture = Some(texture.clone());
    let frame = Frame::render(&scene_of(quad(), material), &[ALBEDO]);
    let mut checked = 0;
    for p in grid() {
        let placed = texture.sampling.place(uv_of(p));
        // Away from texel edges (a pixel covers about 0.05 m).
        let edge = |t: f32| ((t * 2.0).fract().abs() - 0.5).abs() > 0.35;
        if edge(placed.x) || edge(placed.y) {
            continue;
        }
        assert_albedo_is(&frame, p, texel_at(&texture, placed), "placed");
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} points away from texel edges");
}

#[test]
fn vertex_colours_multiply_the_base_colour_and_their_alpha_cuts_holes() {
    let mut mesh = quad();
    // Red rises from 0.2 on the left (x = 0) to 1 on the right; alpha likewise from 0 to 1.
    mesh.colors = mesh
        .positions
        .iter()
        .map(|p| if p.x < 0.0 { Vec4::new(0.2, 0.5, 1.0, 0.0) } else { Vec4::new(1.0, 0.5, 1.0, 1.0) })
        .collect();
    let mut material = vrao_render::scene::Material::plain("coloured", Vec3::new(1.0, 0.8, 0.5));
    material.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    let scene = scene_of(mesh, material);
    assert!(scene.has_alpha_test(), "the vertex alpha can fail the test");
    let frame = Frame::render(&scene, &[ALBEDO, DEPTH]);
    let encode = |c: f32| {
        if c <= 0.0031308 {
            c * 12.92
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        }
    };
    for p in grid() {
        let t = (p.x / 4.0) as f32;
        let depth = frame.at(1, p)[0];
        if t < 0.45 {
            assert_eq!(depth, 0.0, "at {p} the vertex alpha {t} is below the cutoff: a hole");
            continue;
        }
        if t < 0.55 {
            continue;
        }
        assert!(depth > 0.0, "at {p} the vertex alpha {t} passes the cutoff");
        // Colours are stored as 8-bit: 0.5 is 128/255.
        let expected = [(0.2 + 0.8 * t) * 1.0, 128.0 / 255.0 * 0.8, 0.5];
        let got = frame.at(0, p);
        for c in 0..3 {
            let want = encode(expected[c]);
            assert!((got[c] - want).abs() <= 3.0 / 255.0, "at {p} channel {c}: {} expected {want}", got[c]);
        }
    }
}

#[test]
fn emissive_texture_limits_the_emission_and_occlusion_texture_reaches_the_albedo_alpha() {
    let mut material = vrao_render::scene::Material::plain("lamp", Vec3::splat(0.5));
    material.emissive = Vec3::new(4.0, 2.0, 1.0);
    // Emissive: left half black, right half white (sRGB 255 = 1); occlusion: red 51 (0.2)
    // on the left, 255 on the right, at strength 0.5.
    let halves = |left: [u8; 4], right: [u8; 4]| Texture {
        width: 2,
        height: 1,
        rgba8: [left, right].concat().into(),
        source: None,
        sampling: Sampling { magnify: Filter::Nearest, mipmaps: None, ..Default::default() },
    };
    let on_quad = |t: Texture| {
        let mut t = t;
        // One texture width across the 4 m quad.
        t.sampling.transform = uv_transform(Vec2::ZERO, 0.0, Vec2::splat(0.25));
        t
    };
    material.emissive_texture = Some(on_quad(halves([0, 0, 0, 255], [255, 255, 255, 255])));
    material.occlusion_texture = Some((on_quad(halves([51, 0, 0, 255], [255, 0, 0, 255])), 0.5));
    let frame = Frame::render(&scene_of(quad(), material), &[EMISSION, ALBEDO]);
    for (x, emission, occlusion) in [(0.5, 0.0, 1.0 + 0.5 * (0.2 - 1.0)), (3.5, 1.0, 1.0)] {
        for y in [0.5, 2.0, 3.5] {
            let p = DVec3::new(x, y, 0.0);
            let e = frame.at(0, p);
            for (c, factor) in [4.0, 2.0, 1.0].into_iter().enumerate() {
                assert!((e[c] - factor * emission).abs() < 0.01, "emission at {p}: {e:?}");
            }
            let a = frame.at(1, p)[3];
            assert!((a - occlusion).abs() <= 1.5 / 255.0, "baked occlusion at {p}: {a}, expected {occlusion}");
        }
    }
}

#[test]
fn normal_textures_tilt_the_lighting_normal_with_mesh_tangents_or_without_them_and_the_ao_keeps_the_surfaces() {
    // One texel tilting 30° towards +u (image right): (sin 30°, 0, cos 30°) encoded.
    let (s, c) = (30f32.to_radians().sin(), 30f32.to_radians().cos());
    let encode = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    let tilt = Texture {
        width: 1,
        height: 1,
        rgba8: vec![encode(s), encode(0.0), encode(c), 255].into(),
        source: None,
        sampling: Sampling::default(),
    };
    let with_tangents = {
        let mut mesh = quad();
        mesh.tangents = vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 4];
        mesh
    };
    for (label, mesh, scale) in
        [("derived frame", quad(), 1.0), ("mesh tangents", with_tangents, 1.0), ("scale 0", quad(), 0.0)]
    {
        let mut material = vrao_render::scene::Material::plain("bumpy", Vec3::splat(0.5));
        material.normal_texture = Some((tilt.clone(), scale));
        let frame = Frame::render(&scene_of(mesh, material), &[SHADING_NORMALS, NORMALS]);
        // The normal in view space: the eye looks down −z with +x to its right (it is
        // 32 mm left of the head, which turns it by a negligible angle at 2.2 m).
        let tilted = Vec3::new(s * scale, 0.0, c).normalize();
        for p in [DVec3::new(1.0, 1.0, 0.0), DVec3::new(2.0, 3.0, 0.0), DVec3::new(3.0, 2.0, 0.0)] {
            let n = frame.at(0, p);
            let got = Vec3::new(n[0], n[1], n[2]);
            let world_to_view = frame.eyes.eyes[0].view_from_world();
            let expected = world_to_view.transform_vector3(tilted.as_dvec3()).as_vec3();
            assert!(got.abs_diff_eq(expected, 0.03), "{label} at {p}: normal {got}, expected {expected}");
            // The AO keeps the surface's own normal.
            let own = frame.at(1, p);
            let flat = world_to_view.transform_vector3(DVec3::Z).as_vec3();
            assert!(Vec3::new(own[0], own[1], own[2]).abs_diff_eq(flat, 1e-3), "{label} at {p}: AO normal {own:?}");
        }
    }
}

#[test]
fn the_ambient_light_takes_the_smaller_of_the_baked_and_the_screen_space_occlusion() {
    use vrao_ao::plug::FINAL_AO;
    use vrao_render::passes::composite::HDR;
    // A floor under the sky alone (no lights): its radiance is albedo/π × the sky's
    // irradiance × the occlusion the composite applies.
    let lit = |baked: Option<f32>| {
        let mut material = vrao_render::scene::Material::plain("floor", Vec3::splat(0.5));
        material.occlusion_texture = baked.map(|b| {
            let r = (b * 255.0).round() as u8;
            (
                Texture {
                    width: 1,
                    height: 1,
                    rgba8: vec![r, r, r, 255].into(),
                    source: None,
                    sampling: Sampling::default(),
                },
                1.0,
            )
        });
        let mut scene = scene_of(quad(), material);
        scene.environment = Some(vrao_render::scene::Environment::default_sky());
        Frame::render(&scene, &[HDR, FINAL_AO])
    };
    let plain = lit(None);
    let p = DVec3::new(2.0, 2.0, 0.0);
    let ao = plain.at(1, p)[3];
    assert!(ao > 0.6, "an open floor is mostly unoccluded ({ao})");
    for baked in [0.2f32, 1.0] {
        let with = lit(Some(baked));
        let expected = baked.min(ao) / ao;
        let ratio = with.at(0, p)[0] / plain.at(0, p)[0];
        assert!((ratio - expected).abs() < 0.02, "baked {baked}, AO {ao}: radiance ratio {ratio}, expected {expected}");
    }
}
