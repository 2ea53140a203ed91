//! The `vrao` command line: a thin layer over the library.

use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use vrao::error::{Error, Result};
use vrao::settings::{AoSettings, Noise, Quality, Technique};
use vrao::stereo::HeadsetProfile;
use vrao::{BackendChoice, Gpu, HeadPose, Renderer, Resource, Scene, Settings, StereoMode};

#[derive(Parser)]
#[command(name = "vrao", version, about = "Stereo VR ambient-occlusion renderer (SSAO, HBAO, SSDO) on wgpu")]
struct Cli {
    /// Graphics backend: auto (a real GPU if present, else lavapipe), vulkan or gl.
    #[arg(long, global = true, default_value = "auto")]
    backend: BackendChoice,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Print the adapter, its driver, multiview and timestamp support, and key limits.
    Info,
    /// Render both eyes of a scene to left.png and right.png.
    Render(RenderArgs),
}

#[derive(Args)]
struct RenderArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME (plane, crease, room, sphere).
    #[arg(long, default_value = "builtin:room")]
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
    #[arg(long, value_parser = parse_vec3, requires = "look_at")]
    eye: Option<DVec3>,
    /// Point X,Y,Z the head looks at (needs --eye).
    #[arg(long, value_parser = parse_vec3, requires = "eye")]
    look_at: Option<DVec3>,
    /// Stereo G-buffer path: auto, multiview or multipass.
    #[arg(long, default_value = "auto")]
    stereo: StereoMode,
    /// Per-eye width in pixels (default: the Vive-class 1080).
    #[arg(long, default_value_t = 1080)]
    width: u32,
    /// Per-eye height in pixels (default: the Vive-class 1200).
    #[arg(long, default_value_t = 1200)]
    height: u32,
    /// Interpupillary distance in metres.
    #[arg(long, default_value_t = vrao::stereo::DEFAULT_IPD)]
    ipd: f64,
    /// Linear exposure before tone mapping.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Render this many frames and report per-pass GPU medians (with --explain); the
    /// first frames are warm-up and not counted.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Reinhard white point (smallest exposed luminance shown as white).
    #[arg(long, default_value_t = 4.0)]
    white_point: f32,
    #[command(flatten)]
    ao: AoArgs,
}

/// Occlusion options (shared by every command that renders).
#[derive(Args, Clone)]
struct AoArgs {
    /// Occlusion technique: none, ssao, hbao, ssdo or ssdo-bounce.
    #[arg(long, default_value = "ssao")]
    technique: Technique,
    /// Sampling preset: low, medium, high or ultra (N = 12, 24, 36, 64 depth taps).
    #[arg(long, default_value = "medium")]
    quality: Quality,
    /// Depth taps per pixel, 1..=256 (overrides --quality).
    #[arg(long)]
    samples: Option<u32>,
    /// Occlusion radius in metres (default: 8 % of the scene's diagonal, within 0.01..=1 m).
    #[arg(long)]
    radius: Option<f32>,
    /// Occlusion weight, 0..=4 (1 = full occlusion).
    #[arg(long, default_value_t = 1.0)]
    strength: f32,
    /// Depth bias as a fraction of the radius.
    #[arg(long, default_value_t = 0.02)]
    bias: f32,
    /// SSDO bounce strength (ssdo-bounce); 0 leaves the bounce out.
    #[arg(long, default_value_t = 1.0)]
    bounce: f32,
    /// Compute occlusion at half resolution per axis and upsample it.
    #[arg(long)]
    half_res: bool,
    /// Bilateral blur radius in pixels (5 = 11×11); 0 turns the blur off.
    #[arg(long, default_value_t = 5)]
    blur: u32,
    /// Kernel rotation per pixel: halton (per-pixel low-discrepancy) or tiled (5×5 tile).
    #[arg(long, default_value = "halton")]
    noise: Noise,
    /// Turn SSAO's range check (depth constraint) off.
    #[arg(long)]
    no_range_check: bool,
}

