//! The OpenXR headset. The loader is opened at run time (openxr's `loaded` feature), so
//! vrao runs where none is installed; a missing loader or `XR_ERROR_RUNTIME_UNAVAILABLE`
//! means "no headset here" and `vrao run` falls back to the simulated headset.
//!
//! With a runtime, [`OpenXrHeadset`] drives a real session (`openxr/session.rs`): Vulkan
//! through XR_KHR_vulkan_enable2, with the runtime creating the VkInstance and VkDevice
//! and wgpu wrapping them (`openxr/vulkan.rs`); colour and depth swapchains filled from
//! the renderer's 2-layer targets (`openxr/swapchain.rs`); a projection layer with depth
//! (XR_KHR_composition_layer_depth) so the runtime can reproject; the lens's visibility
//! mask (XR_KHR_visibility_mask, `openxr/mask.rs`); and OpenXR's session state machine,
//! falling back to the simulated headset if the session is lost.
//!
//! Only one OpenXR instance lives in a process at a time (runtimes are not required to
//! allow more): [`probe_runtime`] and [`OpenXrHeadset::open`] share one slot.

use super::simulated::SimulatedOptions;
use glam::{DQuat, DVec3};
use vrao_ao::HeadPose;

pub mod mask;
#[cfg(feature = "xr")]
mod session;
pub mod state;
#[cfg(feature = "xr")]
mod swapchain;
#[cfg(feature = "xr")]
mod vulkan;

#[cfg(feature = "xr")]
pub use session::{OpenXrHeadset, OpenXrStats};
#[cfg(feature = "xr")]
pub use swapchain::{EyeBlit, SwapchainLayout};

/// Why no OpenXR headset is available, in one line for the user.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Unavailable {
    /// Built without the `xr` feature.
    NotBuilt,
    /// The OpenXR loader library could not be opened.
    NoLoader(String),
    /// The loader found no runtime (XR_ERROR_RUNTIME_UNAVAILABLE) or the runtime failed.
    NoRuntime(String),
    /// A runtime answered but has no head-mounted display (none connected, or
    /// XR_ERROR_FORM_FACTOR_UNAVAILABLE).
    NoHeadset(String),
    /// The runtime cannot give vrao what it needs: Vulkan through XR_KHR_vulkan_enable2
    /// (or vrao was asked for another backend).
    Unsupported(String),
    /// Setting up the session failed (Vulkan device, session, swapchains).
    Failed(String),
    /// Another OpenXR instance is live in this process.
    Busy,
}

/// An OpenXR or Vulkan call that failed while a session was set up or ran, in one line:
/// the call and what it returned. Setting up, it makes the headset
/// [`Unavailable::Failed`]; running, it ends the session (the state machine's loss).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct RuntimeFailure(pub String);

impl From<String> for RuntimeFailure {
    fn from(why: String) -> RuntimeFailure {
        RuntimeFailure(why)
    }
}

impl From<RuntimeFailure> for Unavailable {
    fn from(failure: RuntimeFailure) -> Unavailable {
        Unavailable::Failed(failure.0)
    }
}

impl From<RuntimeFailure> for crate::error::Error {
    /// The runtime's device could not be used: `Error::Device`.
    fn from(failure: RuntimeFailure) -> crate::error::Error {
        crate::error::Error::device(failure.0)
    }
}

impl std::fmt::Display for Unavailable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unavailable::NotBuilt => write!(f, "vrao was built without the `xr` feature"),
            Unavailable::NoLoader(why) => write!(f, "no OpenXR loader ({why})"),
            Unavailable::NoRuntime(why) => write!(f, "no OpenXR runtime: {why}"),
            Unavailable::NoHeadset(why) => write!(f, "no OpenXR headset ({why})"),
            Unavailable::Unsupported(why) => write!(f, "the OpenXR runtime cannot be used ({why})"),
            Unavailable::Failed(why) => write!(f, "the OpenXR session could not be set up ({why})"),
            Unavailable::Busy => write!(f, "another OpenXR instance is live in this process"),
        }
    }
}

