//! Depth peeling (Ritschel et al. 2009 §4): a second depth layer per eye, the nearest
//! surface behind the G-buffer's depth (peel.wgsl), the engine's `DEPTH_LAYER_2`. Two readers:
//! - the point-sampled SSDO's quality mode (`point_ssdo.depth_peeling`), which counts a sample as
//!   an occluder only between the first and second layer;
//! - GTAO and SSDO on its bitmask with `ao.layers` = 2, whose samples then block the span
//!   between the layers instead of a slab `gtao.thickness` deep. For them the layer keeps a
//!   minimum separation behind the first, `ao.layer_separation` × the radius (deep
//!   G-buffers, Mara et al. 2016), so that it can skip a surface's own back face.
//!
//! The pass runs only for one of them, and not where nothing can lie behind the first
//! layer (the scene is one convex shell seen from inside, scene/shell.rs).
//!
//! One depth-only render pass per eye layer, whatever the G-buffer uses: multiview is
//! unreliable on lavapipe, and each pass reads its own layer of the first depth.

use super::{gpu_scene_of, settings_of};
use crate::gpu::kernel::wgsl;
use crate::gpu::raster::{mesh_pipeline, MeshPipeline, MeshPipelines, MESH_ATTRIBUTES};
use crate::gpu::scene::{GpuScene, MESH_WGSL};
use vrao_ao::plug::{
    shader_module, uniform_entry, DeclareContext, FrameUniforms, Gpu, Pass, PassDecl, RecordContext, COMMON, DEPTH,
    DEPTH_LAYER_2,
};
use vrao_ao::Technique;
use wgpu::util::DeviceExt;

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "depth-peel";

/// Depth peeling's second depth layer of each eye (module docs).
pub struct DepthPeelPass {
    /// One per kind of draw the scene has.
    pipelines: MeshPipelines,
    frame_group: wgpu::BindGroup,
    eye_layout: wgpu::BindGroupLayout,
    /// `PeelEye` of peel.wgsl for each per-eye pass: the eye index (0 left, 1 right) and
    /// the minimum separation in metres.
    eye_index: [wgpu::Buffer; 2],
}

impl DepthPeelPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, scene: &GpuScene, frame: &FrameUniforms) -> Self {
        let device = &gpu.device;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("depth peel frame"),
            // The fragment stage reads the near plane (the minimum separation in metres).
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let eye_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("depth peel eye"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("depth peel"),
            bind_group_layouts: &[Some(&frame_layout), Some(&scene.material_layout), Some(&eye_layout)],
            immediate_size: 0,
        });
        let module = shader_module(gpu, "depth peel", &[COMMON, MESH_WGSL, wgsl!("src/passes/peel/peel.wgsl")]);
        let pipelines = MeshPipelines::new(&scene.kinds, |kind| {
            mesh_pipeline(
                device,
                MeshPipeline {
                    label: "depth peel",
                    layout: &layout,
                    module: &module,
                    vertex: ("vs_peel", &MESH_ATTRIBUTES),
                    // Reversed Z. Both faces of every material: the nearest surface behind
                    // the first layer is kept, and where the material is single-sided
                    // with its facing (peel.wgsl): a front face there tells a sheet (a
                    // sign, a leaf, an open shell) from a closed object, whose back face
                    // comes first. Culling front faces instead took the next back face
                    // behind a sheet, and the air between as solid.
                    depth: (DEPTH_LAYER_2.format(), wgpu::CompareFunction::Greater),
                    fragment: Some((if kind.cull { "fs_peel_single_sided" } else { "fs_peel" }, &[])),
                    multiview_mask: None,
                    alpha_test: kind.alpha_test,
                    cull: None,
                },
            )
        });
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("depth peel frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: frame.frame.as_entire_binding() }],
        });
        let eye_index = [0u32, 1].map(|eye| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("depth peel eye"),
                contents: bytemuck::cast_slice(&[eye, 0, 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
        });
        DepthPeelPass { pipelines, frame_group, eye_layout, eye_index }
    }
}

impl Pass for DepthPeelPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let settings = settings_of(setup);
        let (ao, depth_peeling) = (&settings.ao, settings.point_ssdo.depth_peeling);
        let ssdo = matches!(ao.technique, Technique::SsdoPoints | Technique::SsdoPointsBounce);
        let peeled_ssdo = ssdo && depth_peeling;
        let two_layers = ao.layers == 2 && ao.technique.reads_second_layer();
        let name = ao.technique.name();
        let reason = if depth_peeling && !ssdo && ao.layers == 1 {
            format!("technique is {name}: only the point-sampled SSDO peels (--depth-peeling), and --layers is 1")
        } else if ao.layers == 2 {
            format!("technique is {name}, which reads one depth layer")
        } else if ssdo {
            "depth peeling is off and --layers is 1".to_string()
        } else {
            "one depth layer (--layers 1)".to_string()
        };
        PassDecl::new(NAME)
            .read(DEPTH)
            .write(DEPTH_LAYER_2)
            .occlusion_cost()
            .disabled_if(!peeled_ssdo && !two_layers, reason)
            .disabled_if(
                !setup.second_layer,
                "nothing can lie behind the first depth layer: the scene's triangles bound one convex \
                 region (an open plane, an empty box room) and both eyes are inside it",
            )
    }

    fn record(&self, ctx: &mut RecordContext) {
        let gpu_scene = gpu_scene_of(ctx.setup);
        let ao = &settings_of(ctx.setup).ao;
        // The minimum separation is GTAO's (two layers); SSDO's peeling keeps the gap alone.
        let separation = if ao.layers == 2 { ao.layer_separation * ao.radius } else { 0.0 };
        for (eye, buffer) in self.eye_index.iter().enumerate() {
            let uniform: [u32; 4] = [eye as u32, separation.to_bits(), 0, 0];
            ctx.gpu.queue.write_buffer(buffer, 0, bytemuck::cast_slice(&uniform));
        }
        let first = ctx.view(DEPTH);
        let second = ctx.target(DEPTH_LAYER_2);
        for layer in 0..ctx.setup.views as usize {
            let eye_group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("depth peel eye"),
                layout: &self.eye_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: self.eye_index[layer].as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: first.clone() },
                ],
            });
            let label = if layer == 0 { "depth-peel left" } else { "depth-peel right" };
            let span = ctx.timer.begin(ctx.encoder, label);
            {
                let mut pass = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("depth peel"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &second.layer_views[layer],
                        // Cleared to 0 = infinitely far: where nothing lies behind the first
                        // layer, every sample behind it counts as inside.
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &self.frame_group, &[]);
                pass.set_bind_group(2, &eye_group, &[]);
                gpu_scene.draw_with(&mut pass, &self.pipelines);
            }
            ctx.timer.end(ctx.encoder, span);
        }
    }
}
