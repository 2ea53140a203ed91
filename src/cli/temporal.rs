//! `vrao temporal`: how temporal accumulation converges next to spatial-only settings;
//! with `--motion`, how it copes with moving objects (ghosts, error during motion).

use super::AoArgs;
use clap::Args;
use std::path::PathBuf;
use vrao::measure::reference::default_cache_dir;
use vrao::measure::temporal::motion::{self, motion_study, Sequence};
use vrao::measure::temporal::{study, to_markdown};
use vrao::Result;
use vrao_render::{BackendChoice, Scene};

#[derive(Args)]
pub(crate) struct TemporalArgs {
    /// Scene: builtin:NAME, a .toml scene file, an .obj or a glTF (default: builtin:room,
    /// or builtin:moving with --motion).
    #[arg(long)]
    scene: Option<String>,
    /// Score a motion sequence of a scene that moves instead: every scored frame against
    /// the reference at its time, for temporal accumulation off, by the eyes alone and
    /// by motion vectors, next to the scene frozen at that time.
    #[arg(long)]
    motion: bool,
    /// With --motion: scene time of the sequence's first frame, 0 to 1e6 s.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5, value_parser = super::parse_scene_time)]
    start: f64,
    /// With --motion: frames scored (each traces a reference), 1 to 64.
    #[arg(long, allow_negative_numbers = true, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=64))]
    scored: u32,
    /// With --motion: frames (at 90 Hz) between scored frames, 1 to 90.
    #[arg(long, allow_negative_numbers = true, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=90))]
    every: u32,
    /// Per-eye width in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = 270)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = 300)]
    height: u32,
    /// Reference rays per traced pixel, 1..=65536.
    #[arg(long, allow_negative_numbers = true, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    rays: u32,
    /// Write the points as JSON here.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

pub(crate) fn run(backend: BackendChoice, args: TemporalArgs) -> Result<()> {
    if let Some(out) = &args.out {
        vrao::formats::output::check_output_file(out)?;
    }
    let default_scene = if args.motion { "builtin:moving" } else { "builtin:room" };
    let scene = Scene::load(args.scene.as_deref().unwrap_or(default_scene))?;
    let base = args.ao.eye_settings(&scene, args.width, args.height);
    if args.motion {
        let sequence = Sequence { start: args.start, scored: args.scored, every: args.every };
        let study = motion_study(backend, &scene, &base, sequence, args.rays, &default_cache_dir())?;
        println!(
            "'{}' moving from t = {} s, {} scored every {} at 90 Hz, {}x{} per eye, {} N={} r = {} m, on {}",
            scene.name,
            args.start,
            vrao::formats::output::count(u64::from(args.scored), "frame"),
            args.every,
            args.width,
            args.height,
            base.ao.technique.name(),
            base.ao.samples,
            vrao::formats::output::significant(base.ao.radius as f64, 3),
            study.adapter
        );
        print!("{}", motion::to_markdown(&study.points));
        return match &args.out {
            Some(path) => vrao::formats::output::write_json(path, &study.points),
            None => Ok(()),
        };
    }
    let study = study(backend, &scene, &base, args.rays, &default_cache_dir())?;
    println!(
        "AO RMSE against the reference ({} rays, every 2nd pixel) after k frames; '{}' at {}x{} per eye, {} r = {} m, on {}",
        args.rays,
        scene.name,
        args.width,
        args.height,
        base.ao.technique.name(),
        vrao::formats::output::significant(base.ao.radius as f64, 3),
        study.adapter
    );
    print!("{}", to_markdown(&study.points));
    match &args.out {
        Some(path) => vrao::formats::output::write_json(path, &study.points),
        None => Ok(()),
    }
}
