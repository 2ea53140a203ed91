//! Writes a [`Scene`] as glTF 2.0 (`.glb` or `.gltf`): the project's own test assets and
//! converted scenes (`examples/make_gltf.rs`, `tests/gltf.rs`).
//!
//! Written: every mesh (static meshes in world space, moving ones under their node; vertex
//! colours as `COLOR_0`, VEC3 when every alpha is 1 and VEC4 otherwise; tangents as
//! `TANGENT` with the normals), materials (base colour and alpha factor, alpha mode and
//! cutoff, emission with `KHR_materials_emissive_strength` above 1, `doubleSided`;
//! base colour, emission, normal (with its scale) and occlusion (with its strength)
//! textures as PNG, each with its sampler unless that is glTF's default, and with
//! `KHR_texture_transform` on its texture reference unless the transform is the identity), the node
//! hierarchy with its tracks (a node's `base` becomes a matrix parent of its TRS node),
//! lights (`KHR_lights_punctual`), and an optional camera. [`WriteOptions`] picks how
//! indices, texture coordinates, buffers and images are stored, so that tests reach every
//! path of the loader. The document is built as JSON, read back into `gltf::json::Root`
//! and validated by the `gltf` crate before it is serialised, so what is written is glTF
//! the loader's parser accepts.
//!
//! Positions are written as f32 (an origin far from zero loses what f32 loses); times as
//! f32.

use crate::error::{Error, Result};
use glam::{Affine2, DMat4, DQuat, DVec3, Vec2, Vec3, Vec4};
use serde_json::{json, Value};
use std::path::Path;
use vrao_ao::HeadPose;
use vrao_render::scene::texture::{uv_transform, uv_transform_parts};
use vrao_render::scene::{
    AlphaMode, Filter, Interpolation, Light, Material, Mesh, Sampling, Scene, Texture, Track, Wrap,
};

/// Where buffers or images go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// In the `.glb`'s binary chunk (a `.gltf`'s buffer then becomes a data URI; an image
    /// goes into a buffer view).
    Embedded,
    /// As base64 data URIs in the JSON.
    DataUri,
    /// As files beside the glTF (`NAME.bin`, `NAME_imageI.png`).
    External,
}

/// How triangle indices are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IndexType {
    /// The smallest of u8, u16 and u32 that holds every index.
    Smallest,
    /// Unsigned bytes (at most 256 vertices per mesh).
    U8,
    /// Unsigned shorts (at most 65536 vertices per mesh).
    U16,
    /// Unsigned ints.
    U32,
    /// No indices: three vertices per triangle, repeated where triangles share them.
    NonIndexed,
}

/// How texture coordinates are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexcoordType {
    /// f32.
    F32,
    /// Normalised u8 (coordinates in [0, 1], rounded to 1/255).
    U8Normalized,
    /// Normalised u16 (coordinates in [0, 1], rounded to 1/65535).
    U16Normalized,
}

/// Choices for [`write()`].
#[derive(Clone, Debug)]
pub struct WriteOptions {
    /// Where the geometry buffer goes.
    pub buffers: Storage,
    /// Where images go.
    pub images: Storage,
    /// Index storage.
    pub indices: IndexType,
    /// Texture coordinate storage (written only for textured materials' meshes).
    pub texcoords: TexcoordType,
    /// Whether to write normals (without them the loader computes normals).
    pub normals: bool,
    /// A camera at this pose (the loader takes it as the head pose).
    pub camera: Option<HeadPose>,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            buffers: Storage::Embedded,
            images: Storage::Embedded,
            indices: IndexType::Smallest,
            texcoords: TexcoordType::F32,
            normals: true,
            camera: None,
        }
    }
}

