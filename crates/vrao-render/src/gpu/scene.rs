//! The scene on the GPU: one vertex and one index buffer for all meshes, positions
//! relative to an f64 anchor, one uniform + texture per material, and one transform slot
//! per moving object.
//!
//! Static meshes are uploaded in the anchored world frame and drawn with object 0, whose
//! transform is the identity (exact in f32: the multiply changes no bit). A moving mesh
//! ([`crate::scene::Mesh::node`]) is uploaded once in its node's local frame and
//! moved by its object's transform, which [`GpuScene::set_time`] writes each frame with the
//! previous frame's beside it (the G-buffer's motion vectors), so nothing is re-uploaded.

use super::kernel::wgsl;
use super::raster::{DrawKind, MeshPipelines};
use super::textures::{self, Encoding, Samplers};
use crate::lighting::ShadingBuffers;
use crate::scene::{Environment, Material, Scene, Texture};
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec3};
use std::collections::HashMap;
use vrao_ao::plug::{Gpu, Shader};
use wgpu::util::DeviceExt;

/// mesh.wgsl: the material bind group, `VertexIn` and the material's albedo, shared by
/// the passes that draw the meshes with their materials.
pub const MESH_WGSL: Shader = wgsl!("shaders/mesh.wgsl");

/// One mesh vertex as the vertex buffer holds it.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Vertex {
    /// Position in metres relative to [`GpuScene::anchor`].
    pub position: [f32; 3],
    /// Unit surface normal in world space.
    pub normal: [f32; 3],
    /// Texture coordinates: set 0 in the first two, set 1 (set 0 again where the mesh has
    /// none) in the last two; each texture reads the set its placement names.
    pub uv: [f32; 4],
    /// Linear RGBA vertex colour (unorm8; white without one).
    pub color: [u8; 4],
    /// Tangent along +u and the bitangent's sign in w (snorm16); zero without one, when
    /// the shader finds the tangent frame from screen-space derivatives.
    pub tangent: [i16; 4],
}

/// One material's constants (`Material` of mesh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct MaterialUniform {
    /// Diffuse albedo in rgb; w is 1 when a diffuse texture multiplies it, else 0.
    pub diffuse: [f32; 4],
    /// Emitted radiance in rgb (the emissive texture multiplies it); w unused.
    pub emission: [f32; 4],
    /// x: alpha factor; y: the alpha-test cutoff (−1 for a solid material); z: the normal
    /// texture's scale (0 without one); w: the occlusion texture's strength (0 without one).
    pub alpha: [f32; 4],
    /// Each texture's placement (`KHR_texture_transform`) in [`MaterialTexture`] order, two
    /// rows each: (the 2×2 matrix's columns), (the offset, the texture coordinate set, 0).
    pub placements: [[f32; 4]; 8],
}

/// The textures a material binds, in binding order (mesh.wgsl: texture at 1 + 2k…).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialTexture {
    /// Base colour (sRGB; white without one).
    Diffuse = 0,
    /// Emission (sRGB; white without one).
    Emissive = 1,
    /// Tangent-space normals (linear; unused without one: the scale is 0).
    Normal = 2,
    /// Baked occlusion in red (linear; white without one).
    Occlusion = 3,
}

/// The binding of each [`MaterialTexture`]'s texture (its sampler follows it).
const TEXTURE_BINDINGS: [u32; 4] = [1, 4, 6, 8];

/// One object's transforms (`Object` of mesh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ObjectUniform {
    /// This frame's anchored-from-local transform.
    pub anchored_from_local: [[f32; 4]; 4],
    /// The previous frame's (motion vectors).
    pub previous_anchored_from_local: [[f32; 4]; 4],
    /// The inverse transpose of this frame's, for normals.
    pub normal_from_local: [[f32; 4]; 4],
}

/// Bytes between objects' slots in the object buffer: the largest uniform-offset
/// alignment a device may ask for.
const OBJECT_STRIDE: u64 = 256;

/// One material on the GPU: its uniform, and its textures with their samplers.
pub struct GpuMaterial {
    /// The [`MaterialUniform`].
    pub uniform: wgpu::Buffer,
    /// Its textures in [`MaterialTexture`] order, a 1×1 placeholder where it has none.
    pub textures: [(wgpu::TextureView, wgpu::Sampler); 4],
    /// Whether it has its own diffuse texture (rather than the placeholder).
    pub has_texture: bool,
    /// Whether both its faces are drawn ([`Material::double_sided`]).
    pub double_sided: bool,
}

