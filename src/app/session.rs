//! `vrao run` as one call: the headset profile and size, the budget governor, the headset
//! (OpenXR or simulated), and the frame loop with or without a window until it ends or
//! the caller's interrupt flag is set.

use crate::app::governor::{Frontier, Governor, GovernorConfig};
use crate::app::window::{open_event_loop, run_window, WindowOptions};
use crate::app::{open_headset, BufferView, FrameLoop, HeadsetChoice, HeadsetError, RunSummary};
use crate::error::{Error, Result};
use crate::xr::simulated::motion::HeadMotion;
use crate::xr::simulated::reproject::ReprojectionMode;
use crate::xr::simulated::{SimulatedOptions, TimeMode};
use crate::xr::Headset;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use vrao_ao::plug::Gpu;
use vrao_render::renderer::{Renderer, DEFAULT_FRAMES_IN_FLIGHT};
use vrao_render::scene::Scene;
use vrao_render::settings::{DisplayMode, Settings};
use vrao_render::BackendChoice;

/// The most frames a session renders when asked for a count (a day at 90 Hz is 7.8 M).
pub const RUN_FRAMES_MAX: u64 = 10_000_000;

/// How [`run_session`] runs; `Default` is a simulated-or-OpenXR Vive session with no
/// window, the governor on, until 600 frames.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Which wgpu backend to ask for.
    pub backend: BackendChoice,
    /// Simulated headset, OpenXR, or whichever is available.
    pub headset: HeadsetChoice,
    /// What the desktop window shows (`None`: no window).
    pub display: DisplayMode,
    /// Stop after this many frames (`None`: until the window closes; 600 without one).
    pub frames: Option<u64>,
    /// The simulated headset's head motion and compositor reprojection.
    pub motion: HeadMotion,
    /// How the simulated compositor reprojects a late frame.
    pub reprojection: ReprojectionMode,
    /// Non-empty: the simulated headset runs in virtual time, frames taking these render
    /// times in ms (cycled).
    pub virtual_time: Vec<f64>,
    /// A profile name of [`crate::xr::profiles::by_name`], its refresh rate and per-eye
    /// size overridden where given.
    pub profile: String,
    /// Refresh rate override (Hz).
    pub refresh: Option<f64>,
    /// Per-eye width override (pixels).
    pub width: Option<u32>,
    /// Per-eye height override (pixels).
    pub height: Option<u32>,
    /// The budget governor, with this frontier (`None`: the built-in one).
    pub governor: bool,
    /// A bench JSON to take the frontier from (`None`: the built-in one).
    pub governor_frontier: Option<PathBuf>,
    /// Frames the GPU may work on at once (at least 1).
    pub frames_in_flight: usize,
    /// The desktop window's size, last picture and buffer view.
    pub window: (u32, u32),
    /// Save the window's last picture to this PNG.
    pub screenshot: Option<PathBuf>,
    /// Which buffer the window shows (eyes, AO, depth, …); needs a window.
    pub show: BufferView,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            backend: BackendChoice::Auto,
            headset: HeadsetChoice::Auto,
            display: DisplayMode::None,
            frames: None,
            motion: HeadMotion::Static,
            reprojection: ReprojectionMode::Depth,
            virtual_time: Vec::new(),
            profile: "vive".into(),
            refresh: None,
            width: None,
            height: None,
            governor: true,
            governor_frontier: None,
            frames_in_flight: DEFAULT_FRAMES_IN_FLIGHT,
            window: (1280, 720),
            screenshot: None,
            show: BufferView::Eyes,
        }
    }
}

