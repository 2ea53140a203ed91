#![doc = include_str!("../README.md")]
//!
//! ## Two faces
//!
//! The crate root is the host's face: everything a wgpu program needs to hand the
//! engine its depth (and normals, motion, light) and take the AO back. [`plug`] is the
//! renderer's face: the frame graph, the GPU helpers and the chain's resources, for a
//! renderer that adds its own passes around the engine's (as vrao's renderer does).
//! Everything else is private.

mod ao;
mod driver;
mod error;
mod frame;
mod gpu;
mod graph;
mod graph_targets;
mod passes;
pub mod plug;
mod resource;
mod sampling;
mod settings;
mod sh;
mod stereo;
mod technique;
mod visibility;

/// The check of WGSL mirrors against naga's layout, for the workspace's tests (feature
/// `layout-check`); not part of either face.
#[cfg(any(test, feature = "layout-check"))]
#[doc(hidden)]
pub use gpu::layout_check;

pub use ao::{
    AoConfig, AoEngine, AoFrame, AoOutput, AoOutputFormat, DepthConvention, HostExclusion, HostLight, HostMotion,
    HostNormals, NormalEncoding, NormalSpace, ViewMatrices,
};
pub use error::{Error, Result};
pub use graph::Plan;
pub use passes::RightEyeTiles;
pub use settings::{
    AoSettings, Choice, Denoise, Foveation, GtaoSettings, Noise, Quality, Resolution, Technique, Temporal,
    TemporalBlend,
};
pub use stereo::{Eye, EyePair, EyeSide, Fov, HeadPose, InvalidFov};
pub use visibility::{ViewMask, VisibilityMask};