/// A failed OpenXR call in one line naming the call and its XrResult, with the
/// runtime-independent meaning: `xrReleaseSwapchainImage: XR_ERROR_INSTANCE_LOST (the
/// XrInstance was lost or could not be found)`.
#[cfg(feature = "xr")]
pub fn xr_call_failed(call: &str, result: openxr::sys::Result) -> String {
    format!("{call}: XR_{result:?} ({result})")
}

/// A step of OpenXR's session life cycle (XrSessionState), as the headset saw it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum SessionPhase {
    /// Created, not yet ready to begin.
    Idle,
    /// Ready: the application begins the session.
    Ready,
    /// Running, frames not shown yet.
    Synchronized,
    /// Frames shown, input not focused on the application.
    Visible,
    /// Frames shown and input focused: the normal running state.
    Focused,
    /// The runtime asks the application to end the session.
    Stopping,
    /// The session is being lost (device unplugged, runtime failing).
    LossPending,
    /// The session is over; the application may leave.
    Exiting,
}

impl SessionPhase {
    /// The state's OpenXR name without the prefix (`IDLE`, `READY`, …).
    pub fn name(self) -> &'static str {
        match self {
            SessionPhase::Idle => "IDLE",
            SessionPhase::Ready => "READY",
            SessionPhase::Synchronized => "SYNCHRONIZED",
            SessionPhase::Visible => "VISIBLE",
            SessionPhase::Focused => "FOCUSED",
            SessionPhase::Stopping => "STOPPING",
            SessionPhase::LossPending => "LOSS_PENDING",
            SessionPhase::Exiting => "EXITING",
        }
    }
}

