//! The renderer's `wgsl!` for its own WGSL files (the engine's shared files, `COMMON`,
//! `IRRADIANCE` and `VISIBILITY`, come from [`vrao_ao::plug`]).

/// A [`Shader`] of a WGSL file named by its path within this crate; the file lives
/// beside the code that uses it (`src/passes/<pass>/<pass>.wgsl`).
macro_rules! wgsl {
    ($path:literal) => {
        ::vrao_ao::plug::Shader {
            path: concat!("crates/", env!("CARGO_PKG_NAME"), "/", $path),
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $path)),
        }
    };
}

pub(crate) use wgsl;
