//! The glTF fidelity assets: one small scene per feature a real glTF uses, each with a
//! camera, to render and look at (`vrao render --scene FILE`) and to bench against the
//! reference. Written with the repository's writer where it can say the feature, and as
//! hand-made JSON where only such a file can (primitive modes, quantized and sparse
//! accessors).

use glam::{DVec3, Vec2, Vec3, Vec4};
use serde_json::json;
use std::path::Path;
use vrao::test_assets::gltf_write::{encode_base64, write, WriteOptions};
use vrao_ao::HeadPose;
use vrao_render::scene::{HeadPath, Light, Material, Mesh, Sampling, Scene, Texture, Wrap};

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// Writes every fidelity asset into `out` and names them.
pub(crate) fn write_all(out: &Path) -> Result<()> {
    for (name, scene) in [
        ("tiles.glb", tiles()),
        ("emissive.glb", emissive()),
        ("vertex_colors.glb", vertex_colours()),
        ("normal_map.glb", relief(true)),
        ("normal_map_flat.glb", relief(false)),
    ] {
        let camera = scene.head.pose_at(0.0);
        write(&scene, &out.join(name), &WriteOptions { camera: Some(camera), ..WriteOptions::default() })?;
    }
    std::fs::write(out.join("modes.gltf"), modes().to_string())?;
    std::fs::write(out.join("quantized.gltf"), quantized().to_string())?;
    std::fs::write(out.join("sparse.gltf"), sparse().to_string())?;
    println!(
        "wrote tiles.glb, emissive.glb, vertex_colors.glb, normal_map.glb, normal_map_flat.glb, \
         modes.gltf, quantized.gltf, sparse.gltf"
    );
    Ok(())
}

/// A scene of `meshes` under one sun, seen from `eye` looking at `at`.
fn scene(name: &str, meshes: Vec<Mesh>, materials: Vec<Material>, eye: DVec3, at: DVec3) -> Scene {
    Scene {
        name: name.into(),
        meshes,
        materials,
        lights: vec![Light::Directional {
            direction: Vec3::new(0.3, -1.0, -0.4).normalize(),
            color: Vec3::ONE,
            intensity: 2.0,
        }],
        environment: None,
        head: HeadPath::fixed(HeadPose::look_at(eye, at).unwrap_or(HeadPose::IDENTITY)),
        nodes: Vec::new(),
    }
}

/// A rectangle from `corner` along `u` and `v` (its texture coordinates run 0..`uv_max`
/// along each, v = 0 at the `corner + v` edge, as glTF's top row), split into `cells`²
/// quads, facing `u × v`.
fn sheet(name: &str, corner: DVec3, u: Vec3, v: Vec3, uv_max: Vec2, cells: u32, material: usize) -> Mesh {
    let normal = u.cross(v).normalize();
    let mut mesh = Mesh {
        name: name.into(),
        origin: corner,
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        uvs1: Vec::new(),
        colors: Vec::new(),
        tangents: Vec::new(),
        indices: Vec::new(),
        material,
        node: None,
    };
    for j in 0..=cells {
        for i in 0..=cells {
            let (s, t) = (i as f32 / cells as f32, j as f32 / cells as f32);
            mesh.positions.push(u * s + v * t);
            mesh.normals.push(normal);
            mesh.uvs.push(Vec2::new(s * uv_max.x, (1.0 - t) * uv_max.y));
            mesh.tangents.push(u.normalize().extend(1.0));
        }
    }
    let row = cells + 1;
    for j in 0..cells {
        for i in 0..cells {
            let a = j * row + i;
            mesh.indices.extend([a, a + 1, a + row + 1, a, a + row + 1, a + row]);
        }
    }
    mesh
}

/// An image of `side`² texels from `texel(x, y)` (RGBA8).
fn image(side: u32, sampling: Sampling, texel: impl Fn(u32, u32) -> [u8; 4]) -> Texture {
    let rgba8 = (0..side * side).flat_map(|i| texel(i % side, i / side)).collect::<Vec<u8>>().into();
    Texture { width: side, height: side, rgba8, source: None, sampling }
}

/// An arrow pointing right and up on a grey ground with a red top-left corner: every
/// flip and turn of the texture shows.
fn arrow(sampling: Sampling) -> Texture {
    image(16, sampling, |x, y| {
        let shaft = (6..10).contains(&y) && x < 12;
        let head = x >= 10 && (y as i32 - 8).unsigned_abs() + (x - 10) <= 6;
        let corner = x < 3 && y < 3;
        match (corner, shaft || head) {
            (true, _) => [220, 30, 30, 255],
            (_, true) => [30, 30, 200, 255],
            _ => [200, 200, 190, 255],
        }
    })
}

