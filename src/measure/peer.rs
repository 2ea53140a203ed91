//! `vrao peer`: Bevy's screen-space AO (the peer program in `peers/bevy`) and vrao's on
//! the same frames, scored by the same reference and timed in one run.
//!
//! The scene is written as glTF for the peer, which renders it with one Bevy camera per
//! eye whose view and projection are vrao's own matrices for that eye (the reference's
//! pixels are the peer's pixels). Rounds alternate the peer (every Bevy preset, frame by
//! frame) and vrao (every case, interleaved as `vrao bench --interleave` does); the
//! medians of the rounds' medians are reported. Both families' AO is scored with the
//! bench's [`score`] against one reference, with the screen-space limit of vrao's depth
//! buffer beside.
//!
//! What each side's time is: vrao's occlusion chain as the bench reports it (technique,
//! denoise, upsampling at half resolution; both eyes in one dispatch), Bevy's three AO
//! passes (depth preprocess, main pass, spatial denoise) per camera, one camera per eye.
//! With serial timing (lavapipe) both are wall clock around work submitted alone; with
//! pipelined timing (a GPU) both are GPU timestamps.

use crate::error::{Error, Result};
use crate::measure::bench::{
    pixels_per_degree, score, sweep, BenchCase, BenchRow, ErrorFigures, Measurement, ReferenceOptions,
};
use crate::measure::plot::{Point, ScatterPlot, Series};
use crate::measure::reference::screen_limit::{screen_space_limit, EyeBuffers, LimitSettings, ScreenLimit};
use crate::measure::reference::{trace_cached, ProgressBar, ReferenceImage, ReferenceSettings};
use crate::measure::side_by_side::{grid_panel, save_panels};
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use vrao_ao::plug::{Gpu, DEPTH, FINAL_AO, NORMALS};
use vrao_ao::{Eye, EyePair, Foveation, Technique};
use vrao_render::renderer::{Renderer, Timing, TimingChoice};
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;
use vrao_render::BackendChoice;

/// Bevy 0.19's own SSAO presets: (name, slices, samples per slice side).
pub const BEVY_PRESETS: [(&str, u32, u32); 4] = [("low", 1, 2), ("medium", 2, 2), ("high", 3, 3), ("ultra", 9, 3)];
/// The most rounds a comparison takes.
pub const ROUNDS_MAX: u32 = 20;
/// Where `cargo build --release` in `peers/bevy` puts the peer.
pub const DEFAULT_PEER: &str = "peers/bevy/target/release/vrao-peer-bevy";

/// What a comparison runs.
#[derive(Clone, Debug)]
pub struct PeerOptions {
    /// The wgpu backend for vrao.
    pub backend: BackendChoice,
    /// The peer program.
    pub peer: PathBuf,
    /// Bevy's presets to run (names of [`BEVY_PRESETS`]).
    pub presets: Vec<String>,
    /// vrao's GTAO sample counts.
    pub samples: Vec<u32>,
    /// vrao's resolutions (`true`: half).
    pub half_res: Vec<bool>,
    /// Serial, pipelined or auto, for both sides.
    pub timing: TimingChoice,
    /// Frames discarded before timing, per case and round.
    pub warmup: u32,
    /// Frames timed per case and round.
    pub frames: u32,
    /// Rounds of peer and vrao, alternating which goes first.
    pub rounds: u32,
    /// The reference both are scored against.
    pub reference: ReferenceOptions,
    /// Output folder (the peer's files, the table, the plot, the images).
    pub out: PathBuf,
    /// The scene as glTF for the peer ([`scene_for_peer`] written by the caller).
    pub gltf: PathBuf,
    /// Set when vrao is interrupted: a running peer is then ended.
    pub interrupt: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

/// Which program a row measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Bevy 0.19's `ScreenSpaceAmbientOcclusion`.
    Bevy,
    /// vrao's engine.
    Vrao,
}

/// One row of the comparison.
#[derive(Clone, Debug)]
pub struct PeerRow {
    /// Whose AO.
    pub family: Family,
    /// The setting, as that side names it ("high"; "gtao 24 half").
    pub setting: String,
    /// Median ms per eye (Bevy: the mean of its two cameras).
    pub ms_per_eye: f64,
    /// Median ms for both eyes (vrao: its stereo chain; Bevy: both cameras' chains).
    pub ms_stereo: f64,
    /// Error against the reference.
    pub error: ErrorFigures,
}

