//! Per-frame uniforms shared by every pass (mirrors `Frame`, `Eye` and `Light` in
//! shaders/common.wgsl), built in f64 and rounded once.

use crate::frame::ChainSettings;
use crate::sampling::{hbao_directions_steps, hemisphere_kernel_part, HemisphereDensity};
use crate::settings::Noise;
use crate::stereo::Eye;
use crate::technique::SamplePattern;
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec3, Mat4};

/// One eye's matrices as the shaders read them (`Eye` of common.wgsl; layout must match).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct EyeUniform {
    /// Clip from the scene's anchor frame (geometry is stored relative to the f64 anchor).
    pub clip_from_anchored: [[f32; 4]; 4],
    /// View from the anchor frame (normals use its rotation).
    pub view_from_anchored: [[f32; 4]; 4],
    /// World from view, rotation only (environment lookups).
    pub world_from_view: [[f32; 4]; 4],
    /// tan(left), tan(right), tan(up), tan(down) of the eye's asymmetric frustum.
    pub tangents: [f32; 4],
    /// The other eye's view from this eye's view (identity for a mono view).
    pub other_from_view: [[f32; 4]; 4],
}

/// Per-frame constants of every pass (`Frame` of common.wgsl; layout must match).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct FrameUniform {
    /// The views of layer 0 and layer 1 (layer 1 all zeros for a mono view).
    pub eyes: [EyeUniform; 2],
    /// Full-resolution image size in pixels, per eye.
    pub size: [u32; 2],
    /// Layers of the targets: 2 for stereo, 1 for mono.
    pub layers: u32,
    /// Near plane in metres (reversed-Z, far plane at infinity).
    pub near: f32,
    /// 1 when the scene has an environment light, else 0.
    pub has_environment: u32,
    /// Places the quadratics at a multiple of 16 bytes, as WGSL aligns them.
    pub padding: [u32; 3],
    /// The environment light as quadratics in each eye's view-space direction
    /// (`quadratic_in_view`; zero without an environment): [irradiance of eye 0, of
    /// eye 1 (`Environment::irradiance_quadratic`), pre-filtered radiance of eye 0, of
    /// eye 1 (`Environment::radiance_quadratic`, SSDO)].
    pub environment_quadratics: [[[f32; 4]; 10]; 4],
}

/// The occlusion passes' parameters (`AoParams` of common.wgsl; layout must match).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct AoParamsUniform {
    /// Size of the occlusion targets in pixels (half the full size, rounded up, at half resolution).
    pub ao_size: [u32; 2],
    /// Full-resolution pixels per occlusion pixel along each axis: 1 or 2.
    pub scale: u32,
    /// SSAO/SSDO samples per pixel.
    pub samples: u32,
    /// HBAO directions (directions × steps ≈ samples).
    pub directions: u32,
    /// HBAO steps per direction.
    pub steps: u32,
    /// How the composite applies occlusion: 0 none, 1 scalar AO, 2 directional (SSDO).
    pub technique: u32,
    /// 0 tiled 5×5 rotations, 1 Halton/R2 per-pixel rotation.
    pub noise: u32,
    /// World-space occlusion radius in metres.
    pub radius: f32,
    /// Occlusion weight in [0, 4].
    pub strength: f32,
    /// Depth bias as a fraction of the radius.
    pub bias: f32,
    /// 1: occluders beyond the radius fade out (range check).
    pub range_check: u32,
    /// SSDO bounce strength (0: no bounce work).
    pub bounce: f32,
    /// Extra rotation of every pixel's pattern this frame (HBAO with temporal
    /// accumulation turns its directions by the golden angle per frame; 0 otherwise).
    pub frame_angle: f32,
    /// Bilateral blur radius in occlusion pixels.
    pub blur_radius: u32,
    /// Depth-edge width of the blur, as a fraction of the centre pixel's distance.
    pub blur_plane_sigma: f32,
    /// Scale of the sample lengths this frame (HBAO's temporal range jitter; 1 otherwise).
    pub range_scale: f32,
    /// Pads the struct to 80 bytes, a multiple of 16 (`_pad0`… in common.wgsl).
    pub padding: [u32; 3],
}

