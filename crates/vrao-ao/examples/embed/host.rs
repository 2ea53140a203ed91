//! The host side of the `embed` example: a plain wgpu program's own geometry and its own
//! depth prepass (depth and view-space normals for each eye of a 2-layer array), with no
//! vrao scene and no vrao G-buffer. The engine test (`tests/ao_engine.rs`) renders the
//! same geometry through it and through vrao's renderer.

#![allow(dead_code)]

use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

/// A triangle mesh in world space.
#[derive(Clone)]
pub(crate) struct HostMesh {
    /// Vertex positions (m).
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Triangle list.
    pub indices: Vec<u32>,
}

/// An axis-aligned box (six faces, normals out).
pub(crate) fn cuboid(center: Vec3, size: Vec3) -> HostMesh {
    let h = size * 0.5;
    let mut mesh = HostMesh { positions: Vec::new(), normals: Vec::new(), indices: Vec::new() };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push(center + (n + u * a + v * b) * h);
                mesh.normals.push(n);
            }
            // Counter-clockwise seen from outside.
            let quad = if sign > 0.0 { [0, 1, 2, 0, 2, 3] } else { [0, 2, 1, 0, 3, 2] };
            mesh.indices.extend(quad.iter().map(|i| base + i));
        }
    }
    mesh
}

/// The demo's room corner: a floor, two walls, a crate against them, a low step and a
/// column: contact shadows, creases and corners for the AO.
pub(crate) fn demo_geometry() -> Vec<HostMesh> {
    vec![
        cuboid(Vec3::new(0.0, -0.05, -2.0), Vec3::new(4.0, 0.1, 4.0)),
        cuboid(Vec3::new(0.0, 1.0, -4.05), Vec3::new(4.0, 2.0, 0.1)),
        cuboid(Vec3::new(-2.05, 1.0, -2.0), Vec3::new(0.1, 2.0, 4.0)),
        cuboid(Vec3::new(-1.5, 0.25, -3.5), Vec3::new(0.5, 0.5, 0.5)),
        cuboid(Vec3::new(0.4, 0.08, -2.2), Vec3::new(1.2, 0.16, 0.6)),
        cuboid(Vec3::new(1.1, 0.9, -3.2), Vec3::new(0.25, 1.8, 0.25)),
    ]
}

/// A hand-sized box (18 × 5 × 10 cm) held 10 cm above the step, as a hand or controller
/// hovers over a table.
pub(crate) fn demo_hand() -> HostMesh {
    cuboid(Vec3::new(0.4, 0.285, -2.2), Vec3::new(0.18, 0.05, 0.1))
}

/// Where the demo's eyes are: 1.5 m up, 1 m in front of the room, looking at its corner;
/// 64 mm apart.
pub(crate) fn demo_eyes() -> [Mat4; 2] {
    let head = Vec3::new(0.3, 1.5, 0.2);
    let target = Vec3::new(-0.6, 0.3, -3.0);
    let forward = (target - head).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    [-1.0f32, 1.0].map(|side| {
        let eye = head + right * side * 0.032;
        glam::camera::rh::view::look_at_mat4(eye, eye + forward, Vec3::Y)
    })
}

/// How the host's depth is stored: a format and a projection of the matching kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum HostDepth {
    /// `Depth32Float`, reversed-Z, far plane at infinity.
    ReversedInfinite,
    /// `Depth24Plus`, depth 0 at the near plane and 1 at a far plane.
    StandardFinite {
        /// The far plane's distance (m).
        far: f32,
    },
}

impl HostDepth {
    /// The depth texture's format.
    pub(crate) fn format(self) -> wgpu::TextureFormat {
        match self {
            HostDepth::ReversedInfinite => wgpu::TextureFormat::Depth32Float,
            HostDepth::StandardFinite { .. } => wgpu::TextureFormat::Depth24Plus,
        }
    }