/// A finished comparison.
#[derive(Clone, Debug)]
pub struct PeerRun {
    /// The scene's name.
    pub scene: String,
    /// Per-eye size.
    pub width: u32,
    /// Per-eye size.
    pub height: u32,
    /// vrao's adapter, "name (backend, driver)".
    pub adapter: String,
    /// The peer's adapter as Bevy reports it.
    pub peer_adapter: String,
    /// How both sides were timed.
    pub timing: Timing,
    /// Warm-up, measured frames and rounds.
    pub warmup: u32,
    /// Measured frames per case and round.
    pub frames: u32,
    /// Rounds.
    pub rounds: u32,
    /// The reference's AO radius (m), rays per pixel and stride.
    pub radius: f32,
    /// Rays per traced pixel.
    pub rays: u32,
    /// Traced at every stride-th pixel.
    pub stride: u32,
    /// vrao's occlusion passes (what its time includes).
    pub vrao_passes: Vec<String>,
    /// Bevy's rows, then vrao's.
    pub rows: Vec<PeerRow>,
}

/// The peer's `peer.json`.
#[derive(Deserialize)]
struct PeerFile {
    adapter: String,
    width: u32,
    height: u32,
    timestamps: bool,
    presets: Vec<PeerPreset>,
}

#[derive(Deserialize)]
struct PeerPreset {
    name: String,
    eyes: Vec<PeerEye>,
}

#[derive(Deserialize)]
struct PeerEye {
    eye: String,
    ao: String,
    median_wall_ms: Option<f64>,
    median_gpu_ms: Option<f64>,
}

/// One round of the peer: per preset, per eye, (ms, AO image).
type PeerRound = Vec<(String, Vec<(f64, Vec<f32>)>)>;

/// Refuses options out of range before any work.
pub fn check_options(options: &PeerOptions) -> Result<()> {
    crate::measure::check_frames(options.warmup, options.frames)?;
    if !(1..=ROUNDS_MAX).contains(&options.rounds) {
        return Err(Error::input(format!("{} rounds is not within 1..={ROUNDS_MAX}", options.rounds)));
    }
    if options.presets.is_empty() && options.samples.is_empty() {
        return Err(Error::input("nothing to compare: no Bevy preset and no vrao sample count"));
    }
    if let Some(p) = options.presets.iter().find(|p| !BEVY_PRESETS.iter().any(|(n, _, _)| n == p)) {
        return Err(Error::input(format!("'{p}' is not a Bevy preset (low, medium, high, ultra)")));
    }
    if let Some(p) = crate::measure::named_twice(&options.presets) {
        return Err(Error::input(format!("the Bevy presets name {p} twice")));
    }
    if let Some(n) = crate::measure::named_twice(&options.samples) {
        return Err(Error::input(format!("the sample counts name {n} twice")));
    }
    if !options.presets.is_empty() && !options.peer.is_file() {
        return Err(Error::input(format!(
            "no peer program at {} (build it: cd peers/bevy && cargo build --release)",
            options.peer.display()
        )));
    }
    Ok(())
}

/// The vrao cases: GTAO at every sample count and resolution, at the base radius.
pub fn vrao_cases(base: &Settings, options: &PeerOptions) -> Vec<BenchCase> {
    let mut cases = Vec::new();
    for &half_res in &options.half_res {
        for &samples in &options.samples {
            cases.push(BenchCase {
                technique: Technique::Gtao,
                samples,
                radius: base.ao.radius,
                half_res,
                depth_peeling: false,
                layers: 1,
                temporal: false,
                foveation: Foveation::Off,
                // Bevy computes the whole rectangle: so does vrao here.
                mask: false,
            });
        }
    }
    cases
}

