//! Sweeps of technique × samples × radius × resolution: the median GPU time of every
//! pass per eye over many frames, as a table, CSV and Markdown. (Error against the
//! reference tracer joins these rows when the tracer exists.)

use crate::measure::analytic::luminance;
use crate::measure::metrics;
use crate::measure::plot::{Point, ScatterPlot, Series};
use crate::measure::reference::screen_limit::{screen_space_limit, EyeBuffers, LimitSettings, ScreenLimit};
use crate::measure::reference::{ReferenceImage, ReferencePixel};
use crate::measure::stereo_consistency::{stereo_consistency, EyeImages, StereoConsistency, BORDER_PX};
pub use crate::render::bench_file::{significant, BenchFile, BenchRecord, LimitInfo, ReferenceInfo};
use crate::render::error::{Error, Result};
use crate::render::gpu::timing::{is_per_eye, summarize, SpanSummary};
use crate::render::gpu::Gpu;
use crate::render::passes::final_occlusion;
use crate::render::renderer::{Renderer, Timing};
use crate::render::scene::Scene;
use crate::render::settings::{Settings, Technique};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::sync::Arc;

/// One configuration of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchCase {
    pub technique: Technique,
    pub samples: u32,
    pub radius: f32,
    pub half_res: bool,
    /// SSDO with depth peeling (a second depth layer; its pass counts as occlusion cost).
    pub depth_peeling: bool,
    /// Temporal accumulation (its pass counts as occlusion cost; the error is taken
    /// after the warm-up and measured frames, with a static head: converged).
    pub temporal: bool,
}

/// How each case is run: frames (after warm-up) and the timing mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    pub timing: Timing,
    pub warmup: u32,
    pub frames: u32,
    /// Render whole frames (direct light and composite too), not only the occlusion:
    /// rows then time the composite, which upsamples half-resolution occlusion inline.
    pub whole_frame: bool,
    /// Cases measured at a time, round-robin one frame each (1: each case on its own).
    pub interleave: usize,
}

/// One measured row: the case and per-pass medians over the measured frames.
#[derive(Clone, Debug)]
pub struct BenchRow {
    pub case: BenchCase,
    pub spans: Vec<SpanSummary>,
    /// Views the occlusion passes covered in one dispatch (per-eye = total / views).
    pub views: u32,
    /// The pass that ran the technique.
    pub pass: &'static str,
    /// Error against the reference, when one was traced for this row's radius.
    pub error: Option<ErrorFigures>,
    /// Error of the one-bounce irradiance against the reference's `bounce` (ssdo-bounce
    /// and rsm rows, with a reference).
    pub bounce: Option<BounceFigures>,
    /// How far the eyes' final AO disagree on the points both see (occlusion rows; no
    /// reference needed).
    pub stereo: Option<StereoConsistency>,
}

impl BenchRow {
    /// Median ms of one pass for both eyes together (0 when it did not run).
    pub fn median_ms(&self, span: &str) -> f64 {
        self.spans.iter().find(|s| s.label == span).map_or(0.0, |s| s.median_ms)
    }

    /// Occlusion cost per eye: technique (+ depth peel) + blur + upsample, both-eye
    /// dispatches halved.
    /// Reflective shadow maps (pass `rsm`): the gather plus the light-space pass that
    /// renders the maps.
    pub fn occlusion_ms_per_eye(&self) -> f64 {
        self.occlusion_passes().iter().map(|p| self.median_ms(p)).sum::<f64>() / self.views as f64
    }

    fn occlusion_passes(&self) -> Vec<&str> {
        if self.pass == RSM_PASS {
            vec![RSM_PASS, "shadow"]
        } else {
            vec![self.pass, "depth-peel", "temporal", "blur", "upsample"]
        }
    }

    /// Per eye, the passes of the measured frames besides the occlusion (per-eye spans
    /// lie inside their pass's and are not added): what the occlusion shares the frame
    /// budget with, for the plot's budget line.
    pub fn other_ms_per_eye(&self) -> f64 {
        let occlusion = self.occlusion_passes();
        let other = self.spans.iter().filter(|s| !is_per_eye(&s.label) && !occlusion.contains(&s.label.as_str()));
        other.map(|s| s.median_ms).sum::<f64>() / self.views as f64
    }
}

/// Renders `warmup + frames` frames of `case` producing only the occlusion (the AO
/// alone, as a budget test asks), and returns the per-pass medians; with a reference
/// for the case's radius, also the last frame's error against it.
pub fn measure(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    case: &BenchCase,
    how: Measurement,
    reference: Option<&ReferenceImage>,
) -> Result<BenchRow> {
    let mut run = CaseRun::new(gpu, scene, base, case, how)?;
    for _ in 0..how.warmup {
        run.frame()?;
    }
    for _ in 0..how.frames {
        run.timed_frame()?;
    }
    let limit = match reference {
        Some(reference) => Some(run.screen_limit(reference)?),
        None => None,
    };
    run.finish(reference, limit.as_ref())
}

/// One case being measured: its renderer, and the per-pass times of its frames so far.
/// Kept apart from the loop so that a sweep can interleave cases frame by frame.
struct CaseRun {
    case: BenchCase,
    settings: Settings,
    output: crate::render::graph::Resource,
    /// What each frame renders: the occlusion, and with `whole_frame` the lit image.
    outputs: Vec<crate::render::graph::Resource>,
    renderer: Renderer,
    eyes: crate::render::stereo::EyePair,
    timing: Timing,
    timings: Vec<Vec<(String, f64)>>,
}

impl CaseRun {
    fn new(gpu: &Arc<Gpu>, scene: &Scene, base: &Settings, case: &BenchCase, how: Measurement) -> Result<CaseRun> {
        let timing = how.timing;
        let mut settings = base.clone();
        settings.ao.technique = case.technique;
        settings.ao.samples = case.samples;
        settings.ao.radius = case.radius;
        settings.ao.half_res = case.half_res;
        settings.ao.depth_peeling = case.depth_peeling;
        settings.ao.temporal.enabled = case.temporal;
        let output = final_occlusion(&settings).ok_or_else(|| Error::input("bench needs an occlusion technique"))?;
        if timing == Timing::Pipelined && !gpu.caps.timestamps {
            return Err(Error::Device(format!(
                "{} has no timestamp queries; use serial timing",
                gpu.adapter.get_info().name
            )));
        }
        let mut renderer = Renderer::new(gpu.clone(), scene, &settings)?;
        renderer.set_timing(timing);
        let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
        let mut outputs = vec![output];
        if how.whole_frame {
            outputs.push(crate::render::graph::Resource::Hdr);
        }
        Ok(CaseRun { case: case.clone(), settings, output, outputs, renderer, eyes, timing, timings: Vec::new() })
    }

    /// One frame, not measured (warm-up).
    fn frame(&mut self) -> Result<crate::render::renderer::FrameReport> {
        self.renderer.render_and_wait(&self.eyes.eyes, &self.outputs)
    }

