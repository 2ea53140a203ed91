//! Temporal accumulation in a scene that moves (`vrao temporal --motion`): every scored
//! frame of a motion sequence against the reference traced at that frame's time, for
//! temporal accumulation off, reprojecting by the eyes alone, and by the G-buffer's motion
//! vectors, next to the same scene frozen at that time (what the static-scene error is).

use crate::error::{Error, Result};
use crate::measure::bench::error_figures;
use crate::measure::reference::{trace_cached, world_position, ReferenceImage, ReferenceSettings};
use glam::DVec3;
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;
use vrao_ao::plug::{MoverBox, FINAL_AO};
use vrao_ao::Eye;
use vrao_render::renderer::Renderer;
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;

/// Near a moving object, an AO value further than this from what the same settings give
/// for the scene frozen at that time (converged), and from the reference, is a ghost:
/// occlusion left behind or smeared by the history, not the estimator's own error.
pub const GHOST_THRESHOLD: f32 = 0.1;

/// Frame rate of the sequence (a 90 Hz headset).
pub const SEQUENCE_HZ: f64 = 90.0;

/// Frames rendered before the first scored one, so the history is full.
pub const WARMUP_FRAMES: u32 = 16;

/// The most frames a sequence may score (each needs a traced reference).
pub const MAX_SCORED_FRAMES: u32 = 64;

/// One scored frame of one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct MotionPoint {
    /// `temporal off`, `temporal, eyes only`, `temporal, motion vectors`, or
    /// `frozen scene, temporal` (the static-scene figure at the same time).
    pub configuration: String,
    /// The frame's number in the sequence (0 = its first).
    pub frame: u32,
    /// The frame's scene time in seconds.
    pub time: f64,
    /// AO RMSE against the reference at that time (noise of the reference removed).
    pub ao_rmse: f64,
    /// Mean AO minus the reference's.
    pub ao_bias: f64,
    /// Share of the image's pixels near a moving object's recent path (within the AO
    /// radius of the box around it, anywhere over the temporal window) whose AO is off
    /// by more than [`GHOST_THRESHOLD`] from both the frozen scene's and the reference.
    pub ghost_share: f64,
    /// Share of the image's pixels near a moving object's recent path whose AO is off
    /// by more than [`GHOST_THRESHOLD`] from the reference (the estimator's error included).
    pub off_share: f64,
    /// Share of the image's pixels near a moving object's recent path.
    pub near_motion_share: f64,
}

/// What `vrao temporal --motion` measured.
#[derive(Clone, Debug, Serialize)]
pub struct MotionStudy {
    /// Every configuration's scored frames.
    pub points: Vec<MotionPoint>,
    /// The adapter that rendered them.
    pub adapter: String,
}

/// The sequence: `scored` frames scored every `every` frames after [`WARMUP_FRAMES`],
/// starting at scene time `start`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sequence {
    /// Scene time of the first frame (s).
    pub start: f64,
    /// Frames scored.
    pub scored: u32,
    /// Frames between scored ones.
    pub every: u32,
}

impl Sequence {
    fn frames(&self) -> u32 {
        WARMUP_FRAMES + self.scored * self.every
    }
    fn time_of(&self, frame: u32) -> f64 {
        self.start + frame as f64 / SEQUENCE_HZ
    }
    fn is_scored(&self, frame: u32) -> bool {
        frame >= WARMUP_FRAMES && (frame - WARMUP_FRAMES + 1).is_multiple_of(self.every)
    }
}

/// The configurations compared, from `base` (its technique, quality and radius).
pub fn configurations(base: &Settings) -> Vec<(String, Settings)> {
    let with = |enabled: bool, object_motion: bool| {
        let mut s = base.clone();
        s.ao.temporal.enabled = enabled;
        s.ao.temporal.object_motion = object_motion;
        s
    };
    vec![
        ("temporal off".into(), with(false, true)),
        ("temporal, eyes only".into(), with(true, false)),
        ("temporal, motion vectors".into(), with(true, true)),
    ]
}