/// Most samples a kernel may hold (the settings' limit on N).
pub(crate) const MAX_KERNEL_SAMPLES: usize = 256;

/// What of a scene the frame uniforms carry: the anchor the geometry is stored relative
/// to and the environment in each view's space. A renderer computes them from its scene
/// for this frame's views (its lights and tone mapping are its own); the AO engine has
/// [`FrameLighting::NONE`] or the host's environment.
#[derive(Clone, Copy)]
pub struct FrameLighting<'a> {
    /// The f64 origin of the anchored frame.
    pub anchor: DVec3,
    /// The environment's quadratics in each view's space, as
    /// `environment_quadratics` holds them; `None` without one.
    pub environment: Option<&'a [[[f32; 4]; 10]; 4]>,
}

impl FrameLighting<'_> {
    /// No environment, the world origin as the anchor (a host's views).
    pub const NONE: FrameLighting<'static> = FrameLighting { anchor: DVec3::ZERO, environment: None };
}

/// The uniform buffers of one frame.
pub struct FrameUniforms {
    /// The `FrameUniform`.
    pub frame: wgpu::Buffer,
    /// `AoParams` of common.wgsl.
    pub ao: wgpu::Buffer,
    /// The hemisphere kernel: one [x, y, z, length] per sample.
    pub kernel: wgpu::Buffer,
}

/// Occlusion targets' size: half per axis (rounded up, so odd sizes keep their last
/// row and column) with half resolution.
pub fn ao_extent(width: u32, height: u32, half_res: bool) -> (u32, u32) {
    if half_res {
        (width.div_ceil(2), height.div_ceil(2))
    } else {
        (width, height)
    }
}

impl FrameUniforms {
    /// Allocates the buffers; the driver fills them each frame.
    pub fn new(device: &wgpu::Device) -> FrameUniforms {
        FrameUniforms {
            frame: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame uniforms"),
                size: std::mem::size_of::<FrameUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            ao: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("ao params"),
                size: std::mem::size_of::<AoParamsUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            kernel: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("ao kernel"),
                size: (MAX_KERNEL_SAMPLES * 16) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }

    /// Writes the occlusion parameters and the kernel that suits the technique.
    /// `frame_index` changes the sampling pattern when temporal accumulation is on.
    pub fn update_ao(&self, queue: &wgpu::Queue, settings: &ChainSettings, frame_index: u64) {
        let ao = &settings.ao;
        let (width, height) = ao_extent(settings.width, settings.height, ao.resolution.is_half());
        let (directions, steps) = hbao_directions_steps(ao.samples);
        // SSDO weighs each direction's light by cos θ itself, so its samples are uniform.
        let entry = ao.technique.entry();
        let density = match entry.samples {
            SamplePattern::HemisphereUniform => HemisphereDensity::Uniform,
            _ => HemisphereDensity::Cosine,
        };
        // With temporal accumulation each frame of the window takes its own part of a
        // longer Halton kernel, so the accumulated samples are as stratified as one
        // kernel of window × N. Parts alone leave less noise after the window than
        // golden-angle turns of one kernel or parts plus turns — turning a part breaks the
        // stratification between parts (docs/records/2026-11-29/measurements-in-code.md, kernel-parts). So
        // the hemisphere techniques change their pattern by parts and only the marching
        // techniques (HBAO, GTAO), whose directions are not a Halton kernel, turn.
        let part = if ao.temporal.enabled { (frame_index % ao.temporal.max_frames as u64) as u32 } else { 0 };
        let turns = ao.temporal.enabled && entry.samples == SamplePattern::Directions;
        let kernel = hemisphere_kernel_part(part, ao.samples.min(MAX_KERNEL_SAMPLES as u32), density);
        let params = AoParamsUniform {
            ao_size: [width, height],
            scale: if ao.resolution.is_half() { 2 } else { 1 },
            samples: ao.samples,
            directions,
            steps,
            technique: entry.composite as u32,
            noise: match ao.noise {
                Noise::Tiled5x5 => 0,
                Noise::Halton => 1,
            },
            radius: ao.radius,
            strength: ao.strength,
            bias: ao.bias,
            range_check: ao.range_check as u32,
            bounce: if ao.bounce_active() { ao.bounce } else { 0.0 },
            frame_angle: if turns { temporal_angle(frame_index) } else { 0.0 },
            // The blur radius is in full-resolution pixels: at half resolution the same
            // screen footprint takes half as many taps.
            blur_radius: if ao.resolution.is_half() { ao.blur_radius.div_ceil(2) } else { ao.blur_radius },
            blur_plane_sigma: ao.blur_plane_sigma,
            range_scale: if turns { temporal_range_scale(frame_index) } else { 1.0 },
            padding: [0; 3],
        };
        queue.write_buffer(&self.ao, 0, bytemuck::bytes_of(&params));
        queue.write_buffer(&self.kernel, 0, bytemuck::cast_slice(&kernel));
    }

    /// Writes this frame's views (1 or 2), their environment, and settings.
    pub fn update(&self, queue: &wgpu::Queue, lighting: &FrameLighting, views: &[Eye], settings: &ChainSettings) {
        let FrameLighting { anchor, environment } = *lighting;
        let to_cols = |m: Mat4| m.to_cols_array_2d();
        let mut eyes = [EyeUniform::zeroed(); 2];
        for (index, (slot, eye)) in eyes.iter_mut().zip(views).enumerate() {
            let view_from_anchored = eye.view_from_world() * DMat4::from_translation(anchor);
            let [l, r, u, d] = eye.fov.tangents();
            *slot = EyeUniform {
                clip_from_anchored: to_cols(eye.clip_from_anchored(anchor, settings.near)),
                view_from_anchored: to_cols(view_from_anchored.as_mat4()),
                world_from_view: to_cols(Mat4::from_quat(eye.pose.orientation.as_quat())),
                tangents: [l as f32, r as f32, u as f32, d as f32],
                other_from_view: to_cols(other_from_view(views, index)),
            };
        }
        let uniform = FrameUniform {
            eyes,
            size: [settings.width, settings.height],
            layers: views.len() as u32,
            near: settings.near as f32,
            has_environment: environment.is_some() as u32,
            padding: [0; 3],
            environment_quadratics: environment.copied().unwrap_or([[[0.0; 4]; 10]; 4]),
        };
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniform));
    }
}

