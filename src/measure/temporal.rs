//! How temporal accumulation converges: AO error against the reference after 1, 2, 4, 8
//! and 16 frames, with a static head and with the head moving, next to the same
//! per-frame settings without temporal reuse.

pub mod flicker;
pub mod motion;

use crate::error::{Error, Result};
use crate::measure::bench::error_figures;
use crate::measure::reference::{trace_cached, ReferenceImage, ReferenceSettings};
use crate::stats;
use crate::xr::simulated::motion::HeadMotion;
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;
use vrao_ao::plug::{FrameTiming, Gpu, FINAL_AO};
use vrao_render::renderer::Renderer;
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;

/// The error after `frame` frames of one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct ConvergencePoint {
    /// What was varied, e.g. `temporal N=8, blur`.
    pub configuration: String,
    /// The head motion's name (`static`, `yaw-sweep`).
    pub motion: String,
    /// Frames rendered so far (1 = the first frame).
    pub frame: u32,
    /// AO RMSE against the traced reference.
    pub ao_rmse: f64,
    /// RMSE against the same technique's converged value at this pose (256 samples, no
    /// blur, no reuse): the noise left, without the estimator's bias.
    pub noise_rmse: f64,
    /// Median ms per eye of the occlusion passes (technique, temporal, blur) per frame.
    pub occlusion_ms_per_eye: f64,
}

/// Frames at which the error is recorded.
pub const CHECKPOINTS: [u32; 5] = [1, 2, 4, 8, 16];

/// Renders `16` frames of each configuration along `motion` (90 Hz frame times) and
/// records the AO RMSE against the reference at each checkpoint. With motion, the
/// reference is traced for every checkpoint's pose.
pub fn convergence(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    configurations: &[(String, Settings)],
    motion: HeadMotion,
    reference: &ReferenceSettings,
    cache: &Path,
) -> Result<Vec<ConvergencePoint>> {
    let mut points = Vec::new();
    let dt = 1.0 / 90.0;
    let mut references: Vec<(u32, ReferenceImage)> = Vec::new();
    for (name, settings) in configurations {
        let mut converged_settings = settings.clone();
        converged_settings.ao.samples = 256;
        converged_settings.ao.blur_radius = 0;
        converged_settings.ao.temporal.enabled = false;
        let mut converged = Renderer::new(gpu.clone(), scene, &converged_settings)?;
        let mut renderer = Renderer::new(gpu.clone(), scene, settings)?;
        renderer.set_timing(vrao_render::renderer::Timing::Serial);
        let mut times = Vec::new();
        for frame in 1..=*CHECKPOINTS.last().unwrap() {
            let head = motion.pose_at(&scene.head, frame as f64 * dt);
            let eyes = settings.profile.eyes(&head, settings.near);
            let report = renderer.render_and_wait(&eyes.eyes, &[FINAL_AO])?;
            let ms = FrameTiming::passes_ms(&report.wall_ms, &report.plan.occlusion_passes())
                .map_err(|pass| Error::gpu(format!("pass '{pass}' ran but no time was measured under its name")))?;
            times.push(ms / eyes.eyes.len() as f64);
            if !CHECKPOINTS.contains(&frame) {
                continue;
            }
            let key = if motion == HeadMotion::Static { 1 } else { frame };
            if !references.iter().any(|(k, _)| *k == key) {
                let size = (settings.profile.width, settings.profile.height);
                references.push((key, trace_cached(cache, scene, &eyes.eyes, size, reference, &mut |_| {})?));
            }
            let reference = &references.iter().find(|(k, _)| *k == key).expect("traced above").1;
            let image = renderer.read_f32(FINAL_AO)?;
            let e = error_figures(settings.ao.technique, &image, reference);
            converged.render(&eyes.eyes, &[FINAL_AO])?;
            let target = converged.read_f32(FINAL_AO)?;
            let ao = |layers: &[Vec<f32>]| {
                layers.iter().flat_map(|l| l.iter().skip(3).step_by(4).copied()).collect::<Vec<f32>>()
            };
            let noise_rmse = crate::measure::metrics::rmse(&ao(&image), &ao(&target), None).unwrap_or(f64::NAN);
            points.push(ConvergencePoint {
                configuration: name.clone(),
                motion: motion.name().to_string(),
                frame,
                ao_rmse: e.ao_rmse,
                noise_rmse,
                occlusion_ms_per_eye: stats::median(&times).expect("a frame was timed before each checkpoint"),
            });
        }
    }
    Ok(points)
}

