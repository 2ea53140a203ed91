//! The layered G-buffer: reversed-Z depth, view-space normals, albedo and emission for
//! every eye layer, in a scene that moves each pixel's motion ([`MOTION`]), and in a
//! scene with normal textures the lighting's normals ([`SHADING_NORMALS`]) apart from the
//! AO's.
//! Multiview draws both eyes in one pass; otherwise one pass per eye. Both paths share the
//! fragment shader and vertex transform, so they give equal pixels. Alpha-tested
//! materials are drawn after the solid ones with a pipeline that discards their holes;
//! a scene without them (or without motion) gets neither pipeline nor target.

mod mask;

use super::{gpu_scene_of, settings_of};
use crate::gpu::kernel::wgsl;
use crate::gpu::raster::{mesh_pipeline, DrawKind, MeshPipeline, MeshPipelines, MESH_ATTRIBUTES};
use crate::gpu::scene::{GpuScene, MESH_WGSL};
use bytemuck::{Pod, Zeroable};
use mask::{MaskDepth, MaskStep};
use std::num::NonZeroU32;
use vrao_ao::plug::{
    shader_module, uniform_entry, DeclareContext, FrameUniforms, Gpu, Pass, PassDecl, RecordContext, Resource, Shader,
    Size, COMMON, PIXEL_MOTION,
};
use wgpu::util::DeviceExt;

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "gbuffer";

/// The depth, normals and motion the G-buffer writes are the textures the AO engine
/// reads.
use vrao_ao::plug::{DEPTH, MOTION, NORMALS};
/// Diffuse albedo in rgb (sRGB-encoded, sampled back linear); in alpha the material's baked
/// occlusion (glTF `occlusionTexture`, 1 without one), which the composite combines with the AO.
pub const ALBEDO: Resource = Resource::attachment("albedo", Size::Full, wgpu::TextureFormat::Rgba8UnormSrgb);
/// Emitted radiance.
pub const EMISSION: Resource = Resource::attachment("emission", Size::Full, wgpu::TextureFormat::Rgba16Float);

/// The normals the lighting uses: the normal texture's where a material has one. The AO
/// keeps the surface's own ([`NORMALS`]): against the reference, normal-textured normals
/// tilt GTAO's hemisphere into the flat surface they decorate and raise its error several
/// times (docs/records/2026-11-29/summary.md, "normal textures and the AO"). Written only in a scene
/// with normal textures; otherwise [`LIGHTING_NORMALS`] is [`NORMALS`].
pub const SHADING_NORMALS: Resource =
    Resource::attachment("shading-normals", Size::Full, wgpu::TextureFormat::Rgba16Float);

/// What the lighting passes (direct light, composite) read as normals: [`SHADING_NORMALS`]
/// in a scene with normal textures, else [`NORMALS`].
pub const LIGHTING_NORMALS: Resource = Resource::alias("lighting-normals", wgpu::TextureFormat::Rgba16Float, None);

/// Every colour target in location order; a scene writes those it needs.
const COLOR_TARGETS: [Resource; 5] = [NORMALS, ALBEDO, EMISSION, MOTION, SHADING_NORMALS];

/// gbuffer.wgsl: the vertex transform and fragment shader both paths share.
const GBUFFER_WGSL: Shader = wgsl!("src/passes/gbuffer/gbuffer.wgsl");

/// Mirrors `PreviousEyes` in gbuffer.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PreviousEyes {
    clip_from_anchored: [[[f32; 4]; 4]; 2],
    view_from_anchored: [[[f32; 4]; 4]; 2],
}

/// The pipelines of one path (multiview or per eye): one per kind of draw the scene has
/// (alpha-tested or not, single-sided or not).
struct Pipelines(MeshPipelines);

impl Pipelines {
    /// Draws the scene: solid materials first (early depth test), then the alpha-tested.
    fn draw(&self, pass: &mut wgpu::RenderPass, scene: &GpuScene) {
        scene.draw_with(pass, &self.0);
    }
}

/// The G-buffer of both eyes: depth, normals, albedo, emission and (when the scene moves)
/// motion, multiview or one pass per eye (module docs).
pub struct GBufferPass {
    frame_group: wgpu::BindGroup,
    /// One pass for both layers; `None` when the adapter lacks multiview.
    multiview: Option<Pipelines>,
    multipass: Pipelines,
    /// Bind groups selecting eye 0 and eye 1 for the per-eye path.
    eye_select: [wgpu::BindGroup; 2],
    /// Whether the scene moves: the pipelines then write [`MOTION`].
    motion: bool,
    /// Whether the scene has normal textures: the pipelines then write [`SHADING_NORMALS`].
    mapped: bool,
    /// The previous frame's eyes (`PreviousEyes`).
    previous_eyes: wgpu::Buffer,
    /// The visibility mask drawn into depth around the scene.
    mask: MaskDepth,
}

