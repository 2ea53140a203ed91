//! vrao: a stereo VR renderer for screen-space ambient occlusion on wgpu.
//!
//! The library is usable without the CLI: load a [`Scene`], open a [`Gpu`], make a
//! [`Renderer`] with [`Settings`], and render an [`EyePair`] into layered targets.
//!
//! Four folders with a dependency rule (checked by `tests/layout.rs`): [`render`]
//! imports none of the others; `xr` (headsets) imports only `render`; `app` (the frame
//! loop, governor and window) and `measure` (reference, metrics, bench, studies) import
//! `render` and `xr` but not each other. The CLI (`src/cli/`) is the binary's.
//!
//! Cargo features: [`render`] is always built and needs only wgpu, the scene and image
//! loaders and serde. `app` (default) adds `app`, `measure` and `xr` with what they use
//! (winit, egui, clap, the reference tracer's rayon and BVH, the bench's plots and FLIP);
//! the `vrao` binary needs it. `xr` (default, implies `app`) adds the OpenXR headset.
//! `testing` adds the test oracle `measure::analytic` (with `app`). The renderer alone:
//! `vrao = { version = "0.1", default-features = false }`.

#[cfg(feature = "app")]
pub mod app;
#[cfg(feature = "app")]
pub mod measure;
pub mod render;
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
