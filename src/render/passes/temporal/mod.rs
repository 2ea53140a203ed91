//! Temporal accumulation (Lin's NCTU thesis §3.1; shaders/temporal.wgsl): the occlusion of this
//! frame blended with the history reprojected from the previous frame. The history is
//! two pairs of targets (value, world position + frame count) that swap roles every
//! frame; they persist between frames because the renderer keeps targets whose size
//! does not change.

use super::{FrameContext, FrameSetup, Pass};
use crate::render::gpu::kernel::{Kernel, Slot};
use crate::render::gpu::Gpu;
use crate::render::graph::{PassDecl, Resource};
use crate::render::settings::{Technique, TemporalBlend};
use bytemuck::{Pod, Zeroable};
use glam::DMat4;

/// Mirrors `Temporal` in shaders/temporal.wgsl.
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
    _pad: u32,
}

/// Temporal accumulation of the occlusion by reverse reprojection (module docs).
pub struct TemporalPass {
    kernel: Kernel,
    uniform: wgpu::Buffer,
}

/// This frame's (read, write) history targets: (value, position) pairs swap each frame.
fn history(frame_index: u64) -> ([Resource; 2], [Resource; 2]) {
    let a = [Resource::HistoryValueA, Resource::HistoryPositionA];
    let b = [Resource::HistoryValueB, Resource::HistoryPositionB];
    if frame_index.is_multiple_of(2) {
        (a, b)
    } else {
        (b, a)
    }
}

impl TemporalPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu) -> TemporalPass {
        let slots = [
            Slot::Uniform,
            Slot::Uniform,
            Slot::Uniform,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Layers,
            Slot::Output(Resource::AoAccumulated.format()),
            Slot::Output(Resource::HistoryValueA.format()),
            Slot::Output(Resource::HistoryPositionA.format()),
        ];
        TemporalPass {
            kernel: Kernel::new(gpu, "temporal", &["common.wgsl", "temporal.wgsl"], "main", &slots),
            uniform: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("temporal"),
                size: std::mem::size_of::<TemporalUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

impl Pass for TemporalPass {
    fn declare(&self, setup: &FrameSetup) -> PassDecl {
        let ao = &setup.settings.ao;
        let mut decl = PassDecl::new("temporal")
            .read(Resource::AoGeometry)
            .read(Resource::AoRaw)
            .write(Resource::AoAccumulated)
            .disabled_if(ao.technique == Technique::None, "technique is none: nothing to accumulate")
            .disabled_if(!ao.temporal.enabled, "temporal accumulation is off (--temporal)");
        // Both history pairs are read and written (their roles swap every frame).
        for r in
            [Resource::HistoryValueA, Resource::HistoryPositionA, Resource::HistoryValueB, Resource::HistoryPositionB]
        {
            decl = decl.read(r).write(r);
        }
        decl
    }

    fn record(&self, ctx: &mut FrameContext) {
        let setup = ctx.setup;
        let t = &setup.settings.ao.temporal;
        let near = setup.settings.near;
        let anchor = ctx.scene.anchor;
        let mut u = TemporalUniform::zeroed();
        let views = setup.views as usize;
        let current = setup.current_views;
        for layer in 0..views.min(current.len()) {
            let world_from_view = current[layer].view_from_world().inverse();
            let anchored_from_view = DMat4::from_translation(-anchor) * world_from_view;
            u.anchored_from_view[layer] = anchored_from_view.as_mat4().to_cols_array_2d();
            if let Some(previous) = setup.previous_views {
                u.previous_clip_from_anchored[layer] =
                    previous[layer].clip_from_anchored(anchor, near).to_cols_array_2d();
            }
        }
        u.epsilon = t.epsilon_m;
        u.confidence_bias = t.confidence_bias;
        u.max_frames = t.max_frames as f32;
        u.motion_px = t.motion_px;
        u.blend = match t.blend {
            TemporalBlend::Average => 0,
            TemporalBlend::Confidence => 1,
        };
        u.history_valid = setup.previous_views.is_some() as u32;
        // The frame's own views (an OpenXR runtime's, every frame), not the profile's.
        let p = &setup.settings.profile;
        let fov = current.first().map_or(p.fov_left, |eye| eye.fov);
        let [l, r, _, _] = fov.tangents();
        let scale = if setup.settings.ao.half_res { 2.0 } else { 1.0 };
        u.pixel_tangent = ((r - l) / p.width as f64 * scale) as f32;
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
        let (read, write) = history(setup.frame_index);
        let resources = [
            ctx.frame.frame.as_entire_binding(),
            ctx.frame.ao.as_entire_binding(),
            self.uniform.as_entire_binding(),
            ctx.view(Resource::AoGeometry),
            ctx.view(Resource::AoRaw),
            ctx.view(read[0]),
            ctx.view(read[1]),
            ctx.view(Resource::AoAccumulated),
            ctx.view(write[0]),
            ctx.view(write[1]),
        ];
        self.kernel.dispatch(&ctx.gpu.device, ctx.encoder, &resources, ctx.ao_extent());
    }
}
