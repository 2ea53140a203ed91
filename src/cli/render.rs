//! `vrao render`: both eyes of a scene as PNG files.

use super::{parse_vec3, AoArgs, SCENE_HELP};
use clap::Args;
use glam::DVec3;
use std::path::PathBuf;
use vrao::render::renderer::TimingChoice;
use vrao::render::scene::HeadPath;
use vrao::render::stereo::DEFAULT_IPD;
use vrao::render::still::{render_still, StillOptions};
use vrao::{BackendChoice, Error, HeadPose, HeadsetProfile, Result, Scene, Settings, StereoMode};

#[derive(Args)]
pub struct RenderArgs {
    #[arg(long, default_value = vrao::render::scene::RENDER_DEFAULT, help = SCENE_HELP)]
    scene: String,
    /// Output directory.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Also write depth, normals and albedo per eye.
    #[arg(long)]
    debug: bool,
    /// Print which passes ran and why the others were left out.
    #[arg(long)]
    explain: bool,
    /// Head position X,Y,Z in metres (overrides the scene's head pose; needs --look-at).
    // Hyphen values: "-13,1.8,-1" is a value, not a flag, although it is no single number.
    #[arg(long, value_parser = parse_vec3, requires = "look_at", allow_hyphen_values = true)]
    eye: Option<DVec3>,
    /// Point X,Y,Z the head looks at (needs --eye).
    #[arg(long, value_parser = parse_vec3, requires = "eye", allow_hyphen_values = true)]
    look_at: Option<DVec3>,
    /// Stereo G-buffer path: auto, multiview or multipass.
    #[arg(long, default_value = "auto", hide_possible_values = true)]
    stereo: StereoMode,
    /// Per-eye width in pixels (Vive-class default).
    #[arg(long, default_value_t = 1080)]
    width: u32,
    /// Per-eye height in pixels (Vive-class default).
    #[arg(long, default_value_t = 1200)]
    height: u32,
    /// Interpupillary distance in metres.
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_IPD)]
    ipd: f64,
    /// Linear exposure before tone mapping.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.0)]
    exposure: f32,
    /// Timing with --frames: pipelined (GPU timestamps), serial (also wall clock per
    /// pass) or auto (serial on CPU adapters, pipelined on GPUs).
    #[arg(long, default_value = "pipelined", hide_possible_values = true)]
    timing: TimingChoice,
    /// Render this many frames and report per-pass GPU medians (with --explain); the
    /// first frames are warm-up and not counted.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Reinhard white point (smallest exposed luminance shown as white).
    #[arg(long, allow_negative_numbers = true, default_value_t = 4.0)]
    white_point: f32,
    #[command(flatten)]
    ao: AoArgs,
}

pub fn run(backend: BackendChoice, args: RenderArgs) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    if let (Some(eye), Some(target)) = (args.eye, args.look_at) {
        let pose = HeadPose::look_at(eye, target)
            .ok_or_else(|| Error::input(format!("--eye and --look-at are the same point {eye}")))?;
        scene.head = HeadPath::fixed(pose);
    }
    let mut profile = HeadsetProfile::with_size("vive", args.width, args.height);
    profile.ipd = args.ipd;
    let settings = Settings {
        profile,
        stereo: args.stereo,
        exposure: args.exposure,
        white_point: args.white_point,
        ao: args.ao.settings(&scene),
        shadows: args.ao.lights.settings(&scene),
        ..Settings::default()
    };
    let options = StillOptions { backend, timing: args.timing, frames: args.frames, debug: args.debug, out: args.out };
    let still = render_still(&scene, &settings, &options)?;
    println!("{}", still.summary);
    if args.explain {
        print!("{}", still.explain);
    }
    for path in still.written {
        println!("wrote {}", path.display());
    }
    Ok(())
}
