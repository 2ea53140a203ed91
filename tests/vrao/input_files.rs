//! Files a user names, as the `vrao` binary meets them (issue 39, the sweep's unbounded
//! reads, hangs and silent empty frames): a device, a FIFO or a folder where a file should
//! be is refused at once naming what it is, a glTF's URIs stay in its folder, a scene's
//! triangles have one budget, and a hidden (scale 0) object leaves the rest of the frame
//! as it was. Each refusal is one `error:` line and exit code 2, within seconds.
#![cfg(feature = "app")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn vrao(args: &[&str]) -> (Output, Duration) {
    let started = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_vrao")).args(args).output().expect("vrao runs");
    (out, started.elapsed())
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

/// A fresh, empty directory for one test's files, removed when the test passes.
fn temp_dir(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("input-files-{name}"))
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Exit 2, one `error:` line holding every one of `names`, no panic, within 10 s.
fn refused(args: &[&str], names: &[&str]) -> String {
    let (out, took) = vrao(args);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {t}");
    assert!(!t.contains("panicked") && !t.contains(".cargo/registry"), "{args:?}: {t}");
    let errors: Vec<&str> = t.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{args:?}: one error line: {t}");
    for name in names {
        assert!(errors[0].contains(name), "{args:?}: the error names '{name}': {t}");
    }
    assert!(took < Duration::from_secs(10), "{args:?} took {took:?}");
    t
}

/// A FIFO at `at`, if `mkfifo` can make one.
fn fifo(at: &Path) -> bool {
    Command::new("mkfifo").arg(at).status().is_ok_and(|s| s.success())
}

#[cfg(unix)]
#[test]
fn devices_fifos_and_folders_are_refused_at_once_as_scene_bench_and_frontier_files() {
    let dir = temp_dir("special");
    let zero = dir.join("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let random = dir.join("random.json");
    std::os::unix::fs::symlink("/dev/urandom", &random).unwrap();
    let folder = dir.join("folder.json");
    std::fs::create_dir(&folder).unwrap();
    let pipe = dir.join("pipe.json");
    let mut files = vec![
        (zero.clone(), "is a character device"),
        (random.clone(), "is a character device"),
        (PathBuf::from("/dev/urandom"), "is a character device"),
        (folder, "is a directory"),
    ];
    if fifo(&pipe) {
        files.push((pipe, "is a FIFO (named pipe)"));
    }
    let out = dir.join("out");
    for (file, what) in &files {
        let names = [path(file), what];
        refused(&["render", "--scene", path(file), "--width", "8", "--height", "8", "--out", path(&out)], &names);
        refused(&["bench", "--replot", path(file), "--out", path(&out)], &names);
        refused(&["budget", "--fit", path(file), "--width", "8", "--height", "8"], &names);
        let run =
            ["run", "--headset", "simulated", "--display", "none", "--frames", "2", "--width", "8", "--height", "8"];
        refused(&[&run[..], &["--governor-frontier", path(file)]].concat(), &names);
    }
    // A symlink loop is not a missing file.
    let looped = dir.join("loop.toml");
    std::os::unix::fs::symlink(&looped, &looped).unwrap();
    let t = refused(&["render", "--scene", path(&looped)], &["loop.toml"]);
    assert!(!t.contains("no such file"), "{t}");
}

/// A `.gltf` of one triangle whose buffer and image are the files `buffer` and `image`
/// beside it (`None`: a data URI buffer, no image).
fn triangle_gltf(buffer: Option<&str>, image: Option<&str>) -> String {
    let data = "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    let material = match image {
        Some(uri) => format!(
            r#","materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],"textures":[{{"source":0}}],"images":[{{"uri":"{uri}"}}]"#
        ),
        None => String::new(),
    };
    let primitive_material = if image.is_some() { r#","material":0"# } else { "" };
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}{primitive_material}}}]}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],"bufferViews":[{{"buffer":0,"byteLength":36}}],"buffers":[{{"byteLength":36,"uri":"{}"}}]{material}}}"#,
        buffer.unwrap_or(data)
    )
}