    /// One measured frame: serial timing keeps each pass's wall-clock time; pipelined,
    /// its timestamps.
    fn timed_frame(&mut self) -> Result<()> {
        let report = self.frame()?;
        self.timings.push(if self.timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        Ok(())
    }

    /// The screen-space limit of the last frame for the radius and grid of `reference`
    /// (the march over its depth buffer and normals, [`screen_space_limit`]).
    fn screen_limit(&self, reference: &ReferenceImage) -> Result<ScreenLimit> {
        let depth = self.renderer.read_f32(crate::render::graph::Resource::Depth)?;
        let normals = self.renderer.read_f32(crate::render::graph::Resource::Normals)?;
        let buffers: Vec<EyeBuffers> = (0..depth.len().min(normals.len()))
            .map(|k| EyeBuffers { depth: &depth[k], normals: &normals[k], fov: self.eyes.eyes[k].fov })
            .collect();
        let settings = LimitSettings::for_reference(reference, self.case.radius as f64, self.eyes.near);
        screen_space_limit(&buffers, (reference.width, reference.height), &settings)
    }

    /// Pixels per degree of this case's eyes (the mean of both).
    fn pixels_per_degree(&self) -> f64 {
        let width = self.settings.profile.width;
        self.eyes.eyes.iter().map(|e| pixels_per_degree(&e.fov, width)).sum::<f64>() / self.eyes.eyes.len() as f64
    }

    /// The row: medians of the measured frames, the last frame's stereo consistency, and
    /// with a reference its error (against the screen-space `limit` too when given).
    fn finish(mut self, reference: Option<&ReferenceImage>, limit: Option<&ScreenLimit>) -> Result<BenchRow> {
        let (settings, output) = (&self.settings, self.output);
        let occlusion = self.renderer.read_f32(output)?;
        let error = reference
            .map(|reference| score(self.case.technique, &occlusion, reference, limit, self.pixels_per_degree()));
        let stereo = {
            let depth = self.renderer.read_f32(crate::render::graph::Resource::Depth)?;
            let ao: Vec<Vec<f32>> = occlusion.iter().map(|l| l.iter().skip(3).step_by(4).copied().collect()).collect();
            let size = (settings.profile.width, settings.profile.height);
            (depth.len() == 2 && ao.len() == 2).then(|| {
                stereo_consistency(
                    &self.eyes.eyes,
                    [EyeImages { depth: &depth[0], ao: &ao[0] }, EyeImages { depth: &depth[1], ao: &ao[1] }],
                    size,
                    self.eyes.near,
                )
            })
        };
        // SSDO's bounce alone: the same frame without the bounce (same pattern, and the
        // blur is linear with geometry-only weights), subtracted.
        let bounce = match reference {
            Some(reference) if settings.ao.bounce_active() => {
                let with = self.renderer.read_f32(output)?;
                let mut without = settings.clone();
                without.ao.technique = Technique::Ssdo;
                self.renderer.set_settings(&without)?;
                self.renderer.render(&self.eyes.eyes, &[output])?;
                let difference: Vec<Vec<f32>> = with
                    .iter()
                    .zip(self.renderer.read_f32(output)?)
                    .map(|(a, b)| a.iter().zip(b).map(|(a, b)| a - b).collect())
                    .collect();
                bounce_figures(&difference, settings.profile.width, 1, reference)
            }
            _ => None,
        };
        Ok(BenchRow {
            spans: summarize(&self.timings),
            views: 2,
            pass: settings.ao.pass_name(),
            error,
            bounce,
            stereo,
            case: self.case,
        })
    }
}

/// The graph pass of reflective shadow maps' gather (bench rows of technique "rsm").
pub const RSM_PASS: &str = "rsm";

/// Reflective shadow maps with `samples` VPLs per pixel within `radius` (the reference's
/// radius, so both gather the bounce from about the same neighbourhood): per-pass medians
/// of the light-space pass and the gather, and with a reference the error of the last
/// frame's half-resolution irradiance against the reference's bounce.
pub fn measure_rsm(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    samples: u32,
    radius: f32,
    how: Measurement,
    reference: Option<&ReferenceImage>,
) -> Result<BenchRow> {
    let Measurement { timing, warmup, frames, .. } = how;
    if crate::render::passes::shadow::shadow_casters(scene).is_empty() {
        return Err(Error::input(format!(
            "reflective shadow maps need a directional light; '{}' has none",
            scene.name
        )));
    }
    let mut settings = base.clone();
    settings.shadows.rsm = true;
    settings.shadows.rsm_samples = samples;
    settings.shadows.rsm_radius = radius;
    settings.validate()?;
    let mut renderer = Renderer::new(gpu.clone(), scene, &settings)?;
    renderer.set_timing(timing);
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let mut timings = Vec::new();
    for frame in 0..warmup + frames {
        let report = renderer.render_and_wait(&eyes.eyes, &[crate::render::graph::Resource::RsmIndirect])?;
        if frame >= warmup {
            timings.push(if timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        }
    }
    let bounce = match reference {
        Some(reference) => {
            let irradiance = renderer.read_f32(crate::render::graph::Resource::RsmIndirect)?;
            bounce_figures(&irradiance, settings.profile.width.div_ceil(2), 2, reference)
        }
        None => None,
    };
    let case = BenchCase {
        technique: Technique::None,
        samples,
        radius,
        half_res: true,
        depth_peeling: false,
        temporal: false,
    };
    Ok(BenchRow { case, spans: summarize(&timings), views: 2, pass: RSM_PASS, error: None, bounce, stereo: None })
}

/// A one-bounce irradiance estimate against the reference's `bounce`, by luminance over
/// the reference's hit pixels (both eyes), relative to the reference's mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BounceFigures {
    /// RMSE / mean of the reference.
    pub rel_rmse: f64,
    /// (mean of the estimate − mean of the reference) / mean of the reference.
    pub rel_bias: f64,
}

/// Compares irradiance images (per layer, RGBA, `width` texels a row, each texel standing
/// for `scale`×`scale` full-resolution pixels) with the reference's bounce. `None` when
/// the reference sees no bounce at all.
pub fn bounce_figures(
    estimate: &[Vec<f32>],
    width: u32,
    scale: u32,
    reference: &ReferenceImage,
) -> Option<BounceFigures> {
    let (gw, gh) = reference.grid_size();
    let (mut n, mut sum_ref, mut sum_est, mut sum_sq) = (0usize, 0f64, 0f64, 0f64);
    for (layer, image) in estimate.iter().enumerate().take(reference.layers.len()) {
        let height = image.len() / 4 / width.max(1) as usize;
        for j in 0..gh {
            for i in 0..gw {
                let r = reference.get(layer, i, j);
                if !r.hit {
                    continue;
                }
                let (x, y) = reference.pixel_of(i, j);
                let (x, y) = (((x / scale) as usize).min(width as usize - 1), ((y / scale) as usize).min(height - 1));
                let t = &image[(y * width as usize + x) * 4..][..3];
                let (e, truth) = (luminance([t[0], t[1], t[2]]), luminance(r.bounce));
                n += 1;
                sum_ref += truth;
                sum_est += e;
                sum_sq += (e - truth) * (e - truth);
            }
        }
    }
    let mean = sum_ref / n.max(1) as f64;
    (n > 0 && mean > 1e-9).then(|| BounceFigures {
        rel_rmse: (sum_sq / n as f64).sqrt() / mean,
        rel_bias: (sum_est - sum_ref) / n as f64 / mean,
    })
}

/// A rough estimate, in seconds, of what measuring `cases` will take: the first case's
/// set-up (renderer, pipelines, first frame) and one more frame are timed, and every case
/// is assumed to cost that set-up plus its warm-up and measured frames at that frame
/// time. Other techniques, sample counts and resolutions cost more or less; the
/// reference and the screen-space limit are not included. Returns (estimate, seconds a
/// frame of the first case).
pub fn estimate_seconds(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    cases: &[BenchCase],
    how: Measurement,
) -> Result<(f64, f64)> {
    let Some(first) = cases.first() else {
        return Ok((0.0, 0.0));
    };
    let start = std::time::Instant::now();
    let mut run = CaseRun::new(gpu, scene, base, first, how)?;
    run.frame()?;
    let setup = start.elapsed().as_secs_f64();
    let start = std::time::Instant::now();
    run.frame()?;
    let frame = start.elapsed().as_secs_f64();
    let frames = (how.warmup + how.frames) as f64;
    Ok((cases.len() as f64 * (setup + frames.max(1.0) * frame), frame))
}

/// Runs every case, calling `progress(done, total, row)` after each. `references` holds
/// a reference image per radius (cases whose radius has none get no error figures); the
/// screen-space limit of each such radius is marched once, from the frame of its first
/// case, and scores every row of that radius.
/// `how.interleave` cases at a time are measured round-robin, one frame each per round, so
/// that a slow drift of the machine (other load, clocks, heat) falls on all of them alike
/// and their ratios stay fair; 1 measures each case on its own, in a row.
pub fn sweep(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    cases: &[BenchCase],
    how: Measurement,
    references: &[(f32, ReferenceImage)],
    mut progress: impl FnMut(usize, usize, &BenchRow),
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::with_capacity(cases.len());
    let mut limits: Vec<(f32, ScreenLimit)> = Vec::new();
    for group in cases.chunks(how.interleave.max(1)) {
        let mut runs = Vec::with_capacity(group.len());
        for case in group {
            let mut run = CaseRun::new(gpu, scene, base, case, how)?;
            for _ in 0..how.warmup {
                run.frame()?;
            }
            runs.push(run);
        }
        for _ in 0..how.frames {
            for run in &mut runs {
                run.timed_frame()?;
            }
        }
        for run in runs {
            let reference = references.iter().find(|(r, _)| *r == run.case.radius).map(|(_, image)| image);
            // The limit depends only on the frame's depth and normals (the same G-buffer
            // for every case) and the radius: marched once per radius, for its first row.
            if let Some(reference) = reference {
                if !limits.iter().any(|(r, _)| *r == run.case.radius) {
                    limits.push((run.case.radius, run.screen_limit(reference)?));
                }
            }
            let limit = limits.iter().find(|(r, _)| *r == run.case.radius).map(|(_, l)| l);
            let row = run.finish(reference, limit)?;
            progress(rows.len() + 1, cases.len(), &row);
            rows.push(row);
        }
    }
    Ok(rows)
}

/// How far one row's occlusion is from the reference tracer's, on the pixels the
/// reference traced (both eyes; sky excluded). Every technique is scored against the same
/// target: the reference's `ao`, cosine-weighted visibility within r with a hard cut-off.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorFigures {
    /// RMSE of the AO (`.a`) against the reference's hard cut-off AO, with the reference's
    /// own noise taken out in quadrature.
    pub ao_rmse: f64,
    /// Mean of (estimate − reference): > 0 is too light, < 0 too dark.
    pub ao_bias: f64,
    /// The same over the pixels where the reference is below [`DARK_REFERENCE`]: how well
    /// the occluded places (creases, contacts) come out. `None` when there are none.
    pub ao_bias_dark: Option<f64>,
    /// RMSE against the reference's linear-falloff AO (each occluded direction weighted by
    /// 1 − d/r), noise taken out as for `ao_rmse`: a second figure, for every technique.
    pub ao_rmse_falloff: f64,
    /// Mean SSIM of the AO images against the reference (1 = identical), per eye averaged.
    pub ao_ssim: f64,
    /// RMSE of the ambient light's luminance (what the composite multiplies by albedo/π)
    /// relative to the reference's mean: environment light that gets through within r
    /// plus one bounce of direct light from surfaces within r. Comparable across
    /// techniques; `None` when the reference has no ambient light at all.
    pub ambient_rel_rmse: Option<f64>,
    /// Mean ꟻLIP of the AO against the reference AO ([`metrics::flip_mean`]) on the
    /// reference's grid, at the headset's pixels per degree over the grid's spacing.
    pub flip_mean: Option<f64>,
    /// RMSE against the screen-space limit (the march over this frame's depth buffer):
    /// the estimator's own error (the limit's small noise, ~0.01 at 64 stratified rays,
    /// left in).
    pub ao_rmse_vs_limit: Option<f64>,
    /// The screen-space limit's RMSE against the reference (the reference's noise taken
    /// out, as for `ao_rmse`): the error no depth-buffer method can remove. The same for
    /// every row of a radius.
    pub limit_rmse: Option<f64>,
    /// The screen-space limit's mean bias against the reference.
    pub limit_bias: Option<f64>,
    /// RMSE (noise not taken out) over the pixels within [`BORDER_PX`] of an eye's outer,
    /// top or bottom border, where samples that leave the image count as open: with
    /// `ao_rmse`, what a guard band could win. `None` when no such pixel is covered.
    pub ao_rmse_outer_border: Option<f64>,
    /// Halos: the share (0..1) of the pixels beside a depth edge ([`near_depth_edge`])
    /// that are too dark by more than [`HALO_DARKER`]. `None` when there is no edge.
    pub halo_share: Option<f64>,
}