/// A contiguous range of indices drawn with one material and one object transform.
pub struct Draw {
    /// Indices into [`GpuScene::indices`] to draw.
    pub indices: std::ops::Range<u32>,
    /// Index into [`GpuScene::materials`].
    pub material: usize,
    /// The object slot that moves it (0: static geometry).
    pub object: usize,
    /// Whether its material is alpha-tested, and single-sided (its back faces culled).
    pub kind: DrawKind,
    /// Its material and object (layout: [`GpuScene::material_layout`]).
    pub group: wgpu::BindGroup,
}

/// The scene's meshes, materials and environment uploaded once, shared by every pass.
pub struct GpuScene {
    /// Every position on the GPU is relative to this world point (f64), so geometry far
    /// from the world origin keeps f32 precision.
    pub anchor: DVec3,
    /// Every mesh's [`Vertex`]es, concatenated.
    pub vertices: wgpu::Buffer,
    /// Every mesh's u32 indices, offset into `vertices`.
    pub indices: wgpu::Buffer,
    /// One draw per contiguous run of one material.
    pub draws: Vec<Draw>,
    /// The scene's materials, in scene order.
    pub materials: Vec<GpuMaterial>,
    /// Layout of a draw's bind group (material uniform, diffuse texture, sampler, object
    /// transforms): the G-buffer, the light-space pass and the depth peel draw the scene
    /// with it, at group 1.
    pub material_layout: wgpu::BindGroupLayout,
    /// One [`ObjectUniform`] slot per object, 256 bytes apart (`OBJECT_STRIDE`); slot 0 is the
    /// static geometry's identity.
    pub objects: wgpu::Buffer,
    /// The scene node each object slot after 0 follows.
    pub object_nodes: Vec<usize>,
    /// The kinds of draw the scene has (passes build a pipeline for each).
    pub kinds: Vec<DrawKind>,
    /// Whether some material has a normal texture (the G-buffer then writes the lighting's
    /// normals apart from the AO's).
    pub normal_mapped: bool,
    /// The environment as a filterable equirectangular texture (1×1 black without one).
    pub environment: wgpu::TextureView,
    /// Sampler of the environment (repeats around, clamps at the poles).
    pub sampler: wgpu::Sampler,
    /// The lights and the tone mapping, written each frame in the views' space.
    pub shading: ShadingBuffers,
}

impl GpuScene {
    /// Records every draw into `pass`, grouped by kind (solid before alpha-tested, for the
    /// early depth test), each group with its pipeline from `pipelines`, binding each
    /// draw's material and object at group 1.
    pub fn draw_with(&self, pass: &mut wgpu::RenderPass, pipelines: &MeshPipelines) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for kind in DrawKind::ALL {
            let Some(pipeline) = pipelines.get(kind) else { continue };
            pass.set_pipeline(pipeline);
            for draw in self.draws.iter().filter(|d| d.kind == kind && !d.indices.is_empty()) {
                pass.set_bind_group(1, &draw.group, &[]);
                pass.draw_indexed(draw.indices.clone(), 0, 0..1);
            }
        }
    }

    /// Whether some object moves (the scene has animated meshes).
    pub fn has_moving_objects(&self) -> bool {
        !self.object_nodes.is_empty()
    }

    /// Writes every moving object's transform at scene time `time`, with `previous` (the
    /// previous frame's time; `None` on a first frame or after a cut: no motion) beside it.
    pub fn set_time(&self, queue: &wgpu::Queue, scene: &Scene, time: f64, previous: Option<f64>) {
        if self.object_nodes.is_empty() {
            return;
        }
        let now = scene.node_transforms(time);
        let before = previous.map(|t| scene.node_transforms(t));
        for (i, &node) in self.object_nodes.iter().enumerate() {
            let current = now.get(node).copied().unwrap_or(DMat4::IDENTITY);
            let last = before.as_ref().and_then(|b| b.get(node).copied()).unwrap_or(current);
            let uniform = object_uniform(self.anchor, current, last);
            queue.write_buffer(&self.objects, (i as u64 + 1) * OBJECT_STRIDE, bytemuck::bytes_of(&uniform));
        }
    }

    /// Uploads `scene`'s geometry (relative to the centre of its bounds), materials and environment.
    pub fn upload(gpu: &Gpu, scene: &Scene) -> GpuScene {
        let bounds = scene.bounds();
        let anchor = if bounds.is_empty() { DVec3::ZERO } else { bounds.center() };
        let geometry = Geometry::gather(scene, anchor);
        let device = &gpu.device;
        let vertex_buffer =
            buffer_init(device, "scene vertices", bytemuck::cast_slice(&geometry.vertices), wgpu::BufferUsages::VERTEX);
        let index_buffer =
            buffer_init(device, "scene indices", bytemuck::cast_slice(&geometry.indices), wgpu::BufferUsages::INDEX);
        // Each material's alpha-test cutoff, found once (it scans the texture's alpha).
        let cutoffs = scene.alpha_cutoffs();
        let mut samplers = Samplers::default();
        let mut uploaded = UploadedTextures::new();
        let placeholders = Placeholders::new(gpu);
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .zip(&cutoffs)
            .map(|(m, &cutoff)| upload_material(gpu, m, cutoff, &mut samplers, &placeholders, &mut uploaded))
            .collect();
        let bindings = DrawBindings {
            sampler: environment_sampler(device),
            layout: material_layout(device),
            objects: object_buffer(device, anchor, geometry.object_nodes.len()),
        };
        let draws: Vec<Draw> =
            geometry.runs.into_iter().map(|run| bindings.draw(device, run, &materials, &cutoffs)).collect();
        let mut kinds: Vec<DrawKind> = draws.iter().map(|d| d.kind).collect();
        kinds.sort_by_key(|k| (k.alpha_test, k.cull));
        kinds.dedup();
        let normal_mapped = scene.materials.iter().any(|m| m.normal_texture.is_some());
        GpuScene {
            anchor,
            vertices: vertex_buffer,
            indices: index_buffer,
            draws,
            materials,
            material_layout: bindings.layout,
            objects: bindings.objects,
            object_nodes: geometry.object_nodes,
            kinds,
            normal_mapped,
            environment: environment_texture(gpu, scene.environment.as_ref()),
            sampler: bindings.sampler,
            shading: ShadingBuffers::new(device, scene.lights.len()),
        }
    }
}

