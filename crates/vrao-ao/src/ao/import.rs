//! The AO engine's import pass: the host's depth and normals, imported into the graph as
//! [`HOST_DEPTH`] and [`HOST_NORMALS`], become the G-buffer's [`DEPTH`] and [`NORMALS`]
//! in vrao's conventions (import.wgsl), so that every technique reads a host's frame as
//! it reads vrao's own. One fullscreen triangle per view: a read and a write per pixel
//! (four more depth reads when the normals are rebuilt). A multisampled host (2, 4 or 8
//! samples) is resolved here, each pixel taking its sample nearest the eye
//! (import_msaa.wgsl): one read per sample instead of one per pixel, nothing else.
//!
//! A host's second depth layer ([`HOST_DEPTH_LAYER_2`]), where the occlusion reads two,
//! becomes [`DEPTH_LAYER_2`] in a depth-only pass per view after the first
//! (import.wgsl `import_second_layer`): the same conversion, at the sample the first
//! layer's resolve took.

use super::host_texture::{check_texture, check_texture_size};
use super::{AoConfig, AoFrame, NormalEncoding, NormalSpace, Projection};
use crate::error::{Error, Result};
use crate::gpu::kernel::{shader_module, wgsl, Shader, Slot};
use crate::gpu::{raster, Gpu};
use crate::graph::{PassDecl, Resource, PIXEL_MOTION};
use crate::passes::gtao::reads_second_layer;
use crate::passes::inputs::{DEPTH, DEPTH_LAYER_2, NORMALS};
use crate::passes::{DeclareContext, Pass, RecordContext};
use bytemuck::{Pod, Zeroable};
use std::sync::{Mutex, OnceLock};

/// The pass's name, as `--explain` and the timings show it.
pub(crate) const NAME: &str = "ao-import";

/// The host's depth buffer (any depth format; its readers bind it as depth).
pub(crate) const HOST_DEPTH: Resource = Resource::imported("host-depth", wgpu::TextureFormat::Depth32Float);

/// The host's second depth layer (any depth format, the depth's convention and samples).
pub(crate) const HOST_DEPTH_LAYER_2: Resource =
    Resource::imported("host-depth-layer-2", wgpu::TextureFormat::Depth32Float);

/// The host's normals (any float-sampled format).
pub(crate) const HOST_NORMALS: Resource = Resource::imported("host-normals", wgpu::TextureFormat::Rgba16Float);
/// The host's motion vectors (any float format): temporal accumulation reads them
/// directly as [`crate::graph::PIXEL_MOTION`].
pub(crate) const HOST_MOTION: Resource = Resource::imported("host-motion", wgpu::TextureFormat::Rgba16Float);

const IMPORT_WGSL: Shader = wgsl!("src/ao/import.wgsl");
/// The reads of a host with one sample per pixel.
const SINGLE_WGSL: Shader = wgsl!("src/ao/import_single.wgsl");
/// The reads of a multisampled host.
const MSAA_WGSL: Shader = wgsl!("src/ao/import_msaa.wgsl");

/// The sample counts the engine takes for the host's depth, second layer and normals.
pub(crate) const SAMPLE_COUNTS: [u32; 4] = [1, 2, 4, 8];

/// Depth formats the engine reads (the depth aspect of the depth-stencil ones).
const DEPTH_FORMATS: [wgpu::TextureFormat; 5] = [
    wgpu::TextureFormat::Depth32Float,
    wgpu::TextureFormat::Depth24Plus,
    wgpu::TextureFormat::Depth16Unorm,
    wgpu::TextureFormat::Depth24PlusStencil8,
    wgpu::TextureFormat::Depth32FloatStencil8,
];

/// `ImportLayer` of import.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ImportLayer {
    view_from_world: [[f32; 4]; 4],
    tangents: [f32; 4],
    depth_offset: f32,
    depth_numerator: f32,
    padding: [f32; 2],
}

/// `ImportParams` of import.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ImportParams {
    layers: [ImportLayer; 2],
    size: [u32; 2],
    near: f32,
    reversed: u32,
    host_normals: u32,
    unsigned_normals: u32,
    world_normals: u32,
    cast_none: u32,
}

