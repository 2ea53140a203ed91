//! `vrao bench`: sweep technique × samples × radius × resolution, timed and scored
//! against the reference tracer.

use super::{choice, parse_budget_ms, GtaoArgs, OnOff, SCENE_HELP};
use clap::Args;
use std::path::PathBuf;
use vrao::measure::bench::{replot, run_bench, write_outputs, BenchOptions, ReferenceOptions};
use vrao::measure::reference::default_cache_dir;
use vrao::measure::{MEASURED_FRAMES_MAX, WARMUP_MAX};
use vrao::Result;
use vrao_ao::{AoSettings, Denoise, Foveation, Quality, Technique};
use vrao_render::renderer::TimingChoice;
use vrao_render::scene::RENDER_DEFAULT;
use vrao_render::{BackendChoice, BounceForm, HeadsetProfile, PointSsdoSettings, Scene, Settings};

/// A sweep over a switch: off, on or both.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Sweep {
    Off,
    On,
    Both,
}

impl Sweep {
    fn values(self) -> Vec<bool> {
        match self {
            Sweep::Off => vec![false],
            Sweep::On => vec![true],
            Sweep::Both => vec![false, true],
        }
    }
}

/// The resolutions to sweep.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Resolution {
    Full,
    Half,
    Both,
}

#[derive(Args)]
pub(crate) struct BenchArgs {
    #[arg(long, default_value = RENDER_DEFAULT, help = SCENE_HELP)]
    scene: String,
    /// Techniques to sweep, comma-separated (by default every estimator, gtao first).
    #[arg(value_parser = choice::<Technique>(), long, value_delimiter = ',', default_values_t = Technique::estimators(), hide_possible_values = true)]
    techniques: Vec<Technique>,
    /// Sample counts, comma-separated, each 1..=256 (by default the presets' counts, the
    /// grid of Belonogov 2018).
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',', default_values_t = Quality::ALL.map(Quality::samples))]
    samples: Vec<u32>,
    /// Radii in metres, comma-separated (default: the scene's radius × 0.5, 1, 2).
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',')]
    radii: Vec<f32>,
    /// Resolutions: full, half or both.
    #[arg(long, default_value = "both", hide_possible_values = true)]
    resolution: Resolution,
    /// SSDO depth peeling: off, on or both (each SSDO case with and without; other
    /// techniques never peel).
    #[arg(long, default_value = "off", hide_possible_values = true)]
    depth_peeling: Sweep,
    /// Depth layers to sweep, comma-separated: 1, 2 (two: the renderer peels a second
    /// layer and GTAO and SSDO read it; other techniques get no 2-layer rows). Every row
    /// scored against the reference also gets the two-layer limit.
    #[arg(long, value_delimiter = ',', default_values_t = [1u32], value_parser = clap::value_parser!(u32).range(1..=2))]
    layers: Vec<u32>,
    /// Temporal accumulation: off, on or both (the error of a temporal row is its
    /// converged value after warm-up + frames with a static head).
    #[arg(long, default_value = "off", hide_possible_values = true)]
    temporal: Sweep,
    /// Fixed foveation levels to sweep, comma-separated: off, low, high (each row also
    /// gets its RMSE within 10° of each eye's view axis, where foveation keeps full rate).
    #[arg(value_parser = choice::<Foveation>(), long, value_delimiter = ',', default_values_t = [Foveation::Off], hide_possible_values = true)]
    foveation: Vec<Foveation>,
    /// The visibility mask to sweep, comma-separated: off (the whole rectangle computed),
    /// on (the passes skip what the profile's lens hides). Every row is scored on the
    /// pixels the lens shows; rows with the mask off also over the whole rectangle
    /// (ao_rmse_whole).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [OnOff::from(AoSettings::default().mask)])]
    mask: Vec<OnOff>,
    /// Also measure reflective shadow maps (one bounce of the directional lights) with
    /// these VPL counts (each 1..=1024), comma-separated, gathering within each radius: rows "rsm", whose
    /// error against the reference's bounce (bounce_rel_rmse, bounce_rel_bias) is also
    /// given for ssdo-bounce rows.
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',')]
    rsm_samples: Vec<u32>,
    /// Measured frames per case, after warm-up; 1..=100000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=MEASURED_FRAMES_MAX as i64))]
    frames: u32,
    /// Warm-up frames per case (not measured), 0..=1000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=WARMUP_MAX as i64))]
    warmup: u32,
    /// How ssdo-bounce rows weigh their senders: direction or patch (Ritschel et al. 2009
    /// eq. 2).
    #[arg(value_parser = choice::<BounceForm>(), long, default_value_t = PointSsdoSettings::default().bounce_form, hide_possible_values = true)]
    bounce_form: BounceForm,
    #[command(flatten)]
    gtao: GtaoArgs,
    /// Spatial denoise of every row: tile (edge-aware, 5 taps per axis over the 4×4 noise
    /// tile) or bilateral (11×11 at --blur 5).
    #[arg(value_parser = choice::<Denoise>(), long, default_value_t = AoSettings::default().denoise, hide_possible_values = true)]
    denoise: Denoise,
    /// Bilateral blur radius in full-resolution pixels; 0 turns any denoise off.
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().blur_radius)]
    blur: u32,
    /// Measure this many cases at a time, round-robin one frame each, so that the
    /// machine's drift during a long sweep falls on all of them alike (fair ratios
    /// between techniques); each needs its own targets in memory at once. 1..=64.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    interleave: u32,
    /// Render whole frames (direct light and composite too), not only the occlusion: the
    /// composite is timed, and each half-resolution row gets the cost of upsampling as a
    /// frame pays it, inline in the composite (its composite minus the full-resolution
    /// row's; sweep --resolution both, ideally interleaved).
    #[arg(long)]
    frame: bool,
    /// Per-eye width in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().width)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().height)]
    height: u32,
    /// Timing: pipelined (one submission per frame, GPU timestamps), serial (one
    /// submission per pass, wall clock) or auto (serial on CPU adapters such as lavapipe,
    /// whose timestamps misattribute work between passes; pipelined on GPUs).
    #[arg(value_parser = choice::<TimingChoice>(), long, default_value = "auto", hide_possible_values = true)]
    timing: TimingChoice,
    /// Output directory for bench.csv, bench.json, bench.md and bench.png.
    #[arg(long, default_value = "bench")]
    out: PathBuf,
    /// Reference rays per traced pixel (cosine-weighted, stratified), 1..=65536.
    #[arg(long, allow_negative_numbers = true, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    rays: u32,
    /// Trace the reference at every STRIDE-th pixel in x and y (errors are measured there), 1..=64.
    #[arg(long, allow_negative_numbers = true, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    stride: u32,
    /// Skip the reference: time only, no error columns.
    #[arg(long)]
    no_reference: bool,
    /// Also write OUT/images/ROW.png for every scored row: the left eye's AO beside the
    /// one-layer limit, the two-layer limit and the reference (each traced pixel over its
    /// stride), to see where the error lies.
    #[arg(long, conflicts_with_all = ["no_reference", "replot"])]
    images: bool,
    /// Directory of cached reference images (default: $XDG_CACHE_HOME/vrao or ~/.cache/vrao).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Budget per stereo frame in ms for the plot's budget line (each eye gets half).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_budget_ms, default_value_t = 1000.0 / HeadsetProfile::vive().refresh_hz)]
    budget_ms: f64,
    /// Measure nothing: rewrite the table, CSV, Markdown and plots of this bench.json
    /// (Pareto fronts recomputed) into --out.
    #[arg(long)]
    replot: Option<PathBuf>,
}

