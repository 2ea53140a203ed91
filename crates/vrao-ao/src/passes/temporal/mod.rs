//! Temporal accumulation (Lin's NCTU thesis §3.1; temporal.wgsl): the occlusion of this
//! frame blended with the history reprojected from the previous frame. The history is
//! two pairs of targets (value, world position + frame count) that swap roles every
//! frame; the pass owns them, so they persist from frame to frame whatever the graph
//! allocates, and makes them again only when the occlusion's size changes.

use super::occlusion::AO_GEOMETRY;
use super::{DeclareContext, MoverBox, Pass, RecordContext};
use crate::gpu::kernel::{wgsl, Bind, ByChain, Kernel, Shader, Slot, COMMON, VISIBILITY};
use crate::gpu::layered_target::LayeredTarget;
use crate::gpu::Gpu;
use crate::graph::{PassDecl, Resource, Size, OCCLUSION, PIXEL_MOTION};
use crate::resource::ChainLayout;
use crate::settings::{Technique, TemporalBlend};
use bytemuck::{Pod, Zeroable};
use glam::DMat4;
use std::sync::Mutex;

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub(crate) const NAME: &str = "temporal";

/// Occlusion accumulated over frames by reverse reprojection, at AO resolution, laid out
/// as the raw occlusion.
pub const AO_ACCUMULATED: Resource = Resource::chain_storage("ao-accumulated", Size::Occlusion);

/// The history's accumulated values, a ping-pong pair the pass keeps (not the graph's).
pub const HISTORY_VALUE: [Resource; 2] = [
    Resource::chain_storage("history-value-a", Size::Occlusion),
    Resource::chain_storage("history-value-b", Size::Occlusion),
];

/// The history's world positions relative to the scene anchor, with the accumulated
/// frame count in w: a ping-pong pair the pass keeps.
pub const HISTORY_POSITION: [Resource; 2] = [
    Resource::storage("history-position-a", Size::Occlusion, wgpu::TextureFormat::Rgba32Float),
    Resource::storage("history-position-b", Size::Occlusion, wgpu::TextureFormat::Rgba32Float),
];

/// The most boxes around moving objects (two per object: now and before) whose
/// surroundings get a short history (temporal.wgsl `MAX_MOVERS`); more are left to the
/// motion vectors alone.
const MAX_MOVERS: usize = 16;

/// temporal.wgsl's bindings: frame, AO parameters, the pass's uniform, the occlusion
/// and its geometry, last frame's history (value, position), the accumulation out,
/// this frame's history out (value, position) and the pixels' motion. The history's value
/// out is in the chain's layout: [`bindings_in`].
const BINDINGS: [Bind; 11] = [
    Bind::Frame,
    Bind::AoParams,
    Bind::Own(Slot::Uniform),
    Bind::Read(AO_GEOMETRY),
    Bind::Read(OCCLUSION),
    Bind::Own(Slot::Layers),
    Bind::Own(Slot::Layers),
    Bind::Write(AO_ACCUMULATED),
    Bind::Own(Slot::Output(HISTORY_VALUE[0].format())),
    Bind::Own(Slot::Output(HISTORY_POSITION[0].format())),
    Bind::Read(PIXEL_MOTION),
];

/// [`BINDINGS`] with the history's value out in `chain`'s format.
fn bindings_in(chain: ChainLayout) -> [Bind; 11] {
    let mut binds = BINDINGS;
    binds[8] = Bind::Own(Slot::Output(HISTORY_VALUE[0].format_in(chain)));
    binds
}

/// The pass's WGSL files, in order.
const FILES: [Shader; 3] = [COMMON, VISIBILITY, wgsl!("src/passes/temporal/temporal.wgsl")];

/// Mirrors `Temporal` in temporal.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TemporalUniform {
    anchored_from_view: [[[f32; 4]; 4]; 2],
    previous_clip_from_anchored: [[[f32; 4]; 4]; 2],
    epsilon: f32,
    confidence_bias: f32,
    max_frames: f32,
    blend: u32,
    history_valid: u32,
    pixel_tangent: f32,
    motion_px: f32,
    has_motion: u32,
    previous_anchored_from_view: [[[f32; 4]; 4]; 2],
    previous_tangents: [[f32; 4]; 2],
    previous_view_from_anchored: [[[f32; 4]; 4]; 2],
    movers: [MoverBox; MAX_MOVERS],
    mover_count: u32,
    motion_with_distance: u32,
    motion_uv_scale: [f32; 2],
}

/// Temporal accumulation of the occlusion by reverse reprojection (module docs).
pub(crate) struct TemporalPass {
    kernel: ByChain<Kernel>,
    uniform: wgpu::Buffer,
    /// [value a, value b, position a, position b], made at the occlusion's size.
    history: Mutex<Vec<LayeredTarget>>,
}

impl TemporalPass {
    /// Builds the pass's pipelines.
    pub(crate) fn new(gpu: &Gpu) -> TemporalPass {
        TemporalPass {
            kernel: ByChain::new(gpu, |chain| {
                Kernel::in_chain(gpu, "temporal", &FILES, "main", &bindings_in(chain), &[], chain)
            }),
            uniform: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("temporal"),
                size: std::mem::size_of::<TemporalUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            history: Mutex::new(Vec::new()),
        }
    }

