//! glTF 2.0: round trips through vrao's writer (every storage and accessor type, the node
//! hierarchy and its animation, materials, lights, camera), hand-written files for the
//! static hierarchy, bad input (one line naming the file, never a panic), and Sibenik as
//! `.glb` against its OBJ on the GPU (identical G-buffer).

use crate::common;

use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};
use serde_json::json;
use std::path::{Path, PathBuf};
use vrao::test_assets::gltf_write::{encode_base64, write, IndexType, Storage, TexcoordType, WriteOptions};
use vrao_ao::HeadPose;
use vrao_render::scene::{
    AlphaMode, HeadPath, Interpolation, Light, Material, Mesh, Node, NodeTracks, Scene, Texture, Track, Trs,
};

/// A 4×4 checker whose dark cells are transparent.
fn checker() -> Texture {
    let mut rgba8 = Vec::new();
    for y in 0..4u32 {
        for x in 0..4 {
            let solid = (x + y).is_multiple_of(2);
            rgba8.extend(if solid { [200, 150, 100, 255] } else { [20, 30, 40, 0] });
        }
    }
    Texture { sampling: Default::default(), width: 4, height: 4, rgba8: rgba8.into(), source: None }
}

/// Every feature the writer and loader share: static and moving meshes (a moving root
/// with a base, a child with cubic rotation and stepped scale), textured, masked,
/// blended and emissive materials, the three light kinds and a camera.
fn source_scene() -> Scene {
    Scene {
        name: "source".into(),
        meshes: source_meshes(),
        materials: source_materials(),
        lights: source_lights(),
        environment: None,
        head: HeadPath::fixed(HeadPose::IDENTITY),
        nodes: source_nodes(),
    }
}

/// A textured floor and grille (static), a lamp on the hand and a window on the arm.
fn source_meshes() -> Vec<Mesh> {
    let mut floor = common::square("floor", DVec3::new(0.0, -1.0, -3.0), 4.0, 3);
    floor.uvs = vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ZERO];
    let mut grille = common::square("grille", DVec3::new(0.5, 0.0, -2.0), 1.0, 0);
    grille.uvs = vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)];
    let mut lamp = common::cuboid("lamp", DVec3::new(0.1, 0.2, 0.3), Vec3::new(0.2, 0.1, 0.3), 2);
    lamp.node = Some(1);
    let mut window = common::square("window", DVec3::new(0.0, 0.25, 0.0), 0.5, 1);
    window.node = Some(0);
    vec![floor, grille, lamp, window]
}

/// Masked (textured), blended, emissive and plain.
fn source_materials() -> Vec<Material> {
    let mut masked = Material::plain("checker", Vec3::new(0.9, 0.8, 0.7));
    masked.diffuse_texture = Some(checker());
    masked.alpha_mode = AlphaMode::Mask { cutoff: 0.3 };
    let mut glass = Material::plain("glass", Vec3::new(0.2, 0.3, 0.4));
    glass.alpha = 0.4;
    glass.alpha_mode = AlphaMode::Blend;
    let mut emitter = Material::plain("lamp", Vec3::ONE);
    emitter.emissive = Vec3::new(6.0, 3.0, 0.0);
    vec![masked, glass, emitter, Material::plain("plain", Vec3::splat(0.5))]
}

/// A moving root with a base (linear translation), and its child with a cubic rotation
/// and a stepped scale.
fn source_nodes() -> Vec<Node> {
    let q = |axis: DVec3, angle: f64| DQuat::from_axis_angle(axis, angle);
    let arm = Node {
        name: "arm".into(),
        parent: None,
        base: DMat4::from_rotation_translation(q(DVec3::Y, 0.5), DVec3::new(1.0, 2.0, 3.0)),
        rest: Trs { translation: DVec3::new(0.0, 0.5, 0.0), ..Trs::IDENTITY },
        tracks: NodeTracks {
            translation: Some(Track {
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0, 2.0],
                values: vec![DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 0.5, -1.0)],
            }),
            ..NodeTracks::default()
        },
    };
    let hand = Node {
        name: "hand".into(),
        parent: Some(0),
        base: DMat4::IDENTITY,
        rest: Trs { translation: DVec3::new(0.0, 0.0, 0.25), ..Trs::IDENTITY },
        tracks: NodeTracks {
            rotation: Some(Track {
                interpolation: Interpolation::CubicSpline,
                times: vec![0.0, 1.5],
                values: vec![
                    DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
                    DQuat::IDENTITY,
                    DQuat::from_xyzw(0.0, 0.5, 0.0, 0.0),
                    DQuat::from_xyzw(0.0, 0.25, 0.0, 0.0),
                    q(DVec3::Y, 1.0),
                    DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
                ],
            }),
            scale: Some(Track {
                interpolation: Interpolation::Step,
                times: vec![0.0, 0.5, 1.0],
                values: vec![DVec3::ONE, DVec3::splat(2.0), DVec3::new(1.0, 0.5, 1.0)],
            }),
            ..NodeTracks::default()
        },
    };
    vec![arm, hand]
}

/// A directional, a point and a spot light.
fn source_lights() -> Vec<Light> {
    vec![
        Light::Directional {
            direction: Vec3::new(0.3, -1.0, -0.2).normalize(),
            color: Vec3::new(1.0, 0.9, 0.8),
            intensity: 3.0,
        },
        Light::Point { position: DVec3::new(0.0, 2.5, -1.0), color: Vec3::ONE, intensity: 6.0 },
        Light::Spot {
            position: DVec3::new(1.0, 2.0, 0.5),
            direction: Vec3::new(0.0, -1.0, -0.5).normalize(),
            color: Vec3::new(0.5, 1.0, 0.5),
            intensity: 20.0,
            inner_cone: 0.2,
            outer_cone: 0.6,
        },
    ]
}