/// How much darker than the reference a pixel beside a depth edge must be to count as
/// part of a halo.
pub const HALO_DARKER: f32 = 0.1;

/// Whether grid cell (i, j) of an eye's reference lies beside a depth edge: a neighbour
/// within one cell sees the sky, or the depth along a row or column is not locally
/// linear (second difference above 10 % of the depth; a sloped floor is linear in the
/// pixel coordinate only to first order, far below that).
fn near_depth_edge(pixels: &[ReferencePixel], (gw, gh): (usize, usize), i: usize, j: usize) -> bool {
    let depth = |x: usize, y: usize| pixels[y * gw + x].hit.then_some(pixels[y * gw + x].depth as f64);
    let Some(d) = depth(i, j) else { return false };
    let bent = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (a + b - 2.0 * d).abs() > 0.1 * d,
        _ => true,
    };
    let (left, right) = (i.checked_sub(1), (i + 1 < gw).then_some(i + 1));
    let (up, down) = (j.checked_sub(1), (j + 1 < gh).then_some(j + 1));
    let horizontal = left.is_some() && right.is_some() && bent(depth(left.unwrap(), j), depth(right.unwrap(), j));
    let vertical = up.is_some() && down.is_some() && bent(depth(i, up.unwrap()), depth(i, down.unwrap()));
    horizontal || vertical
}

/// Reference AO below which a pixel counts as occluded for [`ErrorFigures::ao_bias_dark`].
pub const DARK_REFERENCE: f32 = 0.8;

/// Pixels per degree of an eye `width` pixels across its horizontal field of view (the
/// mean over the field: a Vive-class 1080-pixel eye over ~97.5° has ~11.1).
pub fn pixels_per_degree(fov: &crate::render::stereo::Fov, width: u32) -> f64 {
    width as f64 / (fov.right as f64 - fov.left as f64).to_degrees()
}

/// Compares the occlusion a frame produced (per layer, RGBA at the full image size) with
/// the reference on its grid of traced pixels; FLIP at the pixels per degree of the
/// project's Vive-class headset profile at the reference's size (what [`score`] takes
/// from the frame's eyes), no screen-space limit.
pub fn error_figures(technique: Technique, occlusion: &[Vec<f32>], reference: &ReferenceImage) -> ErrorFigures {
    let profile = crate::render::stereo::HeadsetProfile::with_size("vive", reference.width, reference.height);
    score(technique, occlusion, reference, None, pixels_per_degree(&profile.fov_left, reference.width))
}

