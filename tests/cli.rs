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
