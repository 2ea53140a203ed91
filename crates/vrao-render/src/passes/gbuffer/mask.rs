//! The visibility mask drawn into depth around the G-buffer (mask.wgsl), as VR engines
//! draw the hidden-area mesh first: the scene's fragments on hidden pixels fail the depth
//! test before they are shaded, and afterwards those pixels read as sky, so that no
//! compute pass finds a surface there.

use crate::gpu::kernel::wgsl;
use vrao_ao::plug::{shader_module, Gpu, RecordContext, DEPTH};

/// The two depth-only pipelines: hidden pixels to the near plane, then to the sky.
pub(super) struct MaskDepth {
    near: wgpu::RenderPipeline,
    far: wgpu::RenderPipeline,
}

/// Which depth the hidden pixels get.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum MaskStep {
    /// Before the scene (the depth target cleared first): the near plane.
    Near,
    /// After the scene: the sky.
    Far,
}

impl MaskDepth {
    pub(super) fn new(gpu: &Gpu) -> MaskDepth {
        let device = &gpu.device;
        let module = shader_module(gpu, "gbuffer mask", &[wgsl!("src/passes/gbuffer/mask.wgsl")]);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer mask"),
            bind_group_layouts: &[Some(&gpu.visibility_layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("gbuffer mask"),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH.format(),
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_hidden"),
                    compilation_options: Default::default(),
                    targets: &[],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        MaskDepth { near: pipeline("vs_near"), far: pipeline("vs_far") }
    }

    /// Writes `step`'s depth on every layer's hidden pixels (clearing the depth target
    /// first for [`MaskStep::Near`]).
    pub(super) fn draw(&self, ctx: &mut RecordContext, step: MaskStep) {
        let (pipeline, load) = match step {
            MaskStep::Near => (&self.near, wgpu::LoadOp::Clear(0.0)),
            MaskStep::Far => (&self.far, wgpu::LoadOp::Load),
        };
        for layer in 0..ctx.setup.views {
            let view = &ctx.targets[&DEPTH].layer_views[layer as usize];
            let mut pass = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gbuffer mask"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, ctx.visibility.bind_group(), &[]);
            pass.draw(0..3, layer..layer + 1);
        }
    }
}
