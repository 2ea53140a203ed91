//! Writers of test assets: glTF files with every feature vrao reads, and the loaders'
//! fuzzing entry points.

pub mod fuzz;
#[cfg(feature = "gltf")]
pub mod gltf_write;
