//! The compositor's late warp (shaders/reproject.wgsl): a finished stereo frame is
//! re-presented at a newer head pose, rotationally (orientation only, a homography per
//! eye) or positionally (the submitted depth forward-splatted into the new view).

use crate::error::Result;
use crate::wgsl;
use bytemuck::{Pod, Zeroable};
use glam::DMat4;
use vrao_ao::plug::{try_shader_module, Bind, Gpu, Kernel, LayeredTarget, Slot, COMMON};
use vrao_ao::Eye;
use vrao_render::passes::tonemap::COLOR;

/// How the simulated compositor warps a frame to a newer head pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum ReprojectionMode {
    /// Orientation only: every pixel is treated as infinitely far.
    Rotational,
    /// Orientation and position, using the frame's depth; disocclusions take the
    /// background beside them.
    #[default]
    #[cfg_attr(feature = "app", value(alias = "positional"))]
    Depth,
}

impl ReprojectionMode {
    /// The mode's `--reprojection` name.
    pub fn name(self) -> &'static str {
        match self {
            ReprojectionMode::Rotational => "rotational",
            ReprojectionMode::Depth => "depth",
        }
    }
}

/// Mirrors `Reproject` in shaders/reproject.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReprojectUniform {
    source_from_target: [[[f32; 4]; 4]; 2],
    target_from_source: [[[f32; 4]; 4]; 2],
    source_tangents: [[f32; 4]; 2],
    target_tangents: [[f32; 4]; 2],
    size: [u32; 2],
    layers: u32,
    near: f32,
}

/// The compositor's late warp: rotational and positional reprojection kernels and their uniform.
pub struct Reprojector {
    splat: Kernel,
    positional: Kernel,
    rotational: Kernel,
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    /// Splatted target depths, one u32 per pixel and layer (grown on demand).
    splatted: Option<wgpu::Buffer>,
    /// Group 1 every kernel has (the AO chain's visibility maps): the warp masks nothing,
    /// the runtime's compositor having no lens of its own here.
    visibility: vrao_ao::plug::VisibilityMaps,
}

/// shaders/reproject.wgsl's bindings: the warp's uniform, the held depth and colour and their
/// sampler, the splatted depths, the warped colour out (all the compositor's own).
const BINDINGS: [Bind; 6] = [
    Bind::Own(Slot::Uniform),
    Bind::Own(Slot::Depth),
    Bind::Own(Slot::FilterableLayers),
    Bind::Own(Slot::Sampler),
    Bind::Own(Slot::ReadWriteBuffer),
    Bind::Own(Slot::Output(wgpu::TextureFormat::Rgba8Unorm)),
];

impl Reprojector {
    /// Compiles the warp's kernels (splat, positional, rotational); a shader file that
    /// cannot be read (`VRAO_SHADER_DIR`) is the error.
    pub fn new(gpu: &Gpu) -> Result<Reprojector> {
        let module = try_shader_module(gpu, "reproject", &[COMMON, wgsl!("shaders/reproject.wgsl")])?;
        let variant = |label, entry, positional: bool| {
            Kernel::from_module(gpu, label, &module, entry, &BINDINGS, &[("POSITIONAL", f64::from(positional))])
        };
        Ok(Reprojector {
            splat: variant("reproject splat", "splat", true),
            positional: variant("reproject depth", "resolve", true),
            rotational: variant("reproject rotational", "resolve", false),
            uniform: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reproject"),
                size: std::mem::size_of::<ReprojectUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            sampler: gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("reproject"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            splatted: None,
            visibility: vrao_ao::plug::VisibilityMaps::new(gpu),
        })
    }

    /// Records the warp of `color` + `depth` (rendered for `source` eyes) to the `target`
    /// eyes into `output` (Rgba8Unorm, same size and layers).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        mode: ReprojectionMode,
        color: &LayeredTarget,
        depth: &LayeredTarget,
        source: &[Eye],
        target: &[Eye],
        near: f64,
        output: &LayeredTarget,
    ) {
        let layers = source.len().min(target.len()).min(2) as u32;
        let (width, height) = (color.width, color.height);
        let mut u = ReprojectUniform::zeroed();
        for layer in 0..layers as usize {
            let world_from_source = source[layer].view_from_world().inverse();
            let target_from_world: DMat4 = target[layer].view_from_world();
            let target_from_source = target_from_world * world_from_source;
            u.target_from_source[layer] = target_from_source.as_mat4().to_cols_array_2d();
            u.source_from_target[layer] = target_from_source.inverse().as_mat4().to_cols_array_2d();
            u.source_tangents[layer] = source[layer].fov.tangents().map(|t| t as f32);
            u.target_tangents[layer] = target[layer].fov.tangents().map(|t| t as f32);
        }
        u.size = [width, height];
        u.layers = layers;
        u.near = near as f32;
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
        let bytes = (width as u64 * height as u64 * layers as u64 * 4).max(4);
        if self.splatted.as_ref().is_none_or(|b| b.size() < bytes) {
            self.splatted = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reproject splatted depth"),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        let splatted = self.splatted.as_ref().expect("allocated above");
        let resources = [
            self.uniform.as_entire_binding(),
            wgpu::BindingResource::TextureView(&depth.array_view),
            wgpu::BindingResource::TextureView(&color.array_view),
            wgpu::BindingResource::Sampler(&self.sampler),
            splatted.as_entire_binding(),
            wgpu::BindingResource::TextureView(&output.array_view),
        ];
        let extent = (width, height, layers);
        match mode {
            ReprojectionMode::Rotational => {
                self.rotational.dispatch(&gpu.device, encoder, self.visibility.bind_group(), &resources, extent)
            }
            ReprojectionMode::Depth => {
                encoder.clear_buffer(splatted, 0, Some(bytes));
                self.splat.dispatch(&gpu.device, encoder, self.visibility.bind_group(), &resources, extent);
                self.positional.dispatch(&gpu.device, encoder, self.visibility.bind_group(), &resources, extent);
            }
        }
    }
}

/// A target the warp can write and the mirror can read: the colour format of eye frames.
pub fn output_target(gpu: &Gpu, (width, height, layers): (u32, u32, u32)) -> LayeredTarget {
    LayeredTarget::new(
        &gpu.device,
        "compositor output",
        COLOR.format(),
        (width, height, layers),
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    )
}

/// The engine's checker of Rust mirrors of WGSL structs (its `layout-check` feature, a
/// dev-dependency of this crate).
#[cfg(test)]
use vrao_ao::layout_check;

#[cfg(test)]
mod tests {
    use super::layout_check::{self, mirror};
    use super::*;

    #[test]
    fn the_reproject_uniform_matches_reproject_wgsl() {
        // The files of `Reprojector::new`.
        let files = [COMMON, wgsl!("shaders/reproject.wgsl")];
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(ReprojectUniform, files, "Reproject", [source_from_target, target_from_source, source_tangents, target_tangents, size, layers, near]),
        ]);
    }
}