fn camera_pose() -> HeadPose {
    HeadPose::look_at(DVec3::new(0.5, 1.6, 2.0), DVec3::new(0.0, 0.0, -2.0)).unwrap()
}

/// Each mesh's triangle corners in world space at `t`: (position, normal, uv), by name.
/// A triangle corner in world space: position, normal, uv.
type Corner = (DVec3, Vec3, Vec2);

fn corners(scene: &Scene, t: f64) -> Vec<(String, Vec<Corner>)> {
    let transforms = scene.node_transforms(t);
    let mut out: Vec<_> = scene
        .meshes
        .iter()
        .map(|m| {
            let world = m.node.map_or(DMat4::IDENTITY, |n| transforms[n]);
            let normal_matrix = glam::DMat3::from_mat4(world).inverse().transpose();
            let list = m
                .indices
                .iter()
                .map(|&i| {
                    let i = i as usize;
                    let n = (normal_matrix * m.normals[i].as_dvec3()).normalize().as_vec3();
                    (world.transform_point3(m.origin + m.positions[i].as_dvec3()), n, m.uvs[i])
                })
                .collect();
            (m.name.clone(), list)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn material<'a>(scene: &'a Scene, name: &str) -> &'a Material {
    scene.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}"))
}

/// Asserts that `loaded` is `source` as far as glTF carries it.
fn assert_same(source: &Scene, loaded: &Scene, uv_tolerance: f32, label: &str) {
    assert_eq!(loaded.meshes.len(), source.meshes.len(), "{label}");
    for t in [0.0, 0.3, 0.5, 0.77, 1.2, 1.5, 1.99] {
        for ((name, a), (other, b)) in corners(source, t).iter().zip(corners(loaded, t)) {
            assert_eq!(name, &other, "{label}");
            assert_eq!(a.len(), b.len(), "{label} {name}: corner count");
            let textured = material(
                source,
                &source.materials[source.meshes.iter().find(|m| &m.name == name).unwrap().material].name,
            )
            .diffuse_texture
            .is_some();
            for ((pa, na, ua), (pb, nb, ub)) in a.iter().zip(&b) {
                assert!((*pa - *pb).length() < 1e-5, "{label} {name} t={t}: position {pa} vs {pb}");
                assert!((*na - *nb).length() < 1e-5, "{label} {name} t={t}: normal {na} vs {nb}");
                if textured {
                    assert!((*ua - *ub).abs().max_element() <= uv_tolerance, "{label} {name}: uv {ua} vs {ub}");
                }
            }
        }
    }
    for m in &source.materials {
        let l = material(loaded, &m.name);
        assert!((l.diffuse - m.diffuse).length() < 1e-6, "{label} {}", m.name);
        assert!((l.emissive - m.emissive).length() < 1e-5, "{label} {}: {} vs {}", m.name, l.emissive, m.emissive);
        assert_eq!((l.alpha, l.alpha_mode), (m.alpha, m.alpha_mode), "{label} {}", m.name);
        let (lt, mt) = (l.diffuse_texture.as_ref(), m.diffuse_texture.as_ref());
        assert_eq!(lt.map(|t| (t.width, t.height, &t.rgba8)), mt.map(|t| (t.width, t.height, &t.rgba8)), "{label}");
    }
    assert_eq!(loaded.lights.len(), source.lights.len(), "{label}");
    for (a, b) in source.lights.iter().zip(&loaded.lights) {
        let close = match (a, b) {
            (
                Light::Directional { direction: d, color: c, intensity: i },
                Light::Directional { direction: d2, color: c2, intensity: i2 },
            ) => (*d - *d2).length() < 1e-6 && c == c2 && i == i2,
            (
                Light::Point { position: p, color: c, intensity: i },
                Light::Point { position: p2, color: c2, intensity: i2 },
            ) => (*p - *p2).length() < 1e-6 && c == c2 && i == i2,
            (
                Light::Spot { position: p, direction: d, color: c, intensity: i, inner_cone: a1, outer_cone: b1 },
                Light::Spot { position: p2, direction: d2, color: c2, intensity: i2, inner_cone: a2, outer_cone: b2 },
            ) => (*p - *p2).length() < 1e-6 && (*d - *d2).length() < 1e-6 && c == c2 && i == i2 && a1 == a2 && b1 == b2,
            _ => false,
        };
        assert!(close, "{label}: light {a:?} came back as {b:?}");
    }
    assert!(loaded.is_animated(), "{label}");
    assert_eq!(loaded.animation_period(), source.animation_period(), "{label}");
}

#[test]
fn every_storage_and_accessor_type_round_trips() {
    let dir = common::temp_dir("gltf-round-trip");
    let source = source_scene();
    let mut cases = 0;
    for (ext, buffers, images) in [
        ("glb", Storage::Embedded, Storage::Embedded),
        ("glb", Storage::Embedded, Storage::DataUri),
        ("gltf", Storage::DataUri, Storage::DataUri),
        ("gltf", Storage::External, Storage::External),
        ("gltf", Storage::External, Storage::Embedded),
    ] {
        for indices in [IndexType::Smallest, IndexType::U8, IndexType::U16, IndexType::U32, IndexType::NonIndexed] {
            for (texcoords, uv_tolerance) in [
                (TexcoordType::F32, 0.0),
                (TexcoordType::U8Normalized, 0.5 / 255.0),
                (TexcoordType::U16Normalized, 0.5 / 65535.0),
            ] {
                for normals in [true, false] {
                    let label = format!("{ext} {buffers:?}/{images:?} {indices:?} {texcoords:?} normals={normals}");
                    let path = dir.join(format!("case{cases}.{ext}"));
                    let options =
                        WriteOptions { buffers, images, indices, texcoords, normals, camera: Some(camera_pose()) };
                    write(&source, &path, &options).unwrap_or_else(|e| panic!("{label}: {e}"));
                    let loaded = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{label}: {e}"));
                    assert_same(&source, &loaded, uv_tolerance, &label);
                    let head = loaded.head.pose_at(0.0);
                    let expected = camera_pose();
                    assert!((head.position - expected.position).length() < 1e-5, "{label}: camera {head:?}");
                    assert!(head.orientation.dot(expected.orientation).abs() > 1.0 - 1e-6, "{label}: camera {head:?}");
                    cases += 1;
                }
            }
        }
    }
    assert_eq!(cases, 5 * 5 * 3 * 2);
}