/// A floor with the arrow tiled 4 × 4: repeating on the left half, mirrored on the right;
/// a wall behind clamps it (the edge texels stretch beyond one tile).
fn tiles() -> Scene {
    let repeat = Sampling::default();
    let mirrored = Sampling { wrap_u: Wrap::MirroredRepeat, wrap_v: Wrap::MirroredRepeat, ..Sampling::default() };
    let clamped = Sampling { wrap_u: Wrap::ClampToEdge, wrap_v: Wrap::ClampToEdge, ..Sampling::default() };
    let materials = [("repeat", repeat), ("mirrored repeat", mirrored), ("clamp", clamped)]
        .map(|(name, sampling)| {
            let mut m = Material::plain(name, Vec3::ONE);
            m.diffuse_texture = Some(arrow(sampling));
            m
        })
        .to_vec();
    let (x, z) = (Vec3::X, Vec3::NEG_Z);
    let meshes = vec![
        sheet("floor, repeat", DVec3::new(-2.0, 0.0, 1.0), x * 2.0, z * 4.0, Vec2::new(2.0, 4.0), 1, 0),
        sheet("floor, mirrored", DVec3::new(0.0, 0.0, 1.0), x * 2.0, z * 4.0, Vec2::new(2.0, 4.0), 1, 1),
        sheet("wall, clamp", DVec3::new(-2.0, 0.0, -3.0), x * 4.0, Vec3::Y * 2.0, Vec2::new(2.0, 2.0), 1, 2),
    ];
    scene("tiles", meshes, materials, DVec3::new(0.0, 2.2, 2.8), DVec3::new(0.0, 0.3, -1.0))
}

/// A box whose emission is limited to the stripes of its emissive texture, on a floor.
fn emissive() -> Scene {
    let mut lamp = Material::plain("striped lamp", Vec3::splat(0.3));
    lamp.emissive = Vec3::new(3.0, 2.4, 1.2);
    lamp.emissive_texture =
        Some(image(8, Sampling::default(), |_, y| if y % 4 < 1 { [255, 255, 255, 255] } else { [0, 0, 0, 255] }));
    let materials = vec![Material::plain("floor", Vec3::splat(0.6)), lamp];
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let mut meshes = vec![sheet("floor", DVec3::new(-2.0, 0.0, 2.0), x * 4.0, -z * 4.0, Vec2::ONE, 1, 0)];
    // Four sides of a 0.6 × 1 × 0.6 m box, each with the stripes once across.
    let c = DVec3::new(0.0, 0.0, 0.0);
    for (k, (corner, u)) in [
        (c + DVec3::new(-0.3, 0.0, 0.3), x * 0.6),
        (c + DVec3::new(0.3, 0.0, 0.3), -z * 0.6),
        (c + DVec3::new(0.3, 0.0, -0.3), -x * 0.6),
        (c + DVec3::new(-0.3, 0.0, -0.3), z * 0.6),
    ]
    .into_iter()
    .enumerate()
    {
        meshes.push(sheet(&format!("lamp side {k}"), corner, u, y, Vec2::ONE, 1, 1));
    }
    meshes.push(sheet("lamp top", c + DVec3::new(-0.3, 1.0, 0.3), x * 0.6, -z * 0.6, Vec2::ONE, 1, 1));
    scene("emissive", meshes, materials, DVec3::new(1.2, 1.4, 2.0), DVec3::new(0.0, 0.5, 0.0))
}

/// A wall of 8 × 8 cells whose vertex colours run red to green across and fade to blue
/// upwards, over a white base colour, on a grey floor.
fn vertex_colours() -> Scene {
    let materials = vec![Material::plain("floor", Vec3::splat(0.6)), Material::plain("white", Vec3::ONE)];
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let mut wall = sheet("painted wall", DVec3::new(-1.5, 0.0, 0.0), x * 3.0, y * 2.0, Vec2::ONE, 8, 1);
    wall.colors = wall
        .positions
        .iter()
        .map(|p| {
            let (s, t) = (p.x / 3.0, p.y / 2.0);
            Vec4::new((1.0 - s) * (1.0 - t), s * (1.0 - t), t, 1.0)
        })
        .collect();
    wall.tangents.clear();
    let floor = sheet("floor", DVec3::new(-2.0, 0.0, 2.0), x * 4.0, -z * 4.0, Vec2::ONE, 1, 0);
    scene("vertex colours", vec![floor, wall], materials, DVec3::new(0.0, 1.2, 3.0), DVec3::new(0.0, 0.9, 0.0))
}