#[cfg(unix)]
#[test]
fn gltf_uris_naming_devices_fifos_or_files_outside_its_folder_are_refused_naming_the_uri() {
    let outside = temp_dir("uri-outside");
    std::fs::write(outside.join("secret.png"), b"not read").unwrap();
    let folder = temp_dir("uri");
    let dir = folder.join("model");
    std::fs::create_dir_all(&dir).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.bin")).unwrap();
    std::os::unix::fs::symlink("/dev/urandom", dir.join("noise.png")).unwrap();
    std::os::unix::fs::symlink(outside.join("secret.png"), dir.join("link.png")).unwrap();
    std::fs::create_dir(dir.join("textures")).unwrap();
    let escape = format!("../../{}/secret.png", outside.file_name().unwrap().to_string_lossy());
    let absolute = outside.join("secret.png").display().to_string();
    let mut cases = vec![
        (Some("zero.bin"), None, "buffer 0: file 'zero.bin' is a character device, not a regular file"),
        (None, Some("noise.png"), "image 0: file 'noise.png' is a character device"),
        (None, Some("textures"), "image 0: file 'textures' is a directory"),
        (None, Some(escape.as_str()), "image 0: URI '../../"),
        (None, Some(absolute.as_str()), "leaves the glTF's folder"),
        (None, Some("link.png"), "image 0: URI 'link.png' leaves the glTF's folder (a symlink"),
    ];
    if fifo(&dir.join("pipe.bin")) {
        cases.push((Some("pipe.bin"), None, "buffer 0: file 'pipe.bin' is a FIFO (named pipe)"));
    }
    for (i, (buffer, image, expected)) in cases.into_iter().enumerate() {
        let gltf = dir.join(format!("case{i}.gltf"));
        std::fs::write(&gltf, triangle_gltf(buffer, image)).unwrap();
        refused(&["render", "--scene", path(&gltf), "--width", "8", "--height", "8"], &[path(&gltf), expected]);
    }
}

#[test]
fn a_scene_placing_a_2m_triangle_gltf_30_times_is_refused_at_the_entry_that_passes_the_budget() {
    // The sweep's 1 KB scene that passed 6 GiB: one 2 M-triangle glTF placed 30 times.
    let dir = temp_dir("budget");
    let triangles = 2_000_000u32;
    let corners = [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    let mut bin: Vec<u8> = corners.iter().flat_map(|f| f.to_le_bytes()).collect();
    bin.extend((0..3 * triangles).flat_map(|i| ((i % 3) as u16).to_le_bytes()));
    std::fs::write(dir.join("big.bin"), &bin).unwrap();
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":2}},"indices":1}}]}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}},{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"}}],"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":72,"byteLength":{}}},{{"buffer":0,"byteOffset":36,"byteLength":36}}],"buffers":[{{"byteLength":{},"uri":"big.bin"}}]}}"#,
        3 * triangles,
        6 * triangles,
        bin.len()
    );
    std::fs::write(dir.join("big.gltf"), gltf).unwrap();
    let scene = dir.join("thirty.toml");
    let entries: String =
        (0..30).map(|i| format!("[[mesh]]\ngltf = \"big.gltf\"\ntranslate = [{i}, 0, 0]\n")).collect();
    std::fs::write(&scene, entries).unwrap();
    refused(
        &["render", "--scene", path(&scene), "--width", "8", "--height", "8", "--out", path(&dir.join("out"))],
        &["thirty.toml:31:", "mesh gltf 'big.gltf' brings the scene to 22000000 triangles", "20000000"],
    );
    assert!(!dir.join("out").exists(), "nothing written");
}

/// The mean grey level of a PNG and whether every pixel is the same.
fn mean_and_uniform(file: &Path) -> (f64, bool) {
    let image = image::open(file).unwrap_or_else(|e| panic!("{}: {e}", file.display())).to_luma8();
    let pixels = image.as_raw();
    let mean = pixels.iter().map(|&p| p as f64).sum::<f64>() / pixels.len() as f64;
    (mean, pixels.iter().all(|&p| p == pixels[0]))
}

