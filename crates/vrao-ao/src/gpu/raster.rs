//! Raster pieces shared beyond the meshes: a uniform-buffer binding, the full-screen
//! pipeline (window picture, OpenXR blit, multiview probe), one 2D view per layer of an
//! array texture and a colour-and-depth render pass.

use super::kernel::Slot;

/// A uniform-buffer binding at `binding`, seen by the `visibility` stages.
pub fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    Slot::Uniform.layout_entry(binding, visibility)
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