/// The indices one draw covers, with its material and object slot (bind groups come later).
struct Run {
    indices: std::ops::Range<u32>,
    material: usize,
    object: usize,
}

/// Every mesh's vertices and indices concatenated, the draws over them, and the node each
/// moving object slot follows.
struct Geometry {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    runs: Vec<Run>,
    object_nodes: Vec<usize>,
}

impl Geometry {
    /// Gathers `scene`'s meshes: static ones relative to `anchor`, moving ones in their
    /// node's local frame.
    fn gather(scene: &Scene, anchor: DVec3) -> Geometry {
        let mut g = Geometry { vertices: Vec::new(), indices: Vec::new(), runs: Vec::new(), object_nodes: Vec::new() };
        // A node that mirrors (at rest) would turn its meshes' fronts away: their winding
        // is reversed so that culling keeps the faces the file meant.
        let rest = scene.node_transforms(0.0);
        let mirrored = |node: usize| rest.get(node).is_some_and(|m| glam::DMat3::from_mat4(*m).determinant() < 0.0);
        for mesh in &scene.meshes {
            let base = g.vertices.len() as u32;
            let (offset, object) = match mesh.node {
                // In the node's local frame; the object transform adds the anchor.
                Some(node) => (mesh.origin.as_vec3(), g.object_slot(node)),
                None => ((mesh.origin - anchor).as_vec3(), 0),
            };
            for i in 0..mesh.positions.len() {
                let color = mesh.colors.get(i).copied().unwrap_or(glam::Vec4::ONE);
                let tangent = mesh.tangents.get(i).copied().unwrap_or(glam::Vec4::ZERO);
                g.vertices.push(Vertex {
                    position: (mesh.positions[i] + offset).to_array(),
                    normal: mesh.normals[i].to_array(),
                    uv: uv_pair(mesh, i),
                    color: color.to_array().map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8),
                    tangent: tangent
                        .to_array()
                        .map(|c| (if c.is_finite() { c.clamp(-1.0, 1.0) } else { 0.0 } * 32767.0).round() as i16),
                });
            }
            let start = g.indices.len() as u32;
            g.indices.extend(mesh.indices.iter().map(|i| i + base));
            if mesh.node.is_some_and(mirrored) {
                g.indices[start as usize..].chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
            }
            g.runs.push(Run { indices: start..g.indices.len() as u32, material: mesh.material, object });
        }
        // wgpu rejects empty buffers; an empty scene draws nothing from a dummy vertex.
        if g.vertices.is_empty() {
            g.vertices.push(Vertex::zeroed());
            g.indices.extend([0, 0, 0]);
        }
        g
    }

    /// The object slot of animated `node`, given one at its first mesh.
    fn object_slot(&mut self, node: usize) -> usize {
        // Object slot 0 is static geometry; each animated node a mesh hangs from gets one.
        let slot = self.object_nodes.iter().position(|&n| n == node).unwrap_or_else(|| {
            self.object_nodes.push(node);
            self.object_nodes.len() - 1
        });
        slot + 1
    }
}

