//! Sweeps of technique × samples × radius × resolution: the median GPU time of every
//! pass per eye over many frames, as a table, CSV and Markdown. (Error against the
//! reference tracer joins these rows when the tracer exists.)

use crate::error::{Error, Result};
pub use crate::formats::bench_file::{BenchFile, BenchRecord, LimitInfo, ReferenceInfo, Resolution};
pub use crate::formats::output::significant;
use crate::formats::spans::{summarize, SpanSummary};
use crate::measure::metrics;
use crate::measure::metrics::luminance;
use crate::measure::plot::{Point, ScatterPlot, Series};
use crate::measure::reference::screen_limit::{screen_space_limit, EyeBuffers, LimitSettings, ScreenLimit};
use crate::measure::reference::{ReferenceImage, ReferencePixel};
use crate::measure::side_by_side::{grid_panel, save_panels};
use crate::measure::stereo_consistency::{stereo_consistency, EyeImages, StereoConsistency, BORDER_PX};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::sync::Arc;
use vrao_ao::plug::{FrameTiming, Gpu, DEPTH, DEPTH_LAYER_2, FINAL_AO, NORMALS};
use vrao_ao::{Foveation, Technique};
use vrao_render::passes::composite::HDR;
use vrao_render::passes::peel;
use vrao_render::passes::rsm::{self, RSM_INDIRECT};
use vrao_render::passes::shadow;
use vrao_render::renderer::{Renderer, Timing};
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;

mod errors;
mod report;
mod run;
#[cfg(test)]
mod tests;

pub use errors::*;
pub use report::*;
pub use run::{
    cases, format_duration, replot, run_bench, version, write_outputs, BenchOptions, BenchRun, ReferenceOptions,
};

/// One configuration of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchCase {
    /// The occlusion technique.
    pub technique: Technique,
    /// Samples per pixel (N).
    pub samples: u32,
    /// Occlusion radius (m).
    pub radius: f32,
    /// Occlusion at half resolution, then upsampled.
    pub half_res: bool,
    /// SSDO with depth peeling (a second depth layer; its pass counts as occlusion cost).
    pub depth_peeling: bool,
    /// Depth layers the occlusion reads (1 or 2; 2 only for techniques that read a
    /// second layer, whose peel then counts as occlusion cost).
    pub layers: u32,
    /// Temporal accumulation (its pass counts as occlusion cost; the error is taken
    /// after the warm-up and measured frames, with a static head: converged).
    pub temporal: bool,
    /// Fixed foveated occlusion.
    pub foveation: Foveation,
    /// The passes skip the pixels the profile's lens hides ([`crate::xr::profiles::visibility_mask`]).
    pub mask: bool,
}

/// How each case is run: frames (after warm-up) and the timing mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Serial (true per-pass times) or pipelined submission.
    pub timing: Timing,
    /// Frames rendered and discarded before timing.
    pub warmup: u32,
    /// Frames timed (the medians are over these).
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
    /// The configuration measured.
    pub case: BenchCase,
    /// Median and spread of every span over the measured frames.
    pub spans: Vec<SpanSummary>,
    /// Views the occlusion passes covered in one dispatch (per-eye = total / views).
    pub views: u32,
    /// The pass that ran the technique.
    pub pass: &'static str,
    /// The passes whose spans are the occlusion's cost (the graph's occlusion chain, or
    /// the RSM gather and its light-space pass).
    pub occlusion_passes: Vec<&'static str>,
    /// Error against the reference, when one was traced for this row's radius.
    pub error: Option<ErrorFigures>,
    /// Error of the one-bounce irradiance against the reference's `bounce` (ssdo-bounce
    /// and rsm rows, with a reference).
    pub bounce: Option<BounceFigures>,
    /// How far the eyes' final AO disagree on the points both see (occlusion rows; no
    /// reference needed).
    pub stereo: Option<StereoConsistency>,
    /// Per pass, the right eye's tiles computed rather than copied from the left eye in
    /// the last measured frame (empty where the right eye reused nothing).
    pub right_eye: Vec<vrao_ao::RightEyeTiles>,
}

impl BenchRow {
    /// Median ms of one pass for both eyes together, 0 when it did not run: a row is
    /// only made when every pass that ran has a span under its name (`check_timed`), so
    /// look passes up by their `NAME` constants.
    pub fn median_ms(&self, span: &str) -> f64 {
        self.spans.iter().find(|s| s.label == span).map_or(0.0, |s| s.median_ms)
    }

