//! A sweep's rows as records (Pareto fronts marked), and those as CSV, Markdown, JSON
//! and plots.

// The bench's types and imports (this file is a part of bench.rs split out for size).
use super::*;
use vrao_ao::plug::{BLUR_PASS, UPSAMPLE_PASS};
use vrao_render::passes::{composite, peel};

/// The records of measured rows, with the Pareto front marked.
pub fn records(rows: &[BenchRow]) -> Vec<BenchRecord> {
    let mut out: Vec<BenchRecord> = rows
        .iter()
        .map(|row| {
            let c = &row.case;
            let name = row.pass;
            let spread = row.spans.iter().find(|s| s.label == name).map_or(0.0, |s| s.p75_ms / s.p25_ms.max(1e-9));
            let per_eye = |p: &str| row.median_ms(p) / row.views as f64;
            BenchRecord {
                technique: if name == RSM_PASS { RSM_PASS.to_string() } else { c.technique.name().to_string() },
                samples: c.samples,
                radius_m: c.radius,
                resolution: Resolution::from_half_res(c.half_res),
                foveation: c.foveation,
                mask: c.mask,
                ao_rmse_whole: row.error.as_ref().and_then(|e| e.ao_rmse_whole),
                technique_ms_per_eye: per_eye(name),
                blur_ms_per_eye: per_eye(BLUR_PASS),
                upsample_ms_per_eye: per_eye(UPSAMPLE_PASS),
                occlusion_ms_per_eye: row.occlusion_ms_per_eye(),
                p75_over_p25: spread,
                ao_rmse: row.error.as_ref().map(|e| e.ao_rmse),
                ao_rmse_central: row.error.as_ref().and_then(|e| e.ao_rmse_central),
                ao_bias: row.error.as_ref().map(|e| e.ao_bias),
                ao_bias_dark: row.error.as_ref().and_then(|e| e.ao_bias_dark),
                ao_rmse_falloff: row.error.as_ref().map(|e| e.ao_rmse_falloff),
                ao_rmse_vs_limit: row.error.as_ref().and_then(|e| e.ao_rmse_vs_limit),
                limit_rmse: row.error.as_ref().and_then(|e| e.limit_rmse),
                limit_bias: row.error.as_ref().and_then(|e| e.limit_bias),
                limit_two_layer_rmse: row.error.as_ref().and_then(|e| e.limit_two_layer_rmse),
                limit_two_layer_bias: row.error.as_ref().and_then(|e| e.limit_two_layer_bias),
                ao_rmse_outer_border: row.error.as_ref().and_then(|e| e.ao_rmse_outer_border),
                halo_share: row.error.as_ref().and_then(|e| e.halo_share),
                flip_mean: row.error.as_ref().and_then(|e| e.flip_mean),
                stereo_inconsistent: row.stereo.and_then(|c| c.inconsistent),
                stereo_inconsistent_inner_border: row.stereo.and_then(|c| c.inner_border),
                stereo_inconsistent_interior: row.stereo.and_then(|c| c.interior),
                right_eye_tiles_share: right_eye_share(row, |pass| !upsamples(pass)),
                right_eye_upsample_share: right_eye_share(row, upsamples),
                ao_ssim: row.error.as_ref().map(|e| e.ao_ssim),
                ambient_rel_rmse: row.error.as_ref().and_then(|e| e.ambient_rel_rmse),
                pareto: false,
                depth_peeling: c.depth_peeling,
                layers: c.layers,
                peel_ms_per_eye: per_eye(peel::NAME),
                bounce_rel_rmse: row.bounce.map(|b| b.rel_rmse),
                bounce_rel_bias: row.bounce.map(|b| b.rel_bias),
                ambient_rel_rmse_r: row.error.as_ref().and_then(|e| e.ambient_rel_rmse_rgb).map(|c| c[0]),
                ambient_rel_rmse_g: row.error.as_ref().and_then(|e| e.ambient_rel_rmse_rgb).map(|c| c[1]),
                ambient_rel_rmse_b: row.error.as_ref().and_then(|e| e.ambient_rel_rmse_rgb).map(|c| c[2]),
                bounce_limit_rel_rmse: row.bounce.and_then(|b| b.limit_rel_rmse),
                bounce_rel_rmse_r: row.bounce.map(|b| b.rel_rmse_rgb[0]),
                bounce_rel_rmse_g: row.bounce.map(|b| b.rel_rmse_rgb[1]),
                bounce_rel_rmse_b: row.bounce.map(|b| b.rel_rmse_rgb[2]),
                temporal: c.temporal,
                composite_ms_per_eye: per_eye(composite::NAME),
                frame_upsample_ms_per_eye: None,
                other_ms_per_eye: Some(row.other_ms_per_eye()),
            }
        })
        .collect();
    for i in 0..out.len() {
        let half = &out[i];
        if !half.resolution.is_half() || half.composite_ms_per_eye <= 0.0 {
            continue;
        }
        let full = full_resolution_partner(&out, half).filter(|f| f.composite_ms_per_eye > 0.0);
        out[i].frame_upsample_ms_per_eye = full.map(|f| half.composite_ms_per_eye - f.composite_ms_per_eye);
    }
    mark_pareto(&mut out);
    out
}