pub(crate) fn run(backend: BackendChoice, args: BenchArgs) -> Result<()> {
    // An output folder that cannot be written fails now, not after the sweep.
    vrao::formats::output::check_output_folder(&args.out)?;
    let run = match &args.replot {
        Some(path) => replot(path)?,
        None => {
            let scene = Scene::load(&args.scene)?;
            let mut base =
                Settings { profile: HeadsetProfile::with_size("vive", args.width, args.height), ..Settings::default() };
            base.point_ssdo.bounce_form = args.bounce_form;
            args.gtao.apply(&mut base.ao);
            (base.ao.denoise, base.ao.blur_radius) = (args.denoise, args.blur);
            let options = BenchOptions {
                backend,
                techniques: args.techniques.clone(),
                samples: args.samples.clone(),
                radii: args.radii.clone(),
                half_res: match args.resolution {
                    Resolution::Full => vec![false],
                    Resolution::Half => vec![true],
                    Resolution::Both => vec![false, true],
                },
                depth_peeling: args.depth_peeling.values(),
                layers: args.layers.clone(),
                temporal: args.temporal.values(),
                foveation: args.foveation.clone(),
                mask: args.mask.iter().map(|m| m.on()).collect(),
                rsm_samples: args.rsm_samples.clone(),
                timing: args.timing,
                warmup: args.warmup,
                frames: args.frames,
                interleave: args.interleave as usize,
                whole_frame: args.frame,
                reference: (!args.no_reference).then(|| ReferenceOptions {
                    rays_per_pixel: args.rays,
                    stride: args.stride,
                    cache: args.cache.clone().unwrap_or_else(default_cache_dir),
                }),
                command: command_line(),
                images: args.images.then(|| args.out.join("images")),
            };
            run_bench(&scene, &base, &options)?
        }
    };
    print!("{}", write_outputs(&args.out, &run, args.budget_ms)?);
    Ok(())
}

/// The command line as typed (arguments with spaces or quotes quoted), kept in bench.json.
fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if !a.is_empty() && a.chars().all(|c| c.is_ascii_alphanumeric() || "-_./:=,+@%".contains(c)) {
                a
            } else {
                format!("'{}'", a.replace('\'', r"'\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Bench {
        #[command(flatten)]
        args: BenchArgs,
    }

    #[test]
    fn bench_with_no_options_sweeps_every_estimator_on_the_default_scene() {
        let args = Bench::try_parse_from(["bench"]).unwrap().args;
        assert_eq!(args.scene, RENDER_DEFAULT);
        use Technique::*;
        assert_eq!(args.techniques, [Gtao, Ssao, Hbao, Ssdo, SsdoBounce, SsdoPoints, SsdoPointsBounce]);
        assert_eq!(args.samples, [12, 24, 36, 64]);
        assert_eq!((args.denoise, args.blur), (AoSettings::default().denoise, AoSettings::default().blur_radius));
        assert_eq!((args.width, args.height), (1080, 1200));
    }
}