/// Runs the comparison: the glTF, the reference, the rounds, the scores. Logs progress.
pub fn run_peer(scene: &Scene, base: &Settings, options: &PeerOptions) -> Result<PeerRun> {
    check_options(options)?;
    let cases = vrao_cases(base, options);
    check_cases(base, &cases)?;
    let work = peer_work_dir(options)?;
    let gltf = &options.gltf;
    let (width, height) = (base.profile.width, base.profile.height);
    let eyes = base.profile.eyes(&scene.head.pose_at(0.0), base.near);
    let gpu = Arc::new(vrao_render::open(options.backend)?);
    let timing = options.timing.resolve(&gpu);
    let adapter = format!("{} ({:?}, {})", gpu.info.name, gpu.info.backend, gpu.info.driver_info);
    let radius = base.ao.radius;
    let reference = trace_reference(scene, base, &eyes, radius, &options.reference)?;
    let references = vec![(radius, reference)];
    let reference = &references[0].1;
    let (limit, vrao_default) = limit_and_default(&gpu, scene, base, &eyes, reference)?;
    let how = Measurement {
        timing,
        warmup: options.warmup,
        frames: options.frames,
        whole_frame: false,
        interleave: cases.len().max(1),
    };
    let mut peer_rounds: Vec<PeerRound> = Vec::new();
    let mut vrao_rounds: Vec<Vec<BenchRow>> = Vec::new();
    let mut peer_adapter = String::new();
    for round in 0..options.rounds {
        let peer_first = round % 2 == 0;
        for side in [peer_first, !peer_first] {
            if side && !options.presets.is_empty() {
                log::info!("peer: round {} of {}: Bevy, {} presets", round + 1, options.rounds, options.presets.len());
                let dir = work.join(format!("round-{round}"));
                let (adapter, result) = run_peer_round(options, gltf, &dir, &eyes, (width, height), timing)?;
                peer_adapter = adapter;
                peer_rounds.push(result);
            } else if !side && !cases.is_empty() {
                log::info!("peer: round {} of {}: vrao, {} cases", round + 1, options.rounds, cases.len());
                vrao_rounds.push(sweep(&gpu, scene, base, &cases, how, &references, None, |done, total, row| {
                    log::info!(
                        "[{done}/{total}] vrao {} {:.3} ms/eye",
                        setting_name(&row.case),
                        row.occlusion_ms_per_eye()
                    )
                })?);
            }
        }
    }
    let fovs: Vec<_> = eyes.eyes.iter().map(|e| e.fov).collect();
    let ppd = eyes.eyes.iter().map(|e| pixels_per_degree(&e.fov, width)).sum::<f64>() / eyes.eyes.len() as f64;
    let mask = crate::xr::profiles::visibility_mask(&base.profile);
    let visible = reference.visible_only(&crate::measure::bench::lens_coverage(&mask, base, &eyes.eyes));
    let scoring = PeerScoring { reference, visible: &visible, limit: &limit, ppd, fovs: &fovs };
    let mut rows = bevy_rows(&options.presets, &peer_rounds, eyes.eyes.len(), &scoring);
    let (vrao_rows, vrao_passes) = vrao_rows(&cases, &vrao_rounds)?;
    rows.extend(vrao_rows);
    let run = PeerRun {
        scene: scene.name.clone(),
        width,
        height,
        adapter,
        peer_adapter,
        timing,
        warmup: options.warmup,
        frames: options.frames,
        rounds: options.rounds,
        radius,
        rays: options.reference.rays_per_pixel,
        stride: options.reference.stride,
        vrao_passes,
        rows,
    };
    write_side_by_side(&options.out, &run, &peer_rounds, options, &vrao_default, reference)?;
    Ok(run)
}

/// The folder the peer's rounds write into (made), once the glTF it reads is known to
/// exist (when some Bevy preset runs).
fn peer_work_dir(options: &PeerOptions) -> Result<PathBuf> {
    let work = options.out.join("peer-work");
    std::fs::create_dir_all(&work).map_err(|e| Error::Output { path: work.clone(), message: e.to_string() })?;
    let gltf = &options.gltf;
    if !options.presets.is_empty() && !gltf.is_file() {
        return Err(Error::input(format!("no glTF of the scene for the peer at {}", gltf.display())));
    }
    Ok(work)
}

/// Validates each vrao case's settings before any work.
fn check_cases(base: &Settings, cases: &[BenchCase]) -> Result<()> {
    for case in cases {
        let mut s = base.clone();
        (s.ao.technique, s.ao.samples, s.ao.resolution) =
            (case.technique, case.samples, vrao_ao::Resolution::from_half_res(case.half_res));
        s.validate()?;
    }
    Ok(())
}

/// What a peer's AO is scored against: the reference (whole and on the pixels the lens
/// shows), the screen-space limit, and the views' pixel density and fields of view.
struct PeerScoring<'a> {
    reference: &'a ReferenceImage,
    visible: &'a ReferenceImage,
    limit: &'a ScreenLimit,
    ppd: f64,
    fovs: &'a [vrao_ao::Fov],
}

/// The Bevy rows, one per preset: the median time per eye over the rounds, and the last
/// round's AO scored (over `views` eyes).
fn bevy_rows(presets: &[String], peer_rounds: &[PeerRound], views: usize, scoring: &PeerScoring) -> Vec<PeerRow> {
    let PeerScoring { reference, visible, limit, ppd, fovs } = *scoring;
    let mut rows = Vec::new();
    for (k, name) in presets.iter().enumerate() {
        let per_eye: Vec<f64> = (0..views).map(|e| median(peer_rounds.iter().map(|r| r[k].1[e].0).collect())).collect();
        let last = &peer_rounds.last().expect("a round ran")[k].1;
        let occlusion: Vec<Vec<f32>> = last.iter().map(|(_, ao)| rgba_of(ao)).collect();
        // Scored as the bench scores vrao's rows: on the pixels the lens shows, the
        // whole rectangle beside.
        let mut error = score(Technique::Gtao, &occlusion, visible, Some(limit), ppd, fovs);
        error.ao_rmse_whole = Some(score(Technique::Gtao, &occlusion, reference, Some(limit), ppd, fovs).ao_rmse);
        let stereo: f64 = per_eye.iter().sum();
        rows.push(PeerRow {
            family: Family::Bevy,
            setting: name.clone(),
            ms_per_eye: stereo / per_eye.len() as f64,
            ms_stereo: stereo,
            error,
        });
    }
    rows
}

