//! glTF accessors, on hand-written files: `KHR_mesh_quantization` (every component type
//! the extension allows for each attribute decodes as the spec's equations say; the
//! others are refused with one line naming the accessor), sparse accessors (over a
//! buffer view and over zeros, for vertices, indices and animation keys; bad indices and
//! ranges refused), offsets near 2⁶⁴, and the images the `gltf` crate would panic on.

use serde_json::{json, Value};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use vrao::test_assets::fuzz::{load_bytes, Mutator, Target};
use vrao::test_assets::gltf_write::encode_base64;
use vrao_render::scene::Scene;

/// A fresh, empty directory for one test's files, removed when the test passes.
fn temp_dir(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("accessors-{name}"))
}

/// A component type, as glTF numbers it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ty {
    F32,
    I8,
    U8,
    I16,
    U16,
    U32,
}

impl Ty {
    const ALL: [Ty; 6] = [Ty::F32, Ty::I8, Ty::U8, Ty::I16, Ty::U16, Ty::U32];

    fn code(self) -> u32 {
        match self {
            Ty::I8 => 5120,
            Ty::U8 => 5121,
            Ty::I16 => 5122,
            Ty::U16 => 5123,
            Ty::U32 => 5125,
            Ty::F32 => 5126,
        }
    }

    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::U32 | Ty::F32 => 4,
        }
    }

    fn bytes(self, value: f64) -> Vec<u8> {
        match self {
            Ty::F32 => (value as f32).to_le_bytes().to_vec(),
            Ty::I8 => (value as i8).to_le_bytes().to_vec(),
            Ty::U8 => (value as u8).to_le_bytes().to_vec(),
            Ty::I16 => (value as i16).to_le_bytes().to_vec(),
            Ty::U16 => (value as u16).to_le_bytes().to_vec(),
            Ty::U32 => (value as u32).to_le_bytes().to_vec(),
        }
    }

    /// The most negative and the largest value (for floats, -1 and 1).
    fn range(self) -> (f64, f64) {
        match self {
            Ty::F32 => (-1.0, 1.0),
            Ty::I8 => (-128.0, 127.0),
            Ty::U8 => (0.0, 255.0),
            Ty::I16 => (-32768.0, 32767.0),
            Ty::U16 => (0.0, 65535.0),
            Ty::U32 => (0.0, 4294967295.0),
        }
    }

    /// A stored value as glTF reads it: KHR_mesh_quantization's int-to-float table when
    /// normalised, the value itself otherwise (computed in f32, as a GPU would).
    fn decode(self, raw: f64, normalized: bool) -> f32 {
        match (self, normalized) {
            (Ty::F32, _) | (_, false) => raw as f32,
            (Ty::I8, true) => (raw as f32 / 127.0).max(-1.0),
            (Ty::U8, true) => raw as f32 / 255.0,
            (Ty::I16, true) => (raw as f32 / 32767.0).max(-1.0),
            (Ty::U16, true) => raw as f32 / 65535.0,
            (Ty::U32, true) => raw as f32 / 4294967295.0,
        }
    }
}

/// Elements of `components` values of type `ty`, vectors padded to 4 bytes as glTF's
/// alignment rules ask for vertex attributes (scalars tightly packed), with the stride.
fn pack(ty: Ty, components: usize, values: &[f64]) -> (Vec<u8>, usize) {
    let element = components * ty.size();
    let stride = if components == 1 { element } else { element.div_ceil(4) * 4 };
    let mut bytes = Vec::new();
    for chunk in values.chunks(components) {
        chunk.iter().for_each(|&v| bytes.extend(ty.bytes(v)));
        bytes.resize(bytes.len() + stride - element, 0);
    }
    (bytes, stride)
}