#[test]
fn index_types_are_the_ones_asked_for() {
    // The round trip above passes whatever the writer chose; check it chose as asked.
    let dir = common::temp_dir("gltf-index-types");
    let source = source_scene();
    for (indices, component) in [(IndexType::U8, 5121), (IndexType::U16, 5123), (IndexType::U32, 5125)] {
        let path = dir.join("t.gltf");
        write(&source, &path, &WriteOptions { indices, buffers: Storage::DataUri, ..WriteOptions::default() }).unwrap();
        let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        let index_accessor = doc["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
        assert_eq!(doc["accessors"][index_accessor]["componentType"], json!(component), "{indices:?}");
    }
    let path = dir.join("n.gltf");
    write(
        &source,
        &path,
        &WriteOptions { indices: IndexType::NonIndexed, buffers: Storage::DataUri, ..WriteOptions::default() },
    )
    .unwrap();
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert!(doc["meshes"][0]["primitives"][0].get("indices").is_none());
}

/// A `.gltf` with `body`'s objects and one data-URI buffer holding `bin`.
fn gltf_text(bin: &[u8], mut body: serde_json::Value) -> String {
    body["asset"] = json!({ "version": "2.0" });
    body["buffers"] = json!([{ "byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", encode_base64(bin)) }]);
    body.to_string()
}

/// One triangle (positions only) as buffer bytes: 3 × vec3 f32.
fn triangle_bytes() -> Vec<u8> {
    let p: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    bytemuck::cast_slice(&p).to_vec()
}