/// The vrao rows, one per case: the median time per eye over the rounds and the last
/// round's score; with the passes the cases ran, each named once.
fn vrao_rows(cases: &[BenchCase], vrao_rounds: &[Vec<BenchRow>]) -> Result<(Vec<PeerRow>, Vec<String>)> {
    let mut rows = Vec::new();
    let mut vrao_passes = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        let per_eye = median(vrao_rounds.iter().map(|r| r[i].occlusion_ms_per_eye()).collect());
        let last = &vrao_rounds.last().expect("a round ran")[i];
        for pass in &last.occlusion_passes {
            if !vrao_passes.iter().any(|p: &String| p == pass) {
                vrao_passes.push(pass.to_string());
            }
        }
        let error = last.error.clone().ok_or_else(|| Error::gpu("a vrao row was not scored"))?;
        rows.push(PeerRow {
            family: Family::Vrao,
            setting: setting_name(case),
            ms_per_eye: per_eye,
            ms_stereo: per_eye * last.views as f64,
            error,
        });
    }
    Ok((rows, vrao_passes))
}

/// "gtao 24 half": a vrao case as the table names it.
fn setting_name(case: &BenchCase) -> String {
    format!("{} {} {}", case.technique.name(), case.samples, if case.half_res { "half" } else { "full" })
}

/// The median (NaN of none).
fn median(mut values: Vec<f64>) -> f64 {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    }
}

/// An AO image as the RGBA the bench scores (white, AO in alpha).
fn rgba_of(ao: &[f32]) -> Vec<f32> {
    ao.iter().flat_map(|&a| [1.0, 1.0, 1.0, a]).collect()
}

/// `scene` as the peer is to load it (the caller writes it as glTF, e.g. with
/// `test_assets::gltf_write`, and names the file in [`PeerOptions::gltf`]): its geometry
/// and plain materials. AO reads depth and normals only, so textures are left out (the
/// peer needs no image codecs); a material whose alpha comes from a texture is named in a
/// warning, as the peer sees it solid where vrao cuts it out.
pub fn scene_for_peer(scene: &Scene) -> Scene {
    let mut plain = scene.clone();
    for m in &mut plain.materials {
        if m.diffuse_texture.is_some() && m.alpha_mode != vrao_render::scene::AlphaMode::Opaque {
            log::warn!("peer: material '{}' is cut out by its texture in vrao, solid for the peer", m.name);
        }
        (m.diffuse_texture, m.emissive_texture, m.normal_texture, m.occlusion_texture) = (None, None, None, None);
    }
    plain
}

/// The reference at `radius` for both eyes (cached as the bench caches it).
fn trace_reference(
    scene: &Scene,
    base: &Settings,
    eyes: &EyePair,
    radius: f32,
    options: &ReferenceOptions,
) -> Result<ReferenceImage> {
    let settings = ReferenceSettings {
        radius: radius as f64,
        rays_per_pixel: options.rays_per_pixel,
        stride: options.stride,
        near: base.near,
    };
    let mut bar = ProgressBar::new("reference");
    let size = (base.profile.width, base.profile.height);
    let image = trace_cached(&options.cache, scene, &eyes.eyes, size, &settings, &mut |p| bar.update(p))?;
    bar.finish();
    Ok(image)
}

/// One frame of vrao's default AO setting (at the base size): the screen-space limit of
/// its depth buffer (the same for every row: the same pixels) and its AO per eye.
fn limit_and_default(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    eyes: &EyePair,
    reference: &ReferenceImage,
) -> Result<(ScreenLimit, Vec<Vec<f32>>)> {
    let mut renderer = Renderer::new(gpu.clone(), scene, base)?;
    renderer.render_and_wait(&eyes.eyes, &[FINAL_AO])?;
    let depth = renderer.read_f32(DEPTH)?;
    let normals = renderer.read_f32(NORMALS)?;
    let buffers: Vec<EyeBuffers> = (0..depth.len().min(normals.len()))
        .map(|k| EyeBuffers {
            depth: &depth[k],
            normals: &normals[k],
            fov: eyes.eyes[k].fov,
            direct: None,
            second: None,
        })
        .collect();
    let settings = LimitSettings::for_reference(reference, base.ao.radius as f64, eyes.near);
    let limit = screen_space_limit(&buffers, (reference.width, reference.height), &settings)?;
    let ao = renderer.read_f32(FINAL_AO)?.iter().map(|l| l.iter().skip(3).step_by(4).copied().collect()).collect();
    Ok((limit, ao))
}