/// The binary buffer being filled, and the JSON arrays that point into it.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// Appends `bytes` as a buffer view (4-byte aligned) and returns its index.
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// Appends an accessor over new bytes and returns its index.
    fn accessor(&mut self, bytes: &[u8], component: u32, kind: &str, count: usize, extra: Value) -> usize {
        let view = self.view(bytes);
        let mut accessor = json!({ "bufferView": view, "componentType": component, "type": kind, "count": count });
        if let (Some(a), Value::Object(e)) = (accessor.as_object_mut(), extra) {
            a.extend(e);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Appends an f32 accessor over `values` and returns its index.
    fn floats(&mut self, values: &[f32], kind: &str, count: usize, extra: Value) -> usize {
        self.accessor(bytemuck::cast_slice(values), FLOAT, kind, count, extra)
    }

    /// A primitive's `attributes`: positions with their bounds, normals if asked for (and
    /// tangents with them where the mesh has some), texture coordinates for a textured
    /// material and vertex colours where the mesh has some.
    fn attributes(&mut self, v: &MeshVertices, textured: bool, options: &WriteOptions) -> Value {
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        v.positions.iter().for_each(|p| {
            min = min.min(*p);
            max = max.max(*p);
        });
        let flat: Vec<f32> = v.positions.iter().flat_map(|p| p.to_array()).collect();
        let count = v.positions.len();
        let mut attributes = json!({
            "POSITION": self.floats(&flat, "VEC3", count, json!({ "min": min.to_array(), "max": max.to_array() }))
        });
        if options.normals {
            let flat: Vec<f32> = v.normals.iter().flat_map(|n| n.to_array()).collect();
            attributes["NORMAL"] = json!(self.floats(&flat, "VEC3", count, json!({})));
            // Tangents without normals are ignored by the specification: written with them only.
            if count > 0 && v.tangents.len() == count {
                let flat: Vec<f32> = v.tangents.iter().flat_map(|t| t.to_array()).collect();
                attributes["TANGENT"] = json!(self.floats(&flat, "VEC4", count, json!({})));
            }
        }
        if textured && v.uvs.len() == count {
            attributes["TEXCOORD_0"] = json!(self.texcoords(&v.uvs, options.texcoords));
        }
        if textured && count > 0 && v.uvs1.len() == count {
            attributes["TEXCOORD_1"] = json!(self.texcoords(&v.uvs1, options.texcoords));
        }
        if count > 0 && v.colors.len() == count {
            let (flat, kind): (Vec<f32>, _) = if v.colors.iter().all(|c| c.w == 1.0) {
                (v.colors.iter().flat_map(|c| c.truncate().to_array()).collect(), "VEC3")
            } else {
                (v.colors.iter().flat_map(|c| c.to_array()).collect(), "VEC4")
            };
            attributes["COLOR_0"] = json!(self.floats(&flat, kind, count, json!({})));
        }
        attributes
    }

    /// Appends an accessor over texture coordinates stored as `storage` and returns its index.
    fn texcoords(&mut self, uvs: &[Vec2], storage: TexcoordType) -> usize {
        let count = uvs.len();
        match storage {
            TexcoordType::F32 => {
                let flat: Vec<f32> = uvs.iter().flat_map(|t| t.to_array()).collect();
                self.floats(&flat, "VEC2", count, json!({}))
            }
            TexcoordType::U8Normalized => {
                let q: Vec<u8> =
                    uvs.iter().flat_map(|t| t.to_array()).map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
                // Each element padded to 4 bytes, as the spec requires of vertex attributes.
                let padded: Vec<u8> = q.chunks_exact(2).flat_map(|c| [c[0], c[1], 0, 0]).collect();
                let view = self.view(&padded);
                self.views[view]["byteStride"] = json!(4);
                self.accessors.push(json!({ "bufferView": view, "componentType": UNSIGNED_BYTE, "type": "VEC2", "count": count, "normalized": true }));
                self.accessors.len() - 1
            }
            TexcoordType::U16Normalized => {
                let q: Vec<u16> = uvs
                    .iter()
                    .flat_map(|t| t.to_array())
                    .map(|c| (c.clamp(0.0, 1.0) * 65535.0).round() as u16)
                    .collect();
                self.accessor(bytemuck::cast_slice(&q), UNSIGNED_SHORT, "VEC2", count, json!({ "normalized": true }))
            }
        }
    }

    /// Appends an accessor over `indices` stored as `t` (U8, U16 or U32) and returns its index.
    fn indices(&mut self, indices: &[u32], t: IndexType) -> usize {
        let n = indices.len();
        match t {
            IndexType::U8 => self.accessor(
                &indices.iter().map(|&i| i as u8).collect::<Vec<_>>(),
                UNSIGNED_BYTE,
                "SCALAR",
                n,
                json!({}),
            ),
            IndexType::U16 => {
                let v: Vec<u16> = indices.iter().map(|&i| i as u16).collect();
                self.accessor(bytemuck::cast_slice(&v), UNSIGNED_SHORT, "SCALAR", n, json!({}))
            }
            _ => self.accessor(bytemuck::cast_slice(indices), UNSIGNED_INT, "SCALAR", n, json!({})),
        }
    }
}

const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

/// Writes `scene` to `path`: a `.glb` when its extension says so, else `.gltf` JSON.
pub fn write(scene: &Scene, path: &Path, options: &WriteOptions) -> Result<()> {
    let glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
    let files = SideFiles { path, directory: path.parent().unwrap_or(Path::new("")), stem };
    let mut d = Document::default();
    d.add_materials(scene, options.images, &files)?;
    let trs_of = d.add_nodes(scene);
    for mesh in &scene.meshes {
        d.add_mesh(scene, mesh, options, &trs_of)?;
    }
    d.add_animation(scene, &trs_of);
    d.add_lights(scene);
    d.add_camera(options.camera);
    let buffer = d.buffer_json(glb, options.buffers, &files)?;
    let bin = std::mem::take(&mut d.b.bin);
    let root = validated(d.into_json(&scene.name, buffer))?;
    let bytes = file_bytes(&root, glb, bin, path)?;
    std::fs::write(path, bytes).map_err(|e| output(path, &e))
}

/// The error of a file that could not be written.
fn output(file: &Path, e: &dyn std::fmt::Display) -> Error {
    Error::Output { path: file.to_path_buf(), message: e.to_string() }
}

/// Where the asset goes: its path, and the folder and stem of the files written beside it.
struct SideFiles<'a> {
    path: &'a Path,
    directory: &'a Path,
    stem: String,
}

impl SideFiles<'_> {
    /// Writes `bytes` as the side file `name` beside the asset.
    fn write(&self, name: &str, bytes: &[u8]) -> Result<()> {
        std::fs::write(self.directory.join(name), bytes).map_err(|e| output(&self.directory.join(name), &e))
    }
}

/// A mesh's vertex data as written: f32 world positions, and with
/// [`IndexType::NonIndexed`] three vertices per triangle.
struct MeshVertices {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    uvs1: Vec<Vec2>,
    colors: Vec<Vec4>,
    tangents: Vec<Vec4>,
    indices: Vec<u32>,
}

/// The document's JSON arrays as they are filled, and the buffer they point into.
#[derive(Default)]
struct Document {
    b: Builder,
    extensions_used: Vec<&'static str>,
    images: Vec<Value>,
    textures: Vec<Value>,
    /// Texture samplers (the animation's samplers are [`Document::samplers`]).
    texture_samplers: Vec<Value>,
    materials: Vec<Value>,
    nodes: Vec<Value>,
    roots: Vec<usize>,
    meshes: Vec<Value>,
    channels: Vec<Value>,
    samplers: Vec<Value>,
    lights: Vec<Value>,
    cameras: Vec<Value>,
}

