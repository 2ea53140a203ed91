//! The renderer crate ([`vrao_render`], which re-exports the engine's modules) under the
//! name the application's modules use.

pub use vrao_render::*;

/// A shader of a WGSL file named by its path from the workspace root (the
/// application's files live in its own folders, beside the code that uses them).
#[cfg(feature = "app")]
macro_rules! wgsl {
    ($path:literal) => {
        $crate::render::gpu::kernel::Shader {
            path: $path,
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $path)),
        }
    };
}

#[cfg(feature = "app")]
pub(crate) use wgsl;