/// The eye's job line: its name, world-from-view and clip-from-view, column-major, as
/// vrao builds them.
fn eye_line(name: &str, eye: &Eye, near: f64) -> String {
    let world_from_view = eye.pose.world_from_local().as_mat4();
    let clip_from_view = vrao_ao::Fov::reversed_z_projection(&eye.fov, near).as_mat4();
    let numbers: Vec<String> = world_from_view
        .to_cols_array()
        .iter()
        .chain(clip_from_view.to_cols_array().iter())
        .map(|v| format!("{v:e}"))
        .collect();
    format!("eye {name} {}\n", numbers.join(" "))
}

/// The eyes' names, in layer order.
const EYE_NAMES: [&str; 2] = ["left", "right"];

/// Runs the peer once into `dir` and reads what it wrote: per preset, per eye, the
/// median ms (wall clock for serial timing, timestamps for pipelined) and the AO.
fn run_peer_round(
    options: &PeerOptions,
    gltf: &Path,
    dir: &Path,
    eyes: &EyePair,
    (width, height): (u32, u32),
    timing: Timing,
) -> Result<(String, PeerRound)> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Output { path: dir.to_path_buf(), message: e.to_string() })?;
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut job = format!(
        "scene {}\nsize {width} {height}\nwarmup {}\nframes {}\npresets {}\nout {}\n",
        absolute(gltf).display(),
        options.warmup,
        options.frames,
        options.presets.join(" "),
        absolute(dir).display()
    );
    for (k, eye) in eyes.eyes.iter().enumerate() {
        job += &eye_line(EYE_NAMES[k], eye, eyes.near);
    }
    let job_path = dir.join("job.txt");
    let output = |path: &Path, e: std::io::Error| Error::Output { path: path.to_path_buf(), message: e.to_string() };
    std::fs::write(&job_path, job).map_err(|e| output(&job_path, e))?;
    let log_path = dir.join("peer.log");
    let log = std::fs::File::create(&log_path).map_err(|e| output(&log_path, e))?;
    let log2 = log.try_clone().map_err(|e| output(&log_path, e))?;
    let child = std::process::Command::new(&options.peer)
        .arg(&job_path)
        .stdout(log)
        .stderr(log2)
        .spawn()
        .map_err(|e| Error::input(format!("running the peer {}: {e}", options.peer.display())))?;
    let status = wait_for_peer(child, &options.interrupt)?;
    if !status.success() {
        let text = std::fs::read_to_string(&log_path).unwrap_or_default();
        let tail: Vec<&str> = text.lines().rev().take(3).collect();
        return Err(Error::Peer(format!(
            "it failed ({status}): {}",
            tail.into_iter().rev().collect::<Vec<_>>().join(" / ")
        )));
    }
    let file_path = dir.join("peer.json");
    let text = vrao_render::files::read_regular_file_to_string(&file_path, vrao_render::files::MAX_TEXT_BYTES)?;
    let file: PeerFile =
        serde_json::from_str(&text).map_err(|e| Error::Peer(format!("its peer.json does not read: {e}")))?;
    if (file.width, file.height) != (width, height) || file.presets.len() != options.presets.len() {
        return Err(Error::Peer("its peer.json does not match its job (size or presets)".into()));
    }
    if timing == Timing::Pipelined && !file.timestamps {
        return Err(Error::device("the peer's device has no timestamp queries; use serial timing"));
    }
    Ok((file.adapter.clone(), presets_of(&file, dir, (width, height), timing)?))
}

/// Each preset's name and its eyes' times and AO, as the peer's `file` lists them (its
/// AO files in `dir`), checked like any input: two eyes, left then right, finite times,
/// AO files of the right size and range.
fn presets_of(file: &PeerFile, dir: &Path, (width, height): (u32, u32), timing: Timing) -> Result<PeerRound> {
    let mut round = Vec::new();
    for preset in &file.presets {
        if preset.eyes.len() != EYE_NAMES.len() {
            return Err(Error::Peer(format!(
                "its preset '{}' lists {} eyes (want {})",
                preset.name,
                preset.eyes.len(),
                EYE_NAMES.join(" and ")
            )));
        }
        let mut per_eye = Vec::new();
        for (eye, name) in preset.eyes.iter().zip(EYE_NAMES) {
            if eye.eye != name {
                return Err(Error::Peer(format!("its eye '{}' stands where '{name}' belongs", eye.eye)));
            }
            let ms = match timing {
                Timing::Serial => eye.median_wall_ms,
                Timing::Pipelined => eye.median_gpu_ms,
            };
            let ms = ms.filter(|ms| ms.is_finite() && *ms >= 0.0).ok_or_else(|| {
                Error::Peer(format!("its {name} eye's time {ms:?} ms is missing, negative or not finite"))
            })?;
            per_eye.push((ms, read_peer_ao(dir, &eye.ao, (width, height))?));
        }
        round.push((preset.name.clone(), per_eye));
    }
    Ok(round)
}

