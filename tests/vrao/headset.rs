//! `vrao run` with the simulated headset: the OpenXR fall back, deterministic virtual
//! time, and the compositor's reprojection against freshly rendered frames.

use crate::common;

use std::process::{Command, Output};
use vrao::measure::reprojection::{measure, HeadMove};

fn vrao(args: &[&str]) -> Output {
    let _one_at_a_time = common::gpu_lock();
    Command::new(env!("CARGO_BIN_EXE_vrao")).args(args).output().expect("vrao runs")
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

const SMALL: [&str; 4] = ["--width", "48", "--height", "40"];

#[test]
fn without_a_runtime_run_falls_back_to_the_simulated_headset_and_says_why() {
    let mut args = vec!["run", "--frames", "20", "--display", "none"];
    args.extend(SMALL);
    let out = vrao(&args);
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    let headset_line = t.lines().find(|l| l.starts_with("headset:")).unwrap_or_else(|| panic!("no headset line:\n{t}"));
    assert!(headset_line.contains("using the simulated headset"), "{headset_line}");
    if std::env::var_os("CI").is_some() {
        // CI installs the real loader and no runtime.
        assert!(headset_line.contains("no OpenXR runtime"), "{headset_line}");
    } else {
        assert!(headset_line.contains("no OpenXR"), "{headset_line}");
    }
    assert!(t.contains("frames: 20 rendered"), "{t}");
}

#[test]
fn headset_openxr_without_a_runtime_is_an_error_with_exit_2() {
    let mut args = vec!["run", "--frames", "2", "--display", "none", "--headset", "openxr"];
    args.extend(SMALL);
    let out = vrao(&args);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{t}");
    assert!(t.contains("--headset openxr") && t.contains("no OpenXR"), "{t}");
}

#[test]
fn headset_simulated_never_asks_openxr() {
    // With the loader's log on, any use of OpenXR would print loader messages.
    let mut args = vec!["run", "--frames", "3", "--display", "none", "--headset", "simulated"];
    args.extend(SMALL);
    let _one_at_a_time = common::gpu_lock();
    let out = Command::new(env!("CARGO_BIN_EXE_vrao")).args(&args).env("XR_LOADER_DEBUG", "all").output().unwrap();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    assert!(t.contains("headset: using the simulated headset"), "{t}");
    assert!(!t.to_lowercase().contains("openxr-loader") && !t.contains("XR_"), "{t}");
}

fn counters_of_a_virtual_run(dir: &std::path::Path, name: &str) -> serde_json::Value {
    let report = dir.join(name);
    let mut args = vec![
        "run",
        "--headset",
        "simulated",
        "--display",
        "none",
        "--frames",
        "40",
        "--motion",
        "yaw-sweep",
        "--virtual-time",
        "6,9,30,4,15",
        "--report",
        report.to_str().unwrap(),
    ];
    args.extend(SMALL);
    let out = vrao(&args);
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    json["counters"].clone()
}

#[test]
fn virtual_time_runs_are_deterministic_and_count_late_frames_as_reprojected() {
    let dir = common::temp_dir("virtual-time");
    let first = counters_of_a_virtual_run(&dir, "a.json");
    let second = counters_of_a_virtual_run(&dir, "b.json");
    assert_eq!(first, second);
    // The script's 30 ms and 15 ms frames miss their vsync (11.1 ms): those vsyncs are
    // reprojected; the fast frames are presented on time.
    let presented = first["presented"].as_u64().unwrap();
    let reprojected = first["reprojected"].as_u64().unwrap();
    assert!(presented >= 16 && reprojected >= 8, "{first}");
    assert_eq!(first["submitted"], 40);
}

#[test]
fn depth_based_reprojection_beats_rotational_under_translation_and_both_beat_no_warp_under_rotation() {
    let (gpu, _one_at_a_time) = common::gpu();
    let scene = vrao_render::Scene::load("builtin:room").unwrap();
    let settings = vrao_render::Settings {
        profile: vrao_render::HeadsetProfile::with_size("test", 160, 144),
        ..vrao_render::Settings::default()
    };
    let mut renderer = vrao_render::Renderer::new(gpu, &scene, &settings).unwrap();
    let head = scene.head.pose_at(0.0);
    let moves = [HeadMove::RotateDegrees(5.0), HeadMove::TranslateCm(5.0), HeadMove::TranslateCm(10.0)];
    let rows = measure(&mut renderer, &head, &moves, 0.0).unwrap();
    for r in &rows {
        assert!(r.rotational_rmse.is_finite() && r.depth_rmse.is_finite(), "{r:?}");
        assert!(r.depth_rmse < r.stale_rmse, "{r:?}");
    }
    // Rotation: both warps are exact up to resampling and the frame edge.
    let rotation = &rows[0];
    assert!(rotation.rotational_rmse < 0.5 * rotation.stale_rmse, "{rotation:?}");
    assert!(rotation.depth_rmse < 0.5 * rotation.stale_rmse, "{rotation:?}");
    // Translation: parallax that only depth can undo.
    for r in &rows[1..] {
        assert!(r.depth_rmse < 0.8 * r.rotational_rmse, "{r:?}");
    }
}

fn run_report(dir: &std::path::Path, name: &str, extra: &[&str]) -> serde_json::Value {
    let report = dir.join(name);
    let mut args = vec!["run", "--headset", "simulated", "--display", "none", "--frames", "12"];
    args.extend(extra);
    args.extend(["--report", report.to_str().unwrap()]);
    args.extend(SMALL);
    let out = vrao(&args);
    assert!(out.status.success(), "{}", text(&out));
    serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap()
}

#[test]
fn the_run_report_counts_rendered_frames_frames_in_flight_and_the_governors_changes() {
    let dir = common::temp_dir("run-report");
    let on = run_report(&dir, "on.json", &[]);
    assert_eq!(on["frames_rendered"], 12, "{on}");
    assert_eq!(on["frames_in_flight_limit"], 2, "{on}");
    let in_flight = on["frames_in_flight_max"].as_u64().unwrap();
    assert!((1..=2).contains(&in_flight), "{on}");
    // At 500 Hz each frame's GPU work outlasts the 2 ms period: the next frame is handed
    // over while it runs. Nothing the frame loop submits of its own may wait for it (an
    // empty submission to watch the frame's end did, on lavapipe: 1 in flight).
    let fast = run_report(&dir, "fast.json", &["--refresh", "500"]);
    assert_eq!(fast["frames_in_flight_max"], 2, "{fast}");
    // Every frame's GPU time came back (the last ones when the session ended), and each
    // over-budget frame is one of them.
    assert_eq!(on["timed_frames"], 12, "{on}");
    assert!(on["over_budget_frames"].as_u64().unwrap() <= 12, "{on}");
    // In real time each timed frame is judged against its display time on the headset's
    // clock (issue 50); in virtual time none is, and the report says why.
    assert_eq!(on["clocked_frames"], 12, "{on}");
    assert!(on["late_frames"].as_u64().unwrap() <= 12, "{on}");
    assert!(on["late_clock"].as_str().unwrap().starts_with("the headset's clock"), "{on}");
    let virtual_time = run_report(&dir, "virtual.json", &["--virtual-time", "5"]);
    assert_eq!(
        (&virtual_time["clocked_frames"], &virtual_time["late_frames"]),
        (&serde_json::json!(0), &serde_json::json!(0))
    );
    assert!(virtual_time["late_clock"].as_str().unwrap().starts_with("none: virtual time"), "{virtual_time}");
    assert_eq!(on["governor"], "on");
    for change in on["governor_changes"].as_array().unwrap() {
        assert!(change["reason"].as_str().unwrap().contains("ms"), "{change}");
        assert_ne!(change["from"], change["to"], "{change}");
    }
    let off = run_report(&dir, "off.json", &["--governor", "off", "--frames-in-flight", "1"]);
    assert_eq!(off["governor"], "off");
    assert_eq!(off["governor_changes"], serde_json::json!([]));
    // One frame in flight: each frame waits for the one before it.
    assert_eq!(off["frames_in_flight_max"], 1, "{off}");
    // The right eye's share of its tiles that the last frame computed rather than copied
    // from the left eye (issue 49): some, never all; none with independent eyes.
    let shares: Vec<f64> = off["right_eye_tiles"]
        .as_array()
        .expect("right-eye tiles")
        .iter()
        .map(|t| t["share"].as_f64().unwrap())
        .collect();
    assert!(!shares.is_empty() && shares.iter().all(|s| *s > 0.0 && *s < 0.5), "{off}");
    let independent = run_report(&dir, "independent.json", &["--governor", "off", "--independent-eyes"]);
    assert!(independent.get("right_eye_tiles").is_none(), "{independent}");
}

#[test]
fn profiles_set_the_budget_and_an_unknown_profile_or_rate_is_refused() {
    let dir = common::temp_dir("profiles");
    let index = run_report(&dir, "index.json", &["--profile", "index", "--refresh", "144", "--governor", "off"]);
    assert!((index["budget_ms"].as_f64().unwrap() - 1000.0 / 144.0).abs() < 1e-9, "{index}");
    assert!(index["headset"].as_str().unwrap().contains("index"), "{index}");
    assert!(
        index["budget_source"].as_str().unwrap().contains("144 Hz"),
        "the report says which rate governed: {index}"
    );
    // A rate the product does not list but a runtime may run at (the simulated headset
    // takes any sane rate); an insane one is refused.
    let pico = run_report(&dir, "pico.json", &["--profile", "pico-4", "--refresh", "120", "--governor", "off"]);
    assert!((pico["budget_ms"].as_f64().unwrap() - 1000.0 / 120.0).abs() < 1e-9, "{pico}");
    for bad in [&["--profile", "no-such-headset"][..], &["--profile", "pico-4", "--refresh", "1000"][..]] {
        let mut args = vec!["run", "--headset", "simulated", "--display", "none", "--frames", "2"];
        args.extend(bad);
        let out = vrao(&args);
        assert_eq!(out.status.code(), Some(2), "{}", text(&out));
        assert_eq!(text(&out).trim().lines().count(), 1, "{}", text(&out));
    }
}