/// A host frame's inputs, checked: what the import pass writes into its uniform.
#[derive(Clone, Copy)]
pub(crate) struct ImportSource {
    params: ImportParams,
    views: u32,
    /// Samples per pixel of the host's depth (and normals).
    samples: u32,
    /// Whether the host gave motion vectors.
    motion: bool,
    /// Whether the host gave a second depth layer and the settings ask for two.
    second_layer: bool,
}

impl ImportSource {
    /// Checks the host's textures and matrices against the engine's configuration; the
    /// error names the input and what is wrong with it.
    /// `projections` are the views' projections as [`Projection::of`] read them.
    pub(crate) fn check(frame: &AoFrame, config: &AoConfig, projections: &[Projection]) -> Result<ImportSource> {
        check_texture_size("depth", frame.depth, config)?;
        let samples = frame.depth.sample_count();
        if !SAMPLE_COUNTS.contains(&samples) {
            return Err(Error::input(format!(
                "depth: {samples} samples per pixel (the engine takes {SAMPLE_COUNTS:?})"
            )));
        }
        if !DEPTH_FORMATS.contains(&frame.depth.format()) {
            return Err(Error::input(format!(
                "depth: format {:?} is not one of {DEPTH_FORMATS:?}",
                frame.depth.format()
            )));
        }
        if let Some(second) = frame.second_layer {
            check_second_layer(second, samples, config)?;
        }
        let mut params = ImportParams::zeroed();
        if let Some(normals) = &frame.normals {
            check_texture_size("normals", normals.texture, config)?;
            if normals.texture.sample_count() != samples {
                return Err(Error::input(format!(
                    "normals: sample count {} where the depth's is {samples}: give both with the same count",
                    normals.texture.sample_count()
                )));
            }
            let sample = normals.texture.format().sample_type(None, None);
            if !matches!(sample, Some(wgpu::TextureSampleType::Float { .. })) {
                return Err(Error::input(format!(
                    "normals: format {:?} is not read as float",
                    normals.texture.format()
                )));
            }
            params.host_normals = 1;
            params.unsigned_normals = (normals.encoding == NormalEncoding::Unsigned) as u32;
            params.world_normals = (normals.space == NormalSpace::World) as u32;
        }
        if let Some(motion) = &frame.motion {
            check_texture("motion", motion.texture, config)?;
            let sample = motion.texture.format().sample_type(None, None);
            if !matches!(sample, Some(wgpu::TextureSampleType::Float { .. })) {
                return Err(Error::input(format!("motion: format {:?} is not read as float", motion.texture.format())));
            }
            let [x, y] = motion.to_previous_uv;
            if !(x.is_finite() && y.is_finite()) {
                return Err(Error::input(format!("motion: to_previous_uv {:?} is not finite", motion.to_previous_uv)));
            }
        }
        for ((layer, m), p) in params.layers.iter_mut().zip(frame.views).zip(projections) {
            let [l, r, u, d] = p.fov.tangents();
            *layer = ImportLayer {
                view_from_world: m.view.to_cols_array_2d(),
                tangents: [l as f32, r as f32, u as f32, d as f32],
                depth_offset: p.depth_offset as f32,
                depth_numerator: p.depth_numerator as f32,
                padding: [0.0; 2],
            };
        }
        params.size = [config.width, config.height];
        params.reversed = frame.depth_convention.reversed_z as u32;
        params.cast_none = frame.exclusion.map_or(0, |e| e.cast_none);
        Ok(ImportSource {
            params,
            views: config.views,
            samples,
            motion: frame.motion.is_some(),
            second_layer: frame.second_layer.is_some() && config.settings.layers == 2,
        })
    }

    /// The engine's near plane (vrao depth = near / distance).
    fn with_near(mut self, near: f32) -> ImportSource {
        self.params.near = near;
        self
    }
}

