//! The OpenXR headset. The loader is opened at run time (openxr's `loaded` feature), so
//! vrao runs where none is installed; a missing loader or `XR_ERROR_RUNTIME_UNAVAILABLE`
//! means "no headset here" and `vrao run` falls back to the simulated headset.
//!
//! With a runtime, [`OpenXrHeadset`] drives a real session (`openxr/session.rs`): Vulkan
//! through XR_KHR_vulkan_enable2, with the runtime creating the VkInstance and VkDevice
//! and wgpu wrapping them (`openxr/vulkan.rs`); colour and depth swapchains filled from
//! the renderer's 2-layer targets (`openxr/swapchain.rs`); a projection layer with depth
//! (XR_KHR_composition_layer_depth) so the runtime can reproject; and OpenXR's session
//! state machine, falling back to the simulated headset if the session is lost.
//!
//! Only one OpenXR instance lives in a process at a time (runtimes are not required to
//! allow more): [`probe_runtime`] and [`OpenXrHeadset::open`] share one slot.

use super::simulated::SimulatedOptions;
use crate::render::stereo::HeadPose;
use glam::{DQuat, DVec3};

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

impl From<RuntimeFailure> for crate::render::error::Error {
    /// The runtime's device could not be used: `Error::Device`.
    fn from(failure: RuntimeFailure) -> crate::render::error::Error {
        crate::render::error::Error::Device(failure.0)
    }
}

impl std::fmt::Display for Unavailable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unavailable::NotBuilt => write!(f, "vrao was built without the `xr` feature"),
            Unavailable::NoLoader(why) => write!(f, "no OpenXR loader ({why})"),
            Unavailable::NoRuntime(why) => write!(f, "no OpenXR runtime ({why})"),
            Unavailable::NoHeadset(why) => write!(f, "no OpenXR headset ({why})"),
            Unavailable::Unsupported(why) => write!(f, "the OpenXR runtime cannot be used ({why})"),
            Unavailable::Failed(why) => write!(f, "the OpenXR session could not be set up ({why})"),
            Unavailable::Busy => write!(f, "another OpenXR instance is live in this process"),
        }
    }
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
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
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
    /// Why the session was lost or a runtime call failed, if so.
    pub loss_reason: Option<String>,
    /// How the session ended (`EXITING`, a timeout, a loss), once it has.
    pub ending: Option<String>,
    /// Whether the run went on on the simulated headset after a loss.
    pub fell_back: bool,
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
    /// Clamped to the runtime's maximum.
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
        }
    }
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

/// Whether an OpenXR runtime answers: creates (and drops) an instance. Returns the
/// runtime's name and version.
#[cfg(feature = "xr")]
pub fn probe_runtime() -> Result<String, Unavailable> {
    let entry = load_entry()?;
    let _slot = InstanceSlot::take()?;
    let instance = entry
        .create_instance(&application_info(), &openxr::ExtensionSet::default(), &[], &())
        .map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
    let props = instance.properties().map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
    Ok(format!("{} {}", props.runtime_name, props.runtime_version))
}

#[cfg(not(feature = "xr"))]
pub fn probe_runtime() -> Result<String, Unavailable> {
    Err(Unavailable::NotBuilt)
}

/// A headset, the GPU to render for it, and one line saying what was opened.
pub type OpenedHeadset = (Box<dyn super::Headset>, std::sync::Arc<crate::render::gpu::Gpu>, String);

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
    fn heading_of_a_straight_down_view_is_identity() {
        let pose = HeadPose::look_at(DVec3::ZERO, DVec3::new(0.0, -1.0, 0.0)).unwrap();
        assert_eq!(heading_only(&pose).orientation, DQuat::IDENTITY);
    }
}