/// Why a session could not start, by the setting at fault (the command line names its
/// option from the variant); anything else is [`SessionError::Other`].
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// [`RunOptions::profile`] names no headset profile.
    #[error("{0}")]
    Profile(Error),
    /// [`RunOptions::refresh`] is not a rate the profile supports.
    #[error("{0}")]
    Refresh(Error),
    /// [`RunOptions::show`] asks for a buffer view without a window to show it in.
    #[error("the {} buffer view needs a window (a mirror or single-pass display)", .0.name())]
    ViewNeedsWindow(BufferView),
    /// [`RunOptions::screenshot`] asks for the window's picture without a window.
    #[error("a screenshot needs a window (a mirror or single-pass display)")]
    ScreenshotNeedsWindow,
    /// [`RunOptions::frames`] is 0 or above [`RUN_FRAMES_MAX`].
    #[error("{0} frames is not within 1..={RUN_FRAMES_MAX}")]
    Frames(u64),
    /// [`RunOptions::virtual_time`] has a render time out of range.
    #[error("{0}")]
    VirtualTime(Error),
    /// [`RunOptions::governor_frontier`] cannot be read or governed with.
    #[error("{0}")]
    Frontier(Error),
    /// A window display mode and no desktop display to open it on (checked before the
    /// headset opens).
    #[error("{0}")]
    NoWindow(Error),
    /// The headset (OpenXR asked for and unavailable, or the simulated one).
    #[error(transparent)]
    Headset(#[from] HeadsetError),
    /// Any other failure.
    #[error(transparent)]
    Other(#[from] Error),
}

impl From<SessionError> for Error {
    fn from(error: SessionError) -> Error {
        match error {
            SessionError::Profile(e) | SessionError::Refresh(e) | SessionError::Other(e) => e,
            SessionError::ViewNeedsWindow(_) | SessionError::ScreenshotNeedsWindow | SessionError::Frames(_) => {
                Error::input(error.to_string())
            }
            SessionError::VirtualTime(e) | SessionError::Frontier(e) | SessionError::NoWindow(e) => e,
            SessionError::Headset(e) => e.into(),
        }
    }
}

impl SessionError {
    /// Whether the session was refused before any frame (its options, its frontier, no
    /// display for its window, no headset), rather than failing while it ran.
    pub fn is_refusal(&self) -> bool {
        !matches!(self, SessionError::Other(_))
    }
}

/// The report of a session refused with `why` (one line) before it opened anything:
/// the budget of the profile `options` name (at its `--refresh`), where they name one.
pub fn refused_summary(options: &RunOptions, why: &str) -> RunSummary {
    let profile = crate::xr::profiles::by_name(&options.profile).ok().map(|p| match options.refresh {
        Some(hz) => p.with_refresh(hz).unwrap_or(p),
        None => p,
    });
    RunSummary::refused(profile.as_ref(), why)
}

/// Runs a headset session on `scene` with `settings` (their profile is replaced by the
/// one `options` names) and returns its summary. Which headset and governor it uses
/// goes to the log (info). `interrupt` is the caller's cancellation token (its Ctrl-C
/// handler sets it; the library installs none): setting it at any time, from start-up
/// on, ends the session cleanly from whatever state it is in (an OpenXR session before
/// READY or stopped by the runtime included); the summary is still returned, with
/// `interrupted` and the state it was in.
pub fn run_session(
    scene: &Scene,
    settings: &Settings,
    options: &RunOptions,
    interrupt: Arc<AtomicBool>,
) -> std::result::Result<RunSummary, SessionError> {
    let (settings, size) = session_settings(settings, options)?;
    check_options(options)?;
    let governor = match options.governor {
        true => Some(governor_for(options, &settings).map_err(SessionError::Frontier)?),
        false => None,
    };
    // The window's display before the headset: a machine without one is refused before
    // a runtime, session, swapchains and pipelines are made for nothing.
    let event_loop = match options.display {
        DisplayMode::None => None,
        _ => Some(open_event_loop().map_err(SessionError::NoWindow)?),
    };
    let frames = options.frames.or((options.display == DisplayMode::None).then_some(600));
    let simulated = simulated_options(scene, &settings, options, frames);
    let (mut headset, gpu, message) = open_headset(options.headset, simulated, size, options.backend, &interrupt)?;
    log::info!("headset: {message}");
    if let (Some(hz), Some(report)) = (options.refresh, headset.openxr_report()) {
        let (level, line) = refresh_with_openxr(hz, &report.display_refresh_rates_hz, report.display_refresh_rate_hz);
        log::log!(level, "{line}");
    }
    let renderer = match renderer_unless_interrupted(&gpu, scene, &settings, headset.as_ref(), &interrupt) {
        Err(Error::Engine(vrao_ao::Error::Interrupted)) => {
            return end_before_frames(headset.as_mut(), &gpu, &settings, options)
        }
        renderer => renderer?,
    };
    let mut frame_loop = FrameLoop::with_renderer(gpu, renderer, headset);
    frame_loop.frame_limit = frames;
    frame_loop.exit_requested = interrupt;
    frame_loop.renderer.set_frames_in_flight(options.frames_in_flight);
    if let Some(governor) = governor {
        log_governor(&governor);
        frame_loop.set_governor(governor)?;
    }
    run_frames(frame_loop, event_loop, scene, options)
}

/// What `--refresh hz` did with an OpenXR headset, in one line and at the level to log it
/// at: the rate is the simulated headset's; a runtime is only asked for it where it
/// offers that rate (XR_FB_display_refresh_rate, `offered`; `current` the rate it runs
/// at), and its display's rate sets the budget either way.
pub fn refresh_with_openxr(hz: f64, offered: &[f32], current: Option<f32>) -> (log::Level, String) {
    let near = |rate: f32| (f64::from(rate) - hz).abs() < 0.5;
    if offered.iter().copied().any(near) && current.is_some_and(near) {
        return (log::Level::Info, format!("--refresh {hz} Hz: asked of the OpenXR runtime, which offers it"));
    }
    // Either way a whole clause: the display's rate is what sets the budget.
    let runs_at = match current {
        Some(rate) => format!("the runtime's display runs at {rate} Hz, which sets the budget"),
        None => "the runtime's display rate sets the budget".into(),
    };
    let offers = if offered.is_empty() {
        "it offers no rate to choose (no XR_FB_display_refresh_rate)".to_string()
    } else {
        let rates: Vec<String> = offered.iter().map(|r| format!("{r}")).collect();
        format!("it offers {} Hz", rates.join(", "))
    };
    (
        log::Level::Warn,
        format!("--refresh {hz} Hz is the simulated headset's and is not used with OpenXR: {runs_at} ({offers})"),
    )
}

/// Refuses the options that cannot go together or are out of range: a buffer view or a
/// screenshot without a window, a frame count, a virtual render time.
fn check_options(options: &RunOptions) -> std::result::Result<(), SessionError> {
    if options.display == DisplayMode::None && options.show != BufferView::Eyes {
        return Err(SessionError::ViewNeedsWindow(options.show));
    }
    if options.display == DisplayMode::None && options.screenshot.is_some() {
        return Err(SessionError::ScreenshotNeedsWindow);
    }
    if let Some(frames) = options.frames.filter(|n| !(1..=RUN_FRAMES_MAX).contains(n)) {
        return Err(SessionError::Frames(frames));
    }
    if !options.virtual_time.is_empty() {
        crate::xr::simulated::check_virtual_render_ms(&options.virtual_time).map_err(SessionError::VirtualTime)?;
    }
    Ok(())
}

/// The simulated headset's options (used when it stands in for OpenXR), stopping after
/// `frames` if given.
fn simulated_options(
    scene: &Scene,
    settings: &Settings,
    options: &RunOptions,
    frames: Option<u64>,
) -> SimulatedOptions {
    SimulatedOptions {
        profile: settings.profile,
        near: settings.near,
        path: scene.head.clone(),
        motion: options.motion,
        time: if options.virtual_time.is_empty() {
            TimeMode::Real
        } else {
            TimeMode::Virtual { render_ms: options.virtual_time.clone() }
        },
        reprojection: options.reprojection,
        compose: options.display == DisplayMode::Mirror,
        frames,
    }
}

/// The session's renderer, or [`Error::Interrupted`] when `interrupt` is set before or
/// while it is built.
fn renderer_unless_interrupted(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    settings: &Settings,
    headset: &dyn Headset,
    interrupt: &Arc<AtomicBool>,
) -> Result<Renderer> {
    // Interrupted while the headset opened, or while the renderer compiled its pipelines
    // (up to 2 s on a CPU adapter; the interrupt cuts that short): end the session now.
    gpu.cancel_builds_on(interrupt.clone());
    if interrupt.load(Ordering::Relaxed) {
        Err(Error::Engine(vrao_ao::Error::Interrupted))
    } else {
        FrameLoop::renderer_for(gpu, scene, settings, headset)
    }
}

/// Ends an interrupted session before its first frame: asks the headset to exit, submits
/// empty frames until it does, and returns the summary of the state it was in.
fn end_before_frames(
    headset: &mut dyn Headset,
    gpu: &Arc<Gpu>,
    settings: &Settings,
    options: &RunOptions,
) -> std::result::Result<RunSummary, SessionError> {
    let state = headset.session_state();
    headset.request_exit();
    while headset.wait_frame(gpu)?.is_some_and(|request| headset.submit(gpu, &request, None).is_ok()) {}
    headset.end(gpu)?;
    Ok(RunSummary::before_frames(headset, gpu, settings, state, options.frames_in_flight))
}

/// Logs the governor's frontier and starting level.
fn log_governor(governor: &Governor) {
    let frontier = governor.frontier();
    log::info!(
        "governor: on, {} levels (measured at r={} m) from {} to {}; starting at {}",
        frontier.len(),
        crate::formats::output::significant(f64::from(frontier.radius_m()), 2),
        frontier.levels()[0].setting,
        frontier.levels()[frontier.top()].setting,
        governor.current().setting
    );
}

/// Runs the frame loop to its end: headless, or in the desktop window on `event_loop`.
fn run_frames(
    mut frame_loop: FrameLoop,
    event_loop: Option<winit::event_loop::EventLoop<()>>,
    scene: &Scene,
    options: &RunOptions,
) -> std::result::Result<RunSummary, SessionError> {
    match event_loop {
        None => {
            while frame_loop.step()?.is_some() {}
            frame_loop.end()?;
            Ok(RunSummary::of(&frame_loop))
        }
        Some(event_loop) => {
            let window = WindowOptions {
                mode: options.display,
                size: options.window,
                screenshot: options.screenshot.clone(),
                show: options.show,
            };
            Ok(run_window(event_loop, frame_loop, scene, window)?)
        }
    }
}

/// `settings` with the headset profile `options` names, at its refresh rate and size,
/// and the per-eye size asked for instead of the headset's own, if any (a side not
/// given is the profile's).
fn session_settings(
    settings: &Settings,
    options: &RunOptions,
) -> std::result::Result<(Settings, Option<(u32, u32)>), SessionError> {
    let mut profile = crate::xr::profiles::by_name(&options.profile).map_err(SessionError::Profile)?;
    if let Some(hz) = options.refresh {
        profile = profile.with_refresh(hz).map_err(|e| SessionError::Refresh(e.into()))?;
    }
    let size = match (options.width, options.height) {
        (None, None) => None,
        (w, h) => Some((w.unwrap_or(profile.width), h.unwrap_or(profile.height))),
    };
    if let Some((w, h)) = size {
        profile = profile.with_render_size(w, h);
    }
    let mut settings = settings.clone();
    settings.profile = profile;
    settings.validate().map_err(Error::from)?;
    Ok((settings, size))
}

/// The governor of a session: its frontier (the bench file given, or the built-in one),
/// labelled at the radius the run applies, at the frame budget of the profile, starting
/// at the level nearest the asked setting ([`Frontier::nearest`]).
fn governor_for(options: &RunOptions, settings: &Settings) -> Result<Governor> {
    let radius = settings.ao.radius;
    let frontier = match &options.governor_frontier {
        Some(path) => {
            let text = vrao_render::files::read_regular_file_to_string(path, vrao_render::files::MAX_TEXT_BYTES)?;
            Frontier::from_json(&text, path, radius)?
        }
        None => Frontier::builtin_at(radius),
    };
    let start = frontier.nearest(&settings.ao);
    let config = GovernorConfig::for_refresh_hz(settings.profile.refresh_hz);
    Governor::new(frontier, config, start)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refresh_with_openxr_says_it_is_the_simulated_headsets_unless_the_runtime_took_it() {
        // Monado's null compositor: 20 Hz alone.
        let (level, line) = refresh_with_openxr(90.0, &[20.0], Some(20.0));
        assert_eq!(level, log::Level::Warn);
        assert!(line.starts_with("--refresh 90 Hz is the simulated headset's"), "{line}");
        assert!(line.contains("runs at 20 Hz, which sets the budget") && line.contains("offers 20 Hz"), "{line}");
        assert!(!line.contains('\n'), "{line}");
        // No XR_FB_display_refresh_rate.
        let (level, line) = refresh_with_openxr(72.0, &[], None);
        assert_eq!(level, log::Level::Warn);
        assert!(line.contains("no XR_FB_display_refresh_rate"), "{line}");
        // The clause without a rate still has its verb.
        assert!(line.contains("the runtime's display rate sets the budget"), "{line}");
        // A runtime offering the rate was asked for it: said at the info level.
        let (level, line) = refresh_with_openxr(72.0, &[72.0, 90.0, 120.0], Some(72.0));
        assert_eq!(level, log::Level::Info);
        assert!(line.contains("asked of the OpenXR runtime"), "{line}");
    }

    #[test]
    fn a_refused_session_reports_why_with_its_profiles_budget() {
        let options = RunOptions { profile: "index".into(), refresh: Some(144.0), ..RunOptions::default() };
        let summary = refused_summary(&options, "cannot open a desktop window");
        assert_eq!(summary.refused.as_deref(), Some("cannot open a desktop window"));
        assert!((summary.budget_ms - 1000.0 / 144.0).abs() < 1e-9, "{}", summary.budget_ms);
        assert!(summary.budget_source.contains("refused before a headset opened"), "{}", summary.budget_source);
        assert_eq!((summary.frames_rendered, summary.interrupted), (0, false));
        let unknown = RunOptions { profile: "nope".into(), ..RunOptions::default() };
        assert_eq!(refused_summary(&unknown, "no profile").budget_ms, 0.0);
    }
}