    /// Occlusion cost per eye: the occlusion passes' medians (technique, depth peel,
    /// temporal, denoise, upsample as the graph ran them), both-eye dispatches halved.
    /// Reflective shadow maps (pass `rsm`): the gather plus the light-space pass that
    /// renders the maps.
    pub fn occlusion_ms_per_eye(&self) -> f64 {
        self.occlusion_passes.iter().map(|p| self.median_ms(p)).sum::<f64>() / self.views as f64
    }

    /// Per eye, the passes of the measured frames besides the occlusion (per-eye spans
    /// lie inside their pass's and are not added): what the occlusion shares the frame
    /// budget with, for the plot's budget line.
    pub fn other_ms_per_eye(&self) -> f64 {
        let occlusion = &self.occlusion_passes;
        let other =
            self.spans.iter().filter(|s| !FrameTiming::is_per_eye(&s.label) && !occlusion.contains(&s.label.as_str()));
        other.map(|s| s.median_ms).sum::<f64>() / self.views as f64
    }
}

/// Each eye's pixels the `mask` shows for `settings`' size (`None`: all of them).
pub fn lens_coverage(
    mask: &vrao_ao::VisibilityMask,
    settings: &Settings,
    eyes: &[vrao_ao::Eye],
) -> Vec<Option<Vec<u8>>> {
    let (w, h) = (settings.profile.width, settings.profile.height);
    eyes.iter()
        .zip(&mask.views)
        .map(|(eye, view)| Some(view.coverage(w, h, eye.fov.tangents())).filter(|c| c.contains(&0)))
        .collect()
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
    let limits = match reference {
        Some(reference) => {
            let second = second_layer(gpu, scene, base, case, how)?;
            Some(run.screen_limits(reference, second.as_deref())?)
        }
        None => None,
    };
    run.finish(reference, limits.as_ref())
}

/// A frame's screen-space limits for one radius: with one depth layer, and with two
/// (the one-layer limit again where the scene can have nothing behind its first layer).
#[derive(Clone, Debug)]
pub struct Limits {
    /// The one-layer limit (`limit_rmse`).
    pub one: ScreenLimit,
    /// The two-layer limit (`limit_two_layer_rmse`).
    pub two: ScreenLimit,
}

/// The file a row's comparison image takes (`vrao bench --images`): its case, as
/// `gtao-n24-r0.68-full-layers2.png` with `-mask`, `-peel`, `-temporal` and `-fov-LEVEL`
/// where they apply.
pub fn comparison_image_name(case: &BenchCase) -> String {
    let mut name = format!(
        "{}-n{}-r{}-{}-layers{}",
        case.technique.name(),
        case.samples,
        significant(case.radius as f64, 3),
        if case.half_res { "half" } else { "full" },
        case.layers
    );
    for (on, part) in [(case.mask, "-mask"), (case.depth_peeling, "-peel"), (case.temporal, "-temporal")] {
        if on {
            name.push_str(part);
        }
    }
    if case.foveation != Foveation::Off {
        name.push_str(&format!("-fov-{}", case.foveation.name()));
    }
    name + ".png"
}

/// The second depth layer of `case`'s frame as two layers peel it (the case's scene,
/// pose, size, mask and separation; GTAO with `layers` 2 on a renderer of its own, so
/// that the case's own renderer, its history included, is not touched), or `None` when
/// the scene can have nothing behind its first layer (the peel is left out).
fn second_layer(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    case: &BenchCase,
    how: Measurement,
) -> Result<Option<Vec<Vec<f32>>>> {
    let two =
        BenchCase { technique: Technique::Gtao, layers: 2, temporal: false, depth_peeling: false, ..case.clone() };
    let mut run = CaseRun::new(gpu, scene, base, &two, how)?;
    let report = run.frame()?;
    if report.plan.runs(peel::NAME) {
        Ok(Some(run.renderer.read_f32(DEPTH_LAYER_2)?))
    } else {
        Ok(None)
    }
}