/// The longest a peer may run for one round before vrao ends it.
const PEER_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30 * 60);

/// Waits for the peer, ending it when it outlives [`PEER_TIMEOUT`] or when vrao is
/// interrupted (Ctrl-C), so that no peer is left running after vrao.
fn wait_for_peer(
    mut child: std::process::Child,
    interrupt: &std::sync::atomic::AtomicBool,
) -> Result<std::process::ExitStatus> {
    let started = std::time::Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return Ok(status),
            Ok(None) => {}
            Err(e) => return Err(Error::Peer(format!("waiting for it: {e}"))),
        }
        let interrupted = interrupt.load(std::sync::atomic::Ordering::Relaxed);
        if interrupted || started.elapsed() > PEER_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(if interrupted {
                vrao_ao::Error::Interrupted.into()
            } else {
                Error::Peer(format!("it ran past {} minutes and was ended", PEER_TIMEOUT.as_secs() / 60))
            });
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

/// One eye's AO from the peer: `name` is a plain file name in its work folder `dir` (no
/// other folder, no link out), a regular file of exactly `width` × `height` f32 values,
/// each finite and within 0..=1.
fn read_peer_ao(dir: &Path, name: &str, (width, height): (u32, u32)) -> Result<Vec<f32>> {
    let plain = Path::new(name).file_name().is_some_and(|f| f == std::ffi::OsStr::new(name));
    if !plain || name.starts_with('.') {
        return Err(Error::Peer(format!("its AO file '{name}' is not a plain file name in its work folder")));
    }
    let path = dir.join(name);
    let expected = u64::from(width) * u64::from(height) * 4;
    let bytes = vrao_render::files::read_regular_file(&path, expected)?;
    if bytes.len() as u64 != expected {
        return Err(Error::Peer(format!("{} is not {width}x{height} f32 values", path.display())));
    }
    let ao: Vec<f32> = bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    if let Some(bad) = ao.iter().find(|v| !(0.0..=1.0).contains(*v)) {
        return Err(Error::Peer(format!("{} holds {bad}, not an AO within 0..=1", path.display())));
    }
    Ok(ao)
}

/// `side_by_side_left.png`: the left eye's AO from Bevy (High, or the last preset run),
/// vrao's default setting and the reference (nearest cell), side by side.
fn write_side_by_side(
    out: &Path,
    run: &PeerRun,
    peer_rounds: &[PeerRound],
    options: &PeerOptions,
    vrao_default: &[Vec<f32>],
    reference: &ReferenceImage,
) -> Result<()> {
    let (w, h) = (run.width as usize, run.height as usize);
    let Some(last) = peer_rounds.last() else { return Ok(()) };
    let bevy = options.presets.iter().position(|p| p == "high").unwrap_or(options.presets.len() - 1);
    let traced = grid_panel(w, h, reference.stride, reference.grid_size(), |i, j| {
        let p = reference.get(0, i, j);
        if p.hit {
            p.ao
        } else {
            1.0
        }
    });
    save_panels(&out.join("side_by_side_left.png"), w, h, &[last[bevy].1[0].1.clone(), vrao_default[0].clone(), traced])
}

/// The row every ratio is taken against: Bevy's High, else its first preset, else the
/// first row.
fn baseline(run: &PeerRun) -> Option<&PeerRow> {
    run.rows
        .iter()
        .find(|r| r.family == Family::Bevy && r.setting == "high")
        .or_else(|| run.rows.iter().find(|r| r.family == Family::Bevy))
        .or(run.rows.first())
}