impl std::fmt::Display for SessionPhase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What an OpenXR session did, for reports and tests (`Headset::openxr_report`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct OpenXrReport {
    /// The runtime's name and version.
    pub runtime: String,
    /// Session states in the order seen (XrSessionState names), consecutive repeats
    /// dropped.
    pub states_seen: Vec<String>,
    /// Frames the application rendered and submitted with an image (what `--frames`
    /// counts).
    pub frames_rendered: u64,
    /// Frames ended with the projection layer.
    pub layers_submitted: u64,
    /// Of those, layers whose views carried depth (XR_KHR_composition_layer_depth).
    pub depth_layers_submitted: u64,
    /// Frames ended without a layer (not rendered, or run while leaving).
    pub empty_frames: u64,
    /// Frames the runtime told vrao not to render (shouldRender false).
    pub not_rendered: u64,
    /// Refreshes of the display the runtime skipped between the frames it handed out:
    /// the gaps between successive predicted display times in refreshes of the display
    /// (`refresh_period_ms`), beyond one; a 100 ms gap on a 50 ms display is 1 (OpenXR
    /// says nothing more about late or dropped frames: the compositor's own counts are
    /// not visible to vrao).
    pub missed_display_periods: u64,
    /// The runtime's latest predicted display period (ms). Not the budget: the runtime
    /// stretches it to whole refreshes when frames are late.
    pub display_period_ms: f64,
    /// The display's refresh period (ms), the frame budget: from the refresh rate the
    /// runtime reports (XR_FB_display_refresh_rate), else the shortest predicted display
    /// period seen; `None` before either.
    pub refresh_period_ms: Option<f64>,
    /// The session state the run was interrupted in (Ctrl-C), if it was.
    pub interrupted_in: Option<String>,
    /// The display refresh rates the runtime offers (XR_FB_display_refresh_rate; empty
    /// when it does not have the extension).
    pub display_refresh_rates_hz: Vec<f32>,
    /// The display refresh rate the runtime last reported through the extension (after
    /// vrao asked for the profile's, when offered), following its change events.
    pub display_refresh_rate_hz: Option<f32>,
    /// Why the session was lost or a runtime call failed, if so.
    pub loss_reason: Option<String>,
    /// How the session ended (`EXITING`, a timeout, a loss), once it has.
    pub ending: Option<String>,
    /// Whether the run went on on the simulated headset after a loss.
    pub fell_back: bool,
    /// Whether each view's visibility mask was read from the runtime
    /// (XR_KHR_visibility_mask); otherwise it is Monado's default from each view's field
    /// of view (the runtime lacks the extension, or vrao does not call it: the run
    /// report's `visibility_mask` says why).
    pub visibility_mask_from_runtime: bool,
    /// The runtime's XrEventDataVisibilityMaskChangedKHR events followed (each view's mask
    /// read again).
    pub visibility_mask_changes: u64,
}

/// How `vrao run` (or a test) wants the OpenXR headset driven.
#[derive(Clone, Debug)]
pub struct OpenXrOptions {
    /// Near plane in metres (the far plane is at infinity; the depth layer says so).
    pub near: f64,
    /// Where the tracking space's origin sits in the scene: the runtime's LOCAL space
    /// (origin at the head's starting position) is placed at this pose, so the user
    /// starts where the scene's head pose is, facing its way.
    pub origin: HeadPose,
    /// Per-eye render and swapchain size; `None` takes the runtime's recommended size.
    /// A size above the runtime's maximum is scaled down to it with its aspect kept
    /// ([`fit_within`]), with a warning naming both.
    pub size: Option<(u32, u32)>,
    /// End the session after this many rendered frames (submitted with an image):
    /// xrRequestExitSession, then STOPPING → xrEndSession → EXITING, and `wait_frame`
    /// returns `None`.
    pub frames: Option<u64>,
    /// Log session state changes at the info level (debug otherwise); a lost session's
    /// fall back is a warning either way.
    pub report: bool,
    /// Force one swapchain layout (`None`: a 2-layer array when the runtime accepts
    /// one, otherwise one swapchain per eye).
    #[cfg(feature = "xr")]
    pub layout: Option<SwapchainLayout>,
    /// What to continue with when the session is lost (LOSS_PENDING, a lost instance or
    /// a failing runtime); `None` ends the run instead.
    pub fallback: Option<SimulatedOptions>,
    /// The refresh rate to ask the runtime for (XR_FB_display_refresh_rate), when it
    /// offers that rate; the runtime's predicted display period sets the budget either way.
    pub preferred_refresh_hz: Option<f64>,
    /// The caller's cancellation token (its Ctrl-C handler sets it): checked in every
    /// wait, so the session ends from whatever state it is in. `None`: not interruptible.
    pub interrupt: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl OpenXrOptions {
    /// Options matching a simulated headset's: its near plane, frame count and the
    /// start of its head path as the tracking origin (heading only: a tilted scene pose
    /// would tilt the horizon in a real headset). The simulated options are kept as the
    /// fall back.
    pub fn from_simulated(simulated: &SimulatedOptions, size: Option<(u32, u32)>) -> OpenXrOptions {
        OpenXrOptions {
            near: simulated.near,
            origin: heading_only(&simulated.path.pose_at(0.0)),
            size,
            frames: simulated.frames,
            report: true,
            #[cfg(feature = "xr")]
            layout: None,
            fallback: Some(simulated.clone()),
            preferred_refresh_hz: Some(simulated.profile.refresh_hz),
            interrupt: None,
        }
    }
}

/// `wanted` scaled down to fit within `max` with its aspect kept (each side rounded, at
/// least 1); a size that fits is returned as it is. 4000×3000 within 1920×1080 is
/// 1440×1080.
pub fn fit_within(wanted: (u32, u32), max: (u32, u32)) -> (u32, u32) {
    let (w, h) = (u64::from(wanted.0.max(1)), u64::from(wanted.1.max(1)));
    let (max_w, max_h) = (u64::from(max.0.max(1)), u64::from(max.1.max(1)));
    if w <= max_w && h <= max_h {
        return (w as u32, h as u32);
    }
    // Whichever side is tighter sets the scale: w / max_w against h / max_h.
    let (w, h) =
        if w * max_h >= h * max_w { (max_w, (h * max_w + w / 2) / w) } else { ((w * max_h + h / 2) / h, max_h) };
    (w.clamp(1, max_w) as u32, h.clamp(1, max_h) as u32)
}

/// `pose` with its pitch and roll removed (yaw about +Y kept).
pub fn heading_only(pose: &HeadPose) -> HeadPose {
    let pose = pose.sanitized();
    let forward = pose.orientation * -DVec3::Z;
    let flat = DVec3::new(forward.x, 0.0, forward.z);
    let orientation = if flat.length_squared() < 1e-12 {
        DQuat::IDENTITY
    } else {
        DQuat::from_rotation_y(f64::atan2(-flat.x, -flat.z))
    };
    HeadPose { position: pose.position, orientation }
}

/// The one OpenXR instance a process may have at a time.
#[cfg(feature = "xr")]
static INSTANCE_LIVE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Holds the process's OpenXR instance slot while alive.
#[cfg(feature = "xr")]
struct InstanceSlot;

#[cfg(feature = "xr")]
impl InstanceSlot {
    fn take() -> Result<InstanceSlot, Unavailable> {
        use std::sync::atomic::Ordering;
        if INSTANCE_LIVE.swap(true, Ordering::AcqRel) {
            return Err(Unavailable::Busy);
        }
        Ok(InstanceSlot)
    }
}

#[cfg(feature = "xr")]
impl Drop for InstanceSlot {
    fn drop(&mut self) {
        INSTANCE_LIVE.store(false, std::sync::atomic::Ordering::Release);
    }
}

/// The loader's library names, unversioned first (a -dev install), then the soname the
/// runtime package ships (Debian's libopenxr-loader1 has only `libopenxr_loader.so.1`).
#[cfg(feature = "xr")]
const LOADER_NAMES: [&str; 2] = ["libopenxr_loader.so", "libopenxr_loader.so.1"];

/// Opens the OpenXR loader.
#[cfg(feature = "xr")]
pub fn load_entry() -> Result<openxr::Entry, Unavailable> {
    // The loader reads XR_RUNTIME_JSON's manifest unbounded (a device such as /dev/zero
    // is read forever): vrao checks it first, as it reads every file a user names.
    if let Some(manifest) = std::env::var_os("XR_RUNTIME_JSON").filter(|v| !v.is_empty()) {
        let manifest = std::path::PathBuf::from(manifest);
        if let Err(e) = vrao_render::files::read_regular_file_to_string(&manifest, vrao_render::files::MAX_TEXT_BYTES) {
            let shown = manifest.display();
            return Err(Unavailable::NoRuntime(format!(
                "XR_RUNTIME_JSON manifest {shown} cannot be read: {}",
                e.problem
            )));
        }
    }
    // The loader prints its own multi-line errors to stderr when no runtime is installed;
    // vrao says why in one line instead. XR_LOADER_DEBUG set by the user still wins.
    if std::env::var_os("XR_LOADER_DEBUG").is_none() {
        std::env::set_var("XR_LOADER_DEBUG", "none");
    }
    let mut errors = Vec::new();
    for name in LOADER_NAMES {
        // SAFETY: loading the Khronos loader runs its initialisers; it is the library
        // OpenXR applications are meant to load.
        match unsafe { openxr::Entry::load_from(std::path::Path::new(name), &()) } {
            Ok(entry) => return Ok(entry),
            Err(e) => errors.push(format!("{name}: {e}")),
        }
    }
    Err(Unavailable::NoLoader(errors.join("; ")))
}

#[cfg(feature = "xr")]
fn application_info() -> openxr::ApplicationInfo<'static> {
    openxr::ApplicationInfo {
        application_name: "vrao",
        application_version: 1,
        engine_name: "vrao",
        engine_version: 1,
        api_version: openxr::Version::new(1, 0, 0),
    }
}

/// Why xrCreateInstance found no runtime, in one line naming the manifest: the one
/// `XR_RUNTIME_JSON` names (missing, unparsable, naming a library that is not there or
/// does not load) or, without it, the active_runtime.json files the loader reads.
/// `result` is what the loader said.
pub fn no_runtime(result: &str) -> Unavailable {
    let manifest = std::env::var_os("XR_RUNTIME_JSON").filter(|v| !v.is_empty()).map(std::path::PathBuf::from);
    Unavailable::NoRuntime(runtime_trouble(manifest.as_deref(), &active_runtime_paths(), result))
}

/// Where the loader looks for the active runtime on Linux without `XR_RUNTIME_JSON`.
fn active_runtime_paths() -> Vec<std::path::PathBuf> {
    let config = std::env::var_os("XDG_CONFIG_HOME")
        .filter(|v| !v.is_empty())
        .map(std::path::PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| std::path::Path::new(&h).join(".config")));
    let system = std::env::var("XDG_CONFIG_DIRS").unwrap_or_else(|_| "/etc/xdg".into());
    let dirs = config.into_iter().chain(system.split(':').filter(|d| !d.is_empty()).map(Into::into));
    dirs.chain(["/etc".into()]).map(|d: std::path::PathBuf| d.join("openxr/1/active_runtime.json")).collect()
}