    /// The history targets at `extent` in `chain`'s layout, made (zeroed) when they are
    /// missing or of another size or layout; `true` when they were just made and hold no
    /// history.
    fn history_at(&self, gpu: &Gpu, extent: (u32, u32, u32), chain: ChainLayout) -> (Vec<LayeredTarget>, bool) {
        let mut history = self.history.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let fresh =
            history.first().is_none_or(|t| t.extent() != extent || t.format != HISTORY_VALUE[0].format_in(chain));
        if fresh {
            // COPY_DST: tests poison the history by writing it.
            let usage = wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST;
            *history = HISTORY_VALUE
                .iter()
                .chain(&HISTORY_POSITION)
                .map(|r| LayeredTarget::new(&gpu.device, r.name(), r.format_in(chain), extent, usage))
                .collect();
            gpu.invalidate_bind_groups();
        }
        (history.clone(), fresh)
    }
}

impl Pass for TemporalPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let ao = &setup.settings.ao;
        let decl = PassDecl::new(NAME).bindings(&BINDINGS);
        let decl = if uses_motion(setup) {
            decl.note("reprojects by the pixels' motion vectors; short history near moving objects")
        } else {
            decl.unbind(PIXEL_MOTION)
        };
        decl.provide(OCCLUSION, AO_ACCUMULATED)
            .occlusion_cost()
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to accumulate")
            .disabled_if(!ao.temporal.enabled, "temporal accumulation is off")
    }

    fn record(&self, ctx: &mut RecordContext) {
        let setup = ctx.setup;
        let t = &setup.settings.ao.temporal;
        let near = setup.settings.near;
        let anchor = setup.anchor;
        let mut u = TemporalUniform::zeroed();
        let views = setup.views as usize;
        let current = setup.current_views;
        for layer in 0..views.min(current.len()) {
            let world_from_view = current[layer].view_from_world().inverse();
            let anchored_from_view = DMat4::from_translation(-anchor) * world_from_view;
            u.anchored_from_view[layer] = anchored_from_view.as_mat4().to_cols_array_2d();
            if let Some(previous) = setup.previous_views {
                let eye = &previous[layer];
                u.previous_clip_from_anchored[layer] = eye.clip_from_anchored(anchor, near).to_cols_array_2d();
                let anchored_from_view = DMat4::from_translation(-anchor) * eye.view_from_world().inverse();
                u.previous_anchored_from_view[layer] = anchored_from_view.as_mat4().to_cols_array_2d();
                let view_from_anchored = eye.view_from_world() * DMat4::from_translation(anchor);
                u.previous_view_from_anchored[layer] = view_from_anchored.as_mat4().to_cols_array_2d();
                u.previous_tangents[layer] = eye.fov.tangents().map(|t| t as f32);
            }
        }
        u.epsilon = t.epsilon_m;
        u.confidence_bias = t.confidence_bias;
        u.max_frames = t.max_frames as f32;
        u.motion_px = t.motion_px;
        if uses_motion(setup) {
            u.has_motion = 1;
            // Each box reaches by the AO radius: what lies that close sees the object.
            let radius = setup.settings.ao.radius;
            for (slot, m) in u.movers.iter_mut().zip(setup.motion.movers.iter().take(MAX_MOVERS)) {
                *slot = *m;
                slot.half_extents[3] = radius;
            }
            u.mover_count = setup.motion.movers.len().min(MAX_MOVERS) as u32;
            u.motion_with_distance = setup.motion.with_distance as u32;
            u.motion_uv_scale = setup.motion.uv_scale;
        }
        u.blend = match t.blend {
            TemporalBlend::Average => 0,
            TemporalBlend::Confidence => 1,
        };
        let extent = ctx.ao_extent();
        let (history, fresh) = self.history_at(ctx.gpu, extent, setup.chain);
        u.history_valid = (setup.previous_views.is_some() && !fresh) as u32;
        // The frame's own views (an OpenXR runtime's, every frame), not the profile's.
        let [l, r, _, _] = current.first().map_or([-1.0, 1.0, 1.0, -1.0], |eye| eye.fov.tangents());
        let scale = if setup.settings.ao.resolution.is_half() { 2.0 } else { 1.0 };
        u.pixel_tangent = ((r - l) / setup.settings.width as f64 * scale) as f32;
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
        // This frame reads one (value, position) pair and writes the other; they swap each frame.
        let (read, write) = if setup.frame_index.is_multiple_of(2) { (0, 1) } else { (1, 0) };
        fn view(t: &LayeredTarget) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::TextureView(&t.array_view)
        }
        let own = [
            self.uniform.as_entire_binding(),
            view(&history[read]),
            view(&history[2 + read]),
            view(&history[write]),
            view(&history[2 + write]),
        ];
        // The history views live in `history` (clones of the pass's handles) until the dispatch.
        let resources = ctx.bind(&BINDINGS, &own);
        self.kernel.get(setup.chain).dispatch(
            &ctx.gpu.device,
            ctx.encoder,
            ctx.visibility.bind_group(),
            &resources,
            extent,
        );
    }

    fn kept_target(&self, r: Resource) -> Option<LayeredTarget> {
        let index = HISTORY_VALUE.iter().chain(&HISTORY_POSITION).position(|h| *h == r)?;
        self.history.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).get(index).cloned()
    }
}

/// Whether this frame reprojects by motion vectors (the scene moves or the host gave
/// them, and the settings ask for it).
fn uses_motion(setup: &DeclareContext) -> bool {
    setup.motion.vectors && setup.settings.ao.temporal.object_motion
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::gpu::layout_check::{self, mirror};

    #[test]
    fn the_temporal_uniform_matches_temporal_wgsl() {
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(TemporalUniform, FILES, "Temporal", [anchored_from_view, previous_clip_from_anchored, epsilon, confidence_bias, max_frames, blend, history_valid, pixel_tangent, motion_px, has_motion, previous_anchored_from_view, previous_tangents, previous_view_from_anchored, movers, mover_count, motion_with_distance, motion_uv_scale]),
            mirror!(MoverBox, FILES, "MoverBox", [box_from_anchored, half_extents]),
        ]);
    }
}