impl AoArgs {
    fn settings(&self, scene: &Scene) -> AoSettings {
        AoSettings {
            technique: self.technique,
            samples: self.samples.unwrap_or(self.quality.samples()),
            radius: self.radius.unwrap_or_else(|| scene.suggested_ao_radius()),
            strength: self.strength,
            bias: self.bias,
            range_check: !self.no_range_check,
            bounce: self.bounce,
            noise: self.noise,
            half_res: self.half_res,
            blur_radius: self.blur,
        }
    }
}

fn parse_vec3(s: &str) -> std::result::Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("'{s}' is not X,Y,Z"));
    }
    let mut v = [0.0; 3];
    for (slot, part) in v.iter_mut().zip(&parts) {
        *slot = part.parse::<f64>().map_err(|_| format!("'{part}' in '{s}' is not a number"))?;
        if !slot.is_finite() {
            return Err(format!("'{part}' in '{s}' is not finite"));
        }
    }
    Ok(DVec3::from_array(v))
}

fn info(backend: BackendChoice) -> Result<()> {
    let gpu = Gpu::new(backend)?;
    println!("{}", gpu.describe());
    Ok(())
}

fn render(backend: BackendChoice, args: RenderArgs) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    if let (Some(eye), Some(target)) = (args.eye, args.look_at) {
        let pose = HeadPose::look_at(eye, target)
            .ok_or_else(|| Error::input(format!("--eye and --look-at are the same point {eye}")))?;
        scene.head = vrao::scene::HeadPath::fixed(pose);
    }
    let mut profile = HeadsetProfile::with_size("vive", args.width, args.height);
    profile.ipd = args.ipd;
    let settings = Settings {
        profile,
        stereo: args.stereo,
        exposure: args.exposure,
        white_point: args.white_point,
        ao: args.ao.settings(&scene),
        ..Settings::default()
    };
    settings.validate()?;
    let gpu = Arc::new(Gpu::new(backend)?);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings)?;
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let mut outputs = vec![Resource::Color];
    if args.debug {
        outputs.extend([Resource::Depth, Resource::Normals, Resource::Albedo]);
        outputs.extend(vrao::output::occlusion_outputs(&settings));
    }
    // Warm-up frames (pipeline compilation, first-touch allocation) are not measured.
    let warmup = if args.frames > 1 { (args.frames / 10).clamp(1, 10) } else { 0 };
    let mut timings = Vec::new();
    let mut report = None;
    for frame in 0..warmup + args.frames {
        let r = renderer.render(&eyes.eyes, &outputs)?;
        if frame >= warmup {
            timings.push(r.gpu_ms.clone());
            timings.last_mut().unwrap().push(("cpu encode".into(), r.cpu_encode_ms));
        }
        report = Some(r);
    }
    let report = report.expect("at least one frame");
    let written = vrao::output::write_images(&renderer, &args.out, 2, args.debug)?;
    println!(
        "rendered '{}' ({} triangles) on {}: {}x{} per eye, {} G-buffer, {} N={} r={} m{}",
        scene.name,
        scene.triangle_count(),
        gpu.adapter.get_info().name,
        settings.profile.width,
        settings.profile.height,
        if renderer.uses_multiview() { "multiview" } else { "multipass" },
        settings.ao.technique.name(),
        settings.ao.samples,
        settings.ao.radius,
        if settings.ao.half_res { ", half resolution" } else { "" },
    );
    if args.explain {
        print!("{}", report.plan);
        let adapter = gpu.adapter.get_info();
        println!(
            "timing over {} frame(s) after {warmup} warm-up, {} ({:?}):",
            args.frames, adapter.name, adapter.backend
        );
        println!("  {:<18} {:>10} {:>10} {:>10}", "span", "median ms", "p25 ms", "p75 ms");
        for s in vrao::gpu::timing::summarize(&timings) {
            println!("  {:<18} {:>10.3} {:>10.3} {:>10.3}", s.label, s.median_ms, s.p25_ms, s.p75_ms);
        }
        if report.gpu_ms.is_empty() {
            println!("  (this adapter has no timestamp queries: GPU times are not available)");
        }
    }
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Info) => info(cli.backend),
        Some(Command::Render(args)) => render(cli.backend, args),
        None => {
            use clap::CommandFactory;
            let _ = Cli::command().print_help();
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