/// Vertex `i`'s texture coordinates, sets 0 and 1 ([`Vertex::uv`]).
fn uv_pair(mesh: &crate::scene::Mesh, i: usize) -> [f32; 4] {
    let uv0 = mesh.uvs.get(i).copied().unwrap_or_default();
    let uv1 = mesh.uvs1.get(i).copied().unwrap_or(uv0);
    [uv0.x, uv0.y, uv1.x, uv1.y]
}

/// What every draw's bind group binds besides its material: the layout, the diffuse
/// sampler and the object buffer.
struct DrawBindings {
    sampler: wgpu::Sampler,
    layout: wgpu::BindGroupLayout,
    objects: wgpu::Buffer,
}

impl DrawBindings {
    /// The draw of `run`, with the bind group of its material and object slot.
    fn draw(&self, device: &wgpu::Device, run: Run, materials: &[GpuMaterial], cutoffs: &[Option<f32>]) -> Draw {
        let m = &materials[run.material];
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("material and object"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: m.uniform.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.objects,
                        offset: run.object as u64 * OBJECT_STRIDE,
                        size: wgpu::BufferSize::new(std::mem::size_of::<ObjectUniform>() as u64),
                    }),
                },
                texture_entry(m, MaterialTexture::Diffuse),
                sampler_entry(m, MaterialTexture::Diffuse),
                texture_entry(m, MaterialTexture::Emissive),
                sampler_entry(m, MaterialTexture::Emissive),
                texture_entry(m, MaterialTexture::Normal),
                sampler_entry(m, MaterialTexture::Normal),
                texture_entry(m, MaterialTexture::Occlusion),
                sampler_entry(m, MaterialTexture::Occlusion),
            ],
        });
        let kind =
            DrawKind { alpha_test: cutoffs[run.material].is_some(), cull: !materials[run.material].double_sided };
        Draw { indices: run.indices, material: run.material, object: run.object, kind, group }
    }
}

/// A buffer created with `contents`.
fn buffer_init(device: &wgpu::Device, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
}

fn texture_entry(m: &GpuMaterial, kind: MaterialTexture) -> wgpu::BindGroupEntry<'_> {
    let binding = TEXTURE_BINDINGS[kind as usize];
    wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(&m.textures[kind as usize].0) }
}

fn sampler_entry(m: &GpuMaterial, kind: MaterialTexture) -> wgpu::BindGroupEntry<'_> {
    let binding = TEXTURE_BINDINGS[kind as usize] + 1;
    wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::Sampler(&m.textures[kind as usize].1) }
}

/// The 1×1 textures bound where a material has none: white (diffuse, emission,
/// occlusion multiply by 1) and a flat normal.
struct Placeholders {
    white_srgb: wgpu::TextureView,
    white_linear: wgpu::TextureView,
    flat_normal: wgpu::TextureView,
}

impl Placeholders {
    fn new(gpu: &Gpu) -> Self {
        Placeholders {
            white_srgb: textures::placeholder(gpu, "white", [255; 4], Encoding::Srgb),
            white_linear: textures::placeholder(gpu, "white (linear)", [255; 4], Encoding::Linear),
            flat_normal: textures::placeholder(gpu, "flat normal", [128, 128, 255, 255], Encoding::Linear),
        }
    }
}

/// Textures already on the GPU, by their texels (shared by every material slot that
/// names one image), encoding and whether they carry mipmaps: each uploaded once.
type UploadedTextures = HashMap<(usize, Encoding, bool), wgpu::TextureView>;

