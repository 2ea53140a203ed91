//! The `vrao` command line: a thin layer over the library.

use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use vrao::error::{Error, Result};
use vrao::renderer::Timing;
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
    /// Sweep technique × samples × radius × resolution: median GPU ms per eye per pass.
    Bench(BenchArgs),
}

#[derive(Args)]
struct BenchArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME.
    #[arg(long, default_value = "builtin:room")]
    scene: String,
    /// Techniques to sweep, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "ssao,hbao,ssdo,ssdo-bounce")]
    techniques: Vec<Technique>,
    /// Sample counts, comma-separated (seed 003's grid by default).
    #[arg(long, value_delimiter = ',', default_value = "12,24,36,64")]
    samples: Vec<u32>,
    /// Radii in metres, comma-separated (default: the scene's radius × 0.5, 1, 2).
    #[arg(long, value_delimiter = ',')]
    radii: Vec<f32>,
    /// Resolutions: full, half or both.
    #[arg(long, default_value = "both")]
    resolution: String,
    /// Measured frames per case, after warm-up.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Warm-up frames per case (not measured).
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Per-eye width in pixels.
    #[arg(long, default_value_t = 1080)]
    width: u32,
    /// Per-eye height in pixels.
    #[arg(long, default_value_t = 1200)]
    height: u32,
    /// Timing: pipelined (one submission per frame, GPU timestamps), serial (one
    /// submission per pass, wall clock) or auto (serial on CPU adapters such as lavapipe,
    /// whose timestamps misattribute work between passes; pipelined on GPUs).
    #[arg(long, default_value = "auto")]
    timing: TimingArg,
    /// Output directory for bench.csv and bench.md.
    #[arg(long, default_value = "bench")]
    out: PathBuf,
}

#[derive(Args)]
struct RenderArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME (plane, crease, room, sphere, box).
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
    /// Per-eye width in pixels (Vive-class default).
    #[arg(long, default_value_t = 1080)]
    width: u32,
    /// Per-eye height in pixels (Vive-class default).
    #[arg(long, default_value_t = 1200)]
    height: u32,
    /// Interpupillary distance in metres.
    #[arg(long, allow_negative_numbers = true, default_value_t = vrao::stereo::DEFAULT_IPD)]
    ipd: f64,
    /// Linear exposure before tone mapping.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.0)]
    exposure: f32,
    /// Timing with --frames: pipelined (GPU timestamps), serial (also wall clock per
    /// pass) or auto (serial on CPU adapters, pipelined on GPUs).
    #[arg(long, default_value = "pipelined")]
    timing: TimingArg,
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

/// Occlusion options (shared by every command that renders).
#[derive(Args, Clone)]
struct AoArgs {
    /// Occlusion technique: none, ssao, hbao, ssdo or ssdo-bounce (fetch-only: the
    /// benchmark baseline with SSAO's depth taps and no occlusion arithmetic).
    #[arg(long, default_value = "ssao")]
    technique: Technique,
    /// Sampling preset: low, medium, high or ultra (N = 12, 24, 36, 64 depth taps).
    #[arg(long, default_value = "medium")]
    quality: Quality,
    /// Depth taps per pixel, 1..=256 (overrides --quality).
    #[arg(long)]
    samples: Option<u32>,
    /// Occlusion radius in metres (default: 8 % of the scene's diagonal, within 0.01..=1 m).
    #[arg(long, allow_negative_numbers = true)]
    radius: Option<f32>,
    /// Occlusion weight, 0..=4 (1 = full occlusion).
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.0)]
    strength: f32,
    /// Depth bias as a fraction of the radius.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.02)]
    bias: f32,
    /// SSDO bounce strength (ssdo-bounce); 0 leaves the bounce out.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.0)]
    bounce: f32,
    /// Compute occlusion at half resolution per axis and upsample it.
    #[arg(long)]
    half_res: bool,
    /// Bilateral blur radius in full-resolution pixels (5 = 11×11); 0 turns the blur off.
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

/// `--timing`: a mode, or `auto` (decided once the adapter is known).
#[derive(Clone, Copy)]
struct TimingArg(Option<Timing>);

impl std::str::FromStr for TimingArg {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "auto" => Ok(TimingArg(None)),
            "pipelined" => Ok(TimingArg(Some(Timing::Pipelined))),
            "serial" => Ok(TimingArg(Some(Timing::Serial))),
            other => Err(format!("unknown timing '{other}' (expected auto, pipelined or serial)")),
        }
    }
}

