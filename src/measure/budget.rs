//! The headless per-eye budget test: renders frames of one setting and compares every
//! pass's median time, per eye, with the headset's frame budget (11.1 ms per stereo frame
//! at 90 Hz unless overridden).
//!
//! A pass that covers both eyes in one dispatch has no per-eye time of its own, so each
//! measured round renders the stereo frame and then each eye alone (a one-layer frame of
//! the same passes): the stereo figures say what a frame costs, the single-eye figures say
//! what each eye costs. Both are reported. An eye passes when the sum of its passes fits
//! half the budget; the stereo frame passes when the sum of its passes fits the budget.

use crate::error::Result;
use crate::formats::spans::{summarize, RightEyeTilesReport, SpanSummary};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};
use vrao_ao::plug::{FrameTiming, Resource};
use vrao_ao::EyePair;
use vrao_render::passes::tonemap::COLOR;
use vrao_render::renderer::{FrameReport, Renderer, Timing};

mod fit;
pub use fit::{fit_setting, measure_budget, BudgetOptions, BudgetOutcome, Fit};

/// Per-pass times of one budget run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassTimes {
    /// The pass's span label.
    pub pass: String,
    /// Both eyes in one frame (one dispatch covering both layers, or both per-eye passes).
    pub stereo: Option<SpanSummary>,
    /// The left eye rendered alone.
    pub left: Option<SpanSummary>,
    /// The right eye rendered alone.
    pub right: Option<SpanSummary>,
}

/// What a verdict is about; reports write `left eye`, `right eye` or `stereo frame`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scope {
    /// The left eye rendered alone.
    #[serde(rename = "left eye")]
    LeftEye,
    /// The right eye rendered alone.
    #[serde(rename = "right eye")]
    RightEye,
    /// Both eyes in one frame.
    #[serde(rename = "stereo frame")]
    StereoFrame,
}

impl Scope {
    /// `left eye`, `right eye` or `stereo frame`, as reports write it.
    pub fn name(self) -> &'static str {
        match self {
            Scope::LeftEye => "left eye",
            Scope::RightEye => "right eye",
            Scope::StereoFrame => "stereo frame",
        }
    }
}

/// The verdict for one eye or for the whole stereo frame.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Verdict {
    /// One eye alone or the stereo frame.
    pub what: Scope,
    /// Sum of the per-pass medians.
    pub ms: f64,
    /// Half the stereo budget for an eye, the whole budget for the stereo frame (ms).
    pub budget_ms: f64,
    /// `ms` ≤ `budget_ms`.
    pub pass: bool,
}

/// What `vrao budget` measured: per-pass times of the stereo frame and of each eye alone, and the verdicts.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BudgetReport {
    /// GPU adapter name.
    pub adapter: String,
    /// wgpu backend.
    pub backend: String,
    /// Per-eye width in pixels.
    pub width: u32,
    /// Per-eye height in pixels.
    pub height: u32,
    /// Timing mode, lower case (`serial` or `pipelined`).
    pub timing: String,
    /// Frames discarded before timing.
    pub warmup: u32,
    /// Frames timed.
    pub frames: u32,
    /// What the frames produced: the eye colour (a whole frame) or the occlusion alone.
    pub output: String,
    /// The stereo frame budget (ms).
    pub budget_ms: f64,
    /// Every pass's times, in frame order.
    pub passes: Vec<PassTimes>,
    /// CPU time spent encoding the stereo frame, the left and the right eye frame.
    pub cpu_encode: Vec<SpanSummary>,
    /// Left eye, right eye and stereo frame against their budgets.
    pub verdicts: Vec<Verdict>,
    /// The right eye's tiles (8×8 occlusion pixels) the stereo frame's AO chain computed
    /// rather than copied from the left eye, read back from its indirect dispatch (the
    /// same on every machine); absent when the right eye does not reuse the left's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub right_eye_tiles: Vec<RightEyeTilesReport>,
    /// Bytes per pixel of each eye the stereo frame's occlusion passes wrote and read,
    /// counted from their declared textures (the same on every machine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub occlusion_bytes_per_pixel: Option<TrafficReport>,
    /// The share of each eye's pixels the profile's lens hides and the passes skipped in
    /// the stereo frame (`--mask on`); zeros with `--mask off`.
    #[serde(default)]
    pub hidden_share_per_eye: Vec<f64>,
    /// The AO chain (the passes the frame graph counts as occlusion cost) in the stereo
    /// frame against the left eye alone: what the right eye adds; absent without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ao_chain: Option<AoChainCost>,
}