/// The Markdown table with its header lines.
pub fn markdown(run: &PeerRun) -> String {
    let mut md = String::new();
    let how = match run.timing {
        Timing::Serial => "serial: wall clock around work submitted alone and waited for",
        Timing::Pipelined => "pipelined: GPU timestamps",
    };
    let base = baseline(run);
    let base_name = base.map_or(String::new(), |b| format!("{} {}", family_name(b.family), b.setting));
    let _ = writeln!(
        md,
        "Scene `{}`, {}×{} per eye, both eyes; vrao on {}; Bevy on {}.",
        run.scene, run.width, run.height, run.adapter, run.peer_adapter
    );
    let _ = writeln!(
        md,
        "Timing {how}; {} warm-up and {} measured frames per case and round, {} round(s) alternating Bevy and vrao; medians.",
        run.warmup, run.frames, run.rounds
    );
    let _ = writeln!(
        md,
        "vrao's time: its occlusion chain ({}) for both eyes in one dispatch. Bevy's time: its three AO passes (depth preprocess, main pass, spatial denoise) of each eye's camera, the two cameras added.",
        run.vrao_passes.join(" + ")
    );
    let _ = writeln!(
        md,
        "Error against the reference tracer (hard cut-off at r = {} m, {} rays per pixel at every {}th pixel), as `vrao bench` scores it: on the pixels the headset's lens shows, the whole rectangle in the last column (vrao computes every pixel, as Bevy does: no mask); ratios against {base_name}.\n",
        run.radius, run.rays, run.stride
    );
    md.push_str("| AO | setting | ms per eye | ms both eyes | × time | RMSE | × RMSE | bias | dark bias | FLIP | RMSE vs limit | limit RMSE | RMSE, whole rectangle |\n");
    md.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let opt = |v: Option<f64>, signed: bool| match v {
        Some(v) if signed => format!("{v:+.3}"),
        Some(v) => format!("{v:.3}"),
        None => "–".into(),
    };
    for row in &run.rows {
        let (t, e) =
            base.map_or((f64::NAN, f64::NAN), |b| (row.ms_stereo / b.ms_stereo, row.error.ao_rmse / b.error.ao_rmse));
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} | {:.2} | {:.3} | {:.2} | {:+.3} | {} | {} | {} | {} | {} |",
            family_name(row.family),
            row.setting,
            row.ms_per_eye,
            row.ms_stereo,
            t,
            row.error.ao_rmse,
            e,
            row.error.ao_bias,
            opt(row.error.ao_bias_dark, true),
            opt(row.error.flip_mean, false),
            opt(row.error.ao_rmse_vs_limit, false),
            opt(row.error.limit_rmse, false),
            opt(row.error.ao_rmse_whole, false),
        );
    }
    md
}

fn family_name(family: Family) -> &'static str {
    match family {
        Family::Bevy => "Bevy 0.19.1",
        Family::Vrao => "vrao",
    }
}

/// The plot: RMSE against ms for both eyes, one series per family.
pub fn plot(run: &PeerRun) -> ScatterPlot {
    let series = |family: Family, color: [u8; 3]| Series {
        label: family_name(family).to_string(),
        color,
        points: run
            .rows
            .iter()
            .filter(|r| r.family == family)
            .map(|r| Point { x: r.ms_stereo, y: r.error.ao_rmse, label: r.setting.clone() })
            .collect(),
    };
    ScatterPlot {
        title: format!("{}: AO error against time, both eyes ({}×{} per eye)", run.scene, run.width, run.height),
        x_label: match run.timing {
            Timing::Serial => "ms for both eyes (serial wall clock)".into(),
            Timing::Pipelined => "ms for both eyes (GPU timestamps)".into(),
        },
        y_label: "RMSE against the reference".into(),
        series: vec![series(Family::Bevy, [200, 80, 40]), series(Family::Vrao, [40, 90, 200])],
        pareto: Vec::new(),
        vertical_line: None,
    }
}

