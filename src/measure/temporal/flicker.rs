//! Stability under slow head motion: how much a technique's final AO and light change
//! from one frame to the next while the head turns slowly (a yaw at a constant rate, a
//! still scene), each frame compared with the previous one reprojected to it (the point a
//! pixel sees, looked up where the previous frame's eye saw it, on the same surface:
//! `stereo_consistency::lookup`). A still scene's AO and light do not change, so what
//! changes is flicker: the noise pattern sliding over the surfaces, the denoise and the
//! temporal accumulation not holding it.

use crate::error::Result;
use crate::measure::metrics::luminance;
use crate::measure::stereo_consistency::{lookup, EyeImages};
use glam::DQuat;
use std::sync::Arc;
use vrao_ao::plug::{Gpu, DEPTH, FINAL_AO};
use vrao_ao::HeadPose;
use vrao_render::renderer::Renderer;
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;

/// Frames rendered before the first one compared (temporal accumulation settles).
pub const SETTLE_FRAMES: u32 = 8;

/// The frame-to-frame change of one setting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameChange {
    /// RMS of the AO's change between consecutive frames, over the points both see.
    pub ao: f64,
    /// RMS of the light's luminance change (rgb of a light-gathering technique) relative
    /// to its mean; `None` for a technique without light.
    pub light: Option<f64>,
    /// Points compared.
    pub compared: u64,
}

/// The last frame's eyes, then its AO, light and depth per eye.
type PreviousFrame = (Vec<vrao_ao::Eye>, Vec<Vec<f32>>, Vec<Vec<f32>>, Vec<Vec<f32>>);

/// Renders `frames` frames (after [`SETTLE_FRAMES`]) at 90 Hz of `scene` from its head
/// turning about the vertical at `degrees_per_second`, and measures the change between
/// consecutive frames.
pub fn frame_to_frame(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    settings: &Settings,
    degrees_per_second: f64,
    frames: u32,
) -> Result<FrameChange> {
    let mut renderer = Renderer::new(gpu.clone(), scene, settings)?;
    let start = scene.head.pose_at(0.0);
    let light = settings.ao.technique.carries_light();
    let (w, h) = (settings.profile.width as usize, settings.profile.height as usize);
    let mut previous: Option<PreviousFrame> = None;
    let (mut ao2, mut light2, mut light_sum, mut n) = (0f64, 0f64, 0f64, 0u64);
    for frame in 0..SETTLE_FRAMES + frames {
        let yaw = (degrees_per_second * frame as f64 / 90.0).to_radians();
        let head = HeadPose { orientation: DQuat::from_rotation_y(yaw) * start.orientation, ..start };
        let eyes = settings.profile.eyes(&head, settings.near).eyes.to_vec();
        renderer.render(&eyes, &[FINAL_AO])?;
        let image = renderer.read_f32(FINAL_AO)?;
        let depth = renderer.read_f32(DEPTH)?;
        let ao: Vec<Vec<f32>> = image.iter().map(|l| l.iter().skip(3).step_by(4).copied().collect()).collect();
        let lum: Vec<Vec<f32>> =
            image.iter().map(|l| l.chunks(4).map(|t| luminance([t[0], t[1], t[2]]) as f32).collect()).collect();
        if frame >= SETTLE_FRAMES {
            if let Some((before, depth_b, ao_b, lum_b)) = &previous {
                for layer in 0..eyes.len().min(before.len()) {
                    let (now, then) = (&eyes[layer], &before[layer]);
                    let then_from_now = then.view_from_world() * now.pose.sanitized().world_from_local();
                    let tangents = then.fov.tangents();
                    let ao_then = EyeImages { depth: &depth_b[layer], ao: &ao_b[layer] };
                    let lum_then = EyeImages { depth: &depth_b[layer], ao: &lum_b[layer] };
                    for y in 0..h {
                        for x in 0..w {
                            let d = depth[layer][y * w + x] as f64;
                            if !(d.is_finite() && d > 0.0) {
                                continue;
                            }
                            let uv = [(x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64];
                            let v = then_from_now.transform_point3(vrao_ao::Fov::view_position_from_depth(
                                uv,
                                d,
                                &now.fov,
                                settings.near,
                            ));
                            let size = (w as u32, h as u32);
                            let Some(a) = lookup(&ao_then, v, tangents, size, settings.near) else { continue };
                            ao2 += (ao[layer][y * w + x] as f64 - a as f64).powi(2);
                            if light {
                                let l = lookup(&lum_then, v, tangents, size, settings.near).unwrap_or(a);
                                let now_l = lum[layer][y * w + x] as f64;
                                light2 += (now_l - l as f64).powi(2);
                                light_sum += now_l;
                            }
                            n += 1;
                        }
                    }
                }
            }
        }
        previous = Some((eyes, depth, ao, lum));
    }
    let n_f = n.max(1) as f64;
    let mean_light = light_sum / n_f;
    Ok(FrameChange {
        ao: (ao2 / n_f).sqrt(),
        light: (light && mean_light > 1e-12).then(|| (light2 / n_f).sqrt() / mean_light),
        compared: n,
    })
}
