//! The engine's output in the format the host chose ([`AoOutputFormat`]). The chain's
//! final AO is handed over as it is when its format is the one asked for (`R16Float`
//! from a scalar chain, `Rgba16Float` from a four-channel one); otherwise one full-screen
//! draw per view copies its visibility into a target of that format. The same draw sets
//! AO 1 where the host's exclusion mask says a pixel receives none.

use crate::gpu::kernel::{chain_prelude, shader_module, wgsl, Slot};
use crate::gpu::layered_target::LayeredTarget;
use crate::gpu::raster::fullscreen_pipeline;
use crate::gpu::Gpu;
use crate::resource::ChainLayout;

/// The texel format of the engine's output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AoOutputFormat {
    /// `Rgba16Float`, the visibility in alpha (SSDO's light in rgb, else 0), 8 bytes a
    /// pixel: the chain's own target when the chain has four channels (SSDO, or a device
    /// without `R16Float` storage), one extra draw per view otherwise.
    #[default]
    Rgba16Float,
    /// The visibility in red, 2 bytes a pixel: the chain's own target when the chain is
    /// scalar (GTAO, SSAO, HBAO on a device that writes `R16Float` storage), one extra
    /// draw per view otherwise.
    R16Float,
    /// The visibility in red quantised to 1/255, 1 byte a pixel; one extra draw per view.
    R8Unorm,
}

impl AoOutputFormat {
    /// Every output format.
    pub const ALL: [AoOutputFormat; 3] =
        [AoOutputFormat::Rgba16Float, AoOutputFormat::R16Float, AoOutputFormat::R8Unorm];

    /// The texture format.
    pub fn texture_format(self) -> wgpu::TextureFormat {
        match self {
            AoOutputFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
            AoOutputFormat::R16Float => wgpu::TextureFormat::R16Float,
            AoOutputFormat::R8Unorm => wgpu::TextureFormat::R8Unorm,
        }
    }

    /// Bytes a pixel of the output holds (what the host's pass reads per sample).
    pub fn bytes_per_pixel(self) -> u32 {
        self.texture_format().block_copy_size(None).expect("uncompressed colour formats")
    }
}

/// The pass that copies the final AO's visibility into a single-channel target.
pub(crate) struct PackPass {
    layout: wgpu::BindGroupLayout,
    /// By the chain's layout (which the final AO's format says) and the output format.
    pipelines: Vec<(ChainLayout, AoOutputFormat, wgpu::RenderPipeline)>,
    /// One uniform per view layer: the layer its draw reads.
    layer_uniforms: [wgpu::Buffer; 2],
    /// The output target and the format it was made for.
    target: Option<(AoOutputFormat, LayeredTarget)>,
    /// Each layer's bind group and the final AO and mask views they read: made again only
    /// when those change.
    bind_groups: Option<([wgpu::TextureView; 2], Vec<wgpu::BindGroup>)>,
    /// What binds in place of a host's exclusion mask when there is none.
    placeholder_mask: wgpu::TextureView,
}

impl PackPass {
    pub(crate) fn new(gpu: &Gpu) -> PackPass {
        let device = &gpu.device;
        let entries = [
            Slot::Layers.layout_entry(0, wgpu::ShaderStages::FRAGMENT),
            Slot::Uniform.layout_entry(1, wgpu::ShaderStages::FRAGMENT),
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: super::exclusion::MASK_BINDING,
                count: None,
            },
        ];
        let layout = device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("pack"), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pack"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |chain: ChainLayout, format: AoOutputFormat| {
            let module = shader_module(gpu, "pack", &[chain_prelude(chain), wgsl!("src/ao/pack.wgsl")]);
            let entry = if format == AoOutputFormat::Rgba16Float { "fs_rgba" } else { "fs_main" };
            let pipeline = fullscreen_pipeline(
                device,
                "pack",
                &pipeline_layout,
                (&module, entry),
                format.texture_format(),
                None,
                None,
            );
            (chain, format, pipeline)
        };
        let layer_uniform = |layer: u32| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pack layer"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            gpu.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&[layer, 0, 0, 0]));
            buffer
        };
        PackPass {
            layout,
            pipelines: [ChainLayout::Rgba, ChainLayout::Scalar]
                .into_iter()
                .flat_map(|chain| AoOutputFormat::ALL.map(|format| pipeline(chain, format)))
                .collect(),
            layer_uniforms: [layer_uniform(0), layer_uniform(1)],
            target: None,
            bind_groups: None,
            placeholder_mask: super::exclusion::placeholder(gpu),
        }
    }

    /// Records the copy of `final_ao`'s visibility into this pass's target of `format`
    /// (made anew at a new size or format), 1 where `receiving`'s mask has its bits, and
    /// returns the target.
    pub(crate) fn record(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        final_ao: &LayeredTarget,
        format: AoOutputFormat,
        receiving: Option<(wgpu::TextureView, u32)>,
    ) -> &LayeredTarget {
        let (mask, receive_none) = receiving.unwrap_or_else(|| (self.placeholder_mask.clone(), 0));
        for (layer, uniform) in self.layer_uniforms.iter().enumerate() {
            gpu.queue.write_buffer(uniform, 0, bytemuck::cast_slice(&[layer as u32, receive_none, 0, 0]));
        }
        let extent = final_ao.extent();
        let stale = self.target.as_ref().is_none_or(|(f, t)| *f != format || t.extent() != extent);
        if stale {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
            let target = LayeredTarget::new(&gpu.device, "ao output", format.texture_format(), extent, usage);
            self.target = Some((format, target));
        }
        let views = [final_ao.array_view.clone(), mask];
        if self.bind_groups.as_ref().is_none_or(|(bound, _)| *bound != views) {
            let bind_group = |uniform: &wgpu::Buffer| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("pack"),
                    layout: &self.layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(&final_ao.array_view),
                        },
                        wgpu::BindGroupEntry { binding: 1, resource: uniform.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&views[1]) },
                    ],
                })
            };
            let groups = self.layer_uniforms.iter().map(bind_group).collect();
            self.bind_groups = Some((views, groups));
        }
        let (_, target) = self.target.as_ref().expect("made above");
        let (_, bind_groups) = self.bind_groups.as_ref().expect("made above");
        let chain =
            if final_ao.format == ChainLayout::Scalar.format() { ChainLayout::Scalar } else { ChainLayout::Rgba };
        let pipeline =
            &self.pipelines.iter().find(|(c, f, _)| *c == chain && *f == format).expect("every layout and format").2;
        for (view, bind_group) in target.layer_views.iter().zip(bind_groups) {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("pack"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        target
    }
}