impl Document {
    /// Appends `node` under glTF node `parent` (a scene root without one) and returns its index.
    fn add_node(&mut self, node: Value, parent: Option<usize>) -> usize {
        self.nodes.push(node);
        let child = self.nodes.len() - 1;
        match parent {
            Some(p) => {
                let children = self.nodes[p].as_object_mut().map(|o| o.entry("children").or_insert(json!([])));
                if let Some(Value::Array(c)) = children {
                    c.push(json!(child));
                }
            }
            None => self.roots.push(child),
        }
        child
    }

    /// Adds every material, and the images and textures of its textures.
    fn add_materials(&mut self, scene: &Scene, images: Storage, files: &SideFiles) -> Result<()> {
        for (i, m) in scene.materials.iter().enumerate() {
            let mut pbr = json!({
                "baseColorFactor": [m.diffuse.x, m.diffuse.y, m.diffuse.z, m.alpha],
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
            });
            let image = |kind: &str| ImageName { material: i, kind: kind.to_string(), storage: images };
            if let Some(texture) = &m.diffuse_texture {
                pbr["baseColorTexture"] = self.add_texture(texture, &image(""), files, m)?;
            }
            let mut material = json!({ "name": m.name, "pbrMetallicRoughness": pbr, "doubleSided": m.double_sided });
            self.set_emission(&mut material, m.emissive);
            if let Some(texture) = &m.emissive_texture {
                material["emissiveTexture"] = self.add_texture(texture, &image("_emissive"), files, m)?;
            }
            if let Some((texture, scale)) = &m.normal_texture {
                let mut info = self.add_texture(texture, &image("_normal"), files, m)?;
                info["scale"] = json!(scale);
                material["normalTexture"] = info;
            }
            if let Some((texture, strength)) = &m.occlusion_texture {
                let mut info = self.add_texture(texture, &image("_occlusion"), files, m)?;
                info["strength"] = json!(strength);
                material["occlusionTexture"] = info;
            }
            set_alpha_mode(&mut material, m.alpha_mode);
            self.materials.push(material);
        }
        Ok(())
    }

    /// Adds `texture` of material `m` as an image and a texture with its sampler (none for
    /// glTF's default), and returns the material's reference to it (a textureInfo, with
    /// `KHR_texture_transform` unless the transform is the identity).
    fn add_texture(&mut self, texture: &Texture, name: &ImageName, files: &SideFiles, m: &Material) -> Result<Value> {
        let image = self.image_json(texture, name, files)?;
        self.images.push(image);
        let mut entry = json!({ "source": self.images.len() - 1 });
        if texture.sampling != Sampling::default() {
            entry["sampler"] = json!(self.sampler(&texture.sampling));
        }
        self.textures.push(entry);
        let mut info = json!({ "index": self.textures.len() - 1 });
        if texture.sampling.tex_coord != 0 {
            info["texCoord"] = json!(texture.sampling.tex_coord);
        }
        let transform = texture.sampling.transform;
        if transform != Affine2::IDENTITY {
            let (offset, rotation, scale) = uv_transform_parts(&transform);
            let rebuilt = uv_transform(offset, rotation, scale);
            let size = transform.to_cols_array().iter().fold(1f32, |a, c| a.max(c.abs()));
            if !rebuilt.abs_diff_eq(transform, 1e-5 * size) {
                return Err(Error::input(format!(
                    "material '{}': the texture transform {transform:?} shears, which KHR_texture_transform cannot say",
                    m.name
                )));
            }
            info["extensions"] = json!({ "KHR_texture_transform": {
                "offset": offset.to_array(), "rotation": rotation, "scale": scale.to_array()
            } });
            self.use_extension("KHR_texture_transform");
        }
        Ok(info)
    }

    /// The index of a texture sampler for `sampling` (its wrap and filters), one per
    /// distinct sampler. Every field is written: a missing filter is the reader's choice.
    fn sampler(&mut self, sampling: &Sampling) -> usize {
        let entry = sampler_json(sampling);
        match self.texture_samplers.iter().position(|s| *s == entry) {
            Some(i) => i,
            None => {
                self.texture_samplers.push(entry);
                self.texture_samplers.len() - 1
            }
        }
    }

    /// Records that the document uses extension `name`.
    fn use_extension(&mut self, name: &'static str) {
        if !self.extensions_used.contains(&name) {
            self.extensions_used.push(name);
        }
    }

    /// An image's JSON, its PNG stored where `name` says.
    fn image_json(&mut self, texture: &Texture, name: &ImageName, files: &SideFiles) -> Result<Value> {
        let png = encode_png(texture).map_err(|e| output(files.path, &e))?;
        Ok(match name.storage {
            Storage::Embedded => json!({ "bufferView": self.b.view(&png), "mimeType": "image/png" }),
            Storage::DataUri => json!({ "uri": format!("data:image/png;base64,{}", encode_base64(&png)) }),
            Storage::External => {
                let name = format!("{}_image{}{}.png", files.stem, name.material, name.kind);
                files.write(&name, &png)?;
                json!({ "uri": name })
            }
        })
    }

    /// Sets `material`'s emission, with the strength extension where it exceeds 1.
    fn set_emission(&mut self, material: &mut Value, emissive: Vec3) {
        let peak = emissive.max_element();
        if peak > 0.0 {
            // emissiveFactor is limited to [0, 1]: the rest goes into the strength.
            let strength = peak.max(1.0);
            let factor = emissive / strength;
            material["emissiveFactor"] = json!([factor.x, factor.y, factor.z]);
            if strength > 1.0 {
                material["extensions"] = json!({ "KHR_materials_emissive_strength": { "emissiveStrength": strength } });
                self.use_extension("KHR_materials_emissive_strength");
            }
        }
    }

