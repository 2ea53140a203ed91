//! `vrao budget` and `vrao bench` as a user runs them: verdicts, exit codes and the files
//! they write. Small sizes: this checks the mechanism; the figures are for the reports.

use std::process::{Command, Output};
use std::sync::Mutex;

/// The GPU commands run one at a time (two cores, a CPU rasteriser).
static SERIAL: Mutex<()> = Mutex::new(());

fn vrao(args: &[&str]) -> Output {
    let _one_at_a_time = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    Command::new(env!("CARGO_BIN_EXE_vrao")).args(args).output().expect("vrao runs")
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

/// A fresh, empty directory for one test's files, removed when the test passes.
fn temp_dir(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("measure-{name}"))
}

fn budget(dir: &std::path::Path, budget_ms: &str, extra: &[&str]) -> (Output, serde_json::Value) {
    let json = dir.join(format!("budget-{budget_ms}.json"));
    let mut args = vec![
        "budget",
        "--scene",
        "builtin:room",
        "--width",
        "48",
        "--height",
        "40",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--samples",
        "8",
        "--budget-ms",
        budget_ms,
        "--out",
        json.to_str().unwrap(),
    ];
    args.extend(extra);
    let out = vrao(&args);
    let report = std::fs::read_to_string(&json).map(|t| serde_json::from_str(&t).unwrap()).unwrap_or_default();
    (out, report)
}

#[test]
fn budget_passes_a_generous_budget_with_exit_0_and_fails_a_tiny_one_with_exit_3() {
    let dir = temp_dir("budget");
    let (out, report) = budget(&dir, "1000000", &[]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(0), "{t}");
    assert!(t.contains("left eye") && t.contains("right eye") && t.contains("PASS") && !t.contains("FAIL"), "{t}");
    // Every pass of the frame, with stereo and per-eye medians over 3 frames.
    let passes = report["passes"].as_array().expect("passes");
    let names: Vec<&str> = passes.iter().map(|p| p["pass"].as_str().unwrap()).collect();
    // The command line's default technique is gtao.
    for pass in ["gbuffer", "direct", "gtao", "blur", "composite", "tonemap"] {
        assert!(names.contains(&pass), "{pass} missing from {names:?}");
    }
    for p in passes {
        for key in ["stereo", "left", "right"] {
            assert_eq!(p[key]["frames"], 3, "{p}");
            assert!(p[key]["median_ms"].as_f64().unwrap() > 0.0, "{p}");
        }
    }
    assert_eq!(report["verdicts"].as_array().unwrap().len(), 3);
    assert_eq!(report["cpu_encode"].as_array().unwrap().len(), 3);
    // The AO chain sums its passes' medians, and the right eye's added share follows.
    let chain = &report["ao_chain"];
    let chain_passes: Vec<&str> =
        chain["passes"].as_array().expect("ao_chain").iter().map(|p| p.as_str().unwrap()).collect();
    assert_eq!(chain_passes, ["gtao", "blur"], "{chain}");
    let median = |pass: &str, scope: &str| -> f64 {
        passes.iter().find(|p| p["pass"] == pass).unwrap()[scope]["median_ms"].as_f64().unwrap()
    };
    let (left, stereo) =
        (median("gtao", "left") + median("blur", "left"), median("gtao", "stereo") + median("blur", "stereo"));
    assert!((chain["left_eye_ms"].as_f64().unwrap() - left).abs() < 1e-9, "{chain}");
    assert!((chain["stereo_ms"].as_f64().unwrap() - stereo).abs() < 1e-9, "{chain}");
    assert!((chain["right_eye_added_share"].as_f64().unwrap() - (stereo - left) / left).abs() < 1e-9, "{chain}");
    assert!(t.contains("AO chain (gtao + blur)"), "{t}");
    // The profile's lens is applied (`--mask on`, the default) and skipped when told.
    let hidden = |r: &serde_json::Value| -> Vec<f64> {
        r["hidden_share_per_eye"].as_array().expect("hidden shares").iter().map(|h| h.as_f64().unwrap()).collect()
    };
    assert!(hidden(&report).len() == 2 && hidden(&report).iter().all(|&h| h > 0.05 && h < 0.5), "{report}");
    assert!(t.contains("lens mask:"), "{t}");
    let (_, unmasked) = budget(&dir, "1000001", &["--mask", "off"]);
    assert!(hidden(&unmasked).iter().all(|&h| h == 0.0), "{unmasked}");

    let (out, report) = budget(&dir, "0.001", &[]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(3), "{t}");
    assert!(t.contains("FAIL") && !t.contains("panicked"), "{t}");
    assert!(report["verdicts"].as_array().unwrap().iter().all(|v| v["pass"] == false), "{report}");
}