/// A floor and a wall of ridges 0.25 m apart drawn only by a normal texture (and,
/// with `mapped`, an occlusion texture dark in the grooves); without it, the same flat
/// geometry and base colour (for the AO measured with and without the texture).
fn relief(mapped: bool) -> Scene {
    // Ridges along v: the normal tilts ±35° across u in a sine; the grooves, where it
    // tilts most steeply down into them, carry the baked occlusion.
    let ridges = |x: u32| (x as f32 + 0.5) / 32.0 * std::f32::consts::TAU;
    let normal = image(32, Sampling::default(), |x, _| {
        let tilt = 35f32.to_radians() * ridges(x).sin();
        let n = Vec3::new(tilt.sin(), 0.0, tilt.cos());
        let b = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
        [b(n.x), b(n.y), b(n.z), 255]
    });
    let occlusion = image(32, Sampling::default(), |x, _| {
        let groove = (0.5 + 0.5 * ridges(x).cos()).powi(4);
        let r = ((1.0 - 0.6 * groove) * 255.0).round() as u8;
        [r, r, r, 255]
    });
    let mut relief = Material::plain("relief", Vec3::new(0.75, 0.7, 0.6));
    if mapped {
        relief.normal_texture = Some((normal, 1.0));
        relief.occlusion_texture = Some((occlusion, 1.0));
    }
    let materials = vec![relief];
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let uv = Vec2::new(16.0, 16.0);
    let mut meshes = vec![
        sheet("floor", DVec3::new(-2.0, 0.0, 2.0), x * 4.0, -z * 4.0, uv, 4, 0),
        sheet("wall", DVec3::new(-2.0, 0.0, -2.0), x * 4.0, y * 4.0, uv, 4, 0),
    ];
    if !mapped {
        meshes.iter_mut().for_each(|m| m.tangents.clear());
    }
    scene(
        if mapped { "normal map" } else { "normal map (flat)" },
        meshes,
        materials,
        DVec3::new(0.8, 1.6, 1.6),
        DVec3::new(-0.3, 0.4, -1.2),
    )
}

/// A JSON glTF of one buffer (`bin`, as a data URI), with `body`'s other fields.
fn gltf(bin: &[u8], mut body: serde_json::Value) -> serde_json::Value {
    body["asset"] = json!({ "version": "2.0", "generator": "vrao make_gltf" });
    body["buffers"] = json!([{ "byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", encode_base64(bin)) }]);
    body
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A camera node looking from `eye` at `at` (glTF cameras look along −z).
fn camera_node(eye: DVec3, at: DVec3) -> serde_json::Value {
    let pose = HeadPose::look_at(eye, at).unwrap_or(HeadPose::IDENTITY);
    let q = pose.orientation;
    json!({ "camera": 0, "translation": [pose.position.x, pose.position.y, pose.position.z],
            "rotation": [q.x, q.y, q.z, q.w] })
}

fn perspective() -> serde_json::Value {
    json!([{ "type": "perspective", "perspective": { "yfov": 1.2, "znear": 0.05 } }])
}

