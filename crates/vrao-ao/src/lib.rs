//! vrao-ao: screen-space ambient occlusion for wgpu programs, mono or stereo.
//!
//! A program that renders its own depth makes an [`AoEngine`] from its device and queue,
//! and each frame hands it the depth (and optionally normals and motion vectors) with
//! each view's matrices; the engine records its passes into the program's encoder and
//! returns the AO as a layered texture. See [`ao`] for the conventions and
//! `examples/embed` for a whole program.
//!
//! Techniques: GTAO with a visibility bitmask (the default), SSAO, HBAO and a fetch-only
//! baseline ([`settings::Technique`]); then temporal accumulation, a spatial denoise and
//! the upsampling from half resolution, each left out when the settings do not need it.
//! The same frame graph ([`graph`]) and passes ([`passes`]) run inside vrao's renderer
//! (the `vrao-render` crate), which adds its scene passes around them.

pub mod ao;
pub mod driver;
pub mod error;
pub mod gpu;
pub mod graph;
pub mod graph_targets;
pub mod passes;
pub mod sampling;
pub mod settings;
pub mod sh;
pub mod stereo;
pub mod technique;
pub mod visibility;

pub use ao::{
    AoConfig, AoEngine, AoFrame, AoOutput, AoOutputFormat, DepthConvention, HostLight, HostMotion, HostNormals,
    ViewMatrices,
};
pub use error::{Error, Result};
pub use settings::{AoSettings, Technique};
