//! How good the compositor's warp is: a frame rendered at one head pose is reprojected to
//! a moved pose and compared with a frame rendered fresh at that pose, for each mode.

use crate::error::Result;
use crate::xr::simulated::reproject::{output_target, ReprojectionMode, Reprojector};
use glam::{DQuat, DVec3};
use serde::Serialize;
use vrao_ao::plug::{read_layers, DEPTH};
use vrao_ao::HeadPose;
use vrao_render::passes::tonemap::COLOR;
use vrao_render::renderer::Renderer;

/// A head movement between rendering and display.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum HeadMove {
    /// Yaw about the vertical by this many degrees.
    RotateDegrees(f64),
    /// Sideways (the head's +X) by this many centimetres.
    TranslateCm(f64),
}

impl HeadMove {
    /// `pose` after the move: yaw about the world vertical, or sideways along the head's +X.
    pub fn apply(self, pose: &HeadPose) -> HeadPose {
        match self {
            HeadMove::RotateDegrees(deg) => HeadPose {
                position: pose.position,
                orientation: (DQuat::from_rotation_y(deg.to_radians()) * pose.orientation).normalize(),
            },
            HeadMove::TranslateCm(cm) => HeadPose {
                position: pose.position + pose.orientation * DVec3::X * (cm / 100.0),
                orientation: pose.orientation,
            },
        }
    }

    /// The move in words, e.g. `rotate 5°`.
    pub fn describe(self) -> String {
        match self {
            HeadMove::RotateDegrees(d) => format!("rotate {d}°"),
            HeadMove::TranslateCm(c) => format!("translate {c} cm"),
        }
    }
}

/// RMSE (colour values 0..1, both eyes, every pixel) of a warped frame against a fresh one.
#[derive(Clone, Debug, Serialize)]
pub struct ReprojectionError {
    /// The head movement between rendering and display.
    pub movement: HeadMove,
    /// Not warping at all: the old frame shown as it is.
    pub stale_rmse: f64,
    /// With the rotational warp (orientation only).
    pub rotational_rmse: f64,
    /// With the depth-based (positional) warp.
    pub depth_rmse: f64,
}

fn rmse(a: &[Vec<u8>], b: &[Vec<u8>]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (la, lb) in a.iter().zip(b) {
        for (pa, pb) in la.chunks_exact(4).zip(lb.chunks_exact(4)) {
            for c in 0..3 {
                let d = (pa[c] as f64 - pb[c] as f64) / 255.0;
                sum += d * d;
            }
            n += 3;
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

/// Renders at `head`, then for each movement warps that frame in both modes and compares
/// with a fresh render at the moved pose.
///
/// In a scene that moves, the fresh frames are rendered `late_s` seconds of scene time
/// after the source frame (a frame shown that late): the warp moves the eyes, not the
/// objects (the compositor does not extrapolate objects by their motion vectors), so
/// what they moved meanwhile is part of the error.
pub fn measure(
    renderer: &mut Renderer,
    head: &HeadPose,
    movements: &[HeadMove],
    late_s: f64,
) -> Result<Vec<ReprojectionError>> {
    let gpu = renderer.gpu().clone();
    let source_time = renderer.scene_time();
    let settings = renderer.settings().clone();
    let outputs = [COLOR, DEPTH];
    let source_eyes = settings.profile.eyes(head, settings.near);
    renderer.render(&source_eyes.eyes, &outputs)?;
    let stale = read_layers(&gpu, renderer.target(COLOR).expect("rendered"))?;
    // Keep the source frame: the fresh renders below reuse the renderer's targets.
    let extent = renderer.target(COLOR).expect("rendered").extent();
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let color = vrao_ao::plug::LayeredTarget::new(&gpu.device, "source colour", COLOR.format(), extent, usage);
    let depth = vrao_ao::plug::LayeredTarget::new(&gpu.device, "source depth", DEPTH.format(), extent, usage);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (resource, copy) in [(COLOR, &color), (DEPTH, &depth)] {
        let from = renderer.target(resource).expect("rendered");
        encoder.copy_texture_to_texture(
            from.texture.as_image_copy(),
            copy.texture.as_image_copy(),
            from.texture.size(),
        );
    }
    gpu.queue.submit([encoder.finish()]);
    let output = output_target(&gpu, extent);
    let mut reprojector = Reprojector::new(&gpu)?;
    let mut rows = Vec::new();
    renderer.set_scene_time(source_time + late_s);
    for &movement in movements {
        let target_eyes = settings.profile.eyes(&movement.apply(head), settings.near);
        renderer.render(&target_eyes.eyes, &outputs)?;
        let fresh = read_layers(&gpu, renderer.target(COLOR).expect("rendered"))?;
        let mut warped = |mode| -> Result<Vec<Vec<u8>>> {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            reprojector.record(
                &gpu,
                &mut encoder,
                mode,
                &color,
                &depth,
                &source_eyes.eyes,
                &target_eyes.eyes,
                settings.near,
                &output,
            );
            gpu.queue.submit([encoder.finish()]);
            gpu.take_error()?;
            Ok(read_layers(&gpu, &output)?)
        };
        let rotational = warped(ReprojectionMode::Rotational)?;
        let depth_based = warped(ReprojectionMode::Depth)?;
        rows.push(ReprojectionError {
            movement,
            stale_rmse: rmse(&stale, &fresh),
            rotational_rmse: rmse(&rotational, &fresh),
            depth_rmse: rmse(&depth_based, &fresh),
        });
    }
    renderer.set_scene_time(source_time);
    Ok(rows)
}

/// `vrao reprojection`: [`measure`] the [`default_movements`] from `scene`'s head pose
/// at time 0 on a new device, fresh frames one frame period later in a scene that moves;
/// also returns the adapter's name.
pub fn study(
    backend: vrao_render::BackendChoice,
    scene: &vrao_render::scene::Scene,
    settings: &vrao_render::settings::Settings,
) -> Result<(Vec<ReprojectionError>, String)> {
    settings.validate()?;
    let gpu = std::sync::Arc::new(vrao_render::open(backend)?);
    let mut renderer = Renderer::new(gpu.clone(), scene, settings)?;
    let late_s = if scene.is_animated() { 1.0 / settings.profile.refresh_hz } else { 0.0 };
    let rows = measure(&mut renderer, &scene.head.pose_at(0.0), &default_movements(), late_s)?;
    Ok((rows, gpu.info.name.clone()))
}

/// The benchmark's movements: rotations of 1–10° and translations of 1–10 cm.
pub fn default_movements() -> Vec<HeadMove> {
    let steps = [1.0, 2.0, 5.0, 10.0];
    steps.iter().map(|&d| HeadMove::RotateDegrees(d)).chain(steps.iter().map(|&c| HeadMove::TranslateCm(c))).collect()
}

/// The rows as a Markdown table, one movement a row.
pub fn to_markdown(rows: &[ReprojectionError]) -> String {
    let mut s = String::from("| movement | no warp RMSE | rotational RMSE | depth-based RMSE |\n|---|---|---|---|\n");
    for r in rows {
        s += &format!(
            "| {} | {:.4} | {:.4} | {:.4} |\n",
            r.movement.describe(),
            r.stale_rmse,
            r.rotational_rmse,
            r.depth_rmse
        );
    }
    s
}