/// The other view's view-from-this-view of `views[index]`, in f64 (identity without a
/// second view).
fn other_from_view(views: &[Eye], index: usize) -> Mat4 {
    match views.get(1 - index.min(1)) {
        Some(other) if views.len() == 2 => {
            (other.view_from_world() * views[index].view_from_world().inverse()).as_mat4()
        }
        _ => Mat4::IDENTITY,
    }
}

/// HBAO's turn of its directions this frame (radians): the golden angle (137.5°) per frame.
/// Lin's NCTU thesis turns it 10° per frame, which leaves successive patterns so alike that
/// accumulating frames cuts the noise far less than golden-angle steps do
/// (docs/records/2026-11-29/measurements-in-code.md, temporal-angle).
pub(crate) fn temporal_angle(frame_index: u64) -> f32 {
    ((frame_index as f64 * 137.507_764f64).rem_euclid(360.0)).to_radians() as f32
}

/// The range jitter of Lin's NCTU thesis (HBAO): the sample lengths scale by a factor in [0.9,
/// 1] that follows the golden-ratio sequence, so successive frames reach different depths.
pub(crate) fn temporal_range_scale(frame_index: u64) -> f32 {
    let golden = 0.618_033_988_749_895_f64;
    (1.0 - 0.1 * (frame_index as f64 * golden).fract()) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::kernel::COMMON;
    use crate::gpu::layout_check::{self, mirror};

    #[test]
    fn the_uniforms_match_common_wgsl() {
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(EyeUniform, [COMMON], "Eye", [clip_from_anchored, view_from_anchored, world_from_view, tangents, other_from_view]),
            mirror!(FrameUniform, [COMMON], "Frame", [eyes, size, layers, near, has_environment, padding, environment_quadratics]),
            mirror!(AoParamsUniform, [COMMON], "AoParams", [ao_size, scale, samples, directions, steps, technique, noise, radius, strength, bias, range_check, bounce, frame_angle, blur_radius, blur_plane_sigma, range_scale, padding]),
        ]);
    }
}