/// Whether `pass` upsamples the half-resolution AO: its own pass, or in a whole frame
/// (`--frame`) the composite, which upsamples inline and lists the same quads.
fn upsamples(pass: &str) -> bool {
    pass == UPSAMPLE_PASS || pass == composite::NAME
}

/// The right eye's computed share of the first pass `which` takes among the row's
/// right-eye counts (the march's, or the upsampling's).
fn right_eye_share(row: &BenchRow, which: impl Fn(&str) -> bool) -> Option<f64> {
    row.right_eye.iter().find(|t| which(t.pass)).map(|t| t.share())
}

/// The full-resolution record of the same technique and setting as `half`.
fn full_resolution_partner<'a>(records: &'a [BenchRecord], half: &BenchRecord) -> Option<&'a BenchRecord> {
    records.iter().find(|f| {
        f.resolution == Resolution::Full
            && (f.foveation, f.mask) == (half.foveation, half.mask)
            && sweep_case(f) == sweep_case(half)
    })
}

/// A record's sweep axes but its resolution, foveation and mask, which the partner
/// lookups (the same case at full resolution, the same case unfoveated and unmasked) vary.
fn sweep_case(r: &BenchRecord) -> (&str, u32, f32, bool, u32, bool) {
    (r.technique.as_str(), r.samples, r.radius_m, r.depth_peeling, r.layers, r.temporal)
}

/// Marks each record on the Pareto front of AO RMSE against occlusion ms per eye. Each
/// radius is its own target quantity (AO within r), so errors compare only within one
/// radius: one front per radius.
pub fn mark_pareto(out: &mut [BenchRecord]) {
    out.iter_mut().for_each(|r| r.pareto = false);
    let mut radii: Vec<f32> = out.iter().map(|r| r.radius_m).collect();
    radii.sort_by(f32::total_cmp);
    radii.dedup();
    for radius in radii {
        let members: Vec<usize> = (0..out.len()).filter(|&i| out[i].radius_m == radius).collect();
        let points: Vec<(f64, f64)> =
            members.iter().map(|&i| (out[i].occlusion_ms_per_eye, out[i].ao_rmse.unwrap_or(f64::NAN))).collect();
        for k in metrics::pareto_front(&points) {
            out[members[k]].pareto = true;
        }
    }
}

/// One column of the CSV and of the Markdown table: its CSV name, its Markdown
/// header, the CSV value (full precision) and the Markdown value (rounded to what it means).
struct Column {
    name: &'static str,
    header: &'static str,
    csv: fn(&BenchRecord) -> String,
    markdown: fn(&BenchRecord) -> String,
    /// Shown in the Markdown table only when some row has something there.
    optional: bool,
}

fn fixed(v: Option<f64>, decimals: usize) -> String {
    v.map_or(String::new(), |v| format!("{v:.decimals$}"))
}

fn percent(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{:.1} %", v * 100.0))
}

fn yes(b: bool) -> String {
    if b { "yes" } else { "" }.to_string()
}

/// Every column, the ones a reader compares first first.
/// A column of an error figure (`Option<f64>` field): 4 decimals in CSV, 3 in Markdown.
macro_rules! figure_column {
    ($field:ident, $header:literal, $optional:literal) => {
        Column {
            name: stringify!($field),
            header: $header,
            csv: |r| fixed(r.$field, 4),
            markdown: |r| fixed(r.$field, 3),
            optional: $optional,
        }
    };
}