#[test]
fn an_object_hidden_by_a_scale_of_zero_leaves_the_rest_of_the_frame_as_it_was() {
    // Huge keys blanked the whole frame, the static floor too; a key of 0 (hiding an
    // object over time, as content does) stays allowed and must not.
    let dir = temp_dir("hidden");
    std::fs::write(dir.join("tri.obj"), "v -0.5 0 0\nv 0.5 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let head = "[head]\neye = [0, 1.6, 3]\nlook_at = [0, 0, 0]\n";
    let placed = |keys: &str| {
        format!("[[mesh]]\nbuiltin = \"plane\"\n[[mesh]]\nobj = \"tri.obj\"\nanimation = {{ keys = [{keys}] }}\n{head}")
    };
    let scenes = [
        ("plane", format!("[[mesh]]\nbuiltin = \"plane\"\n{head}")),
        ("hidden", placed("{ t = 0, scale = 0 }, { t = 1, scale = [0, 0, 0] }")),
        ("growing", placed("{ t = 0, scale = 0 }, { t = 1, scale = 1 }")),
    ];
    let mut means = Vec::new();
    for (name, contents) in scenes {
        let scene = dir.join(format!("{name}.toml"));
        std::fs::write(&scene, contents).unwrap();
        let out = dir.join(name);
        let (run, _) = vrao(&[
            "render",
            "--scene",
            path(&scene),
            "--width",
            "48",
            "--height",
            "48",
            "--time",
            "0",
            "--out",
            path(&out),
        ]);
        assert!(run.status.success(), "{name}: {}", text(&run));
        let (mean, uniform) = mean_and_uniform(&out.join("left.png"));
        assert!(!uniform && mean > 20.0, "{name}: a blank frame (mean {mean})");
        means.push(mean);
    }
    // Always hidden: the very frame of the plane alone.
    let plane = std::fs::read(dir.join("plane/left.png")).unwrap();
    assert_eq!(plane, std::fs::read(dir.join("hidden/left.png")).unwrap(), "a hidden object changes nothing");
    // Hidden at t = 0 but not later (its bounds count): the floor looks the same.
    assert!((means[2] - means[0]).abs() < 0.05 * means[0], "{means:?}");
}

#[test]
fn gltf_meshes_too_small_in_the_world_say_so_in_one_warning_line() {
    // Issue 50: scales that are each fine (1e-3) multiplied to 1e-9 along three nodes, and
    // tiny positions at scale 1, drew nothing without the warning one tiny scale gets.
    let dir = temp_dir("world-size");
    let render = |file: &Path| {
        let (out, _) =
            vrao(&["render", "--scene", path(file), "--width", "16", "--height", "16", "--out", path(&dir.join("o"))]);
        let t = text(&out);
        assert!(out.status.success(), "{t}");
        let warnings: Vec<String> = t.lines().filter(|l| l.contains("in the world")).map(str::to_string).collect();
        assert!(!t.contains("scaled below"), "no single node is tiny: {t}");
        warnings
    };
    let milli = r#""scale":[1e-3,1e-3,1e-3]"#;
    let nested = triangle_gltf(None, None).replace(
        r#""nodes":[{"mesh":0}]"#,
        &format!(r#""nodes":[{{"children":[1],{milli}}},{{"children":[2],{milli}}},{{"mesh":0,{milli}}}]"#),
    );
    let file = dir.join("nested.gltf");
    std::fs::write(&file, nested).unwrap();
    let warnings = render(&file);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("nested.gltf: node 2 (1.0e-9 m across) smaller than 1e-6 m in the world")
            && warnings[0].contains("not drawn"),
        "{warnings:?}"
    );
    // The same triangle 10 nm across by its positions.
    let floats: [f32; 9] = [0.0, 0.0, 0.0, 1e-8, 0.0, 0.0, 0.0, 1e-8, 0.0];
    std::fs::write(dir.join("tiny.bin"), floats.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>()).unwrap();
    let tiny = triangle_gltf(Some("tiny.bin"), None).replace(r#""max":[1,1,0]"#, r#""max":[1e-8,1e-8,0]"#);
    let file = dir.join("tiny.gltf");
    std::fs::write(&file, tiny).unwrap();
    let warnings = render(&file);
    assert!(warnings.len() == 1 && warnings[0].contains("tiny.gltf: node 0 (1.0e-8 m across)"), "{warnings:?}");
    // 1e-3 and 1e-2: 10 µm across, drawn, and nothing said.
    let centi = r#""scale":[1e-2,1e-2,1e-2]"#;
    let drawn = triangle_gltf(None, None)
        .replace(r#""nodes":[{"mesh":0}]"#, &format!(r#""nodes":[{{"children":[1],{milli}}},{{"mesh":0,{centi}}}]"#));
    let file = dir.join("drawn.gltf");
    std::fs::write(&file, drawn).unwrap();
    assert!(render(&file).is_empty());
}

#[test]
fn a_gltf_node_of_scale_zero_draws_the_rest_and_says_so_in_one_warning_line() {
    let dir = temp_dir("node-scale");
    let gltf = triangle_gltf(None, None)
        .replace(r#""nodes":[0]"#, r#""nodes":[0,1]"#)
        .replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0},{"mesh":0,"scale":[0,0,0],"translation":[0,2,0]}]"#);
    let file = dir.join("hidden.gltf");
    std::fs::write(&file, gltf).unwrap();
    let (out, _) =
        vrao(&["render", "--scene", path(&file), "--width", "16", "--height", "16", "--out", path(&dir.join("o"))]);
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    let warnings: Vec<&str> = t.lines().filter(|l| l.contains("scaled below")).collect();
    assert_eq!(warnings.len(), 1, "{t}");
    assert!(warnings[0].contains("hidden.gltf: node 1 scaled below 1e-6: the meshes below it are not drawn"), "{t}");
    // A far node is refused instead.
    let far = triangle_gltf(None, None)
        .replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"translation":[1e30,0,0]}]"#);
    std::fs::write(&file, far).unwrap();
    refused(&["render", "--scene", path(&file)], &["hidden.gltf", "node 0: translation 1e30 m is farther than 1e6 m"]);
}