/// [`BudgetReport::ao_chain`]: sums of the passes' medians.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AoChainCost {
    /// The chain's passes, in frame order.
    pub passes: Vec<String>,
    /// The left eye alone (ms).
    pub left_eye_ms: f64,
    /// The stereo frame (ms).
    pub stereo_ms: f64,
    /// (stereo − left eye alone) / left eye alone: the right eye's cost in the stereo
    /// frame as a share of the left eye's (about 1 where the eyes are computed alike).
    pub right_eye_added_share: f64,
}

impl AoChainCost {
    /// The chain over `passes` (those of `names` that ran), or `None` when none ran or
    /// the left eye took no time.
    fn of(passes: &[PassTimes], names: &[&str]) -> Option<Self> {
        let chain: Vec<&PassTimes> = passes.iter().filter(|p| names.contains(&p.pass.as_str())).collect();
        let sum = |scope: fn(&PassTimes) -> &Option<SpanSummary>| {
            chain.iter().map(|p| scope(p).as_ref().map_or(0.0, |s| s.median_ms)).sum::<f64>()
        };
        let (left_eye_ms, stereo_ms) = (sum(|p| &p.left), sum(|p| &p.stereo));
        (!chain.is_empty() && left_eye_ms > 0.0).then(|| AoChainCost {
            passes: chain.iter().map(|p| p.pass.clone()).collect(),
            left_eye_ms,
            stereo_ms,
            right_eye_added_share: (stereo_ms - left_eye_ms) / left_eye_ms,
        })
    }
}

/// [`BudgetReport::occlusion_bytes_per_pixel`].
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TrafficReport {
    /// Bytes written per pixel of each eye.
    pub written: f64,
    /// Bytes read per pixel of each eye.
    pub read: f64,
}

impl BudgetReport {
    /// True when every verdict passed.
    pub fn within_budget(&self) -> bool {
        self.verdicts.iter().all(|v| v.pass)
    }

    /// `None` within budget; otherwise what is over it, as the error `vrao budget` exits 3 with.
    pub fn over_budget(&self) -> Option<crate::error::Error> {
        let over: Vec<&str> = self.verdicts.iter().filter(|v| !v.pass).map(|v| v.what.name()).collect();
        (!over.is_empty()).then(|| {
            crate::error::Error::OverBudget(format!(
                "{} over the {:.3} ms stereo frame budget",
                over.join(", "),
                self.budget_ms
            ))
        })
    }

    /// The table `vrao budget` prints.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "budget: {} on {} ({}), {}x{} per eye, {} timing, median of {} frames after {} warm-up (p25–p75)",
            self.output, self.adapter, self.backend, self.width, self.height, self.timing, self.frames, self.warmup
        );
        let cell = |span: &Option<SpanSummary>| match span {
            Some(s) => format!("{:.3} ({:.3}–{:.3})", s.median_ms, s.p25_ms, s.p75_ms),
            None => "-".to_string(),
        };
        let _ = writeln!(
            s,
            "  {:<14} {:>30} {:>30} {:>30}",
            "pass ms", "stereo frame", "left eye alone", "right eye alone"
        );
        for p in &self.passes {
            let _ =
                writeln!(s, "  {:<14} {:>30} {:>30} {:>30}", p.pass, cell(&p.stereo), cell(&p.left), cell(&p.right));
        }
        let encode: Vec<Option<SpanSummary>> = self.cpu_encode.iter().cloned().map(Some).collect();
        if encode.len() == 3 {
            let _ = writeln!(
                s,
                "  {:<14} {:>30} {:>30} {:>30}",
                "cpu encode",
                cell(&encode[0]),
                cell(&encode[1]),
                cell(&encode[2])
            );
        }
        if self.hidden_share_per_eye.iter().any(|&h| h > 0.0) {
            let shares: Vec<String> = self.hidden_share_per_eye.iter().map(|h| format!("{:.1} %", 100.0 * h)).collect();
            let _ = writeln!(s, "lens mask: {} of the pixels hidden and skipped (left, right)", shares.join(", "));
        }
        if let Some(t) = &self.occlusion_bytes_per_pixel {
            let _ = writeln!(
                s,
                "occlusion passes: {:.1} bytes written and {:.1} read per pixel of each eye (declared textures)",
                t.written, t.read
            );
        }
        for t in &self.right_eye_tiles {
            let _ = writeln!(
                s,
                "right eye, {}: {} of {} tiles computed ({:.1} %: {} items), the rest copied from the left eye",
                t.pass,
                t.computed,
                t.total,
                100.0 * t.share,
                t.items
            );
        }
        if let Some(c) = &self.ao_chain {
            let _ = writeln!(
                s,
                "AO chain ({}): left eye alone {:.3} ms, stereo frame {:.3} ms: the right eye adds {:.1} % of the left eye's",
                c.passes.join(" + "),
                c.left_eye_ms,
                c.stereo_ms,
                100.0 * c.right_eye_added_share
            );
        }
        for v in &self.verdicts {
            let _ = writeln!(
                s,
                "{:<13} {:>10.3} ms of {:>8.3} ms  {}",
                v.what.name(),
                v.ms,
                v.budget_ms,
                if v.pass { "PASS".to_string() } else { format!("FAIL ({:.1}× over)", v.ms / v.budget_ms) }
            );
        }
        s
    }
}