/// Refuses a second depth layer that does not follow the depth's rules (checked whether
/// or not this frame reads it, so a bad one shows before the settings ask for two).
fn check_second_layer(second: &wgpu::Texture, samples: u32, config: &AoConfig) -> Result<()> {
    check_texture_size("second layer", second, config)?;
    if second.sample_count() != samples {
        return Err(Error::input(format!(
            "second layer: sample count {} where the depth's is {samples}: give both with the same count",
            second.sample_count()
        )));
    }
    if !DEPTH_FORMATS.contains(&second.format()) {
        return Err(Error::input(format!(
            "second layer: format {:?} is not one of {DEPTH_FORMATS:?}",
            second.format()
        )));
    }
    Ok(())
}

/// The import pass of a host's engine.
pub(crate) struct ImportPass {
    /// For a host with one sample per pixel.
    single: ImportPipeline,
    /// For a multisampled host: made at its first multisampled frame.
    msaa: OnceLock<MsaaImport>,
    /// The second layer's depth-only pipelines, single-sample and multisampled: each
    /// made at the first frame that reads such a second layer.
    second_layer: [OnceLock<ImportPipeline>; 2],
    uniform: wgpu::Buffer,
    /// This frame's checked inputs (set by the engine before it plans the frame).
    source: Mutex<Option<ImportSource>>,
    /// This frame's exclusion mask (all views), or the placeholder of zeros.
    mask: Mutex<Option<wgpu::TextureView>>,
    placeholder_mask: wgpu::TextureView,
}

/// One variant of the import's pipeline and its bind group layout.
struct ImportPipeline {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// The multisampled variant, with the texture it binds in place of normals the host did
/// not give (a multisampled binding takes no single-sample placeholder).
struct MsaaImport {
    pipeline: ImportPipeline,
    no_normals: wgpu::TextureView,
}

/// A fragment-stage binding of `ty` at `binding`.
fn fragment_entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::FRAGMENT, ty, count: None }
}

impl ImportPipeline {
    /// The pipeline of import.wgsl over `reads` (the host's textures bound as `depth`
    /// and `normals`): one colour target for the normals, depth written as `frag_depth`.
    fn new(gpu: &Gpu, reads: Shader, depth: wgpu::BindingType, normals: wgpu::BindingType) -> ImportPipeline {
        let entries = [
            Slot::Uniform.layout_entry(0, wgpu::ShaderStages::FRAGMENT),
            fragment_entry(1, depth),
            fragment_entry(2, normals),
            fragment_entry(3, super::exclusion::MASK_BINDING),
        ];
        Self::build(gpu, reads, &entries, "import_frame", &[Some(NORMALS.format().into())])
    }

    /// The depth-only pipeline of import.wgsl's `import_second_layer` over `reads`, the
    /// host's depth and its second layer both bound as `depth`.
    fn second_layer(gpu: &Gpu, reads: Shader, depth: wgpu::BindingType) -> ImportPipeline {
        let entries = [
            Slot::Uniform.layout_entry(0, wgpu::ShaderStages::FRAGMENT),
            fragment_entry(1, depth),
            fragment_entry(4, depth),
        ];
        Self::build(gpu, reads, &entries, "import_second_layer", &[])
    }

    fn build(
        gpu: &Gpu,
        reads: Shader,
        entries: &[wgpu::BindGroupLayoutEntry],
        fragment: &str,
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> ImportPipeline {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(NAME), entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(NAME),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shader_module(gpu, NAME, &[reads, IMPORT_WGSL]);
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(NAME),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
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
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(fragment),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        ImportPipeline { pipeline, layout }
    }
}

/// A multisampled 2D binding of `sample_type` (one layer of a host's texture).
fn multisampled(sample_type: wgpu::TextureSampleType) -> wgpu::BindingType {
    wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2, multisampled: true }
}

/// A view of `texture`'s layer `layer` alone, of `aspect` (a multisampled binding takes
/// no array).
fn layer_view(texture: &wgpu::Texture, aspect: wgpu::TextureAspect, layer: u32) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some(NAME),
        dimension: Some(wgpu::TextureViewDimension::D2),
        aspect,
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

