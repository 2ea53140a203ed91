//! Pieces every raster pipeline of vrao repeats (G-buffer, depth peeling, shadow maps,
//! the OpenXR blit): a uniform-buffer binding, the scene's vertex layout, and one 2D
//! view per layer of an array texture.

use super::kernel::Slot;
use super::scene::Vertex;

/// A uniform-buffer binding at `binding`, seen by the `visibility` stages.
pub fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    Slot::Uniform.layout_entry(binding, visibility)
}

/// The scene's vertices (position, normal, uv) as the raster passes read them.
pub const MESH_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];

/// One vertex buffer of [`Vertex`] with the given attributes (all, or the position only).
pub fn mesh_vertex_buffer(attributes: &[wgpu::VertexAttribute]) -> wgpu::VertexBufferLayout<'_> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes,
    }
}

/// A 2D view of each of the first `layers` layers of `texture` (render attachments and
/// per-eye bindings).
pub fn layer_views(texture: &wgpu::Texture, label: &str, layers: u32) -> Vec<wgpu::TextureView> {
    (0..layers)
        .map(|layer| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some(label),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            })
        })
        .collect()
}