/// A glTF being written: one buffer (a data URI) of 4-byte-aligned views.
#[derive(Default)]
struct Gltf {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Gltf {
    fn view(&mut self, data: &[u8], stride: Option<usize>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut view = json!({ "buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len() });
        if let Some(stride) = stride {
            view["byteStride"] = json!(stride);
        }
        self.bytes.extend(data);
        self.views.push(view);
        self.views.len() - 1
    }

    fn accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A view of `values` and an accessor reading them (`kind` "VEC3", ...). Vertex
    /// attributes (more than one component) get a byteStride.
    fn data(&mut self, ty: Ty, normalized: bool, kind: &str, values: &[f64]) -> usize {
        let components = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let (bytes, stride) = pack(ty, components, values);
        let view = self.view(&bytes, (components > 1).then_some(stride));
        let mut accessor =
            json!({ "bufferView": view, "componentType": ty.code(), "count": values.len() / components, "type": kind });
        if normalized {
            accessor["normalized"] = json!(true);
        }
        if kind == "VEC3" {
            let column = |j: usize| values.iter().skip(j).step_by(3).copied();
            let min: Vec<f64> = (0..3).map(|j| column(j).fold(f64::INFINITY, f64::min)).collect();
            let max: Vec<f64> = (0..3).map(|j| column(j).fold(f64::NEG_INFINITY, f64::max)).collect();
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.accessor(accessor)
    }

    /// The file: one mesh of `primitive`, drawn by node 0 (`node` adds to it), `extra`
    /// adds top-level members (animations, materials, extensions).
    fn text(&self, primitive: Value, node: Value, extra: Value) -> String {
        let mut node0 = json!({ "mesh": 0 });
        node0.as_object_mut().unwrap().extend(node.as_object().unwrap().clone());
        let mut body = json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": [0] }],
            "nodes": [node0],
            "meshes": [{ "primitives": [primitive] }],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{
                "byteLength": self.bytes.len(),
                "uri": format!("data:application/octet-stream;base64,{}", encode_base64(&self.bytes)),
            }],
        });
        body.as_object_mut().unwrap().extend(extra.as_object().unwrap().clone());
        body.to_string()
    }
}

fn write_file(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn load(dir: &Path, name: &str, text: &str) -> vrao_ao::Result<Scene> {
    vrao_render::scene::gltf::load(&write_file(dir, name, text))
}

/// The error of a load that must fail: one line naming the file.
fn load_error(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    let message = match load(dir, name, text) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => e.to_string(),
    };
    assert!(message.starts_with(&path.display().to_string()), "{name}: the error names the file: {message}");
    assert!(!message.contains('\n'), "{name}: one line: {message}");
    message
}

/// World positions of a static mesh.
fn world(scene: &Scene, mesh: usize) -> Vec<[f64; 3]> {
    let m = &scene.meshes[mesh];
    m.positions.iter().map(|p| (m.origin + p.as_dvec3()).to_array()).collect()
}

/// The world positions of a static mesh's triangle corners, in drawing order (normals
/// computed for a file without them may reorder vertices, not corners).
fn drawn(scene: &Scene, mesh: usize) -> Vec<[f64; 3]> {
    let points = world(scene, mesh);
    scene.meshes[mesh].indices.iter().map(|&i| points[i as usize]).collect()
}

fn assert_close(found: &[[f64; 3]], expected: &[[f64; 3]], what: &str) {
    assert_eq!(found.len(), expected.len(), "{what}");
    let extent = expected.iter().flatten().fold(1.0f64, |m, v| m.max(v.abs()));
    for (f, e) in found.iter().zip(expected) {
        for j in 0..3 {
            // Positions are f32 offsets from an f64 origin.
            assert!((f[j] - e[j]).abs() <= 2e-7 * extent, "{what}: {found:?} != {expected:?}");
        }
    }
}

const TRIANGLE: [f64; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
const UP: [f64; 9] = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];

#[test]
fn quantized_quad_decodes_as_the_spec_says() {
    // The quantized Avocado's and Duck's layout: i16 normalised positions dequantized by
    // the node's scale and translation, i8 normalised normals, u16 texture coordinates
    // that are not normalised.
    let dir = temp_dir("quad");
    let mut g = Gltf::default();
    let positions = [-32768.0, -32767.0, 0.0, 32767.0, -16384.0, 0.0, 16384.0, 32767.0, 0.0, -100.0, 32767.0, 0.0];
    let normals = [0.0, 0.0, 127.0, 0.0, 0.0, 127.0, 0.0, 0.0, 127.0, 0.0, 0.0, 127.0];
    let uvs = [0.0, 0.0, 1000.0, 0.0, 1000.0, 500.0, 0.0, 65535.0];
    let position = g.data(Ty::I16, true, "VEC3", &positions);
    let normal = g.data(Ty::I8, true, "VEC3", &normals);
    let uv = g.data(Ty::U16, false, "VEC2", &uvs);
    let index = g.data(Ty::U16, false, "SCALAR", &[0.0, 1.0, 2.0, 0.0, 2.0, 3.0]);
    let text = g.text(
        json!({ "attributes": { "POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv }, "indices": index }),
        json!({ "scale": [2.0, 2.0, 2.0], "translation": [1.0, 0.0, -3.0] }),
        json!({ "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"] }),
    );
    let scene = load(&dir, "quad.gltf", &text).unwrap();
    assert_eq!(scene.meshes.len(), 1);
    let m = &scene.meshes[0];
    assert_eq!(m.indices, [0, 1, 2, 0, 2, 3]);
    let expected: Vec<[f64; 3]> = positions
        .chunks(3)
        .map(|p| {
            let q = |c: f64| Ty::I16.decode(c, true) as f64;
            [1.0 + 2.0 * q(p[0]), 2.0 * q(p[1]), -3.0 + 2.0 * q(p[2])]
        })
        .collect();
    // max(c / 32767, -1): -32768 and -32767 both give -1, then scaled and moved.
    assert_eq!(expected[0], [-1.0, -2.0, -3.0]);
    assert_close(&world(&scene, 0), &expected, "positions");
    let uvs_found: Vec<[f32; 2]> = m.uvs.iter().map(|t| t.to_array()).collect();
    assert_eq!(uvs_found, [[0.0, 0.0], [1000.0, 0.0], [1000.0, 500.0], [0.0, 65535.0]]);
    assert!(m.normals.iter().all(|n| n.to_array() == [0.0, 0.0, 1.0]), "{:?}", m.normals);
}

/// Which component types glTF allows per attribute: (normalised, not normalised).
/// KHR_mesh_quantization's table for POSITION, NORMAL, TANGENT and TEXCOORD_n; glTF 2.0's
/// for COLOR_n. Float is always allowed; u32 never.
fn allowed(attribute: &str, ty: Ty, normalized: bool) -> bool {
    let (n, plain): (&[Ty], &[Ty]) = match attribute {
        "POSITION" | "TEXCOORD_0" => (&[Ty::I8, Ty::U8, Ty::I16, Ty::U16], &[Ty::I8, Ty::U8, Ty::I16, Ty::U16]),
        "NORMAL" | "TANGENT" => (&[Ty::I8, Ty::I16], &[]),
        "COLOR_0" => (&[Ty::U8, Ty::U16], &[]),
        _ => unreachable!(),
    };
    ty == Ty::F32 || if normalized { n } else { plain }.contains(&ty)
}

/// Three elements of `components` values for `attribute` stored as `ty`: the type's
/// extremes and a middle value, or (normals, tangents) axis vectors at the extremes, so
/// that normalised ones decode to unit length.
fn sample(attribute: &str, ty: Ty, components: usize) -> Vec<f64> {
    let (lo, hi) = ty.range();
    let mid = (hi / 3.0).round();
    match attribute {
        "NORMAL" => vec![hi, 0.0, 0.0, 0.0, lo, 0.0, 0.0, 0.0, hi],
        "TANGENT" => vec![hi, 0.0, 0.0, hi, 0.0, lo, 0.0, lo, 0.0, 0.0, hi, hi],
        _ => [lo, hi, mid, 0.0, hi, lo, mid, 1.0, hi, lo, mid, 0.0].into_iter().take(3 * components).collect(),
    }
}

/// The attributes whose component types are tried, with their accessor types.
const QUANTIZED_ATTRIBUTES: [(&str, &str); 6] = [
    ("POSITION", "VEC3"),
    ("NORMAL", "VEC3"),
    ("TANGENT", "VEC4"),
    ("TEXCOORD_0", "VEC2"),
    ("COLOR_0", "VEC3"),
    ("COLOR_0", "VEC4"),
];

#[test]
fn every_component_type_an_attribute_allows_loads_and_the_others_are_refused() {
    let dir = temp_dir("types");
    let mut loaded = 0;
    let mut refused = 0;
    for (attribute, kind) in QUANTIZED_ATTRIBUTES {
        let components = kind[3..].parse::<usize>().unwrap();
        for ty in Ty::ALL {
            for normalized in [false, true] {
                if ty == Ty::F32 && normalized {
                    continue;
                }
                let values = sample(attribute, ty, components);
                let (text, tested) = quantized_triangle(attribute, kind, ty, normalized, &values);
                let name = format!("{attribute}-{kind}-{ty:?}-{}.gltf", if normalized { "n" } else { "u" });
                let decoded: Vec<f32> = values.iter().map(|&v| ty.decode(v, normalized)).collect();
                if !allowed(attribute, ty, normalized) {
                    let e = load_error(&dir, &name, &text);
                    let what = if normalized { "normalised" } else { "unnormalised" };
                    assert!(e.contains(&format!("{attribute}: accessor {tested} has {what} ")), "{name}: {e}");
                    refused += 1;
                    continue;
                }
                let scene = load(&dir, &name, &text).unwrap_or_else(|e| panic!("{name}: {e}"));
                assert_attribute_decoded(&scene, attribute, components, &decoded, &name);
                loaded += 1;
            }
        }
    }
    // Float plus: 8 for POSITION and TEXCOORD_0, 2 for NORMAL and TANGENT, 2 per COLOR_0 kind.
    assert_eq!(loaded, 9 + 3 + 3 + 9 + 3 + 3);
    assert_eq!(refused, 6 * 11 - loaded);
}

/// A quantised triangle whose `attribute` holds `values` as `kind` of `ty`, the other
/// attributes plain floats; returns the file and the tested accessor's index.
fn quantized_triangle(attribute: &str, kind: &str, ty: Ty, normalized: bool, values: &[f64]) -> (String, usize) {
    let mut g = Gltf::default();
    let position = match attribute {
        "POSITION" => g.data(ty, normalized, kind, values),
        _ => g.data(Ty::F32, false, "VEC3", &TRIANGLE),
    };
    let normal = match attribute {
        "NORMAL" => g.data(ty, normalized, kind, values),
        _ => g.data(Ty::F32, false, "VEC3", &UP),
    };
    let mut attributes = json!({ "POSITION": position, "NORMAL": normal });
    let tested = match attribute {
        "POSITION" => position,
        "NORMAL" => normal,
        _ => {
            let k = g.data(ty, normalized, kind, values);
            attributes[attribute] = json!(k);
            k
        }
    };
    let text = g.text(
        json!({ "attributes": attributes }),
        json!({}),
        json!({ "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"] }),
    );
    (text, tested)
}

/// The loaded mesh's `attribute` is `decoded` (colours: with alpha 1 for RGB, clamped).
fn assert_attribute_decoded(scene: &Scene, attribute: &str, components: usize, decoded: &[f32], name: &str) {
    let m = &scene.meshes[0];
    match attribute {
        "POSITION" => {
            let expected: Vec<[f64; 3]> = decoded.chunks(3).map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect();
            assert_close(&world(scene, 0), &expected, name);
        }
        "NORMAL" => {
            let found: Vec<f32> = m.normals.iter().flat_map(|n| n.to_array()).collect();
            assert_eq!(found, decoded, "{name}");
            assert_eq!(&found[..6], [1.0, 0.0, 0.0, 0.0, -1.0, 0.0], "{name}");
        }
        "TANGENT" => {
            let found: Vec<f32> = m.tangents.iter().flat_map(|t| t.to_array()).collect();
            assert!(found.is_empty() || found == decoded, "{name}: {found:?} != {decoded:?}");
        }
        "TEXCOORD_0" => {
            let found: Vec<f32> = m.uvs.iter().flat_map(|t| t.to_array()).collect();
            assert_eq!(found, decoded, "{name}");
        }
        _ => {
            // RGB gets alpha 1; a colour is clamped to [0, 1].
            let expected: Vec<f32> = decoded
                .chunks(components)
                .flat_map(|c| [c[0], c[1], c[2], c.get(3).copied().unwrap_or(1.0)])
                .map(|c| c.clamp(0.0, 1.0))
                .collect();
            let found: Vec<f32> = m.colors.iter().flat_map(|c| c.to_array()).collect();
            assert_eq!(found, expected, "{name}");
        }
    }
}

#[test]
fn accessor_types_that_do_not_fit_the_attribute_are_refused() {
    let dir = temp_dir("dimensions");
    for (attribute, kind, expected) in [
        ("NORMAL", "VEC4", "expected 3 components"),
        ("TEXCOORD_0", "VEC3", "expected 2 components"),
        ("COLOR_0", "VEC2", "accessor 2 is Vec2"),
        ("TANGENT", "VEC3", "expected 4 components"),
    ] {
        let mut g = Gltf::default();
        let position = g.data(Ty::F32, false, "VEC3", &TRIANGLE);
        let mut attributes = json!({ "POSITION": position });
        let n = if kind == "VEC4" { 12 } else { kind[3..].parse::<usize>().unwrap() * 3 };
        if attribute == "NORMAL" {
            attributes[attribute] = json!(g.data(Ty::F32, false, kind, &vec![0.5; n]));
        } else {
            g.data(Ty::F32, false, "VEC3", &UP);
            attributes[attribute] = json!(g.data(Ty::F32, false, kind, &vec![0.5; n]));
        }
        let e = load_error(
            &dir,
            &format!("{attribute}.gltf"),
            &g.text(json!({ "attributes": attributes }), json!({}), json!({})),
        );
        assert!(e.contains(&format!("{attribute}: accessor")) && e.contains(expected), "{attribute}: {e}");
    }
}

/// A triangle's file whose node 0 is animated by one channel reading `input` and `output`.
fn animated(g: &Gltf, path: &str, input: usize, output: usize) -> String {
    let mut g2 = Gltf { bytes: g.bytes.clone(), views: g.views.clone(), accessors: g.accessors.clone() };
    let position = g2.data(Ty::F32, false, "VEC3", &TRIANGLE);
    let animations = json!([{ "channels": [{ "sampler": 0, "target": { "node": 0, "path": path } }],
                              "samplers": [{ "input": input, "output": output }] }]);
    g2.text(json!({ "attributes": { "POSITION": position } }), json!({}), json!({ "animations": animations }))
}

#[test]
fn animation_keys_take_the_types_core_gltf_allows() {
    let dir = temp_dir("animation");
    // Rotations: float or any normalised 8- or 16-bit integer.
    let mut g = Gltf::default();
    let times = g.data(Ty::F32, false, "SCALAR", &[0.0, 1.0]);
    let rotation = g.data(Ty::I16, true, "VEC4", &[0.0, 0.0, 0.0, 32767.0, 0.0, -32768.0, 0.0, 0.0]);
    let scene = load(&dir, "rotation.gltf", &animated(&g, "rotation", times, rotation)).unwrap();
    let track = scene.nodes[0].tracks.rotation.as_ref().unwrap();
    assert_eq!(track.times, [0.0, 1.0]);
    assert_eq!(track.values[0].to_array(), [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(track.values[1].to_array(), [0.0, -1.0, 0.0, 0.0]);
    // Translation and scale: float only (normalised integers are rotation's and weights').
    let mut g = Gltf::default();
    let times = g.data(Ty::F32, false, "SCALAR", &[0.0, 1.0]);
    let translation = g.data(Ty::I16, true, "VEC3", &[0.0, 0.0, 0.0, 100.0, 0.0, 0.0]);
    let e = load_error(&dir, "translation.gltf", &animated(&g, "translation", times, translation));
    assert!(e.contains("animation 0 channel 0 output: accessor 1 has normalised i16"), "{e}");
    assert!(e.contains("takes f32"), "{e}");
    // Key times: float only.
    let mut g = Gltf::default();
    let times = g.data(Ty::U8, false, "SCALAR", &[0.0, 1.0]);
    let translation = g.data(Ty::F32, false, "VEC3", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
    let e = load_error(&dir, "times.gltf", &animated(&g, "translation", times, translation));
    assert!(e.contains("animation 0 channel 0 input: accessor 0 has unnormalised u8"), "{e}");
}

/// Sparse `indices` (of type `ty`) and `values` (f32) for an accessor of `count` elements.
fn sparse(g: &mut Gltf, ty: Ty, indices: &[f64], values: &[f64]) -> Value {
    let index_bytes: Vec<u8> = indices.iter().flat_map(|&i| ty.bytes(i)).collect();
    let value_bytes: Vec<u8> = values.iter().flat_map(|&v| (v as f32).to_le_bytes()).collect();
    let index_view = g.view(&index_bytes, None);
    let value_view = g.view(&value_bytes, None);
    json!({
        "count": indices.len(),
        "indices": { "bufferView": index_view, "componentType": ty.code() },
        "values": { "bufferView": value_view },
    })
}

#[test]
fn sparse_accessors_substitute_over_their_view_or_over_zeros() {
    let dir = temp_dir("sparse");
    // Over a base view: vertices 1 and 4 of two triangles replaced (u16 indices).
    let mut g = Gltf::default();
    let base = [0.0, 0.0, 0.0, 9.0, 9.0, 9.0, 0.0, 1.0, 0.0, 2.0, 0.0, 0.0, 9.0, 9.0, 9.0, 2.0, 1.0, 0.0];
    let position = g.data(Ty::F32, false, "VEC3", &base);
    g.accessors[position]["sparse"] = sparse(&mut g, Ty::U16, &[1.0, 4.0], &[1.0, 0.0, 0.0, 3.0, 0.0, 0.0]);
    g.accessors[position]["max"] = json!([3, 1, 0]);
    let scene =
        load(&dir, "base.gltf", &g.text(json!({ "attributes": { "POSITION": position } }), json!({}), json!({})))
            .unwrap();
    let expected =
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 1.0, 0.0]];
    assert_close(&drawn(&scene, 0), &expected, "over a view");

    // Over zeros (no bufferView), u8 indices; and quantized, unnormalised u16 texture
    // coordinates substituted over their view (u32 indices).
    let mut g = Gltf::default();
    let position =
        g.accessor(json!({ "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }));
    g.accessors[position]["sparse"] = sparse(&mut g, Ty::U8, &[1.0, 2.0], &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let uv = g.data(Ty::U16, false, "VEC2", &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let mut values = Vec::new();
    values.extend(700u16.to_le_bytes());
    values.extend(65535u16.to_le_bytes());
    let index_view = g.view(&2u32.to_le_bytes(), None);
    let value_view = g.view(&values, None);
    g.accessors[uv]["sparse"] = json!({ "count": 1, "indices": { "bufferView": index_view, "componentType": 5125 },
                                        "values": { "bufferView": value_view } });
    let text = g.text(
        json!({ "attributes": { "POSITION": position, "TEXCOORD_0": uv } }),
        json!({}),
        json!({ "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"] }),
    );
    let scene = load(&dir, "zeros.gltf", &text).unwrap();
    assert_close(&drawn(&scene, 0), &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "over zeros");
    let m = &scene.meshes[0];
    let uvs: Vec<[f32; 2]> = m.indices.iter().map(|&i| m.uvs[i as usize].to_array()).collect();
    assert_eq!(uvs, [[1.0, 2.0], [3.0, 4.0], [700.0, 65535.0]]);

    // Indices: index 2 of (0, 1, 2) replaced by 3.
    let mut g = Gltf::default();
    let position = g.data(Ty::F32, false, "VEC3", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 9.0, 9.0, 0.0, 0.0, 1.0, 0.0]);
    let index = g.data(Ty::U16, false, "SCALAR", &[0.0, 1.0, 2.0]);
    let index_view = g.view(&[2, 0, 0, 0], None);
    let value_view = g.view(&[3, 0, 0, 0], None);
    g.accessors[index]["sparse"] = json!({ "count": 1, "indices": { "bufferView": index_view, "componentType": 5121 },
                                           "values": { "bufferView": value_view, "byteOffset": 0 } });
    let text = g.text(json!({ "attributes": { "POSITION": position }, "indices": index }), json!({}), json!({}));
    let scene = load(&dir, "indices.gltf", &text).unwrap();
    assert_close(&drawn(&scene, 0), &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "sparse indices");

    // Animation keys: times over a view, translations over zeros.
    let mut g = Gltf::default();
    let times = g.data(Ty::F32, false, "SCALAR", &[0.0, 1.0, 2.0]);
    g.accessors[times]["sparse"] = sparse(&mut g, Ty::U16, &[1.0], &[1.5]);
    let translation = g.accessor(json!({ "componentType": 5126, "count": 3, "type": "VEC3" }));
    g.accessors[translation]["sparse"] = sparse(&mut g, Ty::U32, &[0.0, 2.0], &[1.0, 2.0, 3.0, -4.0, -5.0, -6.0]);
    let scene = load(&dir, "keys.gltf", &animated(&g, "translation", times, translation)).unwrap();
    let track = scene.nodes[0].tracks.translation.as_ref().unwrap();
    assert_eq!(track.times, [0.0, 1.5, 2.0]);
    let values: Vec<[f64; 3]> = track.values.iter().map(|v| v.to_array()).collect();
    assert_eq!(values, [[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [-4.0, -5.0, -6.0]]);
}

/// A triangle whose POSITION (3 elements over a view) has the sparse part `sparse`.
fn sparse_triangle(edit: impl FnOnce(&mut Gltf, usize)) -> String {
    let mut g = Gltf::default();
    let position = g.data(Ty::F32, false, "VEC3", &TRIANGLE);
    edit(&mut g, position);
    g.text(json!({ "attributes": { "POSITION": position } }), json!({}), json!({}))
}

#[test]
fn bad_sparse_accessors_are_one_line() {
    let dir = temp_dir("bad-sparse");
    let three = [0.0; 6];
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "decreasing",
            sparse_triangle(|g, p| g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[2.0, 1.0], &three)),
            "POSITION: accessor 0 sparse indices 2 then 1 (at 1) are not strictly increasing",
        ),
        (
            "repeated",
            sparse_triangle(|g, p| g.accessors[p]["sparse"] = sparse(g, Ty::U8, &[1.0, 1.0], &three)),
            "sparse indices 1 then 1 (at 1) are not strictly increasing",
        ),
        (
            "out-of-range",
            sparse_triangle(|g, p| g.accessors[p]["sparse"] = sparse(g, Ty::U32, &[0.0, 3.0], &three)),
            "POSITION: accessor 0 sparse index 3 (at 1) is out of range (3 elements)",
        ),
        (
            "too-many",
            sparse_triangle(|g, p| g.accessors[p]["sparse"] = sparse(g, Ty::U8, &[0.0, 1.0, 2.0, 3.0], &[0.0; 12])),
            "accessor 0 replaces 4 elements (sparse.count) of its 3",
        ),
        (
            "indices-past-view",
            sparse_triangle(|g, p| {
                g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0, 1.0], &three);
                g.accessors[p]["sparse"]["indices"]["byteOffset"] = json!(2);
            }),
            "accessor 0 sparse indices (2 × 2 bytes from byte 2) run past the end of buffer view 1 (4 bytes)",
        ),
        (
            "values-past-view",
            sparse_triangle(|g, p| g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0, 1.0], &[0.0; 5])),
            "accessor 0 sparse values (2 × 12 bytes from byte 0) run past the end of buffer view 2 (20 bytes)",
        ),
        (
            "view-past-buffer",
            sparse_triangle(|g, p| {
                g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0, 1.0], &three);
                g.views[2]["byteLength"] = json!(4000);
            }),
            "POSITION: buffer view 2 (bytes 40..+4000) runs past the end of buffer 0",
        ),
    ];
    for (name, text, expected) in cases {
        let e = load_error(&dir, &format!("{name}.gltf"), &text);
        assert!(e.contains(expected), "{name}: {e}");
    }
    // A sparse accessor without a view cannot make gigabytes of zeros from a line of JSON.
    let text = sparse_triangle(|g, p| {
        g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0], &[0.0; 3]);
        g.accessors[p].as_object_mut().unwrap().remove("bufferView");
        g.accessors[p]["count"] = json!(50_000_000);
    });
    let e = load_error(&dir, "zeros.gltf", &text);
    assert!(e.contains("accessor 0 declares 50000000 elements without a buffer view"), "{e}");
}

