//! One bounce of directional light from reflective shadow maps (Lin's NCTU thesis §3.3,
//! rsm.wgsl): at half resolution per axis, each pixel gathers N virtual point
//! lights from the light-space pass's maps in a disk of radius R, with a pattern turned
//! per pixel and per frame. The composite upsamples the irradiance (3×3 joint
//! bilateral, in composite.wgsl) and adds irradiance × albedo/π to the ambient.

use super::shadow::{rsm_active, shadow_casters, LightSpace, RSM_FLUX, RSM_NORMAL, SHADOW_MAP, SHADOW_WGSL};
use super::{scene_of, settings_of};
use crate::gpu::kernel::wgsl;
use bytemuck::{Pod, Zeroable};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use vrao_ao::plug::{
    ao_extent, Bind, DeclareContext, Gpu, Kernel, Pass, PassDecl, RecordContext, Resource, Shader, Size, Slot, COMMON,
    DEPTH, NORMALS,
};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "rsm";

/// The pass's WGSL files, in order.
const FILES: [Shader; 3] = [COMMON, SHADOW_WGSL, wgsl!("src/passes/rsm/rsm.wgsl")];

/// `RsmParams` of rsm.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RsmParamsUniform {
    low_size: [u32; 2],
    samples: u32,
    frame: u32,
    radius: f32,
    _pad: [f32; 3],
}

/// One-bounce irradiance gathered from the reflective shadow maps, half resolution per
/// axis (rgb).
pub const RSM_INDIRECT: Resource = Resource::storage("rsm-indirect", Size::Half, wgpu::TextureFormat::Rgba16Float);

/// Normal (xyz) and view distance (w) at each [`RSM_INDIRECT`] pixel, for the
/// composite's joint bilateral upsampling.
pub const RSM_GEOMETRY: Resource = Resource::storage("rsm-geometry", Size::Half, wgpu::TextureFormat::Rgba32Float);

/// rsm.wgsl's bindings: frame, the lights' `Shadows`, the gather's parameters, the
/// G-buffer and the light-space maps in, the irradiance and its geometry out.
const BINDINGS: [Bind; 10] = [
    Bind::Frame,
    Bind::Own(Slot::Uniform),
    Bind::Own(Slot::Uniform),
    Bind::Read(DEPTH),
    Bind::Read(NORMALS),
    Bind::Read(SHADOW_MAP),
    Bind::Read(RSM_NORMAL),
    Bind::Read(RSM_FLUX),
    Bind::Write(RSM_INDIRECT),
    Bind::Write(RSM_GEOMETRY),
];

/// One bounce of directional light from reflective shadow maps (module docs).
pub struct RsmPass {
    kernel: Kernel,
    light_space: Arc<LightSpace>,
    params: wgpu::Buffer,
    /// Frames this pass has gathered: turns the sampling pattern (Lin's NCTU thesis).
    frame: AtomicU32,
}

impl RsmPass {
    /// Builds the pass's pipelines.
    pub fn new(gpu: &Gpu, light_space: Arc<LightSpace>) -> RsmPass {
        let kernel = Kernel::new(gpu, "rsm", &FILES, "main", &BINDINGS);
        let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rsm params"),
            size: std::mem::size_of::<RsmParamsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        RsmPass { kernel, light_space, params, frame: AtomicU32::new(0) }
    }
}

impl Pass for RsmPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let s = &settings_of(setup).shadows;
        let lights = shadow_casters(scene_of(setup)).len();
        PassDecl::new(NAME)
            .bindings(&BINDINGS)
            .disabled_if(lights == 0, "no directional light to bounce (reflective shadow maps need one)")
            .disabled_if(!s.rsm, "reflective shadow maps are off (turned on, they add one bounce of the sun)")
            .note(format!(
                "{} VPLs per pixel and light within {} m, half resolution, pattern turned per frame{}",
                s.rsm_samples,
                s.rsm_radius,
                if settings_of(setup).ao.bounce_active() { "; SSDO's bounce adds the sun's bounce too" } else { "" }
            ))
    }

    fn record(&self, ctx: &mut RecordContext) {
        debug_assert!(rsm_active(scene_of(ctx.setup), settings_of(ctx.setup)));
        let p = &settings_of(ctx.setup).profile;
        let (w, h) = ao_extent(p.width, p.height, true);
        let s = &settings_of(ctx.setup).shadows;
        let frame = self.frame.fetch_add(1, Ordering::Relaxed);
        let params =
            RsmParamsUniform { low_size: [w, h], samples: s.rsm_samples, frame, radius: s.rsm_radius, _pad: [0.0; 3] };
        ctx.gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let own = [self.light_space.uniform.as_entire_binding(), self.params.as_entire_binding()];
        let resources = ctx.bind(&BINDINGS, &own);
        self.kernel.dispatch(
            &ctx.gpu.device,
            ctx.encoder,
            ctx.visibility.bind_group(),
            &resources,
            (w, h, ctx.setup.views),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vrao_ao::layout_check::{self, mirror};

    #[test]
    fn the_rsm_uniform_matches_rsm_wgsl() {
        layout_check::check(&[mirror!(RsmParamsUniform, FILES, "RsmParams", [low_size, samples, frame, radius, _pad])]);
    }
}
