//! Pieces every raster pipeline of vrao repeats: a uniform-buffer binding, the scene's
//! vertex layout, the mesh-drawing pipeline (G-buffer, depth peeling, shadow maps), the
//! full-screen pipeline (window picture, OpenXR blit, multiview probe), and one 2D view
//! per layer of an array texture.

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

/// What differs between the mesh-drawing pipelines (G-buffer, depth peeling, shadow maps).
pub struct MeshPipeline<'a> {
    /// The pipeline's label.
    pub label: &'a str,
    /// Its bind group layouts.
    pub layout: &'a wgpu::PipelineLayout,
    /// The module holding both entry points.
    pub module: &'a wgpu::ShaderModule,
    /// The vertex entry point and the vertex attributes it reads ([`MESH_ATTRIBUTES`] or
    /// a prefix of them).
    pub vertex: (&'a str, &'a [wgpu::VertexAttribute]),
    /// The depth attachment's format and test.
    pub depth: (wgpu::TextureFormat, wgpu::CompareFunction),
    /// The fragment entry point and its colour targets; `None` for depth only.
    pub fragment: Option<(&'a str, &'a [Option<wgpu::ColorTargetState>])>,
    /// Multiview's view mask, if the pipeline draws every layer at once.
    pub multiview_mask: Option<std::num::NonZeroU32>,
    /// Whether the fragment stage discards alpha-tested holes (mesh.wgsl's `ALPHA_TEST`
    /// override; the module must include mesh.wgsl and have a fragment stage).
    pub alpha_test: bool,
}

/// A pipeline that draws the scene's meshes two-sided, writing depth (OBJ windings are
/// not trusted: the G-buffer faces normals towards the eye, depth peeling wants the back
/// faces, and both faces of a surface cast shadows).
pub fn mesh_pipeline(device: &wgpu::Device, p: MeshPipeline) -> wgpu::RenderPipeline {
    let (format, compare) = p.depth;
    let alpha_constants = [("ALPHA_TEST", 1.0)];
    let fragment_options = wgpu::PipelineCompilationOptions {
        constants: if p.alpha_test { &alpha_constants } else { &[] },
        ..Default::default()
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(p.label),
        layout: Some(p.layout),
        vertex: wgpu::VertexState {
            module: p.module,
            entry_point: Some(p.vertex.0),
            compilation_options: Default::default(),
            buffers: &[Some(mesh_vertex_buffer(p.vertex.1))],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(true),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: p.fragment.map(|(entry, targets)| wgpu::FragmentState {
            module: p.module,
            entry_point: Some(entry),
            compilation_options: fragment_options,
            targets,
        }),
        multiview_mask: p.multiview_mask,
        cache: None,
    })
}

/// A full-screen pipeline: `vs_main` of the shader's module draws one triangle over the
/// target (no vertex buffer) and its `fragment` entry point writes one colour target of
/// `format`, with an optional depth attachment (the window's picture, the OpenXR blit,
/// the multiview probe).
pub fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    (module, fragment): (&wgpu::ShaderModule, &str),
    format: wgpu::TextureFormat,
    depth_stencil: Option<wgpu::DepthStencilState>,
    multiview_mask: Option<std::num::NonZeroU32>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask,
        cache: None,
    })
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

/// A render pass that clears one colour target to `clear` and, when given, a reversed-Z
/// depth target to 0 (infinitely far): the fullscreen passes that write both (the AO
/// engine's import, the OpenXR blit).
pub fn colour_and_depth_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    (colour, clear): (&wgpu::TextureView, wgpu::Color),
    depth: Option<&wgpu::TextureView>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: colour,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: depth.map(|view| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
