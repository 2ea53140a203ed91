//! The OpenGL backend cannot run the renderer (src/render/gpu/support.rs says what it
//! lacks): `--backend gl`, `vrao info` and auto's fall-back to GL when no Vulkan driver
//! exists each refuse it in one line with exit 2, before any pipeline is built.

use std::process::Command;

/// Exit code and the non-empty lines of stdout and stderr.
fn run(command: &mut Command) -> (Option<i32>, Vec<String>) {
    let out = command.output().expect("vrao runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.code(), text.lines().filter(|l| !l.trim().is_empty()).map(String::from).collect())
}

fn assert_refused(what: &str, (code, lines): (Option<i32>, Vec<String>)) {
    assert_eq!(code, Some(2), "{what}: {lines:#?}");
    assert_eq!(lines.len(), 1, "{what}: one line, not {lines:#?}");
    // Either this machine has a GL adapter and the line names what it lacks, or it has none.
    let line = &lines[0];
    assert!(
        (line.contains("lacks") && line.contains("textureLoad on depth textures")) || line.contains("no adapter"),
        "{what}: {line}"
    );
}

fn vrao() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vrao"))
}

#[test]
fn backend_gl_is_refused_in_one_line() {
    let out = std::env::temp_dir().join(format!("vrao-gl-{}", std::process::id()));
    let render = ["render", "--backend", "gl", "--width", "64", "--height", "64", "--out"];
    assert_refused("render --backend gl", run(vrao().args(render).arg(&out)));
    assert_refused("info --backend gl", run(vrao().args(["info", "--backend", "gl"])));
    assert!(!out.exists(), "nothing is written when the backend is refused");
}

#[test]
fn auto_falls_back_to_gl_only_to_refuse_it() {
    // Point the Vulkan loader at no driver at all, so auto finds only GL (if anything).
    let mut command = vrao();
    command
        .args(["info"])
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json");
    assert_refused("info with no Vulkan driver", run(&mut command));
}
