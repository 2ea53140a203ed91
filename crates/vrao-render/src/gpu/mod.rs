//! The engine's GPU plumbing ([`vrao_ao::gpu`]) and the renderer's own pieces: the scene
//! uploaded to the GPU and the mesh-drawing pipelines.

pub use vrao_ao::gpu::*;

pub mod kernel;
/// The engine's test helper that checks the Rust mirrors of WGSL structs.
#[cfg(test)]
#[path = "../../../vrao-ao/src/gpu/layout_check.rs"]
pub(crate) mod layout_check;
pub mod raster;
pub mod scene;
pub mod textures;
