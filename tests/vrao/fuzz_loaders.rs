//! Bounded fuzzing of the OBJ, MTL, scene-file and glTF loaders on stable Rust: seeded
//! mutations of valid files (and of the shared scenes' own OBJ and MTL when present),
//! each loaded through `Scene::load`. Any `Ok` or `Err` is fine; a panic fails the test
//! and the input is saved under `target/fuzz-crashes/` to become a regression file in
//! `tests/fuzz_regressions/`. `cargo fuzz` runs the same targets without a bound
//! (`fuzz/`, nightly).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::{Duration, Instant};
use vrao::test_assets::fuzz::{
    load_bytes, Mutator, Target, VALID_GLTF, VALID_GLTF_FILES, VALID_MTL, VALID_OBJ, VALID_SCENE, VALID_SCENE_GLTF,
};

/// Time per target; `VRAO_FUZZ_SECONDS` overrides it for longer runs.
fn budget() -> Duration {
    let seconds = std::env::var("VRAO_FUZZ_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(8.0);
    Duration::from_secs_f64(seconds)
}

fn scratch(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("fuzz-{name}"))
}

fn seeds(target: Target) -> Vec<Vec<u8>> {
    let mut seeds = vec![match target {
        Target::Obj => VALID_OBJ.as_bytes().to_vec(),
        Target::Mtl => VALID_MTL.as_bytes().to_vec(),
        Target::SceneFile => VALID_SCENE.as_bytes().to_vec(),
        Target::Gltf => VALID_GLTF.as_bytes().to_vec(),
    }];
    let cornell = |ext: &str| crate::common::public_scene(&format!("cornell_box/CornellBox-Original.{ext}"));
    match target {
        Target::Obj => seeds.extend(cornell("obj").and_then(|p| std::fs::read(p).ok())),
        Target::Mtl => seeds.extend(cornell("mtl").and_then(|p| std::fs::read(p).ok())),
        Target::SceneFile => {
            seeds.push(include_bytes!("../../assets/scenes/cornell.toml").to_vec());
            seeds.push(VALID_SCENE_GLTF.as_bytes().to_vec());
        }
        Target::Gltf => {
            seeds.push(VALID_GLTF_FILES.as_bytes().to_vec());
            // The same content as a .glb container, as vrao's writer makes it.
            let dir = scratch("glb-seed");
            let glb = dir.join("seed.glb");
            let scene = vrao_render::scene::Scene::load("builtin:furnished").unwrap();
            vrao::test_assets::gltf_write::write(&scene, &glb, &Default::default()).unwrap();
            seeds.push(std::fs::read(glb).unwrap());
        }
    }
    seeds
}

fn save_crash(target: Target, input: &[u8]) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-crashes");
    std::fs::create_dir_all(&dir).unwrap();
    let hash = input.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    let path = dir.join(format!("crash-{hash:016x}.{}", target.extension()));
    std::fs::write(&path, input).unwrap();
    path
}

#[test]
fn mutated_obj_mtl_and_scene_files_never_panic() {
    // Panics are caught and reported below; keep the default hook from printing each.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut report = Vec::new();
    // Checked once the hook is back, so a failure says what it is.
    let mut failures = Vec::new();
    for target in Target::ALL {
        let dir = scratch(target.extension());
        let seeds = seeds(target);
        let mut rng = Mutator::new(0x5eed ^ target as u64);
        let (started, mut runs, mut errors) = (Instant::now(), 0u64, 0u64);
        let mut crashes = Vec::new();
        while started.elapsed() < budget() {
            let mut input = seeds[runs as usize % seeds.len()].clone();
            // A few rounds of mutation, so inputs drift further from the seeds.
            for _ in 0..1 + runs % 4 {
                rng.mutate(&mut input);
            }
            match catch_unwind(AssertUnwindSafe(|| load_bytes(target, &input, &dir))) {
                Ok(Ok(_)) => {}
                Ok(Err(e)) => {
                    errors += 1;
                    // Errors must say where: the file, and for parse errors the line.
                    let message = e.to_string();
                    if !message.contains("fuzz.") {
                        failures.push(format!("{target:?}: an error that names no file: {message}"));
                    }
                }
                Err(_) => crashes.push(save_crash(target, &input)),
            }
            runs += 1;
        }
        report.push(format!("{}: {runs} inputs, {errors} rejected, {} panics", target.extension(), crashes.len()));
        if !crashes.is_empty() {
            failures.push(format!("{target:?} panicked on {crashes:?}"));
        }
        if runs <= 50 {
            failures.push(format!("{target:?}: only {runs} inputs in the time"));
        }
    }
    std::panic::set_hook(default_hook);
    eprintln!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_saved_regression_input_loads_or_errs_without_a_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let scratch = scratch("regressions");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let target = match path.extension().and_then(|e| e.to_str()) {
            Some("obj") => Target::Obj,
            Some("mtl") => Target::Mtl,
            Some("toml") => Target::SceneFile,
            Some("gltf") => Target::Gltf,
            _ => continue,
        };
        let input = std::fs::read(&path).unwrap();
        let result = catch_unwind(AssertUnwindSafe(|| load_bytes(target, &input, &scratch)));
        let Ok(result) = result else { panic!("{} panics", path.display()) };
        // Inputs a loader once let through (finite values the renderer cannot draw: black
        // frames, vanished geometry) must now be refused, naming the file and line.
        let name = path.file_name().unwrap().to_string_lossy();
        if name.starts_with("refused-") {
            let error = result.err().unwrap_or_else(|| panic!("{name} loads; it must be refused")).to_string();
            let place = format!("fuzz.{}:", target.extension());
            assert!(error.contains(&place), "{name}: the error names the file and line: {error}");
        }
        checked += 1;
    }
    assert!(checked > 0, "no regression inputs in {}", dir.display());
}

