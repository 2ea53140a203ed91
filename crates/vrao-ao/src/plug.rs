//! The renderer's face: what a renderer needs to run the engine's chain inside its own
//! frame graph and to add passes of its own around it (vrao's renderer is one). A host
//! that only wants AO for its depth never needs this module (see the crate root).
//!
//! A pass is a [`Pass`]: it declares what it reads and writes ([`PassDecl`], resources
//! named by [`Resource`]) when the graph plans a frame, and records its commands
//! ([`RecordContext`]) when the [`GraphDriver`] runs it. Compute passes are [`Kernel`]s
//! over WGSL [`Shader`] files; the chain's resources ([`DEPTH`], [`NORMALS`], …,
//! [`FINAL_AO`]) are the names a renderer's passes write for the chain and read from it.

// The frame graph: passes, their declarations, the driver that plans and records them.
pub use crate::driver::{FrameParams, GraphDriver, Submission};
pub use crate::frame::{ChainSettings, DeclareContext, FrameMotion, MoverBox};
pub use crate::graph::{plan, PassDecl, PixelTraffic};
pub use crate::passes::{ao_chain, record, Pass, RecordContext};
pub use crate::resource::{ChainLayout, Kind, Resource, Size, Written};

// Compute kernels, their WGSL and the GPU helpers a pass records with.
pub use crate::gpu::kernel::{
    shader_module, try_shader_module, Bind, Kernel, Shader, Slot, COMMON, IRRADIANCE, VISIBILITY,
};
pub use crate::gpu::layered_target::LayeredTarget;
pub use crate::gpu::raster::{colour_and_depth_pass, fullscreen_pipeline, layer_views, uniform_entry};
pub use crate::gpu::readback::{read_layers, read_layers_f32};
pub use crate::gpu::timing::{FrameTiming, PassTimer};
pub use crate::gpu::uniforms::{ao_extent, FrameLighting, FrameUniforms};
pub use crate::gpu::visibility::VisibilityMaps;
pub use crate::gpu::{Capabilities, Gpu};

// The chain's resources and passes by name: what a renderer writes for the chain (its
// G-buffer) and reads from it, and the occlusion layout a light-gathering pass shares.
pub use crate::passes::blur::{AO_BLURRED, NAME as BLUR_PASS};
pub use crate::passes::inputs::{DEPTH, DEPTH_LAYER_2, DIRECT_LIGHT, MOTION, NORMALS};
pub use crate::passes::occlusion::{bindings_and, technique_decl, AO_GEOMETRY, AO_RAW, OCCLUSION_WGSL};
pub use crate::passes::right_eye_list::RightEyeList;
pub use crate::passes::temporal::{AO_ACCUMULATED, HISTORY_POSITION, HISTORY_VALUE};
pub use crate::passes::upsample::{reuses_left_eye_upsample, AO_FULL, JOINT_UPSAMPLE_WGSL, NAME as UPSAMPLE_PASS};
pub use crate::resource::{FINAL_AO, OCCLUSION, PIXEL_MOTION};

// What a renderer's light and the measurement's oracle read of the engine's numerics.
pub use crate::sampling::{hbao_directions_steps, hemisphere_kernel, HemisphereDensity};
pub use crate::sh::{prefiltered_radiance, quadratic_in_view, sh9_quadratic};
pub use crate::stereo::DEFAULT_NEAR;