/// [`no_runtime`]'s message for `manifest` (from `XR_RUNTIME_JSON`) or, without one,
/// the first of `active` that exists.
pub fn runtime_trouble(manifest: Option<&std::path::Path>, active: &[std::path::PathBuf], result: &str) -> String {
    let (manifest, named_by) = match manifest {
        Some(path) => (path.to_path_buf(), "XR_RUNTIME_JSON"),
        None => match active.iter().find(|p| p.exists()) {
            Some(path) => (path.clone(), "the active runtime"),
            None => {
                let looked: Vec<String> = active.iter().map(|p| p.display().to_string()).collect();
                return format!(
                    "none is installed: XR_RUNTIME_JSON is not set and there is no {} ({result})",
                    looked.join(" or ")
                );
            }
        },
    };
    let shown = manifest.display();
    let text = match vrao_render::files::read_regular_file_to_string(&manifest, vrao_render::files::MAX_TEXT_BYTES) {
        Ok(text) => text,
        Err(e) => return format!("{named_by} manifest {shown} cannot be read: {}", e.problem),
    };
    let json: serde_json::Value = match serde_json::from_str(&text) {
        Ok(json) => json,
        Err(e) => return format!("{named_by} manifest {shown} does not parse as JSON: {e}"),
    };
    let Some(library) = json["runtime"]["library_path"].as_str() else {
        return format!("{named_by} manifest {shown} names no runtime.library_path");
    };
    // A relative library path is relative to the manifest's folder.
    let library_path = manifest.parent().unwrap_or(std::path::Path::new("")).join(library);
    let bare_name = !library.contains('/');
    if !bare_name && !library_path.exists() {
        return format!(
            "the runtime library {} that {named_by} manifest {shown} names does not exist",
            library_path.display()
        );
    }
    format!("the runtime library {library} that {named_by} manifest {shown} names did not load or start ({result})")
}