    /// An asymmetric projection of the given frustum tangents (left, right, up, down)
    /// with this depth convention (wgpu's 0..1 depth range).
    pub(crate) fn projection(self, [l, r, u, d]: [f32; 4], near: f32) -> Mat4 {
        let (sx, sy) = (2.0 / (r - l), 2.0 / (u - d));
        let (cx, cy) = ((r + l) / (r - l), (u + d) / (u - d));
        // depth = a + b / distance, as clip z = a·(−z) ... written as z_clip = p22·z + p32.
        let (p22, p32) = match self {
            HostDepth::ReversedInfinite => (0.0, near),
            HostDepth::StandardFinite { far } => (far / (near - far), near * far / (near - far)),
        };
        Mat4::from_cols_array(&[sx, 0.0, 0.0, 0.0, 0.0, sy, 0.0, 0.0, cx, cy, p22, -1.0, 0.0, 0.0, p32, 0.0])
    }

    fn compare(self) -> wgpu::CompareFunction {
        match self {
            HostDepth::ReversedInfinite => wgpu::CompareFunction::Greater,
            HostDepth::StandardFinite { .. } => wgpu::CompareFunction::Less,
        }
    }

    fn clear(self) -> f32 {
        match self {
            HostDepth::ReversedInfinite => 0.0,
            HostDepth::StandardFinite { .. } => 1.0,
        }
    }
}

/// The host's per-view uniform: clip from world and view from world.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ViewUniform {
    clip_from_world: [[f32; 4]; 4],
    view_from_world: [[f32; 4]; 4],
}