    /// Adds the node hierarchy and returns the glTF TRS node of each vrao node.
    fn add_nodes(&mut self, scene: &Scene) -> Vec<usize> {
        // Nodes: vrao node k is glTF node trs[k] (under a matrix node when it has a base).
        let mut trs_of = Vec::with_capacity(scene.nodes.len());
        for node in &scene.nodes {
            let mut attach = node.parent.and_then(|p| trs_of.get(p).copied());
            if node.base != DMat4::IDENTITY {
                let base =
                    json!({ "name": format!("{} base", node.name), "matrix": node.base.as_mat4().to_cols_array() });
                attach = Some(self.add_node(base, attach));
            }
            let r = node.rest;
            let trs = json!({
                "name": node.name,
                "translation": r.translation.as_vec3().to_array(),
                "rotation": r.rotation.as_quat().normalize().to_array(),
                "scale": r.scale.as_vec3().to_array(),
            });
            trs_of.push(self.add_node(trs, attach));
        }
        trs_of
    }

    /// Adds `mesh` as one glTF mesh with one primitive, on a node of its own.
    fn add_mesh(&mut self, scene: &Scene, mesh: &Mesh, options: &WriteOptions, trs_of: &[usize]) -> Result<()> {
        let textured = scene.materials.get(mesh.material).is_some_and(|m| {
            m.diffuse_texture.is_some()
                || m.emissive_texture.is_some()
                || m.normal_texture.is_some()
                || m.occlusion_texture.is_some()
        });
        let v = mesh_vertices(mesh, options.indices);
        let count = v.positions.len();
        let attributes = self.b.attributes(&v, textured, options);
        let mut primitive = json!({ "attributes": attributes, "mode": 4, "material": mesh.material });
        if let Some(t) = index_type(options.indices, count) {
            if !index_fits(t, count) {
                return Err(Error::input(format!("mesh '{}': {count} vertices do not fit {t:?} indices", mesh.name)));
            }
            primitive["indices"] = json!(self.b.indices(&v.indices, t));
        }
        self.meshes.push(json!({ "name": mesh.name, "primitives": [primitive] }));
        let parent = mesh.node.and_then(|k| trs_of.get(k).copied());
        self.add_node(json!({ "name": mesh.name, "mesh": self.meshes.len() - 1 }), parent);
        Ok(())
    }

    /// Adds the animation: one channel per animated property.
    fn add_animation(&mut self, scene: &Scene, trs_of: &[usize]) {
        for (k, node) in scene.nodes.iter().enumerate() {
            let target = trs_of[k];
            if let Some(t) = &node.tracks.translation {
                let values: Vec<f32> = t.values.iter().flat_map(|v| v.as_vec3().to_array()).collect();
                self.add_channel(Channel {
                    track: t,
                    values: &values,
                    kind: "VEC3",
                    node: target,
                    path: "translation",
                });
            }
            if let Some(t) = &node.tracks.rotation {
                let values: Vec<f32> = t.values.iter().flat_map(|q| q.as_quat().to_array()).collect();
                self.add_channel(Channel { track: t, values: &values, kind: "VEC4", node: target, path: "rotation" });
            }
            if let Some(t) = &node.tracks.scale {
                let values: Vec<f32> = t.values.iter().flat_map(|v| v.as_vec3().to_array()).collect();
                self.add_channel(Channel { track: t, values: &values, kind: "VEC3", node: target, path: "scale" });
            }
        }
    }

    /// Adds one animation channel and its sampler.
    fn add_channel<T>(&mut self, c: Channel<T>) {
        self.samplers.push(sampler(&mut self.b, c.track, c.values, c.kind));
        self.channels.push(json!({ "sampler": self.samplers.len() - 1, "target": { "node": c.node, "path": c.path } }));
    }

    /// Adds every light (`KHR_lights_punctual`), each on a root node of its own.
    fn add_lights(&mut self, scene: &Scene) {
        for light in &scene.lights {
            let (entry, position, direction) = light_json(light);
            self.lights.push(entry);
            // Lights shine along their node's −Z.
            let rotation = DQuat::from_rotation_arc(DVec3::NEG_Z, direction.as_dvec3().normalize_or(DVec3::NEG_Z));
            let node = json!({
                "name": format!("light {}", self.lights.len() - 1),
                "translation": position.as_vec3().to_array(),
                "rotation": rotation.as_quat().normalize().to_array(),
                "extensions": { "KHR_lights_punctual": { "light": self.lights.len() - 1 } },
            });
            self.add_node(node, None);
        }
        if !self.lights.is_empty() {
            self.use_extension("KHR_lights_punctual");
        }
    }

    /// Adds a camera at `pose`, if any, on a root node of its own.
    fn add_camera(&mut self, pose: Option<HeadPose>) {
        if let Some(pose) = pose {
            self.cameras.push(json!({ "type": "perspective", "perspective": { "yfov": 1.6, "znear": 0.05 } }));
            let node = json!({
                "name": "camera",
                "camera": 0,
                "translation": pose.position.as_vec3().to_array(),
                "rotation": pose.orientation.as_quat().normalize().to_array(),
            });
            self.add_node(node, None);
        }
    }