/// A column of a share (`Option<f64>` in 0..1): 4 decimals in CSV, a percentage in Markdown.
macro_rules! share_column {
    ($field:ident, $header:literal, $optional:literal) => {
        Column {
            name: stringify!($field),
            header: $header,
            csv: |r| fixed(r.$field, 4),
            markdown: |r| percent(r.$field),
            optional: $optional,
        }
    };
}

const COLUMNS: &[Column] = &[
    Column {
        name: "technique",
        header: "technique",
        csv: |r| r.technique.clone(),
        markdown: |r| r.technique.clone(),
        optional: false,
    },
    Column {
        name: "samples",
        header: "N",
        csv: |r| r.samples.to_string(),
        markdown: |r| r.samples.to_string(),
        optional: false,
    },
    Column {
        name: "radius_m",
        header: "r (m)",
        csv: |r| format!("{}", r.radius_m),
        markdown: |r| significant(r.radius_m as f64, 2),
        optional: false,
    },
    Column {
        name: "resolution",
        header: "res",
        csv: |r| r.resolution.name().to_string(),
        markdown: |r| r.resolution.name().to_string(),
        optional: false,
    },
    Column {
        name: "foveation",
        header: "foveation",
        csv: |r| r.foveation.name().to_string(),
        markdown: |r| if r.foveation == Foveation::Off { String::new() } else { r.foveation.name().to_string() },
        optional: true,
    },
    Column {
        name: "layers",
        header: "layers",
        csv: |r| r.layers.to_string(),
        // Shown where some row read two (one layer is every row before them).
        markdown: |r| if r.layers == 2 { "2".to_string() } else { String::new() },
        optional: true,
    },
    Column {
        name: "mask",
        header: "mask",
        csv: |r| if r.mask { "on" } else { "off" }.to_string(),
        markdown: |r| if r.mask { "on" } else { "" }.to_string(),
        optional: true,
    },
    Column {
        name: "occlusion_ms_per_eye",
        header: "ms/eye",
        csv: |r| format!("{:.3}", r.occlusion_ms_per_eye),
        markdown: |r| format!("{:.1}", r.occlusion_ms_per_eye),
        optional: false,
    },
    figure_column!(ao_rmse, "RMSE", false),
    figure_column!(ao_rmse_central, "RMSE central 20°", false),
    figure_column!(ao_rmse_whole, "RMSE whole rectangle", true),
    figure_column!(ao_bias, "bias", false),
    figure_column!(ao_bias_dark, "bias (ref < 0.8)", false),
    figure_column!(ao_rmse_vs_limit, "RMSE vs limit", false),
    figure_column!(limit_rmse, "limit RMSE", false),
    figure_column!(limit_bias, "limit bias", false),
    figure_column!(limit_two_layer_rmse, "2-layer limit RMSE", true),
    figure_column!(limit_two_layer_bias, "2-layer limit bias", true),
    figure_column!(ao_rmse_outer_border, "RMSE outer border", false),
    share_column!(halo_share, "halo", false),
    figure_column!(flip_mean, "FLIP", false),
    share_column!(stereo_inconsistent, "stereo ≠", false),
    share_column!(stereo_inconsistent_inner_border, "≠ inner border", false),
    share_column!(stereo_inconsistent_interior, "≠ interior", false),
    share_column!(right_eye_tiles_share, "right-eye tiles", true),
    share_column!(right_eye_upsample_share, "right-eye upsampling", true),
    figure_column!(ao_rmse_falloff, "RMSE falloff", false),
    figure_column!(ao_ssim, "SSIM", false),
    figure_column!(ambient_rel_rmse, "ambient rel. RMSE", true),
    Column {
        name: "technique_ms_per_eye",
        header: "technique ms",
        csv: |r| format!("{:.3}", r.technique_ms_per_eye),
        markdown: |r| format!("{:.1}", r.technique_ms_per_eye),
        optional: false,
    },
    Column {
        name: "blur_ms_per_eye",
        header: "blur ms",
        csv: |r| format!("{:.3}", r.blur_ms_per_eye),
        markdown: |r| format!("{:.1}", r.blur_ms_per_eye),
        optional: false,
    },
    Column {
        name: "upsample_ms_per_eye",
        header: "upsample ms",
        csv: |r| format!("{:.3}", r.upsample_ms_per_eye),
        markdown: |r| if r.resolution.is_half() { format!("{:.1}", r.upsample_ms_per_eye) } else { String::new() },
        optional: true,
    },
    Column {
        name: "p75_over_p25",
        header: "p75/p25",
        csv: |r| format!("{:.3}", r.p75_over_p25),
        markdown: |r| format!("{:.2}", r.p75_over_p25),
        optional: false,
    },
    Column { name: "pareto", header: "Pareto", csv: |r| yes(r.pareto), markdown: |r| yes(r.pareto), optional: true },
    Column {
        name: "depth_peeling",
        header: "peeled",
        csv: |r| yes(r.depth_peeling),
        markdown: |r| yes(r.depth_peeling),
        optional: true,
    },
    Column {
        name: "peel_ms_per_eye",
        header: "peel ms",
        csv: |r| format!("{:.3}", r.peel_ms_per_eye),
        markdown: |r| {
            if r.depth_peeling || r.layers == 2 {
                format!("{:.1}", r.peel_ms_per_eye)
            } else {
                String::new()
            }
        },
        optional: true,
    },
    figure_column!(bounce_rel_rmse, "bounce rel. RMSE", true),
    figure_column!(bounce_rel_bias, "bounce rel. bias", true),
    figure_column!(bounce_limit_rel_rmse, "bounce limit rel. RMSE", true),
    figure_column!(ambient_rel_rmse_r, "ambient rel. RMSE r", true),
    figure_column!(ambient_rel_rmse_g, "ambient rel. RMSE g", true),
    figure_column!(ambient_rel_rmse_b, "ambient rel. RMSE b", true),
    figure_column!(bounce_rel_rmse_r, "bounce rel. RMSE r", true),
    figure_column!(bounce_rel_rmse_g, "bounce rel. RMSE g", true),
    figure_column!(bounce_rel_rmse_b, "bounce rel. RMSE b", true),
    Column {
        name: "temporal",
        header: "temporal",
        csv: |r| yes(r.temporal),
        markdown: |r| yes(r.temporal),
        optional: true,
    },
    Column {
        name: "composite_ms_per_eye",
        header: "composite ms",
        csv: |r| format!("{:.3}", r.composite_ms_per_eye),
        markdown: |r| {
            if r.composite_ms_per_eye > 0.0 {
                format!("{:.1}", r.composite_ms_per_eye)
            } else {
                String::new()
            }
        },
        optional: true,
    },
    Column {
        name: "frame_upsample_ms_per_eye",
        header: "frame upsample ms",
        csv: |r| fixed(r.frame_upsample_ms_per_eye, 3),
        markdown: |r| fixed(r.frame_upsample_ms_per_eye, 1),
        optional: true,
    },
];