/// Every primitive mode in one file: a quad as a triangle strip, a quad as a fan, a
/// triangle list, and lines and points (skipped with one warning).
fn modes() -> serde_json::Value {
    // Three quads side by side, 1 m each, facing +z: strip order, fan order, list order.
    let strip = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0];
    let fan = [1.5f32, 0.0, 0.0, 2.5, 0.0, 0.0, 2.5, 1.0, 0.0, 1.5, 1.0, 0.0];
    let list = [3.0f32, 0.0, 0.0, 4.0, 0.0, 0.0, 4.0, 1.0, 0.0, 3.0, 0.0, 0.0, 4.0, 1.0, 0.0, 3.0, 1.0, 0.0];
    let floor =
        [-1.0f32, -0.01, 2.0, 5.0, -0.01, 2.0, 5.0, -0.01, -2.0, -1.0, -0.01, 2.0, 5.0, -0.01, -2.0, -1.0, -0.01, -2.0];
    let mut bin = Vec::new();
    let mut accessors = Vec::new();
    let mut views = Vec::new();
    for (values, count) in [(&strip[..], 4), (&fan[..], 4), (&list[..], 6), (&floor[..], 6)] {
        let (min, max) = bounds(values);
        views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": values.len() * 4 }));
        accessors.push(json!({ "bufferView": views.len() - 1, "componentType": 5126, "count": count, "type": "VEC3", "min": min, "max": max }));
        bin.extend(f32_bytes(values));
    }
    gltf(
        &bin,
        json!({
            "bufferViews": views, "accessors": accessors,
            "materials": [{ "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.5, 0.3, 1.0], "metallicFactor": 0.0 } },
                          { "pbrMetallicRoughness": { "baseColorFactor": [0.6, 0.6, 0.6, 1.0], "metallicFactor": 0.0 } }],
            "meshes": [{ "primitives": [
                { "attributes": { "POSITION": 0 }, "mode": 5, "material": 0 },
                { "attributes": { "POSITION": 1 }, "mode": 6, "material": 0 },
                { "attributes": { "POSITION": 2 }, "mode": 4, "material": 0 },
                { "attributes": { "POSITION": 3 }, "mode": 4, "material": 1 },
                { "attributes": { "POSITION": 2 }, "mode": 1 },
                { "attributes": { "POSITION": 2 }, "mode": 0 }
            ] }],
            "cameras": perspective(),
            "nodes": [{ "mesh": 0 }, camera_node(DVec3::new(2.0, 1.5, 3.5), DVec3::new(2.0, 0.4, 0.0))],
            "scenes": [{ "nodes": [0, 1] }], "scene": 0
        }),
    )
}

fn bounds(values: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let mut min = vec![f32::INFINITY; 3];
    let mut max = vec![f32::NEG_INFINITY; 3];
    for p in values.chunks(3) {
        for c in 0..3 {
            min[c] = min[c].min(p[c]);
            max[c] = max[c].max(p[c]);
        }
    }
    (min, max)
}

/// A quantized, textured 16 × 16-cell dome as the quantized sample models store theirs:
/// i16 normalised positions scaled back by the node, i8 normalised normals, and u16
/// unnormalised texture coordinates scaled back by `KHR_texture_transform`.
fn quantized() -> serde_json::Value {
    let cells = 16u32;
    let (mut positions, mut normals, mut uvs, mut indices) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for j in 0..=cells {
        for i in 0..=cells {
            let (s, t) = (i as f32 / cells as f32, j as f32 / cells as f32);
            let (x, z) = (s * 2.0 - 1.0, t * 2.0 - 1.0);
            let y = 0.5 * (1.0 - (x * x + z * z) * 0.5).max(0.0);
            // The dome's slope gives its normal.
            let n = Vec3::new(0.5 * x, 1.0, 0.5 * z).normalize();
            positions.extend([x, y, z].map(|c| (c * 32767.0).round() as i16));
            positions.push(0); // 8-byte alignment of each position (glTF: 4-byte elements)
            normals.extend([n.x, n.y, n.z].map(|c| (c * 127.0).round() as i8));
            normals.push(0);
            uvs.extend([s, t].map(|c| (c * 1024.0).round() as u16));
        }
    }
    let row = cells + 1;
    for j in 0..cells {
        for i in 0..cells {
            let a = (j * row + i) as u16;
            let row = row as u16;
            indices.extend([a, a + row, a + row + 1, a, a + row + 1, a + 1]);
        }
    }
    let mut bin: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    let normals_at = bin.len();
    bin.extend(normals.iter().map(|&v| v as u8));
    let uvs_at = bin.len();
    bin.extend(uvs.iter().flat_map(|v| v.to_le_bytes()));
    let indices_at = bin.len();
    bin.extend(indices.iter().flat_map(|v| v.to_le_bytes()));
    let count = (row * row) as usize;
    let checker: Vec<u8> =
        (0..64u32).flat_map(|k| if (k % 8 + k / 8) % 2 == 0 { [230, 120, 40] } else { [40, 90, 200] }).collect();
    let png = {
        let mut bytes = Vec::new();
        image::RgbImage::from_raw(8, 8, checker)
            .expect("8×8 RGB")
            .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
            .expect("a PNG encodes");
        bytes
    };
    gltf(
        &bin,
        json!({
            "extensionsUsed": ["KHR_mesh_quantization", "KHR_texture_transform"],
            "extensionsRequired": ["KHR_mesh_quantization"],
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": normals_at, "byteStride": 8 },
                { "buffer": 0, "byteOffset": normals_at, "byteLength": uvs_at - normals_at, "byteStride": 4 },
                { "buffer": 0, "byteOffset": uvs_at, "byteLength": indices_at - uvs_at, "byteStride": 4 },
                { "buffer": 0, "byteOffset": indices_at, "byteLength": bin.len() - indices_at }
            ],
            "accessors": [
                { "bufferView": 0, "componentType": 5122, "normalized": true, "count": count, "type": "VEC3",
                  "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.5, 1.0] },
                { "bufferView": 1, "componentType": 5120, "normalized": true, "count": count, "type": "VEC3" },
                { "bufferView": 2, "componentType": 5123, "count": count, "type": "VEC2" },
                { "bufferView": 3, "componentType": 5123, "count": indices.len(), "type": "SCALAR" }
            ],
            "images": [{ "uri": format!("data:image/png;base64,{}", encode_base64(&png)) }],
            "samplers": [{ "magFilter": 9728 }],
            "textures": [{ "source": 0, "sampler": 0 }],
            "materials": [{ "pbrMetallicRoughness": { "metallicFactor": 0.0, "baseColorTexture": { "index": 0,
                "extensions": { "KHR_texture_transform": { "scale": [4.0 / 1024.0, 4.0 / 1024.0] } } } } }],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0 }] }],
            "cameras": perspective(),
            "nodes": [{ "mesh": 0, "scale": [1.5, 1.5, 1.5] }, camera_node(DVec3::new(0.0, 2.0, 2.6), DVec3::new(0.0, 0.2, 0.0))],
            "scenes": [{ "nodes": [0, 1] }], "scene": 0
        }),
    )
}

