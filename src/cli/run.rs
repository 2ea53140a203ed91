//! `vrao run`: a headset session (OpenXR or the simulated headset), with a desktop window.

use super::{choice, AoArgs, OnOff, SCENE_HELP};
use clap::Args;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use vrao::app::{
    refused_summary, run_session, BufferView, HeadsetChoice, HeadsetError, RunOptions, SessionError, RUN_FRAMES_MAX,
};
use vrao::xr::simulated::motion::HeadMotion;
use vrao::xr::simulated::reproject::ReprojectionMode;
use vrao::{Error, Result};
use vrao_render::renderer::DEFAULT_FRAMES_IN_FLIGHT;
use vrao_render::settings::{DisplayMode, EYE_SIDE_MAX};
use vrao_render::{BackendChoice, Scene, Settings};

#[derive(Args)]
pub(crate) struct RunArgs {
    #[arg(long, default_value = "builtin:room", help = SCENE_HELP)]
    scene: String,
    /// Headset: auto (OpenXR if a runtime answers, else simulated), openxr or simulated.
    #[arg(long, default_value = "auto", hide_possible_values = true)]
    headset: HeadsetChoice,
    /// Desktop window: none, mirror (both eyes side by side) or single-pass (mono view).
    #[arg(value_parser = choice::<DisplayMode>(), long, default_value = "mirror", hide_possible_values = true)]
    display: DisplayMode,
    /// Stop after this many frames, 1..=10000000 (default: until the window is closed;
    /// 600 without one).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(1..=RUN_FRAMES_MAX))]
    frames: Option<u64>,
    /// Simulated head motion: static, yaw-sweep, figure-eight or head-roll.
    #[arg(long, default_value = "static", hide_possible_values = true)]
    motion: HeadMotion,
    /// Simulated compositor reprojection: rotational or depth.
    #[arg(long, default_value = "depth", hide_possible_values = true)]
    reprojection: ReprojectionMode,
    /// Run the simulated headset in virtual time, each frame taking these render times
    /// in ms (cycled), each within 0..=10000: deterministic counters.
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',')]
    virtual_time: Vec<f64>,
    /// Headset profile of the simulated headset: vive, vive-pro-2, index, quest-2,
    /// quest-3 or pico-4 (per-eye size, field of view, refresh rate; the frame budget
    /// follows the rate). An OpenXR runtime's recommended size and views win over it.
    #[arg(long, default_value = "vive")]
    profile: String,
    /// Refresh rate in Hz of the simulated headset, 10..=500 (default: the profile's).
    /// With OpenXR the display's rate sets the frame budget; the rate is asked of the
    /// runtime only where it offers it (XR_FB_display_refresh_rate), else a warning says
    /// it is not used.
    #[arg(long, allow_negative_numbers = true)]
    refresh: Option<f64>,
    /// Per-eye width to render at, 1..=8192 (default: the profile's; with OpenXR, the
    /// runtime's).
    // Checked here, alone: checked with the other side filled in, a bad value was named
    // with a profile's size that OpenXR never uses.
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=EYE_SIDE_MAX as i64))]
    width: Option<u32>,
    /// Per-eye height to render at, 1..=8192 (default: the profile's; with OpenXR, the
    /// runtime's).
    // Checked here, alone: checked with the other side filled in, a bad value was named
    // with a profile's size that OpenXR never uses.
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=EYE_SIDE_MAX as i64))]
    height: Option<u32>,
    /// Budget governor: on (choose the AO setting by error per millisecond so that each
    /// frame's GPU time stays under the display period) or off (keep the settings).
    #[arg(long, default_value = "on", hide_possible_values = true)]
    governor: OnOff,
    /// The governor's frontier: a bench JSON made by `vrao bench` (default: the built-in
    /// one, measured on the furnished room; see assets/governor/README.md).
    #[arg(long)]
    governor_frontier: Option<PathBuf>,
    /// Frames the GPU may work on at once, 1..=8.
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_FRAMES_IN_FLIGHT as u64, value_parser = clap::value_parser!(u64).range(1..=8))]
    frames_in_flight: u64,
    /// Window size WIDTHxHEIGHT, each 1..=16384.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    window: (u32, u32),
    /// Save a screenshot of the window to this PNG after the last frame.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// What the window shows of each eye: eyes, ao (the final AO), raw-ao (before any
    /// filter), depth or normals; the panel can change it.
    #[arg(long, default_value = "eyes", hide_possible_values = true)]
    show: BufferView,
    /// Write the frame counters and per-pass medians to this JSON file; also whenever the
    /// run is refused (exit 2), `refused` then saying why (not when this path itself is
    /// refused, nor after a GPU failure, exit 1).
    #[arg(long)]
    report: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

