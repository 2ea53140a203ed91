//! Checks at start-up that multiview really reaches every layer. Mesa's lavapipe 22.x
//! advertises multiview but routes triangles that need clipping to layer 0 only, which
//! leaves holes in the right eye and ghosts in the left. A driver that fails the probe
//! is used one pass per eye unless the user insists.

use super::kernel::wgsl;
use std::num::NonZeroU32;
use vrao_ao::plug::{fullscreen_pipeline, read_layers, shader_module, Gpu, LayeredTarget};

const SIZE: u32 = 16;

/// True when an oversized multiview triangle covers both layers completely.
pub(crate) fn multiview_reaches_every_layer(gpu: &Gpu) -> bool {
    let device = &gpu.device;
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let target =
        LayeredTarget::new(device, "multiview probe", format, (SIZE, SIZE, 2), wgpu::TextureUsages::RENDER_ATTACHMENT);
    let module = shader_module(gpu, "multiview probe", &[wgsl!("src/gpu/multiview_probe.wgsl")]);
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("multiview probe"),
        bind_group_layouts: &[],
        immediate_size: 0,
    });
    let mask = NonZeroU32::new(0b11);
    let pipeline = fullscreen_pipeline(device, "multiview probe", &layout, (&module, "fs_main"), format, None, mask);
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("multiview probe"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target.array_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: NonZeroU32::new(0b11),
        });
        pass.set_pipeline(&pipeline);
        pass.draw(0..3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    match read_layers(gpu, &target) {
        Ok(layers) => layers.iter().all(|layer| layer.iter().all(|&b| b == 255)),
        Err(e) => {
            log::warn!("multiview probe failed to read back: {e}");
            false
        }
    }
}
