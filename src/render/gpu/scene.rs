//! The scene on the GPU: one vertex and one index buffer for all meshes, positions
//! relative to an f64 anchor, and one uniform + texture per material.

use super::kernel::{wgsl, Shader};
use super::Gpu;
use crate::render::scene::{Environment, Scene};
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
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
    /// Texture coordinates of the diffuse texture.
    pub uv: [f32; 2],
}

/// One material's constants (`Material` uniform of the G-buffer shader).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct MaterialUniform {
    /// Diffuse albedo in rgb; w is 1 when a diffuse texture multiplies it, else 0.
    pub diffuse: [f32; 4],
    /// Emitted radiance in rgb; w unused.
    pub emission: [f32; 4],
}

/// One material on the GPU: its uniform and diffuse texture.
pub struct GpuMaterial {
    /// The [`MaterialUniform`].
    pub uniform: wgpu::Buffer,
    /// The diffuse texture, or a 1×1 white placeholder without one.
    pub texture: wgpu::TextureView,
    /// Whether `texture` is the material's own texture rather than the placeholder.
    pub has_texture: bool,
}

/// A contiguous range of indices drawn with one material.
pub struct Draw {
    /// Indices into [`GpuScene::indices`] to draw.
    pub indices: std::ops::Range<u32>,
    /// Index into [`GpuScene::materials`] and `material_groups`.
    pub material: usize,
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
    /// Layout of a material's bind group (uniform, diffuse texture, sampler; fragment
    /// stage), and one bind group per material: the G-buffer and the light-space pass
    /// both draw the scene with them.
    pub material_layout: wgpu::BindGroupLayout,
    /// One bind group per material, in `materials` order (layout: `material_layout`).
    pub material_groups: Vec<wgpu::BindGroup>,
    /// The environment as a filterable equirectangular texture (1×1 black without one).
    pub environment: wgpu::TextureView,
    /// Sampler of the materials' diffuse textures.
    pub sampler: wgpu::Sampler,
}

impl GpuScene {
    /// Records every draw of the scene into `pass`, binding each draw's material at
    /// `material_group` (or none, for passes that read positions only).
    pub fn draw(&self, pass: &mut wgpu::RenderPass, material_group: Option<u32>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for draw in self.draws.iter().filter(|d| !d.indices.is_empty()) {
            if let Some(group) = material_group {
                pass.set_bind_group(group, &self.material_groups[draw.material], &[]);
            }
            pass.draw_indexed(draw.indices.clone(), 0, 0..1);
        }
    }

    /// Uploads `scene`'s geometry (relative to the centre of its bounds), materials and environment.
    pub fn upload(gpu: &Gpu, scene: &Scene) -> GpuScene {
        let bounds = scene.bounds();
        let anchor = if bounds.is_empty() { DVec3::ZERO } else { bounds.center() };
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut draws = Vec::new();
        for mesh in &scene.meshes {
            let base = vertices.len() as u32;
            let offset = (mesh.origin - anchor).as_vec3();
            for i in 0..mesh.positions.len() {
                vertices.push(Vertex {
                    position: (mesh.positions[i] + offset).to_array(),
                    normal: mesh.normals[i].to_array(),
                    uv: mesh.uvs.get(i).copied().unwrap_or_default().to_array(),
                });
            }
            let start = indices.len() as u32;
            indices.extend(mesh.indices.iter().map(|i| i + base));
            draws.push(Draw { indices: start..indices.len() as u32, material: mesh.material });
        }
        // wgpu rejects empty buffers; an empty scene draws nothing from a dummy vertex.
        if vertices.is_empty() {
            vertices.push(Vertex::zeroed());
            indices.extend([0, 0, 0]);
        }
        let device = &gpu.device;
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| {
                let (texture, has_texture) = match &m.diffuse_texture {
                    Some(t) => (rgba8_texture(gpu, &m.name, t.width, t.height, &t.rgba8), true),
                    None => (rgba8_texture(gpu, "white", 1, 1, &[255; 4]), false),
                };
                let uniform = MaterialUniform {
                    diffuse: [m.diffuse.x, m.diffuse.y, m.diffuse.z, if has_texture { 1.0 } else { 0.0 }],
                    emission: [m.emissive.x, m.emissive.y, m.emissive.z, 0.0],
                };
                GpuMaterial {
                    uniform: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(&m.name),
                        contents: bytemuck::bytes_of(&uniform),
                        usage: wgpu::BufferUsages::UNIFORM,
                    }),
                    texture,
                    has_texture,
                }
            })
            .collect();
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear repeat"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Nearest,
            ..Default::default()
        });
        let material_layout = material_layout(device);
        let material_groups = materials
            .iter()
            .map(|m| {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("material"),
                    layout: &material_layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: m.uniform.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&m.texture) },
                        wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&sampler) },
                    ],
                })
            })
            .collect();
        GpuScene {
            anchor,
            vertices: vertex_buffer,
            indices: index_buffer,
            draws,
            materials,
            material_layout,
            material_groups,
            environment: environment_texture(gpu, scene.environment.as_ref()),
            sampler,
        }
    }
}

fn rgba8_texture(gpu: &Gpu, label: &str, width: u32, height: u32, rgba8: &[u8]) -> wgpu::TextureView {
    let texture = gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        rgba8,
    );
    texture.create_view(&Default::default())
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

/// The bind-group layout of one material: its uniform, diffuse texture and sampler.
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
                binding: 1,
                visibility: fragment,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: fragment,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::saturating_f16;
    use half::f16;

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
