#![doc = include_str!("../README.md")]
//!
//! ## Where things are
//!
//! See [`ao`] for the conventions (depth, normals, matrices, formats). The same frame
//! graph ([`graph`]) and passes ([`passes`]) run inside vrao's renderer (the
//! `vrao-render` crate), which adds its scene passes around them.

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