#[test]
fn offsets_and_lengths_near_2_to_the_64_are_refused_not_wrapped() {
    let dir = temp_dir("huge");
    let near = u64::MAX - 7;
    let sparse_edit = |part: &'static str| {
        move |g: &mut Gltf, p: usize| {
            g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0, 1.0], &[0.0; 6]);
            g.accessors[p]["sparse"][part]["byteOffset"] = json!(near);
        }
    };
    let cases: Vec<(&str, String, &str)> = vec![
        ("accessor-max", sparse_triangle(|g, p| g.accessors[p]["byteOffset"] = json!(u64::MAX)), "runs past the end"),
        ("accessor-near", sparse_triangle(|g, p| g.accessors[p]["byteOffset"] = json!(near)), "runs past the end"),
        (
            "view-offset",
            sparse_triangle(|g, _| g.views[0]["byteOffset"] = json!(near)),
            "runs past the end of buffer 0",
        ),
        (
            "view-length",
            sparse_triangle(|g, _| g.views[0]["byteLength"] = json!(u64::MAX)),
            "runs past the end of buffer 0",
        ),
        ("sparse-indices", sparse_triangle(sparse_edit("indices")), "sparse indices"),
        ("sparse-values", sparse_triangle(sparse_edit("values")), "sparse values"),
        (
            "sparse-count",
            sparse_triangle(|g, p| {
                g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0], &[0.0; 3]);
                g.accessors[p]["sparse"]["count"] = json!(u64::MAX);
            }),
            "replaces",
        ),
        ("count", sparse_triangle(|g, p| g.accessors[p]["count"] = json!(u64::MAX)), "declares"),
    ];
    for (name, text, expected) in cases {
        let e = load_error(&dir, &format!("{name}.gltf"), &text);
        assert!(e.contains(expected), "{name}: {e}");
    }
    // An image in a buffer view that starts near 2⁶⁴.
    let e = load_error(&dir, "image-view.gltf", &textured(json!({ "bufferView": 1, "mimeType": "image/png" }), near));
    assert!(e.contains("image 0: buffer view 1") && e.contains("runs past the end of buffer 0"), "{e}");
}