/// Bench files feed `vrao bench --replot`, `vrao budget --fit` and the governor's
/// frontier: mutated copies of the built-in frontier are refused naming the file, or load
/// with every record in range and give a frontier (or a refusal) without a panic.
#[cfg(feature = "app")]
#[test]
fn mutated_bench_files_are_refused_or_load_in_range_without_a_panic() {
    use vrao::app::governor::Frontier;
    use vrao::formats::bench_file::BenchFile;
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let seed = include_bytes!("../../assets/governor/frontier.json").to_vec();
    let origin = std::path::Path::new("fuzz.json");
    let mut rng = Mutator::new(0xbe4c);
    let (started, mut runs, mut accepted) = (Instant::now(), 0u64, 0u64);
    let mut crashes = Vec::new();
    while started.elapsed() < budget() {
        let mut input = seed.clone();
        for _ in 0..1 + runs % 4 {
            rng.mutate(&mut input);
        }
        let text = String::from_utf8_lossy(&input).into_owned();
        let outcome = catch_unwind(AssertUnwindSafe(|| match BenchFile::from_json(&text, origin) {
            Ok(file) => {
                for r in &file.records {
                    assert!((1..=1024).contains(&r.samples), "{r:?}");
                    assert!(r.radius_m.is_finite() && r.radius_m > 0.0, "{r:?}");
                    assert!(r.occlusion_ms_per_eye.is_finite() && r.occlusion_ms_per_eye >= 0.0, "{r:?}");
                }
                if let Ok(frontier) = Frontier::from_bench(&file, 0.3) {
                    assert!(frontier.levels().iter().all(|l| l.ms_per_eye.is_finite() && l.ms_per_eye > 0.0));
                }
                true
            }
            Err(e) => {
                assert!(e.to_string().starts_with("fuzz.json"), "an error that names no file: {e}");
                false
            }
        }));
        match outcome {
            Ok(true) => accepted += 1,
            Ok(false) => {}
            Err(_) => crashes.push(text),
        }
        runs += 1;
    }
    std::panic::set_hook(default_hook);
    eprintln!("bench files: {runs} inputs, {accepted} accepted, {} panics", crashes.len());
    assert!(crashes.is_empty(), "bench files that panicked: {:?}", &crashes[..crashes.len().min(2)]);
    assert!(runs > 50 && accepted > 0, "{runs} inputs, {accepted} accepted: the mutations reach the records");
}

#[test]
fn every_seed_loads() {
    for target in Target::ALL {
        let dir = scratch(&format!("seed-{}", target.extension()));
        for (i, seed) in seeds(target).iter().enumerate() {
            if let Err(e) = load_bytes(target, seed, &dir) {
                panic!("{target:?} seed {i} is refused, so mutations start from a broken file: {e}");
            }
        }
    }
}

/// The inputs the fuzzing tokens reach, each checked: a path that names a device, a FIFO,
/// a folder or a file outside the glTF's folder is refused at once, naming what it is.
#[test]
fn special_files_named_by_any_loader_are_refused_at_once_naming_what_they_are() {
    let dir = scratch("special");
    let gltf_with = |uri: &str| VALID_GLTF_FILES.replace("\"uri\":\"fuzz.bin\"", &format!("\"uri\":\"{uri}\""));
    let scene_with = |what: &str| VALID_SCENE.replace("obj = \"fuzz.obj\"", what);
    let mut cases: Vec<(Target, String, &str)> = vec![
        (Target::Gltf, gltf_with("zero.bin"), "buffer 0: file 'zero.bin' is a character device"),
        (Target::Gltf, gltf_with("folder.png"), "buffer 0: file 'folder.png' is a directory"),
        (
            Target::Gltf,
            gltf_with("../vrao-fuzz-outside.bin"),
            "buffer 0: URI '../vrao-fuzz-outside.bin' leaves the glTF's folder",
        ),
        (Target::Gltf, gltf_with("/dev/zero"), "buffer 0: URI '/dev/zero' leaves the glTF's folder"),
        (Target::SceneFile, scene_with("obj = \"zero.bin\""), "mesh obj 'zero.bin' ("),
        (Target::SceneFile, scene_with("gltf = \"folder.png\""), "is a directory, not a regular file"),
        (Target::Mtl, "newmtl red\nmap_Kd zero.bin\n".into(), "texture file 'zero.bin' ("),
    ];
    if cfg!(unix) {
        cases.push((
            Target::Gltf,
            gltf_with("link.bin"),
            "buffer 0: URI 'link.bin' leaves the glTF's folder (a symlink",
        ));
        cases.push((Target::Gltf, gltf_with("pipe.bin"), "buffer 0: file 'pipe.bin' is a FIFO (named pipe)"));
        cases.push((Target::SceneFile, scene_with("obj = \"pipe.bin\""), "is a FIFO (named pipe), not a regular file"));
        cases.push((Target::Mtl, "newmtl red\nmap_Kd pipe.bin\n".into(), "is a FIFO (named pipe)"));
    }
    for (target, input, expected) in cases {
        let started = Instant::now();
        let e = load_bytes(target, input.as_bytes(), &dir).err().unwrap_or_else(|| panic!("{input} loads")).to_string();
        assert!(e.contains(&format!("fuzz.{}", target.extension())) && e.contains(expected), "{target:?}: {e}");
        assert!(started.elapsed() < Duration::from_secs(2), "{target:?} {expected}: {:?}", started.elapsed());
    }
}