    /// Pads the binary buffer to 4 bytes and returns its JSON, writing it as a side file
    /// or encoding it as a data URI where a `.gltf` asks for it.
    fn buffer_json(&mut self, glb: bool, storage: Storage, files: &SideFiles) -> Result<Value> {
        let bin = &mut self.b.bin;
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        Ok(match (glb, storage) {
            (true, _) => json!({ "byteLength": bin.len() }),
            (false, Storage::External) => {
                let name = format!("{}.bin", files.stem);
                files.write(&name, bin)?;
                json!({ "byteLength": bin.len(), "uri": name })
            }
            (false, _) => json!({
                "byteLength": bin.len(),
                "uri": format!("data:application/octet-stream;base64,{}", encode_base64(bin)),
            }),
        })
    }

    /// The whole glTF JSON document, with `buffer` as its one buffer; lists that would be
    /// empty are left out.
    fn into_json(self, scene_name: &str, buffer: Value) -> Value {
        let mut document = json!({
            "asset": { "version": "2.0", "generator": "vrao" },
            "scene": 0,
            "scenes": [{ "name": scene_name, "nodes": self.roots }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "accessors": self.b.accessors,
            "bufferViews": self.b.views,
            "buffers": [buffer],
        });
        let object = document.as_object_mut().expect("an object");
        for (key, list) in [
            ("images", self.images),
            ("samplers", self.texture_samplers),
            ("textures", self.textures),
            ("cameras", self.cameras),
        ] {
            if !list.is_empty() {
                object.insert(key.into(), Value::Array(list));
            }
        }
        if !self.channels.is_empty() {
            let animation = json!({ "name": "motion", "channels": self.channels, "samplers": self.samplers });
            object.insert("animations".into(), json!([animation]));
        }
        if !self.lights.is_empty() {
            object.insert("extensions".into(), json!({ "KHR_lights_punctual": { "lights": self.lights } }));
        }
        if !self.extensions_used.is_empty() {
            object.insert("extensionsUsed".into(), json!(self.extensions_used));
        }
        document
    }
}

/// One animated property of one node, for [`Document::add_channel`].
struct Channel<'a, T> {
    track: &'a Track<T>,
    /// The track's values, flattened to f32.
    values: &'a [f32],
    /// The accessor type of one value.
    kind: &'a str,
    /// The glTF node it animates.
    node: usize,
    /// The property it animates.
    path: &'a str,
}

/// Where one image goes and what it is called as a side file: `STEM_imageM.png` for
/// material M's base colour, `STEM_imageM_KIND.png` for its other textures.
struct ImageName {
    material: usize,
    /// "" for the base colour, else `_emissive`, `_normal` or `_occlusion`.
    kind: String,
    storage: Storage,
}

/// A texture sampler's JSON: its wrap per axis and both filters.
fn sampler_json(sampling: &Sampling) -> Value {
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => REPEAT,
        Wrap::MirroredRepeat => MIRRORED_REPEAT,
        Wrap::ClampToEdge => CLAMP_TO_EDGE,
    };
    let magnify = match sampling.magnify {
        Filter::Nearest => NEAREST,
        Filter::Linear => LINEAR,
    };
    let minify = match (sampling.minify, sampling.mipmaps) {
        (Filter::Nearest, None) => NEAREST,
        (Filter::Linear, None) => LINEAR,
        (Filter::Nearest, Some(Filter::Nearest)) => NEAREST_MIPMAP_NEAREST,
        (Filter::Linear, Some(Filter::Nearest)) => LINEAR_MIPMAP_NEAREST,
        (Filter::Nearest, Some(Filter::Linear)) => NEAREST_MIPMAP_LINEAR,
        (Filter::Linear, Some(Filter::Linear)) => LINEAR_MIPMAP_LINEAR,
    };
    json!({ "magFilter": magnify, "minFilter": minify, "wrapS": wrap(sampling.wrap_u), "wrapT": wrap(sampling.wrap_v) })
}

const NEAREST: u32 = 9728;
const LINEAR: u32 = 9729;
const NEAREST_MIPMAP_NEAREST: u32 = 9984;
const LINEAR_MIPMAP_NEAREST: u32 = 9985;
const NEAREST_MIPMAP_LINEAR: u32 = 9986;
const LINEAR_MIPMAP_LINEAR: u32 = 9987;
const CLAMP_TO_EDGE: u32 = 33071;
const MIRRORED_REPEAT: u32 = 33648;
const REPEAT: u32 = 10497;

/// Sets `material`'s alpha mode, and its cutoff for a mask.
fn set_alpha_mode(material: &mut Value, mode: AlphaMode) {
    match mode {
        AlphaMode::Opaque => material["alphaMode"] = json!("OPAQUE"),
        AlphaMode::Mask { cutoff } => {
            material["alphaMode"] = json!("MASK");
            material["alphaCutoff"] = json!(cutoff);
        }
        AlphaMode::Blend => material["alphaMode"] = json!("BLEND"),
    }
}

/// `mesh`'s vertices in f32 world space, repeated per triangle for non-indexed storage.
fn mesh_vertices(mesh: &Mesh, index_type: IndexType) -> MeshVertices {
    let mut positions = world_f32(mesh.origin, &mesh.positions);
    let mut normals = mesh.normals.clone();
    let mut uvs = mesh.uvs.clone();
    let mut uvs1 = mesh.uvs1.clone();
    let mut colors = mesh.colors.clone();
    let mut tangents = mesh.tangents.clone();
    let mut indices = mesh.indices.clone();
    if index_type == IndexType::NonIndexed {
        positions = indices.iter().map(|&i| positions[i as usize]).collect();
        normals = indices.iter().map(|&i| normals[i as usize]).collect();
        uvs = indices.iter().map(|&i| uvs[i as usize]).collect();
        if !uvs1.is_empty() {
            uvs1 = indices.iter().map(|&i| uvs1[i as usize]).collect();
        }
        if !colors.is_empty() {
            colors = indices.iter().map(|&i| colors[i as usize]).collect();
        }
        if !tangents.is_empty() {
            tangents = indices.iter().map(|&i| tangents[i as usize]).collect();
        }
        indices = (0..positions.len() as u32).collect();
    }
    MeshVertices { positions, normals, uvs, uvs1, colors, tangents, indices }
}