/// [`error_figures`] with the screen-space limit of the same frame and radius (the limit
/// columns are `None` without it) and FLIP at `pixels_per_degree` of the full image.
pub fn score(
    technique: Technique,
    occlusion: &[Vec<f32>],
    reference: &ReferenceImage,
    limit: Option<&ScreenLimit>,
    pixels_per_degree: f64,
) -> ErrorFigures {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let (gw, gh) = reference.grid_size();
    let (gw, gh) = (gw as usize, gh as usize);
    let limit = limit.filter(|l| l.grid_size() == reference.grid_size() && l.layers.len() >= reference.layers.len());
    let (mut gpu_ao, mut ref_ao, mut falloff, mut noise2, mut mask) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut limit_ao, mut limit_mask) = (Vec::new(), Vec::new());
    let (mut gpu_ambient, mut ref_ambient) = (Vec::new(), Vec::new());
    let (mut ssim_sum, mut flip_sum, mut flip_pixels) = (0.0, 0.0, 0usize);
    let (mut outer_border, mut beside_edge) = (Vec::new(), Vec::new());
    for (layer, pixels) in reference.layers.iter().enumerate() {
        let image = &occlusion[layer];
        let first = gpu_ao.len();
        for gy in 0..gh {
            for gx in 0..gw {
                let r = &pixels[gy * gw + gx];
                let (x, y) = reference.pixel_of(gx as u32, gy as u32);
                let (x, y) = ((x as usize).min(w - 1), (y as usize).min(h - 1));
                let texel = &image[(y * w + x) * 4..(y * w + x) * 4 + 4];
                // Layer 0 is the left eye: its outer border is on the left.
                let outer = if layer == 0 { x } else { w - 1 - x };
                outer_border.push(r.hit && outer.min(y).min(h - 1 - y) < BORDER_PX as usize);
                beside_edge.push(r.hit && near_depth_edge(pixels, (gw, gh), gx, gy));
                gpu_ao.push(texel[3]);
                ref_ao.push(r.ao);
                falloff.push(r.ao_falloff);
                mask.push(r.hit);
                noise2.push(if r.hit { (r.ao_std_error as f64).powi(2) } else { 0.0 });
                let l = limit.map(|l| *l.get(layer, gx as u32, gy as u32));
                limit_ao.push(l.map_or(1.0, |l| l.ao));
                limit_mask.push(r.hit && l.is_some_and(|l| l.hit));
                let ambient = if technique.carries_light() {
                    [texel[0], texel[1], texel[2]]
                } else {
                    r.unoccluded.map(|c| c * texel[3])
                };
                let truth = [0, 1, 2].map(|c| r.environment_visible[c] + r.bounce[c]);
                gpu_ambient.push(luminance(ambient) as f32);
                ref_ambient.push(luminance(truth) as f32);
            }
        }
        let range = first..gpu_ao.len();
        ssim_sum +=
            metrics::ssim(&gpu_ao[range.clone()], &ref_ao[range.clone()], gw, gh, Some(&mask[range.clone()]), 1.0)
                .unwrap_or(0.0);
        // FLIP on this eye's grid, the sky 1 in both; pooled over both eyes' hit pixels.
        let sky_is_one = |values: &[f32]| -> Vec<f32> {
            values.iter().zip(&mask[range.clone()]).map(|(&v, &hit)| if hit { v } else { 1.0 }).collect()
        };
        let grid_ppd = pixels_per_degree / reference.stride.max(1) as f64;
        let (test, truth) = (sky_is_one(&gpu_ao[range.clone()]), sky_is_one(&ref_ao[range.clone()]));
        let hits = mask[range.clone()].iter().filter(|&&m| m).count();
        if let Some(mean) = metrics::flip_mean(&test, &truth, gw, gh, Some(&mask[range]), grid_ppd) {
            flip_sum += mean * hits as f64;
            flip_pixels += hits;
        }
    }
    let hit_count = mask.iter().filter(|&&m| m).count();
    let hits = hit_count.max(1) as f64;
    let noise = (noise2.iter().sum::<f64>() / hits).sqrt();
    let corrected = |a: &[f32], b: &[f32], mask: &[bool], noise: f64| {
        metrics::noise_corrected_rmse(metrics::rmse(a, b, Some(mask)).unwrap_or(f64::NAN), noise)
    };
    let mean_difference = |a: &[f32], b: &[f32], keep: &dyn Fn(usize) -> bool| {
        let (mut n, mut sum) = (0usize, 0f64);
        for i in (0..a.len()).filter(|&i| keep(i)) {
            n += 1;
            sum += a[i] as f64 - b[i] as f64;
        }
        (n > 0).then(|| sum / n as f64)
    };
    let ao_bias = mean_difference(&gpu_ao, &ref_ao, &|i| mask[i]).unwrap_or(f64::NAN);
    let ao_bias_dark = mean_difference(&gpu_ao, &ref_ao, &|i| mask[i] && ref_ao[i] < DARK_REFERENCE);
    let mean_ambient = ref_ambient.iter().zip(&mask).filter(|(_, &m)| m).map(|(&a, _)| a as f64).sum::<f64>() / hits;
    let ambient_rel_rmse = (mean_ambient > 1e-12)
        .then(|| metrics::rmse(&gpu_ambient, &ref_ambient, Some(&mask)).map(|e| e / mean_ambient))
        .flatten();
    // The limit against the reference with the reference's noise taken out, as `ao_rmse`
    // (so the two compare directly). The limit's own noise is not subtracted: its
    // binomial bound ignores the stratification of its rays and is several times what
    // they leave (on the crease the limit and a 64-ray reference differ by an RMSE of
    // 0.011 while each one's bound is ~0.03), so subtracting it would zero real error.
    let (ao_rmse_vs_limit, limit_rmse, limit_bias) = match limit {
        Some(_) if limit_mask.iter().any(|&m| m) => {
            let n = limit_mask.iter().filter(|&&m| m).count() as f64;
            let ref_noise2 = noise2.iter().zip(&limit_mask).filter(|(_, &m)| m).map(|(v, _)| v).sum::<f64>() / n;
            (
                metrics::rmse(&gpu_ao, &limit_ao, Some(&limit_mask)),
                Some(corrected(&limit_ao, &ref_ao, &limit_mask, ref_noise2.sqrt())),
                mean_difference(&limit_ao, &ref_ao, &|i| limit_mask[i]),
            )
        }
        _ => (None, None, None),
    };
    let edge_pixels = beside_edge.iter().filter(|&&e| e).count();
    let halos = (0..gpu_ao.len()).filter(|&i| beside_edge[i] && gpu_ao[i] < ref_ao[i] - HALO_DARKER).count();
    ErrorFigures {
        ao_rmse_outer_border: outer_border
            .iter()
            .any(|&b| b)
            .then(|| metrics::rmse(&gpu_ao, &ref_ao, Some(&outer_border)))
            .flatten(),
        halo_share: (edge_pixels > 0).then(|| halos as f64 / edge_pixels as f64),
        ao_rmse: corrected(&gpu_ao, &ref_ao, &mask, noise),
        ao_bias,
        ao_bias_dark,
        ao_rmse_falloff: corrected(&gpu_ao, &falloff, &mask, noise),
        ao_ssim: ssim_sum / reference.layers.len().max(1) as f64,
        ambient_rel_rmse,
        flip_mean: (flip_pixels > 0).then(|| flip_sum / flip_pixels as f64),
        ao_rmse_vs_limit,
        limit_rmse,
        limit_bias,
    }
}

impl LimitInfo {
    /// The defaults every bench uses.
    pub fn defaults() -> LimitInfo {
        use crate::measure::reference::screen_limit::{DEFAULT_RAYS, DEFAULT_STEPS, DEFAULT_THICKNESS_OF_RADIUS};
        LimitInfo {
            rays_per_pixel: DEFAULT_RAYS,
            steps: DEFAULT_STEPS,
            thickness_of_radius: DEFAULT_THICKNESS_OF_RADIUS,
        }
    }
}