/// Material `m` on the GPU: its uniform (with its alpha-test `cutoff`) and its textures,
/// placeholders where it has none.
fn upload_material(
    gpu: &Gpu,
    m: &Material,
    cutoff: Option<f32>,
    samplers: &mut Samplers,
    placeholders: &Placeholders,
    uploaded_textures: &mut UploadedTextures,
) -> GpuMaterial {
    let mut upload = |texture: Option<&Texture>, kind: &str, encoding: Encoding, placeholder: &wgpu::TextureView| {
        let sampling = texture.map(|t| t.sampling).unwrap_or_default();
        let view = match texture {
            Some(t) => {
                let key = (std::sync::Arc::as_ptr(&t.rgba8) as usize, encoding, t.sampling.mipmaps.is_some());
                let label = format!("{} {kind}", m.name);
                uploaded_textures.entry(key).or_insert_with(|| textures::upload(gpu, &label, t, encoding)).clone()
            }
            None => placeholder.clone(),
        };
        (view, samplers.get(&gpu.device, &sampling), sampling)
    };
    let normal = m.normal_texture.as_ref();
    let occlusion = m.occlusion_texture.as_ref();
    let uploaded = [
        upload(m.diffuse_texture.as_ref(), "diffuse", Encoding::Srgb, &placeholders.white_srgb),
        upload(m.emissive_texture.as_ref(), "emissive", Encoding::Srgb, &placeholders.white_srgb),
        upload(normal.map(|(t, _)| t), "normal", Encoding::Linear, &placeholders.flat_normal),
        upload(occlusion.map(|(t, _)| t), "occlusion", Encoding::Linear, &placeholders.white_linear),
    ];
    let mut placements = [[0.0; 4]; 8];
    for (k, (_, _, sampling)) in uploaded.iter().enumerate() {
        let transform = sampling.transform;
        let (x, y) = (transform.matrix2.x_axis, transform.matrix2.y_axis);
        placements[2 * k] = [x.x, x.y, y.x, y.y];
        let set = sampling.tex_coord.min(1) as f32;
        placements[2 * k + 1] = [transform.translation.x, transform.translation.y, set, 0.0];
    }
    let has_texture = m.diffuse_texture.is_some();
    let uniform = MaterialUniform {
        diffuse: [m.diffuse.x, m.diffuse.y, m.diffuse.z, if has_texture { 1.0 } else { 0.0 }],
        emission: [m.emissive.x, m.emissive.y, m.emissive.z, 0.0],
        alpha: [m.alpha, cutoff.unwrap_or(-1.0), normal.map_or(0.0, |n| n.1), occlusion.map_or(0.0, |o| o.1)],
        placements,
    };
    let uniform = buffer_init(&gpu.device, &m.name, bytemuck::bytes_of(&uniform), wgpu::BufferUsages::UNIFORM);
    let textures = uploaded.map(|(view, sampler, _)| (view, sampler));
    GpuMaterial { uniform, textures, has_texture, double_sided: m.double_sided }
}

/// The environment's sampler: the equirectangular map repeats around the horizon and
/// clamps at the poles.
fn environment_sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("environment"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Nearest,
        ..Default::default()
    })
}

/// The object buffer: slot 0 for static geometry and one per moving object, `OBJECT_STRIDE` apart.
fn object_buffer(device: &wgpu::Device, anchor: DVec3, moving: usize) -> wgpu::Buffer {
    // Every slot starts at the identity (static geometry, and moving objects until
    // the first `set_time`) with no motion.
    let identity = object_uniform(anchor, DMat4::from_translation(anchor), DMat4::from_translation(anchor));
    let slots: Vec<u8> = (0..=moving)
        .flat_map(|_| {
            let mut slot = bytemuck::bytes_of(&identity).to_vec();
            slot.resize(OBJECT_STRIDE as usize, 0);
            slot
        })
        .collect();
    buffer_init(device, "scene objects", &slots, wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST)
}

/// An object's uniform: `world_from_local` now and in the previous frame, made relative
/// to the anchor in f64 before rounding to f32.
fn object_uniform(anchor: DVec3, world_from_local: DMat4, previous_world_from_local: DMat4) -> ObjectUniform {
    let anchored = DMat4::from_translation(-anchor);
    let now = anchored * world_from_local;
    let normal = glam::DMat3::from_mat4(now).inverse().transpose();
    let normal = if normal.is_finite() { DMat4::from_mat3(normal) } else { DMat4::IDENTITY };
    ObjectUniform {
        anchored_from_local: now.as_mat4().to_cols_array_2d(),
        previous_anchored_from_local: (anchored * previous_world_from_local).as_mat4().to_cols_array_2d(),
        normal_from_local: normal.as_mat4().to_cols_array_2d(),
    }
}