/// The index type a mesh of `count` vertices is written with (`None`: non-indexed).
fn index_type(asked: IndexType, count: usize) -> Option<IndexType> {
    match asked {
        IndexType::NonIndexed => None,
        IndexType::Smallest if count <= 256 => Some(IndexType::U8),
        IndexType::Smallest if count <= 65536 => Some(IndexType::U16),
        IndexType::Smallest => Some(IndexType::U32),
        other => Some(other),
    }
}

/// Whether indices of type `t` can address `count` vertices.
fn index_fits(t: IndexType, count: usize) -> bool {
    match t {
        IndexType::U8 => count <= 256,
        IndexType::U16 => count <= 65536,
        _ => true,
    }
}

/// A light's `KHR_lights_punctual` entry, with the position and direction of its node.
fn light_json(light: &Light) -> (Value, DVec3, Vec3) {
    let (kind, position, direction, color, intensity) = match *light {
        Light::Directional { direction, color, intensity } => ("directional", DVec3::ZERO, direction, color, intensity),
        Light::Point { position, color, intensity } => ("point", position, Vec3::NEG_Z, color, intensity),
        Light::Spot { position, direction, color, intensity, .. } => ("spot", position, direction, color, intensity),
    };
    let mut entry = json!({ "type": kind, "color": color.to_array(), "intensity": intensity });
    if let Light::Spot { inner_cone, outer_cone, .. } = *light {
        entry["spot"] = json!({ "innerConeAngle": inner_cone, "outerConeAngle": outer_cone });
    }
    (entry, position, direction)
}

/// `document` through `gltf::json` and its validation: the writer's output is glTF the
/// loader reads.
fn validated(document: Value) -> Result<::gltf::json::Root> {
    let root: ::gltf::json::Root =
        serde_json::from_value(document).map_err(|e| Error::input(format!("glTF writer built invalid JSON: {e}")))?;
    Ok(::gltf::Document::from_json(root)
        .map_err(|e| Error::input(format!("glTF writer built an invalid document: {e}")))?
        .into_json())
}

/// The file's bytes: the serialised JSON, or a `.glb` of it and `bin`.
fn file_bytes(root: &::gltf::json::Root, glb: bool, bin: Vec<u8>, path: &Path) -> Result<Vec<u8>> {
    let text = ::gltf::json::serialize::to_vec(root).map_err(|e| output(path, &e))?;
    if !glb {
        return Ok(text);
    }
    let glb = ::gltf::binary::Glb {
        header: ::gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: text.into(),
        bin: Some(bin.into()),
    };
    glb.to_vec().map_err(|e| output(path, &e))
}

/// World positions as f32 that the loaders' recentring (on the centre of their bounds)
/// turns back into exactly `origin` and `offsets`, so that a loaded OBJ written as glTF
/// loads bit for bit as the OBJ did. Each coordinate is the nearest f32 to origin + offset
/// or a neighbour of it (the OBJ's own f32 is one of these); the extremes are chosen as a
/// pair whose centre is `origin`.
fn world_f32(origin: DVec3, offsets: &[Vec3]) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; offsets.len()];
    for k in 0..3 {
        let o = origin[k];
        let (lo, hi) = offsets.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| (a.min(p[k]), b.max(p[k])));
        let pair = candidates(o, lo)
            .into_iter()
            .flat_map(|a| candidates(o, hi).into_iter().map(move |b| (a, b)))
            .find(|&(a, b)| (a as f64 + b as f64) * 0.5 == o);
        for (w, p) in out.iter_mut().zip(offsets) {
            w[k] = match pair {
                Some((a, _)) if p[k] == lo => a,
                Some((_, b)) if p[k] == hi => b,
                _ => candidates(o, p[k]).first().copied().unwrap_or((o + p[k] as f64) as f32),
            };
        }
    }
    out
}

/// The f32 values within one step of origin + offset whose offset from `origin`, rounded
/// to f32, is `offset` again (nearest first).
fn candidates(origin: f64, offset: f32) -> Vec<f32> {
    let nearest = (origin + offset as f64) as f32;
    [nearest, nearest.next_down(), nearest.next_up()]
        .into_iter()
        .filter(|&w| ((w as f64 - origin) as f32).to_bits() == offset.to_bits())
        .collect()
}

/// A sampler's JSON with its input (times) and output (values) accessors.
fn sampler<T>(b: &mut Builder, track: &Track<T>, values: &[f32], kind: &str) -> Value {
    let times: Vec<f32> = track.times.iter().map(|&t| t as f32).collect();
    let (lo, hi) = (times.first().copied().unwrap_or(0.0), times.last().copied().unwrap_or(0.0));
    let input = b.floats(&times, "SCALAR", times.len(), json!({ "min": [lo], "max": [hi] }));
    let per = if kind == "VEC4" { 4 } else { 3 };
    let output = b.floats(values, kind, values.len() / per, json!({}));
    let interpolation = match track.interpolation {
        Interpolation::Step => "STEP",
        Interpolation::Linear => "LINEAR",
        Interpolation::CubicSpline => "CUBICSPLINE",
    };
    json!({ "input": input, "output": output, "interpolation": interpolation })
}

/// A texture as PNG bytes.
fn encode_png(texture: &Texture) -> std::result::Result<Vec<u8>, image::ImageError> {
    let mut png = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut png);
    image::ImageEncoder::write_image(
        encoder,
        &texture.rgba8,
        texture.width,
        texture.height,
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(png)
}

