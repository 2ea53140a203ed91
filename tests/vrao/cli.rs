//! The `vrao` binary as a user runs it: exit codes, messages, written files.

use std::process::{Command, Output};

fn vrao(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vrao")).args(args).output().expect("vrao runs")
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

/// A fresh, empty directory for one test's files, removed when the test passes.
fn temp_dir(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("cli-{name}"))
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
    // The right eye's marched pixels in red over its grey image: some, not all, and
    // mostly on its outer (right) side, which the left eye's frustum never sees.
    let marched = image::open(out_dir.join("marched_right.png")).unwrap().to_rgb8();
    assert_eq!(marched.dimensions(), (96, 108));
    let red: Vec<u32> = marched.enumerate_pixels().filter(|(_, _, p)| p[0] != p[1]).map(|(x, _, _)| x).collect();
    let share = red.len() as f64 / (96.0 * 108.0);
    let outer = red.iter().filter(|&&x| x >= 48).count();
    assert!((0.02..0.5).contains(&share), "the right eye marched {share:.3} of its pixels");
    assert!(outer > 3 * (red.len() - outer), "marched pixels by side: {outer} outer, {} inner", red.len() - outer);
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
        // As far as a scene file's pose is refused (it rendered the sky alone).
        &["render", "--eye", "2e6,1,0", "--look-at", "0,0,0"],
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
    use vrao_ao::{Choice, Denoise, Foveation, Noise, Quality, Technique, TemporalBlend};
    use vrao_render::renderer::TimingChoice;
    use vrao_render::settings::{DisplayMode, StereoMode};
    use vrao_render::{BackendChoice, BounceForm};
    // The engine's and the renderer's settings (no clap there): every name distinct,
    // lower-case words joined by '-', and read back as the value it names.
    fn check_choice<T: Choice + std::fmt::Display>() {
        let names: Vec<&str> = T::all().iter().map(|v| v.name()).collect();
        for (i, &v) in T::all().iter().enumerate() {
            assert!(!names[..i].contains(&v.name()), "{v:?}: its name is taken");
            assert!(v.name().chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'), "{v:?}");
            assert_eq!(T::from_name(v.name()), Some(v));
            assert_eq!(v.to_string(), v.name());
        }
        assert_eq!(T::from_name("no-such-name"), None);
    }
    check_choice::<Technique>();
    check_choice::<Quality>();
    check_choice::<BounceForm>();
    check_choice::<Denoise>();
    check_choice::<Foveation>();
    check_choice::<TemporalBlend>();
    check_choice::<DisplayMode>();
    check_choice::<StereoMode>();
    check_choice::<TimingChoice>();
    check_choice::<BackendChoice>();
    assert_eq!(Noise::from_name("tiled5x5"), Some(Noise::Tiled5x5));
    // The application's own choices (clap's ValueEnum there).
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
    check(&vrao::xr::simulated::motion::HeadMotion::ALL, vrao::xr::simulated::motion::HeadMotion::name);
    // Bench files name techniques; the governor parses them back.
    for &t in Technique::all() {
        assert_eq!(t.name().parse::<Technique>().ok(), Some(t));
    }
}

/// Runs vrao and asserts the bad-input contract: exit 2, an `error:` line containing
/// every one of `names`, no panic and no path into the cargo registry. Returns the text.
fn refused(args: &[&str], names: &[&str]) -> String {
    refused_with(&[], args, names)
}

/// [`refused`] with the environment variables `env` set for vrao.
fn refused_with(env: &[(&str, &str)], args: &[&str], names: &[&str]) -> String {
    let out =
        Command::new(env!("CARGO_BIN_EXE_vrao")).args(args).envs(env.iter().copied()).output().expect("vrao runs");
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {t}");
    assert!(!t.contains("panicked") && !t.contains(".cargo/registry"), "{args:?}: {t}");
    let errors: Vec<String> =
        String::from_utf8_lossy(&out.stderr).lines().filter(|l| l.starts_with("error:")).map(str::to_string).collect();
    assert_eq!(errors.len(), 1, "{args:?}: one error line: {t}");
    for name in names {
        assert!(errors[0].contains(name), "{args:?}: the error names '{name}': {t}");
    }
    t
}

#[test]
fn count_and_time_options_are_bounded_and_say_so_in_help() {
    // Problem 6: warm-up + frames wrapped a u32 and panicked; problem 7: --warmup and
    // --virtual-time had no upper bound and ran on.
    let budget = ["budget", "--scene", "builtin:box", "--width", "96", "--height", "96", "--frames", "1"];
    refused(&[&budget[..], &["--warmup", "4294967295"]].concat(), &["--warmup", "0..=1000"]);
    refused(&["bench", "--warmup", "4294967295", "--no-reference"], &["--warmup", "0..=1000"]);
    refused(&["bench", "--frames", "0"], &["--frames", "1..=100000"]);
    refused(&["temporal", "--rays", "0"], &["--rays", "1..=65536"]);
    refused(&["run", "--frames", "10000001"], &["--frames", "1..=10000000"]);
    let run = ["run", "--headset", "simulated", "--display", "none", "--frames", "3"];
    refused(&[&run[..], &["--virtual-time", "1e300"]].concat(), &["--virtual-time", "1e300", "0..=10000"]);
    refused(&[&run[..], &["--virtual-time", "5,NaN"]].concat(), &["--virtual-time", "NaN"]);
    refused(&[&run[..], &["--refresh", "5"]].concat(), &["--refresh", "10..=500 Hz"]);
    refused(&[&run[..], &["--refresh", "1e300"]].concat(), &["--refresh", "10..=500 Hz"]);
    // vrao's own variable for the OpenXR mask is refused like `--mask bogus`, whichever
    // headset the run would have.
    for headset in ["simulated", "auto"] {
        let env = [("VRAO_OPENXR_VISIBILITY_MASK", "bogus")];
        let args = ["run", "--headset", headset, "--display", "none", "--frames", "1"];
        refused_with(&env, &args, &["VRAO_OPENXR_VISIBILITY_MASK=bogus", "`runtime`", "`fov`"]);
    }
    // Each side alone: the message names the option and its bound, never a profile's
    // other side (1200, the Vive's height) that OpenXR would not use.
    for (option, value) in [("--width", "0"), ("--height", "0"), ("--width", "8193")] {
        let t = refused(&[&run[..], &[option, value]].concat(), &[option, value, "1..=8192"]);
        assert!(!t.contains("1200") && !t.contains("1080"), "{t}");
    }
    for (command, bounds) in [
        ("budget", &["0..=1000", "1..=100000"][..]),
        ("bench", &["0..=1000", "1..=100000", "1..=65536", "1..=64"]),
        ("run", &["1..=10000000", "0..=10000", "10..=500"]),
        ("render", &["1..=100000"]),
        ("temporal", &["1..=65536"]),
    ] {
        let help = text(&vrao(&[command, "--help"]));
        for bound in bounds {
            assert!(help.contains(bound), "`vrao {command} --help` states {bound}:\n{help}");
        }
    }
}

#[test]
fn a_simulated_headset_takes_a_runtime_rate_such_as_20_hz() {
    let dir = temp_dir("refresh-20");
    let report = dir.join("r.json");
    let out = vrao(&[
        "run",
        "--headset",
        "simulated",
        "--display",
        "none",
        "--frames",
        "2",
        "--refresh",
        "20",
        "--width",
        "32",
        "--height",
        "32",
        "--governor",
        "off",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(json["budget_ms"], 50.0, "{json}");
}

/// Writes `name` under `dir` with `text`; returns its path as a string.
fn write(dir: &std::path::Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn light_that_would_overflow_the_shading_is_refused_naming_file_and_line() {
    // Problem 8: finite values whose product overflowed: black frames with exit 0.
    let dir = temp_dir("bright");
    let sun = write(
        &dir,
        "sun.toml",
        "[[mesh]]\nbuiltin = \"box\"\n\n[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\ncolor = [1e30, 1e30, 1e30]\nintensity = 1e30\n",
    );
    refused(&["render", "--scene", &sun], &["sun.toml:4:", "light color × intensity", "65504"]);
    let sky =
        write(&dir, "sky.toml", "[[mesh]]\nbuiltin = \"box\"\n\n[environment]\nsky = \"default\"\nintensity = 3e38\n");
    refused(&["render", "--scene", &sky], &["sky.toml:4:", "environment intensity"]);
    write(&dir, "lamp.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 3e38 3e38 3e38\n");
    let lamp = write(&dir, "lamp.obj", "mtllib lamp.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    refused(&["render", "--scene", &lamp], &["lamp.mtl:3:", "Ke"]);
    // Ordinary bright values still load.
    let fine = write(
        &dir,
        "fine.toml",
        "[[mesh]]\nbuiltin = \"box\"\n\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 500\n",
    );
    let out = vrao(&[
        "render",
        "--scene",
        &fine,
        "--width",
        "16",
        "--height",
        "16",
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
}

#[test]
fn geometry_that_would_vanish_is_refused_naming_file_and_line() {
    // Problem 12: far vertices, a scale that is 0 in f32, a far translation: a frame
    // of sky (or black) with exit 0.
    let dir = temp_dir("vanish");
    let far = write(&dir, "far.obj", "v 0 0 0\nv 1 0 0\nv 3e38 1 0\nf 1 2 3\n");
    refused(&["render", "--scene", &far], &["far.obj:3:", "3e38"]);
    let mesh = "[[mesh]]\nbuiltin = \"box\"\n";
    let tiny = write(&dir, "tiny.toml", &format!("{mesh}scale = 1e-300\n"));
    refused(&["render", "--scene", &tiny], &["tiny.toml:1:", "scale"]);
    let away = write(&dir, "away.toml", &format!("{mesh}translate = [1e300, 0, 0]\n"));
    refused(&["render", "--scene", &away], &["away.toml:1:", "translate 1e300"]);
    let huge = write(&dir, "huge.toml", &format!("{mesh}translate = [9e5, 0, 0]\nscale = 1e5\n"));
    refused(&["render", "--scene", &huge], &["huge.toml:1:", "vertex"]);
}

#[test]
fn a_texture_larger_than_the_device_takes_is_refused_naming_file_and_limit() {
    // Problem 9: 30 lines of wgpu log, exit 1, an empty --out folder.
    let dir = temp_dir("wide-texture");
    let limit: u32 = text(&vrao(&["info"]))
        .lines()
        .find_map(|l| l.trim().strip_prefix("max_texture_dimension_2d")?.trim().parse().ok())
        .expect("info prints max_texture_dimension_2d");
    image::RgbaImage::new(limit + 1, 1).save(dir.join("wide.png")).unwrap();
    write(&dir, "wide.mtl", "newmtl wide\nmap_Kd wide.png\n");
    let obj = write(&dir, "wide.obj", "mtllib wide.mtl\nusemtl wide\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let out_dir = dir.join("out");
    refused(
        &["render", "--scene", &obj, "--width", "16", "--height", "16", "--out", out_dir.to_str().unwrap()],
        &["wide.png", &format!("{}x1", limit + 1), &format!("at most {limit}")],
    );
    assert!(!out_dir.exists(), "a refused scene leaves no empty --out folder");
}

#[test]
fn a_screenshot_without_a_window_is_refused() {
    // Problem 10: silently ignored, exit 0, no file.
    let dir = temp_dir("screenshot");
    let shot = dir.join("s.png");
    refused(
        &[
            "run",
            "--headset",
            "simulated",
            "--display",
            "none",
            "--frames",
            "2",
            "--screenshot",
            shot.to_str().unwrap(),
        ],
        &["--screenshot", "window"],
    );
}

/// A change made to a bench file's JSON.
type BenchChange = dyn Fn(&mut serde_json::Value);

/// A copy of the built-in frontier (a real bench file) with `change` applied to its JSON.
fn bench_file(dir: &std::path::Path, name: &str, change: impl Fn(&mut serde_json::Value)) -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/governor/frontier.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    change(&mut json);
    write(dir, name, &serde_json::to_string_pretty(&json).unwrap())
}

#[test]
fn bench_and_frontier_files_are_validated_on_load_naming_file_record_and_value() {
    // Problem 11: empty files, unknown techniques, negative times and N = 100000 were
    // plotted, fitted and governed with.
    let dir = temp_dir("bench-files");
    let cases: [(&str, &BenchChange, &[&str]); 5] = [
        ("empty.json", &|j| j["records"] = serde_json::json!([]), &["empty.json", "no bench records"]),
        ("unknown.json", &|j| j["records"][2]["technique"] = "raytrace9000".into(), &["record 3", "raytrace9000"]),
        ("negative.json", &|j| j["records"][0]["occlusion_ms_per_eye"] = (-0.891).into(), &["record 1", "-0.891"]),
        ("samples.json", &|j| j["records"][1]["samples"] = 100000.into(), &["record 2", "samples 100000"]),
        ("radius.json", &|j| j["records"][0]["radius_m"] = 0.0.into(), &["record 1", "radius 0 m"]),
    ];
    for (name, change, names) in cases {
        let file = bench_file(&dir, name, change);
        let names: Vec<&str> = [&[name][..], names].concat();
        refused(&["bench", "--replot", &file, "--out", dir.join("replot").to_str().unwrap()], &names);
        refused(
            &["budget", "--fit", &file, "--width", "8", "--height", "8", "--out", dir.join("b.json").to_str().unwrap()],
            &names,
        );
        let run =
            ["run", "--headset", "simulated", "--display", "none", "--frames", "2", "--width", "8", "--height", "8"];
        let t = refused(&[&run[..], &["--governor-frontier", &file]].concat(), &names);
        assert!(!t.contains("governor: on"), "refused before the levels are printed as valid: {t}");
    }
}

#[test]
fn output_paths_are_checked_before_the_work() {
    // Problem 13: bench, temporal, budget and run failed at the end of their work.
    let dir = temp_dir("outputs");
    let file = write(&dir, "a-file", "not a folder");
    refused(&["bench", "--out", &file], &[&file, "is a file"]);
    let unwritable = "/proc/nope/r.json";
    refused(&["temporal", "--out", unwritable], &[unwritable]);
    refused(&["reprojection", "--out", unwritable], &[unwritable]);
    refused(&["budget", "--out", dir.to_str().unwrap()], &[dir.to_str().unwrap(), "folder"]);
    refused(&["run", "--headset", "simulated", "--display", "none", "--report", unwritable], &[unwritable]);
    // A check leaves nothing behind.
    let entries: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(entries, [std::ffi::OsString::from("a-file")]);
}

#[test]
fn messages_name_the_real_cause() {
    // Problem 14.
    let dir = temp_dir("messages");
    let big = write(&dir, "big.toml", "[[mesh]]\nbuiltin = \"box\"\nscale = \"big\"\n");
    refused(&["render", "--scene", &big], &["big.toml:3:", "scale must be a number or [x, y, z]"]);
    let looped = dir.join("loop.toml");
    std::os::unix::fs::symlink(&looped, &looped).unwrap();
    let t = refused(&["render", "--scene", looped.to_str().unwrap()], &["loop.toml"]);
    assert!(!t.contains("no such file"), "a symlink loop is not a missing file: {t}");
    // No display: a window problem, not a GPU one, and no build path.
    let out = Command::new(env!("CARGO_BIN_EXE_vrao"))
        .args([
            "run",
            "--headset",
            "simulated",
            "--display",
            "mirror",
            "--frames",
            "2",
            "--width",
            "8",
            "--height",
            "8",
        ])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{t}");
    assert!(t.contains("cannot open a desktop window") && t.contains("--display none"), "{t}");
    assert!(!t.contains("no usable GPU") && !t.contains(".cargo") && !t.contains("winit-0"), "{t}");
}

#[test]
fn sigterm_and_sigint_end_a_session_with_its_report() {
    // Problem 10: SIGTERM lost the report. The handler is in place before the session.
    let dir = temp_dir("signals");
    for signal in ["TERM", "INT"] {
        let report = dir.join(format!("{signal}.json"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_vrao"))
            .args(["run", "--headset", "simulated", "--display", "none", "--width", "16", "--height", "16"])
            .args(["--frames", "10000000", "--report", report.to_str().unwrap()])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // Whenever the signal lands (start-up or running), the run ends with its report.
        std::thread::sleep(std::time::Duration::from_secs(3));
        let sent = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().unwrap();
        assert!(sent.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(0), "SIG{signal} ends the run cleanly");
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(json["interrupted"], true, "SIG{signal}: {json}");
        assert!(json["interrupted_in"].is_string(), "SIG{signal}: the report says in which state: {json}");
    }
}

#[test]
fn an_unusable_openxr_runtime_names_its_manifest_not_the_gpu() {
    // Before: every case read "no usable GPU: --headset openxr: no OpenXR runtime (…)".
    let dir = temp_dir("manifest");
    let missing = dir.join("missing.json").to_str().unwrap().to_string();
    let broken = write(&dir, "broken.json", "{ not json");
    let gone = write(&dir, "gone.json", r#"{"runtime": {"library_path": "./libgone.so"}}"#);
    // A device is refused before the loader reads it (the loader read /dev/zero forever).
    let device = "/dev/zero".to_string();
    let cases = [
        (&missing, "cannot be read"),
        (&broken, "does not parse"),
        (&gone, "does not exist"),
        (&device, "cannot be read"),
    ];
    for (manifest, cause) in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_vrao"))
            .args(["run", "--headset", "openxr", "--display", "none", "--frames", "1"])
            .env("XR_RUNTIME_JSON", manifest)
            .output()
            .unwrap();
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{t}");
        assert!(!t.contains("no usable GPU") && !t.contains("panicked"), "{t}");
        assert_eq!(error_lines(&out).len(), 1, "{t}");
        // Without the OpenXR loader installed, that is the cause named instead.
        if !t.contains("no OpenXR loader") {
            assert!(t.contains(manifest.as_str()) && t.contains(cause), "{manifest}: {t}");
        }
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

#[test]
fn negative_numbers_are_values_refused_by_their_range_and_the_bench_refuses_duplicates() {
    let dir = temp_dir("negative");
    let out_dir = dir.join("out");
    let out = vrao(&["render", "--time", "-1", "--width", "8", "--height", "8", "--out", out_dir.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("-1 s is not within"), "{stderr}");
    let out = vrao(&["run", "--refresh", "-90", "--headset", "simulated", "--display", "none", "--frames", "1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("unexpected argument") && stderr.contains("-90"), "{stderr}");
    let out = vrao(&[
        "bench",
        "--techniques",
        "ssao,ssao",
        "--no-reference",
        "--width",
        "8",
        "--height",
        "8",
        "--frames",
        "1",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("techniques name ssao twice"), "{stderr}");
    // A negative count or size is a value its parser refuses, naming it, not a flag.
    for args in [
        &["render", "--samples", "-1"][..],
        &["render", "--width", "-5"],
        &["run", "--frames-in-flight", "-1", "--headset", "simulated", "--display", "none"],
        &["peer", "--radius", "-1"],
    ] {
        let out = vrao(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        let names_it = stderr.contains("-1") || stderr.contains("-5");
        assert!(!stderr.contains("unexpected argument") && names_it, "{args:?}: {stderr}");
    }
    let out = vrao(&["bench", "--mask", "on,on", "--no-reference", "--width", "8", "--height", "8", "--frames", "1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("mask settings name on twice"), "{stderr}");
}

#[test]
fn a_window_without_a_display_is_refused_before_the_headset_opens_and_the_report_says_why() {
    // Issue 39: refused only after the runtime, session, swapchains and pipelines were
    // made (2.2 s), and no report written.
    let dir = temp_dir("no-display");
    for headset in ["simulated", "openxr"] {
        let report = dir.join(format!("{headset}.json"));
        let started = std::time::Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_vrao"))
            .args([
                "run",
                "--headset",
                headset,
                "--display",
                "mirror",
                "--frames",
                "2",
                "--width",
                "8",
                "--height",
                "8",
            ])
            .args(["--report", report.to_str().unwrap()])
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("WAYLAND_SOCKET")
            // No runtime either: the window is what is named, so it was checked first.
            .env("XR_RUNTIME_JSON", dir.join("no-runtime.json"))
            .output()
            .unwrap();
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{headset}: {t}");
        let errors = error_lines(&out);
        assert_eq!(errors.len(), 1, "{headset}: {t}");
        assert!(errors[0].contains("cannot open a desktop window") && errors[0].contains("--display none"), "{t}");
        assert!(!t.contains("headset:") && !t.contains("OpenXR"), "{headset}: nothing was opened first: {t}");
        assert!(started.elapsed() < std::time::Duration::from_secs(10), "{headset}: {:?}", started.elapsed());
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert!(json["refused"].as_str().unwrap().contains("cannot open a desktop window"), "{json}");
        assert_eq!(json["frames_rendered"], 0, "{json}");
        assert!((json["budget_ms"].as_f64().unwrap() - 1000.0 / 90.0).abs() < 1e-9, "the vive profile's: {json}");
    }
    // A run that starts writes no `refused`.
    let report = dir.join("ran.json");
    let out = vrao(&[
        "run",
        "--headset",
        "simulated",
        "--display",
        "none",
        "--frames",
        "2",
        "--width",
        "8",
        "--height",
        "8",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(json["refused"].is_null() && json["stretched_frames"] == 0, "{json}");
    assert!(json["budget_source"].as_str().unwrap().contains("simulated headset"), "{json}");
}

#[test]
fn every_refused_run_writes_its_report_and_a_refused_report_path_writes_nothing() {
    // Issue 50: some refusals wrote the report and others (the scene, the screenshot's
    // path) did not. Now every refusal after the report's own path is accepted does.
    let dir = temp_dir("refused-reports");
    let frontier = dir.join("frontier.json");
    std::fs::write(&frontier, "{}").unwrap();
    let frontier = frontier.to_str().unwrap().to_string();
    let missing_folder = dir.join("no-such-folder").join("shot.png");
    let missing_folder = missing_folder.to_str().unwrap().to_string();
    let base = ["run", "--headset", "simulated", "--display", "none", "--frames", "1", "--width", "8", "--height", "8"];
    // (name, extra arguments, an environment variable, what the error names)
    type Case<'a> = (&'a str, Vec<&'a str>, Option<(&'a str, &'a str)>, &'a str);
    let cases: [Case; 5] = [
        ("scene", vec!["--scene", "no-such-scene.obj"], None, "no-such-scene.obj"),
        ("screenshot", vec!["--screenshot", &missing_folder], None, "shot.png"),
        ("variable", vec![], Some(("VRAO_OPENXR_VISIBILITY_MASK", "bogus")), "VRAO_OPENXR_VISIBILITY_MASK"),
        ("window", vec!["--show", "ao"], None, "--show ao"),
        ("frontier", vec!["--governor-frontier", &frontier], None, "frontier.json"),
    ];
    for (name, extra, env, named) in cases {
        let report = dir.join(format!("{name}.json"));
        let mut args: Vec<&str> = base.to_vec();
        args.extend(extra);
        args.extend(["--report", report.to_str().unwrap()]);
        let out = Command::new(env!("CARGO_BIN_EXE_vrao")).args(&args).envs(env).output().unwrap();
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{name}: {t}");
        let errors = error_lines(&out);
        assert!(errors.len() == 1 && errors[0].contains(named), "{name}: {t}");
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert!(errors[0].contains(json["refused"].as_str().unwrap()), "{name}: the report says why: {json}");
        assert_eq!(json["frames_rendered"], 0, "{name}: {json}");
    }
    // The report's own path refused: nothing is written, wherever else the run fails.
    let report = dir.join("no-such-folder").join("report.json");
    let out = vrao(&[&base[..], &["--scene", "no-such-scene.obj", "--report", report.to_str().unwrap()]].concat());
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(error_lines(&out)[0].contains("report.json"), "the report's path is checked first: {}", text(&out));
    assert!(!report.exists() && !dir.join("no-such-folder").exists());
}

#[test]
fn an_interrupted_render_leaves_nothing_behind() {
    // Issue 39: a render interrupted by Ctrl-C left an empty output folder.
    let dir = temp_dir("render-interrupted");
    for (signal, after_ms) in [("INT", 1500), ("TERM", 4000), ("INT", 6000)] {
        let out_dir = dir.join(format!("{signal}-{after_ms}")).join("nested");
        let child = Command::new(env!("CARGO_BIN_EXE_vrao"))
            .args(["render", "--width", "64", "--height", "64", "--frames", "100000", "--debug"])
            .args(["--out", out_dir.to_str().unwrap()])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(after_ms));
        let sent = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().unwrap();
        assert!(sent.success());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "SIG{signal} at {after_ms} ms: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!out_dir.parent().unwrap().exists(), "SIG{signal} at {after_ms} ms left {}", out_dir.display());
    }
    // While the files are written: once the first file appears, one signal (the render
    // stops and removes what it wrote) or two (the second removes it and exits at once).
    for signals in [1, 2] {
        let out_dir = dir.join(format!("writing-{signals}")).join("nested");
        let child = Command::new(env!("CARGO_BIN_EXE_vrao"))
            .args(["render", "--width", "768", "--height", "768", "--debug"])
            .args(["--out", out_dir.to_str().unwrap()])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let started = std::time::Instant::now();
        while !out_dir.join("left.png").exists() && started.elapsed() < std::time::Duration::from_secs(120) {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        for _ in 0..signals {
            Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        if out.status.code() == Some(0) {
            // Done before the signal landed: then every file is whole.
            eprintln!("{signals} signal(s) came after the render finished: {stderr}");
            assert!(image::open(out_dir.join("albedo_right.png")).is_ok());
            std::fs::remove_dir_all(out_dir.parent().unwrap()).unwrap();
            continue;
        }
        assert_eq!(out.status.code(), Some(130), "{signals} signal(s) while writing: {stderr}");
        assert!(!out_dir.parent().unwrap().exists(), "{signals} signal(s) while writing left {}", out_dir.display());
    }
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing in {}", dir.display());
}

/// `render --mask on` leaves the pixels the lens hides black, as its help says (they were
/// computed and shown before: on and off gave byte-identical images); `off` computes the
/// whole rectangle.
#[test]
fn render_with_the_mask_leaves_what_the_lens_hides_black() {
    let dir = temp_dir("render-mask");
    let corner_and_centre = |mask: &str| {
        let out_dir = dir.join(mask);
        let args = ["render", "--mask", mask, "--width", "64", "--height", "72", "--out", out_dir.to_str().unwrap()];
        let out = vrao(&args);
        assert!(out.status.success(), "{}", text(&out));
        let image = image::open(out_dir.join("left.png")).unwrap().to_rgba8();
        (image.get_pixel(0, 0).0, image.get_pixel(32, 36).0)
    };
    let (on_corner, on_centre) = corner_and_centre("on");
    let (off_corner, off_centre) = corner_and_centre("off");
    assert_eq!(&on_corner[..3], &[0, 0, 0], "the lens hides the corner: black");
    assert_ne!(&off_corner[..3], &[0, 0, 0], "without the mask the corner is computed");
    assert_eq!(on_centre, off_centre, "the centre, which the lens shows, is the same either way");
}
