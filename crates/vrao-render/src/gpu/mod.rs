//! The engine's GPU plumbing ([`vrao_ao::gpu`]) and the renderer's own pieces: the scene
//! uploaded to the GPU and the mesh-drawing pipelines.

pub use vrao_ao::gpu::*;

pub mod kernel;
pub mod raster;
pub mod scene;
pub mod textures;
