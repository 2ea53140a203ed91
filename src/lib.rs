//! vrao, the application: the `vrao` binary's library. It drives the renderer
//! (`vrao-render`, built on the AO engine `vrao-ao`) on OpenXR and simulated headsets with
//! a desktop mirror, and measures it against a ray-traced reference.
//!
//! Folders with a dependency rule (checked by `tests/layout.rs`): `xr` (headsets) imports
//! only the renderer; `app` (the frame loop, governor and window) and `measure`
//! (reference, metrics, bench, studies) import the renderer and `xr` but not each other;
//! `formats` (the bench file, still images, writers), `test_assets` and `stats` (the one
//! definition of a quantile) are shared. The
//! CLI (`src/cli/`) is the binary's. The renderer and the engine are named by their own
//! names (`vrao_render::…`, `vrao_ao::…`); [`error`] wraps the engine's error with the
//! application's own failures and exit codes.
//!
//! Cargo features: `app` (default) adds `app`, `measure` and `xr` with what they use
//! (winit, egui, clap, the reference tracer's rayon and BVH, the bench's plots and FLIP);
//! the `vrao` binary needs it. `xr` (default, implies `app`) adds the OpenXR headset.
//! `gltf` (default) reads glTF scenes. `testing` adds the test oracle
//! `measure::analytic` (with `app`).

#[cfg(feature = "app")]
pub mod app;
pub mod error;
pub mod formats;
#[cfg(feature = "app")]
pub mod measure;
pub mod stats;
pub mod test_assets;
#[cfg(feature = "app")]
pub mod xr;

pub use error::{Error, Result};

/// A shader of a WGSL file named by its path from the workspace root (the
/// application's files live in `shaders/`).
#[cfg(feature = "app")]
macro_rules! wgsl {
    ($path:literal) => {
        vrao_ao::plug::Shader { path: $path, source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $path)) }
    };
}

#[cfg(feature = "app")]
pub(crate) use wgsl;