/// Whether an OpenXR runtime answers: creates (and drops) an instance. Returns the
/// runtime's name and version.
#[cfg(feature = "xr")]
pub fn probe_runtime() -> Result<String, Unavailable> {
    let entry = load_entry()?;
    let _slot = InstanceSlot::take()?;
    let instance = entry
        .create_instance(&application_info(), &openxr::ExtensionSet::default(), &[], &())
        .map_err(|e| no_runtime(&xr_call_failed("xrCreateInstance", e)))?;
    let props = instance.properties().map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
    Ok(format!("{} {}", props.runtime_name, props.runtime_version))
}

#[cfg(not(feature = "xr"))]
pub fn probe_runtime() -> Result<String, Unavailable> {
    Err(Unavailable::NotBuilt)
}

/// A headset, the GPU to render for it, and one line saying what was opened.
pub type OpenedHeadset = (Box<dyn super::Headset>, std::sync::Arc<vrao_ao::plug::Gpu>, String);

/// Opens the OpenXR headset and the GPU its session runs on, for `vrao run`.
#[cfg(feature = "xr")]
pub fn open_headset(options: OpenXrOptions) -> Result<OpenedHeadset, Unavailable> {
    use super::Headset as _;
    let (headset, gpu) = OpenXrHeadset::open(options)?;
    let message = format!("an OpenXR runtime answered: using the {}", headset.describe());
    Ok((Box::new(headset), gpu, message))
}

