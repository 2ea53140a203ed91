//! The engine's kernel plumbing ([`vrao_ao::gpu::kernel`], with the shared WGSL files
//! `COMMON` and `IRRADIANCE`) and the renderer's `wgsl!` for its own.

pub use vrao_ao::gpu::kernel::*;

/// A [`Shader`] of a WGSL file named by its path within this crate; the file lives
/// beside the code that uses it (`src/passes/<pass>/<pass>.wgsl`).
macro_rules! wgsl {
    ($path:literal) => {
        $crate::gpu::kernel::Shader {
            path: concat!("crates/", env!("CARGO_PKG_NAME"), "/", $path),
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $path)),
        }
    };
}

pub(crate) use wgsl;
