//! The OpenXR headset. The loader is opened at run time (openxr's `loaded` feature), so
//! vrao runs where none is installed; a missing loader or `XR_ERROR_RUNTIME_UNAVAILABLE`
//! means "no headset here" and `vrao run` falls back to the simulated headset.

/// Why no OpenXR headset is available, in one line for the user.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Unavailable {
    /// Built without the `xr` feature.
    NotBuilt,
    /// The OpenXR loader library could not be opened.
    NoLoader(String),
    /// The loader found no runtime (XR_ERROR_RUNTIME_UNAVAILABLE) or the runtime failed.
    NoRuntime(String),
}

impl std::fmt::Display for Unavailable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unavailable::NotBuilt => write!(f, "vrao was built without the `xr` feature"),
            Unavailable::NoLoader(why) => write!(f, "no OpenXR loader ({why})"),
            Unavailable::NoRuntime(why) => write!(f, "no OpenXR runtime ({why})"),
        }
    }
}

/// The loader's library names, unversioned first (a -dev install), then the soname the
/// runtime package ships (Debian's libopenxr-loader1 has only `libopenxr_loader.so.1`).
#[cfg(feature = "xr")]
const LOADER_NAMES: [&str; 2] = ["libopenxr_loader.so", "libopenxr_loader.so.1"];

/// Opens the OpenXR loader.
#[cfg(feature = "xr")]
pub fn load_entry() -> Result<openxr::Entry, Unavailable> {
    // The loader prints its own multi-line errors to stderr when no runtime is installed;
    // vrao says why in one line instead. XR_LOADER_DEBUG set by the user still wins.
    if std::env::var_os("XR_LOADER_DEBUG").is_none() {
        std::env::set_var("XR_LOADER_DEBUG", "none");
    }
    let mut errors = Vec::new();
    for name in LOADER_NAMES {
        // SAFETY: loading the Khronos loader runs its initialisers; it is the library
        // OpenXR applications are meant to load.
        match unsafe { openxr::Entry::load_from(std::path::Path::new(name), &()) } {
            Ok(entry) => return Ok(entry),
            Err(e) => errors.push(format!("{name}: {e}")),
        }
    }
    Err(Unavailable::NoLoader(errors.join("; ")))
}

/// Whether an OpenXR runtime answers: creates (and drops) an instance. Returns the
/// runtime's name and version.
#[cfg(feature = "xr")]
pub fn probe_runtime() -> Result<String, Unavailable> {
    let entry = load_entry()?;
    let app = openxr::ApplicationInfo {
        application_name: "vrao",
        application_version: 1,
        engine_name: "vrao",
        engine_version: 1,
        api_version: openxr::Version::new(1, 0, 0),
    };
    let instance = entry
        .create_instance(&app, &openxr::ExtensionSet::default(), &[], &())
        .map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
    let props = instance.properties().map_err(|e| Unavailable::NoRuntime(e.to_string()))?;
    Ok(format!("{} {}", props.runtime_name, props.runtime_version))
}

#[cfg(not(feature = "xr"))]
pub fn probe_runtime() -> Result<String, Unavailable> {
    Err(Unavailable::NotBuilt)
}