/// The records of measured rows, with the Pareto front marked.
pub fn records(rows: &[BenchRow]) -> Vec<BenchRecord> {
    let mut out: Vec<BenchRecord> = rows
        .iter()
        .map(|row| {
            let c = &row.case;
            let name = row.pass;
            let spread = row.spans.iter().find(|s| s.label == name).map_or(0.0, |s| s.p75_ms / s.p25_ms.max(1e-9));
            let per_eye = |p: &str| row.median_ms(p) / row.views as f64;
            BenchRecord {
                technique: if name == RSM_PASS { RSM_PASS.to_string() } else { c.technique.name().to_string() },
                samples: c.samples,
                radius_m: c.radius,
                resolution: if c.half_res { "half" } else { "full" }.to_string(),
                technique_ms_per_eye: per_eye(name),
                blur_ms_per_eye: per_eye("blur"),
                upsample_ms_per_eye: per_eye("upsample"),
                occlusion_ms_per_eye: row.occlusion_ms_per_eye(),
                p75_over_p25: spread,
                ao_rmse: row.error.as_ref().map(|e| e.ao_rmse),
                ao_bias: row.error.as_ref().map(|e| e.ao_bias),
                ao_bias_dark: row.error.as_ref().and_then(|e| e.ao_bias_dark),
                ao_rmse_falloff: row.error.as_ref().map(|e| e.ao_rmse_falloff),
                ao_rmse_vs_limit: row.error.as_ref().and_then(|e| e.ao_rmse_vs_limit),
                limit_rmse: row.error.as_ref().and_then(|e| e.limit_rmse),
                limit_bias: row.error.as_ref().and_then(|e| e.limit_bias),
                ao_rmse_outer_border: row.error.as_ref().and_then(|e| e.ao_rmse_outer_border),
                halo_share: row.error.as_ref().and_then(|e| e.halo_share),
                flip_mean: row.error.as_ref().and_then(|e| e.flip_mean),
                stereo_inconsistent: row.stereo.and_then(|c| c.inconsistent),
                stereo_inconsistent_inner_border: row.stereo.and_then(|c| c.inner_border),
                stereo_inconsistent_interior: row.stereo.and_then(|c| c.interior),
                ao_ssim: row.error.as_ref().map(|e| e.ao_ssim),
                ambient_rel_rmse: row.error.as_ref().and_then(|e| e.ambient_rel_rmse),
                pareto: false,
                depth_peeling: c.depth_peeling,
                peel_ms_per_eye: per_eye("depth-peel"),
                bounce_rel_rmse: row.bounce.map(|b| b.rel_rmse),
                bounce_rel_bias: row.bounce.map(|b| b.rel_bias),
                temporal: c.temporal,
                composite_ms_per_eye: per_eye("composite"),
                frame_upsample_ms_per_eye: None,
                other_ms_per_eye: Some(row.other_ms_per_eye()),
            }
        })
        .collect();
    for i in 0..out.len() {
        let half = &out[i];
        if half.resolution != "half" || half.composite_ms_per_eye <= 0.0 {
            continue;
        }
        let full = full_resolution_partner(&out, half).filter(|f| f.composite_ms_per_eye > 0.0);
        out[i].frame_upsample_ms_per_eye = full.map(|f| half.composite_ms_per_eye - f.composite_ms_per_eye);
    }
    mark_pareto(&mut out);
    out
}

/// The full-resolution record of the same technique and setting as `half`.
fn full_resolution_partner<'a>(records: &'a [BenchRecord], half: &BenchRecord) -> Option<&'a BenchRecord> {
    let h = half;
    records.iter().find(|f| {
        f.resolution == "full"
            && (f.technique.as_str(), f.samples, f.radius_m, f.depth_peeling, f.temporal)
                == (h.technique.as_str(), h.samples, h.radius_m, h.depth_peeling, h.temporal)
    })
}

/// Marks each record on the Pareto front of AO RMSE against occlusion ms per eye. Each
/// radius is its own target quantity (AO within r), so errors compare only within one
/// radius: one front per radius.
pub fn mark_pareto(out: &mut [BenchRecord]) {
    out.iter_mut().for_each(|r| r.pareto = false);
    let mut radii: Vec<f32> = out.iter().map(|r| r.radius_m).collect();
    radii.sort_by(f32::total_cmp);
    radii.dedup();
    for radius in radii {
        let members: Vec<usize> = (0..out.len()).filter(|&i| out[i].radius_m == radius).collect();
        let points: Vec<(f64, f64)> =
            members.iter().map(|&i| (out[i].occlusion_ms_per_eye, out[i].ao_rmse.unwrap_or(f64::NAN))).collect();
        for k in metrics::pareto_front(&points) {
            out[members[k]].pareto = true;
        }
    }
}

/// One column of the CSV and of the Markdown table: its CSV name, its Markdown
/// header, the CSV value (full precision) and the Markdown value (rounded to what it means).
struct Column {
    name: &'static str,
    header: &'static str,
    csv: fn(&BenchRecord) -> String,
    markdown: fn(&BenchRecord) -> String,
    /// Shown in the Markdown table only when some row has something there.
    optional: bool,
}

fn fixed(v: Option<f64>, decimals: usize) -> String {
    v.map_or(String::new(), |v| format!("{v:.decimals$}"))
}

fn percent(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{:.1} %", v * 100.0))
}

fn yes(b: bool) -> String {
    if b { "yes" } else { "" }.to_string()
}

/// Every column, the ones a reader compares first first.
/// A column of an error figure (`Option<f64>` field): 4 decimals in CSV, 3 in Markdown.
macro_rules! figure_column {
    ($field:ident, $header:literal, $optional:literal) => {
        Column {
            name: stringify!($field),
            header: $header,
            csv: |r| fixed(r.$field, 4),
            markdown: |r| fixed(r.$field, 3),
            optional: $optional,
        }
    };
}

/// A column of a share (`Option<f64>` in 0..1): 4 decimals in CSV, a percentage in Markdown.
macro_rules! share_column {
    ($field:ident, $header:literal) => {
        Column {
            name: stringify!($field),
            header: $header,
            csv: |r| fixed(r.$field, 4),
            markdown: |r| percent(r.$field),
            optional: false,
        }
    };
}