impl MsaaImport {
    fn new(gpu: &Gpu) -> MsaaImport {
        let pipeline = ImportPipeline::new(
            gpu,
            MSAA_WGSL,
            multisampled(wgpu::TextureSampleType::Depth),
            multisampled(wgpu::TextureSampleType::Float { filterable: false }),
        );
        let no_normals = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("ao-import no normals"),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 4,
            dimension: wgpu::TextureDimension::D2,
            format: HOST_NORMALS.format(),
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        MsaaImport { pipeline, no_normals: no_normals.create_view(&Default::default()) }
    }
}

impl ImportPass {
    /// Builds the single-sample pipeline (the multisampled one waits for a multisampled
    /// host).
    pub(crate) fn new(gpu: &Gpu) -> ImportPass {
        let single = ImportPipeline::new(gpu, SINGLE_WGSL, Slot::Depth.binding_type(), Slot::Layers.binding_type());
        let uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(NAME),
            size: std::mem::size_of::<ImportParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let placeholder_mask = super::exclusion::placeholder(gpu);
        ImportPass {
            single,
            msaa: OnceLock::new(),
            second_layer: [OnceLock::new(), OnceLock::new()],
            uniform,
            source: Mutex::new(None),
            mask: Mutex::new(None),
            placeholder_mask,
        }
    }

    /// The inputs of the frame about to be planned and recorded, and its exclusion mask.
    pub(crate) fn set_source(&self, source: ImportSource, mask: Option<wgpu::TextureView>) {
        *self.source.lock().unwrap_or_else(|p| p.into_inner()) = Some(source);
        *self.mask.lock().unwrap_or_else(|p| p.into_inner()) = mask;
    }

    fn source(&self) -> Option<ImportSource> {
        *self.source.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// One bind group per view: the layered views for a single-sample host (the same
    /// group for every view), each view's layer for a multisampled one.
    fn bind_groups(&self, ctx: &RecordContext, source: &ImportSource) -> (&wgpu::RenderPipeline, Vec<wgpu::BindGroup>) {
        let uniform = self.uniform.as_entire_binding();
        let mask = self.mask.lock().unwrap_or_else(|p| p.into_inner()).clone();
        let mask = mask.unwrap_or_else(|| self.placeholder_mask.clone());
        let group = |layout: &wgpu::BindGroupLayout, depth: &wgpu::BindingResource, normals: &wgpu::BindingResource| {
            ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(NAME),
                layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.clone() },
                    wgpu::BindGroupEntry { binding: 1, resource: depth.clone() },
                    wgpu::BindGroupEntry { binding: 2, resource: normals.clone() },
                    wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&mask) },
                ],
            })
        };
        if source.samples == 1 {
            let single = group(&self.single.layout, &ctx.view(HOST_DEPTH), &ctx.view(HOST_NORMALS));
            return (&self.single.pipeline, vec![single; source.views as usize]);
        }
        let msaa = self.msaa.get_or_init(|| MsaaImport::new(ctx.gpu));
        let groups = (0..source.views)
            .map(|layer| {
                let depth = layer_view(&ctx.target(HOST_DEPTH).texture, wgpu::TextureAspect::DepthOnly, layer);
                let normals = match source.params.host_normals {
                    1 => layer_view(&ctx.target(HOST_NORMALS).texture, wgpu::TextureAspect::All, layer),
                    _ => msaa.no_normals.clone(),
                };
                group(
                    &msaa.pipeline.layout,
                    &wgpu::BindingResource::TextureView(&depth),
                    &wgpu::BindingResource::TextureView(&normals),
                )
            })
            .collect();
        (&msaa.pipeline.pipeline, groups)
    }

    /// Converts the host's second layer into [`DEPTH_LAYER_2`]: one depth-only pass per
    /// view, after the first layer's (the uniform is the one it wrote).
    fn record_second_layer(&self, ctx: &mut RecordContext, source: &ImportSource) {
        let msaa = source.samples > 1;
        let pipeline = self.second_layer[usize::from(msaa)].get_or_init(|| match msaa {
            false => ImportPipeline::second_layer(ctx.gpu, SINGLE_WGSL, Slot::Depth.binding_type()),
            true => ImportPipeline::second_layer(ctx.gpu, MSAA_WGSL, multisampled(wgpu::TextureSampleType::Depth)),
        });
        let group = |depth: &wgpu::BindingResource, second: &wgpu::BindingResource| {
            ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(NAME),
                layout: &pipeline.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: depth.clone() },
                    wgpu::BindGroupEntry { binding: 4, resource: second.clone() },
                ],
            })
        };
        let bind_groups: Vec<wgpu::BindGroup> = if msaa {
            let (depth, second) = (&ctx.target(HOST_DEPTH).texture, &ctx.target(HOST_DEPTH_LAYER_2).texture);
            (0..source.views)
                .map(|layer| {
                    let depth = layer_view(depth, wgpu::TextureAspect::DepthOnly, layer);
                    let second = layer_view(second, wgpu::TextureAspect::DepthOnly, layer);
                    group(&wgpu::BindingResource::TextureView(&depth), &wgpu::BindingResource::TextureView(&second))
                })
                .collect()
        } else {
            vec![group(&ctx.view(HOST_DEPTH), &ctx.view(HOST_DEPTH_LAYER_2)); source.views as usize]
        };
        let target = ctx.target(DEPTH_LAYER_2);
        for (layer, bind_group) in (0..source.views).zip(&bind_groups) {
            let mut pass = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(NAME),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.layer_views[layer as usize],
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline.pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, layer..layer + 1);
        }
    }
}

