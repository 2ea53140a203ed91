//! `vrao bench` as library calls: expand the options into cases, trace a reference per
//! radius, sweep, and write the table, CSV, JSON, Markdown and plots.

use super::{
    estimate_seconds, mark_pareto, markdown_report, measure_rsm, pixels_per_degree, plot, read_json, records, sweep,
    to_csv, to_json, BenchCase, BenchFile, BenchRecord, BenchRow, LimitInfo, Measurement, ReferenceInfo, Resolution,
};
use crate::error::{Error, Result};
use crate::measure::reference::{trace_cached_visible, ProgressBar, ReferenceImage, ReferenceSettings};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use vrao_ao::plug::Gpu;
use vrao_ao::{Foveation, Technique};
use vrao_render::renderer::TimingChoice;
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;
use vrao_render::BackendChoice;

/// What a bench sweeps and how it measures.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Which wgpu backend to ask for.
    pub backend: BackendChoice,
    /// Techniques to sweep.
    pub techniques: Vec<Technique>,
    /// Samples per pixel (N) to sweep.
    pub samples: Vec<u32>,
    /// Radii in metres (empty: the scene's suggested radius × 0.5, 1 and 2).
    pub radii: Vec<f32>,
    /// The resolutions (`true`: half), depth-peeling and temporal modes to sweep; depth
    /// peeling applies to the SSDO techniques only.
    pub half_res: Vec<bool>,
    /// Depth peeling off/on to sweep (SSDO techniques only).
    pub depth_peeling: Vec<bool>,
    /// Depth layers to sweep (1, 2; 2 only for the techniques that read a second layer).
    pub layers: Vec<u32>,
    /// Temporal accumulation off/on to sweep.
    pub temporal: Vec<bool>,
    /// Foveation levels to sweep.
    pub foveation: Vec<Foveation>,
    /// The visibility mask off (`false`) and on to sweep.
    pub mask: Vec<bool>,
    /// VPL counts of reflective-shadow-map rows (empty: none).
    pub rsm_samples: Vec<u32>,
    /// Serial, pipelined or auto (decided once the adapter is known).
    pub timing: TimingChoice,
    /// Frames discarded before timing, per case.
    pub warmup: u32,
    /// Frames timed per case.
    pub frames: u32,
    /// Cases measured at a time, round-robin one frame each (1: each case on its own).
    pub interleave: usize,
    /// Render whole frames, not only the occlusion.
    pub whole_frame: bool,
    /// Trace a reference to score each row (`None`: timing only).
    pub reference: Option<ReferenceOptions>,
    /// The command line that ran the bench, kept in bench.json.
    pub command: String,
    /// A folder for each scored row's comparison image ([`super::comparison_image_name`]):
    /// `None` writes none.
    pub images: Option<PathBuf>,
}

/// The reference each row is scored against.
#[derive(Clone, Debug)]
pub struct ReferenceOptions {
    /// Rays traced per pixel (1..=`MAX_RAYS_PER_PIXEL`).
    pub rays_per_pixel: u32,
    /// Traced at every `stride`-th pixel in x and y.
    pub stride: u32,
    /// Where traced images are cached ([`crate::measure::reference::default_cache_dir`]).
    pub cache: PathBuf,
}

/// A measured (or re-read) bench: its file, the radii it covers and the adapter that
/// measured it.
#[derive(Clone, Debug)]
pub struct BenchRun {
    /// What was measured, as written to bench.json.
    pub file: BenchFile,
    /// The radii (m) the rows cover: as given, or the scene's suggested radius × 0.5, 1 and 2.
    pub radii: Vec<f32>,
    /// "name (backend, driver)".
    pub adapter: String,
}

