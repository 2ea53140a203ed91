//! The renderer's GPU pieces beside the engine's ([`vrao_ao::plug`]): opening the
//! device, the scene uploaded to the GPU and the mesh-drawing pipelines.

pub mod direct_readback;
pub mod kernel;
pub(crate) mod multiview_probe;
pub mod open;
pub mod raster;
pub mod scene;
pub mod textures;
