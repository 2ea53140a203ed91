#![no_main]
//! Fuzzes the glTF loader (`Target::Gltf`: `.gltf` JSON or a `.glb` container; see
//! vrao::scene::fuzz).

use libfuzzer_sys::fuzz_target;
use vrao::scene::fuzz::{load_bytes, Target};

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("vrao-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let _ = load_bytes(Target::Gltf, data, &dir);
});