/// The cases of a sweep, in order: technique × samples × radius × resolution × depth
/// peeling (SSDO only) × layers (2 for GTAO and SSDO only) × temporal × mask × foveation.
/// Layers sit next to each other, so `--interleave 2` times 1 and 2 layers together.
pub fn cases(options: &BenchOptions, radii: &[f32]) -> Vec<BenchCase> {
    let mut cases = Vec::new();
    for &technique in &options.techniques {
        for &samples in &options.samples {
            for &radius in radii {
                for &half_res in &options.half_res {
                    for &depth_peeling in &options.depth_peeling {
                        if depth_peeling && !technique.carries_light() {
                            continue;
                        }
                        for &layers in &options.layers {
                            if layers == 2 && !technique.reads_second_layer() {
                                continue;
                            }
                            for &temporal in &options.temporal {
                                for &mask in &options.mask {
                                    for &foveation in &options.foveation {
                                        cases.push(BenchCase {
                                            technique,
                                            samples,
                                            radius,
                                            half_res,
                                            depth_peeling,
                                            layers,
                                            temporal,
                                            foveation,
                                            mask,
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    cases
}

/// Sweeps `options` over `scene`; `base` gives everything the cases do not vary (the
/// per-eye size, denoise, bounce form, GTAO parameters). Logs its progress (info).
pub fn run_bench(scene: &Scene, base: &Settings, options: &BenchOptions) -> Result<BenchRun> {
    let radii = if options.radii.is_empty() {
        let r = scene.suggested_ao_radius();
        vec![r * 0.5, r, r * 2.0]
    } else {
        options.radii.clone()
    };
    let cases = cases(options, &radii);
    check_options(scene, base, options, &cases)?;
    let gpu = Arc::new(vrao_render::open(options.backend)?);
    let info = gpu.info.clone();
    let timing = options.timing.resolve(&gpu);
    let (width, height) = (base.profile.width, base.profile.height);
    let eyes = base.profile.eyes(&scene.head.pose_at(0.0), base.near);
    let (references, reference_info) = match &options.reference {
        Some(reference) => {
            // Rows with the mask off are scored over the whole rectangle too; with every
            // row masked the tracer leaves out what the lens hides.
            let coverage = options.mask.iter().all(|&m| m).then(|| {
                crate::measure::bench::lens_coverage(
                    &crate::xr::profiles::visibility_mask(&base.profile),
                    base,
                    &eyes.eyes,
                )
            });
            let (images, info) = trace_references(scene, base, &eyes.eyes, &radii, reference, coverage.as_deref())?;
            (images, Some(info))
        }
        None => (Vec::new(), None),
    };
    log::info!(
        "bench: {} cases on '{}' ({}), {width}x{height} per eye, {} frames each, {timing:?} timing",
        cases.len(),
        scene.name,
        info.name,
        options.frames
    );
    let how = Measurement {
        timing,
        warmup: options.warmup,
        frames: options.frames,
        whole_frame: options.whole_frame,
        interleave: options.interleave,
    };
    log_estimate(&gpu, scene, base, &cases, how)?;
    let started = std::time::Instant::now();
    let mut rows =
        sweep(&gpu, scene, base, &cases, how, &references, options.images.as_deref(), |done, total, row| {
            log::info!("{}", progress_line(done, total, row, started.elapsed().as_secs_f64()));
        })?;
    rows.extend(rsm_rows(&gpu, scene, base, options, &radii, how, &references)?);
    let file = BenchFile {
        scene: scene.name.clone(),
        adapter: info.name.clone(),
        backend: format!("{:?}", info.backend),
        driver: info.driver_info.clone(),
        width,
        height,
        timing: format!("{timing:?}").to_lowercase(),
        warmup: options.warmup,
        frames: options.frames,
        limit: reference_info.as_ref().map(|_| LimitInfo::defaults()),
        pixels_per_degree: Some(eyes.eyes.iter().map(|e| pixels_per_degree(&e.fov, width)).sum::<f64>() / 2.0),
        reference: reference_info,
        version: version(),
        command: options.command.clone(),
        records: records(&rows),
    };
    let adapter = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
    Ok(BenchRun { file, radii, adapter })
}

/// Refuses a list of the bench's options that names a value twice, naming it.
fn named_once<T: PartialEq + std::fmt::Display>(what: &str, list: &[T]) -> Result<()> {
    match crate::measure::named_twice(list) {
        Some(value) => Err(Error::input(format!("the bench's {what} name {value} twice"))),
        None => Ok(()),
    }
}

/// Refuses a sweep before any GPU work: every case's settings must be valid and have an
/// occlusion technique, and reflective-shadow-map rows need a directional light and a
/// VPL count within 1..=1024.
fn check_options(scene: &Scene, base: &Settings, options: &BenchOptions, cases: &[BenchCase]) -> Result<()> {
    crate::measure::check_frames(options.warmup, options.frames)?;
    // A value named twice would measure the same rows twice (the table refuses it too).
    named_once("techniques", &options.techniques)?;
    named_once("sample counts", &options.samples)?;
    named_once("radii", &options.radii)?;
    named_once("foveation levels", &options.foveation)?;
    named_once("layer counts", &options.layers)?;
    if let Some(n) = options.layers.iter().find(|n| !(1..=2).contains(*n)) {
        return Err(Error::input(format!("layers {n} is not 1 or 2")));
    }
    // The mask's values as the command line names them (`--mask on,off`).
    let masks: Vec<&str> = options.mask.iter().map(|&on| if on { "on" } else { "off" }).collect();
    named_once("mask settings", &masks)?;
    named_once("RSM sample counts", &options.rsm_samples)?;
    for case in cases {
        let mut s = base.clone();
        (s.ao.technique, s.ao.samples, s.ao.radius, s.ao.resolution, s.point_ssdo.depth_peeling, s.ao.layers) = (
            case.technique,
            case.samples,
            case.radius,
            vrao_ao::Resolution::from_half_res(case.half_res),
            case.depth_peeling,
            case.layers,
        );
        s.validate()?;
        if case.technique == Technique::None {
            return Err(Error::input("the bench's techniques include none, which has no occlusion to measure"));
        }
    }
    if !options.rsm_samples.is_empty() && vrao_render::passes::shadow::shadow_casters(scene).is_empty() {
        return Err(Error::input(format!(
            "reflective shadow map rows: '{}' has no directional light to bounce",
            scene.name
        )));
    }
    if let Some(n) = options.rsm_samples.iter().find(|n| !(1..=1024).contains(*n)) {
        return Err(Error::input(format!("reflective shadow map rows: {n} VPLs is not within 1..=1024")));
    }
    Ok(())
}

/// Logs how long the sweep is likely to take ([`estimate_seconds`]).
fn log_estimate(gpu: &Arc<Gpu>, scene: &Scene, base: &Settings, cases: &[BenchCase], how: Measurement) -> Result<()> {
    let (estimate, frame_seconds) = estimate_seconds(gpu, scene, base, cases, how)?;
    log::info!(
        "bench: estimated {} ({} cases × ({} + {} frames) at ~{:.0} ms a frame of the first case, plus set-up; other cases may differ)",
        format_duration(estimate),
        cases.len(),
        how.warmup,
        how.frames,
        frame_seconds * 1000.0
    );
    Ok(())
}

/// One measured row as a progress line: the case, its cost, its error figures when it
/// has them, and the time so far and to go (after `elapsed` seconds).
fn progress_line(done: usize, total: usize, row: &BenchRow, elapsed: f64) -> String {
    let eta = elapsed / done as f64 * (total - done) as f64;
    let mut error = row.error.as_ref().map_or(String::new(), |e| {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
        format!(
            "  RMSE {:.3} bias {:+.3} vs limit {} (limit {}, 2-layer {}) FLIP {}",
            e.ao_rmse,
            e.ao_bias,
            opt(e.ao_rmse_vs_limit),
            opt(e.limit_rmse),
            opt(e.limit_two_layer_rmse),
            opt(e.flip_mean)
        )
    });
    if let Some(share) = row.stereo.and_then(|s| s.inconsistent) {
        error += &format!("  stereo ≠ {:.1} %", share * 100.0);
    }
    format!(
        "[{done:>3}/{total}] {:<12} N={:<3} r={:<7} {:<4} {:>9.3} ms/eye{error}   (elapsed {elapsed:.0} s, eta {eta:.0} s)",
        format!(
            "{}{}{}",
            row.case.technique.name(),
            if row.case.depth_peeling { "+peel" } else { "" },
            if row.case.layers == 2 { "+2L" } else { "" }
        ),
        row.case.samples,
        row.case.radius,
        format!(
            "{}{}",
            Resolution::from_half_res(row.case.half_res).name(),
            match row.case.foveation {
                Foveation::Off => String::new(),
                level => format!(" fov-{}", level.name()),
            } + if row.case.mask { " mask" } else { "" }
        ),
        row.occlusion_ms_per_eye()
    )
}

/// The reflective-shadow-map rows: every VPL count of `options` at every radius.
fn rsm_rows(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    options: &BenchOptions,
    radii: &[f32],
    how: Measurement,
    references: &[(f32, ReferenceImage)],
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    for &samples in &options.rsm_samples {
        for &radius in radii {
            let reference = references.iter().find(|(r, _)| *r == radius).map(|(_, image)| image);
            let row = measure_rsm(gpu, scene, base, samples, radius, how, reference)?;
            let error = row.bounce.map_or(String::new(), |b| format!("  bounce rel RMSE {:.4}", b.rel_rmse));
            log::info!("[rsm] N={samples:<3} r={radius:<7} half {:>9.3} ms/eye{error}", row.occlusion_ms_per_eye());
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Traces (or reads from the cache) the reference of every radius, with a progress bar.
fn trace_references(
    scene: &Scene,
    base: &Settings,
    eyes: &[vrao_ao::Eye],
    radii: &[f32],
    options: &ReferenceOptions,
    coverage: Option<&[Option<Vec<u8>>]>,
) -> Result<(Vec<(f32, ReferenceImage)>, ReferenceInfo)> {
    let (mut noise, mut rays, mut seconds) = (0.0f64, 0u64, 0.0f64);
    let mut references = Vec::new();
    for &radius in radii {
        let settings = ReferenceSettings {
            radius: radius as f64,
            rays_per_pixel: options.rays_per_pixel,
            stride: options.stride,
            near: base.near,
        };
        log::info!(
            "reference: r = {radius} m, {} rays per pixel, every {} pixels",
            options.rays_per_pixel,
            options.stride
        );
        let mut bar = ProgressBar::new("reference");
        let size = (base.profile.width, base.profile.height);
        let image =
            trace_cached_visible(&options.cache, scene, eyes, size, &settings, coverage, &mut |p| bar.update(p))?;
        bar.finish();
        noise = noise.max(image.stats.noise);
        if !image.stats.from_cache {
            rays += image.stats.rays;
            seconds += image.stats.seconds;
        }
        references.push((radius, image));
    }
    let info = ReferenceInfo {
        rays_per_pixel: options.rays_per_pixel,
        stride: options.stride,
        ao_noise_rms: noise,
        rays_per_second: (seconds > 0.0).then(|| rays as f64 / seconds),
    };
    Ok((references, info))
}

/// Re-reads a bench.json to write it again (Pareto fronts recomputed), measuring nothing.
pub fn replot(path: &Path) -> Result<BenchRun> {
    let mut file = read_json(path)?;
    mark_pareto(&mut file.records);
    let mut radii: Vec<f32> = file.records.iter().map(|r| r.radius_m).collect();
    radii.sort_by(f32::total_cmp);
    radii.dedup();
    let adapter = format!("{} ({}, {})", file.adapter, file.backend, file.driver);
    Ok(BenchRun { file, radii, adapter })
}

/// Writes bench.csv, bench.json, bench.md and (with a reference) one plot per radius
/// into `out`, with the plots' budget line at `budget_ms` per stereo frame; returns the
/// report to print (the Markdown, the reference, the Pareto fronts, what was written).
pub fn write_outputs(out: &Path, run: &BenchRun, budget_ms: f64) -> Result<String> {
    if !(budget_ms.is_finite() && budget_ms > 0.0) {
        return Err(Error::input(format!("the plots' frame budget {budget_ms} ms must be a positive number")));
    }
    let file = &run.file;
    std::fs::create_dir_all(out).map_err(|e| Error::Output {
        path: out.to_path_buf(),
        message: format!("cannot create this directory: {e}"),
    })?;
    let write = |name: &str, text: String| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })
    };
    write("bench.csv", to_csv(&file.records))?;
    let markdown = markdown_report(file);
    write("bench.md", markdown.clone())?;
    write("bench.json", to_json(file))?;
    let mut written = "bench.csv, bench.json, bench.md".to_string();
    if file.reference.is_some() {
        // One plot per radius (errors compare only within a radius); bench.png is the
        // middle radius, the scene's suggested one by default.
        for (i, &radius) in run.radii.iter().enumerate() {
            let name = if i == run.radii.len() / 2 { "bench.png".to_string() } else { super::plot_file_name(radius) };
            plot(file, radius, budget_ms / 2.0).save_png(&out.join(&name), 1280, 800)?;
            written += &format!(", {name}");
        }
    }
    let mut s = format!("{markdown}\n");
    if let Some(r) = &file.reference {
        let _ = writeln!(
            s,
            "reference: {} rays per pixel at every {} pixels; its AO noise (RMS standard error) {:.4}{}",
            r.rays_per_pixel,
            r.stride,
            r.ao_noise_rms,
            r.rays_per_second.map_or(String::new(), |s| format!("; traced at {:.2} Mrays/s", s / 1e6))
        );
        for &radius in &run.radii {
            let mut front: Vec<&BenchRecord> =
                file.records.iter().filter(|r| r.pareto && r.radius_m == radius).collect();
            front.sort_by(|a, b| a.occlusion_ms_per_eye.total_cmp(&b.occlusion_ms_per_eye));
            let front: Vec<String> = front
                .iter()
                .map(|r| {
                    format!("{} ({:.1} ms, {:.4})", r.setting(), r.occlusion_ms_per_eye, r.ao_rmse.unwrap_or(f64::NAN))
                })
                .collect();
            let _ = writeln!(s, "Pareto front at r = {radius} m (fastest first): {}", front.join("; "));
        }
    }
    let _ = writeln!(s, "adapter: {}; wrote {written} in {}", run.adapter, out.display());
    Ok(s)
}

/// vrao's version, with the git commit it was built from when git can tell (read at run
/// time from the source tree the binary was built in; "+changes" when it has uncommitted
/// changes).
pub fn version() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(env!("CARGO_MANIFEST_DIR"))
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let mut v = env!("CARGO_PKG_VERSION").to_string();
    if let Some(hash) = git(&["rev-parse", "--short", "HEAD"]).filter(|h| !h.is_empty()) {
        let dirty = git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
        v += &format!(" (git {hash}{})", if dirty { "+changes" } else { "" });
    }
    v
}

/// "42 s", "3.5 min" or "1.2 h".
pub fn format_duration(seconds: f64) -> String {
    if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 5400.0 {
        format!("{:.1} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}
