//! `vrao table`: the GPU table — per-pass ms per eye of every technique × preset × AO
//! resolution × foveation, the stereo frame against the budget, per scene — as one
//! Markdown file.

use super::{choice, parse_budget_ms};
use clap::Args;
use std::path::PathBuf;
use vrao::measure::bench::{version, Resolution};
use vrao::measure::table::{check_scene_count, run_table, TableOptions};
use vrao::measure::{MEASURED_FRAMES_MAX, WARMUP_MAX};
use vrao::{Error, Result};
use vrao_ao::{Foveation, Quality, Technique};
use vrao_render::renderer::TimingChoice;
use vrao_render::{BackendChoice, HeadsetProfile, Scene};

/// An AO resolution on the command line.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Res {
    Full,
    Half,
}

#[derive(Args)]
pub(crate) struct TableArgs {
    /// Scenes, comma-separated, each a scene file or builtin:NAME (Sibenik's file names
    /// its mesh under $VRAO_SCENES); at most 16.
    #[arg(long, value_delimiter = ',', default_values_t = ["assets/scenes/sibenik.toml".to_string(), "builtin:furnished".to_string()])]
    scenes: Vec<String>,
    /// Techniques, comma-separated.
    #[arg(value_parser = choice::<Technique>(), long, value_delimiter = ',', default_values_t = [Technique::Gtao, Technique::Ssao, Technique::Hbao, Technique::Ssdo], hide_possible_values = true)]
    techniques: Vec<Technique>,
    /// Quality presets, comma-separated: low, medium, high, ultra.
    #[arg(value_parser = choice::<Quality>(), long, value_delimiter = ',', default_values_t = Quality::ALL, hide_possible_values = true)]
    qualities: Vec<Quality>,
    /// AO resolutions, comma-separated: full, half.
    #[arg(long, value_delimiter = ',', value_enum, default_values_t = [Res::Full, Res::Half], hide_possible_values = true)]
    resolutions: Vec<Res>,
    /// Foveation settings, comma-separated: off, low, high.
    #[arg(value_parser = choice::<Foveation>(), long, value_delimiter = ',', default_values_t = [Foveation::Off, Foveation::High], hide_possible_values = true)]
    foveations: Vec<Foveation>,
    /// Per-eye width in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().width)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().height)]
    height: u32,
    /// Measured rounds per row (each: the stereo frame, then each eye alone), after
    /// warm-up; 1..=100000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=MEASURED_FRAMES_MAX as i64))]
    frames: u32,
    /// Warm-up rounds per row (not measured), 0..=1000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=WARMUP_MAX as i64))]
    warmup: u32,
    /// Budget of one stereo frame in ms (default: the headset's refresh interval, 11.1 ms
    /// at 90 Hz).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_budget_ms)]
    budget_ms: Option<f64>,
    /// Timing: pipelined, serial or auto (serial on CPU adapters).
    #[arg(value_parser = choice::<TimingChoice>(), long, default_value = "auto", hide_possible_values = true)]
    timing: TimingChoice,
    /// Where to write the Markdown table.
    #[arg(long, default_value = "gpu-table.md")]
    out: PathBuf,
}

pub(crate) fn run(backend: BackendChoice, args: TableArgs) -> Result<()> {
    // A table that cannot be written, or a bad option, fails now: before the scenes load
    // and long before the sweep ends.
    vrao::formats::output::check_output_file(&args.out)?;
    let options = TableOptions {
        backend,
        timing: args.timing,
        width: args.width,
        height: args.height,
        frames: args.frames,
        warmup: args.warmup,
        budget_ms: args.budget_ms,
        techniques: args.techniques,
        qualities: args.qualities,
        resolutions: args
            .resolutions
            .iter()
            .map(|r| match r {
                Res::Full => Resolution::Full,
                Res::Half => Resolution::Half,
            })
            .collect(),
        foveations: args.foveations,
    };
    options.validate()?;
    check_scene_count(args.scenes.len())?;
    let scenes = args.scenes.iter().map(|spec| Ok((spec.clone(), Scene::load(spec)?))).collect::<Result<Vec<_>>>()?;
    let table = run_table(&scenes, &options)?;
    let command = std::env::args().map(|a| shell_word(&a)).collect::<Vec<_>>().join(" ");
    let markdown = table.to_markdown(&version(), &command);
    std::fs::write(&args.out, markdown)
        .map_err(|e| Error::Output { path: args.out.clone(), message: format!("cannot write: {e}") })?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// `word` as a shell reads it back: bare when it is plain, else single-quoted.
fn shell_word(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./:,=+@%".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}