#[cfg(not(feature = "xr"))]
pub fn open_headset(_options: OpenXrOptions) -> Result<OpenedHeadset, Unavailable> {
    Err(Unavailable::NotBuilt)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heading_only_keeps_yaw_and_position() {
        let pose = HeadPose::look_at(DVec3::new(1.0, 1.6, 2.0), DVec3::new(-2.0, 0.5, -1.0)).unwrap();
        let flat = heading_only(&pose);
        assert_eq!(flat.position, pose.position);
        let forward = flat.orientation * -DVec3::Z;
        assert!(forward.y.abs() < 1e-12);
        let expected = DVec3::new(-3.0, 0.0, -3.0).normalize();
        assert!((forward - expected).length() < 1e-9, "{forward:?}");
        let up = flat.orientation * DVec3::Y;
        assert!((up - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn a_missing_runtime_is_explained_by_its_manifest() {
        let dir = std::env::temp_dir().join(format!("vrao-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let result = "xrCreateInstance: XR_ERROR_RUNTIME_UNAVAILABLE";
        let trouble = |manifest: &std::path::Path| runtime_trouble(Some(manifest), &[], result);
        // Named by XR_RUNTIME_JSON but not there.
        let missing = dir.join("missing.json");
        let t = trouble(&missing);
        assert!(
            t.contains("XR_RUNTIME_JSON manifest") && t.contains("missing.json") && t.contains("cannot be read"),
            "{t}"
        );
        // Not JSON.
        let broken = dir.join("broken.json");
        std::fs::write(&broken, "{ not json").unwrap();
        let t = trouble(&broken);
        assert!(t.contains("broken.json") && t.contains("does not parse as JSON"), "{t}");
        // JSON naming a library that is not there (relative to the manifest's folder).
        let gone = dir.join("gone.json");
        std::fs::write(&gone, r#"{"file_format_version": "1.0.0", "runtime": {"library_path": "./libgone.so"}}"#)
            .unwrap();
        let t = trouble(&gone);
        assert!(t.contains("libgone.so") && t.contains("does not exist") && t.contains("gone.json"), "{t}");
        // A library that is there but did not start: the loader's result is kept.
        let present = dir.join("present.json");
        std::fs::write(dir.join("libpresent.so"), "not a library").unwrap();
        std::fs::write(&present, r#"{"runtime": {"library_path": "libpresent.so"}}"#).unwrap();
        let t = trouble(&present);
        assert!(t.contains("did not load or start") && t.contains("XR_ERROR_RUNTIME_UNAVAILABLE"), "{t}");
        // No manifest at all: where the loader looked.
        let t = runtime_trouble(None, &[dir.join("active_runtime.json")], result);
        assert!(t.contains("XR_RUNTIME_JSON is not set") && t.contains("active_runtime.json"), "{t}");
        for t in [trouble(&missing), trouble(&broken), trouble(&gone)] {
            assert!(!t.contains('\n') && !t.contains("GPU"), "{t}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_size_above_the_maximum_is_scaled_down_with_its_aspect_kept() {
        assert_eq!(fit_within((4000, 3000), (1920, 1080)), (1440, 1080), "4:3 stays 4:3");
        assert_eq!(fit_within((4000, 1000), (1920, 1080)), (1920, 480), "the width is the tighter side");
        assert_eq!(fit_within((1920, 1080), (1920, 1080)), (1920, 1080));
        assert_eq!(fit_within((320, 240), (1920, 1080)), (320, 240), "a size that fits is kept");
        assert_eq!(fit_within((8192, 1), (1920, 1080)), (1920, 1), "never below one pixel");
        assert_eq!(fit_within((3000, 3000), (1920, 1080)), (1080, 1080));
        // Each side rounded: 2000 × 1080 / 1333 = 1620.4.
        assert_eq!(fit_within((2000, 1333), (1920, 1080)), (1620, 1080));
    }

    #[test]
    fn heading_of_a_straight_down_view_is_identity() {
        let pose = HeadPose::look_at(DVec3::ZERO, DVec3::new(0.0, -1.0, 0.0)).unwrap();
        assert_eq!(heading_only(&pose).orientation, DQuat::IDENTITY);
    }
}
