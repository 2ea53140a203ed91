//! The desktop window under a real X server (Xvfb, started by .ci/run): each display mode
//! draws, and its screenshot holds the panel and the scene.

use crate::common;

use std::process::{Command, Output};

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

/// The X display to use, or `None` (skip) when there is none outside CI.
fn display() -> Option<String> {
    match std::env::var("DISPLAY") {
        Ok(d) if !d.is_empty() => Some(d),
        _ => {
            common::skip("needs an X display (DISPLAY is unset; .ci/test starts Xvfb)");
            None
        }
    }
}

fn run_window(mode: &str, screenshot: &std::path::Path, extra: &[&str]) -> Output {
    let _one_at_a_time = common::gpu_lock();
    Command::new(env!("CARGO_BIN_EXE_vrao"))
        .args(["run", "--headset", "simulated", "--display", mode, "--frames", "3", "--width", "96", "--height", "80"])
        .args(["--window", "640x360", "--motion", "yaw-sweep", "--screenshot", screenshot.to_str().unwrap()])
        .args(extra)
        .output()
        .expect("vrao runs")
}

/// The largest difference between two colour channels of any pixel in a region: 0 for
/// a grey picture.
fn region_colourfulness(image: &image::RgbaImage, x0: u32, x1: u32, y0: u32, y1: u32) -> u8 {
    (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .map(|(x, y)| {
            let p = image.get_pixel(x, y);
            let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            hi - lo
        })
        .max()
        .unwrap_or(0)
}

/// Mean and standard deviation of the luminance of a region of the screenshot.
fn region_stats(image: &image::RgbaImage, x0: u32, x1: u32, y0: u32, y1: u32) -> (f64, f64) {
    let values: Vec<f64> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .map(|(x, y)| {
            let p = image.get_pixel(x, y);
            0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
        })
        .collect();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64;
    (mean, var.sqrt())
}

#[test]
fn mirror_and_single_pass_windows_show_the_panel_and_the_scene() {
    let Some(_display) = display() else { return };
    let dir = common::temp_dir("window");
    // The panel is 300 points wide; at scale 1 the picture fills x 300..640.
    for mode in ["mirror", "single-pass"] {
        let shot = dir.join(format!("{mode}.png"));
        let out = run_window(mode, &shot, &[]);
        assert!(out.status.success(), "{mode}: {}", text(&out));
        let image = image::open(&shot).unwrap_or_else(|e| panic!("{mode}: no screenshot: {e}")).to_rgba8();
        assert_eq!(image.dimensions(), (640, 360), "{mode}");
        // The panel: text on a dark background.
        let (panel_mean, panel_spread) = region_stats(&image, 0, 290, 0, 360);
        assert!(panel_mean > 10.0 && panel_spread > 10.0, "{mode}: panel {panel_mean} ± {panel_spread}");
        // The picture: lit walls, not the black clear colour, and not one flat colour.
        let halves = if mode == "mirror" { vec![(300, 470), (470, 640)] } else { vec![(300, 640)] };
        for (x0, x1) in halves {
            let (mean, spread) = region_stats(&image, x0, x1, 60, 300);
            assert!(mean > 40.0 && spread > 5.0, "{mode}: picture x {x0}..{x1}: {mean} ± {spread}");
        }
    }
}

#[test]
fn the_buffer_view_shows_each_eyes_ao_depth_and_normals() {
    let Some(_display) = display() else { return };
    let dir = common::temp_dir("window-buffers");
    // Half-resolution GTAO with the blur: the final AO (upsampled) and the raw AO differ.
    let ao = ["--technique", "gtao", "--half-res", "--governor", "off"];
    let mut pictures = Vec::new();
    for show in ["ao", "raw-ao", "depth", "normals"] {
        let shot = dir.join(format!("{show}.png"));
        let out = run_window("mirror", &shot, &[&ao[..], &["--show", show]].concat());
        assert!(out.status.success(), "{show}: {}", text(&out));
        let image = image::open(&shot).unwrap_or_else(|e| panic!("{show}: no screenshot: {e}")).to_rgba8();
        // Each 96×80 eye fills its 170-pixel-wide slot, 142 pixels tall around y = 180.
        for (x0, x1) in [(302, 468), (472, 638)] {
            let (mean, spread) = region_stats(&image, x0, x1, 115, 245);
            let colour = region_colourfulness(&image, x0, x1, 115, 245);
            match show {
                // AO: mostly unoccluded (white) with darker corners, grey.
                "ao" | "raw-ao" => {
                    assert!(
                        mean > 150.0 && spread > 5.0 && colour <= 2,
                        "{show} x {x0}..{x1}: {mean} ± {spread}, {colour}"
                    )
                }
                // Depth: grey, varying across the room.
                "depth" => assert!(
                    mean > 40.0 && spread > 3.0 && colour <= 2,
                    "{show} x {x0}..{x1}: {mean} ± {spread}, {colour}"
                ),
                // Normals: the walls face different ways, so different colours.
                _ => assert!(colour > 100 && spread > 20.0, "{show} x {x0}..{x1}: {mean} ± {spread}, {colour}"),
            }
        }
        pictures.push(image);
    }
    // The final AO is filtered: it is not the raw AO texel for texel.
    let differing = pictures[0].pixels().zip(pictures[1].pixels()).filter(|(a, b)| a[0].abs_diff(b[0]) > 8).count();
    assert!(differing > 1000, "final and raw AO differ in only {differing} pixels");
}

#[test]
fn display_none_needs_no_window_system() {
    let _one_at_a_time = common::gpu_lock();
    let out = Command::new(env!("CARGO_BIN_EXE_vrao"))
        .args([
            "run",
            "--headset",
            "simulated",
            "--display",
            "none",
            "--frames",
            "2",
            "--width",
            "32",
            "--height",
            "32",
        ])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
}