impl TimingArg {
    /// `auto` is serial on CPU adapters, whose timestamps between passes in one
    /// submission credit work to the wrong pass (lavapipe 22.x), and pipelined elsewhere.
    fn resolve(self, gpu: &Gpu) -> Timing {
        self.0.unwrap_or(if gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
            Timing::Serial
        } else {
            Timing::Pipelined
        })
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
    renderer.set_timing(args.timing.resolve(&gpu));
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
            let mut spans = r.gpu_ms.clone();
            spans.extend(r.wall_ms.iter().map(|(pass, ms)| (format!("{pass} (wall)"), *ms)));
            spans.push(("cpu encode".into(), r.cpu_encode_ms));
            timings.push(spans);
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
        println!("  {:<22} {:>10} {:>10} {:>10}", "span", "median ms", "p25 ms", "p75 ms");
        for s in vrao::gpu::timing::summarize(&timings) {
            println!("  {:<22} {:>10.3} {:>10.3} {:>10.3}", s.label, s.median_ms, s.p25_ms, s.p75_ms);
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

fn bench(backend: BackendChoice, args: BenchArgs) -> Result<()> {
    use vrao::bench::{sweep, to_csv, to_markdown, BenchCase, Measurement};
    let scene = Scene::load(&args.scene)?;
    let resolutions: &[bool] = match args.resolution.as_str() {
        "full" => &[false],
        "half" => &[true],
        "both" => &[false, true],
        other => return Err(Error::input(format!("--resolution '{other}' is not full, half or both"))),
    };
    let base_radius = scene.suggested_ao_radius();
    let radii = if args.radii.is_empty() {
        vec![base_radius * 0.5, base_radius, base_radius * 2.0]
    } else {
        args.radii.clone()
    };
    let settings =
        Settings { profile: HeadsetProfile::with_size("vive", args.width, args.height), ..Settings::default() };
    let mut cases = Vec::new();
    for &technique in &args.techniques {
        for &samples in &args.samples {
            for &radius in &radii {
                for &half_res in resolutions {
                    cases.push(BenchCase { technique, samples, radius, half_res });
                }
            }
        }
    }
    for case in &cases {
        let mut s = settings.clone();
        (s.ao.technique, s.ao.samples, s.ao.radius, s.ao.half_res) =
            (case.technique, case.samples, case.radius, case.half_res);
        s.validate()?;
        if case.technique == Technique::None {
            return Err(Error::input("--techniques: none has no occlusion to measure"));
        }
    }
    let gpu = Arc::new(Gpu::new(backend)?);
    let info = gpu.adapter.get_info();
    let timing = args.timing.resolve(&gpu);
    eprintln!(
        "bench: {} cases on '{}' ({}), {}x{} per eye, {} frames each, {timing:?} timing",
        cases.len(),
        scene.name,
        info.name,
        args.width,
        args.height,
        args.frames
    );
    let started = std::time::Instant::now();
    let rows = sweep(
        &gpu,
        &scene,
        &settings,
        &cases,
        Measurement { timing, warmup: args.warmup, frames: args.frames },
        |done, total, row| {
            let elapsed = started.elapsed().as_secs_f64();
            let eta = elapsed / done as f64 * (total - done) as f64;
            eprintln!(
            "[{done:>3}/{total}] {:<12} N={:<3} r={:<7} {:<4} {:>9.3} ms/eye   (elapsed {elapsed:.0} s, eta {eta:.0} s)",
            row.case.technique.name(),
            row.case.samples,
            row.case.radius,
            if row.case.half_res { "half" } else { "full" },
            row.occlusion_ms_per_eye()
        );
        },
    )?;
    std::fs::create_dir_all(&args.out).map_err(|e| Error::Output { path: args.out.clone(), message: e.to_string() })?;
    for (name, text) in [("bench.csv", to_csv(&rows)), ("bench.md", to_markdown(&rows))] {
        let path = args.out.join(name);
        std::fs::write(&path, text).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })?;
    }
    println!("{}", to_markdown(&rows));
    println!(
        "adapter: {} ({:?}, {}); wrote {}/bench.csv and bench.md",
        info.name,
        info.backend,
        info.driver_info,
        args.out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    // Mesa's Vulkan drivers probe for a Wayland display and print "error: XDG_RUNTIME_DIR
    // is invalid" on headless machines although nothing is wrong; give the probe a
    // directory to look in (it then finds no display, quietly).
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Info) => info(cli.backend),
        Some(Command::Render(args)) => render(cli.backend, args),
        Some(Command::Bench(args)) => bench(cli.backend, args),
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
