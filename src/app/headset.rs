//! Which headset a session drives: OpenXR when a runtime answers, the simulated one
//! otherwise, and the GPU each renders on.

use crate::error::Error;
use crate::xr::openxr::{self, OpenXrOptions, OpenedHeadset, Unavailable};
use crate::xr::simulated::{SimulatedHeadset, SimulatedOptions};
use crate::xr::Headset as _;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use vrao_render::BackendChoice;

/// Which headset `vrao run` drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum HeadsetChoice {
    /// OpenXR when a runtime answers, the simulated headset otherwise.
    #[default]
    Auto,
    /// OpenXR or an error (exit 2).
    #[value(name = "openxr")]
    OpenXr,
    /// The simulated headset; OpenXR is never touched.
    Simulated,
}

/// Why [`open_headset`] opened nothing.
#[derive(Debug, thiserror::Error)]
pub enum HeadsetError {
    /// OpenXR alone was asked for ([`HeadsetChoice::OpenXr`]) and is not available.
    #[error("OpenXR headset: {0}")]
    OpenXrUnavailable(Unavailable),
    /// The simulated headset or its GPU could not be opened.
    #[error(transparent)]
    Other(#[from] Error),
}

impl From<HeadsetError> for Error {
    /// An unavailable OpenXR headset is no GPU's fault (`Error::Unavailable`, exit 2).
    fn from(error: HeadsetError) -> Error {
        match error {
            HeadsetError::OpenXrUnavailable(_) => Error::Unavailable(error.to_string()),
            HeadsetError::Other(error) => error,
        }
    }
}

/// Opens the chosen headset and the GPU to render for it; the message says which one
/// and, on fall back, why. An OpenXR session brings its own GPU (the runtime creates the
/// Vulkan device); the simulated headset renders on `vrao_render::open(backend)`.
///
/// The OpenXR headset renders at the runtime's recommended per-eye size (and with its
/// views) unless `size` asks for another; the profile is the simulated headset's only.
/// It falls back to the simulated headset if its session is lost. Setting `interrupt`
/// (the caller's cancellation token) ends an OpenXR session from whatever state it is in,
/// within one poll of the runtime's events.
pub fn open_headset(
    choice: HeadsetChoice,
    simulated: SimulatedOptions,
    size: Option<(u32, u32)>,
    backend: BackendChoice,
    interrupt: &Arc<AtomicBool>,
) -> Result<OpenedHeadset, HeadsetError> {
    // `why`: the reason the simulated headset stands in for OpenXR, if it does.
    let simulated_headset = |why: Option<String>| -> Result<OpenedHeadset, HeadsetError> {
        let headset = SimulatedHeadset::new(simulated.clone())?;
        let gpu = Arc::new(vrao_render::open(backend).map_err(Error::from)?);
        let using = format!("using the {}", headset.describe());
        let message = match why {
            Some(why) => format!("{why}: {using}"),
            None => using,
        };
        Ok((Box::new(headset), gpu, message))
    };
    let openxr = || {
        if backend == BackendChoice::Gl {
            return Err(Unavailable::Unsupported("OpenXR sessions need the Vulkan backend, not GL".into()));
        }
        let options =
            OpenXrOptions { interrupt: Some(interrupt.clone()), ..OpenXrOptions::from_simulated(&simulated, size) };
        openxr::open_headset(options)
    };
    match choice {
        HeadsetChoice::Simulated => simulated_headset(None),
        HeadsetChoice::Auto => match openxr() {
            Ok(opened) => Ok(opened),
            Err(why) => simulated_headset(Some(why.to_string())),
        },
        HeadsetChoice::OpenXr => openxr().map_err(HeadsetError::OpenXrUnavailable),
    }
}
