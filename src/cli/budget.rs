//! `vrao budget`: per-pass medians of one setting against the frame budget (exit 3 over it).

use super::{choice, parse_budget_ms, AoArgs, SCENE_HELP};
use clap::Args;
use std::path::PathBuf;
use vrao::measure::budget::{measure_budget, BudgetOptions};
use vrao::measure::{MEASURED_FRAMES_MAX, WARMUP_MAX};
use vrao::Result;
use vrao_render::renderer::TimingChoice;
use vrao_render::{BackendChoice, HeadsetProfile, Scene};

/// What each measured frame produces.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Measure {
    Frame,
    Occlusion,
}

#[derive(Args)]
pub(crate) struct BudgetArgs {
    #[arg(long, default_value = "builtin:room", help = SCENE_HELP)]
    scene: String,
    /// Per-eye width in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().width)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().height)]
    height: u32,
    /// Measured frames (each: the stereo frame, then each eye alone), after warm-up; 1..=100000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=MEASURED_FRAMES_MAX as i64))]
    frames: u32,
    /// Warm-up frames (not measured), 0..=1000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=WARMUP_MAX as i64))]
    warmup: u32,
    /// Budget of one stereo frame in ms (default: the headset's refresh interval, 11.1 ms
    /// at 90 Hz); each eye gets half.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_budget_ms)]
    budget_ms: Option<f64>,
    /// What each frame produces: frame (the eye colour, every pass) or occlusion (the
    /// occlusion passes alone).
    #[arg(long, default_value = "frame", hide_possible_values = true)]
    measure: Measure,
    /// Timing: pipelined, serial or auto (serial on CPU adapters).
    #[arg(value_parser = choice::<TimingChoice>(), long, default_value = "auto", hide_possible_values = true)]
    timing: TimingChoice,
    /// Pick the occlusion setting from this bench JSON (made by `vrao bench` on this
    /// device) with the least error that fits the budget, then measure it.
    #[arg(long)]
    fit: Option<PathBuf>,
    /// Where to write the JSON report.
    #[arg(long, default_value = "budget.json")]
    out: PathBuf,
    #[command(flatten)]
    ao: AoArgs,
}

pub(crate) fn run(backend: BackendChoice, args: BudgetArgs) -> Result<()> {
    // A report that cannot be written fails now, not after the measurement.
    vrao::formats::output::check_output_file(&args.out)?;
    let scene = Scene::load(&args.scene)?;
    let settings = args.ao.eye_settings(&scene, args.width, args.height);
    let options = BudgetOptions {
        backend,
        timing: args.timing,
        frames: args.frames,
        warmup: args.warmup,
        budget_ms: args.budget_ms,
        occlusion_only: args.measure == Measure::Occlusion,
        fit: args.fit,
    };
    let outcome = measure_budget(&scene, &settings, &options)?;
    if let Some(fit) = &outcome.fit {
        fit.warnings.iter().for_each(|w| eprintln!("{w}"));
        fit.notes.iter().for_each(|n| println!("{n}"));
    }
    print!("{}", outcome.report.to_text());
    vrao::formats::output::write_json(&args.out, &outcome.report)?;
    println!("wrote {}", args.out.display());
    outcome.report.over_budget().map_or(Ok(()), Err)
}
