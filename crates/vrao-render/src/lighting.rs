//! The scene's lights and environment in each view's space, and the tone mapping: the
//! environment for the engine's [`FrameLighting`] (SSDO gathers it), the lights and the
//! tone mapping for the renderer's own shaders ([`ShadingBuffers`], lighting.wgsl).

use crate::gpu::kernel::wgsl;
use crate::scene::{spot_ramp, Light, Scene};
use crate::settings::Settings;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat3, Vec3};
use vrao_ao::plug::{quadratic_in_view, FrameLighting, Shader};
use vrao_ao::Eye;

/// lighting.wgsl: `Shading` and `Light`, what [`ShadingBuffers`] hold.
pub const LIGHTING_WGSL: Shader = wgsl!("src/lighting.wgsl");

/// The tone mapping and the lights' count (`Shading` of lighting.wgsl; layout must match).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShadingUniform {
    light_count: u32,
    exposure: f32,
    white_point: f32,
    padding: u32,
}

/// One light in one view's space (`Light` of lighting.wgsl; layout must match).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct LightUniform {
    /// Directional: the direction the light travels; point and spot: view-space position (m).
    pub pos_or_dir: [f32; 4],
    /// Colour × intensity in rgb.
    pub radiance: [f32; 4],
    /// x: 0 directional, 1 point, 2 spot.
    pub kind: [u32; 4],
    /// Spot: the view-space unit direction of the cone's axis in xyz.
    pub spot_direction: [f32; 4],
    /// Spot: cos(outer cone) and the falloff ramp's scale ([`spot_ramp`]).
    pub cone: [f32; 4],
}

/// The buffers the renderer's shaders read its lights and tone mapping from, written
/// each frame ([`ViewLighting::write`]).
pub struct ShadingBuffers {
    /// `Shading` of lighting.wgsl (uniform).
    pub shading: wgpu::Buffer,
    /// Both views' [`LightUniform`]s (storage; at least one element: wgpu rejects empty
    /// bindings).
    pub lights: wgpu::Buffer,
    light_capacity: usize,
}

impl ShadingBuffers {
    /// Room for `lights_per_view` lights in each of two views.
    pub fn new(device: &wgpu::Device, lights_per_view: usize) -> ShadingBuffers {
        let light_capacity = (lights_per_view * 2).max(1);
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        ShadingBuffers {
            shading: buffer("shading", std::mem::size_of::<ShadingUniform>() as u64, wgpu::BufferUsages::UNIFORM),
            lights: buffer(
                "lights",
                (light_capacity * std::mem::size_of::<LightUniform>()) as u64,
                wgpu::BufferUsages::STORAGE,
            ),
            light_capacity,
        }
    }
}

/// A frame's lights and environment in each of its views' space.
pub struct ViewLighting {
    anchor: DVec3,
    lights: Vec<LightUniform>,
    environment: Option<[[[f32; 4]; 10]; 4]>,
    exposure: f32,
    white_point: f32,
}

impl ViewLighting {
    /// `scene`'s lights and environment seen from each of `views`, anchored at `anchor`.
    pub fn new(scene: &Scene, anchor: DVec3, views: &[Eye], settings: &Settings) -> ViewLighting {
        let mut lights = Vec::with_capacity(scene.lights.len() * views.len());
        let mut quadratics = [[[0.0; 4]; 10]; 4];
        for (index, eye) in views.iter().enumerate().take(2) {
            let view_from_world = eye.view_from_world();
            if let Some(env) = &scene.environment {
                let rotation = Mat3::from_quat(eye.pose.orientation.as_quat());
                let in_view = |q: [Vec3; 10]| quadratic_in_view(&q, rotation).map(|c| c.extend(0.0).to_array());
                quadratics[index] = in_view(env.irradiance_quadratic());
                quadratics[2 + index] = in_view(env.radiance_quadratic());
            }
            lights.extend(scene.lights.iter().map(|light| light_in_view(light, &view_from_world)));
        }
        ViewLighting {
            anchor,
            lights,
            environment: scene.environment.is_some().then_some(quadratics),
            exposure: settings.exposure,
            white_point: settings.white_point,
        }
    }

    /// The engine's view of it: the anchor and the environment.
    pub fn frame_lighting(&self) -> FrameLighting<'_> {
        FrameLighting { anchor: self.anchor, environment: self.environment.as_ref() }
    }

    /// Writes the lights and the tone mapping into `buffers` (made for as many lights).
    pub fn write(&self, queue: &wgpu::Queue, buffers: &ShadingBuffers, views: usize) {
        debug_assert!(
            self.lights.len() <= buffers.light_capacity,
            "more lights than ShadingBuffers::new made room for"
        );
        let uniform = ShadingUniform {
            light_count: self.lights.len().checked_div(views).unwrap_or(0) as u32,
            exposure: self.exposure,
            white_point: self.white_point,
            padding: 0,
        };
        queue.write_buffer(&buffers.shading, 0, bytemuck::bytes_of(&uniform));
        if !self.lights.is_empty() {
            queue.write_buffer(&buffers.lights, 0, bytemuck::cast_slice(&self.lights));
        }
    }
}

/// One light in the space of a view with this view-from-world.
fn light_in_view(light: &Light, view_from_world: &glam::DMat4) -> LightUniform {
    match *light {
        Light::Directional { direction, color, intensity } => LightUniform {
            pos_or_dir: view_from_world
                .transform_vector3(direction.as_dvec3())
                .normalize_or_zero()
                .as_vec3()
                .extend(0.0)
                .to_array(),
            radiance: (color * intensity).extend(0.0).to_array(),
            kind: [0; 4],
            ..LightUniform::zeroed()
        },
        Light::Point { position, color, intensity } => LightUniform {
            pos_or_dir: view_from_world.transform_point3(position).as_vec3().extend(1.0).to_array(),
            radiance: (color * intensity).extend(0.0).to_array(),
            kind: [1, 0, 0, 0],
            ..LightUniform::zeroed()
        },
        Light::Spot { position, direction, color, intensity, inner_cone, outer_cone } => {
            let (cos_outer, scale) = spot_ramp(inner_cone, outer_cone);
            let axis = view_from_world.transform_vector3(direction.as_dvec3()).normalize_or_zero();
            LightUniform {
                pos_or_dir: view_from_world.transform_point3(position).as_vec3().extend(1.0).to_array(),
                radiance: (color * intensity).extend(0.0).to_array(),
                kind: [2, 0, 0, 0],
                spot_direction: axis.as_vec3().extend(0.0).to_array(),
                cone: [cos_outer, scale, 0.0, 0.0],
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vrao_ao::layout_check::{self, mirror};

    #[test]
    fn the_uniforms_match_lighting_wgsl() {
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(ShadingUniform, [LIGHTING_WGSL], "Shading", [light_count, exposure, white_point, padding]),
            mirror!(LightUniform, [LIGHTING_WGSL], "Light", [pos_or_dir, radiance, kind, spot_direction, cone]),
        ]);
    }
}