/// How the budget run measures.
#[derive(Clone, Copy, Debug)]
pub struct BudgetRun {
    /// Serial (true per-pass times) or pipelined submission.
    pub timing: Timing,
    /// Frames discarded before timing.
    pub warmup: u32,
    /// Frames timed.
    pub frames: u32,
    /// The stereo frame budget in milliseconds.
    pub budget_ms: f64,
    /// The target the frames render up to: the eye colour (whole frame) or the occlusion alone.
    pub output: Resource,
}

/// A frame's pass times: wall clock per pass with serial timing, timestamps otherwise.
fn pass_times(report: &FrameReport, timing: Timing) -> Vec<(String, f64)> {
    let source = if timing == Timing::Serial { &report.wall_ms } else { &report.gpu_ms };
    // Per-eye sub-spans inside a pass ("gbuffer left") are not passes of their own.
    source.iter().filter(|(name, _)| !FrameTiming::is_per_eye(name)).cloned().collect()
}

/// How long a measurement's first setting renders before it is measured (when the run
/// warms up at all, on a GPU), and at most how many rounds that takes. A GPU that idled has
/// clocked down: a warm-up of a few rounds left the first row far slower than every later
/// one (docs/records/2026-11-29/measurements-in-code.md, table-settle-time).
const SETTLE_TIME: Duration = Duration::from_millis(1500);
const SETTLE_MAX_ROUNDS: u32 = 500;

/// Renders rounds of `how` unmeasured until the device has worked for `SETTLE_TIME` (or
/// `SETTLE_MAX_ROUNDS` rounds): its clocks up, its caches and allocations warm.
/// Nothing without a warm-up (`how.warmup` 0), and nothing on a CPU adapter (lavapipe):
/// its first frame already keeps the cores busy, and its tests run at a few pixels, where
/// the settle would only add time.
pub fn settle(renderer: &mut Renderer, eyes: &EyePair, how: BudgetRun) -> Result<()> {
    if how.warmup == 0 || renderer.gpu().info.device_type == wgpu::DeviceType::Cpu {
        return Ok(());
    }
    // Rounds as `run` renders them, without its report (read-backs, plan, summaries).
    renderer.set_timing(how.timing);
    let start = Instant::now();
    for _ in 0..SETTLE_MAX_ROUNDS {
        if start.elapsed() >= SETTLE_TIME {
            break;
        }
        for view in round_views(eyes) {
            renderer.render_and_wait(view, &[how.output])?;
        }
    }
    Ok(())
}

/// One measuring round's views, in order: the stereo frame, the left eye alone, the right
/// eye alone.
fn round_views(eyes: &EyePair) -> [&[vrao_ao::Eye]; 3] {
    [&eyes.eyes, &eyes.eyes[..1], &eyes.eyes[1..]]
}