impl Pass for ImportPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let decl = PassDecl::new(NAME).read(HOST_DEPTH).read(HOST_NORMALS).write(DEPTH).write(NORMALS);
        let ao = &setup.settings.ao;
        let decl = match self.source() {
            Some(source) if source.second_layer && reads_second_layer(setup) => {
                decl.read(HOST_DEPTH_LAYER_2).write(DEPTH_LAYER_2)
            }
            _ if ao.layers == 2 && ao.technique.reads_second_layer() => {
                decl.note("one depth layer: the host gave no second layer (AoFrame::second_layer)")
            }
            _ => decl,
        };
        // The host's motion goes to temporal accumulation as it is.
        let decl = match self.source() {
            Some(source) if source.motion => decl.read(HOST_MOTION).provide(PIXEL_MOTION, HOST_MOTION),
            _ => decl,
        };
        match self.source() {
            Some(source) if source.params.host_normals == 1 => decl,
            _ => decl.unbind(HOST_NORMALS).note("no host normals: rebuilt from the depth"),
        }
    }

    fn record(&self, ctx: &mut RecordContext) {
        let Some(source) = self.source() else { return };
        let source = source.with_near(ctx.setup.settings.near as f32);
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&source.params));
        let (pipeline, bind_groups) = self.bind_groups(ctx, &source);
        let (depth, normals) = (ctx.target(DEPTH), ctx.target(NORMALS));
        for (layer, bind_group) in (0..source.views).zip(&bind_groups) {
            let normals = (&normals.layer_views[layer as usize], wgpu::Color::TRANSPARENT);
            let depth = &depth.layer_views[layer as usize];
            let mut pass = raster::colour_and_depth_pass(ctx.encoder, NAME, normals, Some(depth));
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, layer..layer + 1);
        }
        if source.second_layer && reads_second_layer(ctx.setup) {
            self.record_second_layer(ctx, &source);
        }
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::gpu::layout_check::{self, mirror};

    #[test]
    fn the_import_uniform_matches_import_wgsl() {
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(ImportLayer, [SINGLE_WGSL, IMPORT_WGSL], "ImportLayer", [view_from_world, tangents, depth_offset, depth_numerator, padding]),
            mirror!(ImportParams, [SINGLE_WGSL, IMPORT_WGSL], "ImportParams", [layers, size, near, reversed, host_normals, unsigned_normals, world_normals, cast_none]),
        ]);
    }
}