/// A file placing the triangle under `nodes` (node 0 is the scene's root).
fn triangle_file(nodes: serde_json::Value, extra: serde_json::Value) -> String {
    let mut body = json!({
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": nodes,
        "meshes": [{ "name": "tri", "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0] }],
        "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
    });
    if let (Some(b), serde_json::Value::Object(e)) = (body.as_object_mut(), extra) {
        b.extend(e);
    }
    gltf_text(&triangle_bytes(), body)
}

/// Appends to a JSON array (indexing past its end would panic).
fn push(array: &mut serde_json::Value, value: serde_json::Value) {
    array.as_array_mut().expect("an array").push(value);
}

fn write_file(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn static_matrix_and_trs_hierarchy_is_baked_into_world_space() {
    let dir = common::temp_dir("gltf-hierarchy");
    // Root: matrix (scale 2, then move by (10, 0, 0)); child: TRS turning 90° about Z,
    // moved up 1; the triangle on the child.
    let matrix = DMat4::from_scale_rotation_translation(DVec3::splat(2.0), DQuat::IDENTITY, DVec3::new(10.0, 0.0, 0.0));
    let turn = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let nodes = json!([
        { "matrix": matrix.as_mat4().to_cols_array(), "children": [1] },
        { "translation": [0, 1, 0], "rotation": turn.as_quat().to_array(), "mesh": 0 },
    ]);
    let path = write_file(&dir, "h.gltf", triangle_file(nodes, json!({})));
    let scene = Scene::load(path.to_str().unwrap()).unwrap();
    assert!(scene.nodes.is_empty(), "a still glTF has no nodes");
    assert!(!scene.has_alpha_test(), "an opaque glTF has no alpha test");
    assert!(!scene.is_animated());
    let m = &scene.meshes[0];
    let world: Vec<DVec3> = m.positions.iter().map(|p| m.origin + p.as_dvec3()).collect();
    // (1,0,0) → turned (0,1,0) → up (0,2,0) → scaled (0,4,0) → moved (10,4,0).
    let expected = [DVec3::new(10.0, 2.0, 0.0), DVec3::new(10.0, 4.0, 0.0), DVec3::new(8.0, 2.0, 0.0)];
    for (w, e) in world.iter().zip(expected) {
        assert!((*w - e).length() < 1e-6, "{world:?}");
    }
    // Normals computed (no NORMAL attribute) from the winding, turned with the mesh: +Z.
    assert!(m.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6), "{:?}", m.normals);
    // The default material of glTF: white, opaque.
    assert_eq!(scene.materials[0].diffuse, Vec3::ONE);
    // No light in the file: the default sun; no camera: framed like an OBJ.
    assert_eq!(scene.lights, vec![Light::default_sun()]);
    assert_eq!(scene.head.pose_at(0.0), scene.bounds().framing_pose());
}

#[test]
fn a_mirroring_node_keeps_triangles_counter_clockwise_around_their_normals() {
    let dir = common::temp_dir("gltf-mirror");
    let nodes = json!([{ "scale": [-1, 1, 1], "mesh": 0 }]);
    let scene = Scene::load(write_file(&dir, "m.gltf", triangle_file(nodes, json!({}))).to_str().unwrap()).unwrap();
    let m = &scene.meshes[0];
    let [a, b, c] = [0, 1, 2].map(|k| m.positions[m.indices[k] as usize]);
    let face = (b - a).cross(c - a).normalize();
    assert!((face - m.normals[0]).length() < 1e-6, "face {face}, normal {}", m.normals[0]);
}

#[test]
fn several_nodes_may_draw_one_mesh() {
    let dir = common::temp_dir("gltf-instances");
    let nodes = json!([
        { "children": [1, 2] },
        { "translation": [0, 0, 0], "mesh": 0 },
        { "translation": [5, 0, 0], "mesh": 0 },
    ]);
    let scene = Scene::load(write_file(&dir, "i.gltf", triangle_file(nodes, json!({}))).to_str().unwrap()).unwrap();
    assert_eq!(scene.meshes.len(), 2);
    assert!((scene.meshes[1].origin - scene.meshes[0].origin - DVec3::new(5.0, 0.0, 0.0)).length() < 1e-9);
}

/// Loads `text` as `name` in `dir` and returns the error line (the load must fail).
fn load_error(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> String {
    let path = write_file(dir, name, text);
    let message = match Scene::load(path.to_str().unwrap()) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => e.to_string(),
    };
    assert!(message.starts_with(&path.display().to_string()), "{name}: the error names the file: {message}");
    assert!(!message.contains('\n'), "{name}: one line: {message}");
    message
}

#[test]
fn bad_input_is_one_line_naming_the_file_and_the_problem() {
    let dir = common::temp_dir("gltf-bad");
    let valid = triangle_file(ok_nodes(), json!({}));
    assert!(Scene::load(write_file(&dir, "valid.gltf", &valid).to_str().unwrap()).is_ok());
    // Each group takes the valid file (or the writer's .glb) and breaks one thing.
    truncated_glb_and_malformed_json(&dir, &valid);
    accessors_and_views_out_of_bounds(&dir, &valid);
    non_finite_positions(&dir, &valid);
    missing_and_bad_buffers(&dir, &valid);
    missing_and_undecodable_images(&dir);
    indices_out_of_range_or_not_whole_triangles(&dir, &valid);
    unsupported_extensions_and_bad_nodes(&dir);
    animation_times_not_increasing(&dir, &valid);
}

/// The nodes of `triangle_file`'s valid file: one drawing mesh 0.
fn ok_nodes() -> serde_json::Value {
    json!([{ "mesh": 0 }])
}

/// A truncated .glb, malformed JSON and glTF the parser refuses.
fn truncated_glb_and_malformed_json(dir: &Path, valid: &str) {
    // A truncated .glb.
    let glb_path = dir.join("whole.glb");
    write(&source_scene(), &glb_path, &WriteOptions::default()).unwrap();
    let glb = std::fs::read(&glb_path).unwrap();
    for cut in [6, 20, glb.len() / 2, glb.len() - 1] {
        let e = load_error(dir, "cut.glb", &glb[..cut]);
        assert!(e.contains("truncated .glb"), "{cut}: {e}");
    }
    // Malformed JSON: the parser's message with its line and column.
    let e = load_error(dir, "broken.gltf", &valid[..valid.len() - 10]);
    assert!(e.contains("not valid glTF JSON") && e.contains("line 1"), "{e}");
    let e = load_error(
        dir,
        "notgltf.gltf",
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 7}], \"scenes\": [{\"nodes\": [0]}]}",
    );
    assert!(e.contains("invalid glTF") && e.contains("nodes[0].mesh"), "{e}");
}

