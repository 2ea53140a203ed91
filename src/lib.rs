//! vrao: a stereo VR renderer for screen-space ambient occlusion on wgpu.
//!
//! The library is usable without the CLI: load a [`Scene`], open a [`Gpu`], make a
//! [`Renderer`] with [`Settings`], and render an [`EyePair`] into layered targets.

pub mod analytic;
pub mod app;
pub mod bench;
pub mod budget;
pub mod display;
pub mod error;
pub mod governor;
pub mod gpu;
pub mod graph;
pub mod headset;
pub mod metrics;
pub mod output;
pub mod passes;
pub mod plot;
pub mod profiles;
pub mod reference;
pub mod renderer;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod stereo;
pub mod stereo_consistency;
pub mod temporal_bench;

pub use error::{Error, Result};
pub use gpu::{BackendChoice, Gpu};
pub use graph::Resource;
pub use renderer::{FrameReport, Renderer};
pub use scene::Scene;
pub use settings::{Settings, StereoMode};
pub use stereo::{Eye, EyePair, Fov, HeadPose, HeadsetProfile};
