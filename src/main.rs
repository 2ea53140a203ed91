//! The `vrao` command line: a thin layer over the library.

use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use vrao::error::{Error, Result};
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
        ..Settings::default()
    };
    settings.validate()?;
    let gpu = Arc::new(Gpu::new(backend)?);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings)?;
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let mut outputs = vec![Resource::Color];
    if args.debug {
        outputs.extend([Resource::Depth, Resource::Normals, Resource::Albedo]);
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
        "rendered '{}' ({} triangles) on {}: {}x{} per eye, {} G-buffer",
        scene.name,
        scene.triangle_count(),
        gpu.adapter.get_info().name,
        settings.profile.width,
        settings.profile.height,
        if renderer.uses_multiview() { "multiview" } else { "multipass" }
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