/// Renders the frozen scene at each scored time, with temporal accumulation converged
/// over [`WARMUP_FRAMES`] frames (the static-scene figure), then the sequence of `scene`
/// (which must move) for each configuration, scoring the scored frames against
/// references traced at their times (cached in `cache`) and the frozen scene's AO.
pub fn motion_study(
    backend: vrao_render::BackendChoice,
    scene: &Scene,
    base: &Settings,
    sequence: Sequence,
    rays: u32,
    cache: &Path,
) -> Result<MotionStudy> {
    base.validate()?;
    if !scene.is_animated() {
        return Err(Error::input(format!("scene '{}' has no moving object: nothing to measure", scene.name)));
    }
    if sequence.scored == 0 || sequence.scored > MAX_SCORED_FRAMES || sequence.every == 0 || sequence.every > 90 {
        return Err(Error::input(format!(
            "a motion sequence scores 1..={MAX_SCORED_FRAMES} frames, every 1..=90 frames (asked: {} every {})",
            sequence.scored, sequence.every
        )));
    }
    let gpu = Arc::new(vrao_render::open(backend)?);
    let reference =
        ReferenceSettings { radius: base.ao.radius as f64, rays_per_pixel: rays, stride: 2, near: base.near };
    let size = (base.profile.width, base.profile.height);
    let eyes = base.profile.eyes(&scene.head.pose_at(0.0), base.near).eyes;
    let mut references: Vec<(u32, ReferenceImage)> = Vec::new();
    let mut reference_at = |frame: u32| -> Result<ReferenceImage> {
        if let Some((_, r)) = references.iter().find(|(f, _)| *f == frame) {
            return Ok(r.clone());
        }
        let frozen = scene.at_time(sequence.time_of(frame));
        let traced = trace_cached(cache, &frozen, &eyes, size, &reference, &mut |_| {})?;
        references.push((frame, traced.clone()));
        Ok(traced)
    };
    // The static-scene figure first: each scored frame of the scene frozen at its time,
    // converged over the temporal window; the ghosts are counted against it.
    let mut converged = base.clone();
    converged.ao.temporal.enabled = true;
    let mut points = Vec::new();
    let mut frozen_images = Vec::new();
    for frame in (0..sequence.frames()).filter(|&f| sequence.is_scored(f)) {
        let time = sequence.time_of(frame);
        let mut renderer = Renderer::new(gpu.clone(), &scene.at_time(time), &converged)?;
        for _ in 0..WARMUP_FRAMES {
            renderer.render_and_wait(&eyes, &[FINAL_AO])?;
        }
        let image = renderer.read_f32(FINAL_AO)?;
        let r = reference_at(frame)?;
        let frame_score = Frame { scene, settings: &converged, eyes: &eyes, reference: &r, frozen: None };
        points.push(frame_score.score("frozen scene, temporal", frame, time, &image));
        frozen_images.push((frame, image));
    }
    for (name, settings) in configurations(base) {
        log::info!("temporal --motion: {name}, {} frames", sequence.frames());
        let mut renderer = Renderer::new(gpu.clone(), scene, &settings)?;
        for frame in 0..sequence.frames() {
            let time = sequence.time_of(frame);
            renderer.set_scene_time(time);
            renderer.render_and_wait(&eyes, &[FINAL_AO])?;
            if sequence.is_scored(frame) {
                let image = renderer.read_f32(FINAL_AO)?;
                let r = reference_at(frame)?;
                let frozen = frozen_images.iter().find(|(f, _)| *f == frame).map(|(_, i)| &i[..]);
                let frame_score = Frame { scene, settings: &settings, eyes: &eyes, reference: &r, frozen };
                points.push(frame_score.score(&name, frame, time, &image));
            }
        }
    }
    Ok(MotionStudy { points, adapter: gpu.info.name.clone() })
}