const COLUMNS: &[Column] = &[
    Column {
        name: "technique",
        header: "technique",
        csv: |r| r.technique.clone(),
        markdown: |r| r.technique.clone(),
        optional: false,
    },
    Column {
        name: "samples",
        header: "N",
        csv: |r| r.samples.to_string(),
        markdown: |r| r.samples.to_string(),
        optional: false,
    },
    Column {
        name: "radius_m",
        header: "r (m)",
        csv: |r| format!("{}", r.radius_m),
        markdown: |r| significant(r.radius_m as f64, 2),
        optional: false,
    },
    Column {
        name: "resolution",
        header: "res",
        csv: |r| r.resolution.clone(),
        markdown: |r| r.resolution.clone(),
        optional: false,
    },
    Column {
        name: "occlusion_ms_per_eye",
        header: "ms/eye",
        csv: |r| format!("{:.3}", r.occlusion_ms_per_eye),
        markdown: |r| format!("{:.1}", r.occlusion_ms_per_eye),
        optional: false,
    },
    figure_column!(ao_rmse, "RMSE", false),
    figure_column!(ao_bias, "bias", false),
    figure_column!(ao_bias_dark, "bias (ref < 0.8)", false),
    figure_column!(ao_rmse_vs_limit, "RMSE vs limit", false),
    figure_column!(limit_rmse, "limit RMSE", false),
    figure_column!(limit_bias, "limit bias", false),
    figure_column!(ao_rmse_outer_border, "RMSE outer border", false),
    share_column!(halo_share, "halo"),
    figure_column!(flip_mean, "FLIP", false),
    share_column!(stereo_inconsistent, "stereo ≠"),
    share_column!(stereo_inconsistent_inner_border, "≠ inner border"),
    share_column!(stereo_inconsistent_interior, "≠ interior"),
    figure_column!(ao_rmse_falloff, "RMSE falloff", false),
    figure_column!(ao_ssim, "SSIM", false),
    figure_column!(ambient_rel_rmse, "ambient rel. RMSE", true),
    Column {
        name: "technique_ms_per_eye",
        header: "technique ms",
        csv: |r| format!("{:.3}", r.technique_ms_per_eye),
        markdown: |r| format!("{:.1}", r.technique_ms_per_eye),
        optional: false,
    },
    Column {
        name: "blur_ms_per_eye",
        header: "blur ms",
        csv: |r| format!("{:.3}", r.blur_ms_per_eye),
        markdown: |r| format!("{:.1}", r.blur_ms_per_eye),
        optional: false,
    },
    Column {
        name: "upsample_ms_per_eye",
        header: "upsample ms",
        csv: |r| format!("{:.3}", r.upsample_ms_per_eye),
        markdown: |r| if r.resolution == "half" { format!("{:.1}", r.upsample_ms_per_eye) } else { String::new() },
        optional: true,
    },
    Column {
        name: "p75_over_p25",
        header: "p75/p25",
        csv: |r| format!("{:.3}", r.p75_over_p25),
        markdown: |r| format!("{:.2}", r.p75_over_p25),
        optional: false,
    },
    Column { name: "pareto", header: "Pareto", csv: |r| yes(r.pareto), markdown: |r| yes(r.pareto), optional: true },
    Column {
        name: "depth_peeling",
        header: "peeled",
        csv: |r| yes(r.depth_peeling),
        markdown: |r| yes(r.depth_peeling),
        optional: true,
    },
    Column {
        name: "peel_ms_per_eye",
        header: "peel ms",
        csv: |r| format!("{:.3}", r.peel_ms_per_eye),
        markdown: |r| if r.depth_peeling { format!("{:.1}", r.peel_ms_per_eye) } else { String::new() },
        optional: true,
    },
    figure_column!(bounce_rel_rmse, "bounce rel. RMSE", true),
    figure_column!(bounce_rel_bias, "bounce rel. bias", true),
    Column {
        name: "temporal",
        header: "temporal",
        csv: |r| yes(r.temporal),
        markdown: |r| yes(r.temporal),
        optional: true,
    },
    Column {
        name: "composite_ms_per_eye",
        header: "composite ms",
        csv: |r| format!("{:.3}", r.composite_ms_per_eye),
        markdown: |r| {
            if r.composite_ms_per_eye > 0.0 {
                format!("{:.1}", r.composite_ms_per_eye)
            } else {
                String::new()
            }
        },
        optional: true,
    },
    Column {
        name: "frame_upsample_ms_per_eye",
        header: "frame upsample ms",
        csv: |r| fixed(r.frame_upsample_ms_per_eye, 3),
        markdown: |r| fixed(r.frame_upsample_ms_per_eye, 1),
        optional: true,
    },
];

/// The CSV: every column of every record, full precision (shares as fractions 0..1).
pub fn to_csv(records: &[BenchRecord]) -> String {
    let mut s = COLUMNS.iter().map(|c| c.name).collect::<Vec<_>>().join(",") + "\n";
    for r in records {
        s += &(COLUMNS.iter().map(|c| (c.csv)(r)).collect::<Vec<_>>().join(",") + "\n");
    }
    s
}

/// The table of records as Markdown, rounded for reading (RMSE and bias to 3 decimals, ms
/// to 1, shares in percent to 1); optional columns only where some row has a value.
pub fn to_markdown(records: &[BenchRecord]) -> String {
    let shown: Vec<&Column> =
        COLUMNS.iter().filter(|c| !c.optional || records.iter().any(|r| !(c.markdown)(r).is_empty())).collect();
    let mut s = format!(
        "| {} |\n|{}\n",
        shown.iter().map(|c| c.header).collect::<Vec<_>>().join(" | "),
        "---|".repeat(shown.len())
    );
    for r in records {
        let _ = writeln!(s, "| {} |", shown.iter().map(|c| (c.markdown)(r)).collect::<Vec<_>>().join(" | "));
    }
    s
}