#[test]
fn budget_rejects_a_budget_that_is_not_a_positive_number() {
    for bad in ["0", "-5", "nan"] {
        let out = vrao(&["budget", "--budget-ms", bad, "--width", "8", "--height", "8"]);
        assert_eq!(out.status.code(), Some(2), "--budget-ms {bad}: {}", text(&out));
    }
}

/// `vrao bench` on the crease at 48×40: 3 techniques × 2 sample counts × 2 resolutions
/// at one radius, writing to `out` and caching the reference in `cache`.
fn bench_args<'a>(out: &'a str, cache: &'a str) -> Vec<&'a str> {
    vec![
        "bench",
        "--scene",
        "builtin:crease",
        "--width",
        "48",
        "--height",
        "40",
        "--techniques",
        "ssao,hbao,ssdo",
        "--samples",
        "8,16",
        "--radii",
        "0.5",
        "--resolution",
        "both",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--rays",
        "64",
        "--stride",
        "2",
        "--out",
        out,
        "--cache",
        cache,
    ]
}

/// The rows `bench_args` asks for.
const BENCH_ROWS: usize = 3 * 2 * 2;

#[test]
fn bench_writes_csv_json_markdown_and_plot_holding_every_row_and_fit_picks_from_it() {
    let dir = temp_dir("bench");
    let out_dir = dir.join("bench");
    let cache = dir.join("cache");
    let args = bench_args(out_dir.to_str().unwrap(), cache.to_str().unwrap());
    let out = vrao(&args);
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    assert_bench_csv(&out_dir);
    assert_bench_markdown(&out_dir);
    let json = read_json(&out_dir.join("bench.json"));
    let records = json["records"].as_array().unwrap();
    assert_eq!(records.len(), BENCH_ROWS);
    for r in records {
        assert_bench_record(r);
    }
    // The limit is the same for every row of the radius (one frame's depth buffer).
    assert!(records.iter().all(|r| r["limit_rmse"] == records[0]["limit_rmse"]), "{records:?}");
    assert!(records.iter().any(|r| r["pareto"] == true));
    assert!(json["reference"]["ao_noise_rms"].as_f64().unwrap() > 0.0);
    let png = image::open(out_dir.join("bench.png")).expect("bench.png is an image");
    assert_eq!((png.width(), png.height()), (1280, 800));
    // The second run finds the reference in the cache.
    let cached: Vec<_> = std::fs::read_dir(&cache).unwrap().collect();
    assert_eq!(cached.len(), 1, "one radius, one cached reference");
    assert_interleaving_keeps_every_row(&dir, &args, records);
    assert_fit_picks_the_least_error_row(&dir, &out_dir, records);
}

/// bench.csv: a header and one line a row, each with every column, among them the
/// bias, the screen-space limit, FLIP and stereo consistency.
fn assert_bench_csv(out_dir: &std::path::Path) {
    let csv = std::fs::read_to_string(out_dir.join("bench.csv")).unwrap();
    assert_eq!(csv.lines().count(), BENCH_ROWS + 1, "{csv}");
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for line in csv.lines().skip(1) {
        assert_eq!(line.split(',').count(), header.len(), "{line}");
    }
    for want in ["bias", "limit", "flip", "consisten"] {
        assert!(header.iter().any(|c| c.contains(want) && !c.contains("bounce")), "no '{want}' column: {header:?}");
    }
}

/// bench.md: what ran where (scene, adapter, version, the command line), the table of
/// rows (header, rule, one line a row), what the columns mean, then the ratios: half /
/// full for each case, and HBAO and SSDO against SSAO at each setting and resolution.
fn assert_bench_markdown(out_dir: &std::path::Path) {
    let markdown = std::fs::read_to_string(out_dir.join("bench.md")).unwrap();
    assert!(markdown.starts_with("# vrao bench: crease\n"), "{markdown}");
    for line in ["- adapter: ", "- vrao 0.1", "- command: `", "--techniques ssao,hbao,ssdo"] {
        assert!(markdown.contains(line), "no '{line}' in {markdown}");
    }
    let table: Vec<&str> =
        markdown.lines().skip_while(|l| !l.starts_with("| technique")).take_while(|l| l.starts_with('|')).collect();
    assert_eq!(table.len(), BENCH_ROWS + 2, "{markdown}");
    for name in ["RMSE", "bias", "RMSE vs limit", "limit RMSE", "FLIP", "stereo ≠", "ms/eye"] {
        assert!(table[0].split('|').any(|c| c.trim() == name), "no column '{name}': {}", table[0]);
    }
    assert!(table[2].contains(" %"), "shares in percent: {}", table[2]);
    let ratio_rows = |title: &str| {
        let section = markdown.split(title).nth(1).unwrap_or_else(|| panic!("no '{title}' in {markdown}"));
        section.lines().skip(4).take_while(|l| l.starts_with("| ")).count()
    };
    assert_eq!(ratio_rows("Half / full resolution"), 3 * 2, "{markdown}");
    assert_eq!(ratio_rows("against SSAO"), 2 * 2 * 2, "{markdown}");
}

