//! The workspace's integration tests, linked into one binary: one module per subject.
//!
//! A module that needs the application (`app`), glTF (`gltf`) or the OpenXR loader (`xr`)
//! is compiled only with that feature, so `cargo test --no-default-features` runs the rest.
//! GPU tests take the one device in `common` and run one at a time; CPU tests run beside
//! them. Tests that need the public scenes and cannot find them report themselves as
//! skipped (see `common::skip`), and fail under CI.

mod common;

mod ao_engine;
mod build_interrupt;
mod foveation;
mod gltf_materials;
mod gltf_materials_reference;
mod gpu_stereo;
mod layout;
mod pipelines;
mod presets;
mod visibility_mask;

#[cfg(feature = "app")]
mod chain_layout;
#[cfg(feature = "app")]
mod cli;
#[cfg(all(feature = "app", feature = "gltf"))]
mod content;
#[cfg(feature = "app")]
mod depth_peeling;
#[cfg(feature = "gltf")]
mod fuzz_loaders;
#[cfg(feature = "app")]
mod gl;
#[cfg(all(feature = "app", feature = "gltf"))]
mod gltf;
#[cfg(feature = "gltf")]
mod gltf_accessors;
#[cfg(all(feature = "app", feature = "gltf"))]
mod gltf_as_authored;
#[cfg(feature = "app")]
mod headset;
#[cfg(all(feature = "app", feature = "gltf"))]
mod input_files;
#[cfg(feature = "app")]
mod measure;
#[cfg(feature = "app")]
mod numerics;
#[cfg(feature = "app")]
mod occlusion_denoise;
#[cfg(feature = "app")]
mod occlusion_hbao_gtao;
#[cfg(feature = "app")]
mod occlusion_plan;
#[cfg(feature = "app")]
mod occlusion_robustness;
#[cfg(feature = "app")]
mod occlusion_ssao_ssdo;
#[cfg(feature = "app")]
mod occlusion_stereo;
#[cfg(feature = "xr")]
mod openxr;
#[cfg(all(feature = "app", feature = "gltf"))]
mod peer;
#[cfg(feature = "app")]
mod reference_error;
#[cfg(feature = "gltf")]
mod resource_bounds;
#[cfg(feature = "app")]
mod scene_loading;
#[cfg(feature = "app")]
mod shadows;
#[cfg(feature = "app")]
mod soak;
#[cfg(feature = "app")]
mod ssdo_light;
#[cfg(feature = "app")]
mod table;
#[cfg(feature = "app")]
mod temporal;
#[cfg(feature = "app")]
mod two_layers;
#[cfg(feature = "app")]
mod window;
