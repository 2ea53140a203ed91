//! vrao, the application: the `vrao` binary's library. It drives the renderer
//! (`vrao-render`, built on the AO engine `vrao-ao`) on OpenXR and simulated headsets with
//! a desktop mirror, and measures it against a ray-traced reference.
//!
//! Folders with a dependency rule (checked by `tests/layout.rs`): `xr` (headsets) imports
//! only the renderer; `app` (the frame loop, governor and window) and `measure`
//! (reference, metrics, bench, studies) import the renderer and `xr` but not each other;
//! `formats` (the bench file, still images, writers), `test_assets` and `stats` (the one
//! definition of a quantile) are shared. The
//! CLI (`src/cli/`) is the binary's. [`render`] is the renderer crate under the name these
//! modules use.
//!
//! Cargo features: `app` (default) adds `app`, `measure` and `xr` with what they use
//! (winit, egui, clap, the reference tracer's rayon and BVH, the bench's plots and FLIP);
//! the `vrao` binary needs it. `xr` (default, implies `app`) adds the OpenXR headset.
//! `gltf` (default) reads glTF scenes. `testing` adds the test oracle
//! `measure::analytic` (with `app`).

#[cfg(feature = "app")]
pub mod app;
pub mod formats;
#[cfg(feature = "app")]
pub mod measure;
pub mod render;
pub mod stats;
pub mod test_assets;
#[cfg(feature = "app")]
pub mod xr;

pub use render::ao;
pub use render::error::{Error, Result};
pub use render::gpu::{BackendChoice, Gpu};
pub use render::graph::Resource;
pub use render::renderer::{FrameReport, Renderer};
pub use render::scene::Scene;
pub use render::settings::{Settings, StereoMode};
pub use render::stereo::{Eye, EyePair, Fov, HeadPose, HeadsetProfile};