/// Renders `warmup + frames` rounds of (stereo frame, left eye alone, right eye alone)
/// and compares the medians with the budget.
pub fn run(renderer: &mut Renderer, eyes: &EyePair, how: BudgetRun) -> Result<BudgetReport> {
    // Bounded counts: `warmup + frames` never wraps, and there is a measured frame.
    crate::measure::check_frames(how.warmup, how.frames)?;
    renderer.set_timing(how.timing);
    let views = round_views(eyes);
    let mut times: [Vec<Vec<(String, f64)>>; 3] = Default::default();
    let mut encode: [Vec<Vec<(String, f64)>>; 3] = Default::default();
    let mut pass_order: Vec<String> = Vec::new();
    let mut right_eye_tiles = Vec::new();
    let mut occlusion_bytes_per_pixel = None;
    let mut hidden_share_per_eye = Vec::new();
    for round in 0..how.warmup + how.frames {
        for (k, v) in views.iter().enumerate() {
            let report = renderer.render_and_wait(v, &[how.output])?;
            if round < how.warmup {
                continue;
            }
            // The last stereo frame's figures (the right eye's counts are a blocking
            // readback: once, not every round).
            if k == 0 && round + 1 == how.warmup + how.frames {
                hidden_share_per_eye = renderer.hidden_share().to_vec();
                occlusion_bytes_per_pixel =
                    renderer.occlusion_traffic().map(|t| TrafficReport { written: t.written, read: t.read });
                right_eye_tiles = renderer.right_eye_tiles().iter().map(RightEyeTilesReport::from).collect();
            }
            let t = pass_times(&report, how.timing);
            for (name, _) in &t {
                if !pass_order.contains(name) {
                    pass_order.push(name.clone());
                }
            }
            times[k].push(t);
            encode[k].push(vec![("cpu encode".to_string(), report.cpu_encode_ms)]);
        }
    }
    let summaries: Vec<Vec<SpanSummary>> = times.iter().map(|t| summarize(t)).collect();
    let find = |k: usize, pass: &str| summaries[k].iter().find(|s| s.label == pass).cloned();
    let passes: Vec<PassTimes> = pass_order
        .iter()
        .map(|p| PassTimes { pass: p.clone(), stereo: find(0, p), left: find(1, p), right: find(2, p) })
        .collect();
    let ao_chain = AoChainCost::of(&passes, &renderer.plan(2, &[how.output])?.occlusion_passes());
    let total = |k: usize| summaries[k].iter().map(|s| s.median_ms).sum::<f64>();
    let per_eye_budget = how.budget_ms / 2.0;
    let verdict = |what: Scope, ms: f64, budget_ms: f64| Verdict { what, ms, budget_ms, pass: ms <= budget_ms };
    let verdicts = vec![
        verdict(Scope::LeftEye, total(1), per_eye_budget),
        verdict(Scope::RightEye, total(2), per_eye_budget),
        verdict(Scope::StereoFrame, total(0), how.budget_ms),
    ];
    let cpu_encode = [Scope::StereoFrame, Scope::LeftEye, Scope::RightEye]
        .iter()
        .zip(&encode)
        .map(|(scope, e)| {
            let mut s = summarize(e).pop().expect("at least one measured frame");
            s.label = scope.name().to_string();
            s
        })
        .collect();
    let info = renderer.gpu().info.clone();
    let p = &renderer.settings().profile;
    Ok(BudgetReport {
        adapter: info.name.clone(),
        backend: format!("{:?}", info.backend),
        width: p.width,
        height: p.height,
        timing: format!("{:?}", how.timing).to_lowercase(),
        warmup: how.warmup,
        frames: how.frames,
        output: if how.output == COLOR { "whole frame".into() } else { format!("{} only", how.output.name()) },
        budget_ms: how.budget_ms,
        passes,
        cpu_encode,
        verdicts,
        right_eye_tiles,
        occlusion_bytes_per_pixel,
        hidden_share_per_eye,
        ao_chain,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdict_scopes_keep_their_names_in_reports() {
        for (scope, name) in
            [(Scope::LeftEye, "left eye"), (Scope::RightEye, "right eye"), (Scope::StereoFrame, "stereo frame")]
        {
            assert_eq!(scope.name(), name);
            assert_eq!(serde_json::to_string(&scope).unwrap(), format!("\"{name}\""));
            assert_eq!(serde_json::from_str::<Scope>(&format!("\"{name}\"")).unwrap(), scope);
        }
    }
}