/// What a scored frame is compared with.
struct Frame<'a> {
    scene: &'a Scene,
    settings: &'a Settings,
    eyes: &'a [Eye],
    reference: &'a ReferenceImage,
    /// The frozen scene's converged AO at this frame (none when scoring that itself).
    frozen: Option<&'a [Vec<f32>]>,
}

impl Frame<'_> {
    /// Error figures, and the ghosts near the moving objects' recent path (where each
    /// object was over the temporal window, grown by the AO radius).
    fn score(&self, configuration: &str, frame: u32, time: f64, image: &[Vec<f32>]) -> MotionPoint {
        let (settings, reference) = (self.settings, self.reference);
        let e = error_figures(settings.ao.technique, image, reference);
        let window = settings.ao.temporal.max_frames.max(1);
        let path: Vec<MoverBox> =
            (0..window).flat_map(|k| moving_boxes(self.scene, time - k as f64 / SEQUENCE_HZ)).collect();
        let reach = settings.ao.radius;
        let (gw, gh) = reference.grid_size();
        let (mut cells, mut near, mut off, mut ghosts) = (0usize, 0usize, 0usize, 0usize);
        for (layer, eye) in self.eyes.iter().enumerate().take(image.len()) {
            for j in 0..gh {
                for i in 0..gw {
                    cells += 1;
                    let Some(world) = world_position(reference, eye, layer, i, j) else { continue };
                    if !path.iter().any(|b| box_distance(b, world) <= reach) {
                        continue;
                    }
                    near += 1;
                    let (x, y) = reference.pixel_of(i, j);
                    let index = 4 * (y * reference.width + x) as usize + 3;
                    let ao = image[layer][index];
                    if (ao - reference.get(layer, i, j).ao).abs() > GHOST_THRESHOLD {
                        off += 1;
                        if self.frozen.is_some_and(|f| (ao - f[layer][index]).abs() > GHOST_THRESHOLD) {
                            ghosts += 1;
                        }
                    }
                }
            }
        }
        let share = |n: usize| n as f64 / cells.max(1) as f64;
        MotionPoint {
            configuration: configuration.into(),
            frame,
            time,
            ao_rmse: e.ao_rmse,
            ao_bias: e.ao_bias,
            ghost_share: share(ghosts),
            off_share: share(off),
            near_motion_share: share(near),
        }
    }
}

/// Boxes around each moving mesh at time `t` (in world space: anchored at the origin).
fn moving_boxes(scene: &Scene, t: f64) -> Vec<MoverBox> {
    let transforms = scene.node_transforms(t);
    scene
        .meshes
        .iter()
        .filter_map(|m| {
            let world = transforms.get(m.node?)?;
            let mut local = vrao_render::scene::Aabb::EMPTY;
            m.positions.iter().for_each(|p| local.extend(m.origin + p.as_dvec3()));
            (!local.is_empty()).then(|| MoverBox::of((local.min, local.max), world, DVec3::ZERO))
        })
        .collect()
}

/// How far world point `p` lies outside box `b` (0 inside).
fn box_distance(b: &MoverBox, p: DVec3) -> f32 {
    let p = p.as_vec3().extend(1.0);
    let outside = |i: usize| {
        let local = glam::Vec4::from(b.box_from_anchored[i]).dot(p);
        (local.abs() - b.half_extents[i]).max(0.0)
    };
    glam::Vec3::new(outside(0), outside(1), outside(2)).length()
}

