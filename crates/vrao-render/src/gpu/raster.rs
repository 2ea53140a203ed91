//! The mesh-drawing pieces of the renderer's raster passes: the scene's vertex layout and
//! the mesh pipeline (G-buffer, depth peeling, shadow maps). The engine's raster pieces
//! (full-screen pipeline, layer views) are in [`vrao_ao::plug`].

use super::scene::Vertex;

/// The scene's vertices (position, normal, uv sets 0 and 1, colour, tangent) as the raster
/// passes read them.
pub const MESH_ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Unorm8x4, 4 => Snorm16x4
];

/// One vertex buffer of [`Vertex`] with the given attributes (all, or the position only).
pub fn mesh_vertex_buffer(attributes: &[wgpu::VertexAttribute]) -> wgpu::VertexBufferLayout<'_> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes,
    }
}

/// What differs between the mesh-drawing pipelines (G-buffer, depth peeling, shadow maps).
pub struct MeshPipeline<'a> {
    /// The pipeline's label.
    pub label: &'a str,
    /// Its bind group layouts.
    pub layout: &'a wgpu::PipelineLayout,
    /// The module holding both entry points.
    pub module: &'a wgpu::ShaderModule,
    /// The vertex entry point and the vertex attributes it reads ([`MESH_ATTRIBUTES`] or
    /// a prefix of them).
    pub vertex: (&'a str, &'a [wgpu::VertexAttribute]),
    /// The depth attachment's format and test.
    pub depth: (wgpu::TextureFormat, wgpu::CompareFunction),
    /// The fragment entry point and its colour targets; `None` for depth only.
    pub fragment: Option<(&'a str, &'a [Option<wgpu::ColorTargetState>])>,
    /// Multiview's view mask, if the pipeline draws every layer at once.
    pub multiview_mask: Option<std::num::NonZeroU32>,
    /// Whether the fragment stage discards alpha-tested holes (mesh.wgsl's `ALPHA_TEST`
    /// override; the module must include mesh.wgsl and have a fragment stage).
    pub alpha_test: bool,
    /// The faces culled: back faces (clockwise on screen) for a single-sided material's
    /// surface; front faces where a pass wants what lies behind (the depth peel).
    pub cull: Option<wgpu::Face>,
}

/// What a draw needs of its pipeline: an alpha test, back-face culling, both or neither.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawKind {
    /// Its material is alpha-tested ([`MeshPipeline::alpha_test`]).
    pub alpha_test: bool,
    /// Its material is single-sided ([`MeshPipeline::cull`]).
    pub cull: bool,
}

impl DrawKind {
    /// Every kind, in drawing order: solid before alpha-tested (early depth test).
    pub const ALL: [DrawKind; 4] = [
        DrawKind { alpha_test: false, cull: false },
        DrawKind { alpha_test: false, cull: true },
        DrawKind { alpha_test: true, cull: false },
        DrawKind { alpha_test: true, cull: true },
    ];
}

/// One pass's mesh pipelines: one per [`DrawKind`] the scene draws, none for the others.
pub struct MeshPipelines {
    /// In [`DrawKind::ALL`] order.
    pub by_kind: [Option<wgpu::RenderPipeline>; 4],
}

impl MeshPipelines {
    /// `make`'s pipeline for each kind among `kinds` (what the scene draws).
    pub fn new(kinds: &[DrawKind], mut make: impl FnMut(DrawKind) -> wgpu::RenderPipeline) -> MeshPipelines {
        MeshPipelines { by_kind: DrawKind::ALL.map(|k| kinds.contains(&k).then(|| make(k))) }
    }

    /// The pipeline for `kind`, if the scene draws it.
    pub fn get(&self, kind: DrawKind) -> Option<&wgpu::RenderPipeline> {
        let i = DrawKind::ALL.iter().position(|&k| k == kind)?;
        self.by_kind[i].as_ref()
    }

    /// Whether some pipeline discards alpha-tested holes.
    pub fn alpha_tested(&self) -> bool {
        DrawKind::ALL.iter().zip(&self.by_kind).any(|(k, p)| k.alpha_test && p.is_some())
    }
}

/// A pipeline that draws the scene's meshes, writing depth: two-sided for double-sided
/// materials (OBJ windings are not trusted: the G-buffer faces normals towards the eye,
/// and both faces of a surface cast shadows). A single-sided material's back faces are
/// culled in every pass that draws its surface, shadow maps included, as Unity's and
/// Bevy's shadow casters follow the material's culling; the depth peel draws both faces
/// of every material and marks which it kept (`peel/mod.rs`).
pub fn mesh_pipeline(device: &wgpu::Device, p: MeshPipeline) -> wgpu::RenderPipeline {
    let (format, compare) = p.depth;
    let alpha_constants = [("ALPHA_TEST", 1.0)];
    let fragment_options = wgpu::PipelineCompilationOptions {
        constants: if p.alpha_test { &alpha_constants } else { &[] },
        ..Default::default()
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(p.label),
        layout: Some(p.layout),
        vertex: wgpu::VertexState {
            module: p.module,
            entry_point: Some(p.vertex.0),
            compilation_options: Default::default(),
            buffers: &[Some(mesh_vertex_buffer(p.vertex.1))],
        },
        primitive: wgpu::PrimitiveState { front_face: wgpu::FrontFace::Ccw, cull_mode: p.cull, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(true),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: p.fragment.map(|(entry, targets)| wgpu::FragmentState {
            module: p.module,
            entry_point: Some(entry),
            compilation_options: fragment_options,
            targets,
        }),
        multiview_mask: p.multiview_mask,
        cache: None,
    })
}