pub(crate) fn run(backend: BackendChoice, args: RunArgs) -> Result<()> {
    // Before anything that takes time or opens a session: a Ctrl-C (or SIGTERM) from
    // here on ends the run cleanly, with its report.
    let interrupt = interrupt_on_ctrl_c();
    // The report's own path first: a report that could not be written refuses the run
    // before anything else, and nothing is written.
    if let Some(report) = &args.report {
        vrao::formats::output::check_output_file(report)?;
    }
    let (scene, ao, report) = (args.scene, args.ao, args.report);
    let options = RunOptions {
        backend,
        headset: args.headset,
        display: args.display,
        frames: args.frames,
        motion: args.motion,
        reprojection: args.reprojection,
        virtual_time: args.virtual_time,
        profile: args.profile,
        refresh: args.refresh,
        width: args.width,
        height: args.height,
        governor: args.governor.on(),
        governor_frontier: args.governor_frontier,
        frames_in_flight: args.frames_in_flight as usize,
        window: args.window,
        screenshot: args.screenshot,
        show: args.show,
    };
    let summary = match session(&scene, &ao, &options, interrupt) {
        Ok(summary) => summary,
        Err(error) => {
            // Every refusal (exit 2) once the report's path is accepted leaves the report,
            // saying why, whatever refused it (an input, a file, the window, the
            // headset); a run that failed on the GPU (exit 1) leaves none.
            if let (vrao::error::EXIT_INPUT, Some(path)) = (error.exit_code(), &report) {
                let refused = refused_summary(&options, &error.to_string());
                if let Err(e) = vrao::formats::output::write_json(path, &refused) {
                    log::warn!("{e}");
                }
            }
            return Err(error);
        }
    };
    println!("{}", summary.to_text());
    match &report {
        Some(path) => vrao::formats::output::write_json(path, &summary),
        None => Ok(()),
    }
}

/// The session of `vrao run` after its report's path was accepted: the other inputs
/// checked, the scene loaded, the headset run.
fn session(
    scene: &str,
    ao: &AoArgs,
    options: &RunOptions,
    interrupt: Arc<AtomicBool>,
) -> Result<vrao::app::RunSummary> {
    if let Some(screenshot) = &options.screenshot {
        vrao::formats::output::check_output_file(screenshot)?;
    }
    // The OpenXR mask's variable is an input like `--mask`: a bad value is refused before
    // any work, whichever headset answers (the simulated one would never read it).
    vrao::xr::openxr::mask::MaskChoice::from_env().map_err(|e| Error::input(e.to_string()))?;
    let scene = Scene::load(scene)?;
    // The session replaces the profile with the one --profile names.
    let settings = Settings {
        ao: ao.settings(&scene),
        point_ssdo: ao.point_ssdo(),
        shadows: ao.lights.settings(&scene),
        ..Settings::default()
    };
    run_session(&scene, &settings, options, interrupt).map_err(name_the_option)
}

/// A flag that the first Ctrl-C (SIGINT) or SIGTERM sets, which ends the session cleanly
/// in whatever state it is (the summary and report are still written); a second one
/// while it ends stops the process (130, as a shell reports an interrupted command).
fn interrupt_on_ctrl_c() -> Arc<AtomicBool> {
    super::interrupt_on_signals("ending the session", || {})
}

/// The session's error with the command-line option that caused it named.
fn name_the_option(error: SessionError) -> Error {
    match error {
        SessionError::Profile(e) => with_option("--profile", e),
        SessionError::Refresh(e) => with_option("--refresh", e),
        SessionError::ViewNeedsWindow(view) => {
            Error::input(format!("--show {} needs a window (--display mirror or single-pass)", view.name()))
        }
        SessionError::ScreenshotNeedsWindow => {
            Error::input("--screenshot needs a window (--display mirror or single-pass)")
        }
        SessionError::Frames(n) => Error::input(format!("--frames {n} is not within 1..={RUN_FRAMES_MAX}")),
        SessionError::VirtualTime(e) => with_option("--virtual-time", e),
        SessionError::Headset(HeadsetError::OpenXrUnavailable(why)) => {
            Error::Unavailable(format!("--headset openxr: {why}"))
        }
        other => other.into(),
    }
}

/// `error` with its message led by `option`, its kind (and exit code) kept.
fn with_option(option: &str, error: Error) -> Error {
    match error {
        Error::Engine(vrao_ao::Error::Input { file, line, message }) => {
            vrao_ao::Error::Input { file, line, message: format!("{option}: {message}") }.into()
        }
        Error::Engine(vrao_ao::Error::Device(message)) => Error::device(format!("{option}: {message}")),
        Error::Unavailable(message) => Error::Unavailable(format!("{option}: {message}")),
        other => other,
    }
}

/// `WIDTHxHEIGHT`, each within 1..=16384.
fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let parsed =
        s.split_once('x').and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => Ok((w, h)),
        _ => Err(format!("'{s}' is not WIDTHxHEIGHT within 1..=16384")),
    }
}
