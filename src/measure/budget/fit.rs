//! `vrao budget` as one call: open the device, optionally pick the setting from a bench
//! file (the least AO error that fits the budget), and measure it.

use super::{run, settle, BudgetReport, BudgetRun, Scope};
use crate::error::{Error, Result};
use crate::measure::bench::{BenchFile, BenchRecord};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use vrao_ao::plug::Gpu;
use vrao_ao::{AoSettings, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::renderer::{Renderer, TimingChoice};
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;
use vrao_render::BackendChoice;

/// How [`measure_budget`] measures.
#[derive(Clone, Debug)]
pub struct BudgetOptions {
    /// Which wgpu backend to ask for.
    pub backend: BackendChoice,
    /// Serial, pipelined or auto (decided once the adapter is known).
    pub timing: TimingChoice,
    /// Measured frames (each: the stereo frame, then each eye alone), after warm-up.
    pub frames: u32,
    /// Frames discarded before timing.
    pub warmup: u32,
    /// The stereo frame budget in ms; `None`: the profile's refresh interval.
    pub budget_ms: Option<f64>,
    /// Measure the occlusion passes alone instead of the whole frame.
    pub occlusion_only: bool,
    /// A bench JSON (made by `vrao bench` on this device) to pick the setting from.
    pub fit: Option<PathBuf>,
}

/// The setting `--fit` chose and why.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The AO settings of the chosen row.
    pub ao: AoSettings,
    /// Whether the chosen row's point-sampled SSDO peeled a second layer.
    pub depth_peeling: bool,
    /// Doubts about the bench file (measured at another size).
    pub warnings: Vec<String>,
    /// Which row was chosen, and why ("fit: ...").
    pub notes: Vec<String>,
}

/// What [`measure_budget`] measured.
#[derive(Clone, Debug)]
pub struct BudgetOutcome {
    /// The measured times and verdicts.
    pub report: BudgetReport,
    /// The setting `--fit` chose, when it was asked for.
    pub fit: Option<Fit>,
}

/// Measures `settings` (or, with `options.fit`, the bench row that fits the budget best)
/// on `scene` against the frame budget.
pub fn measure_budget(scene: &Scene, settings: &Settings, options: &BudgetOptions) -> Result<BudgetOutcome> {
    let budget_ms = options.budget_ms.unwrap_or(settings.profile.budget_ms());
    if !(budget_ms.is_finite() && budget_ms > 0.0) {
        return Err(Error::input(format!("the frame budget {budget_ms} ms must be a positive number")));
    }
    settings.validate()?;
    crate::measure::check_frames(options.warmup, options.frames)?;
    let fit_file = match &options.fit {
        Some(path) => Some((crate::measure::bench::read_json(path)?, path)),
        None => None,
    };
    let gpu = Arc::new(vrao_render::open(options.backend)?);
    let timing = options.timing.resolve(&gpu);
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let settled = std::cell::Cell::new(false);
    let measure = |settings: &Settings, frames: u32| -> Result<BudgetReport> {
        let output = if options.occlusion_only {
            if settings.ao.technique == vrao_ao::Technique::None {
                return Err(Error::input("measuring the occlusion alone needs an occlusion technique, not none"));
            }
            vrao_ao::plug::FINAL_AO
        } else {
            COLOR
        };
        let mut renderer = Renderer::new(gpu.clone(), scene, settings)?;
        // The profile's lens, as a headset run has it (the passes skip it with `--mask on`).
        renderer.set_visibility_mask(Some(crate::xr::profiles::visibility_mask(&settings.profile)));
        let how = BudgetRun { timing, warmup: options.warmup, frames, budget_ms, output };
        // The device's clocks come up once, before the first setting measured.
        if !settled.replace(true) {
            settle(&mut renderer, &eyes, how)?;
        }
        run(&mut renderer, &eyes, how)
    };
    let mut settings = settings.clone();
    let fit = match fit_file {
        Some((file, path)) => {
            let fit = fit_setting(&file, path, &gpu, &settings, budget_ms, options.occlusion_only, measure)?;
            settings.ao = fit.ao.clone();
            settings.point_ssdo.depth_peeling = fit.depth_peeling;
            Some(fit)
        }
        None => None,
    };
    let report = measure(&settings, options.frames)?;
    Ok(BudgetOutcome { report, fit })
}