/// One case being measured: its renderer, and the per-pass times of its frames so far.
/// Kept apart from the loop so that a sweep can interleave cases frame by frame.
struct CaseRun {
    case: BenchCase,
    settings: Settings,
    output: vrao_ao::plug::Resource,
    /// What each frame renders: the occlusion, and with `whole_frame` the lit image.
    outputs: Vec<vrao_ao::plug::Resource>,
    renderer: Renderer,
    eyes: vrao_ao::EyePair,
    timing: Timing,
    timings: Vec<Vec<(String, f64)>>,
    /// Each eye's pixels the profile's lens shows (0: hidden): rows are scored there.
    coverage: Vec<Option<Vec<u8>>>,
}

impl CaseRun {
    fn new(gpu: &Arc<Gpu>, scene: &Scene, base: &Settings, case: &BenchCase, how: Measurement) -> Result<CaseRun> {
        let timing = how.timing;
        let mut settings = base.clone();
        settings.ao.technique = case.technique;
        settings.ao.samples = case.samples;
        settings.ao.radius = case.radius;
        settings.ao.resolution = vrao_ao::Resolution::from_half_res(case.half_res);
        settings.point_ssdo.depth_peeling = case.depth_peeling;
        settings.ao.layers = case.layers;
        settings.ao.temporal.enabled = case.temporal;
        settings.ao.foveation = case.foveation;
        settings.ao.mask = case.mask;
        if settings.ao.technique == Technique::None {
            return Err(Error::input("bench needs an occlusion technique"));
        }
        let output = FINAL_AO;
        if timing == Timing::Pipelined && !gpu.caps.timestamps {
            return Err(Error::device(format!(
                "{} has no timestamp queries; use serial timing",
                gpu.info.name.clone()
            )));
        }
        let mut renderer = Renderer::new(gpu.clone(), scene, &settings)?;
        renderer.set_timing(timing);
        let mask = crate::xr::profiles::visibility_mask(&settings.profile);
        renderer.set_visibility_mask(Some(mask.clone()));
        let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
        let mut outputs = vec![output];
        if how.whole_frame {
            outputs.push(HDR);
        }
        let coverage = lens_coverage(&mask, &settings, &eyes.eyes);
        Ok(CaseRun {
            case: case.clone(),
            settings,
            output,
            outputs,
            renderer,
            eyes,
            timing,
            timings: Vec::new(),
            coverage,
        })
    }

    /// One frame, not measured (warm-up).
    fn frame(&mut self) -> Result<vrao_render::renderer::FrameReport> {
        Ok(self.renderer.render_and_wait(&self.eyes.eyes, &self.outputs)?)
    }

