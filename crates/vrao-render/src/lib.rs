//! vrao-render: vrao's stereo renderer, built around the `vrao-ao` engine.
//!
//! Load a [`Scene`] (OBJ, glTF, vrao's TOML, or a built-in one), open a [`Gpu`], make a
//! [`Renderer`] with [`Settings`], and render an [`EyePair`] into layered targets. The
//! renderer draws the G-buffer, the directional lights' shadow maps, direct light,
//! reflective shadow maps and a second depth layer, runs the engine's AO chain over the
//! G-buffer (with SSDO, which gathers the renderer's light, among its techniques), and
//! composites and tone-maps the result.
//!
//! The engine's modules are re-exported under the same names ([`graph`], [`stereo`],
//! …), with the renderer's own passes and GPU pieces beside the engine's in [`passes`]
//! and [`gpu`].

pub mod files;
pub mod gpu;
pub mod lighting;
pub mod passes;
pub mod renderer;
pub mod scene;
pub mod settings;

pub use vrao_ao::{ao, driver, error, graph, graph_targets, sampling, stereo, technique, visibility};

pub use error::{Error, Result};
pub use gpu::{BackendChoice, Gpu};
pub use graph::Resource;
pub use renderer::{FrameReport, Renderer};
pub use scene::Scene;
pub use settings::{Settings, StereoMode};
pub use stereo::{Eye, EyePair, Fov, HeadPose, HeadsetProfile};
