//! Per-frame uniforms shared by every pass (mirrors `Frame`, `Eye` and `Light` in
//! shaders/common.wgsl), built in f64 and rounded once.

use super::scene::GpuScene;
use crate::scene::{Light, Scene};
use crate::settings::Settings;
use crate::stereo::Eye;
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, Mat4};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct EyeUniform {
    pub clip_from_anchored: [[f32; 4]; 4],
    pub view_from_anchored: [[f32; 4]; 4],
    pub world_from_view: [[f32; 4]; 4],
    pub tangents: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct FrameUniform {
    pub eyes: [EyeUniform; 2],
    pub size: [u32; 2],
    pub layers: u32,
    pub light_count: u32,
    pub near: f32,
    pub exposure: f32,
    pub white_point: f32,
    pub has_environment: u32,
    pub irradiance_sh: [[f32; 4]; 9],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct LightUniform {
    pub pos_or_dir: [f32; 4],
    pub radiance: [f32; 4],
    pub kind: [u32; 4],
}

/// The uniform and light buffers of one frame.
pub struct FrameBuffers {
    pub frame: wgpu::Buffer,
    pub lights: wgpu::Buffer,
    light_capacity: usize,
}

impl FrameBuffers {
    pub fn new(device: &wgpu::Device, light_count: usize) -> FrameBuffers {
        // Both eyes' copies; at least one element since wgpu rejects empty bindings.
        let light_capacity = (light_count * 2).max(1);
        FrameBuffers {
            frame: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame uniforms"),
                size: std::mem::size_of::<FrameUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            lights: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lights"),
                size: (light_capacity * std::mem::size_of::<LightUniform>()) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            light_capacity,
        }
    }

    /// Writes this frame's views (1 or 2), lights in each view's space, and settings.
    pub fn update(&self, queue: &wgpu::Queue, scene: &Scene, gpu_scene: &GpuScene, views: &[Eye], settings: &Settings) {
        let to_cols = |m: Mat4| m.to_cols_array_2d();
        let mut eyes = [EyeUniform::zeroed(); 2];
        let mut lights = Vec::with_capacity(self.light_capacity);
        for (slot, eye) in eyes.iter_mut().zip(views) {
            let view_from_world = eye.view_from_world();
            let view_from_anchored = view_from_world * DMat4::from_translation(gpu_scene.anchor);
            let [l, r, u, d] = eye.fov.tangents();
            *slot = EyeUniform {
                clip_from_anchored: to_cols(eye.clip_from_anchored(gpu_scene.anchor, settings.near)),
                view_from_anchored: to_cols(view_from_anchored.as_mat4()),
                world_from_view: to_cols(Mat4::from_quat(eye.pose.orientation.as_quat())),
                tangents: [l as f32, r as f32, u as f32, d as f32],
            };
            for light in &scene.lights {
                lights.push(match *light {
                    Light::Directional { direction, color, intensity } => LightUniform {
                        pos_or_dir: view_from_world
                            .transform_vector3(direction.as_dvec3())
                            .normalize_or_zero()
                            .as_vec3()
                            .extend(0.0)
                            .to_array(),
                        radiance: (color * intensity).extend(0.0).to_array(),
                        kind: [0; 4],
                    },
                    Light::Point { position, color, intensity } => LightUniform {
                        pos_or_dir: view_from_world.transform_point3(position).as_vec3().extend(1.0).to_array(),
                        radiance: (color * intensity).extend(0.0).to_array(),
                        kind: [1, 0, 0, 0],
                    },
                });
            }
        }
        let mut irradiance_sh = [[0.0; 4]; 9];
        if let Some(env) = &scene.environment {
            for (dst, c) in irradiance_sh.iter_mut().zip(env.irradiance_sh_scaled()) {
                *dst = c.extend(0.0).to_array();
            }
        }
        let uniform = FrameUniform {
            eyes,
            size: [settings.profile.width, settings.profile.height],
            layers: views.len() as u32,
            light_count: scene.lights.len() as u32,
            near: settings.near as f32,
            exposure: settings.exposure,
            white_point: settings.white_point,
            has_environment: scene.environment.is_some() as u32,
            irradiance_sh,
        };
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniform));
        if !lights.is_empty() {
            queue.write_buffer(&self.lights, 0, bytemuck::cast_slice(&lights));
        }
    }
}