/// `--fit`: the bench row with the least AO error whose occlusion cost fits what the
/// budget leaves per eye after the passes every frame pays (measured here with no
/// occlusion, by `measure(settings, frames)`), returned as the settings to measure.
pub fn fit_setting(
    file: &BenchFile,
    path: &Path,
    gpu: &Gpu,
    settings: &Settings,
    budget_ms: f64,
    occlusion_only: bool,
    measure: impl Fn(&Settings, u32) -> Result<BudgetReport>,
) -> Result<Fit> {
    let adapter = gpu.info.name.clone();
    if file.adapter != adapter {
        return Err(Error::in_file(
            path,
            format!("was measured on '{}', not on this device '{adapter}'; run vrao bench here first", file.adapter),
        ));
    }
    let (mut warnings, mut notes) = (Vec::new(), Vec::new());
    if (file.width, file.height) != (settings.profile.width, settings.profile.height) {
        warnings.push(format!(
            "warning: {} was measured at {}x{} per eye, this budget is for {}x{}",
            path.display(),
            file.width,
            file.height,
            settings.profile.width,
            settings.profile.height
        ));
    }
    // What every frame pays besides the occlusion, per eye (eyes measured alone).
    let base_ms = if occlusion_only {
        0.0
    } else {
        let mut base = settings.clone();
        base.ao.technique = Technique::None;
        let report = measure(&base, 5)?;
        report.verdicts.iter().filter(|v| v.what != Scope::StereoFrame).map(|v| v.ms).fold(0.0, f64::max)
    };
    let left_per_eye = budget_ms / 2.0 - base_ms;
    let chosen = choose_row(file, path, settings.ao.radius, left_per_eye, base_ms, &mut notes)?;
    let mut ao = settings.ao.clone();
    ao.technique = chosen.technique.parse().map_err(|e: vrao_ao::Error| Error::in_file(path, e.to_string()))?;
    ao.samples = chosen.samples;
    ao.radius = chosen.radius_m;
    ao.resolution = chosen.resolution;
    Ok(Fit { ao, depth_peeling: chosen.depth_peeling, warnings, notes })
}

/// The bench row with the least AO error among those at the bench radius nearest to
/// `radius_asked` whose occlusion fits `left_per_eye` ms per eye (what the budget leaves
/// after `base_ms` of the other passes), or the cheapest when none fits; `notes` say
/// which and why.
fn choose_row<'a>(
    file: &'a BenchFile,
    path: &Path,
    radius_asked: f32,
    left_per_eye: f64,
    base_ms: f64,
    notes: &mut Vec<String>,
) -> Result<&'a BenchRecord> {
    // Errors compare only within one radius (each radius is its own target quantity):
    // take the rows of the radius asked for, or of the bench radius nearest to it.
    let measured: Vec<_> = file.records.iter().filter(|r| r.ao_rmse.is_some_and(f64::is_finite)).collect();
    let Some(radius) = measured
        .iter()
        .map(|r| r.radius_m)
        .min_by(|a, b| (a - radius_asked).abs().total_cmp(&(b - radius_asked).abs()))
    else {
        return Err(Error::in_file(path, "has no rows with an error against the reference"));
    };
    if radius != radius_asked {
        notes.push(format!(
            "fit: the bench has no rows at r = {} m; using its nearest radius, {radius} m",
            radius_asked
        ));
    }
    let with_error: Vec<_> = measured.into_iter().filter(|r| r.radius_m == radius).collect();
    let fitting: Vec<_> = with_error.iter().filter(|r| r.occlusion_ms_per_eye <= left_per_eye).collect();
    let chosen = match fitting.iter().min_by(|a, b| a.ao_rmse.unwrap().total_cmp(&b.ao_rmse.unwrap())) {
        Some(r) => {
            notes.push(format!(
                "fit: {} — AO RMSE {:.4}, the least of the {} of {} bench rows whose occlusion ({:.3} ms per eye) fits the {:.3} ms per eye left after {:.3} ms of the other passes",
                r.setting(),
                r.ao_rmse.unwrap(),
                fitting.len(),
                with_error.len(),
                r.occlusion_ms_per_eye,
                left_per_eye,
                base_ms
            ));
            r
        }
        None => {
            let cheapest =
                with_error.iter().min_by(|a, b| a.occlusion_ms_per_eye.total_cmp(&b.occlusion_ms_per_eye)).unwrap();
            notes.push(format!(
                "fit: no bench row fits the {:.3} ms per eye left after {:.3} ms of the other passes; the cheapest, {} ({:.3} ms per eye), is measured",
                left_per_eye, base_ms, cheapest.setting(), cheapest.occlusion_ms_per_eye
            ));
            cheapest
        }
    };
    Ok(chosen)
}
