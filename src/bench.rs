//! Sweeps of technique × samples × radius × resolution: the median GPU time of every
//! pass per eye over many frames, as a table, CSV and Markdown. (Error against the
//! reference tracer joins these rows when the tracer exists.)

use crate::error::{Error, Result};
use crate::gpu::timing::{summarize, SpanSummary};
use crate::gpu::Gpu;
use crate::passes::final_occlusion;
use crate::renderer::{Renderer, Timing};
use crate::scene::Scene;
use crate::settings::{Settings, Technique};
use std::fmt::Write as _;
use std::sync::Arc;

/// One configuration of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchCase {
    pub technique: Technique,
    pub samples: u32,
    pub radius: f32,
    pub half_res: bool,
}

/// How each case is run: frames (after warm-up) and the timing mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    pub timing: Timing,
    pub warmup: u32,
    pub frames: u32,
}

/// One measured row: the case and per-pass medians over the measured frames.
#[derive(Clone, Debug)]
pub struct BenchRow {
    pub case: BenchCase,
    pub spans: Vec<SpanSummary>,
    /// Views the occlusion passes covered in one dispatch (per-eye = total / views).
    pub views: u32,
    /// The pass that ran the technique.
    pub pass: &'static str,
}

impl BenchRow {
    /// Median ms of one pass for both eyes together (0 when it did not run).
    pub fn median_ms(&self, span: &str) -> f64 {
        self.spans.iter().find(|s| s.label == span).map_or(0.0, |s| s.median_ms)
    }

    /// Occlusion cost per eye: technique + blur + upsample, both-eye dispatches halved.
    pub fn occlusion_ms_per_eye(&self) -> f64 {
        let passes = [self.pass, "blur", "upsample"];
        passes.iter().map(|p| self.median_ms(p)).sum::<f64>() / self.views as f64
    }
}

/// Renders `warmup + frames` frames of `case` producing only the occlusion (the AO
/// alone, as a budget test asks), and returns the per-pass medians.
pub fn measure(gpu: &Arc<Gpu>, scene: &Scene, base: &Settings, case: &BenchCase, how: Measurement) -> Result<BenchRow> {
    let Measurement { timing, warmup, frames } = how;
    let mut settings = base.clone();
    settings.ao.technique = case.technique;
    settings.ao.samples = case.samples;
    settings.ao.radius = case.radius;
    settings.ao.half_res = case.half_res;
    let output = final_occlusion(&settings).ok_or_else(|| Error::input("bench needs an occlusion technique"))?;
    let mut renderer = Renderer::new(gpu.clone(), scene, &settings)?;
    renderer.set_timing(timing);
    if timing == Timing::Pipelined && !gpu.caps.timestamps {
        return Err(Error::Device(format!(
            "{} has no timestamp queries; use serial timing",
            gpu.adapter.get_info().name
        )));
    }
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let mut timings = Vec::new();
    for frame in 0..warmup + frames {
        let report = renderer.render(&eyes.eyes, &[output])?;
        if frame >= warmup {
            // Serial timing reports each pass's wall-clock time; pipelined, its timestamps.
            timings.push(if timing == Timing::Serial { report.wall_ms } else { report.gpu_ms });
        }
    }
    Ok(BenchRow { case: case.clone(), spans: summarize(&timings), views: 2, pass: settings.ao.pass_name() })
}

/// Runs every case, calling `progress(done, total, row)` after each.
pub fn sweep(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    base: &Settings,
    cases: &[BenchCase],
    how: Measurement,
    mut progress: impl FnMut(usize, usize, &BenchRow),
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::with_capacity(cases.len());
    for (i, case) in cases.iter().enumerate() {
        let row = measure(gpu, scene, base, case, how)?;
        progress(i + 1, cases.len(), &row);
        rows.push(row);
    }
    Ok(rows)
}

const COLUMNS: [&str; 9] = [
    "technique",
    "samples",
    "radius_m",
    "resolution",
    "technique_ms_per_eye",
    "blur_ms_per_eye",
    "upsample_ms_per_eye",
    "occlusion_ms_per_eye",
    "p75_over_p25",
];

fn row_values(row: &BenchRow) -> [String; 9] {
    let c = &row.case;
    let name = row.pass;
    let spread = row.spans.iter().find(|s| s.label == name).map_or(0.0, |s| s.p75_ms / s.p25_ms.max(1e-9));
    let per_eye = |p: &str| row.median_ms(p) / row.views as f64;
    [
        c.technique.name().to_string(),
        c.samples.to_string(),
        format!("{}", c.radius),
        if c.half_res { "half" } else { "full" }.to_string(),
        format!("{:.3}", per_eye(name)),
        format!("{:.3}", per_eye("blur")),
        format!("{:.3}", per_eye("upsample")),
        format!("{:.3}", row.occlusion_ms_per_eye()),
        format!("{spread:.3}"),
    ]
}

pub fn to_csv(rows: &[BenchRow]) -> String {
    let mut s = COLUMNS.join(",") + "\n";
    for row in rows {
        s += &(row_values(row).join(",") + "\n");
    }
    s
}

pub fn to_markdown(rows: &[BenchRow]) -> String {
    let mut s = format!("| {} |\n|{}\n", COLUMNS.join(" | "), "---|".repeat(COLUMNS.len()));
    for row in rows {
        let _ = writeln!(s, "| {} |", row_values(row).join(" | "));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(technique: Technique, ms: f64) -> BenchRow {
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
            case: BenchCase { technique, samples: 12, radius: 0.5, half_res: false },
            spans: vec![span(technique.name(), ms), span("blur", 2.0), span("gbuffer", 50.0)],
            views: 2,
            pass: technique.name(),
        }
    }

    #[test]
    fn per_eye_cost_halves_both_eye_dispatches_and_ignores_other_passes() {
        assert_eq!(row(Technique::Ssao, 10.0).occlusion_ms_per_eye(), 6.0);
    }

    #[test]
    fn csv_and_markdown_hold_every_row() {
        let rows = [row(Technique::Ssao, 10.0), row(Technique::Hbao, 12.0)];
        let csv = to_csv(&rows);
        assert_eq!(csv.lines().count(), 3);
        assert!(csv.lines().nth(2).unwrap().starts_with("hbao,12,0.5,full,6.000,1.000,0.000,7.000"));
        assert_eq!(to_markdown(&rows).lines().count(), 4);
    }
}