impl GBufferPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, scene: &GpuScene, frame: &FrameUniforms) -> Self {
        let device = &gpu.device;
        let vs_fs = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer frame"),
            entries: &[uniform_entry(0, vs_fs), uniform_entry(1, wgpu::ShaderStages::VERTEX)],
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
        let motion = scene.has_moving_objects();
        let mapped = scene.normal_mapped;
        let pipelines = |layout: &wgpu::PipelineLayout, module: &wgpu::ShaderModule, mask: Option<NonZeroU32>| {
            Pipelines(MeshPipelines::new(&scene.kinds, |kind| {
                pipeline(device, layout, module, mask, (motion, mapped), kind)
            }))
        };
        let multiview = gpu.caps.multiview.then(|| {
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gbuffer multiview"),
                bind_group_layouts: &[Some(&frame_layout), Some(&scene.material_layout)],
                immediate_size: 0,
            });
            let module = shader_module(
                gpu,
                "gbuffer multiview",
                &[COMMON, MESH_WGSL, GBUFFER_WGSL, wgsl!("src/passes/gbuffer/gbuffer_multiview.wgsl")],
            );
            pipelines(&layout, &module, NonZeroU32::new(0b11))
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer multipass"),
            bind_group_layouts: &[Some(&frame_layout), Some(&scene.material_layout), Some(&eye_layout)],
            immediate_size: 0,
        });
        let module = shader_module(
            gpu,
            "gbuffer multipass",
            &[COMMON, MESH_WGSL, GBUFFER_WGSL, wgsl!("src/passes/gbuffer/gbuffer_multipass.wgsl")],
        );
        let multipass = pipelines(&layout, &module, None);
        let previous_eyes = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("gbuffer previous eyes"),
            size: std::mem::size_of::<PreviousEyes>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer frame"),
            layout: &frame_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: frame.frame.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: previous_eyes.as_entire_binding() },
            ],
        });
        let mask = MaskDepth::new(gpu);
        GBufferPass { frame_group, multiview, multipass, eye_select, motion, mapped, previous_eyes, mask }
    }

    /// The colour targets this scene's pipelines write, by location (`None`: not written).
    fn color_targets(&self) -> Vec<Option<Resource>> {
        color_targets(self.motion, self.mapped)
    }

    /// Writes the previous frame's eyes (this frame's when there is none: then only
    /// objects move).
    fn write_previous_eyes(&self, ctx: &RecordContext) {
        let setup = ctx.setup;
        let eyes = setup.previous_views.unwrap_or(setup.current_views);
        let mut u = PreviousEyes::zeroed();
        for (layer, eye) in eyes.iter().take(2).enumerate() {
            u.clip_from_anchored[layer] =
                eye.clip_from_anchored(setup.anchor, settings_of(setup).near).to_cols_array_2d();
            let view_from_anchored = eye.view_from_world() * glam::DMat4::from_translation(setup.anchor);
            u.view_from_anchored[layer] = view_from_anchored.as_mat4().to_cols_array_2d();
        }
        ctx.gpu.queue.write_buffer(&self.previous_eyes, 0, bytemuck::bytes_of(&u));
    }
}

/// The colour targets by location of a scene that moves (`motion`) or has normal
/// textures (`mapped`); `None` where a location is not written.
fn color_targets(motion: bool, mapped: bool) -> Vec<Option<Resource>> {
    let mut targets: Vec<Option<Resource>> = COLOR_TARGETS[..3].iter().copied().map(Some).collect();
    if motion || mapped {
        targets.push(motion.then_some(MOTION));
    }
    if mapped {
        targets.push(Some(SHADING_NORMALS));
    }
    targets
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    multiview_mask: Option<NonZeroU32>,
    (motion, mapped): (bool, bool),
    kind: DrawKind,
) -> wgpu::RenderPipeline {
    let targets: Vec<_> = color_targets(motion, mapped)
        .into_iter()
        .map(|r| r.map(|r| wgpu::ColorTargetState::from(r.format())))
        .collect();
    let vertex = if motion { "vs_motion" } else { "vs_main" };
    let fragment = match (motion, mapped) {
        (false, false) => "fs_main",
        (true, false) => "fs_motion",
        (false, true) => "fs_mapped",
        (true, true) => "fs_motion_mapped",
    };
    mesh_pipeline(
        device,
        MeshPipeline {
            label: if kind.alpha_test { "gbuffer alpha-tested" } else { "gbuffer" },
            layout,
            module,
            vertex: (vertex, &MESH_ATTRIBUTES),
            // Reversed Z: nearer is greater.
            depth: (DEPTH.format(), wgpu::CompareFunction::Greater),
            fragment: Some((fragment, &targets)),
            multiview_mask,
            alpha_test: kind.alpha_test,
            cull: kind.cull.then_some(wgpu::Face::Back),
        },
    )
}