/// A 6 × 6-cell floor whose base positions are flat and whose sparse accessor lifts a
/// cross of vertices 0.5 m (the raised cross shows only if the substitution is read).
fn sparse() -> serde_json::Value {
    let cells = 6u32;
    let row = cells + 1;
    let mut flat = Vec::new();
    for j in 0..row {
        for i in 0..row {
            flat.extend([i as f32 / cells as f32 * 3.0 - 1.5, 0.0, j as f32 / cells as f32 * 3.0 - 1.5]);
        }
    }
    let mut indices = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            let a = j * row + i;
            indices.extend([a, a + row, a + row + 1, a, a + row + 1, a + 1].map(|v| v as u16));
        }
    }
    // The cross through the middle vertex, in increasing index order.
    let mid = cells / 2;
    let lifted: Vec<u16> = (0..row * row).filter(|k| k % row == mid || k / row == mid).map(|k| k as u16).collect();
    let values: Vec<f32> = lifted.iter().flat_map(|&k| [flat[3 * k as usize], 0.5, flat[3 * k as usize + 2]]).collect();
    let mut bin = f32_bytes(&flat);
    let indices_at = bin.len();
    bin.extend(indices.iter().flat_map(|v| v.to_le_bytes()));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let lifted_at = bin.len();
    bin.extend(lifted.iter().flat_map(|v| v.to_le_bytes()));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let values_at = bin.len();
    bin.extend(f32_bytes(&values));
    gltf(
        &bin,
        json!({
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": indices_at },
                { "buffer": 0, "byteOffset": indices_at, "byteLength": indices.len() * 2 },
                { "buffer": 0, "byteOffset": lifted_at, "byteLength": lifted.len() * 2 },
                { "buffer": 0, "byteOffset": values_at, "byteLength": values.len() * 4 }
            ],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": row * row, "type": "VEC3",
                  "min": [-1.5, 0.0, -1.5], "max": [1.5, 0.5, 1.5],
                  "sparse": { "count": lifted.len(),
                              "indices": { "bufferView": 2, "componentType": 5123 },
                              "values": { "bufferView": 3 } } },
                { "bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR" }
            ],
            "materials": [{ "pbrMetallicRoughness": { "baseColorFactor": [0.7, 0.7, 0.65, 1.0], "metallicFactor": 0.0 } }],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "material": 0 }] }],
            "cameras": perspective(),
            "nodes": [{ "mesh": 0 }, camera_node(DVec3::new(2.2, 2.0, 2.6), DVec3::new(0.0, 0.0, 0.0))],
            "scenes": [{ "nodes": [0, 1] }], "scene": 0
        }),
    )
}
