//! `vrao render`: both eyes of a scene as PNG files.

use super::{choice, parse_vec3, AoArgs, SCENE_HELP};
use clap::Args;
use glam::DVec3;
use std::path::PathBuf;
use vrao::formats::output::OutputTrail;
use vrao::formats::still::{render_still, StillOptions};
use vrao::{Error, Result};
use vrao_ao::HeadPose;
use vrao_render::renderer::TimingChoice;
use vrao_render::scene::HeadPath;
use vrao_render::settings::{DEFAULT_EXPOSURE, DEFAULT_WHITE_POINT};
use vrao_render::{BackendChoice, HeadsetProfile, Scene, Settings, StereoMode};

#[derive(Args)]
pub(crate) struct RenderArgs {
    #[arg(long, default_value = vrao_render::scene::RENDER_DEFAULT, help = SCENE_HELP)]
    scene: String,
    /// Output directory.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Also write depth, normals and albedo per eye, and the right eye with the pixels its
    /// march computed (not taken from the left eye) in red: marched_right.png.
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
    #[arg(value_parser = choice::<StereoMode>(), long, default_value_t = StereoMode::default(), hide_possible_values = true)]
    stereo: StereoMode,
    /// Per-eye width in pixels, 1..=8192 (Vive-class default).
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().width)]
    width: u32,
    /// Per-eye height in pixels, 1..=8192 (Vive-class default).
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().height)]
    height: u32,
    /// Interpupillary distance in metres.
    #[arg(long, allow_negative_numbers = true, default_value_t = HeadsetProfile::vive().ipd)]
    ipd: f64,
    /// Linear exposure before tone mapping.
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_EXPOSURE)]
    exposure: f32,
    /// Timing with --frames: pipelined (GPU timestamps), serial (also wall clock per
    /// pass) or auto (serial on CPU adapters, pipelined on GPUs).
    #[arg(value_parser = choice::<TimingChoice>(), long, default_value = "pipelined", hide_possible_values = true)]
    timing: TimingChoice,
    /// Render this many frames and report per-pass GPU medians (with --explain); the
    /// first frames are warm-up and not counted. 1..=100000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Scene time in seconds (0 to 1e6): where animated objects and a scripted head are.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0, value_parser = super::parse_scene_time)]
    time: f64,
    /// Reinhard white point (smallest exposed luminance shown as white).
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_WHITE_POINT)]
    white_point: f32,
    #[command(flatten)]
    ao: AoArgs,
}

impl RenderArgs {
    /// The settings these options give for `scene`.
    fn settings(&self, scene: &Scene) -> Settings {
        let mut profile = HeadsetProfile::with_size("vive", self.width, self.height);
        profile.ipd = self.ipd;
        Settings {
            profile,
            stereo: self.stereo,
            exposure: self.exposure,
            white_point: self.white_point,
            ao: self.ao.settings(scene),
            point_ssdo: self.ao.point_ssdo(),
            shadows: self.ao.lights.settings(scene),
            ..Settings::default()
        }
    }
}

pub(crate) fn run(backend: BackendChoice, args: RenderArgs) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    if let (Some(eye), Some(target)) = (args.eye, args.look_at) {
        let pose = HeadPose::look_at(eye, target)
            .ok_or_else(|| Error::input(format!("--eye and --look-at are the same point {eye}")))?;
        scene.head = HeadPath::fixed(pose);
    }
    let settings = args.settings(&scene);
    // Ctrl-C or SIGTERM stops the render and takes away what it wrote (a second one
    // while it does so removes it at once): an interrupted render leaves nothing behind.
    let trail = OutputTrail::new();
    let cleanup = trail.clone();
    let interrupt = super::interrupt_on_signals("stopping; what was written is removed", move || cleanup.remove_all());
    let options = StillOptions {
        backend,
        timing: args.timing,
        frames: args.frames,
        debug: args.debug,
        out: args.out,
        time: args.time,
        trail: trail.interruptible(interrupt),
        // As `vrao run` and the bench take it from the simulated headset's profile.
        mask: settings.ao.mask.then(|| vrao::xr::profiles::visibility_mask(&settings.profile)),
    };
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    /// `vrao render`'s options alone, parsed as the subcommand parses them.
    #[derive(Parser)]
    struct Render {
        #[command(flatten)]
        args: RenderArgs,
    }

    #[test]
    fn render_with_no_options_uses_the_library_defaults() {
        let args = Render::try_parse_from(["render"]).unwrap().args;
        assert_eq!(args.scene, vrao_render::scene::RENDER_DEFAULT);
        let scene = Scene::load(&args.scene).unwrap();
        assert_eq!(args.settings(&scene), Settings::default());
        assert_eq!(Settings::default().ao.technique, vrao_ao::Technique::Gtao);
    }

    #[test]
    fn the_technique_help_is_the_engines_table() {
        use clap::CommandFactory;
        let command = Render::command();
        let technique = command.get_arguments().find(|a| a.get_id() == "technique").unwrap();
        let help = technique.get_help().unwrap().to_string();
        assert_eq!(help, format!("Occlusion technique: {}", vrao_ao::Technique::help_list()));
        for t in vrao_ao::Technique::all() {
            assert!(help.contains(t.name()), "{} missing from {help}", t.name());
        }
    }

    #[test]
    fn render_options_reach_the_settings() {
        let line = "render --quality ultra --half-res --radius 0.25 --technique hbao --temporal";
        let args = Render::try_parse_from(line.split(' ')).unwrap().args;
        let settings = args.settings(&Scene::load(&args.scene).unwrap());
        let ao = &settings.ao;
        assert_eq!(
            (ao.samples, ao.layers, ao.resolution.is_half(), ao.radius, ao.technique),
            (64, 2, true, 0.25, vrao_ao::Technique::Hbao)
        );
        assert!(ao.temporal.enabled);
        assert_ne!(settings, Settings::default());
        // --layers overrides the preset's; the default preset reads one layer.
        for (line, layers) in [("render --quality ultra --layers 1", 1), ("render", 1), ("render --layers 2", 2)] {
            let args = Render::try_parse_from(line.split(' ')).unwrap().args;
            assert_eq!(args.settings(&Scene::load(&args.scene).unwrap()).ao.layers, layers, "{line}");
        }
    }
}