/// `v` as f16 bits, saturated to ±65504 and NaN as 0: `half` alone would give Inf or
/// NaN, and an upload must never carry a non-finite value.
fn saturating_f16(v: f32) -> u16 {
    let max = half::f16::MAX.to_f32();
    half::f16::from_f32(if v.is_nan() { 0.0 } else { v.clamp(-max, max) }).to_bits()
}

/// The environment's radiance (times its intensity) as Rgba16Float, for the sky behind
/// the scene. Values beyond the half range saturate rather than turn into Inf.
fn environment_texture(gpu: &Gpu, env: Option<&Environment>) -> wgpu::TextureView {
    let (width, height, texels): (u32, u32, Vec<[f32; 3]>) = match env {
        Some(e) => (e.width, e.height, e.texels.iter().map(|t| t.map(|c| c * e.intensity)).collect()),
        None => (1, 1, vec![[0.0; 3]]),
    };
    let data: Vec<u16> = texels.iter().flat_map(|t| [t[0], t[1], t[2], 1.0]).map(saturating_f16).collect();
    let texture = gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("environment"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&data),
    );
    texture.create_view(&Default::default())
}

/// The bind-group layout of one draw: its material's uniform, diffuse texture and
/// sampler, and its object's transforms.
fn material_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let fragment = wgpu::ShaderStages::FRAGMENT;
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("material"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: fragment,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ObjectUniform>() as u64),
                },
                count: None,
            },
            texture_layout(TEXTURE_BINDINGS[0]),
            sampler_layout(TEXTURE_BINDINGS[0] + 1),
            texture_layout(TEXTURE_BINDINGS[1]),
            sampler_layout(TEXTURE_BINDINGS[1] + 1),
            texture_layout(TEXTURE_BINDINGS[2]),
            sampler_layout(TEXTURE_BINDINGS[2] + 1),
            texture_layout(TEXTURE_BINDINGS[3]),
            sampler_layout(TEXTURE_BINDINGS[3] + 1),
        ],
    })
}

fn texture_layout(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn sampler_layout(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

#[cfg(test)]
mod tests {
    use super::{saturating_f16, MaterialUniform, ObjectUniform, MESH_WGSL};
    use half::f16;
    use vrao_ao::layout_check::{self, mirror};
    use vrao_ao::plug::COMMON;

    /// `Vertex` mirrors no WGSL struct in memory: the vertex attributes convert it to
    /// mesh.wgsl's `VertexIn`, so they are what must match its fields.
    #[test]
    fn the_vertex_attributes_match_the_vertex_fields() {
        use super::Vertex;
        use std::mem::{offset_of, size_of};
        let attributes = crate::gpu::raster::MESH_ATTRIBUTES;
        let fields = [
            (offset_of!(Vertex, position), size_of::<[f32; 3]>()),
            (offset_of!(Vertex, normal), size_of::<[f32; 3]>()),
            (offset_of!(Vertex, uv), size_of::<[f32; 4]>()),
            (offset_of!(Vertex, color), size_of::<[u8; 4]>()),
            (offset_of!(Vertex, tangent), size_of::<[i16; 4]>()),
        ];
        for (attribute, (offset, size)) in attributes.iter().zip(fields) {
            let location = attribute.shader_location;
            assert_eq!(attribute.offset, offset as u64, "location {location}'s offset");
            assert_eq!(attribute.format.size(), size as u64, "location {location}'s size");
        }
        let end = attributes.last().map(|a| a.offset + a.format.size());
        assert_eq!(end, Some(size_of::<Vertex>() as u64), "the attributes cover the vertex");
    }

    #[test]
    fn the_material_and_object_uniforms_match_mesh_wgsl() {
        // mesh.wgsl as the G-buffer, the depth peel and the light-space pass compile it.
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(MaterialUniform, [COMMON, MESH_WGSL], "Material", [diffuse, emission, alpha, placements]),
            mirror!(ObjectUniform, [COMMON, MESH_WGSL], "Object", [anchored_from_local, previous_anchored_from_local, normal_from_local]),
        ]);
    }

    #[test]
    fn environment_texels_saturate_and_never_carry_nan() {
        let back = |v: f32| f16::from_bits(saturating_f16(v)).to_f32();
        assert_eq!(back(1.0), 1.0);
        assert_eq!(back(-2.5), -2.5);
        assert_eq!(back(1e30), 65504.0);
        assert_eq!(back(f32::NEG_INFINITY), -65504.0);
        assert_eq!(back(f32::NAN), 0.0);
    }
}
