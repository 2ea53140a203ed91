//! `vrao temporal`: how temporal accumulation converges next to spatial-only settings.

use super::{AoArgs, SCENE_HELP};
use clap::Args;
use std::path::PathBuf;
use vrao::measure::reference::default_cache_dir;
use vrao::measure::temporal::{study, to_markdown};
use vrao::{BackendChoice, Result, Scene};

#[derive(Args)]
pub struct TemporalArgs {
    #[arg(long, default_value = "builtin:room", help = SCENE_HELP)]
    scene: String,
    /// Per-eye width in pixels, 1..=8192.
    #[arg(long, default_value_t = 270)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192.
    #[arg(long, default_value_t = 300)]
    height: u32,
    /// Reference rays per traced pixel, 1..=65536.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    rays: u32,
    /// Write the points as JSON here.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

pub fn run(backend: BackendChoice, args: TemporalArgs) -> Result<()> {
    if let Some(out) = &args.out {
        vrao::render::output::check_output_file(out)?;
    }
    let scene = Scene::load(&args.scene)?;
    let base = args.ao.eye_settings(&scene, args.width, args.height);
    let study = study(backend, &scene, &base, args.rays, &default_cache_dir())?;
    println!(
        "AO RMSE against the reference ({} rays, every 2nd pixel) after k frames; '{}' at {}x{} per eye, {} r = {} m, on {}",
        args.rays,
        scene.name,
        args.width,
        args.height,
        base.ao.technique.name(),
        vrao::render::output::significant(base.ao.radius as f64, 3),
        study.adapter
    );
    print!("{}", to_markdown(&study.points));
    match &args.out {
        Some(path) => vrao::render::output::write_json(path, &study.points),
        None => Ok(()),
    }
}