/// The CSV: every column of every record, full precision (shares as fractions 0..1).
pub fn to_csv(records: &[BenchRecord]) -> String {
    let mut s = COLUMNS.iter().map(|c| c.name).collect::<Vec<_>>().join(",") + "\n";
    for r in records {
        s += &(COLUMNS.iter().map(|c| (c.csv)(r)).collect::<Vec<_>>().join(",") + "\n");
    }
    s
}

/// The table of records as Markdown, rounded for reading (RMSE and bias to 3 decimals, ms
/// to 1, shares in percent to 1); optional columns only where some row has a value.
pub fn to_markdown(records: &[BenchRecord]) -> String {
    let shown: Vec<&Column> =
        COLUMNS.iter().filter(|c| !c.optional || records.iter().any(|r| !(c.markdown)(r).is_empty())).collect();
    let mut s = format!(
        "| {} |\n|{}\n",
        shown.iter().map(|c| c.header).collect::<Vec<_>>().join(" | "),
        "---|".repeat(shown.len())
    );
    for r in records {
        let _ = writeln!(s, "| {} |", shown.iter().map(|c| (c.markdown)(r)).collect::<Vec<_>>().join(" | "));
    }
    s
}

/// What the columns mean, for the foot of bench.md.
pub const COLUMN_NOTES: &str = "\
- **RMSE**, **bias**: the AO against the ray-traced reference's hard cut-off AO (cosine-weighted \
visibility within r), the target every technique is scored against; bias is mean(estimate − \
reference), > 0 too light; **bias (ref < 0.8)** over the pixels the reference finds occluded. \
**RMSE falloff**: against the reference with HBAO's linear falloff 1 − d/r instead, for comparison. \
Every figure counts only the pixels the profile's lens shows (its visibility mask); **RMSE whole \
rectangle**, on rows with the mask off, counts every pixel, as figures before the mask did. \
**mask** on: the passes skipped the hidden pixels.
- **limit RMSE**, **limit bias**: the *screen-space limit* (a brute-force march over this frame's \
own depth buffer: many rays of length r, a thickness, off-image open) against the reference: the \
error of seeing one depth layer per eye, which no screen-space technique can remove. The same \
for every row of a radius.
- **RMSE vs limit**: the technique against that limit: its *estimator* error (too few samples, \
falloffs, one sample point per direction, noise). A technique with RMSE ≈ limit RMSE and a small \
RMSE vs limit is as good as screen space gets; a large RMSE vs limit is the estimator's own fault.
- **RMSE outer border**: RMSE over the pixels within 40 px of an eye's outer, top or bottom \
border, where samples that leave the image count as open (the other eye sees no further there): \
compared with RMSE, what rendering a guard band around the image could win.
- **halo**: share of the pixels beside a depth edge (within one reference cell) that are too \
dark by more than 0.1: occlusion spilling from a near object onto the far surface behind it.
- **FLIP**: mean ꟻLIP of the AO image against the reference AO (both as grey images, sky 1) at \
the headset's pixels per degree over the reference's stride: how visible the difference is; \
noise and blotches count more than a smooth offset of the same RMSE.
- **stereo ≠**: share of the surface points both eyes see whose final AO differs between the \
eyes by more than 0.02 (both directions pooled), overall, within 40 px of each eye's inner \
(nasal) border, and farther than 40 px from every border.
- **ms/eye**: occlusion cost per eye (technique + blur + upsampling), median over the measured frames.
";

/// The header of bench.md: scene, adapter, version, command line and how it was measured.
pub fn markdown_header(file: &BenchFile) -> String {
    let mut s = format!("# vrao bench: {}\n\n", file.scene);
    let driver = if file.driver.is_empty() { String::new() } else { format!(", driver {}", file.driver) };
    let _ = writeln!(s, "- adapter: {} ({}{driver})", file.adapter, file.backend);
    if !file.version.is_empty() {
        let _ = writeln!(s, "- vrao {}", file.version);
    }
    if !file.command.is_empty() {
        let _ = writeln!(s, "- command: `{}`", file.command);
    }
    let _ = writeln!(
        s,
        "- {}×{} per eye, {} timing, {} warm-up + {} measured frames per case",
        file.width, file.height, file.timing, file.warmup, file.frames
    );
    if let Some(r) = &file.reference {
        let _ = writeln!(
            s,
            "- reference: {} rays per pixel at every {} pixels (its AO noise, RMS standard error: {:.4})",
            r.rays_per_pixel, r.stride, r.ao_noise_rms
        );
        if let Some(l) = &file.limit {
            let _ = writeln!(
                s,
                "- screen-space limit: {} rays × {} steps per pixel on the same pixels, thickness {} r",
                l.rays_per_pixel, l.steps, l.thickness_of_radius
            );
        }
        if let Some(ppd) = file.pixels_per_degree {
            let _ = writeln!(
                s,
                "- FLIP at {ppd:.1} pixels per degree, {:.1} on the reference's grid",
                ppd / r.stride.max(1) as f64
            );
        }
    }
    s + "\n"
}

/// bench.md: the header, the table, what the columns mean, and the ratios.
pub fn markdown_report(file: &BenchFile) -> String {
    let mut s = markdown_header(file) + &to_markdown(&file.records);
    if file.reference.is_some() {
        s += "\n";
        s += COLUMN_NOTES;
    }
    s + &ratios_markdown(&file.records)
}

/// The ratios a sweep is judged by, as Markdown (empty when no row has a partner):
/// - half / full resolution of each case: occlusion ms per eye (technique + blur + the
///   stand-alone upsample pass) and, with `--frame`, the same with the frame's inline
///   upsampling instead of the pass;
/// - each technique's pass against SSAO's at the same setting and resolution;
/// - each technique's pass against fetch-only's (the same depth taps, no arithmetic):
///   how far it is from the memory limit;
/// - each foveated row against the same case without foveation: the chain's cost, the
///   error where the eye looks and over the whole image.
pub fn ratios_markdown(records: &[BenchRecord]) -> String {
    let mut s = String::new();
    s += &foveation_markdown(records);
    let plain = |r: &&BenchRecord| !r.depth_peeling && !r.temporal;
    let mut half_full = String::new();
    for half in records.iter().filter(|r| r.resolution.is_half()) {
        let Some(full) = full_resolution_partner(records, half) else {
            continue;
        };
        let in_frame = half
            .frame_upsample_ms_per_eye
            .map_or(String::new(), |_| format!("{:.3}", chain_ms_per_eye(half) / full.occlusion_ms_per_eye));
        let _ = writeln!(
            half_full,
            "| {} | {} | {} | {:.3} | {in_frame} |",
            half.technique,
            half.samples,
            significant(half.radius_m as f64, 2),
            half.occlusion_ms_per_eye / full.occlusion_ms_per_eye
        );
    }
    if !half_full.is_empty() {
        s += "\nHalf / full resolution, occlusion ms per eye (technique + blur + upsampling):\n\n";
        s += "| technique | samples | radius_m | with the upsample pass | with the frame's inline upsampling |\n|---|---|---|---|---|\n";
        s += &half_full;
    }
    for (against, title) in [
        (Technique::Ssao.name(), "Technique pass against SSAO's at the same setting and resolution"),
        (Technique::FetchOnly.name(), "Technique pass against fetch-only's (same depth taps, no arithmetic)"),
    ] {
        let mut table = String::new();
        for r in records.iter().filter(plain).filter(|r| r.technique != against && r.technique != RSM_PASS) {
            let partner = records.iter().filter(plain).find(|b| {
                b.technique == against
                    && (b.samples, b.radius_m, b.resolution, b.foveation)
                        == (r.samples, r.radius_m, r.resolution, r.foveation)
            });
            if let Some(b) = partner {
                let ratio = r.technique_ms_per_eye / b.technique_ms_per_eye;
                let occlusion = r.occlusion_ms_per_eye / b.occlusion_ms_per_eye;
                let _ = writeln!(
                    table,
                    "| {} | {} | {} | {} | {ratio:.3} | {occlusion:.3} |",
                    r.technique,
                    r.samples,
                    significant(r.radius_m as f64, 2),
                    r.resolution
                );
            }
        }
        if !table.is_empty() {
            let _ = write!(s, "\n{title}:\n\n| technique | samples | radius_m | resolution | technique pass | occlusion (with blur, upsampling) |\n|---|---|---|---|---|---|\n{table}");
        }
    }
    s
}

/// The bench file as pretty-printed JSON (`bench.json`).
pub fn to_json(file: &BenchFile) -> String {
    serde_json::to_string_pretty(file).expect("bench records serialise")
}

/// Reads a bench JSON file (for `vrao budget --fit`).
pub fn read_json(path: &std::path::Path) -> Result<BenchFile> {
    let text = vrao_render::files::read_regular_file_to_string(path, vrao_render::files::MAX_TEXT_BYTES)?;
    BenchFile::from_json(&text, path)
}

/// The plot's file name for one radius, rounded so that it carries no float noise:
/// `bench-r0.26.png`.
pub fn plot_file_name(radius_m: f32) -> String {
    format!("bench-r{}.png", significant(radius_m as f64, 2))
}

/// The plot of AO error against occlusion ms per eye for the rows of one radius, every
/// point labelled with its setting, with that radius's Pareto front and a budget line.
///
/// The x axis is the occlusion's time alone (what the Pareto front and `vrao budget
/// --fit` rank by), so the budget line is the occlusion's share of the frame: the
/// per-eye budget minus the other passes the bench measured in the same frames (the
/// median over the radius's rows). A file without those times gets the whole per-eye
/// budget, labelled as such.
pub fn plot(file: &BenchFile, radius_m: f32, budget_ms_per_eye: f64) -> ScatterPlot {
    // One hue per technique variant, dark at full and light at half resolution.
    const HUES: [([u8; 3], [u8; 3]); 6] = [
        ([31, 90, 180], [120, 170, 230]),
        ([220, 110, 0], [250, 180, 100]),
        ([30, 130, 40], [130, 200, 120]),
        ([190, 30, 40], [240, 130, 130]),
        ([110, 60, 170], [190, 160, 220]),
        ([120, 75, 40], [200, 160, 120]),
    ];
    let rows: Vec<&BenchRecord> =
        file.records.iter().filter(|r| r.radius_m == radius_m && r.ao_rmse.is_some()).collect();
    let (mut series, mut variants): (Vec<Series>, Vec<String>) = (Vec::new(), Vec::new());
    for r in &rows {
        let technique = format!(
            "{}{}{}",
            r.technique,
            if r.depth_peeling { " peeled" } else { "" },
            if r.temporal { " temporal" } else { "" }
        );
        let label = format!("{technique} {}", r.resolution);
        if !variants.contains(&technique) {
            variants.push(technique.clone());
        }
        let point = Point {
            x: r.occlusion_ms_per_eye,
            y: r.ao_rmse.unwrap_or(f64::NAN),
            label: format!("{technique} N={} {}", r.samples, r.resolution),
        };
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push(point),
            None => {
                let hue = HUES[variants.iter().position(|v| v == &technique).unwrap_or(0) % HUES.len()];
                let color = if r.resolution.is_half() { hue.1 } else { hue.0 };
                series.push(Series { label, color, points: vec![point] });
            }
        }
    }
    let pareto: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.pareto).map(|r| (r.occlusion_ms_per_eye, r.ao_rmse.unwrap_or(f64::NAN))).collect();
    let other: Vec<f64> = rows.iter().filter_map(|r| r.other_ms_per_eye).collect();
    let line = match crate::stats::median(&other) {
        Some(other) => {
            let share = (budget_ms_per_eye - other).max(0.0);
            let label = format!(
                "occlusion budget {share:.2} ms/eye\n({budget_ms_per_eye:.2} per eye \u{2212} {other:.2} other passes)"
            );
            (share, label)
        }
        None => (budget_ms_per_eye, format!("whole budget {budget_ms_per_eye:.2} ms/eye\n(other passes not recorded)")),
    };
    ScatterPlot {
        title: format!(
            "{}: AO error against time, r = {} m, {}x{} per eye, {}",
            file.scene,
            significant(radius_m as f64, 2),
            file.width,
            file.height,
            file.adapter
        ),
        x_label: "occlusion ms per eye (technique + blur + upsample)".into(),
        y_label: "AO RMSE against the reference".into(),
        series,
        pareto,
        vertical_line: Some(line),
    }
}