/// Accessors past the end of their view, absurd counts, bad strides; a view past the
/// end of its buffer.
fn accessors_and_views_out_of_bounds(dir: &Path, valid: &str) {
    let with_accessor = |accessor: serde_json::Value| {
        let mut body: serde_json::Value = serde_json::from_str(valid).unwrap();
        body["accessors"][0] = accessor;
        // POSITION needs bounds to pass the parser's validation.
        body["accessors"][0]["min"] = json!([0, 0, 0]);
        body["accessors"][0]["max"] = json!([1, 1, 0]);
        body.to_string()
    };
    let e = load_error(
        dir,
        "long.gltf",
        with_accessor(json!({ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3" })),
    );
    assert!(e.contains("accessor 0 (4 elements) runs past the end of buffer view 0"), "{e}");
    let e = load_error(
        dir,
        "offset.gltf",
        with_accessor(json!({ "bufferView": 0, "byteOffset": 4, "componentType": 5126, "count": 3, "type": "VEC3" })),
    );
    assert!(e.contains("runs past the end"), "{e}");
    let e = load_error(
        dir,
        "huge.gltf",
        with_accessor(json!({ "bufferView": 0, "componentType": 5126, "count": 4_000_000_000u64, "type": "VEC3" })),
    );
    assert!(e.contains("declares 4000000000 elements"), "{e}");
    let mut body: serde_json::Value = serde_json::from_str(valid).unwrap();
    body["bufferViews"][0]["byteLength"] = json!(400);
    let e = load_error(dir, "view.gltf", body.to_string());
    assert!(e.contains("buffer view 0 (bytes 0..+400) runs past the end of buffer 0 (36 bytes)"), "{e}");
}

/// NaN and infinite positions.
fn non_finite_positions(dir: &Path, valid: &str) {
    for (name, bad) in [("nan.gltf", f32::NAN), ("inf.gltf", f32::INFINITY)] {
        let mut bytes = triangle_bytes();
        bytes[12..16].copy_from_slice(&bad.to_le_bytes());
        let mut body: serde_json::Value = serde_json::from_str(valid).unwrap();
        body["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", encode_base64(&bytes)));
        let e = load_error(dir, name, body.to_string());
        assert!(e.contains("POSITION: accessor 0 element 1 is not finite"), "{e}");
    }
}

/// Missing buffer file, bad data URI, a buffer shorter than declared, a buffer without a
/// URI outside a .glb.
fn missing_and_bad_buffers(dir: &Path, valid: &str) {
    let mut body: serde_json::Value = serde_json::from_str(valid).unwrap();
    body["buffers"][0]["uri"] = json!("missing.bin");
    let e = load_error(dir, "nobuffer.gltf", body.to_string());
    assert!(e.contains("buffer 0: file 'missing.bin' not found"), "{e}");
    body["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@");
    let e = load_error(dir, "baduri.gltf", body.to_string());
    assert!(e.contains("buffer 0: data URI holds invalid base64"), "{e}");
    body["buffers"][0]["uri"] = json!("data:text/plain,hello");
    let e = load_error(dir, "plainuri.gltf", body.to_string());
    assert!(e.contains("not base64"), "{e}");
    body["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", encode_base64(&[0; 12])));
    let e = load_error(dir, "short.gltf", body.to_string());
    assert!(e.contains("buffer 0 has 12 bytes, the file says 36"), "{e}");
    let mut glb_without_bin: serde_json::Value = serde_json::from_str(valid).unwrap();
    glb_without_bin["buffers"][0] = json!({ "byteLength": 36 });
    let e = load_error(dir, "nobin.gltf", glb_without_bin.to_string());
    assert!(e.contains("binary chunk, which is missing"), "{e}");
}

/// Missing and undecodable images.
fn missing_and_undecodable_images(dir: &Path) {
    let textured = |uri: &str| {
        triangle_file(
            ok_nodes(),
            json!({
                "materials": [{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }],
                "textures": [{ "source": 0 }],
                "images": [{ "uri": uri }],
            }),
        )
        .replace("\"attributes\"", "\"material\":0,\"attributes\"")
    };
    let e = load_error(dir, "noimage.gltf", textured("missing.png"));
    assert!(e.contains("image 0: file 'missing.png' not found"), "{e}");
    let e =
        load_error(dir, "badimage.gltf", textured(&format!("data:image/png;base64,{}", encode_base64(b"not a png"))));
    assert!(e.contains("image 0: cannot decode"), "{e}");
}

/// Indices out of range, or not whole triangles.
fn indices_out_of_range_or_not_whole_triangles(dir: &Path, valid: &str) {
    let mut bytes = triangle_bytes();
    bytes.extend([0u8, 1, 3, 0]);
    let mut body: serde_json::Value = serde_json::from_str(valid).unwrap();
    body["buffers"][0] =
        json!({ "byteLength": 40, "uri": format!("data:application/octet-stream;base64,{}", encode_base64(&bytes)) });
    push(&mut body["bufferViews"], json!({ "buffer": 0, "byteOffset": 36, "byteLength": 3 }));
    push(&mut body["accessors"], json!({ "bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR" }));
    body["meshes"][0]["primitives"][0]["indices"] = json!(1);
    let e = load_error(dir, "index.gltf", body.to_string());
    assert!(e.contains("index 3 at 2 is out of range (3 vertices)"), "{e}");
    body["accessors"][1]["count"] = json!(2);
    let e = load_error(dir, "partial.gltf", body.to_string());
    assert!(e.contains("2 indices, not a whole number of triangles"), "{e}");
}

/// Required extensions vrao lacks; node cycles; too many nodes; a rotation that is not a
/// quaternion.
fn unsupported_extensions_and_bad_nodes(dir: &Path) {
    let e = load_error(
        dir,
        "draco.gltf",
        triangle_file(
            ok_nodes(),
            json!({ "extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"] }),
        ),
    );
    assert!(e.contains("requires extension KHR_draco_mesh_compression, which vrao does not support"), "{e}");
    let e = load_error(
        dir,
        "cycle.gltf",
        triangle_file(json!([{ "children": [1] }, { "children": [0], "mesh": 0 }]), json!({})),
    );
    assert!(e.contains("is reached twice"), "{e}");
    let many: Vec<serde_json::Value> = (0..100_001).map(|_| json!({})).collect();
    let e = load_error(dir, "many.gltf", triangle_file(json!(many), json!({})));
    assert!(e.contains("100001 nodes, more than vrao's limit of 100000"), "{e}");
    let e = load_error(dir, "notrs.gltf", triangle_file(json!([{ "rotation": [0, 0, 0, 0], "mesh": 0 }]), json!({})));
    assert!(e.contains("is not a quaternion"), "{e}");
}

/// Animation key times that are not increasing.
fn animation_times_not_increasing(dir: &Path, valid: &str) {
    let mut bytes = triangle_bytes();
    bytes.extend(bytemuck::cast_slice::<f32, u8>(&[1.0, 0.5, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]));
    let mut body: serde_json::Value = serde_json::from_str(valid).unwrap();
    body["buffers"][0] = json!({ "byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{}", encode_base64(&bytes)) });
    body["bufferViews"] = json!([{ "buffer": 0, "byteLength": 36 }, { "buffer": 0, "byteOffset": 36, "byteLength": 12 }, { "buffer": 0, "byteOffset": 48, "byteLength": 24 }]);
    push(
        &mut body["accessors"],
        json!({ "bufferView": 1, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0], "max": [1] }),
    );
    push(&mut body["accessors"], json!({ "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3" }));
    body["animations"] = json!([{ "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }],
                                  "samplers": [{ "input": 1, "output": 2 }] }]);
    let e = load_error(dir, "times.gltf", body.to_string());
    assert!(e.contains("animation 0 channel 0: key times 1 then 0.5 are not increasing"), "{e}");
}

