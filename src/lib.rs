//! vrao: a stereo VR renderer for screen-space ambient occlusion on wgpu.
//!
//! The library is usable without the CLI: load a [`Scene`], open a [`Gpu`], make a
//! [`Renderer`] with [`Settings`], and render an [`EyePair`] into layered targets.
//!
//! Four folders with a dependency rule (checked by `tests/layout.rs`): [`render`]
//! imports none of the others; [`xr`] (headsets) imports only `render`; [`app`] (the
//! frame loop, governor and window) and [`measure`] (reference, metrics, bench, studies)
//! import `render` and `xr` but not each other. The CLI (`src/cli/`) is the binary's.

pub mod app;
pub mod measure;
pub mod render;
pub mod xr;

pub use render::error::{Error, Result};
pub use render::gpu::{BackendChoice, Gpu};
pub use render::graph::Resource;
pub use render::renderer::{FrameReport, Renderer};
pub use render::scene::Scene;
pub use render::settings::{Settings, StereoMode};
pub use render::stereo::{Eye, EyePair, Fov, HeadPose, HeadsetProfile};