    /// One measured frame: serial timing keeps each pass's wall-clock time; pipelined,
    /// its timestamps.
    fn timed_frame(&mut self) -> Result<()> {
        let report = self.frame()?;
        self.timings.push(if self.timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        Ok(())
    }

    /// The screen-space limits of the last frame for the radius and grid of `reference`
    /// (the march over its depth buffer and normals, [`screen_space_limit`]): with one
    /// depth layer, and with the second layer the renderer peels for two (the one-layer
    /// limit again where the scene can have nothing behind its first layer).
    fn screen_limits(&self, reference: &ReferenceImage, second: Option<&[Vec<f32>]>) -> Result<Limits> {
        let depth = self.renderer.read_f32(DEPTH)?;
        let normals = self.renderer.read_f32(NORMALS)?;
        let buffers: Vec<EyeBuffers> = (0..depth.len().min(normals.len()))
            .map(|k| EyeBuffers {
                depth: &depth[k],
                normals: &normals[k],
                fov: self.eyes.eyes[k].fov,
                direct: None,
                second: None,
            })
            .collect();
        let settings = LimitSettings::for_reference(reference, self.case.radius as f64, self.eyes.near);
        let size = (reference.width, reference.height);
        let one = screen_space_limit(&buffers, size, &settings)?;
        let two = match second {
            Some(second) => {
                let buffers: Vec<EyeBuffers> = buffers
                    .iter()
                    .zip(second)
                    .map(|(eye, second)| EyeBuffers { second: Some(second), ..*eye })
                    .collect();
                screen_space_limit(&buffers, size, &settings)?
            }
            None => one.clone(),
        };
        Ok(Limits { one, two })
    }

    /// The bounce's screen-space limit of the last frame (the limit's march with this
    /// frame's direct light), against the reference's bounce: its relative RMSE.
    fn bounce_limit(&self, reference: &ReferenceImage) -> Result<Option<f64>> {
        let depth = self.renderer.read_f32(DEPTH)?;
        let normals = self.renderer.read_f32(NORMALS)?;
        let direct = self.renderer.read_f32(vrao_render::passes::direct::DIRECT)?;
        let buffers: Vec<EyeBuffers> = (0..depth.len().min(normals.len()).min(direct.len()))
            .map(|k| EyeBuffers {
                depth: &depth[k],
                normals: &normals[k],
                fov: self.eyes.eyes[k].fov,
                direct: Some(&direct[k]),
                second: None,
            })
            .collect();
        let settings = LimitSettings::for_reference(reference, self.case.radius as f64, self.eyes.near);
        let limit = screen_space_limit(&buffers, (reference.width, reference.height), &settings)?;
        Ok(limit_bounce_rel_rmse(&limit, reference))
    }

    /// Pixels per degree of this case's eyes (the mean of both).
    fn pixels_per_degree(&self) -> f64 {
        let width = self.settings.profile.width;
        self.eyes.eyes.iter().map(|e| pixels_per_degree(&e.fov, width)).sum::<f64>() / self.eyes.eyes.len() as f64
    }

    /// Writes the left eye's final AO beside the one-layer limit, the two-layer limit and
    /// the reference (each traced cell over its stride's pixels) into `folder`, as
    /// [`comparison_image_name`]: where the row's error lies, to look at.
    fn write_comparison(&self, folder: &std::path::Path, reference: &ReferenceImage, limits: &Limits) -> Result<()> {
        let (w, h) = (self.settings.profile.width as usize, self.settings.profile.height as usize);
        let estimate = self.renderer.read_f32(self.output)?.swap_remove(0).into_iter().skip(3).step_by(4).collect();
        // Each traced cell's AO, unoccluded where nothing was hit.
        let grid = |cell: &dyn Fn(u32, u32) -> f32| grid_panel(w, h, reference.stride, reference.grid_size(), cell);
        let limit = |limit: &ScreenLimit, i, j| Some(limit.get(0, i, j)).filter(|p| p.hit).map_or(1.0, |p| p.ao);
        let panels = [
            estimate,
            grid(&|i, j| limit(&limits.one, i, j)),
            grid(&|i, j| limit(&limits.two, i, j)),
            grid(&|i, j| Some(reference.get(0, i, j)).filter(|p| p.hit).map_or(1.0, |p| p.ao)),
        ];
        std::fs::create_dir_all(folder)
            .map_err(|e| Error::Output { path: folder.into(), message: format!("cannot create this folder: {e}") })?;
        let path = folder.join(comparison_image_name(&self.case));
        save_panels(&path, w, h, &panels)?;
        log::info!("wrote {}", path.display());
        Ok(())
    }

    /// The row: medians of the measured frames, the last frame's stereo consistency, and
    /// with a reference its error (against the screen-space `limit` too when given).
    fn finish(mut self, reference: Option<&ReferenceImage>, limits: Option<&Limits>) -> Result<BenchRow> {
        let limit = limits.map(|l| &l.one);
        let (settings, output) = (&self.settings, self.output);
        // The measured frames' plan, before the bounce below renders a frame of another.
        let plan = self.renderer.last_plan().cloned().ok_or_else(|| Error::gpu("no frame was measured"))?;
        let spans = summarize(&self.timings);
        check_timed(&plan.names, &spans)?;
        let right_eye = self.renderer.right_eye_tiles();
        let occlusion = self.renderer.read_f32(output)?;
        let error = reference.map(|reference| {
            let fovs: Vec<_> = self.eyes.eyes.iter().map(|e| e.fov).collect();
            let ppd = self.pixels_per_degree();
            // Scored where the eye can see; with the mask off also over the whole rectangle.
            let visible = reference.visible_only(&self.coverage);
            let mut figures = score(self.case.technique, &occlusion, &visible, limit, ppd, &fovs);
            if let Some(limits) = limits {
                (figures.limit_two_layer_rmse, figures.limit_two_layer_bias) =
                    limit_against_reference(&limits.two, &visible);
            }
            let traced_whole = reference.layers.iter().flatten().filter(|p| p.hit).count()
                > visible.layers.iter().flatten().filter(|p| p.hit).count();
            if !self.case.mask && traced_whole {
                figures.ao_rmse_whole =
                    Some(score(self.case.technique, &occlusion, reference, limit, ppd, &fovs).ao_rmse);
            }
            figures
        });
        let stereo = {
            let mut depth = self.renderer.read_f32(DEPTH)?;
            // Points the lens hides in either eye count as unseen (as sky), mask on or off.
            for (layer, shown) in depth.iter_mut().zip(&self.coverage) {
                if let Some(shown) = shown {
                    layer.iter_mut().zip(shown).filter(|(_, &s)| s == 0).for_each(|(d, _)| *d = 0.0);
                }
            }
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
                without.ao.technique = settings.ao.technique.without_bounce();
                self.renderer.set_settings(&without)?;
                self.renderer.render(&self.eyes.eyes, &[output])?;
                let difference: Vec<Vec<f32>> = with
                    .iter()
                    .zip(self.renderer.read_f32(output)?)
                    .map(|(a, b)| a.iter().zip(b).map(|(a, b)| a - b).collect())
                    .collect();
                let figures = bounce_figures(&difference, settings.profile.width, 1, reference);
                let limit = self.bounce_limit(reference)?;
                figures.map(|f| BounceFigures { limit_rel_rmse: limit, ..f })
            }
            _ => None,
        };
        Ok(BenchRow {
            spans,
            views: 2,
            pass: settings.ao.pass_name(),
            occlusion_passes: plan.occlusion_passes(),
            error,
            bounce,
            stereo,
            right_eye,
            case: self.case,
        })
    }
}

