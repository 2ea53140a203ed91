//! Tests of the bench's rows, records, Pareto fronts and reports.

use super::errors::near_depth_edge;
use super::*;
use vrao_ao::plug::{BLUR_PASS, UPSAMPLE_PASS};
use vrao_render::passes::gbuffer;

fn row(technique: Technique, ms: f64, ao_rmse: f64) -> BenchRow {
    let span = |label: &str, median_ms| SpanSummary {
        label: label.into(),
        frames: 30,
        median_ms,
        p25_ms: median_ms,
        p75_ms: median_ms,
        min_ms: median_ms,
        max_ms: median_ms,
    };
    BenchRow {
        case: BenchCase {
            technique,
            samples: 12,
            radius: 0.5,
            half_res: false,
            depth_peeling: false,
            layers: 1,
            temporal: false,
            foveation: Foveation::Off,
            mask: false,
        },
        spans: vec![span(technique.name(), ms), span(BLUR_PASS, 2.0), span(gbuffer::NAME, 50.0)],
        views: 2,
        pass: technique.name(),
        occlusion_passes: vec![technique.name(), BLUR_PASS],
        error: Some(ErrorFigures {
            ao_rmse,
            ao_rmse_central: Some(ao_rmse),
            ao_bias: -0.05,
            ao_bias_dark: Some(-0.1),
            ao_rmse_falloff: 0.3,
            ao_ssim: 0.9,
            ambient_rel_rmse: None,
            ambient_rel_rmse_rgb: None,
            flip_mean: Some(0.125),
            ao_rmse_vs_limit: Some(0.06),
            limit_rmse: Some(0.04),
            limit_bias: Some(0.01),
            limit_two_layer_rmse: None,
            limit_two_layer_bias: None,
            ao_rmse_outer_border: Some(0.07),
            halo_share: Some(0.0625),
            ao_rmse_whole: None,
        }),
        bounce: None,
        stereo: Some(StereoConsistency {
            inconsistent: Some(0.25),
            inner_border: Some(0.5),
            interior: Some(0.125),
            compared: 1000,
        }),
        // The march listed 15 of the right eye's 100 tiles; the upsampling ran at full
        // resolution, so it has no count.
        right_eye: vec![vrao_ao::RightEyeTiles {
            pass: technique.name(),
            computed: 15,
            total: 100,
            items: 960,
            frame: 3,
        }],
    }
}

fn file(records: Vec<BenchRecord>) -> BenchFile {
    BenchFile {
        scene: "crease".into(),
        adapter: "test".into(),
        backend: "Vulkan".into(),
        driver: String::new(),
        width: 64,
        height: 48,
        timing: "serial".into(),
        warmup: 1,
        frames: 30,
        reference: None,
        limit: None,
        pixels_per_degree: None,
        version: String::new(),
        command: String::new(),
        records,
    }
}

#[test]
fn a_depth_edge_is_a_step_or_the_sky_not_a_slope() {
    let cell = |depth: f32| ReferencePixel { hit: depth > 0.0, depth, ..ReferencePixel::SKY };
    // A floor receding linearly along the row (1, 2, …, 5 m): no edge anywhere inside.
    let slope: Vec<_> = (1..=5).map(|d| cell(d as f32)).collect();
    assert!((1..4).all(|i| !near_depth_edge(&slope, (5, 1), i, 0)));
    // A near object (1 m) in front of a wall (4 m): both sides of the step are edges,
    // cells two away are not.
    let step: Vec<_> = [1.0, 1.0, 1.0, 4.0, 4.0, 4.0].into_iter().map(cell).collect();
    let edges: Vec<_> = (0..6).map(|i| near_depth_edge(&step, (6, 1), i, 0)).collect();
    assert_eq!(edges, [false, false, true, true, false, false]);
    // Beside the sky.
    let sky: Vec<_> = [2.0, 2.0, 0.0].into_iter().map(cell).collect();
    assert!(near_depth_edge(&sky, (3, 1), 1, 0));
    assert!(!near_depth_edge(&sky, (3, 1), 2, 0), "the sky itself is no edge pixel");
}

#[test]
fn per_eye_cost_halves_both_eye_dispatches_and_ignores_other_passes() {
    assert_eq!(row(Technique::Ssao, 10.0, 0.1).occlusion_ms_per_eye(), 6.0);
}

#[test]
fn the_pareto_front_keeps_rows_no_other_row_beats_in_both_time_and_error() {
    // ssao: 6 ms, 0.10; hbao: 7 ms, 0.05; ssdo: 8 ms, 0.07 (slower and worse than hbao).
    let rows = [row(Technique::Ssao, 10.0, 0.10), row(Technique::Hbao, 12.0, 0.05), row(Technique::Ssdo, 14.0, 0.07)];
    let pareto: Vec<bool> = records(&rows).iter().map(|r| r.pareto).collect();
    assert_eq!(pareto, [true, true, false]);
}

