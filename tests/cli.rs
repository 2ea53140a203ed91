//! The `vrao` binary as a user runs it: exit codes, messages, written files.

use std::path::PathBuf;
use std::process::{Command, Output};

fn vrao(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vrao")).args(args).output().expect("vrao runs")
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vrao-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn info_reports_adapter_multiview_and_timestamps() {
    let out = vrao(&["info"]);
    assert!(out.status.success(), "{}", text(&out));
    let t = text(&out);
    for key in ["adapter:", "backend:", "driver:", "multiview:", "timestamps:", "max_texture_array_layers"] {
        assert!(t.contains(key), "info lacks '{key}':\n{t}");
    }
}

#[test]
fn no_vulkan_driver_is_a_clear_error_with_exit_2() {
    // Point the Vulkan loader at no driver at all.
    let out = Command::new(env!("CARGO_BIN_EXE_vrao"))
        .args(["info", "--backend", "vulkan"])
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{t}");
    assert!(t.contains("no usable GPU") && !t.contains("panicked"), "{t}");
}

#[test]
fn render_writes_both_eyes_and_explains_the_graph() {
    let dir = temp_dir("render");
    let out_dir = dir.join("out");
    let out = vrao(&[
        "render",
        "--scene",
        "builtin:room",
        "--out",
        out_dir.to_str().unwrap(),
        "--width",
        "96",
        "--height",
        "108",
        "--debug",
        "--explain",
    ]);
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    for name in
        ["left", "right", "depth_left", "depth_right", "normals_left", "normals_right", "albedo_left", "albedo_right"]
    {
        let image = image::open(out_dir.join(format!("{name}.png"))).unwrap_or_else(|e| panic!("{name}.png: {e}"));
        assert_eq!((image.width(), image.height()), (96, 108), "{name}.png size");
    }
    for name in ["ao_left", "ao_right"] {
        assert!(out_dir.join(format!("{name}.png")).is_file(), "the final AO is written beside the eyes");
    }
    assert!(t.contains(&format!("wrote {}", out_dir.join("ao_left.png").display())), "says where: {t}");
    assert!(t.contains("ran       gbuffer") && t.contains("ran       tonemap"), "{t}");
    let left = std::fs::read(out_dir.join("left.png")).unwrap();
    let right = std::fs::read(out_dir.join("right.png")).unwrap();
    assert_ne!(left, right, "the eyes see the scene from different places");
}

#[test]
fn bad_input_names_the_file_and_line_and_exits_2() {
    let dir = temp_dir("bad");
    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    let out = vrao(&["render", "--scene", bad.to_str().unwrap(), "--out", dir.join("o").to_str().unwrap()]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{t}");
    assert!(t.contains("bad.obj:3:"), "error names file and line: {t}");
    assert!(!t.contains("panicked"), "{t}");

    let missing = dir.join("missing.obj");
    let out = vrao(&["render", "--scene", missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out).contains("missing.obj"));

    let nan = dir.join("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n").unwrap();
    let out = vrao(&["render", "--scene", nan.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out).contains("nan.obj:3:"), "{}", text(&out));
}

#[test]
fn out_of_range_values_exit_2() {
    for args in [
        &["render", "--width", "0"][..],
        &["render", "--ipd", "-1"],
        &["render", "--ipd", "NaN"],
        &["render", "--exposure", "0"],
        &["render", "--eye", "1,2", "--look-at", "0,0,0"],
        &["render", "--eye", "0,0,0", "--look-at", "0,0,0"],
        &["render", "--stereo", "sideways"],
        &["render", "--scene", "builtin:nope"],
    ] {
        let out = vrao(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", text(&out));
        assert!(!text(&out).contains("panicked"), "{args:?}");
    }
}

/// The lines of stderr that are errors (vrao prints one).
fn error_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr).lines().filter(|l| l.starts_with("error:")).map(str::to_string).collect()
}

#[test]
fn vector_options_take_negative_numbers_without_equals() {
    let dir = temp_dir("negative-eye");
    let out_dir = dir.join("out");
    let out = vrao(&[
        "render",
        "--eye",
        "-13,1.8,-1",
        "--look-at",
        "-0.5,-1,0",
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(out_dir.join("left.png").is_file());
}

#[test]
fn an_unwritable_out_is_one_line_naming_it_with_exit_2() {
    let dir = temp_dir("unwritable");
    let file = dir.join("a-file");
    std::fs::write(&file, "not a directory").unwrap();
    let under_file = file.join("out");
    for out_path in ["/proc/vrao-cannot-write-here", under_file.to_str().unwrap()] {
        let out = vrao(&["render", "--width", "32", "--height", "32", "--out", out_path]);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "--out {out_path}: {t}");
        let errors = error_lines(&out);
        assert_eq!(errors.len(), 1, "one error line: {t}");
        assert!(errors[0].contains(out_path), "the error names {out_path}: {t}");
        assert!(!t.contains("panicked"), "{t}");
    }
    // A JSON report behind a file is refused the same way (after the work is done).
    let report = file.join("budget.json");
    let out = vrao(&[
        "budget",
        "--width",
        "8",
        "--height",
        "8",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--budget-ms",
        "1e9",
        "--out",
        report.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(error_lines(&out).iter().any(|l| l.contains(report.to_str().unwrap())), "{}", text(&out));
}

#[test]
fn a_scene_with_no_mesh_is_an_error_naming_the_file_with_exit_2() {
    let dir = temp_dir("empty-scene");
    let toml = dir.join("empty.toml");
    std::fs::write(&toml, "name = \"x\"\n").unwrap();
    let obj = dir.join("no-faces.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    for scene in [&toml, &obj] {
        let out = vrao(&[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
            "--out",
            dir.join("o").to_str().unwrap(),
        ]);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{}: {t}", scene.display());
        let errors = error_lines(&out);
        assert_eq!(errors.len(), 1, "{t}");
        assert!(errors[0].contains(scene.to_str().unwrap()), "the error names the file: {t}");
    }
}

#[test]
fn an_unknown_enum_value_exits_2_listing_the_accepted_values() {
    for (args, accepted) in [
        (&["render", "--technique", "foo"][..], &["ssao", "hbao", "gtao", "ssdo-bounce"][..]),
        (&["render", "--noise", "foo"], &["halton", "tiled"]),
        (&["run", "--motion", "foo"], &["static", "yaw-sweep", "figure-eight", "head-roll"]),
        (&["run", "--show", "foo"], &["eyes", "ao", "raw-ao", "depth", "normals"]),
        (&["run", "--headset", "foo"], &["auto", "openxr", "simulated"]),
        (&["bench", "--resolution", "quarter"], &["full", "half", "both"]),
        (&["budget", "--timing", "foo"], &["auto", "pipelined", "serial"]),
        (&["info", "--backend", "metal"], &["auto", "vulkan", "gl"]),
    ] {
        let out = vrao(args);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {t}");
        for value in accepted {
            assert!(t.contains(value), "{args:?} lists '{value}': {t}");
        }
    }
}

#[test]
fn value_names_users_type_today_still_parse() {
    // Parsed and then refused for a reason of their own (no window for --show) or run to
    // completion: either way not a usage error about the value.
    for args in [
        &["render", "--noise", "tiled5x5", "--width", "8", "--height", "8", "--out"][..],
        &["render", "--technique", "ssdo-bounce", "--width", "8", "--height", "8", "--out"],
        &[
            "render",
            "--stereo",
            "multipass",
            "--temporal-blend",
            "confidence",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
        ],
    ] {
        let dir = temp_dir("names");
        let mut args = args.to_vec();
        let out_dir = dir.join("o");
        args.push(out_dir.to_str().unwrap());
        let out = vrao(&args);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {}", text(&out));
    }
    let out = vrao(&["run", "--display", "none", "--show", "raw-ao", "--motion", "figure-eight"]);
    assert!(text(&out).contains("--show raw-ao needs a window"), "{}", text(&out));
}

#[test]
fn help_texts_name_papers_not_seed_numbers() {
    for command in ["info", "render", "bench", "run", "reprojection", "temporal", "budget"] {
        let out = vrao(&[command, "--help"]);
        let t = text(&out);
        assert!(out.status.success(), "{command} --help: {t}");
        for seed in ["seed 000", "seed 001", "seed 002", "seed 003"] {
            assert!(!t.contains(seed), "vrao {command} --help cites '{seed}':\n{t}");
        }
    }
}

#[test]
fn main_rs_is_a_thin_dispatcher() {
    let main = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/src/main.rs")).unwrap();
    let lines = main.lines().count();
    assert!(lines < 150, "src/main.rs has {lines} lines: subcommands belong in src/cli/, logic in the library");
    for entry in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/src/cli")).unwrap() {
        let path = entry.unwrap().path();
        let lines = std::fs::read_to_string(&path).unwrap().lines().count();
        assert!(lines <= 600, "{} has {lines} lines", path.display());
    }
}

#[test]
fn command_line_names_are_the_names_reports_print() {
    use clap::ValueEnum;
    use vrao::render::settings::{BounceForm, Denoise, DisplayMode, Quality, Technique};
    fn check<T: ValueEnum + Copy + PartialEq + std::fmt::Debug>(all: &[T], name: impl Fn(T) -> &'static str) {
        // The plain-Rust lists (the library has them without clap) miss no variant.
        for v in T::value_variants() {
            assert!(all.contains(v), "{v:?} is missing from the list");
        }
        assert_eq!(all.len(), T::value_variants().len());
        for &v in all {
            let typed = v.to_possible_value().expect("no hidden variants");
            assert_eq!(typed.get_name(), name(v), "{v:?}");
            assert!(T::from_str(name(v), false).is_ok(), "{v:?}");
        }
    }
    check(Technique::all(), Technique::name);
    check(&Quality::ALL, Quality::name);
    check(&BounceForm::ALL, BounceForm::name);
    check(&Denoise::ALL, Denoise::name);
    check(&DisplayMode::ALL, DisplayMode::name);
    check(&vrao::xr::simulated::motion::HeadMotion::ALL, vrao::xr::simulated::motion::HeadMotion::name);
    // Bench files name techniques; the governor parses them back.
    for &t in Technique::all() {
        assert_eq!(t.name().parse::<Technique>().ok(), Some(t));
    }
}

#[test]
fn a_bad_gltf_exits_2_with_one_line_and_writes_nothing() {
    let dir = temp_dir("bad-gltf");
    let truncated = dir.join("cut.glb");
    std::fs::write(&truncated, b"glTF\x02\0\0\0\xff\xff\0\0JSON").unwrap();
    let json = dir.join("lines.gltf");
    std::fs::write(&json, r#"{"asset":{"version":"2.0"},"nodes":[{"mesh":7}],"scenes":[{"nodes":[0]}]}"#).unwrap();
    for scene in [&truncated, &json] {
        let out_dir = dir.join("out");
        let out = vrao(&[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{}: {t}", scene.display());
        let errors = error_lines(&out);
        assert_eq!(errors.len(), 1, "{t}");
        assert!(errors[0].contains(scene.to_str().unwrap()), "the error names the file: {t}");
        assert!(!out_dir.exists() || std::fs::read_dir(&out_dir).unwrap().next().is_none(), "nothing written: {t}");
    }
}