/// The graph pass of reflective shadow maps' gather, whose name bench rows of it also
/// carry as their technique ("rsm").
pub const RSM_PASS: &str = rsm::NAME;

/// Fails when a pass of `ran` has no span in `spans`: a pass's cost is looked up by its
/// name, and one timed under another name would otherwise read as 0 ms.
fn check_timed(ran: &[&'static str], spans: &[SpanSummary]) -> Result<()> {
    match ran.iter().find(|pass| !spans.iter().any(|s| s.label == **pass)) {
        Some(pass) => Err(Error::gpu(format!("pass '{pass}' ran but no GPU time was measured under its name"))),
        None => Ok(()),
    }
}

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
    if vrao_render::passes::shadow::shadow_casters(scene).is_empty() {
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
    let mut ran = Vec::new();
    for frame in 0..warmup + frames {
        let report = renderer.render_and_wait(&eyes.eyes, &[RSM_INDIRECT])?;
        ran = report.plan.names;
        if frame >= warmup {
            timings.push(if timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        }
    }
    let spans = summarize(&timings);
    check_timed(&ran, &spans)?;
    let bounce = match reference {
        Some(reference) => {
            let irradiance = renderer.read_f32(RSM_INDIRECT)?;
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
        layers: 1,
        temporal: false,
        foveation: Foveation::Off,
        mask: settings.ao.mask,
    };
    Ok(BenchRow {
        case,
        spans,
        views: 2,
        pass: RSM_PASS,
        occlusion_passes: vec![RSM_PASS, shadow::NAME],
        error: None,
        bounce,
        stereo: None,
        right_eye: Vec::new(),
    })
}

/// A one-bounce irradiance estimate against the reference's `bounce`, by luminance over
/// the reference's hit pixels (both eyes), relative to the reference's mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BounceFigures {
    /// RMSE / mean of the reference, the reference's own noise (its per-pixel standard
    /// errors) taken out in quadrature as for the AO.
    pub rel_rmse: f64,
    /// (mean of the estimate − mean of the reference) / mean of the reference.
    pub rel_bias: f64,
    /// [`Self::rel_rmse`] per colour channel (r, g, b), each relative to its own mean
    /// (NaN for a channel the reference has no bounce in).
    #[serde(default)]
    pub rel_rmse_rgb: [f64; 3],
    /// The bounce's screen-space limit (a march of many rays over the frame's own depth
    /// and direct light, `screen_limit`) against the reference's bounce: the
    /// [`Self::rel_rmse`] no depth-buffer bounce can go below.
    #[serde(default)]
    pub limit_rel_rmse: Option<f64>,
}

/// The relative RMSE (luminance, the reference's noise taken out) of a screen-space
/// limit's bounce against the reference's, on the reference's grid; `None` when the
/// grids differ or the reference has no bounce.
pub fn limit_bounce_rel_rmse(limit: &ScreenLimit, reference: &ReferenceImage) -> Option<f64> {
    if limit.grid_size() != reference.grid_size() {
        return None;
    }
    let (gw, gh) = reference.grid_size();
    let (mut n, mut sum_ref, mut sum_sq, mut noise2) = (0usize, 0f64, 0f64, 0f64);
    for layer in 0..reference.layers.len().min(limit.layers.len()) {
        for j in 0..gh {
            for i in 0..gw {
                let r = reference.get(layer, i, j);
                let l = limit.get(layer, i, j);
                if !r.hit || !l.hit {
                    continue;
                }
                let (e, truth) = (luminance(l.bounce), luminance(r.bounce));
                n += 1;
                sum_ref += truth;
                sum_sq += (e - truth) * (e - truth);
                noise2 += (r.bounce_std_error[3] as f64).powi(2);
            }
        }
    }
    let n_f = n.max(1) as f64;
    let mean = sum_ref / n_f;
    (n > 0 && mean > 1e-9)
        .then(|| crate::measure::metrics::noise_corrected_rmse((sum_sq / n_f).sqrt(), (noise2 / n_f).sqrt()) / mean)
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
    // Per channel r, g, b and luminance: sums of the reference, the estimate, the squared
    // difference and the reference's variance.
    let (mut n, mut sum_ref, mut sum_est, mut sum_sq, mut noise2) =
        (0usize, [0f64; 4], [0f64; 4], [0f64; 4], [0f64; 4]);
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
                let e = [t[0] as f64, t[1] as f64, t[2] as f64, luminance([t[0], t[1], t[2]])];
                let b = r.bounce;
                let truth = [b[0] as f64, b[1] as f64, b[2] as f64, luminance(b)];
                n += 1;
                for k in 0..4 {
                    sum_ref[k] += truth[k];
                    sum_est[k] += e[k];
                    sum_sq[k] += (e[k] - truth[k]) * (e[k] - truth[k]);
                    noise2[k] += (r.bounce_std_error[k] as f64).powi(2);
                }
            }
        }
    }
    let n_f = n.max(1) as f64;
    let rel_rmse = |k: usize| {
        let mean = sum_ref[k] / n_f;
        let rmse = crate::measure::metrics::noise_corrected_rmse((sum_sq[k] / n_f).sqrt(), (noise2[k] / n_f).sqrt());
        if mean > 1e-9 {
            rmse / mean
        } else {
            f64::NAN
        }
    };
    let mean = sum_ref[3] / n_f;
    (n > 0 && mean > 1e-9).then(|| BounceFigures {
        rel_rmse: rel_rmse(3),
        rel_bias: (sum_est[3] - sum_ref[3]) / n_f / mean,
        rel_rmse_rgb: [0, 1, 2].map(rel_rmse),
        limit_rel_rmse: None,
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
/// and their ratios stay fair; 1 measures each case on its own, in a row. With `images`,
/// each scored row's comparison image is written there, named by [`comparison_image_name`].
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    cases: &[BenchCase],
    how: Measurement,
    references: &[(f32, ReferenceImage)],
    images: Option<&std::path::Path>,
    mut progress: impl FnMut(usize, usize, &BenchRow),
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::with_capacity(cases.len());
    let mut limits: Vec<(f32, Limits)> = Vec::new();
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
            // The limits depend only on the frame's depth layers and normals (the same
            // G-buffer for every case; the second layer with the sweep's one separation)
            // and the radius: marched once per radius, for its first row.
            if let Some(reference) = reference {
                if !limits.iter().any(|(r, _)| *r == run.case.radius) {
                    let second = second_layer(gpu, scene, base, &run.case, how)?;
                    limits.push((run.case.radius, run.screen_limits(reference, second.as_deref())?));
                }
            }
            let limit = limits.iter().find(|(r, _)| *r == run.case.radius).map(|(_, l)| l);
            if let (Some(folder), Some(reference), Some(limit)) = (images, reference, limit) {
                run.write_comparison(folder, reference, limit)?;
            }
            let row = run.finish(reference, limit)?;
            progress(rows.len() + 1, cases.len(), &row);
            rows.push(row);
        }
    }
    Ok(rows)
}
