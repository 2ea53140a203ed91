//! The scene's lights and environment as the frame uniforms hold them: in each view's
//! space, for the engine's [`FrameLighting`].

use crate::scene::{spot_ramp, Light, Scene};
use crate::settings::Settings;
use bytemuck::Zeroable;
use glam::{DVec3, Mat3, Vec3};
use vrao_ao::plug::{quadratic_in_view, FrameLighting, LightUniform};
use vrao_ao::Eye;

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

    /// The engine's view of it.
    pub fn frame_lighting(&self) -> FrameLighting<'_> {
        FrameLighting {
            anchor: self.anchor,
            lights: &self.lights,
            environment: self.environment.as_ref(),
            exposure: self.exposure,
            white_point: self.white_point,
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