#[test]
fn unknown_optional_extensions_and_skins_still_load() {
    let dir = common::temp_dir("gltf-optional");
    let text =
        triangle_file(json!([{ "mesh": 0 }]), json!({ "extensionsUsed": ["KHR_materials_clearcoat", "EXT_foo"] }));
    let scene = Scene::load(write_file(&dir, "o.gltf", text).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 1);
}

#[test]
fn mesh_quantization_positions_decode() {
    // KHR_mesh_quantization: u16 positions (not normalised) and normalised i8 normals.
    let dir = common::temp_dir("gltf-quantized");
    let positions: [u16; 12] = [0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0];
    let normals: [i8; 12] = [0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0];
    let mut bytes = bytemuck::cast_slice::<u16, u8>(&positions).to_vec();
    bytes.extend(normals.iter().map(|&n| n as u8));
    let body = json!({
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1 } }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5123, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [2, 2, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3" },
        ],
        "bufferViews": [{ "buffer": 0, "byteLength": 24, "byteStride": 8 }, { "buffer": 0, "byteOffset": 24, "byteLength": 12, "byteStride": 4 }],
    });
    let scene = Scene::load(write_file(&dir, "q.gltf", gltf_text(&bytes, body)).to_str().unwrap()).unwrap();
    let m = &scene.meshes[0];
    let world: Vec<DVec3> = m.positions.iter().map(|p| m.origin + p.as_dvec3()).collect();
    assert_eq!(world, vec![DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0)]);
    assert!(m.normals.iter().all(|n| *n == Vec3::Z), "{:?}", m.normals);
}

#[test]
fn sibenik_as_glb_gives_the_objs_g_buffer() {
    use vrao_ao::plug::{DEPTH, FINAL_AO, NORMALS};
    use vrao_render::{HeadsetProfile, Renderer, Settings};
    let Some(obj) = common::public_scene("sibenik/sibenik.obj") else { return };
    let dir = common::temp_dir("gltf-sibenik");
    let from_obj = Scene::load(obj.to_str().unwrap()).unwrap();
    let glb = dir.join("sibenik.glb");
    write(&from_obj, &glb, &WriteOptions::default()).unwrap();
    let from_glb = Scene::load(glb.to_str().unwrap()).unwrap();
    assert_eq!(from_glb.triangle_count(), from_obj.triangle_count());
    assert!(from_glb.nodes.is_empty() && !from_glb.has_alpha_test());
    // The same meshes, bit for bit: the writer picks the f32 coordinates that recentre
    // back into the OBJ's offsets, and unit normals keep their bits.
    assert_eq!(from_glb.meshes.len(), from_obj.meshes.len());
    for (a, b) in from_obj.meshes.iter().zip(&from_glb.meshes) {
        assert_eq!(a.origin, b.origin, "{}", a.name);
        assert_eq!(a.positions, b.positions, "{}", a.name);
        assert_eq!(a.normals, b.normals, "{}", a.name);
        assert_eq!(a.indices, b.indices, "{}", a.name);
    }

    let (gpu, _guard) = common::gpu();
    let (w, h) = (96, 108);
    let settings = Settings { profile: HeadsetProfile::with_size("test", w, h), ..Settings::default() };
    let render = |scene: &Scene| {
        let mut renderer = Renderer::new(gpu.clone(), scene, &settings).unwrap();
        // Standing in the nave (assets/scenes/sibenik.toml's head), looking at the altar.
        let head = HeadPose::look_at(DVec3::new(-14.0, -13.6, 0.0), DVec3::new(6.0, -12.0, 0.0)).unwrap();
        let eyes = settings.profile.eyes(&head, settings.near);
        renderer.render_and_wait(&eyes.eyes, &[DEPTH, NORMALS, FINAL_AO]).unwrap();
        [DEPTH, NORMALS, FINAL_AO].map(|r| renderer.read_f32(r).unwrap())
    };
    let [a_depth, a_normals, a_ao] = render(&from_obj);
    let [b_depth, b_normals, b_ao] = render(&from_glb);
    let max_diff = |a: &[Vec<f32>], b: &[Vec<f32>]| {
        a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max)
    };
    let covered = a_depth.iter().flatten().filter(|&&d| d > 0.0).count();
    assert_eq!(covered, 2 * (w * h) as usize, "the nave fills both eyes");
    let (depth, normals, ao) = (max_diff(&a_depth, &b_depth), max_diff(&a_normals, &b_normals), max_diff(&a_ao, &b_ao));
    eprintln!("sibenik .glb vs .obj: max |Δdepth| {depth:e}, |Δnormal| {normals:e}, |ΔAO| {ao:e}");
    assert!(depth <= 1e-5, "depth differs by {depth}");
    assert!(normals <= 1e-5, "normals differ by {normals}");
    assert_eq!(ao, 0.0, "AO differs by {ao}");
}

