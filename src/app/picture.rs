//! The window's picture pipelines: a full-screen triangle drawing one 2D view into a
//! viewport — an eye image (filtered), or one of the buffers behind it texel for texel
//! (shaders/mirror.wgsl).

use crate::app::BufferView;
use crate::error::Result;
use crate::wgsl;
use vrao_ao::plug::{fullscreen_pipeline, try_shader_module, Gpu};

/// The picture's pipelines: a full-screen triangle drawing one 2D view into a viewport,
/// one pipeline per kind of picture: the eye image (filtered), occlusion as grey, normals,
/// depth (texel for texel).
pub(super) struct Blit {
    eye: wgpu::RenderPipeline,
    occlusion: wgpu::RenderPipeline,
    occlusion_red: wgpu::RenderPipeline,
    normals: wgpu::RenderPipeline,
    depth: wgpu::RenderPipeline,
    eye_layout: wgpu::BindGroupLayout,
    float_layout: wgpu::BindGroupLayout,
    depth_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

/// A bind group layout of one fragment-stage texture or sampler per entry.
fn fragment_layout(gpu: &Gpu, label: &str, entries: &[(u32, wgpu::BindingType)]) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = entries
        .iter()
        .map(|&(binding, ty)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty,
            count: None,
        })
        .collect();
    gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

fn texture_binding(sample_type: wgpu::TextureSampleType) -> wgpu::BindingType {
    wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false }
}

impl Blit {
    pub(super) fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Result<Blit> {
        let device = &gpu.device;
        let eye_layout = fragment_layout(
            gpu,
            "mirror",
            &[
                (0, texture_binding(wgpu::TextureSampleType::Float { filterable: true })),
                (1, wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering)),
            ],
        );
        let float_layout = fragment_layout(
            gpu,
            "buffer view",
            &[(2, texture_binding(wgpu::TextureSampleType::Float { filterable: false }))],
        );
        let depth_layout = fragment_layout(gpu, "depth view", &[(3, texture_binding(wgpu::TextureSampleType::Depth))]);
        let module = try_shader_module(gpu, "mirror", &[wgsl!("shaders/mirror.wgsl")])?;
        let pipeline = |layout: &wgpu::BindGroupLayout, entry_point: &str| {
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry_point),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            fullscreen_pipeline(device, entry_point, &pipeline_layout, (&module, entry_point), format, None, None)
        };
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("mirror"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Blit {
            eye: pipeline(&eye_layout, "fs_main"),
            occlusion: pipeline(&float_layout, "fs_occlusion"),
            occlusion_red: pipeline(&float_layout, "fs_occlusion_red"),
            normals: pipeline(&float_layout, "fs_normals"),
            depth: pipeline(&depth_layout, "fs_depth"),
            eye_layout,
            float_layout,
            depth_layout,
            sampler,
        })
    }

    /// The pipeline that draws `shown` from `view` (occlusion: in alpha, or in red for a
    /// single-channel AO chain).
    pub(super) fn pipeline(&self, shown: BufferView, view: &wgpu::TextureView) -> &wgpu::RenderPipeline {
        match shown {
            BufferView::Eyes => &self.eye,
            BufferView::FinalAo | BufferView::RawAo if view.texture().format().components() == 1 => &self.occlusion_red,
            BufferView::FinalAo | BufferView::RawAo => &self.occlusion,
            BufferView::Normals => &self.normals,
            BufferView::Depth => &self.depth,
        }
    }

    pub(super) fn bind_group(&self, gpu: &Gpu, shown: BufferView, view: &wgpu::TextureView) -> wgpu::BindGroup {
        let texture = wgpu::BindingResource::TextureView(view);
        let (layout, entries) = match shown {
            BufferView::Eyes => (
                &self.eye_layout,
                vec![
                    wgpu::BindGroupEntry { binding: 0, resource: texture },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                ],
            ),
            BufferView::FinalAo | BufferView::RawAo | BufferView::Normals => {
                (&self.float_layout, vec![wgpu::BindGroupEntry { binding: 2, resource: texture }])
            }
            BufferView::Depth => (&self.depth_layout, vec![wgpu::BindGroupEntry { binding: 3, resource: texture }]),
        };
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("mirror"), layout, entries: &entries })
    }
}
