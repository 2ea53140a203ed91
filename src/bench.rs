//! Sweeps of technique × samples × radius × resolution: the median GPU time of every
//! pass per eye over many frames, as a table, CSV and Markdown. (Error against the
//! reference tracer joins these rows when the tracer exists.)

use crate::analytic::luminance;
use crate::error::{Error, Result};
use crate::gpu::timing::{summarize, SpanSummary};
use crate::gpu::Gpu;
use crate::metrics;
use crate::passes::final_occlusion;
use crate::plot::{ScatterPlot, Series};
use crate::reference::ReferenceImage;
use crate::renderer::{Renderer, Timing};
use crate::scene::Scene;
use crate::settings::{Settings, Technique};
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
        if self.pass == RSM_PASS {
            return (self.median_ms(RSM_PASS) + self.median_ms("shadow")) / self.views as f64;
        }
        let passes = [self.pass, "depth-peel", "temporal", "blur", "upsample"];
        passes.iter().map(|p| self.median_ms(p)).sum::<f64>() / self.views as f64
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
    run.finish(reference)
}

/// One case being measured: its renderer, and the per-pass times of its frames so far.
/// Kept apart from the loop so that a sweep can interleave cases frame by frame.
struct CaseRun {
    case: BenchCase,
    settings: Settings,
    output: crate::graph::Resource,
    /// What each frame renders: the occlusion, and with `whole_frame` the lit image.
    outputs: Vec<crate::graph::Resource>,
    renderer: Renderer,
    eyes: crate::stereo::EyePair,
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
            outputs.push(crate::graph::Resource::Hdr);
        }
        Ok(CaseRun { case: case.clone(), settings, output, outputs, renderer, eyes, timing, timings: Vec::new() })
    }

    /// One frame, not measured (warm-up).
    fn frame(&mut self) -> Result<crate::renderer::FrameReport> {
        self.renderer.render(&self.eyes.eyes, &self.outputs)
    }

    /// One measured frame: serial timing keeps each pass's wall-clock time; pipelined,
    /// its timestamps.
    fn timed_frame(&mut self) -> Result<()> {
        let report = self.frame()?;
        self.timings.push(if self.timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        Ok(())
    }

    /// The row: medians of the measured frames, and the last frame's error.
    fn finish(mut self, reference: Option<&ReferenceImage>) -> Result<BenchRow> {
        let (settings, output) = (&self.settings, self.output);
        let error = match reference {
            Some(reference) => Some(error_figures(self.case.technique, &self.renderer.read_f32(output)?, reference)),
            None => None,
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
    if crate::passes::shadow::shadow_casters(scene).is_empty() {
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
        let report = renderer.render(&eyes.eyes, &[crate::graph::Resource::RsmIndirect])?;
        if frame >= warmup {
            timings.push(if timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        }
    }
    let bounce = match reference {
        Some(reference) => {
            let irradiance = renderer.read_f32(crate::graph::Resource::RsmIndirect)?;
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
    Ok(BenchRow { case, spans: summarize(&timings), views: 2, pass: RSM_PASS, error: None, bounce })
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

/// Runs every case, calling `progress(done, total, row)` after each. `references` holds
/// a reference image per radius (cases whose radius has none get no error figures).
/// `interleave` cases at a time are measured round-robin, one frame each per round, so
/// that a slow drift of the machine (other load, clocks, heat) falls on all of them alike
/// and their ratios stay fair; 1 measures each case on its own, in a row.
pub fn sweep(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    cases: &[BenchCase],
    how: Measurement,
    interleave: usize,
    references: &[(f32, ReferenceImage)],
    mut progress: impl FnMut(usize, usize, &BenchRow),
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::with_capacity(cases.len());
    for group in cases.chunks(interleave.max(1)) {
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
            let row = run.finish(reference)?;
            progress(rows.len() + 1, cases.len(), &row);
            rows.push(row);
        }
    }
    Ok(rows)
}

/// How far one row's occlusion is from the reference tracer's, on the pixels the
/// reference traced (both eyes; sky excluded).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorFigures {
    /// RMSE of the AO (`.a`) against the reference the technique approximates (HBAO: with
    /// its linear falloff), with the reference's own noise taken out in quadrature.
    pub ao_rmse: f64,
    /// Mean SSIM of the AO images against the reference (1 = identical), per eye averaged.
    pub ao_ssim: f64,
    /// RMSE of the ambient light's luminance (what the composite multiplies by albedo/π)
    /// relative to the reference's mean: environment light that gets through within r
    /// plus one bounce of direct light from surfaces within r. Comparable across
    /// techniques; `None` when the reference has no ambient light at all.
    pub ambient_rel_rmse: Option<f64>,
}

/// Compares the occlusion a frame produced (per layer, RGBA at the full image size) with
/// the reference on its grid of traced pixels.
pub fn error_figures(technique: Technique, occlusion: &[Vec<f32>], reference: &ReferenceImage) -> ErrorFigures {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let stride = reference.stride.max(1) as usize;
    let (gw, gh) = (w.div_ceil(stride), h.div_ceil(stride));
    let (mut gpu_ao, mut ref_ao, mut noise2, mut mask) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut gpu_ambient, mut ref_ambient) = (Vec::new(), Vec::new());
    let mut ssim_sum = 0.0;
    for (layer, pixels) in reference.layers.iter().enumerate() {
        let image = &occlusion[layer];
        let first = gpu_ao.len();
        for gy in 0..gh {
            for gx in 0..gw {
                let r = &pixels[gy * gw + gx];
                let (x, y) = ((gx * stride + stride / 2).min(w - 1), (gy * stride + stride / 2).min(h - 1));
                let texel = &image[(y * w + x) * 4..(y * w + x) * 4 + 4];
                let target = if technique == Technique::Hbao { r.ao_falloff } else { r.ao };
                gpu_ao.push(texel[3]);
                ref_ao.push(target);
                mask.push(r.hit);
                noise2.push(if r.hit { (r.ao_std_error as f64).powi(2) } else { 0.0 });
                let ambient = match technique {
                    Technique::Ssdo | Technique::SsdoBounce => [texel[0], texel[1], texel[2]],
                    _ => r.unoccluded.map(|c| c * texel[3]),
                };
                let truth = [0, 1, 2].map(|c| r.environment_visible[c] + r.bounce[c]);
                gpu_ambient.push(luminance(ambient) as f32);
                ref_ambient.push(luminance(truth) as f32);
            }
        }
        let range = first..gpu_ao.len();
        ssim_sum += metrics::ssim(&gpu_ao[range.clone()], &ref_ao[range.clone()], gw, gh, Some(&mask[range]), 1.0)
            .unwrap_or(0.0);
    }
    let hits = mask.iter().filter(|&&m| m).count().max(1) as f64;
    let noise = (noise2.iter().sum::<f64>() / hits).sqrt();
    let ao_rmse =
        metrics::noise_corrected_rmse(metrics::rmse(&gpu_ao, &ref_ao, Some(&mask)).unwrap_or(f64::NAN), noise);
    let mean_ambient = ref_ambient.iter().zip(&mask).filter(|(_, &m)| m).map(|(&a, _)| a as f64).sum::<f64>() / hits;
    let ambient_rel_rmse = (mean_ambient > 1e-12)
        .then(|| metrics::rmse(&gpu_ambient, &ref_ambient, Some(&mask)).map(|e| e / mean_ambient))
        .flatten();
    ErrorFigures { ao_rmse, ao_ssim: ssim_sum / reference.layers.len().max(1) as f64, ambient_rel_rmse }
}

/// One row as written to CSV, JSON and Markdown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchRecord {
    pub technique: String,
    pub samples: u32,
    pub radius_m: f32,
    pub resolution: String,
    pub technique_ms_per_eye: f64,
    pub blur_ms_per_eye: f64,
    pub upsample_ms_per_eye: f64,
    /// Technique + blur + upsample per eye: the occlusion's cost.
    pub occlusion_ms_per_eye: f64,
    /// p75 / p25 of the technique pass: the run-to-run spread.
    pub p75_over_p25: f64,
    pub ao_rmse: Option<f64>,
    pub ao_ssim: Option<f64>,
    pub ambient_rel_rmse: Option<f64>,
    /// On the Pareto front of AO RMSE against occlusion ms per eye.
    pub pareto: bool,
    /// SSDO with depth peeling; its second-layer pass is in `occlusion_ms_per_eye`.
    #[serde(default)]
    pub depth_peeling: bool,
    #[serde(default)]
    pub peel_ms_per_eye: f64,
    /// One-bounce irradiance against the reference's bounce (ssdo-bounce, rsm rows).
    #[serde(default)]
    pub bounce_rel_rmse: Option<f64>,
    #[serde(default)]
    pub bounce_rel_bias: Option<f64>,
    /// Temporal accumulation on; its pass is in `occlusion_ms_per_eye`.
    #[serde(default)]
    pub temporal: bool,
    /// The composite (bench `--frame`; 0 without). At half resolution it upsamples the
    /// occlusion inline, as every frame does.
    #[serde(default)]
    pub composite_ms_per_eye: f64,
    /// Half-resolution rows with `--frame`: what upsampling costs a frame, this row's
    /// composite minus the composite of the same case at full resolution (measured in
    /// the same sweep). Frames do not run the stand-alone upsample pass.
    #[serde(default)]
    pub frame_upsample_ms_per_eye: Option<f64>,
}

impl BenchRecord {
    pub fn setting(&self) -> String {
        let peel = if self.depth_peeling { " peeled" } else { "" };
        let temporal = if self.temporal { " temporal" } else { "" };
        format!("{}{peel}{temporal} N={} r={} m {}", self.technique, self.samples, self.radius_m, self.resolution)
    }
}

/// A whole sweep: where it ran, how, and every row.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchFile {
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub driver: String,
    pub width: u32,
    pub height: u32,
    pub timing: String,
    pub warmup: u32,
    pub frames: u32,
    /// The reference tracer's settings and noise, when errors were measured.
    pub reference: Option<ReferenceInfo>,
    pub records: Vec<BenchRecord>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub rays_per_pixel: u32,
    pub stride: u32,
    /// RMS over hit pixels of the reference AO's standard error (worst radius).
    pub ao_noise_rms: f64,
    /// Tracer throughput on this machine (rays per second, all cores), when it traced.
    pub rays_per_second: Option<f64>,
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

const COLUMNS: [&str; 20] = [
    "technique",
    "samples",
    "radius_m",
    "resolution",
    "technique_ms_per_eye",
    "blur_ms_per_eye",
    "upsample_ms_per_eye",
    "occlusion_ms_per_eye",
    "p75_over_p25",
    "ao_rmse",
    "ao_ssim",
    "ambient_rel_rmse",
    "pareto",
    "depth_peeling",
    "peel_ms_per_eye",
    "bounce_rel_rmse",
    "bounce_rel_bias",
    "temporal",
    "composite_ms_per_eye",
    "frame_upsample_ms_per_eye",
];

fn record_values(r: &BenchRecord) -> [String; 20] {
    let optional = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.4}"));
    [
        r.technique.clone(),
        r.samples.to_string(),
        format!("{}", r.radius_m),
        r.resolution.clone(),
        format!("{:.3}", r.technique_ms_per_eye),
        format!("{:.3}", r.blur_ms_per_eye),
        format!("{:.3}", r.upsample_ms_per_eye),
        format!("{:.3}", r.occlusion_ms_per_eye),
        format!("{:.3}", r.p75_over_p25),
        optional(r.ao_rmse),
        optional(r.ao_ssim),
        optional(r.ambient_rel_rmse),
        if r.pareto { "yes" } else { "" }.to_string(),
        if r.depth_peeling { "yes" } else { "" }.to_string(),
        format!("{:.3}", r.peel_ms_per_eye),
        optional(r.bounce_rel_rmse),
        optional(r.bounce_rel_bias),
        if r.temporal { "yes" } else { "" }.to_string(),
        format!("{:.3}", r.composite_ms_per_eye),
        r.frame_upsample_ms_per_eye.map_or(String::new(), |v| format!("{v:.3}")),
    ]
}

pub fn to_csv(records: &[BenchRecord]) -> String {
    let mut s = COLUMNS.join(",") + "\n";
    for r in records {
        s += &(record_values(r).join(",") + "\n");
    }
    s
}

pub fn to_markdown(records: &[BenchRecord]) -> String {
    let mut s = format!("| {} |\n|{}\n", COLUMNS.join(" | "), "---|".repeat(COLUMNS.len()));
    for r in records {
        let _ = writeln!(s, "| {} |", record_values(r).join(" | "));
    }
    s
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
            half.radius_m,
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
                    r.technique, r.samples, r.radius_m, r.resolution
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

/// The plot of error against per-eye ms for the rows of one radius, with that radius's
/// Pareto front and the budget line.
pub fn plot(file: &BenchFile, radius_m: f32, budget_ms_per_eye: f64) -> ScatterPlot {
    const COLOURS: [[u8; 3]; 8] = [
        [31, 119, 180],
        [255, 127, 14],
        [44, 160, 44],
        [214, 39, 40],
        [148, 103, 189],
        [140, 86, 75],
        [23, 190, 207],
        [188, 189, 34],
    ];
    let rows: Vec<&BenchRecord> =
        file.records.iter().filter(|r| r.radius_m == radius_m && r.ao_rmse.is_some()).collect();
    let mut series: Vec<Series> = Vec::new();
    for r in &rows {
        let label = format!(
            "{}{}{} {}",
            r.technique,
            if r.depth_peeling { " peeled" } else { "" },
            if r.temporal { " temporal" } else { "" },
            r.resolution
        );
        let point = (r.occlusion_ms_per_eye, r.ao_rmse.unwrap_or(f64::NAN));
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push(point),
            None => {
                let color = COLOURS[series.len() % COLOURS.len()];
                series.push(Series { label, color, points: vec![point] });
            }
        }
    }
    let mut pareto: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.pareto).map(|r| (r.occlusion_ms_per_eye, r.ao_rmse.unwrap_or(f64::NAN))).collect();
    pareto.sort_by(|a, b| a.0.total_cmp(&b.0));
    ScatterPlot {
        title: format!(
            "{}: AO error against time, r = {radius_m} m, {}x{} per eye, {}",
            file.scene, file.width, file.height, file.adapter
        ),
        x_label: "occlusion ms per eye (technique + blur + upsample)".into(),
        y_label: "AO RMSE vs reference".into(),
        series,
        pareto,
        vertical_line: Some((budget_ms_per_eye, format!("budget {budget_ms_per_eye:.2} ms/eye"))),
        log_x: true,
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
            error: Some(ErrorFigures { ao_rmse, ao_ssim: 0.9, ambient_rel_rmse: None }),
            bounce: None,
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
            records,
        }
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
        assert!(csv
            .lines()
            .nth(2)
            .unwrap()
            .starts_with("hbao,12,0.5,full,6.000,1.000,0.000,7.000,1.000,0.2000,0.9000,,"));
        assert_eq!(to_markdown(&recs).lines().count(), 4);
        let json = to_json(&file(recs.clone()));
        let back: BenchFile = serde_json::from_str(&json).unwrap();
        assert_eq!(back.records, recs);
    }
}