#[test]
fn obj_map_d_and_d_become_alpha() {
    let dir = common::temp_dir("obj-alpha");
    // A 2×2 alpha map (grey, no alpha channel) and a 4×4 diffuse texture: resampled nearest.
    image::GrayImage::from_raw(2, 2, vec![0, 255, 255, 0]).unwrap().save(dir.join("mask.png")).unwrap();
    image::RgbaImage::from_pixel(4, 4, image::Rgba([10, 20, 30, 255])).save(dir.join("colour.png")).unwrap();
    std::fs::write(
        dir.join("a.mtl"),
        "newmtl cut\nmap_Kd colour.png\nmap_d mask.png\nnewmtl bare\nmap_d -clamp on mask.png\n\
         newmtl glass\nd 0.25\nnewmtl tr\nTr 0.5\nnewmtl solid\nd 1\n",
    )
    .unwrap();
    let mut obj = String::from("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for m in ["cut", "bare", "glass", "tr", "solid"] {
        obj.push_str(&format!("usemtl {m}\nf 1 2 3\n"));
    }
    let scene = Scene::load(write_file(&dir, "a.obj", obj).to_str().unwrap()).unwrap();
    let cut = material(&scene, "cut");
    assert_eq!(cut.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    let t = cut.diffuse_texture.as_ref().unwrap();
    assert_eq!((t.width, t.height), (4, 4));
    let alphas: Vec<u8> = t.rgba8.chunks(4).map(|c| c[3]).collect();
    assert_eq!(alphas, [0, 0, 255, 255, 0, 0, 255, 255, 255, 255, 0, 0, 255, 255, 0, 0]);
    assert_eq!(&t.rgba8[..3], &[10, 20, 30], "colour kept");
    // OBJ textures tile on both axes (V was clamped).
    assert_eq!(
        (t.sampling.wrap_u, t.sampling.wrap_v),
        (vrao_render::scene::Wrap::Repeat, vrao_render::scene::Wrap::Repeat)
    );
    let bare = material(&scene, "bare").diffuse_texture.as_ref().unwrap();
    assert_eq!((bare.width, bare.height, &bare.rgba8[..8]), (2, 2, &[255, 255, 255, 0, 255, 255, 255, 255][..]));
    assert_eq!((material(&scene, "glass").alpha, material(&scene, "glass").alpha_mode), (0.25, AlphaMode::Blend));
    assert_eq!((material(&scene, "tr").alpha, material(&scene, "tr").alpha_mode), (0.5, AlphaMode::Blend));
    assert_eq!((material(&scene, "solid").alpha, material(&scene, "solid").alpha_mode), (1.0, AlphaMode::Opaque));
    assert!(scene.has_alpha_test());

    for (mtl, expected) in [
        ("newmtl x\nd 1.5\n", "bad.mtl:2: d 1.5 is not in [0, 1]"),
        ("newmtl x\nTr -0.5\n", "bad.mtl:2: Tr -0.5 is not in [0, 1]"),
        ("newmtl x\nmap_d gone.png\n", "bad.mtl:2: texture file 'gone.png' not found"),
        ("newmtl x\nmap_d\n", "bad.mtl:2: map_d needs a texture file name"),
    ] {
        std::fs::write(dir.join("bad.mtl"), mtl).unwrap();
        let path = write_file(&dir, "bad.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
        let e = Scene::load(path.to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains(expected), "{e}");
    }
}

#[test]
fn scene_files_place_gltf_and_animate_meshes() {
    let dir = common::temp_dir("gltf-scene-file");
    let source = source_scene();
    write(&source, &dir.join("thing.glb"), &WriteOptions::default()).unwrap();
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let toml = r#"
[[mesh]]
gltf = "thing.glb"
translate = [10, 0, 0]

[[mesh]]
obj = "tri.obj"
translate = [0, 0, -5]
animation = { interpolation = "linear", keys = [
    { t = 0.0, translate = [0, 0, 0], rotate_deg = [0, 0, 0] },
    { t = 4.0, translate = [2, 0, 0], rotate_deg = [0, 0, 90] } ] }
"#;
    let path = write_file(&dir, "s.toml", toml);
    let scene = Scene::load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.meshes.len(), source.meshes.len() + 1);
    // The glTF's meshes, static and moving, 10 m along x at every time.
    for t in [0.0, 0.7, 1.9] {
        let placed = corners(&scene, t);
        for (name, expected) in corners(&source, t) {
            let got = &placed.iter().find(|(n, _)| *n == name).unwrap().1;
            for (a, b) in expected.iter().zip(got) {
                assert!((a.0 + DVec3::new(10.0, 0.0, 0.0) - b.0).length() < 1e-5, "{name} t={t}: {} vs {}", a.0, b.0);
            }
        }
    }
    // The OBJ triangle at t = 2 (half way): turned 45° about z, moved 1 m, then placed.
    let tri = corners(&scene, 2.0).into_iter().find(|(n, _)| n == "unnamed_object" || n.is_empty() || n == "tri");
    let (_, corners_at_2) =
        tri.unwrap_or_else(|| panic!("{:?}", scene.meshes.iter().map(|m| &m.name).collect::<Vec<_>>()));
    let turn = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4);
    let expected = [DVec3::ZERO, DVec3::X, DVec3::Y].map(|p| turn * p + DVec3::new(1.0, 0.0, -5.0));
    for (c, e) in corners_at_2.iter().zip(expected) {
        assert!((c.0 - e).length() < 1e-6, "{} vs {e}", c.0);
    }
    assert!(scene.is_animated());
    assert_eq!(scene.animation_period(), 4.0);

    for (animation, expected) in [
        ("{ keys = [] }", "needs 1 to 10000 keys, found 0"),
        (
            "{ keys = [{ t = 1.0, translate = [0, 0, 0] }, { t = 1.0, translate = [1, 0, 0] }] }",
            "1 then 1 are not strictly increasing",
        ),
        ("{ keys = [{ t = -1.0, translate = [0, 0, 0] }] }", "key time -1 must be finite"),
        ("{ keys = [{ t = 0.0, translate = [0, 0, 0] }, { t = 1.0 }] }", "translate is given in 1 of 2 keys"),
        ("{ keys = [{ t = 0.0 }] }", "give none of translate"),
        ("{ interpolation = \"cubic\", keys = [{ t = 0.0, scale = 1 }] }", "interpolation 'cubic'"),
        ("{ keys = [{ t = 0.0, scale = 1 }], speed = 2 }", "unknown field `speed`"),
    ] {
        let text = format!("\n[[mesh]]\nobj = \"tri.obj\"\nanimation = {animation}\n");
        let e = Scene::load(write_file(&dir, "bad.toml", text).to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains("bad.toml:") && e.contains(expected), "{animation}: {e}");
    }
    let e = Scene::load(write_file(&dir, "nog.toml", "[[mesh]]\ngltf = \"none.glb\"\n").to_str().unwrap()).unwrap_err();
    assert!(e.to_string().contains("nog.toml:1: mesh gltf 'none.glb' not found"), "{e}");
}