/// A bench.json.
fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// One bench row's errors, times and shares are all there and in range.
fn assert_bench_record(r: &serde_json::Value) {
    let rmse = r["ao_rmse"].as_f64().expect("every row has an error");
    let ssim = r["ao_ssim"].as_f64().unwrap();
    assert!((0.0..0.5).contains(&rmse) && (-1.0..=1.0).contains(&ssim), "{r}");
    assert!(r["occlusion_ms_per_eye"].as_f64().unwrap() > 0.0, "{r}");
    // The G-buffer the occlusion shares the frame with: the plot's budget line needs it.
    assert!(r["other_ms_per_eye"].as_f64().is_some_and(|o| o > 0.0), "{r}");
    // Bias is within ±RMSE (|mean| ≤ RMS; the RMSE has the reference's noise taken
    // out, so allow for that); the crease is darker than 0.8 near its line.
    let bias = r["ao_bias"].as_f64().unwrap();
    assert!(bias.abs() <= rmse + 0.05, "{r}");
    assert!(r["ao_bias_dark"].as_f64().is_some_and(|b| (-1.0..=1.0).contains(&b)), "{r}");
    assert!(r["ao_rmse_falloff"].as_f64().is_some_and(|e| (0.0..0.5).contains(&e)), "{r}");
    // The screen-space limit sees the whole crease (both planes face the eyes): it is
    // close to the reference, and the technique's distance from it is an RMSE.
    let limit = r["limit_rmse"].as_f64().unwrap();
    assert!((0.0..0.06).contains(&limit) && r["limit_bias"].as_f64().unwrap().abs() < 0.03, "{r}");
    assert!(r["ao_rmse_vs_limit"].as_f64().is_some_and(|e| (0.0..0.5).contains(&e)), "{r}");
    assert!(r["flip_mean"].as_f64().is_some_and(|f| f > 0.0 && f < 1.0), "{r}");
    for share in ["stereo_inconsistent", "stereo_inconsistent_inner_border"] {
        assert!(r[share].as_f64().is_some_and(|s| (0.0..=1.0).contains(&s)), "{share}: {r}");
    }
    // No pixel of a 48×40 image is farther than 40 px from every border.
    assert!(r["stereo_inconsistent_interior"].is_null(), "{r}");
}

/// Interleaved in groups of 5 (the last group short), every case keeps its own
/// renderer: the same rows in the same order with the same errors (the frames are
/// deterministic), only the times measured round-robin.
fn assert_interleaving_keeps_every_row(dir: &std::path::Path, args: &[&str], records: &[serde_json::Value]) {
    let interleaved_dir = dir.join("interleaved");
    let mut interleaved_args: Vec<&str> = args.to_vec();
    let out_index = interleaved_args.iter().position(|a| *a == "--out").unwrap() + 1;
    interleaved_args[out_index] = interleaved_dir.to_str().unwrap();
    // Also with whole frames: the composite is timed and half-resolution rows get the
    // frame's inline upsampling cost, from their full-resolution partner.
    interleaved_args.extend(["--interleave", "5", "--frame"]);
    let out = vrao(&interleaved_args);
    assert!(out.status.success(), "{}", text(&out));
    let again = read_json(&interleaved_dir.join("bench.json"));
    let again = again["records"].as_array().unwrap();
    assert_eq!(again.len(), BENCH_ROWS);
    for (a, b) in records.iter().zip(again) {
        for key in [
            "technique",
            "samples",
            "resolution",
            "ao_rmse",
            "ao_ssim",
            "ao_bias",
            "ao_rmse_vs_limit",
            "flip_mean",
            "stereo_inconsistent",
        ] {
            assert_eq!(a[key], b[key], "{key}: {a} vs {b}");
        }
        assert_eq!(a["composite_ms_per_eye"].as_f64(), Some(0.0), "no composite without --frame: {a}");
        assert!(a["frame_upsample_ms_per_eye"].is_null(), "{a}");
        assert!(b["composite_ms_per_eye"].as_f64().unwrap() > 0.0, "{b}");
        let half = b["resolution"] == "half";
        assert_eq!(b["frame_upsample_ms_per_eye"].as_f64().is_some(), half, "only half rows: {b}");
    }
}

