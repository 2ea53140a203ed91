//! The AO engine's import pass: the host's depth and normals, imported into the graph as
//! [`HOST_DEPTH`] and [`HOST_NORMALS`], become the G-buffer's [`DEPTH`] and [`NORMALS`]
//! in vrao's conventions (import.wgsl), so that every technique reads a host's frame as
//! it reads vrao's own. One fullscreen triangle per view: a read and a write per pixel
//! (four more depth reads when the normals are rebuilt).

use super::{AoConfig, AoFrame, NormalEncoding, NormalSpace, Projection};
use crate::error::{Error, Result};
use crate::gpu::kernel::{shader_module, wgsl, Shader, Slot};
use crate::gpu::raster;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, PIXEL_MOTION};
use crate::passes::inputs::{DEPTH, NORMALS};
use crate::passes::{DeclareContext, Pass, RecordContext};
use bytemuck::{Pod, Zeroable};
use std::sync::Mutex;

/// The pass's name, as `--explain` and the timings show it.
pub const NAME: &str = "ao-import";

/// The host's depth buffer (any depth format; its readers bind it as depth).
pub const HOST_DEPTH: Resource = Resource::imported("host-depth", wgpu::TextureFormat::Depth32Float);

/// The host's normals (any float-sampled format).
pub const HOST_NORMALS: Resource = Resource::imported("host-normals", wgpu::TextureFormat::Rgba16Float);
/// The host's motion vectors (any float format): temporal accumulation reads them
/// directly as [`crate::graph::PIXEL_MOTION`].
pub const HOST_MOTION: Resource = Resource::imported("host-motion", wgpu::TextureFormat::Rgba16Float);

const IMPORT_WGSL: Shader = wgsl!("src/ao/import.wgsl");

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
    padding: u32,
}

/// A host frame's inputs, checked: what the import pass writes into its uniform.
#[derive(Clone, Copy)]
pub struct ImportSource {
    params: ImportParams,
    views: u32,
    /// Whether the host gave motion vectors.
    motion: bool,
}

impl ImportSource {
    /// Checks the host's textures and matrices against the engine's configuration; the
    /// error names the input and what is wrong with it.
    /// `projections` are the views' projections as [`Projection::of`] read them.
    pub(crate) fn check(frame: &AoFrame, config: &AoConfig, projections: &[Projection]) -> Result<ImportSource> {
        check_texture("depth", frame.depth, config)?;
        if !DEPTH_FORMATS.contains(&frame.depth.format()) {
            return Err(Error::input(format!(
                "depth: format {:?} is not one of {DEPTH_FORMATS:?}",
                frame.depth.format()
            )));
        }
        let mut params = ImportParams::zeroed();
        if let Some(normals) = &frame.normals {
            check_texture("normals", normals.texture, config)?;
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
        Ok(ImportSource { params, views: config.views, motion: frame.motion.is_some() })
    }

    /// The engine's near plane (vrao depth = near / distance).
    fn with_near(mut self, near: f32) -> ImportSource {
        self.params.near = near;
        self
    }
}

/// Refuses a texture of another size, too few layers, multisampled or not bindable.
pub(crate) fn check_texture(what: &str, texture: &wgpu::Texture, config: &AoConfig) -> Result<()> {
    let size = texture.size();
    if (size.width, size.height) != (config.width, config.height) {
        return Err(Error::input(format!(
            "{what}: {}×{} does not match the engine's {}×{}",
            size.width, size.height, config.width, config.height
        )));
    }
    if size.depth_or_array_layers < config.views || texture.dimension() != wgpu::TextureDimension::D2 {
        return Err(Error::input(format!(
            "{what}: a 2D texture with {} layer(s) cannot hold {} view(s)",
            size.depth_or_array_layers, config.views
        )));
    }
    if texture.sample_count() != 1 {
        return Err(Error::input(format!("{what}: {} samples per pixel; resolve it first", texture.sample_count())));
    }
    if !texture.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return Err(Error::input(format!("{what}: the texture lacks TEXTURE_BINDING usage")));
    }
    Ok(())
}

/// The import pass of a host's engine.
pub struct ImportPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    /// This frame's checked inputs (set by the engine before it plans the frame).
    source: Mutex<Option<ImportSource>>,
}

impl ImportPass {
    /// Builds the pipeline (one colour target for the normals, depth written as
    /// `frag_depth`).
    pub fn new(gpu: &Gpu) -> ImportPass {
        let device = &gpu.device;
        let entries = [
            Slot::Uniform.layout_entry(0, wgpu::ShaderStages::FRAGMENT),
            Slot::Depth.layout_entry(1, wgpu::ShaderStages::FRAGMENT),
            Slot::Layers.layout_entry(2, wgpu::ShaderStages::FRAGMENT),
        ];
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(NAME), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(NAME),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shader_module(gpu, NAME, &[IMPORT_WGSL]);
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
                entry_point: Some("import_frame"),
                compilation_options: Default::default(),
                targets: &[Some(NORMALS.format().into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(NAME),
            size: std::mem::size_of::<ImportParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ImportPass { pipeline, layout, uniform, source: Mutex::new(None) }
    }

    /// The inputs of the frame about to be planned and recorded.
    pub fn set_source(&self, source: ImportSource) {
        *self.source.lock().unwrap_or_else(|p| p.into_inner()) = Some(source);
    }

    fn source(&self) -> Option<ImportSource> {
        *self.source.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl Pass for ImportPass {
    fn declare(&self, _setup: &DeclareContext) -> PassDecl {
        let decl = PassDecl::new(NAME).read(HOST_DEPTH).read(HOST_NORMALS).write(DEPTH).write(NORMALS);
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
        let bind_group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(NAME),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: ctx.view(HOST_DEPTH) },
                wgpu::BindGroupEntry { binding: 2, resource: ctx.view(HOST_NORMALS) },
            ],
        });
        let (depth, normals) = (ctx.target(DEPTH), ctx.target(NORMALS));
        for layer in 0..source.views {
            let normals = (&normals.layer_views[layer as usize], wgpu::Color::TRANSPARENT);
            let depth = &depth.layer_views[layer as usize];
            let mut pass = raster::colour_and_depth_pass(ctx.encoder, NAME, normals, Some(depth));
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, layer..layer + 1);
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
            mirror!(ImportLayer, [IMPORT_WGSL], "ImportLayer", [view_from_world, tangents, depth_offset, depth_numerator, padding]),
            mirror!(ImportParams, [IMPORT_WGSL], "ImportParams", [layers, size, near, reversed, host_normals, unsigned_normals, world_normals, padding]),
        ]);
    }
}