#[test]
fn a_spot_light_lights_its_cone_with_gltfs_falloff_on_the_gpu() {
    use vrao_render::passes::composite::HDR;
    use vrao_render::{HeadsetProfile, Renderer, Settings};
    let (intensity, inner, outer) = (8.0f32, 0.1f32, 0.7f32);
    let mut floor = common::square("floor", DVec3::ZERO, 8.0, 0);
    // Turn the square (facing +Z) to face up.
    floor.positions.iter_mut().for_each(|p| *p = Vec3::new(p.x, 0.0, -p.y));
    floor.normals = vec![Vec3::Y; 4];
    let mut scene = common::bare_scene(vec![floor]);
    scene.lights = vec![Light::Spot {
        position: DVec3::new(0.0, 2.0, 0.0),
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity,
        inner_cone: inner,
        outer_cone: outer,
    }];
    let (gpu, _guard) = common::gpu();
    let (w, h) = (96, 108);
    let settings = Settings { profile: HeadsetProfile::with_size("test", w, h), ..Settings::default() };
    let head = HeadPose::look_at(DVec3::new(0.0, 3.0, 2.0), DVec3::ZERO).unwrap();
    let eyes = settings.profile.eyes(&head, settings.near);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings).unwrap();
    renderer.render_and_wait(&eyes.eyes, &[HDR]).unwrap();
    let hdr = renderer.read_f32(HDR).unwrap();
    let radiance_at = |p: DVec3| {
        let (uv, _) = eyes.eyes[0].project(p, settings.near).unwrap();
        let (x, y) = ((uv[0] * w as f64) as usize, (uv[1] * h as f64) as usize);
        hdr[0][4 * (y * w as usize + x)]
    };
    // albedo/π × I × falloff × cos / d² at a floor point `angle` off the spot's axis.
    let expected = |angle: f32| {
        let (cos_outer, scale) = vrao_render::scene::spot_ramp(inner, outer);
        let ramp = ((angle.cos() - cos_outer) * scale).clamp(0.0, 1.0);
        let d = 2.0 / angle.cos();
        0.5 / std::f32::consts::PI * intensity * ramp * ramp * angle.cos() / (d * d)
    };
    for angle in [0.0f32, 0.3, 0.45] {
        let got = radiance_at(DVec3::new((2.0 * angle.tan()) as f64, 0.0, 0.0));
        let want = expected(angle);
        assert!((got - want).abs() <= 0.08 * want, "{angle} rad off the axis: {got}, expected {want}");
    }
    assert_eq!(radiance_at(DVec3::new(2.0 * 0.8f64.tan(), 0.0, 0.0)), 0.0, "outside the outer cone");
    assert!(
        (vrao_render::scene::spot_falloff(0.3f32.cos(), inner, outer) - {
            let r: f32 = (0.3f32.cos() - outer.cos()) / (inner.cos() - outer.cos());
            r * r
        })
        .abs()
            < 1e-6
    );
}

#[test]
fn strips_and_fans_become_triangles_and_points_and_lines_are_skipped() {
    let dir = common::temp_dir("gltf-modes");
    // A unit quad in z = 0 as a strip (0 1 2 3: two triangles) and as a fan (0 1 3 2),
    // each facing +z, and the same vertices as lines and as points.
    let p: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0];
    let fan_order: [u16; 4] = [0, 1, 3, 2];
    let mut bin: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    bin.extend(bytemuck::cast_slice(&fan_order));
    let primitive = |mode: u32, indices: Option<u32>| {
        let mut p = json!({ "attributes": { "POSITION": 0 }, "mode": mode });
        if let Some(i) = indices {
            p["indices"] = json!(i);
        }
        p
    };
    let body = json!({
        "scene": 0,
        "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [2, 0, 0] }],
        "meshes": [
            { "name": "strip", "primitives": [primitive(5, None), primitive(1, None), primitive(0, None)] },
            { "name": "fan", "primitives": [primitive(6, Some(1)), primitive(3, None)] },
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5123, "count": 4, "type": "SCALAR" },
        ],
        "bufferViews": [{ "buffer": 0, "byteLength": 48 }, { "buffer": 0, "byteOffset": 48, "byteLength": 8 }],
    });
    let path = write_file(&dir, "modes.gltf", gltf_text(&bin, body));
    let scene = Scene::load(path.to_str().unwrap()).unwrap();
    // The lines and points primitives are gone; the strip and the fan are two triangles each.
    assert_eq!(scene.meshes.len(), 2, "{:?}", scene.meshes.iter().map(|m| &m.name).collect::<Vec<_>>());
    for mesh in &scene.meshes {
        assert_eq!(mesh.indices.len(), 6, "{}", mesh.name);
        let mut area = 0.0;
        for t in mesh.indices.chunks(3) {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
            let normal = (b - a).cross(c - a);
            assert!(normal.z > 0.0, "{}: triangle {t:?} faces {normal}", mesh.name);
            area += normal.length() / 2.0;
        }
        assert!((area - 1.0).abs() < 1e-6, "{}: the triangles cover {area}, not the unit quad", mesh.name);
    }
}