/// The AO chain a frame pays per eye: the occlusion passes, with the frame's inline
/// upsampling in place of the stand-alone upsample pass where `--frame` measured it.
fn chain_ms_per_eye(r: &BenchRecord) -> f64 {
    match r.frame_upsample_ms_per_eye {
        Some(inline) => r.occlusion_ms_per_eye - r.upsample_ms_per_eye + inline,
        None => r.occlusion_ms_per_eye,
    }
}

/// Each foveated or masked row against the same case with neither (empty without such
/// pairs): the chain's cost ratio, the RMSE within the central 20° and over the pixels
/// the lens shows (the differences), and FLIP (the ratio).
fn foveation_markdown(records: &[BenchRecord]) -> String {
    let mut table = String::new();
    for r in records.iter().filter(|r| r.foveation != Foveation::Off || r.mask) {
        let off = records.iter().find(|b| {
            b.foveation == Foveation::Off && !b.mask && b.resolution == r.resolution && sweep_case(b) == sweep_case(r)
        });
        let Some(off) = off else { continue };
        let difference = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => format!("{:+.4}", a - b),
            _ => String::new(),
        };
        let flip = match (r.flip_mean, off.flip_mean) {
            (Some(a), Some(b)) if b > 0.0 => format!("{:.3}", a / b),
            _ => String::new(),
        };
        let _ = writeln!(
            table,
            "| {} | {} | {} | {} | {} | {} | {:.3} | {} | {} | {flip} |",
            r.technique,
            r.samples,
            significant(r.radius_m as f64, 2),
            r.resolution,
            r.foveation.name(),
            if r.mask { "on" } else { "off" },
            chain_ms_per_eye(r) / chain_ms_per_eye(off),
            difference(r.ao_rmse_central, off.ao_rmse_central),
            difference(r.ao_rmse, off.ao_rmse),
        );
    }
    if table.is_empty() {
        return table;
    }
    format!(
        "\nFoveated or masked against neither, same case (chain: the occlusion passes per eye, with the frame's inline upsampling under --frame; errors over the pixels the lens shows):\n\n\
         | technique | samples | radius_m | resolution | foveation | mask | chain ms ratio | Δ RMSE central 20° | Δ RMSE visible | FLIP ratio |\n\
         |---|---|---|---|---|---|---|---|---|---|\n{table}"
    )
}