/// A Markdown table: per configuration, the worst and mean ghost share, the mean RMSE and
/// bias over the scored frames, and the mean RMSE's ratio to the frozen scene's. A figure
/// that is not a finite number is "-": a mean over frames without a surface, or the ratio
/// where the frozen scene's error is 0 (within the reference's noise at few rays), with a
/// line under the table saying why.
pub fn to_markdown(points: &[MotionPoint]) -> String {
    let frozen: Vec<&MotionPoint> = points.iter().filter(|p| p.configuration.starts_with("frozen")).collect();
    let mut s = String::from(
        "| configuration | ghosts, worst frame | ghosts, mean | off the reference near motion, mean | near-motion share | AO RMSE, mean | RMSE / frozen scene's, means | bias, mean |\n|---|---|---|---|---|---|---|---|\n",
    );
    let mut names: Vec<&str> = Vec::new();
    for p in points {
        if !names.contains(&p.configuration.as_str()) {
            names.push(&p.configuration);
        }
    }
    // The ratio of the means: a frame's own ratio swings where both errors are small.
    let frozen_mean = frozen.iter().map(|f| f.ao_rmse).sum::<f64>() / frozen.len().max(1) as f64;
    let mut no_ratio = false;
    for name in names {
        let rows: Vec<&MotionPoint> = points.iter().filter(|p| p.configuration == name).collect();
        let n = rows.len().max(1) as f64;
        let worst_ghosts = rows.iter().map(|r| r.ghost_share).fold(0.0, f64::max);
        let mean = |f: fn(&MotionPoint) -> f64| rows.iter().map(|r| f(r)).sum::<f64>() / n;
        // A zero frozen error has no ratio (x / 0 is inf, 0 / 0 NaN).
        let ratio = if frozen_mean > 0.0 { mean(|r| r.ao_rmse) / frozen_mean } else { f64::NAN };
        no_ratio |= !ratio.is_finite();
        s += &format!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} |\n",
            shown(100.0 * worst_ghosts, |x| format!("{x:.3} %")),
            shown(100.0 * mean(|r| r.ghost_share), |x| format!("{x:.3} %")),
            shown(100.0 * mean(|r| r.off_share), |x| format!("{x:.2} %")),
            shown(100.0 * mean(|r| r.near_motion_share), |x| format!("{x:.2} %")),
            shown(mean(|r| r.ao_rmse), |x| format!("{x:.4}")),
            shown(ratio, |x| format!("{x:.3}")),
            shown(mean(|r| r.ao_bias), |x| format!("{x:+.4}")),
        );
    }
    if no_ratio {
        s += "\n\"-\": no figure (no ratio where the frozen scene's error is 0, within the reference's noise: more --rays give one).\n";
    }
    s
}

/// `x` written by `write`, or "-" when it is not a finite number.
fn shown(x: f64, write: impl Fn(f64) -> String) -> String {
    if x.is_finite() {
        write(x)
    } else {
        "-".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(configuration: &str, ao_rmse: f64, ao_bias: f64) -> MotionPoint {
        MotionPoint {
            configuration: configuration.into(),
            frame: 16,
            time: 0.2,
            ao_rmse,
            ao_bias,
            ghost_share: 0.01,
            off_share: 0.02,
            near_motion_share: 0.1,
        }
    }

    #[test]
    fn the_table_never_prints_nan_or_inf() {
        // At one ray a pixel the frozen scene's error is within the reference's noise (0
        // once the noise is taken out), and a frame without a surface has no error.
        let points = [
            point("frozen scene, temporal", 0.0, 0.01),
            point("temporal off", 0.05, 0.02),
            point("temporal, motion vectors", f64::NAN, f64::NAN),
        ];
        let table = to_markdown(&points);
        let lower = table.to_lowercase();
        assert!(!lower.contains("nan") && !lower.contains("inf"), "{table}");
        assert!(
            table.contains("| temporal off | 1.000 % | 1.000 % | 2.00 % | 10.00 % | 0.0500 | - | +0.0200 |"),
            "{table}"
        );
        assert!(
            table.contains("| temporal, motion vectors | 1.000 % | 1.000 % | 2.00 % | 10.00 % | - | - | - |"),
            "{table}"
        );
        assert!(table.contains("more --rays"), "{table}");
        // With a frozen error the ratio is there, and no note.
        let points = [point("frozen scene, temporal", 0.02, 0.0), point("temporal off", 0.05, 0.0)];
        let table = to_markdown(&points);
        assert!(table.contains("| 0.0500 | 2.500 |") && !table.contains("more --rays"), "{table}");
    }
}
