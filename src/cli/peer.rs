//! `vrao peer`: Bevy's SSAO (the peer program in `peers/bevy`) and vrao's GTAO on the
//! same frames, scored by the same reference and timed in one run.

use super::{choice, SCENE_HELP};
use clap::Args;
use std::path::PathBuf;
use vrao::measure::bench::ReferenceOptions;
use vrao::measure::peer::{
    check_options, run_peer, scene_for_peer, write_outputs, PeerOptions, BEVY_PRESETS, DEFAULT_PEER, ROUNDS_MAX,
};
use vrao::measure::reference::default_cache_dir;
use vrao::measure::{MEASURED_FRAMES_MAX, WARMUP_MAX};
use vrao::Result;
use vrao_ao::{AoSettings, Quality};
use vrao_render::renderer::TimingChoice;
use vrao_render::scene::RENDER_DEFAULT;
use vrao_render::{BackendChoice, HeadsetProfile, Scene, Settings};

#[derive(Args)]
pub(crate) struct PeerArgs {
    #[arg(long, default_value = RENDER_DEFAULT, help = SCENE_HELP)]
    scene: String,
    /// The peer program (build it: cd peers/bevy && cargo build --release).
    #[arg(long, default_value = DEFAULT_PEER)]
    peer: PathBuf,
    /// Bevy's presets, comma-separated: low, medium, high, ultra (none: vrao alone).
    #[arg(long, value_delimiter = ',', default_values_t = BEVY_PRESETS.map(|p| p.0.to_string()))]
    presets: Vec<String>,
    /// vrao's GTAO sample counts, comma-separated, each 1..=256 (by default its presets').
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',', default_values_t = Quality::ALL.map(Quality::samples))]
    samples: Vec<u32>,
    /// vrao's resolutions: full, half or both.
    #[arg(long, default_value = "both", value_parser = ["full", "half", "both"])]
    resolution: String,
    /// Measured frames per case and round, 1..=100000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=MEASURED_FRAMES_MAX as i64))]
    frames: u32,
    /// Warm-up frames per case and round, 0..=1000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=WARMUP_MAX as i64))]
    warmup: u32,
    /// Rounds of Bevy and vrao, alternating which goes first, 1..=20.
    #[arg(long, allow_negative_numbers = true, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=ROUNDS_MAX as i64))]
    rounds: u32,
    /// AO radius in metres of vrao's cases and of the reference (Bevy's own is fixed: 0.73 m
    /// with a falloff from 0.28 m).
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().radius, value_parser = parse_radius)]
    radius: f32,
    /// Per-eye width in pixels, 16..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().width, value_parser = clap::value_parser!(u32).range(16..=8192))]
    width: u32,
    /// Per-eye height in pixels, 16..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().height, value_parser = clap::value_parser!(u32).range(16..=8192))]
    height: u32,
    /// Timing of both sides: serial (wall clock around work submitted alone), pipelined
    /// (GPU timestamps) or auto (serial on CPU adapters such as lavapipe).
    #[arg(value_parser = choice::<TimingChoice>(), long, default_value = "auto", hide_possible_values = true)]
    timing: TimingChoice,
    /// Reference rays per traced pixel, 1..=65536.
    #[arg(long, allow_negative_numbers = true, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    rays: u32,
    /// Trace the reference at every STRIDE-th pixel in x and y, 1..=64.
    #[arg(long, allow_negative_numbers = true, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    stride: u32,
    /// Directory of cached reference images (default: $XDG_CACHE_HOME/vrao or ~/.cache/vrao).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Output folder: peer.md, peer.png, side_by_side_left.png and the peer's files
    /// (peer-work/: the scene as glTF, each round's job, log, timings and AO images).
    #[arg(long, default_value = "peer")]
    out: PathBuf,
}

pub(crate) fn run(backend: BackendChoice, args: PeerArgs) -> Result<()> {
    vrao::formats::output::check_output_folder(&args.out)?;
    let work = args.out.join("peer-work");
    let options = PeerOptions {
        backend,
        peer: args.peer,
        presets: args.presets.iter().filter(|p| !p.is_empty()).cloned().collect(),
        samples: args.samples,
        half_res: match args.resolution.as_str() {
            "full" => vec![false],
            "half" => vec![true],
            _ => vec![false, true],
        },
        timing: args.timing,
        warmup: args.warmup,
        frames: args.frames,
        rounds: args.rounds,
        reference: ReferenceOptions {
            rays_per_pixel: args.rays,
            stride: args.stride,
            cache: args.cache.unwrap_or_else(default_cache_dir),
        },
        out: args.out.clone(),
        gltf: work.join("scene.glb"),
        interrupt: super::interrupt_on_signals("ending the peer", || {}),
    };
    check_options(&options)?;
    let scene = Scene::load(&args.scene)?;
    let mut base =
        Settings { profile: HeadsetProfile::with_size("vive", args.width, args.height), ..Settings::default() };
    base.ao.radius = args.radius;
    // The scene as glTF for the peer, written into the output folder at run time.
    std::fs::create_dir_all(&work).map_err(|e| vrao::Error::Output { path: work.clone(), message: e.to_string() })?;
    vrao::test_assets::gltf_write::write(&scene_for_peer(&scene), &options.gltf, &Default::default())?;
    let run = run_peer(&scene, &base, &options)?;
    print!("{}", write_outputs(&args.out, &run)?);
    Ok(())
}

/// A radius within the engine's range (its settings check it again).
fn parse_radius(text: &str) -> std::result::Result<f32, String> {
    let r: f32 = text.parse().map_err(|_| format!("'{text}' is not a number"))?;
    if r.is_finite() && r > 0.0 && r <= 100.0 {
        Ok(r)
    } else {
        Err(format!("radius {r} m is not within (0, 100]"))
    }
}