/// --fit picks the least-error row (at the bench's radius) that fits a generous
/// budget and measures it.
fn assert_fit_picks_the_least_error_row(
    dir: &std::path::Path,
    out_dir: &std::path::Path,
    records: &[serde_json::Value],
) {
    let best = records
        .iter()
        .min_by(|a, b| a["ao_rmse"].as_f64().unwrap().total_cmp(&b["ao_rmse"].as_f64().unwrap()))
        .unwrap();
    let fit_json = dir.join("fit.json");
    let out = vrao(&[
        "budget",
        "--scene",
        "builtin:crease",
        "--width",
        "48",
        "--height",
        "40",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--budget-ms",
        "1000000",
        "--radius",
        "0.5",
        "--fit",
        out_dir.join("bench.json").to_str().unwrap(),
        "--out",
        fit_json.to_str().unwrap(),
    ]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(0), "{t}");
    let expected = format!("fit: {} N={}", best["technique"].as_str().unwrap(), best["samples"]);
    assert!(t.contains(&expected), "expected '{expected}' in:\n{t}");
}

/// Measures the reference tracer's throughput on Sibenik (run with `--ignored
/// --nocapture`; needs the shared scenes).
#[test]
#[ignore = "a measurement, not a check: run with --ignored --nocapture to print the throughput"]
fn sibenik_throughput() {
    use vrao::measure::reference::{trace, ProgressBar, ReferenceSettings};
    if crate::common::public_scenes().is_none() {
        return;
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/sibenik.toml");
    let started = std::time::Instant::now();
    let scene = vrao_render::Scene::load(path.to_str().unwrap()).unwrap();
    eprintln!("loaded {} triangles in {:.2} s", scene.triangle_count(), started.elapsed().as_secs_f64());
    let size = (270, 300);
    let near = vrao_ao::plug::DEFAULT_NEAR;
    let s = ReferenceSettings { radius: scene.suggested_ao_radius() as f64, rays_per_pixel: 64, stride: 1, near };
    let eyes = vrao_render::HeadsetProfile::with_size("test", size.0, size.1).eyes(&scene.head.pose_at(0.0), near);
    let mut bar = ProgressBar::new("sibenik");
    let image = trace(&scene, &eyes.eyes, size, &s, &mut |p| bar.update(p)).unwrap();
    bar.finish();
    eprintln!("{} ({:?}, r = {})", bar.summary(), image.stats, s.radius);
}

#[test]
fn bench_images_show_each_row_beside_its_limits_and_the_reference() {
    let dir = temp_dir("images");
    let (out_dir, cache) = (dir.join("out"), dir.join("cache"));
    let (w, h) = (48u32, 54u32);
    let args = |extra: &[&str]| {
        let mut args: Vec<String> = [
            "bench",
            "--scene",
            "builtin:crease",
            "--techniques",
            "gtao",
            "--samples",
            "12",
            "--radii",
            "0.5",
            "--resolution",
            "full",
            "--mask",
            "off",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--width",
            "48",
            "--height",
            "54",
            "--stride",
            "2",
            "--rays",
            "64",
            "--images",
        ]
        .map(String::from)
        .to_vec();
        args.extend(["--cache", cache.to_str().unwrap(), "--out", out_dir.to_str().unwrap()].map(String::from));
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let refused = vrao(&args(&["--no-reference"]).iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(refused.status.code(), Some(2), "--images without the reference: {}", text(&refused));
    let replot = vrao(&["bench", "--images", "--replot", "bench.json"]);
    assert_eq!(replot.status.code(), Some(2), "--images with nothing measured: {}", text(&replot));
    let out = vrao(&args(&[]).iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", text(&out));
    let image = image::open(out_dir.join("images/gtao-n12-r0.5-full-layers1.png")).unwrap().to_luma8();
    assert_eq!((image.width(), image.height()), (4 * w, h));
    let panel = |k: u32| -> Vec<f64> {
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| f64::from(image.get_pixel(k * w + x, y)[0]) / 255.0)
            .collect()
    };
    // The row's AO, the one-layer limit, the two-layer limit and the reference. The
    // crease has nothing behind its first layer, so its two limits are one image.
    let (estimate, one, two, reference) = (panel(0), panel(1), panel(2), panel(3));
    assert_eq!(one, two);
    // Each traced pixel stands for its 2×2 block.
    for y in (0..h as usize).step_by(2) {
        for x in (0..w as usize).step_by(2) {
            let v = reference[y * w as usize + x];
            assert_eq!([reference[y * w as usize + x + 1], reference[(y + 1) * w as usize + x]], [v, v], "({x}, {y})");
        }
    }
    // The crease darkens its corner, and the estimate is that frame's AO, not a copy.
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(reference.iter().any(|&v| v < 0.8) && estimate.iter().any(|&v| v < 0.8));
    assert!((mean(&estimate) - mean(&reference)).abs() < 0.05, "{} vs {}", mean(&estimate), mean(&reference));
    assert_ne!(estimate, reference);
}
