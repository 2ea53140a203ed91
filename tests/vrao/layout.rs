//! The dependency rule between the application library's folders (see `src/lib.rs`):
//! the shared `formats` and `test_assets` import only the leaves (`error`, the
//! application's error, and `stats`, the one quantile definition); `xr` only the leaves
//! (and the `wgsl!` macro); `app` and `measure` use `xr`, `formats` and the leaves but not
//! each other; and nothing in the library reaches the CLI. Cargo enforces the rule
//! between the crates, and no crate re-exports another's modules: each is named by its
//! own name.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

/// The top-level folders of `src/` a file refers to by `crate::<folder>` (in code, doc
/// links included; plain comments are skipped).
fn references(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.trim_start();
        if code.starts_with("//") && !code.starts_with("///") && !code.starts_with("//!") {
            continue;
        }
        let mut rest = line;
        while let Some(at) = rest.find("crate::") {
            let name: String = rest[at + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            found.push((n + 1, name));
            rest = &rest[at + 7..];
        }
    }
    found
}

#[test]
fn each_folder_imports_only_what_the_rule_allows() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let allowed: [(&str, &[&str]); 5] = [
        ("formats", &["error", "formats", "stats"]),
        ("test_assets", &["error", "test_assets"]),
        ("xr", &["error", "xr", "stats", "wgsl"]),
        ("app", &["error", "xr", "app", "formats", "stats", "wgsl"]),
        ("measure", &["error", "xr", "measure", "formats", "stats"]),
    ];
    let mut violations = Vec::new();
    let mut files_checked = 0;
    for (folder, may_use) in allowed {
        for file in rust_files(&src.join(folder)) {
            files_checked += 1;
            let text = std::fs::read_to_string(&file).expect("readable source");
            for (line, name) in references(&text) {
                if !may_use.contains(&name.as_str()) {
                    violations.push(format!("{}:{line}: {folder} uses crate::{name}", file.display()));
                }
            }
        }
    }
    assert!(files_checked > 50, "only {files_checked} files under src/formats, test_assets, xr, app and measure");
    assert!(violations.is_empty(), "the dependency rule is broken:\n{}", violations.join("\n"));
}

#[test]
fn the_library_never_reaches_the_cli() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("src/lib.rs");
    assert!(!lib.contains("mod cli"), "src/lib.rs declares the CLI: it belongs to the binary");
}

#[test]
fn the_reference_scanner_sees_imports_and_skips_comments() {
    let text = "use crate::error::Result;\n// crate::app in a comment\n/// [`crate::xr::Headset`]\nlet x = crate::measure::metrics::rmse(a, b);";
    let names: Vec<String> = references(text).into_iter().map(|(_, n)| n).collect();
    assert_eq!(names, ["error", "xr", "measure"]);
}

/// `pub use` lines in `dir` that re-export a module (or everything) of another
/// workspace crate: the crates are named by their own names, not merged.
fn cross_crate_reexports(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for file in rust_files(dir) {
        let text = std::fs::read_to_string(&file).expect("readable source");
        for (n, line) in text.lines().enumerate() {
            let code = line.trim_start();
            let Some(path) = code.strip_prefix("pub use ") else { continue };
            let crate_named = path.starts_with("vrao_ao::") || path.starts_with("vrao_render::");
            let last = path.trim_end_matches(';').rsplit("::").next().unwrap_or("");
            let module_or_glob = last == "*" || last.chars().next().is_some_and(|c| c.is_ascii_lowercase());
            if crate_named && module_or_glob {
                found.push(format!("{}:{}: {code}", file.display(), n + 1));
            }
        }
    }
    found
}

#[test]
fn no_crate_re_exports_another_crates_modules() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = cross_crate_reexports(&root.join("src"));
    found.extend(cross_crate_reexports(&root.join("crates/vrao-render/src")));
    assert!(found.is_empty(), "re-exports across crates:\n{}", found.join("\n"));
    let sample = root.join("target/layout-reexport-sample");
    std::fs::create_dir_all(&sample).unwrap();
    std::fs::write(sample.join("a.rs"), "pub use vrao_ao::plug::*;\npub use vrao_ao::AoEngine;\n").unwrap();
    assert_eq!(cross_crate_reexports(&sample).len(), 1, "the scanner finds a glob and passes an item");
}
