//! `vrao reprojection`: how far a warped frame is from a fresh render.

use super::{AoArgs, SCENE_HELP};
use clap::Args;
use std::path::PathBuf;
use vrao::measure::reprojection::{study, to_markdown};
use vrao::Result;
use vrao_render::{BackendChoice, HeadsetProfile, Scene};

#[derive(Args)]
pub(crate) struct ReprojectionArgs {
    #[arg(long, default_value = "builtin:room", help = SCENE_HELP)]
    scene: String,
    /// Per-eye width in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().width)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().height)]
    height: u32,
    /// Write the rows as JSON here.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

pub(crate) fn run(backend: BackendChoice, args: ReprojectionArgs) -> Result<()> {
    if let Some(out) = &args.out {
        vrao::formats::output::check_output_file(out)?;
    }
    let scene = Scene::load(&args.scene)?;
    let settings = args.ao.eye_settings(&scene, args.width, args.height);
    let (rows, adapter) = study(backend, &scene, &settings)?;
    // In a scene that moves the fresh frames are one frame period later (`study`): the
    // warp moves the eyes, not the objects.
    let late = if scene.is_animated() {
        format!(", {:.1} ms of scene time later (objects moved meanwhile)", 1e3 / settings.profile.refresh_hz)
    } else {
        String::new()
    };
    println!(
        "reprojection of '{}' at {}x{} per eye on {adapter}: RMSE of colour (0..1, both eyes) against a fresh render{late}",
        scene.name, args.width, args.height
    );
    print!("{}", to_markdown(&rows));
    match &args.out {
        Some(path) => vrao::formats::output::write_json(path, &rows),
        None => Ok(()),
    }
}