const PREPASS_WGSL: &str = r#"
struct View { clip_from_world: mat4x4<f32>, view_from_world: mat4x4<f32> };
@group(0) @binding(0) var<uniform> view: View;
struct Out { @builtin(position) clip: vec4<f32>, @location(0) normal: vec3<f32> };
@vertex fn vs(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Out {
    var out: Out;
    out.clip = view.clip_from_world * vec4<f32>(position, 1.0);
    out.normal = (view.view_from_world * vec4<f32>(normal, 0.0)).xyz;
    return out;
}
@fragment fn fs(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(normalize(in.normal), 0.0);
}
"#;

/// The host's depth prepass: its own pipeline, vertex buffers and targets.
pub(crate) struct DepthPrepass {
    pipeline: wgpu::RenderPipeline,
    /// The hand's draw, when it is marked in the stencil: its pipeline (stencil set to
    /// [`HAND_STENCIL`]) and its indices, after the scene's.
    hand: Option<(wgpu::RenderPipeline, std::ops::Range<u32>)>,
    layout: wgpu::BindGroupLayout,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    depth_kind: HostDepth,
    /// The depth buffer: a 2-layer array, one layer per eye.
    pub depth: wgpu::Texture,
    /// View-space normals (`Rgba16Float`), one layer per eye.
    pub normals: wgpu::Texture,
}

impl DepthPrepass {
    /// Uploads `meshes` and makes both eyes' targets (2-layer arrays) at `width` × `height`.
    pub(crate) fn new(device: &wgpu::Device, meshes: &[HostMesh], depth_kind: HostDepth, size: (u32, u32)) -> Self {
        Self::with_layers(device, meshes, depth_kind, size, 2)
    }

    /// [`DepthPrepass::new`] with `layers` layers (1: plain 2D textures for a mono view).
    pub(crate) fn with_layers(
        device: &wgpu::Device,
        meshes: &[HostMesh],
        depth_kind: HostDepth,
        size: (u32, u32),
        layers: u32,
    ) -> Self {
        Self::multisampled(device, meshes, depth_kind, size, layers, 1)
    }

    /// [`DepthPrepass::with_layers`] drawn with `samples` samples per pixel, as a forward
    /// renderer with MSAA draws (2 layers of a multisampled texture need the device's
    /// `MULTISAMPLE_ARRAY` feature).
    pub(crate) fn multisampled(
        device: &wgpu::Device,
        meshes: &[HostMesh],
        depth_kind: HostDepth,
        (width, height): (u32, u32),
        layers: u32,
        samples: u32,
    ) -> Self {
        let (vertices, indices) = merge_meshes(meshes);
        let (vertex_buffer, index_buffer) = upload_geometry(device, &vertices, &indices);
        let layout = view_layout(device);
        let pipeline =
            prepass_pipeline(device, &layout, depth_kind, depth_kind.format(), samples, None, wgpu::Face::Back);
        let target = |label, format| layered_target(device, label, format, (width, height), layers, samples);
        DepthPrepass {
            pipeline,
            hand: None,
            layout,
            vertices: vertex_buffer,
            indices: index_buffer,
            index_count: indices.len() as u32,
            depth_kind,
            depth: target("host depth", depth_kind.format()),
            normals: target("host normals", wgpu::TextureFormat::Rgba16Float),
        }
    }

    /// [`DepthPrepass::new`] with `hand` drawn last and marked in the stencil of a
    /// `Depth24PlusStencil8` depth buffer ([`HAND_STENCIL`]), as hosts mark hands and UI.
    pub(crate) fn with_marked_hand(
        device: &wgpu::Device,
        meshes: &[HostMesh],
        hand: &HostMesh,
        depth_kind: HostDepth,
        size: (u32, u32),
    ) -> Self {
        let format = wgpu::TextureFormat::Depth24PlusStencil8;
        let mut all: Vec<&HostMesh> = meshes.iter().collect();
        all.push(hand);
        let owned: Vec<HostMesh> = all.into_iter().cloned().collect();
        let mut prepass = Self::new(device, &owned, depth_kind, size);
        let scene_indices: u32 = meshes.iter().map(|m| m.indices.len() as u32).sum();
        let mark = wgpu::StencilFaceState { pass_op: wgpu::StencilOperation::Replace, ..Default::default() };
        let stencil = wgpu::StencilState { front: mark, back: mark, read_mask: 0xff, write_mask: 0xff };
        prepass.pipeline = prepass_pipeline(device, &prepass.layout, depth_kind, format, 1, None, wgpu::Face::Back);
        let hand_pipeline =
            prepass_pipeline(device, &prepass.layout, depth_kind, format, 1, Some(stencil), wgpu::Face::Back);
        prepass.hand = Some((hand_pipeline, scene_indices..prepass.index_count));
        prepass.index_count = scene_indices;
        prepass.depth = layered_target(device, "host depth", format, size, 2, 1);
        prepass
    }

    /// This prepass drawing back faces instead of front faces: its depth is then each
    /// pixel's nearest back face, which for closed meshes seen from outside is the surface
    /// behind the first one, a host's depth peel (`AoFrame::second_layer`).
    pub(crate) fn back_faces(mut self, device: &wgpu::Device) -> Self {
        let (format, samples) = (self.depth.format(), self.depth.sample_count());
        self.pipeline =
            prepass_pipeline(device, &self.layout, self.depth_kind, format, samples, None, wgpu::Face::Front);
        self
    }

    /// Draws every eye's depth and normals: one render pass per layer.
    pub(crate) fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        views: &[super::ViewMatrices],
    ) {
        for (layer, m) in views.iter().enumerate() {
            let uniform = ViewUniform {
                clip_from_world: (m.projection * m.view).to_cols_array_2d(),
                view_from_world: m.view.to_cols_array_2d(),
            };
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("host view"),
                contents: bytemuck::bytes_of(&uniform),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("host view"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
            });
            let layer_view = |texture: &wgpu::Texture| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer as u32,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            };
            let (depth, normals) = (layer_view(&self.depth), layer_view(&self.normals));
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host prepass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &normals,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(self.depth_kind.clear()),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: self
                        .hand
                        .as_ref()
                        .map(|_| wgpu::Operations { load: wgpu::LoadOp::Clear(0), store: wgpu::StoreOp::Store }),
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.index_count, 0, 0..1);
            if let Some((pipeline, indices)) = &self.hand {
                pass.set_pipeline(pipeline);
                pass.set_stencil_reference(HAND_STENCIL);
                pass.draw_indexed(indices.clone(), 0, 0..1);
            }
        }
    }
}

/// All meshes as one vertex list (position, normal) and one index list into it.
fn merge_meshes(meshes: &[HostMesh]) -> (Vec<[f32; 6]>, Vec<u32>) {
    let mut vertices: Vec<[f32; 6]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    for mesh in meshes {
        let base = vertices.len() as u32;
        vertices.extend(mesh.positions.iter().zip(&mesh.normals).map(|(p, n)| [p.x, p.y, p.z, n.x, n.y, n.z]));
        indices.extend(mesh.indices.iter().map(|i| base + i));
    }
    (vertices, indices)
}

/// Uploads the merged vertices and indices into a vertex and an index buffer.
fn upload_geometry(device: &wgpu::Device, vertices: &[[f32; 6]], indices: &[u32]) -> (wgpu::Buffer, wgpu::Buffer) {
    let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("host vertices"),
        contents: bytemuck::cast_slice(vertices),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("host indices"),
        contents: bytemuck::cast_slice(indices),
        usage: wgpu::BufferUsages::INDEX,
    });
    (vertex_buffer, index_buffer)
}