/// A triangle with a base-colour texture whose image is `image`; buffer view 1 (4 bytes)
/// starts at `view_offset`.
fn textured(image: Value, view_offset: u64) -> String {
    let mut g = Gltf::default();
    let position = g.data(Ty::F32, false, "VEC3", &TRIANGLE);
    g.view(&[0; 4], None);
    g.views[1]["byteOffset"] = json!(view_offset);
    g.text(
        json!({ "attributes": { "POSITION": position }, "material": 0 }),
        json!({}),
        json!({
            "materials": [{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }],
            "textures": [{ "source": 0 }],
            "images": [image],
        }),
    )
}

#[test]
fn images_the_gltf_crate_would_panic_on_are_one_line() {
    let dir = temp_dir("images");
    let e = load_error(&dir, "nomime.gltf", &textured(json!({ "bufferView": 1 }), 36));
    assert!(e.ends_with("image 0: has a bufferView but no mimeType"), "{e}");
    let e = load_error(&dir, "nosource.gltf", &textured(json!({ "name": "nothing" }), 36));
    assert!(e.ends_with("image 0: has neither a uri nor a bufferView"), "{e}");
    // An image no texture uses is checked too: the file is not valid glTF.
    let mut body: Value = serde_json::from_str(&textured(json!({ "uri": "a.png" }), 36)).unwrap();
    body["images"].as_array_mut().unwrap().push(json!({ "bufferView": 1 }));
    let e = load_error(&dir, "unused.gltf", &body.to_string());
    assert!(e.ends_with("image 1: has a bufferView but no mimeType"), "{e}");
    // What the crate's validation catches before its getters unwrap: a texture without
    // a source or with one that does not exist, a sampler that does not exist, a sampler
    // with an unknown wrap mode, sparse indices of a float type.
    let with = |edit: &dyn Fn(&mut Value)| {
        let mut body: Value =
            serde_json::from_str(&textured(json!({ "bufferView": 1, "mimeType": "image/png" }), 36)).unwrap();
        edit(&mut body);
        body.to_string()
    };
    let cases: Vec<(&str, String)> = vec![
        ("texture-without-source", with(&|b| b["textures"][0] = json!({}))),
        ("texture-source", with(&|b| b["textures"][0]["source"] = json!(7))),
        ("texture-sampler", with(&|b| b["textures"][0]["sampler"] = json!(3))),
        ("sampler-wrap", {
            with(&|b| {
                b["textures"][0]["sampler"] = json!(0);
                b["samplers"] = json!([{ "wrapS": 1234 }]);
            })
        }),
        ("image-view", with(&|b| b["images"][0]["bufferView"] = json!(9))),
        ("sparse-float-indices", {
            sparse_triangle(|g, p| {
                g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0], &[0.0; 3]);
                g.accessors[p]["sparse"]["indices"]["componentType"] = json!(5126);
            })
        }),
        ("sparse-view", {
            sparse_triangle(|g, p| {
                g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0], &[0.0; 3]);
                g.accessors[p]["sparse"]["values"]["bufferView"] = json!(99);
            })
        }),
    ];
    for (name, text) in cases {
        let e = load_error(&dir, &format!("{name}.gltf"), &text);
        assert!(e.contains("invalid glTF") || e.contains("not valid glTF"), "{name}: {e}");
    }
}

