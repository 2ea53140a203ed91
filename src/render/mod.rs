//! The renderer: the GPU device and its helpers, the frame graph and its passes, stereo
//! views, scenes and settings. It imports nothing else of vrao: `xr`, `app` and
//! `measure` build on it (checked by `tests/layout.rs`).

pub mod ao;
pub mod bench_file;
pub mod error;
pub mod frame_targets;
pub mod gpu;
pub mod graph;
pub mod output;
pub mod passes;
pub mod renderer;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod stats;
pub mod stereo;
pub mod still;