/// The bind group layout of the per-view uniform (binding 0, vertex stage).
fn view_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("host view"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

/// The stencil value the host's hand is drawn with (the engine's `cast_none` bit).
pub(crate) const HAND_STENCIL: u32 = 1;

/// The prepass pipeline: meshes with their `cull` faces culled into `depth_kind`'s depth
/// (of `format`) and `Rgba16Float` view-space normals, writing `stencil` when given.
fn prepass_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    depth_kind: HostDepth,
    format: wgpu::TextureFormat,
    samples: u32,
    stencil: Option<wgpu::StencilState>,
    cull: wgpu::Face,
) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("host prepass"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host prepass"),
        source: wgpu::ShaderSource::Wgsl(PREPASS_WGSL.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("host prepass"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 24,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            })],
        },
        primitive: wgpu::PrimitiveState { cull_mode: Some(cull), ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(true),
            depth_compare: Some(depth_kind.compare()),
            stencil: stencil.unwrap_or_default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::TextureFormat::Rgba16Float.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A render target of `format` with `layers` layers of `width` × `height`, also sampled.
pub(crate) fn layered_target(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    layers: u32,
    samples: u32,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        // Copied from only when single-sampled (a test reads the depth back).
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | if samples == 1 { wgpu::TextureUsages::COPY_SRC } else { wgpu::TextureUsages::empty() },
        view_formats: &[],
    })
}

/// One layer of the engine's output, read back: the visibility (alpha of `Rgba16Float`,
/// red of the single-channel outputs), one value a pixel.
pub(crate) fn read_alpha(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture, layer: u32) -> Vec<f32> {
    let (texel, value): (u32, fn(&[u8]) -> f32) = match texture.format() {
        wgpu::TextureFormat::Rgba16Float => (8, |t| half::f16::from_bits(u16::from_le_bytes([t[6], t[7]])).to_f32()),
        wgpu::TextureFormat::R16Float => (2, |t| half::f16::from_bits(u16::from_le_bytes([t[0], t[1]])).to_f32()),
        wgpu::TextureFormat::R8Unorm => (1, |t| f32::from(t[0]) / 255.0),
        other => panic!("the engine does not write {other:?}"),
    };
    read_layer(device, queue, texture, layer, texel).chunks(texel as usize).map(value).collect()
}

/// One layer of an `Rgba16Float` output, read back: r, g, b, a per pixel.
pub(crate) fn read_rgba(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture, layer: u32) -> Vec<f32> {
    assert_eq!(texture.format(), wgpu::TextureFormat::Rgba16Float, "the light is in the Rgba16Float output");
    let half = |t: &[u8]| half::f16::from_bits(u16::from_le_bytes([t[0], t[1]])).to_f32();
    read_layer(device, queue, texture, layer, 8).chunks(2).map(half).collect()
}

/// One layer's texels (`texel` bytes each), rows packed.
pub(crate) fn read_layer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    layer: u32,
    texel: u32,
) -> Vec<u8> {
    let size = texture.size();
    let row = (size.width * texel).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(row * size.height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: None },
        },
        wgpu::Extent3d { width: size.width, height: size.height, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("readback");
    let data = slice.get_mapped_range().expect("the readback buffer is mapped");
    let mut bytes = Vec::with_capacity((size.width * size.height * texel) as usize);
    for y in 0..size.height {
        let start = (y * row) as usize;
        bytes.extend_from_slice(&data[start..start + (size.width * texel) as usize]);
    }
    bytes
}

/// The engine's test helper that checks the Rust mirrors of WGSL structs (the example
/// builds as a test with the crate's: `test = true`).
#[cfg(test)]
#[path = "../../src/gpu/layout_check.rs"]
mod layout_check;

#[cfg(test)]
mod tests {
    use super::layout_check::{self, mirror};
    use super::*;

    #[test]
    fn the_view_uniform_matches_the_prepass_wgsl() {
        let prepass = [layout_check::Text { path: "examples/embed/host.rs PREPASS_WGSL", source: PREPASS_WGSL }];
        layout_check::check(&[mirror!(ViewUniform, prepass, "View", [clip_from_world, view_from_world])]);
    }
}