/// Writes `peer.md` and `peer.png` into `out` and returns the table.
pub fn write_outputs(out: &Path, run: &PeerRun) -> Result<String> {
    let md = markdown(run);
    let path = out.join("peer.md");
    std::fs::write(&path, &md).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })?;
    plot(run).save_png(&out.join("peer.png"), 1200, 800)?;
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A work folder with `files` (name, bytes) in it.
    fn work_dir(name: &str, files: &[(&str, Vec<u8>)]) -> vrao_render::test_dir::TestDir {
        let dir = vrao_render::test_dir::TestDir::new(&format!("peer-{name}"));
        for (file, bytes) in files {
            dir.write(file, bytes);
        }
        dir
    }

    fn f32_bytes(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn a_peer_s_files_are_input_checked_like_any_other() {
        let good = f32_bytes(&[0.5; 6]);
        let dir = work_dir(
            "files",
            &[
                ("ao.f32", good.clone()),
                ("nan.f32", f32_bytes(&[0.5, 0.5, 0.5, f32::NAN, 0.5, 0.5])),
                ("short.f32", f32_bytes(&[0.5; 5])),
            ],
        );
        assert_eq!(read_peer_ao(&dir, "ao.f32", (3, 2)).unwrap(), vec![0.5; 6]);
        for (name, says) in [
            ("../ao.f32", "plain file name"),
            ("/etc/passwd", "plain file name"),
            ("nan.f32", "not an AO"),
            ("short.f32", "not 3x2"),
            ("missing.f32", "missing.f32"),
        ] {
            let e = read_peer_ao(&dir, name, (3, 2)).unwrap_err();
            assert!(e.to_string().contains(says), "{name}: {e}");
        }
        // A file larger than the image is refused by its size before it is read.
        std::fs::write(dir.join("big.f32"), vec![0u8; 1 << 20]).unwrap();
        assert!(read_peer_ao(&dir, "big.f32", (3, 2)).is_err());
    }

    #[test]
    fn a_peer_listing_other_than_two_eyes_or_bad_times_is_refused_not_a_panic() {
        let dir = work_dir("eyes", &[("ao.f32", f32_bytes(&[1.0; 4]))]);
        let eye = |name: &str, ms: Option<f64>| PeerEye {
            eye: name.into(),
            ao: "ao.f32".into(),
            median_wall_ms: ms,
            median_gpu_ms: ms,
        };
        let file = |eyes: Vec<PeerEye>| PeerFile {
            adapter: "peer".into(),
            width: 2,
            height: 2,
            timestamps: true,
            presets: vec![PeerPreset { name: "high".into(), eyes }],
        };
        let ok = presets_of(&file(vec![eye("left", Some(1.0)), eye("right", Some(2.0))]), &dir, (2, 2), Timing::Serial);
        assert_eq!(ok.unwrap()[0].1.iter().map(|(ms, _)| *ms).collect::<Vec<_>>(), [1.0, 2.0]);
        for (eyes, says) in [
            (vec![eye("left", Some(1.0))], "lists 1 eyes"),
            (vec![eye("left", Some(1.0)), eye("right", Some(1.0)), eye("right", Some(1.0))], "lists 3 eyes"),
            (vec![eye("right", Some(1.0)), eye("left", Some(1.0))], "stands where 'left' belongs"),
            (vec![eye("left", Some(f64::NAN)), eye("right", Some(1.0))], "not finite"),
            (vec![eye("left", Some(-1.0)), eye("right", Some(1.0))], "negative"),
            (vec![eye("left", None), eye("right", Some(1.0))], "missing"),
        ] {
            let e = presets_of(&file(eyes), &dir, (2, 2), Timing::Serial).unwrap_err();
            assert!(e.to_string().starts_with("the peer: ") && e.to_string().contains(says), "{e}");
            assert_eq!(e.exit_code(), 1, "a peer's failure is the peer's, not a GPU error");
        }
    }

    #[test]
    fn a_peer_is_ended_when_vrao_is_interrupted() {
        let child = std::process::Command::new("sleep").arg("30").spawn().unwrap();
        let interrupt = std::sync::atomic::AtomicBool::new(true);
        let started = std::time::Instant::now();
        let e = wait_for_peer(child, &interrupt).unwrap_err();
        assert!(matches!(e, Error::Engine(vrao_ao::Error::Interrupted)), "{e}");
        assert!(started.elapsed() < std::time::Duration::from_secs(10), "the peer was ended, not waited for");
    }

    fn options() -> PeerOptions {
        PeerOptions {
            backend: BackendChoice::Auto,
            peer: PathBuf::from("/nonexistent/peer"),
            presets: vec![],
            samples: vec![12],
            half_res: vec![true],
            timing: TimingChoice::Auto,
            warmup: 1,
            frames: 1,
            rounds: 1,
            reference: ReferenceOptions { rays_per_pixel: 16, stride: 8, cache: PathBuf::from("/tmp") },
            out: PathBuf::from("/tmp"),
            gltf: PathBuf::from("/nonexistent/scene.glb"),
            interrupt: Default::default(),
        }
    }

    #[test]
    fn options_out_of_range_are_refused_naming_the_value() {
        let mut o = options();
        assert!(check_options(&o).is_ok());
        o.rounds = 0;
        assert!(check_options(&o).unwrap_err().to_string().contains("0 rounds"));
        o.rounds = 1;
        o.presets = vec!["extreme".into()];
        assert!(check_options(&o).unwrap_err().to_string().contains("'extreme'"));
        o.presets = vec!["high".into()];
        assert!(check_options(&o).unwrap_err().to_string().contains("no peer program"));
        o.presets = vec![];
        o.samples = vec![12, 12];
        assert!(check_options(&o).unwrap_err().to_string().contains("12 twice"));
    }

    #[test]
    fn an_eye_line_carries_the_projection_vrao_renders_with() {
        let profile = vrao_render::HeadsetProfile::with_size("vive", 64, 80);
        let eyes = profile.eyes(&vrao_ao::HeadPose::IDENTITY, 0.05);
        let line = eye_line("left", &eyes.eyes[0], eyes.near);
        let numbers: Vec<f32> = line.split_whitespace().skip(2).map(|s| s.parse().unwrap()).collect();
        assert_eq!(numbers.len(), 32);
        let projection = vrao_ao::Fov::reversed_z_projection(&eyes.eyes[0].fov, eyes.near).as_mat4();
        assert_eq!(&numbers[16..], &projection.to_cols_array()[..]);
        // Reversed Z with the far plane at infinity: a point at the near plane lands at 1.
        let clip = projection * glam::Vec4::new(0.0, 0.0, -(eyes.near as f32), 1.0);
        assert!((clip.z / clip.w - 1.0).abs() < 1e-6);
    }

    #[test]
    fn medians_skip_what_was_not_measured() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, f64::NAN, 2.0, 3.0]), 2.5);
        assert!(median(vec![]).is_nan());
    }
}