impl Pass for GBufferPass {
    fn declare(&self, _: &DeclareContext) -> PassDecl {
        let mut decl = PassDecl::new(NAME).write(DEPTH).write(NORMALS).write(ALBEDO).write(EMISSION);
        decl = if self.motion {
            decl.write(MOTION).provide(PIXEL_MOTION, MOTION)
        } else {
            decl.note("motion vectors left out: nothing in the scene moves")
        };
        decl = if self.mapped {
            decl.write(SHADING_NORMALS).provide(LIGHTING_NORMALS, SHADING_NORMALS)
        } else {
            decl.provide(LIGHTING_NORMALS, NORMALS).note("shading normals left out: no material has a normal texture")
        };
        if !self.multipass.0.alpha_tested() {
            decl = decl.note("alpha test left out: no material has holes");
        }
        decl
    }

    fn record(&self, ctx: &mut RecordContext) {
        let gpu_scene = gpu_scene_of(ctx.setup);
        if self.motion {
            self.write_previous_eyes(ctx);
        }
        let targets = &self.color_targets();
        // The lens's hidden pixels first, at the near plane: the scene's fragments there
        // fail the depth test before they are shaded.
        let masked = ctx.visibility.masked();
        if masked {
            self.mask.draw(ctx, MaskStep::Near);
        }
        let depth_load = if masked { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(0.0) };
        let multiview = ctx.setup.multiview && ctx.setup.views == 2;
        if multiview {
            let pipelines = self.multiview.as_ref().expect("multiview requested without adapter support");
            let views = |r: Resource| &ctx.targets[&r].array_view;
            let mut pass = begin(ctx.encoder, targets, views, depth_load, NonZeroU32::new(0b11));
            pass.set_bind_group(0, &self.frame_group, &[]);
            pipelines.draw(&mut pass, gpu_scene);
        } else {
            for layer in 0..ctx.setup.views as usize {
                let label = if layer == 0 { "gbuffer left" } else { "gbuffer right" };
                let span = ctx.timer.begin(ctx.encoder, label);
                {
                    let views = |r: Resource| &ctx.targets[&r].layer_views[layer];
                    let mut pass = begin(ctx.encoder, targets, views, depth_load, None);
                    pass.set_bind_group(0, &self.frame_group, &[]);
                    pass.set_bind_group(2, &self.eye_select[layer], &[]);
                    self.multipass.draw(&mut pass, gpu_scene);
                }
                ctx.timer.end(ctx.encoder, span);
            }
        }
        if masked {
            // Then as sky: the compute passes find no surface on hidden pixels.
            self.mask.draw(ctx, MaskStep::Far);
        }
    }
}

/// A render pass clearing every G-buffer colour target (motion to 0 = invalid) and
/// loading depth with `depth_load` (a clear to 0 = infinitely far, or the visibility
/// mask's depth drawn before).
fn begin<'e, 't>(
    encoder: &'e mut wgpu::CommandEncoder,
    targets: &[Option<Resource>],
    views: impl Fn(Resource) -> &'t wgpu::TextureView,
    depth_load: wgpu::LoadOp<f32>,
    multiview_mask: Option<NonZeroU32>,
) -> wgpu::RenderPass<'e> {
    let color: Vec<_> = targets
        .iter()
        .map(|&r| {
            let r = r?;
            Some(wgpu::RenderPassColorAttachment {
                view: views(r),
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("gbuffer"),
        color_attachments: &color,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: views(DEPTH),
            depth_ops: Some(wgpu::Operations { load: depth_load, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask,
    })
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use vrao_ao::layout_check::{self, mirror};

    #[test]
    fn the_gbuffer_uniform_matches_gbuffer_wgsl() {
        // The files of the per-eye path (`GBufferPass::new`).
        let files = [COMMON, MESH_WGSL, GBUFFER_WGSL, wgsl!("src/passes/gbuffer/gbuffer_multipass.wgsl")];
        layout_check::check(&[mirror!(PreviousEyes, files, "PreviousEyes", [clip_from_anchored, view_from_anchored])]);
    }
}
