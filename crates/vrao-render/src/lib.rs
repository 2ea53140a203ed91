//! vrao-render: vrao's stereo renderer, built around the `vrao-ao` engine.
//!
//! Load a [`Scene`] (OBJ, glTF, vrao's TOML, or a built-in one), open a GPU ([`open`]), make a
//! [`Renderer`] with [`Settings`], and render a [`vrao_ao::EyePair`] into layered targets. The
//! renderer draws the G-buffer, the directional lights' shadow maps, direct light,
//! reflective shadow maps and a second depth layer, runs the engine's AO chain over the
//! G-buffer (with SSDO, which gathers the renderer's light, among its techniques), and
//! composites and tone-maps the result.
//!
//! The engine is named by its own name: its host face (`vrao_ao::AoSettings`,
//! `vrao_ao::Error`, the stereo types) and its renderer face (`vrao_ao::plug`: the frame
//! graph, the GPU helpers, the chain's resources), which the renderer's passes in
//! [`passes`] and GPU pieces in [`gpu`] are written against.

pub mod files;
pub mod gpu;
pub mod headset;
pub mod lighting;
pub mod passes;
pub mod renderer;
pub mod scene;
pub mod settings;
#[doc(hidden)]
pub mod test_dir;

pub use gpu::open::{open, BackendChoice};
pub use headset::HeadsetProfile;
pub use renderer::{FrameReport, Renderer};
pub use scene::Scene;
pub use settings::{BounceForm, PointSsdoSettings, Settings, StereoMode};