#[test]
fn mutations_of_these_files_never_panic() {
    // The loader fuzz test's mutations (tests/fuzz_loaders.rs), over this file's inputs.
    let mut seeds = Vec::new();
    let mut g = Gltf::default();
    let position = g.data(Ty::I16, true, "VEC3", &[-32768.0, 0.0, 0.0, 32767.0, 0.0, 0.0, 0.0, 32767.0, 0.0]);
    let normal = g.data(Ty::I8, true, "VEC3", &[0.0, 0.0, 127.0, 0.0, 0.0, 127.0, 0.0, 0.0, 127.0]);
    let uv = g.data(Ty::U16, false, "VEC2", &[0.0, 0.0, 1000.0, 0.0, 0.0, 65535.0]);
    g.accessors[uv]["sparse"] = sparse(&mut g, Ty::U8, &[1.0], &[0.0, 0.0]);
    let times = g.data(Ty::F32, false, "SCALAR", &[0.0, 1.0]);
    let rotation = g.data(Ty::I16, true, "VEC4", &[0.0, 0.0, 0.0, 32767.0, 0.0, 32767.0, 0.0, 0.0]);
    let translation = g.accessor(json!({ "componentType": 5126, "count": 2, "type": "VEC3" }));
    g.accessors[translation]["sparse"] = sparse(&mut g, Ty::U16, &[1.0], &[1.0, 2.0, 3.0]);
    let animations = json!([{ "channels": [{ "sampler": 0, "target": { "node": 0, "path": "rotation" } },
                                           { "sampler": 1, "target": { "node": 0, "path": "translation" } }],
                              "samplers": [{ "input": times, "output": rotation }, { "input": times, "output": translation }] }]);
    seeds.push(g.text(
        json!({ "attributes": { "POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv } }),
        json!({ "scale": [2, 2, 2] }),
        json!({ "extensionsRequired": ["KHR_mesh_quantization"], "extensionsUsed": ["KHR_mesh_quantization"], "animations": animations }),
    ));
    seeds.push(sparse_triangle(|g, p| g.accessors[p]["sparse"] = sparse(g, Ty::U16, &[0.0, 2.0], &[0.0; 6])));
    seeds.push(textured(json!({ "bufferView": 1, "mimeType": "image/png" }), 36));
    let dir = temp_dir("fuzz");
    for seed in &seeds {
        if let Err(e) = load_bytes(Target::Gltf, seed.as_bytes(), &dir) {
            // The textured seed's image is four zero bytes: not decodable, but read that far.
            assert!(e.to_string().contains("image 0: cannot decode"), "{e}");
        }
    }
    let mut rng = Mutator::new(0xacce55);
    let started = Instant::now();
    let mut failures = Vec::new();
    let mut runs = 0;
    while started.elapsed() < Duration::from_secs(3) {
        let mut input = seeds[runs % seeds.len()].clone().into_bytes();
        for _ in 0..1 + runs % 3 {
            rng.mutate(&mut input);
        }
        if catch_unwind(AssertUnwindSafe(|| load_bytes(Target::Gltf, &input, &dir))).is_err() {
            failures.push(String::from_utf8_lossy(&input).into_owned());
        }
        runs += 1;
    }
    assert!(failures.is_empty(), "{} of {runs} mutated inputs panicked, the first: {}", failures.len(), failures[0]);
}