/// What the columns mean, for the foot of bench.md.
pub const COLUMN_NOTES: &str = "\
- **RMSE**, **bias**: the AO against the ray-traced reference's hard cut-off AO (cosine-weighted \
visibility within r), the target every technique is scored against; bias is mean(estimate − \
reference), > 0 too light; **bias (ref < 0.8)** over the pixels the reference finds occluded. \
**RMSE falloff**: against the reference with HBAO's linear falloff 1 − d/r instead, for comparison.
- **limit RMSE**, **limit bias**: the *screen-space limit* (a brute-force march over this frame's \
own depth buffer: many rays of length r, a thickness, off-image open) against the reference: the \
error of seeing one depth layer per eye, which no screen-space technique can remove. The same \
for every row of a radius.
- **RMSE vs limit**: the technique against that limit: its *estimator* error (too few samples, \
falloffs, one sample point per direction, noise). A technique with RMSE ≈ limit RMSE and a small \
RMSE vs limit is as good as screen space gets; a large RMSE vs limit is the estimator's own fault.
- **RMSE outer border**: RMSE over the pixels within 40 px of an eye's outer, top or bottom \
border, where samples that leave the image count as open (the other eye sees no further there): \
compared with RMSE, what rendering a guard band around the image could win.
- **halo**: share of the pixels beside a depth edge (within one reference cell) that are too \
dark by more than 0.1: occlusion spilling from a near object onto the far surface behind it.
- **FLIP**: mean ꟻLIP of the AO image against the reference AO (both as grey images, sky 1) at \
the headset's pixels per degree over the reference's stride: how visible the difference is; \
noise and blotches count more than a smooth offset of the same RMSE.
- **stereo ≠**: share of the surface points both eyes see whose final AO differs between the \
eyes by more than 0.02 (both directions pooled), overall, within 40 px of each eye's inner \
(nasal) border, and farther than 40 px from every border.
- **ms/eye**: occlusion cost per eye (technique + blur + upsampling), median over the measured frames.
";

/// The header of bench.md: scene, adapter, version, command line and how it was measured.
pub fn markdown_header(file: &BenchFile) -> String {
    let mut s = format!("# vrao bench: {}\n\n", file.scene);
    let driver = if file.driver.is_empty() { String::new() } else { format!(", driver {}", file.driver) };
    let _ = writeln!(s, "- adapter: {} ({}{driver})", file.adapter, file.backend);
    if !file.version.is_empty() {
        let _ = writeln!(s, "- vrao {}", file.version);
    }
    if !file.command.is_empty() {
        let _ = writeln!(s, "- command: `{}`", file.command);
    }
    let _ = writeln!(
        s,
        "- {}×{} per eye, {} timing, {} warm-up + {} measured frames per case",
        file.width, file.height, file.timing, file.warmup, file.frames
    );
    if let Some(r) = &file.reference {
        let _ = writeln!(
            s,
            "- reference: {} rays per pixel at every {} pixels (its AO noise, RMS standard error: {:.4})",
            r.rays_per_pixel, r.stride, r.ao_noise_rms
        );
        if let Some(l) = &file.limit {
            let _ = writeln!(
                s,
                "- screen-space limit: {} rays × {} steps per pixel on the same pixels, thickness {} r",
                l.rays_per_pixel, l.steps, l.thickness_of_radius
            );
        }
        if let Some(ppd) = file.pixels_per_degree {
            let _ = writeln!(
                s,
                "- FLIP at {ppd:.1} pixels per degree, {:.1} on the reference's grid",
                ppd / r.stride.max(1) as f64
            );
        }
    }
    s + "\n"
}

/// bench.md: the header, the table, what the columns mean, and the ratios.
pub fn markdown_report(file: &BenchFile) -> String {
    let mut s = markdown_header(file) + &to_markdown(&file.records);
    if file.reference.is_some() {
        s += "\n";
        s += COLUMN_NOTES;
    }
    s + &ratios_markdown(&file.records)
}

/// The ratios a sweep is judged by, as Markdown (empty when no row has a partner):
/// - half / full resolution of each case: occlusion ms per eye (technique + blur + the
///   stand-alone upsample pass) and, with `--frame`, the same with the frame's inline
///   upsampling instead of the pass;
/// - each technique's pass against SSAO's at the same setting and resolution;
/// - each technique's pass against fetch-only's (the same depth taps, no arithmetic):
///   how far it is from the memory limit.
pub fn ratios_markdown(records: &[BenchRecord]) -> String {
    let mut s = String::new();
    let plain = |r: &&BenchRecord| !r.depth_peeling && !r.temporal;
    let mut half_full = String::new();
    for half in records.iter().filter(|r| r.resolution == "half") {
        let Some(full) = full_resolution_partner(records, half) else {
            continue;
        };
        let in_frame = half.frame_upsample_ms_per_eye.map_or(String::new(), |up| {
            format!("{:.3}", (half.occlusion_ms_per_eye - half.upsample_ms_per_eye + up) / full.occlusion_ms_per_eye)
        });
        let _ = writeln!(
            half_full,
            "| {} | {} | {} | {:.3} | {in_frame} |",
            half.technique,
            half.samples,
            significant(half.radius_m as f64, 2),
            half.occlusion_ms_per_eye / full.occlusion_ms_per_eye
        );
    }
    if !half_full.is_empty() {
        s += "\nHalf / full resolution, occlusion ms per eye (technique + blur + upsampling):\n\n";
        s += "| technique | samples | radius_m | with the upsample pass | with the frame's inline upsampling |\n|---|---|---|---|---|\n";
        s += &half_full;
    }
    for (against, title) in [
        ("ssao", "Technique pass against SSAO's at the same setting and resolution"),
        ("fetch-only", "Technique pass against fetch-only's (same depth taps, no arithmetic)"),
    ] {
        let mut table = String::new();
        for r in records.iter().filter(plain).filter(|r| r.technique != against && r.technique != "rsm") {
            let partner = records.iter().filter(plain).find(|b| {
                b.technique == against
                    && (b.samples, b.radius_m, &b.resolution) == (r.samples, r.radius_m, &r.resolution)
            });
            if let Some(b) = partner {
                let ratio = r.technique_ms_per_eye / b.technique_ms_per_eye;
                let occlusion = r.occlusion_ms_per_eye / b.occlusion_ms_per_eye;
                let _ = writeln!(
                    table,
                    "| {} | {} | {} | {} | {ratio:.3} | {occlusion:.3} |",
                    r.technique,
                    r.samples,
                    significant(r.radius_m as f64, 2),
                    r.resolution
                );
            }
        }
        if !table.is_empty() {
            let _ = write!(s, "\n{title}:\n\n| technique | samples | radius_m | resolution | technique pass | occlusion (with blur, upsampling) |\n|---|---|---|---|---|---|\n{table}");
        }
    }
    s
}

pub fn to_json(file: &BenchFile) -> String {
    serde_json::to_string_pretty(file).expect("bench records serialise")
}

/// Reads a bench JSON file (for `vrao budget --fit`).
pub fn read_json(path: &std::path::Path) -> Result<BenchFile> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::in_file(path, e.to_string()))?;
    serde_json::from_str(&text).map_err(|e| Error::at_line(path, e.line(), format!("not a vrao bench file: {e}")))
}

/// The plot's file name for one radius, rounded so that it carries no float noise:
/// `bench-r0.26.png`.
pub fn plot_file_name(radius_m: f32) -> String {
    format!("bench-r{}.png", significant(radius_m as f64, 2))
}

