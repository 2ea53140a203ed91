//! One stereo frame written as PNG files, optionally rendered several times to time its
//! passes: what `vrao render` does, reachable from the library.

use crate::error::{Error, Result};
use crate::formats::output::OutputTrail;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use vrao_render::renderer::{Renderer, TimingChoice};
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;
use vrao_render::BackendChoice;

/// How [`render_still`] renders and what it writes.
#[derive(Clone, Debug)]
pub struct StillOptions {
    /// Which wgpu backend to ask for.
    pub backend: BackendChoice,
    /// How passes are submitted and timed (`Auto` decides once the adapter is known).
    pub timing: TimingChoice,
    /// Frames to render (at least 1); with more than one, a tenth (1 to 10) are warm-up
    /// and the rest are timed.
    pub frames: u32,
    /// Also write depth, normals, albedo and the occlusion per eye.
    pub debug: bool,
    /// Directory for the PNG files (created if missing).
    pub out: PathBuf,
    /// Scene time in seconds: where the head (on a scripted path) and the animated
    /// objects are.
    pub time: f64,
    /// Records the folder and files written. When its cancellation token
    /// ([`OutputTrail::interrupted_by`], the caller's Ctrl-C) is set, the render stops
    /// (between frames, pipeline builds, files) and returns `Error::Interrupted` with
    /// everything it wrote removed again.
    pub trail: OutputTrail,
    /// The headset's visibility mask (the caller's, from the headset profile) when the
    /// settings' `mask` is on: what the lens hides is skipped and stays black.
    pub mask: Option<vrao_ao::VisibilityMask>,
}

/// What [`render_still`] did.
#[derive(Clone, Debug)]
pub struct Still {
    /// One line: the scene, adapter, size, stereo path and occlusion setting.
    pub summary: String,
    /// Which passes ran and why the others were left out, then the per-pass timing table.
    pub explain: String,
    /// Every file written, in writing order.
    pub written: Vec<PathBuf>,
}

/// Renders `scene` from its head pose at `options.time` and writes `left.png` and `right.png`
/// (and with `debug` the buffers behind them) into `options.out`. The folder is made only
/// once the frames are rendered; a failure or an interrupt removes whatever was written,
/// so nothing is left behind.
pub fn render_still(scene: &Scene, settings: &Settings, options: &StillOptions) -> Result<Still> {
    let result = render_and_write(scene, settings, options);
    if result.is_err() {
        options.trail.remove_all();
    }
    result
}

fn render_and_write(scene: &Scene, settings: &Settings, options: &StillOptions) -> Result<Still> {
    settings.validate()?;
    // An unwritable directory fails before the GPU starts.
    crate::formats::output::check_output_folder(&options.out)?;
    let interrupted =
        || if options.trail.interrupted() { Err(Error::Engine(vrao_ao::Error::Interrupted)) } else { Ok(()) };
    let gpu = Arc::new(vrao_render::open(options.backend)?);
    if let Some(flag) = options.trail.interrupt_flag() {
        // An interrupt cuts the pipeline builds short (Renderer::new: Error::Engine(vrao_ao::Error::Interrupted)).
        gpu.cancel_builds_on(flag);
    }
    interrupted()?;
    let mut renderer = Renderer::new(gpu.clone(), scene, settings)?;
    renderer.set_timing(options.timing.resolve(&gpu));
    renderer.set_visibility_mask(options.mask.clone().filter(|_| settings.ao.mask));
    renderer.set_scene_time(options.time);
    let eyes = settings.profile.eyes(&scene.head.pose_at(options.time), settings.near);
    let outputs = crate::formats::output::outputs(settings, options.debug);
    // Warm-up frames (pipeline compilation, first-touch allocation) are not measured.
    let frames = options.frames.max(1);
    let warmup = if frames > 1 { (frames / 10).clamp(1, 10) } else { 0 };
    let mut timings = Vec::new();
    let mut report = None;
    for frame in 0..warmup + frames {
        interrupted()?;
        let r = renderer.render_and_wait(&eyes.eyes, &outputs)?;
        if frame >= warmup {
            let mut spans = r.gpu_ms.clone();
            spans.extend(r.wall_ms.iter().map(|(pass, ms)| (format!("{pass} (wall)"), *ms)));
            spans.push(("cpu encode".into(), r.cpu_encode_ms));
            timings.push(spans);
        }
        report = Some(r);
    }
    let report = report.expect("at least one frame");
    let written = crate::formats::output::write_images(&renderer, &options.out, 2, options.debug, &options.trail)?;
    let adapter = &gpu.info;
    let summary = format!(
        "rendered '{}' ({} triangles) on {}: {}x{} per eye, {} G-buffer, {} N={} r={} m{}",
        scene.name,
        scene.triangle_count(),
        adapter.name,
        settings.profile.width,
        settings.profile.height,
        if renderer.uses_multiview() { "multiview" } else { "multipass" },
        settings.ao.technique.name(),
        settings.ao.samples,
        crate::formats::output::significant(settings.ao.radius as f64, 3),
        if settings.ao.resolution.is_half() { ", half resolution" } else { "" },
    );
    let mut explain = report.plan.to_string();
    if let Some(traffic) = renderer.occlusion_traffic() {
        let chain = if gpu.caps.scalar_chain && !settings.ao.technique.carries_light() {
            "single-channel R16Float"
        } else {
            "four-channel Rgba16Float"
        };
        let _ = writeln!(
            explain,
            "occlusion passes: {:.1} bytes written and {:.1} read per pixel of each eye (declared textures; {chain} chain)",
            traffic.written, traffic.read
        );
    }
    let _ = writeln!(
        explain,
        "timing over {frames} frame(s) after {warmup} warm-up, {} ({:?}):",
        adapter.name, adapter.backend
    );
    let _ = writeln!(explain, "  {:<22} {:>10} {:>10} {:>10}", "span", "median ms", "p25 ms", "p75 ms");
    for s in crate::formats::spans::summarize(&timings) {
        let _ = writeln!(explain, "  {:<22} {:>10.3} {:>10.3} {:>10.3}", s.label, s.median_ms, s.p25_ms, s.p75_ms);
    }
    if report.gpu_ms.is_empty() {
        let _ = writeln!(explain, "  (this adapter has no timestamp queries: GPU times are not available)");
    }
    Ok(Still { summary, explain, written })
}