/// The upsampling's share is its pass's, or in a whole frame the composite's (which
/// upsamples inline); the march's column never takes either.
#[test]
fn the_upsampling_share_is_the_upsample_pass_or_the_frames_composite() {
    let counted = |pass| vrao_ao::RightEyeTiles { pass, computed: 20, total: 100, items: 1200, frame: 3 };
    for upsampling in [UPSAMPLE_PASS, vrao_render::passes::composite::NAME] {
        let mut r = row(Technique::Gtao, 10.0, 0.1);
        r.right_eye.push(counted(upsampling));
        let record = &records(&[r])[0];
        assert_eq!(
            (record.right_eye_tiles_share, record.right_eye_upsample_share),
            (Some(0.15), Some(0.2)),
            "{upsampling}"
        );
    }
    let mut only_composite = row(Technique::Gtao, 10.0, 0.1);
    only_composite.right_eye = vec![counted(vrao_render::passes::composite::NAME)];
    let record = &records(&[only_composite])[0];
    assert_eq!((record.right_eye_tiles_share, record.right_eye_upsample_share), (None, Some(0.2)));
}

#[test]
fn csv_markdown_and_json_hold_every_row() {
    let rows = [row(Technique::Ssao, 10.0, 0.1), row(Technique::Hbao, 12.0, 0.2)];
    let recs = records(&rows);
    let csv = to_csv(&recs);
    assert_eq!(csv.lines().count(), 3);
    // technique, N, r, resolution, foveation, layers, mask, ms/eye, RMSE, central RMSE, whole-rectangle RMSE,
    // bias, bias (ref < 0.8), vs limit,
    // limit RMSE, limit bias, two-layer limit RMSE and bias (none here), outer border RMSE, halo, FLIP, stereo shares,
    // the right eye's march and upsampling shares (none here), falloff RMSE, SSIM, ambient, …
    assert!(
        csv.lines().nth(2).unwrap().starts_with(
            "hbao,12,0.5,full,off,1,off,7.000,0.2000,0.2000,,-0.0500,-0.1000,0.0600,0.0400,0.0100,,,0.0700,0.0625,0.1250,0.2500,0.5000,0.1250,0.1500,,0.3000,0.9000,,6.000,1.000,0.000,1.000,"
        ),
        "{csv}"
    );
    let header = csv.lines().next().unwrap();
    for want in ["bias", "limit", "flip", "consisten"] {
        assert!(header.split(',').any(|c| c.contains(want) && !c.contains("bounce")), "{want}: {header}");
    }
    // Markdown: rounded for reading; optional columns (peeling, bounce, …) left out.
    let markdown = to_markdown(&recs);
    assert_eq!(markdown.lines().count(), 4);
    let hbao = markdown.lines().nth(3).unwrap();
    assert!(
        hbao.starts_with("| hbao | 12 | 0.5 | full | 7.0 | 0.200 | 0.200 | -0.050 | -0.100 | 0.060 | 0.040 | 0.010 | 0.070 | 6.2 % | 0.125 | 25.0 % | 50.0 % | 12.5 % | 15.0 % |"),
        "{hbao}"
    );
    assert!(!markdown.contains("peel") && !markdown.contains("bounce"), "{markdown}");
    assert!(!markdown.contains("right-eye upsampling"), "no row has an upsampling count: {markdown}");
    let json = to_json(&file(recs.clone()));
    let back: BenchFile = serde_json::from_str(&json).unwrap();
    assert_eq!(back.records, recs);
    // The resolution keeps its name in files written before it was an enum.
    assert!(json.contains("\"resolution\": \"full\""), "{json}");
}

#[test]
fn a_pass_that_ran_without_a_span_is_an_error_not_zero_ms() {
    let spans = row(Technique::Ssao, 10.0, 0.1).spans;
    assert!(check_timed(&[Technique::Ssao.name(), BLUR_PASS, gbuffer::NAME], &spans).is_ok());
    let error = check_timed(&[Technique::Ssao.name(), UPSAMPLE_PASS], &spans).unwrap_err();
    assert!(error.to_string().contains("'upsample'"), "{error}");
    // A pass that did not run reads 0 ms.
    assert_eq!(row(Technique::Ssao, 10.0, 0.1).median_ms(UPSAMPLE_PASS), 0.0);
}

#[test]
fn the_plot_labels_every_point_and_bounds_occlusion_by_its_share_of_the_budget() {
    let mut f = file(records(&[row(Technique::Ssao, 10.0, 0.1), row(Technique::Hbao, 14.0, 0.08)]));
    let p = plot(&f, 0.5, 55.5);
    let labels: Vec<&str> = p.series.iter().flat_map(|s| s.points.iter().map(|p| p.label.as_str())).collect();
    assert_eq!(labels, ["ssao N=12 full", "hbao N=12 full"]);
    // Occlusion ms on x, so the line is what the per-eye budget leaves after the other
    // passes of the same frames (the G-buffer, 50 ms for both eyes).
    assert_eq!(f.records[0].other_ms_per_eye, Some(25.0));
    let (x, label) = p.vertical_line.clone().unwrap();
    assert_eq!(x, 30.5);
    assert!(label.starts_with("occlusion budget 30.50 ms/eye"), "{label}");
    // A file from before the other passes were recorded: the whole budget, said so.
    f.records.iter_mut().for_each(|r| r.other_ms_per_eye = None);
    let (x, label) = plot(&f, 0.5, 55.5).vertical_line.unwrap();
    assert!(x == 55.5 && label.contains("other passes not recorded"), "{label}");
    assert_eq!(plot_file_name(0.25612497), "bench-r0.26.png");
    assert!(p.title.contains("r = 0.5 m"), "{}", p.title);
}