/// The configurations `vrao temporal` compares, named: spatial-only settings (with and
/// without blur, and with 4× the samples) next to temporal accumulation (averaged, with
/// and without blur, and blended by confidence), all at `base`'s sample count N.
pub fn configurations(base: &Settings) -> Vec<(String, Settings)> {
    use vrao_ao::TemporalBlend;
    let n = base.ao.samples;
    let blur = base.ao.blur_radius;
    let with = |temporal: bool, blend: TemporalBlend, samples: u32, blur: u32| {
        let mut s = base.clone();
        s.ao.samples = samples;
        s.ao.blur_radius = blur;
        s.ao.temporal.enabled = temporal;
        s.ao.temporal.blend = blend;
        s
    };
    vec![
        (format!("spatial N={n}, blur"), with(false, TemporalBlend::Average, n, blur)),
        (format!("spatial N={n}, no blur"), with(false, TemporalBlend::Average, n, 0)),
        (format!("spatial N={}, blur (4× the samples)", 4 * n), with(false, TemporalBlend::Average, 4 * n, blur)),
        (format!("temporal N={n}, no blur"), with(true, TemporalBlend::Average, n, 0)),
        (format!("temporal N={n}, blur"), with(true, TemporalBlend::Average, n, blur)),
        (format!("temporal N={n}, confidence blend, no blur"), with(true, TemporalBlend::Confidence, n, 0)),
    ]
}

/// The points of a temporal study and the adapter that measured them.
#[derive(Clone, Debug)]
pub struct TemporalStudy {
    /// Every configuration's points, frame by frame.
    pub points: Vec<ConvergencePoint>,
    /// The adapter that measured them.
    pub adapter: String,
}

/// `vrao temporal`: [`convergence`] of every one of [`configurations`]`(base)` with a
/// static head and with a yaw sweep, against a reference of `rays` rays per pixel at
/// every 2nd pixel (cached in `cache`).
pub fn study(
    backend: vrao_render::BackendChoice,
    scene: &Scene,
    base: &Settings,
    rays: u32,
    cache: &Path,
) -> Result<TemporalStudy> {
    base.validate()?;
    let configurations = configurations(base);
    for (_, s) in &configurations {
        s.validate()?;
    }
    let gpu = Arc::new(vrao_render::open(backend)?);
    let reference =
        ReferenceSettings { radius: base.ao.radius as f64, rays_per_pixel: rays, stride: 2, near: base.near };
    let mut points = Vec::new();
    for motion in [HeadMotion::Static, HeadMotion::YawSweep] {
        log::info!("temporal: {} ({} configurations × 16 frames)", motion.name(), configurations.len());
        points.extend(convergence(&gpu, scene, &configurations, motion, &reference, cache)?);
    }
    Ok(TemporalStudy { points, adapter: gpu.info.name.clone() })
}

/// A Markdown table: one row per configuration, one column per checkpoint, each cell
/// "error against the reference / noise against the converged estimator".
pub fn to_markdown(points: &[ConvergencePoint]) -> String {
    let mut s = String::from("| configuration | motion | ms/eye |");
    for c in CHECKPOINTS {
        s += &format!(" {c} frame{} |", if c == 1 { "" } else { "s" });
    }
    s += &format!("\n|---|---|---|{}\n", "---|".repeat(CHECKPOINTS.len()));
    let mut seen: Vec<(String, String)> = Vec::new();
    for p in points {
        let key = (p.configuration.clone(), p.motion.clone());
        if seen.contains(&key) {
            continue;
        }
        seen.push(key.clone());
        let rows: Vec<&ConvergencePoint> =
            points.iter().filter(|q| q.configuration == key.0 && q.motion == key.1).collect();
        let ms = rows.last().map_or(0.0, |r| r.occlusion_ms_per_eye);
        s += &format!("| {} | {} | {ms:.1} |", key.0, key.1);
        for r in rows {
            s += &format!(" {:.4} / {:.4} |", r.ao_rmse, r.noise_rmse);
        }
        s += "\n";
    }
    s
}
