//! The layered G-buffer: reversed-Z depth, view-space normals, albedo and emission for
//! every eye layer. Multiview draws both eyes in one pass; otherwise one pass per eye.
//! Both paths share the fragment shader and vertex transform, so they give equal pixels.

use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::frame::FrameBuffers;
use crate::render::gpu::kernel::{shader_module, wgsl, Shader, COMMON};
use crate::render::gpu::raster::{mesh_pipeline, uniform_entry, MeshPipeline, MESH_ATTRIBUTES};
use crate::render::gpu::scene::{GpuScene, MESH_WGSL};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource, Size};
use std::num::NonZeroU32;
use wgpu::util::DeviceExt;

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "gbuffer";

/// Reversed-Z depth of every eye layer.
pub const DEPTH: Resource = Resource::attachment("depth", Size::Full, wgpu::TextureFormat::Depth32Float);
/// View-space unit normals (w unused).
pub const NORMALS: Resource = Resource::attachment("normals", Size::Full, wgpu::TextureFormat::Rgba16Float);
/// Diffuse albedo (sRGB-encoded, reads back linear).
pub const ALBEDO: Resource = Resource::attachment("albedo", Size::Full, wgpu::TextureFormat::Rgba8UnormSrgb);
/// Emitted radiance.
pub const EMISSION: Resource = Resource::attachment("emission", Size::Full, wgpu::TextureFormat::Rgba16Float);

const COLOR_TARGETS: [Resource; 3] = [NORMALS, ALBEDO, EMISSION];

/// gbuffer.wgsl: the vertex transform and fragment shader both paths share.
const GBUFFER_WGSL: Shader = wgsl!("src/render/passes/gbuffer/gbuffer.wgsl");

/// The G-buffer of both eyes: depth, normals, albedo and emission, multiview or one pass per
/// eye (module docs).
pub struct GBufferPass {
    frame_group: wgpu::BindGroup,
    /// One pass for both layers; `None` when the adapter lacks multiview.
    multiview: Option<wgpu::RenderPipeline>,
    multipass: wgpu::RenderPipeline,
    /// Bind groups selecting eye 0 and eye 1 for the per-eye path.
    eye_select: [wgpu::BindGroup; 2],
}

impl GBufferPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, scene: &GpuScene, frame: &FrameBuffers) -> Self {
        let device = &gpu.device;
        let vs_fs = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer frame"),
            entries: &[uniform_entry(0, vs_fs)],
        });
        let eye_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer eye select"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX)],
        });
        let eye_select = [0u32, 1].map(|eye| {
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("eye select"),
                contents: bytemuck::cast_slice(&[eye, 0, 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("eye select"),
                layout: &eye_layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
            })
        });
        let multiview = gpu.caps.multiview.then(|| {
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gbuffer multiview"),
                bind_group_layouts: &[Some(&frame_layout), Some(&scene.material_layout)],
                immediate_size: 0,
            });
            let module = shader_module(
                device,
                "gbuffer multiview",
                &[COMMON, MESH_WGSL, GBUFFER_WGSL, wgsl!("src/render/passes/gbuffer/gbuffer_multiview.wgsl")],
            );
            pipeline(device, &layout, &module, NonZeroU32::new(0b11))
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer multipass"),
            bind_group_layouts: &[Some(&frame_layout), Some(&scene.material_layout), Some(&eye_layout)],
            immediate_size: 0,
        });
        let module = shader_module(
            device,
            "gbuffer multipass",
            &[COMMON, MESH_WGSL, GBUFFER_WGSL, wgsl!("src/render/passes/gbuffer/gbuffer_multipass.wgsl")],
        );
        let multipass = pipeline(device, &layout, &module, None);
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: frame.frame.as_entire_binding() }],
        });
        GBufferPass { frame_group, multiview, multipass, eye_select }
    }
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    multiview_mask: Option<NonZeroU32>,
) -> wgpu::RenderPipeline {
    let targets = COLOR_TARGETS.map(|r| Some(wgpu::ColorTargetState::from(r.format())));
    mesh_pipeline(
        device,
        MeshPipeline {
            label: "gbuffer",
            layout,
            module,
            vertex: ("vs_main", &MESH_ATTRIBUTES),
            // Reversed Z: nearer is greater.
            depth: (DEPTH.format(), wgpu::CompareFunction::Greater),
            fragment: Some(("fs_main", &targets)),
            multiview_mask,
        },
    )
}

impl Pass for GBufferPass {
    fn declare(&self, _: &FrameSetup) -> PassDecl {
        PassDecl::new(NAME).write(DEPTH).write(NORMALS).write(ALBEDO).write(EMISSION)
    }

    fn record(&self, ctx: &mut FrameContext) {
        let gpu_scene = ctx.gpu_scene();
        let multiview = ctx.setup.multiview && ctx.setup.views == 2;
        if multiview {
            let pipeline = self.multiview.as_ref().expect("multiview requested without adapter support");
            let views = |r: Resource| &ctx.targets[&r].array_view;
            let mut pass = begin(ctx.encoder, views, NonZeroU32::new(0b11));
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.frame_group, &[]);
            gpu_scene.draw(&mut pass, Some(1));
        } else {
            for layer in 0..ctx.setup.views as usize {
                let label = if layer == 0 { "gbuffer left" } else { "gbuffer right" };
                let span = ctx.timer.begin(ctx.encoder, label);
                {
                    let views = |r: Resource| &ctx.targets[&r].layer_views[layer];
                    let mut pass = begin(ctx.encoder, views, None);
                    pass.set_pipeline(&self.multipass);
                    pass.set_bind_group(0, &self.frame_group, &[]);
                    pass.set_bind_group(2, &self.eye_select[layer], &[]);
                    gpu_scene.draw(&mut pass, Some(1));
                }
                ctx.timer.end(ctx.encoder, span);
            }
        }
    }
}

/// A render pass clearing every G-buffer target (depth to 0 = infinitely far).
fn begin<'e, 't>(
    encoder: &'e mut wgpu::CommandEncoder,
    views: impl Fn(Resource) -> &'t wgpu::TextureView,
    multiview_mask: Option<NonZeroU32>,
) -> wgpu::RenderPass<'e> {
    let color = COLOR_TARGETS.map(|r| {
        Some(wgpu::RenderPassColorAttachment {
            view: views(r),
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store },
        })
    });
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("gbuffer"),
        color_attachments: &color,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: views(DEPTH),
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask,
    })
}