/// Standard base64 with padding.
pub fn encode_base64(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let bits = chunk.iter().enumerate().fold(0u32, |acc, (i, &b)| acc | (b as u32) << (16 - 8 * i));
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(DIGITS[(bits >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;
    use vrao_render::scene::HeadPath;

    /// A 2×2 RGBA texture sampled as `sampling`.
    fn texture(sampling: Sampling) -> Texture {
        Texture {
            width: 2,
            height: 2,
            rgba8: (0..16).map(|i| i * 16).collect::<Vec<u8>>().into(),
            source: None,
            sampling,
        }
    }

    /// A unit quad in z = 0 with `colors` and `tangents` (each empty or one per corner).
    fn quad(name: &str, material: usize, colors: Vec<Vec4>, tangents: Vec<Vec4>) -> Mesh {
        Mesh {
            name: name.into(),
            origin: DVec3::ZERO,
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            uvs1: Vec::new(),
            colors,
            tangents,
            indices: vec![0, 1, 2, 0, 2, 3],
            material,
            node: None,
        }
    }

    fn scene(meshes: Vec<Mesh>, materials: Vec<Material>) -> Scene {
        Scene {
            name: "materials".into(),
            meshes,
            materials,
            lights: vec![],
            environment: None,
            head: HeadPath::fixed(HeadPose::IDENTITY),
            nodes: Vec::new(),
        }
    }

    /// Every kind of texture and vertex attribute the writer knows: material 0 has a
    /// tiled, transformed, nearest base colour, an emission texture with the default
    /// sampler, a normal texture and an occlusion texture sampled as the base colour.
    fn everything() -> Scene {
        let tiled = Sampling {
            wrap_u: Wrap::MirroredRepeat,
            wrap_v: Wrap::ClampToEdge,
            magnify: Filter::Nearest,
            minify: Filter::Linear,
            mipmaps: None,
            transform: uv_transform(Vec2::new(0.25, -0.5), 0.3, Vec2::new(2.0, 3.0)),
            tex_coord: 0,
        };
        let mut m = Material::plain("everything", Vec3::new(0.5, 0.6, 0.7));
        m.emissive = Vec3::new(0.2, 0.1, 0.0);
        m.diffuse_texture = Some(texture(tiled));
        m.emissive_texture = Some(texture(Sampling::default()));
        m.normal_texture = Some((texture(Sampling { mipmaps: Some(Filter::Nearest), ..Sampling::default() }), 0.7));
        m.occlusion_texture = Some((texture(tiled), 0.4));
        let translucent = vec![Vec4::new(1.0, 0.0, 0.0, 0.5), Vec4::ONE, Vec4::new(0.0, 0.0, 1.0, 1.0), Vec4::W];
        let tangents = vec![Vec4::new(1.0, 0.0, 0.0, -1.0); 4];
        let opaque = vec![Vec4::new(0.0, 1.0, 0.0, 1.0); 4];
        scene(
            vec![quad("translucent", 0, translucent, tangents), quad("opaque", 1, opaque, vec![])],
            vec![m, Material::plain("plain", Vec3::ONE)],
        )
    }

    /// `scene` written to a `.gltf` named `name` with `options`, read back as JSON.
    fn written(scene: &Scene, name: &str, options: &WriteOptions) -> (Value, vrao_render::test_dir::TestDir) {
        let dir = vrao_render::test_dir::TestDir::new(&format!("gltf-write-{name}"));
        let path = dir.join(format!("{name}.gltf"));
        write(scene, &path, options).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        ::gltf::Gltf::from_slice(&bytes).expect("the gltf crate reads what was written");
        (serde_json::from_slice(&bytes).unwrap(), dir)
    }

    /// The accessor type of attribute `name` of mesh `mesh`'s primitive, if written.
    fn attribute_type<'a>(doc: &'a Value, mesh: usize, name: &str) -> Option<&'a str> {
        let accessor = doc["meshes"][mesh]["primitives"][0]["attributes"][name].as_u64()?;
        doc["accessors"][accessor as usize]["type"].as_str()
    }

    #[test]
    fn samplers_texture_transforms_and_every_texture_are_written() {
        let options = WriteOptions { buffers: Storage::DataUri, images: Storage::DataUri, ..Default::default() };
        let (doc, dir) = written(&everything(), "everything", &options);
        let material = &doc["materials"][0];
        let base = &material["pbrMetallicRoughness"]["baseColorTexture"];
        let texture = |info: &Value| doc["textures"][info["index"].as_u64().unwrap() as usize].clone();
        // One sampler, shared by the base colour and occlusion textures; none (glTF's
        // default) for the emission texture; the normal texture's differs in its mipmaps.
        let samplers = doc["samplers"].as_array().unwrap();
        assert_eq!(samplers.len(), 2, "{samplers:?}");
        let tiled = &samplers[texture(base)["sampler"].as_u64().unwrap() as usize];
        assert_eq!(tiled, &json!({ "magFilter": 9728, "minFilter": 9729, "wrapS": 33648, "wrapT": 33071 }));
        assert_eq!(texture(&material["occlusionTexture"])["sampler"], texture(base)["sampler"]);
        assert!(texture(&material["emissiveTexture"]).get("sampler").is_none());
        let normal = &samplers[texture(&material["normalTexture"])["sampler"].as_u64().unwrap() as usize];
        assert_eq!(normal, &json!({ "magFilter": 9729, "minFilter": 9985, "wrapS": 10497, "wrapT": 10497 }));
        // The transform as offset, rotation and scale, on the base colour and occlusion
        // references only; rebuilt, it is the transform that was written.
        let t = &base["extensions"]["KHR_texture_transform"];
        let f = |v: &Value| v.as_f64().unwrap() as f32;
        let (offset, rotation, scale) = (
            Vec2::new(f(&t["offset"][0]), f(&t["offset"][1])),
            f(&t["rotation"]),
            Vec2::new(f(&t["scale"][0]), f(&t["scale"][1])),
        );
        assert!((offset - Vec2::new(0.25, -0.5)).length() < 1e-6 && (rotation - 0.3).abs() < 1e-6, "{t}");
        assert!((scale - Vec2::new(2.0, 3.0)).length() < 1e-5, "{t}");
        let original = everything().materials[0].diffuse_texture.as_ref().unwrap().sampling.transform;
        assert!(uv_transform(offset, rotation, scale).abs_diff_eq(original, 1e-5));
        assert!(material["occlusionTexture"]["extensions"]["KHR_texture_transform"].is_object());
        assert!(material["emissiveTexture"].get("extensions").is_none());
        assert_eq!(doc["extensionsUsed"], json!(["KHR_texture_transform"]));
        // Scale and strength beside their textures.
        assert_eq!(f(&material["normalTexture"]["scale"]), 0.7);
        assert_eq!(f(&material["occlusionTexture"]["strength"]), 0.4);
        assert_eq!(doc["images"].as_array().unwrap().len(), 4);
        // Colours with an alpha below 1 as VEC4, opaque ones as VEC3; tangents where the
        // mesh has them.
        assert_eq!(attribute_type(&doc, 0, "COLOR_0"), Some("VEC4"));
        assert_eq!(attribute_type(&doc, 0, "TANGENT"), Some("VEC4"));
        assert_eq!(attribute_type(&doc, 1, "COLOR_0"), Some("VEC3"));
        assert_eq!(attribute_type(&doc, 1, "TANGENT"), None);
        assert_eq!(attribute_type(&doc, 1, "TEXCOORD_0"), None, "material 1 has no texture");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn vertex_colours_and_tangents_follow_the_vertices_they_belong_to() {
        // Non-indexed: repeated per triangle corner, as the positions are.
        let options = WriteOptions {
            buffers: Storage::External,
            images: Storage::External,
            indices: IndexType::NonIndexed,
            ..Default::default()
        };
        let scene = everything();
        let (doc, dir) = written(&scene, "nonindexed", &options);
        let bin = std::fs::read(dir.join("nonindexed.bin")).unwrap();
        let floats = |attribute: &str| -> Vec<f32> {
            let accessor = &doc["accessors"]
                [doc["meshes"][0]["primitives"][0]["attributes"][attribute].as_u64().unwrap() as usize];
            let view = &doc["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
            let (start, length) =
                (view["byteOffset"].as_u64().unwrap() as usize, view["byteLength"].as_u64().unwrap() as usize);
            bytemuck::pod_collect_to_vec(&bin[start..start + length])
        };
        let mesh = &scene.meshes[0];
        let expected =
            |v: &[Vec4]| -> Vec<f32> { mesh.indices.iter().flat_map(|&i| v[i as usize].to_array()).collect() };
        assert_eq!(floats("COLOR_0"), expected(&mesh.colors));
        assert_eq!(floats("TANGENT"), expected(&mesh.tangents));
        // External images: the base colour keeps its name, the others say what they are.
        for name in ["_image0.png", "_image0_emissive.png", "_image0_normal.png", "_image0_occlusion.png"] {
            assert!(dir.join(format!("nonindexed{name}")).is_file(), "{name}");
        }
        // Without normals, tangents are not written (the specification ignores them).
        let (doc, _) = written(&scene, "nonormals", &WriteOptions { normals: false, ..Default::default() });
        assert_eq!(attribute_type(&doc, 0, "TANGENT"), None);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn default_samplers_and_identity_transforms_write_nothing_and_a_shear_is_refused() {
        let mut m = Material::plain("default", Vec3::ONE);
        m.diffuse_texture = Some(texture(Sampling::default()));
        let (doc, dir) =
            written(&scene(vec![quad("q", 0, vec![], vec![])], vec![m.clone()]), "default", &Default::default());
        assert!(doc.get("samplers").is_none() && doc.get("extensionsUsed").is_none(), "{doc}");
        assert_eq!(doc["textures"], json!([{ "source": 0 }]));
        assert!(doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].get("extensions").is_none());
        assert_eq!(attribute_type(&doc, 0, "COLOR_0"), None);
        std::fs::remove_dir_all(&dir).ok();
        // A transform with shear has no offset, rotation and scale: refused, naming the material.
        let sheared = Affine2::from_cols_array(&[1.0, 0.0, 0.5, 1.0, 0.0, 0.0]);
        m.diffuse_texture = Some(texture(Sampling { transform: sheared, ..Sampling::default() }));
        let dir = vrao_render::test_dir::TestDir::new("gltf-write-sheared");
        let path = dir.join("sheared.gltf");
        let e = write(&scene(vec![quad("q", 0, vec![], vec![])], vec![m]), &path, &Default::default()).unwrap_err();
        assert!(e.to_string().contains("'default'") && e.to_string().contains("shear"), "{e}");
    }

    #[test]
    fn base64_round_trips() {
        for n in 0..10 {
            let bytes: Vec<u8> = (0..n).map(|i| (i * 37 + 11) as u8).collect();
            let text = super::encode_base64(&bytes);
            assert_eq!(text.len() % 4, 0);
            assert_eq!(vrao_render::scene::gltf::decode_base64(&text).unwrap(), bytes, "{text}");
        }
        assert_eq!(super::encode_base64(b"hello"), "aGVsbG8=");
    }
}