/// The plot of AO error against occlusion ms per eye for the rows of one radius, every
/// point labelled with its setting, with that radius's Pareto front and a budget line.
///
/// The x axis is the occlusion's time alone (what the Pareto front and `vrao budget
/// --fit` rank by), so the budget line is the occlusion's share of the frame: the
/// per-eye budget minus the other passes the bench measured in the same frames (the
/// median over the radius's rows). A file without those times gets the whole per-eye
/// budget, labelled as such.
pub fn plot(file: &BenchFile, radius_m: f32, budget_ms_per_eye: f64) -> ScatterPlot {
    // One hue per technique variant, dark at full and light at half resolution.
    const HUES: [([u8; 3], [u8; 3]); 6] = [
        ([31, 90, 180], [120, 170, 230]),
        ([220, 110, 0], [250, 180, 100]),
        ([30, 130, 40], [130, 200, 120]),
        ([190, 30, 40], [240, 130, 130]),
        ([110, 60, 170], [190, 160, 220]),
        ([120, 75, 40], [200, 160, 120]),
    ];
    let rows: Vec<&BenchRecord> =
        file.records.iter().filter(|r| r.radius_m == radius_m && r.ao_rmse.is_some()).collect();
    let (mut series, mut variants): (Vec<Series>, Vec<String>) = (Vec::new(), Vec::new());
    for r in &rows {
        let technique = format!(
            "{}{}{}",
            r.technique,
            if r.depth_peeling { " peeled" } else { "" },
            if r.temporal { " temporal" } else { "" }
        );
        let label = format!("{technique} {}", r.resolution);
        if !variants.contains(&technique) {
            variants.push(technique.clone());
        }
        let point = Point {
            x: r.occlusion_ms_per_eye,
            y: r.ao_rmse.unwrap_or(f64::NAN),
            label: format!("{technique} N={} {}", r.samples, r.resolution),
        };
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push(point),
            None => {
                let hue = HUES[variants.iter().position(|v| v == &technique).unwrap_or(0) % HUES.len()];
                let color = if r.resolution == "half" { hue.1 } else { hue.0 };
                series.push(Series { label, color, points: vec![point] });
            }
        }
    }
    let pareto: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.pareto).map(|r| (r.occlusion_ms_per_eye, r.ao_rmse.unwrap_or(f64::NAN))).collect();
    let mut other: Vec<f64> = rows.iter().filter_map(|r| r.other_ms_per_eye).collect();
    other.sort_by(f64::total_cmp);
    let line = match other.get(other.len() / 2) {
        Some(&other) => {
            let share = (budget_ms_per_eye - other).max(0.0);
            let label = format!(
                "occlusion budget {share:.2} ms/eye\n({budget_ms_per_eye:.2} per eye \u{2212} {other:.2} other passes)"
            );
            (share, label)
        }
        None => (budget_ms_per_eye, format!("whole budget {budget_ms_per_eye:.2} ms/eye\n(other passes not recorded)")),
    };
    ScatterPlot {
        title: format!(
            "{}: AO error against time, r = {} m, {}x{} per eye, {}",
            file.scene,
            significant(radius_m as f64, 2),
            file.width,
            file.height,
            file.adapter
        ),
        x_label: "occlusion ms per eye (technique + blur + upsample)".into(),
        y_label: "AO RMSE against the reference".into(),
        series,
        pareto,
        vertical_line: Some(line),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(technique: Technique, ms: f64, ao_rmse: f64) -> BenchRow {
        let span = |label: &str, median_ms| SpanSummary {
            label: label.into(),
            frames: 30,
            median_ms,
            p25_ms: median_ms,
            p75_ms: median_ms,
            min_ms: median_ms,
            max_ms: median_ms,
        };
        BenchRow {
            case: BenchCase {
                technique,
                samples: 12,
                radius: 0.5,
                half_res: false,
                depth_peeling: false,
                temporal: false,
            },
            spans: vec![span(technique.name(), ms), span("blur", 2.0), span("gbuffer", 50.0)],
            views: 2,
            pass: technique.name(),
            error: Some(ErrorFigures {
                ao_rmse,
                ao_bias: -0.05,
                ao_bias_dark: Some(-0.1),
                ao_rmse_falloff: 0.3,
                ao_ssim: 0.9,
                ambient_rel_rmse: None,
                flip_mean: Some(0.125),
                ao_rmse_vs_limit: Some(0.06),
                limit_rmse: Some(0.04),
                limit_bias: Some(0.01),
                ao_rmse_outer_border: Some(0.07),
                halo_share: Some(0.0625),
            }),
            bounce: None,
            stereo: Some(StereoConsistency {
                inconsistent: Some(0.25),
                inner_border: Some(0.5),
                interior: Some(0.125),
                compared: 1000,
            }),
        }
    }

    fn file(records: Vec<BenchRecord>) -> BenchFile {
        BenchFile {
            scene: "crease".into(),
            adapter: "test".into(),
            backend: "Vulkan".into(),
            driver: String::new(),
            width: 64,
            height: 48,
            timing: "serial".into(),
            warmup: 1,
            frames: 30,
            reference: None,
            limit: None,
            pixels_per_degree: None,
            version: String::new(),
            command: String::new(),
            records,
        }
    }

    #[test]
    fn the_plot_labels_every_point_and_bounds_occlusion_by_its_share_of_the_budget() {
        let mut f = file(records(&[row(Technique::Ssao, 10.0, 0.1), row(Technique::Hbao, 14.0, 0.08)]));
        let p = plot(&f, 0.5, 55.5);
        let labels: Vec<&str> = p.series.iter().flat_map(|s| s.points.iter().map(|p| p.label.as_str())).collect();
        assert_eq!(labels, ["ssao N=12 full", "hbao N=12 full"]);
        // Occlusion ms on x, so the line is what the per-eye budget leaves after the other
        // passes of the same frames (the G-buffer, 50 ms for both eyes).
        assert_eq!(f.records[0].other_ms_per_eye, Some(25.0));
        let (x, label) = p.vertical_line.clone().unwrap();
        assert_eq!(x, 30.5);
        assert!(label.starts_with("occlusion budget 30.50 ms/eye"), "{label}");
        // A file from before the other passes were recorded: the whole budget, said so.
        f.records.iter_mut().for_each(|r| r.other_ms_per_eye = None);
        let (x, label) = plot(&f, 0.5, 55.5).vertical_line.unwrap();
        assert!(x == 55.5 && label.contains("other passes not recorded"), "{label}");
        assert_eq!(plot_file_name(0.25612497), "bench-r0.26.png");
        assert!(p.title.contains("r = 0.5 m"), "{}", p.title);
    }

    #[test]
    fn a_depth_edge_is_a_step_or_the_sky_not_a_slope() {
        let cell = |depth: f32| ReferencePixel { hit: depth > 0.0, depth, ..ReferencePixel::SKY };
        // A floor receding linearly along the row (1, 2, …, 5 m): no edge anywhere inside.
        let slope: Vec<_> = (1..=5).map(|d| cell(d as f32)).collect();
        assert!((1..4).all(|i| !near_depth_edge(&slope, (5, 1), i, 0)));
        // A near object (1 m) in front of a wall (4 m): both sides of the step are edges,
        // cells two away are not.
        let step: Vec<_> = [1.0, 1.0, 1.0, 4.0, 4.0, 4.0].into_iter().map(cell).collect();
        let edges: Vec<_> = (0..6).map(|i| near_depth_edge(&step, (6, 1), i, 0)).collect();
        assert_eq!(edges, [false, false, true, true, false, false]);
        // Beside the sky.
        let sky: Vec<_> = [2.0, 2.0, 0.0].into_iter().map(cell).collect();
        assert!(near_depth_edge(&sky, (3, 1), 1, 0));
        assert!(!near_depth_edge(&sky, (3, 1), 2, 0), "the sky itself is no edge pixel");
    }

    #[test]
    fn per_eye_cost_halves_both_eye_dispatches_and_ignores_other_passes() {
        assert_eq!(row(Technique::Ssao, 10.0, 0.1).occlusion_ms_per_eye(), 6.0);
    }

    #[test]
    fn the_pareto_front_keeps_rows_no_other_row_beats_in_both_time_and_error() {
        // ssao: 6 ms, 0.10; hbao: 7 ms, 0.05; ssdo: 8 ms, 0.07 (slower and worse than hbao).
        let rows =
            [row(Technique::Ssao, 10.0, 0.10), row(Technique::Hbao, 12.0, 0.05), row(Technique::Ssdo, 14.0, 0.07)];
        let pareto: Vec<bool> = records(&rows).iter().map(|r| r.pareto).collect();
        assert_eq!(pareto, [true, true, false]);
    }

    #[test]
    fn csv_markdown_and_json_hold_every_row() {
        let rows = [row(Technique::Ssao, 10.0, 0.1), row(Technique::Hbao, 12.0, 0.2)];
        let recs = records(&rows);
        let csv = to_csv(&recs);
        assert_eq!(csv.lines().count(), 3);
        // technique, N, r, resolution, ms/eye, RMSE, bias, bias (ref < 0.8), vs limit,
        // limit RMSE, limit bias, outer border RMSE, halo, FLIP, stereo shares, falloff
        // RMSE, SSIM, ambient, …
        assert!(
            csv.lines().nth(2).unwrap().starts_with(
                "hbao,12,0.5,full,7.000,0.2000,-0.0500,-0.1000,0.0600,0.0400,0.0100,0.0700,0.0625,0.1250,0.2500,0.5000,0.1250,0.3000,0.9000,,6.000,1.000,0.000,1.000,"
            ),
            "{csv}"
        );
        let header = csv.lines().next().unwrap();
        for want in ["bias", "limit", "flip", "consisten"] {
            assert!(header.split(',').any(|c| c.contains(want) && !c.contains("bounce")), "{want}: {header}");
        }
        // Markdown: rounded for reading; optional columns (peeling, bounce, …) left out.
        let markdown = to_markdown(&recs);
        assert_eq!(markdown.lines().count(), 4);
        let hbao = markdown.lines().nth(3).unwrap();
        assert!(
            hbao.starts_with("| hbao | 12 | 0.5 | full | 7.0 | 0.200 | -0.050 | -0.100 | 0.060 | 0.040 | 0.010 | 0.070 | 6.2 % | 0.125 | 25.0 % | 50.0 % | 12.5 % |"),
            "{hbao}"
        );
        assert!(!markdown.contains("peel") && !markdown.contains("bounce"), "{markdown}");
        let json = to_json(&file(recs.clone()));
        let back: BenchFile = serde_json::from_str(&json).unwrap();
        assert_eq!(back.records, recs);
    }
}
