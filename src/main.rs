//! The `vrao` command line: a thin layer over the library.

use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use vrao::render::error::{Error, Result};
use vrao::render::renderer::Timing;
use vrao::render::settings::{AoSettings, Noise, Quality, Technique};
use vrao::render::stereo::HeadsetProfile;
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
    /// Sweep technique × samples × radius × resolution: median ms per eye per pass and
    /// error against the reference tracer; writes CSV, JSON, Markdown and a PNG plot.
    Bench(BenchArgs),
    /// Run a headset session: OpenXR when a runtime is present, otherwise the simulated
    /// headset; with a desktop window for --display mirror or single-pass.
    Run(RunArgs),
    /// Reprojection quality: warp a frame to moved head poses (rotations 1–10°,
    /// translations 1–10 cm) in both modes and compare with fresh renders.
    Reprojection(ReprojectionArgs),
    /// Temporal accumulation: AO error against the reference after 1, 2, 4, 8 and 16
    /// frames (static head and yaw sweep) next to spatial-only settings.
    Temporal(TemporalArgs),
    /// Headless per-eye budget test: per-pass medians against the frame budget; exit 0
    /// within budget, 3 over it.
    Budget(BudgetArgs),
}

#[derive(Args)]
struct RunArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME.
    #[arg(long, default_value = "builtin:room")]
    scene: String,
    /// Headset: auto (OpenXR if a runtime answers, else simulated), openxr or simulated.
    #[arg(long, default_value = "auto")]
    headset: vrao::app::HeadsetChoice,
    /// Desktop window: none, mirror (both eyes side by side) or single-pass (mono view).
    #[arg(long, default_value = "mirror")]
    display: vrao::render::settings::DisplayMode,
    /// Stop after this many frames (default: until the window is closed; 600 without one).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Simulated head motion: static, yaw-sweep, figure-eight or head-roll.
    #[arg(long, default_value = "static")]
    motion: vrao::xr::simulated::motion::HeadMotion,
    /// Simulated compositor reprojection: rotational or depth.
    #[arg(long, default_value = "depth")]
    reprojection: vrao::xr::simulated::reproject::ReprojectionMode,
    /// Run the simulated headset in virtual time, each frame taking these render times
    /// in ms (cycled): deterministic counters.
    #[arg(long, value_delimiter = ',')]
    virtual_time: Vec<f64>,
    /// Headset profile of the simulated headset: vive, vive-pro-2, index, quest-2,
    /// quest-3 or pico-4 (per-eye size, field of view, refresh rate; the frame budget
    /// follows the rate). An OpenXR runtime's recommended size and views win over it.
    #[arg(long, default_value = "vive")]
    profile: String,
    /// Refresh rate in Hz, one the profile supports (default: the profile's).
    #[arg(long)]
    refresh: Option<f64>,
    /// Per-eye width to render at (default: the profile's; with OpenXR, the runtime's).
    #[arg(long)]
    width: Option<u32>,
    /// Per-eye height to render at (default: the profile's; with OpenXR, the runtime's).
    #[arg(long)]
    height: Option<u32>,
    /// Budget governor: on (choose the AO setting by error per millisecond so that each
    /// frame's GPU time stays under the display period) or off (keep the settings).
    #[arg(long, default_value = "on")]
    governor: OnOff,
    /// The governor's frontier: a bench JSON made by `vrao bench` (default: the built-in
    /// one, measured on the furnished room; see assets/governor/README.md).
    #[arg(long)]
    governor_frontier: Option<PathBuf>,
    /// Frames the GPU may work on at once.
    #[arg(long, default_value_t = vrao::render::renderer::DEFAULT_FRAMES_IN_FLIGHT as u64, value_parser = clap::value_parser!(u64).range(1..=8))]
    frames_in_flight: u64,
    /// Window size WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    window: String,
    /// Save a screenshot of the window to this PNG after the last frame.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// What the window shows of each eye: eyes, ao (the final AO), raw-ao (before any
    /// filter), depth or normals; the panel can change it.
    #[arg(long, default_value = "eyes")]
    show: vrao::app::BufferView,
    /// Write the frame counters and per-pass medians to this JSON file.
    #[arg(long)]
    report: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

#[derive(Args)]
struct ReprojectionArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME.
    #[arg(long, default_value = "builtin:room")]
    scene: String,
    /// Per-eye width in pixels.
    #[arg(long, default_value_t = 1080)]
    width: u32,
    /// Per-eye height in pixels.
    #[arg(long, default_value_t = 1200)]
    height: u32,
    /// Write the rows as JSON here.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

#[derive(Args)]
struct TemporalArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME.
    #[arg(long, default_value = "builtin:room")]
    scene: String,
    /// Per-eye width in pixels.
    #[arg(long, default_value_t = 270)]
    width: u32,
    /// Per-eye height in pixels.
    #[arg(long, default_value_t = 300)]
    height: u32,
    /// Reference rays per traced pixel.
    #[arg(long, default_value_t = 256)]
    rays: u32,
    /// Write the points as JSON here.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    ao: AoArgs,
}

#[derive(Args)]
struct BudgetArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME.
    #[arg(long, default_value = "builtin:room")]
    scene: String,
    /// Per-eye width in pixels.
    #[arg(long, default_value_t = 1080)]
    width: u32,
    /// Per-eye height in pixels.
    #[arg(long, default_value_t = 1200)]
    height: u32,
    /// Measured frames (each: the stereo frame, then each eye alone), after warm-up.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Warm-up frames (not measured).
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Budget of one stereo frame in ms (default: the headset's refresh interval, 11.1 ms
    /// at 90 Hz); each eye gets half.
    #[arg(long, allow_negative_numbers = true)]
    budget_ms: Option<f64>,
    /// What each frame produces: frame (the eye colour, every pass) or occlusion (the
    /// occlusion passes alone).
    #[arg(long, default_value = "frame")]
    measure: String,
    /// Timing: pipelined, serial or auto (serial on CPU adapters).
    #[arg(long, default_value = "auto")]
    timing: TimingArg,
    /// Pick the occlusion setting from this bench JSON (made by `vrao bench` on this
    /// device) with the least error that fits the budget, then measure it.
    #[arg(long)]
    fit: Option<PathBuf>,
    /// Where to write the JSON report.
    #[arg(long, default_value = "budget.json")]
    out: PathBuf,
    #[command(flatten)]
    ao: AoArgs,
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
    /// SSDO depth peeling: off, on or both (each SSDO case with and without; other
    /// techniques never peel).
    #[arg(long, default_value = "off")]
    depth_peeling: String,
    /// Temporal accumulation: off, on or both (the error of a temporal row is its
    /// converged value after warm-up + frames with a static head).
    #[arg(long, default_value = "off")]
    temporal: String,
    /// Also measure reflective shadow maps (one bounce of the directional lights) with
    /// these VPL counts, comma-separated, gathering within each radius: rows "rsm", whose
    /// error against the reference's bounce (bounce_rel_rmse, bounce_rel_bias) is also
    /// given for ssdo-bounce rows.
    #[arg(long, value_delimiter = ',')]
    rsm_samples: Vec<u32>,
    /// Measured frames per case, after warm-up.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Warm-up frames per case (not measured).
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// How ssdo-bounce rows weigh their senders: direction or patch (seed 002 eq. 2).
    #[arg(long, default_value = "direction")]
    bounce_form: vrao::render::settings::BounceForm,
    #[command(flatten)]
    gtao: GtaoArgs,
    /// Spatial denoise of every row: tile (edge-aware, 5 taps per axis over the 4×4 noise tile) or bilateral (11×11 at --blur 5).
    #[arg(long, default_value = "tile")]
    denoise: vrao::render::settings::Denoise,
    /// Bilateral blur radius in full-resolution pixels; 0 turns any denoise off.
    #[arg(long, default_value_t = 5)]
    blur: u32,
    /// Measure this many cases at a time, round-robin one frame each, so that the
    /// machine's drift during a long sweep falls on all of them alike (fair ratios
    /// between techniques); each needs its own targets in memory at once.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    interleave: u32,
    /// Render whole frames (direct light and composite too), not only the occlusion: the
    /// composite is timed, and each half-resolution row gets the cost of upsampling as a
    /// frame pays it, inline in the composite (its composite minus the full-resolution
    /// row's; sweep --resolution both, ideally interleaved).
    #[arg(long)]
    frame: bool,
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
    /// Output directory for bench.csv, bench.json, bench.md and bench.png.
    #[arg(long, default_value = "bench")]
    out: PathBuf,
    /// Reference rays per traced pixel (cosine-weighted, stratified).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    rays: u32,
    /// Trace the reference at every STRIDE-th pixel in x and y (errors are measured there).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    stride: u32,
    /// Skip the reference: time only, no error columns.
    #[arg(long)]
    no_reference: bool,
    /// Directory of cached reference images (default: $XDG_CACHE_HOME/vrao or ~/.cache/vrao).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Budget per stereo frame in ms for the plot's budget line (each eye gets half).
    #[arg(long, default_value_t = 1000.0 / 90.0)]
    budget_ms: f64,
    /// Measure nothing: rewrite the table, CSV, Markdown and plots of this bench.json
    /// (Pareto fronts recomputed) into --out.
    #[arg(long)]
    replot: Option<PathBuf>,
}

#[derive(Args)]
struct RenderArgs {
    /// A scene file (.toml), a bare .obj, or builtin:NAME (plane, crease, room, sphere, box,
    /// furnished, columns, flipped-normals).
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
    #[arg(long, allow_negative_numbers = true, default_value_t = vrao::render::stereo::DEFAULT_IPD)]
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

/// Shadow options for directional lights (part of every command that renders).
const SHADOW_HEADING: &str = "Shadows and reflective shadow maps";

#[derive(Args, Clone)]
struct LightArgs {
    /// Shadow maps with 3×3 PCF for the directional lights: on or off (a scene with no
    /// directional light has none either way).
    #[arg(long, help_heading = SHADOW_HEADING, default_value = "on")]
    #[arg(value_parser = parse_on_off, action = clap::ArgAction::Set)]
    shadows: bool,
    /// Texels along each side of the square light-space maps.
    #[arg(long, help_heading = SHADOW_HEADING, default_value_t = 2048)]
    shadow_size: u32,
    /// One bounce of the directional lights from reflective shadow maps: on or off.
    #[arg(long, help_heading = SHADOW_HEADING, default_value = "off")]
    #[arg(value_parser = parse_on_off, action = clap::ArgAction::Set)]
    rsm: bool,
    /// Virtual point lights gathered per pixel and light by the reflective shadow maps.
    #[arg(long, help_heading = SHADOW_HEADING, default_value_t = 64)]
    rsm_samples: u32,
    /// RSM gather radius in metres (default: a quarter of the scene's diagonal, within 0.1..=4 m).
    #[arg(long, help_heading = SHADOW_HEADING, allow_negative_numbers = true)]
    rsm_radius: Option<f32>,
}

impl LightArgs {
    fn settings(&self, scene: &Scene) -> vrao::render::settings::ShadowSettings {
        vrao::render::settings::ShadowSettings {
            enabled: self.shadows,
            size: self.shadow_size,
            rsm: self.rsm,
            rsm_samples: self.rsm_samples,
            rsm_radius: self.rsm_radius.unwrap_or_else(|| vrao::render::passes::shadow::suggested_rsm_radius(scene)),
        }
    }
}

fn parse_on_off(s: &str) -> std::result::Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        other => Err(format!("'{other}' is not on or off")),
    }
}

/// GTAO's free parameters (the render commands and the bench).
#[derive(Args, Clone)]
struct GtaoArgs {
    /// GTAO: the slab behind each depth sample that counts as solid, as a fraction of the
    /// radius (thin objects stop occluding behind themselves).
    #[arg(long, allow_negative_numbers = true, default_value_t = vrao::render::settings::DEFAULT_THICKNESS)]
    thickness: f32,
    /// GTAO: the samples' spread along a half-slice, 1..=2 (1 even, 2 quadratic: crowded
    /// near the pixel).
    #[arg(long, allow_negative_numbers = true, default_value_t = vrao::render::settings::DEFAULT_STEP_POWER)]
    step_power: f32,
    /// GTAO: successive samples closer in distance than this fraction of the radius
    /// join into one surface (0: never).
    #[arg(long, allow_negative_numbers = true, default_value_t = vrao::render::settings::DEFAULT_CONNECT)]
    connect: f32,
    /// Compute both eyes on their own; by default the right eye takes the left eye's value
    /// wherever the left eye sees the same surface point (GTAO's march; at half resolution
    /// every technique's denoise, and the upsampled AO of all but SSDO).
    #[arg(long)]
    independent_eyes: bool,
}

impl GtaoArgs {
    fn apply(&self, ao: &mut AoSettings) {
        (ao.thickness, ao.step_power, ao.connect) = (self.thickness, self.step_power, self.connect);
        ao.stereo_reuse = !self.independent_eyes;
    }
}

/// Occlusion options (shared by every command that renders).
#[derive(Args, Clone)]
struct AoArgs {
    #[command(flatten)]
    lights: LightArgs,
    /// Occlusion technique: none, ssao, hbao, gtao (the default: the most accurate per
    /// millisecond), ssdo or ssdo-bounce (fetch-only: the benchmark baseline with SSAO's
    /// depth taps and no occlusion arithmetic).
    #[arg(long, default_value = "gtao")]
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
    /// How the bounce weighs a blocking sample's sender: direction (its solid angle 2π/N ×
    /// the receiver cosine) or patch (seed 002 eq. 2: area π r²/N, both cosines, 1/d²).
    #[arg(long, default_value = "direction")]
    bounce_form: vrao::render::settings::BounceForm,
    /// Compute occlusion at half resolution per axis and upsample it.
    #[arg(long)]
    half_res: bool,
    /// SSDO quality mode (seed 002 §4): peel a second depth layer per eye; a sample then
    /// occludes only inside an object (between the layers), which removes the halos of
    /// thin objects in front of a background. Assumes closed geometry.
    #[arg(long)]
    depth_peeling: bool,
    /// Spatial denoise: tile (edge-aware, 5 taps per axis over the 4×4 noise tile) or
    /// bilateral (separable, --blur px either side).
    #[arg(long, default_value = "tile")]
    denoise: vrao::render::settings::Denoise,
    /// Bilateral blur radius in full-resolution pixels (5 = 11×11); 0 turns any denoise off.
    #[arg(long, default_value_t = 5)]
    blur: u32,
    /// Blur depth-edge width as a fraction of the pixel's distance (smaller keeps sharper edges).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.02)]
    blur_sigma: f32,
    /// Kernel rotation per pixel: halton (per-pixel low-discrepancy) or tiled (5×5 tile).
    #[arg(long, default_value = "halton")]
    noise: Noise,
    #[command(flatten)]
    gtao: GtaoArgs,
    /// Turn SSAO's range check (depth constraint) off.
    #[arg(long)]
    no_range_check: bool,
    /// Accumulate occlusion over frames by reverse reprojection (seed 001); the sampling
    /// pattern changes every frame (SSAO/SSDO: the next part of a longer Halton kernel;
    /// HBAO: turned by the golden angle, its range jittered).
    #[arg(long)]
    temporal: bool,
    /// Temporal disocclusion threshold in metres (plus two pixel footprints).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.02)]
    temporal_epsilon: f32,
    /// Temporal blend: average (running mean) or confidence (seed 001 eqs. 4–5).
    #[arg(long, default_value = "average")]
    temporal_blend: vrao::render::settings::TemporalBlend,
    /// Frames after which a pixel counts as converged.
    #[arg(long, default_value_t = 16)]
    temporal_frames: u32,
    /// Motion-adaptive temporal window: a pixel that moved m pixels since the last frame
    /// averages at most frames / (1 + m / this) frames (at least 4); 0 turns it off.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5)]
    temporal_motion_px: f32,
}

impl AoArgs {
    /// Settings for a Vive-class headset at `width`×`height` per eye with these occlusion,
    /// shadow and RSM options (the commands that render frames share this).
    fn eye_settings(&self, scene: &Scene, width: u32, height: u32) -> Settings {
        Settings {
            profile: HeadsetProfile::with_size("vive", width, height),
            ao: self.settings(scene),
            shadows: self.lights.settings(scene),
            ..Settings::default()
        }
    }

    fn settings(&self, scene: &Scene) -> AoSettings {
        AoSettings {
            technique: self.technique,
            samples: self.samples.unwrap_or(self.quality.samples()),
            radius: self.radius.unwrap_or_else(|| scene.suggested_ao_radius()),
            strength: self.strength,
            bias: self.bias,
            range_check: !self.no_range_check,
            bounce: self.bounce,
            bounce_form: self.bounce_form,
            noise: self.noise,
            half_res: self.half_res,
            depth_peeling: self.depth_peeling,
            denoise: self.denoise,
            blur_radius: self.blur,
            blur_plane_sigma: self.blur_sigma,
            temporal: vrao::render::settings::Temporal {
                enabled: self.temporal,
                epsilon_m: self.temporal_epsilon,
                blend: self.temporal_blend,
                max_frames: self.temporal_frames,
                motion_px: self.temporal_motion_px,
                ..Default::default()
            },
            thickness: self.gtao.thickness,
            step_power: self.gtao.step_power,
            connect: self.gtao.connect,
            stereo_reuse: !self.gtao.independent_eyes,
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
        scene.head = vrao::render::scene::HeadPath::fixed(pose);
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
    settings.validate()?;
    let gpu = Arc::new(Gpu::new(backend)?);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings)?;
    renderer.set_timing(args.timing.resolve(&gpu));
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let mut outputs = vec![Resource::Color];
    if args.debug {
        outputs.extend([Resource::Depth, Resource::Normals, Resource::Albedo]);
        outputs.extend(vrao::render::output::occlusion_outputs(&settings));
    }
    // Warm-up frames (pipeline compilation, first-touch allocation) are not measured.
    let warmup = if args.frames > 1 { (args.frames / 10).clamp(1, 10) } else { 0 };
    let mut timings = Vec::new();
    let mut report = None;
    for frame in 0..warmup + args.frames {
        let r = renderer.render_and_wait(&eyes.eyes, &outputs)?;
        if frame >= warmup {
            let mut spans = r.gpu_ms.clone();
            spans.extend(r.wall_ms.iter().map(|(pass, ms)| (format!("{pass} (wall)"), *ms)));
            spans.push(("cpu encode".into(), r.cpu_encode_ms));
            timings.push(spans);
        }
        report = Some(r);
    }
    let report = report.expect("at least one frame");
    let written = vrao::render::output::write_images(&renderer, &args.out, 2, args.debug)?;
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
        for s in vrao::render::gpu::timing::summarize(&timings) {
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
    use vrao::measure::bench::{records, sweep, BenchCase, BenchFile, Measurement};
    if let Some(path) = &args.replot {
        let mut file = vrao::measure::bench::read_json(path)?;
        vrao::measure::bench::mark_pareto(&mut file.records);
        let mut radii: Vec<f32> = file.records.iter().map(|r| r.radius_m).collect();
        radii.sort_by(f32::total_cmp);
        radii.dedup();
        let adapter = format!("{} ({}, {})", file.adapter, file.backend, file.driver);
        return write_bench(&args, &file, &radii, &adapter);
    }
    let scene = Scene::load(&args.scene)?;
    let resolutions: &[bool] = match args.resolution.as_str() {
        "full" => &[false],
        "half" => &[true],
        "both" => &[false, true],
        other => return Err(Error::input(format!("--resolution '{other}' is not full, half or both"))),
    };
    let peeling: &[bool] = match args.depth_peeling.as_str() {
        "off" => &[false],
        "on" => &[true],
        "both" => &[false, true],
        other => return Err(Error::input(format!("--depth-peeling '{other}' is not off, on or both"))),
    };
    let temporal_modes: &[bool] = match args.temporal.as_str() {
        "off" => &[false],
        "on" => &[true],
        "both" => &[false, true],
        other => return Err(Error::input(format!("--temporal '{other}' is not off, on or both"))),
    };
    if !(args.budget_ms.is_finite() && args.budget_ms > 0.0) {
        return Err(Error::input(format!("--budget-ms {} must be a positive number of milliseconds", args.budget_ms)));
    }
    let base_radius = scene.suggested_ao_radius();
    let radii = if args.radii.is_empty() {
        vec![base_radius * 0.5, base_radius, base_radius * 2.0]
    } else {
        args.radii.clone()
    };
    let mut settings =
        Settings { profile: HeadsetProfile::with_size("vive", args.width, args.height), ..Settings::default() };
    settings.ao.bounce_form = args.bounce_form;
    args.gtao.apply(&mut settings.ao);
    (settings.ao.denoise, settings.ao.blur_radius) = (args.denoise, args.blur);
    let mut cases = Vec::new();
    for &technique in &args.techniques {
        for &samples in &args.samples {
            for &radius in &radii {
                for &half_res in resolutions {
                    for &depth_peeling in peeling {
                        if depth_peeling && !matches!(technique, Technique::Ssdo | Technique::SsdoBounce) {
                            continue;
                        }
                        for &temporal in temporal_modes {
                            cases.push(BenchCase { technique, samples, radius, half_res, depth_peeling, temporal });
                        }
                    }
                }
            }
        }
    }
    for case in &cases {
        let mut s = settings.clone();
        (s.ao.technique, s.ao.samples, s.ao.radius, s.ao.half_res, s.ao.depth_peeling) =
            (case.technique, case.samples, case.radius, case.half_res, case.depth_peeling);
        s.validate()?;
        if case.technique == Technique::None {
            return Err(Error::input("--techniques: none has no occlusion to measure"));
        }
    }
    if !args.rsm_samples.is_empty() && vrao::render::passes::shadow::shadow_casters(&scene).is_empty() {
        return Err(Error::input(format!("--rsm-samples: '{}' has no directional light to bounce", scene.name)));
    }
    if let Some(n) = args.rsm_samples.iter().find(|n| !(1..=1024).contains(*n)) {
        return Err(Error::input(format!("--rsm-samples {n} is not within 1..=1024")));
    }
    let gpu = Arc::new(Gpu::new(backend)?);
    let info = gpu.adapter.get_info();
    let timing = args.timing.resolve(&gpu);
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let mut references = Vec::new();
    let mut reference_info = None;
    if !args.no_reference {
        let cache = args.cache.clone().unwrap_or_else(default_cache_dir);
        let (mut noise, mut rays, mut seconds) = (0.0f64, 0u64, 0.0f64);
        for &radius in &radii {
            let reference_settings = vrao::measure::reference::ReferenceSettings {
                radius: radius as f64,
                rays_per_pixel: args.rays,
                stride: args.stride,
                near: settings.near,
            };
            eprintln!("reference: r = {radius} m, {} rays per pixel, every {} pixels", args.rays, args.stride);
            let mut bar = vrao::measure::reference::ProgressBar::new("reference");
            let image = vrao::measure::reference::trace_cached(
                &cache,
                &scene,
                &eyes.eyes,
                (args.width, args.height),
                &reference_settings,
                &mut |p| bar.update(p),
            )?;
            bar.finish();
            noise = noise.max(image.stats.noise);
            if !image.stats.from_cache {
                rays += image.stats.rays;
                seconds += image.stats.seconds;
            }
            references.push((radius, image));
        }
        reference_info = Some(vrao::measure::bench::ReferenceInfo {
            rays_per_pixel: args.rays,
            stride: args.stride,
            ao_noise_rms: noise,
            rays_per_second: (seconds > 0.0).then(|| rays as f64 / seconds),
        });
    }
    eprintln!(
        "bench: {} cases on '{}' ({}), {}x{} per eye, {} frames each, {timing:?} timing",
        cases.len(),
        scene.name,
        info.name,
        args.width,
        args.height,
        args.frames
    );
    let how = Measurement {
        timing,
        warmup: args.warmup,
        frames: args.frames,
        whole_frame: args.frame,
        interleave: args.interleave as usize,
    };
    let (estimate, frame_seconds) = vrao::measure::bench::estimate_seconds(&gpu, &scene, &settings, &cases, how)?;
    eprintln!(
        "bench: estimated {} ({} cases × ({} + {} frames) at ~{:.0} ms a frame of the first case, plus set-up; other cases may differ)",
        format_duration(estimate),
        cases.len(),
        args.warmup,
        args.frames,
        frame_seconds * 1000.0
    );
    let started = std::time::Instant::now();
    let mut rows = sweep(&gpu, &scene, &settings, &cases, how, &references, |done, total, row| {
        let elapsed = started.elapsed().as_secs_f64();
        let eta = elapsed / done as f64 * (total - done) as f64;
        let mut error = row.error.as_ref().map_or(String::new(), |e| {
            let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
            format!(
                "  RMSE {:.3} bias {:+.3} vs limit {} (limit {}) FLIP {}",
                e.ao_rmse,
                e.ao_bias,
                opt(e.ao_rmse_vs_limit),
                opt(e.limit_rmse),
                opt(e.flip_mean)
            )
        });
        if let Some(share) = row.stereo.and_then(|s| s.inconsistent) {
            error += &format!("  stereo ≠ {:.1} %", share * 100.0);
        }
        eprintln!(
                "[{done:>3}/{total}] {:<12} N={:<3} r={:<7} {:<4} {:>9.3} ms/eye{error}   (elapsed {elapsed:.0} s, eta {eta:.0} s)",
                format!("{}{}", row.case.technique.name(), if row.case.depth_peeling { "+peel" } else { "" }),
                row.case.samples,
                row.case.radius,
                if row.case.half_res { "half" } else { "full" },
                row.occlusion_ms_per_eye()
            );
    })?;
    for &samples in &args.rsm_samples {
        for &radius in &radii {
            let reference = references.iter().find(|(r, _)| *r == radius).map(|(_, image)| image);
            let row = vrao::measure::bench::measure_rsm(&gpu, &scene, &settings, samples, radius, how, reference)?;
            let error = row.bounce.map_or(String::new(), |b| format!("  bounce rel RMSE {:.4}", b.rel_rmse));
            eprintln!("[rsm] N={samples:<3} r={radius:<7} half {:>9.3} ms/eye{error}", row.occlusion_ms_per_eye());
            rows.push(row);
        }
    }
    let file = BenchFile {
        scene: scene.name.clone(),
        adapter: info.name.clone(),
        backend: format!("{:?}", info.backend),
        driver: info.driver_info.clone(),
        width: args.width,
        height: args.height,
        timing: format!("{timing:?}").to_lowercase(),
        warmup: args.warmup,
        frames: args.frames,
        limit: reference_info.as_ref().map(|_| vrao::measure::bench::LimitInfo::defaults()),
        pixels_per_degree: Some(
            eyes.eyes.iter().map(|e| vrao::measure::bench::pixels_per_degree(&e.fov, args.width)).sum::<f64>() / 2.0,
        ),
        reference: reference_info,
        version: version(),
        command: command_line(),
        records: records(&rows),
    };
    let adapter = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
    write_bench(&args, &file, &radii, &adapter)
}

/// Writes a bench's table, CSV, JSON, Markdown and plots into `args.out` and prints them.
fn write_bench(args: &BenchArgs, file: &vrao::measure::bench::BenchFile, radii: &[f32], adapter: &str) -> Result<()> {
    use vrao::measure::bench::{markdown_report, plot, to_csv, to_json};
    std::fs::create_dir_all(&args.out).map_err(|e| Error::Output { path: args.out.clone(), message: e.to_string() })?;
    let write = |name: &str, text: String| {
        let path = args.out.join(name);
        std::fs::write(&path, text).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })
    };
    write("bench.csv", to_csv(&file.records))?;
    let markdown = markdown_report(file);
    write("bench.md", markdown.clone())?;
    write("bench.json", to_json(file))?;
    let mut written = "bench.csv, bench.json, bench.md".to_string();
    if file.reference.is_some() {
        // One plot per radius (errors compare only within a radius); bench.png is the
        // middle radius, the scene's suggested one by default.
        for (i, &radius) in radii.iter().enumerate() {
            let name = if i == radii.len() / 2 {
                "bench.png".to_string()
            } else {
                vrao::measure::bench::plot_file_name(radius)
            };
            plot(file, radius, args.budget_ms / 2.0).save_png(&args.out.join(&name), 1280, 800)?;
            written += &format!(", {name}");
        }
    }
    println!("{markdown}");
    if let Some(r) = &file.reference {
        println!(
            "reference: {} rays per pixel at every {} pixels; its AO noise (RMS standard error) {:.4}{}",
            r.rays_per_pixel,
            r.stride,
            r.ao_noise_rms,
            r.rays_per_second.map_or(String::new(), |s| format!("; traced at {:.2} Mrays/s", s / 1e6))
        );
        for &radius in radii {
            let mut front: Vec<&vrao::measure::bench::BenchRecord> =
                file.records.iter().filter(|r| r.pareto && r.radius_m == radius).collect();
            front.sort_by(|a, b| a.occlusion_ms_per_eye.total_cmp(&b.occlusion_ms_per_eye));
            let front: Vec<String> = front
                .iter()
                .map(|r| {
                    format!("{} ({:.1} ms, {:.4})", r.setting(), r.occlusion_ms_per_eye, r.ao_rmse.unwrap_or(f64::NAN))
                })
                .collect();
            println!("Pareto front at r = {radius} m (fastest first): {}", front.join("; "));
        }
    }
    println!("adapter: {adapter}; wrote {written} in {}", args.out.display());
    Ok(())
}

/// vrao's version, with the git commit it was built from when git can tell (read at run
/// time from the source tree the binary was built in; "+changes" when it has uncommitted
/// changes).
fn version() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(env!("CARGO_MANIFEST_DIR"))
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let mut v = env!("CARGO_PKG_VERSION").to_string();
    if let Some(hash) = git(&["rev-parse", "--short", "HEAD"]).filter(|h| !h.is_empty()) {
        let dirty = git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
        v += &format!(" (git {hash}{})", if dirty { "+changes" } else { "" });
    }
    v
}

/// The command line as typed (arguments with spaces or quotes quoted).
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

/// "42 s", "3.5 min" or "1.2 h".
fn format_duration(seconds: f64) -> String {
    if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 5400.0 {
        format!("{:.1} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

/// Where reference images are cached between runs.
fn default_cache_dir() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("vrao").join("reference")
}

fn parse_size(s: &str) -> Result<(u32, u32)> {
    let parsed =
        s.split_once('x').and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => Ok((w, h)),
        _ => Err(Error::input(format!("--window '{s}' is not WIDTHxHEIGHT within 1..=16384"))),
    }
}

fn run(backend: BackendChoice, args: RunArgs) -> Result<()> {
    use vrao::render::settings::DisplayMode;
    use vrao::xr::simulated::{SimulatedOptions, TimeMode};
    let scene = Scene::load(&args.scene)?;
    let mut profile =
        vrao::xr::profiles::by_name(&args.profile).map_err(|e| Error::input(format!("--profile: {e}")))?;
    if let Some(hz) = args.refresh {
        profile = profile.with_refresh(hz).map_err(|e| Error::input(format!("--refresh: {e}")))?;
    }
    let size = match (args.width, args.height) {
        (None, None) => None,
        (w, h) => Some((w.unwrap_or(profile.width), h.unwrap_or(profile.height))),
    };
    if let Some((w, h)) = size {
        profile = profile.with_render_size(w, h);
    }
    let mut settings = args.ao.eye_settings(&scene, profile.width, profile.height);
    settings.profile = profile;
    settings.validate()?;
    let window_size = parse_size(&args.window)?;
    if args.display == DisplayMode::None && args.show != vrao::app::BufferView::Eyes {
        return Err(Error::input(format!(
            "--show {} needs a window (--display mirror or single-pass)",
            args.show.name()
        )));
    }
    let governor = match args.governor {
        OnOff::Off => None,
        OnOff::On => Some(governor_for(&args, &settings)?),
    };
    let frames = args.frames.or((args.display == DisplayMode::None).then_some(600));
    let simulated = SimulatedOptions {
        profile: settings.profile,
        near: settings.near,
        path: scene.head.clone(),
        motion: args.motion,
        time: if args.virtual_time.is_empty() {
            TimeMode::Real
        } else {
            TimeMode::Virtual { render_ms: args.virtual_time.clone() }
        },
        reprojection: args.reprojection,
        compose: args.display == DisplayMode::Mirror,
        frames,
    };
    let (headset, gpu, message) = vrao::app::open_headset(args.headset, simulated, size, backend)?;
    println!("headset: {message}");
    let mut frame_loop = vrao::app::FrameLoop::new(gpu.clone(), &scene, &settings, headset)?;
    frame_loop.frame_limit = frames;
    frame_loop.renderer.set_frames_in_flight(args.frames_in_flight as usize);
    if let Some(governor) = governor {
        println!(
            "governor: on, {} levels from {} to {}; starting at {}",
            governor.frontier().len(),
            governor.frontier().levels()[0].setting,
            governor.frontier().levels()[governor.frontier().top()].setting,
            governor.current().setting
        );
        frame_loop.set_governor(governor)?;
    }
    // Ctrl-C ends the session cleanly (OpenXR walks to EXITING) and the report is still
    // written; a second Ctrl-C while it ends is the default: the process stops.
    let exit = frame_loop.exit_requested.clone();
    let _ = ctrlc::set_handler(move || {
        if exit.swap(true, std::sync::atomic::Ordering::Relaxed) {
            std::process::exit(130);
        }
        eprintln!("Ctrl-C: ending the session");
    });
    let summary = if args.display == DisplayMode::None {
        while frame_loop.step()?.is_some() {}
        frame_loop.end()?;
        vrao::app::RunSummary::of(&frame_loop)
    } else {
        vrao::app::window::run_window(
            frame_loop,
            &scene,
            vrao::app::window::WindowOptions {
                mode: args.display,
                size: window_size,
                screenshot: args.screenshot.clone(),
                show: args.show,
            },
        )?
    };
    println!("{}", summary.to_text());
    if let Some(path) = &args.report {
        let json = serde_json::to_string_pretty(&summary).expect("run summary serialises");
        std::fs::write(path, json).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })?;
    }
    Ok(())
}

/// The governor of `vrao run`: its frontier (the bench file given, or the built-in one)
/// at the frame budget of the profile, starting at the level nearest the asked setting.
fn governor_for(args: &RunArgs, settings: &Settings) -> Result<vrao::app::governor::Governor> {
    use vrao::app::governor::{Frontier, Governor, GovernorConfig};
    let frontier = match &args.governor_frontier {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| Error::in_file(path, e.to_string()))?;
            Frontier::from_json(&text, &path.display().to_string(), settings.ao.radius).map_err(Error::input)?
        }
        None => Frontier::builtin(),
    };
    let ao = &settings.ao;
    let start = frontier
        .levels()
        .iter()
        .position(|l| {
            l.technique == ao.technique
                && l.samples == ao.samples
                && l.half_res == ao.half_res
                && l.temporal == ao.temporal.enabled
        })
        .unwrap_or(frontier.top());
    let config = GovernorConfig::for_refresh_hz(settings.profile.refresh_hz);
    Governor::new(frontier, config, start).map_err(Error::input)
}

/// A switch: on or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum OnOff {
    On,
    Off,
}

fn reprojection(backend: BackendChoice, args: ReprojectionArgs) -> Result<()> {
    use vrao::measure::reprojection::{default_movements, measure, to_markdown};
    let scene = Scene::load(&args.scene)?;
    let settings = args.ao.eye_settings(&scene, args.width, args.height);
    settings.validate()?;
    let gpu = Arc::new(Gpu::new(backend)?);
    let mut renderer = Renderer::new(gpu.clone(), &scene, &settings)?;
    let rows = measure(&mut renderer, &scene.head.pose_at(0.0), &default_movements())?;
    println!(
        "reprojection of '{}' at {}x{} per eye on {}: RMSE of colour (0..1, both eyes) against a fresh render",
        scene.name,
        args.width,
        args.height,
        gpu.adapter.get_info().name
    );
    print!("{}", to_markdown(&rows));
    if let Some(path) = &args.out {
        let json = serde_json::to_string_pretty(&rows).expect("rows serialise");
        std::fs::write(path, json).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })?;
    }
    Ok(())
}

fn temporal(backend: BackendChoice, args: TemporalArgs) -> Result<()> {
    use vrao::render::settings::TemporalBlend;
    use vrao::xr::simulated::motion::HeadMotion;
    let scene = Scene::load(&args.scene)?;
    let base = args.ao.eye_settings(&scene, args.width, args.height);
    base.validate()?;
    let n = base.ao.samples;
    let with = |temporal: bool, blend: TemporalBlend, samples: u32, blur: u32| {
        let mut s = base.clone();
        s.ao.samples = samples;
        s.ao.blur_radius = blur;
        s.ao.temporal.enabled = temporal;
        s.ao.temporal.blend = blend;
        s
    };
    let configurations = vec![
        (format!("spatial N={n}, blur"), with(false, TemporalBlend::Average, n, base.ao.blur_radius)),
        (format!("spatial N={n}, no blur"), with(false, TemporalBlend::Average, n, 0)),
        (
            format!("spatial N={}, blur (4× the samples)", 4 * n),
            with(false, TemporalBlend::Average, 4 * n, base.ao.blur_radius),
        ),
        (format!("temporal N={n}, no blur"), with(true, TemporalBlend::Average, n, 0)),
        (format!("temporal N={n}, blur"), with(true, TemporalBlend::Average, n, base.ao.blur_radius)),
        (format!("temporal N={n}, confidence blend, no blur"), with(true, TemporalBlend::Confidence, n, 0)),
    ];
    for (_, s) in &configurations {
        s.validate()?;
    }
    let gpu = Arc::new(Gpu::new(backend)?);
    let reference = vrao::measure::reference::ReferenceSettings {
        radius: base.ao.radius as f64,
        rays_per_pixel: args.rays,
        stride: 2,
        near: base.near,
    };
    let mut points = Vec::new();
    for motion in [HeadMotion::Static, HeadMotion::YawSweep] {
        eprintln!("temporal: {} ({} configurations × 16 frames)", motion.name(), configurations.len());
        points.extend(vrao::measure::temporal::convergence(
            &gpu,
            &scene,
            &configurations,
            motion,
            &reference,
            &default_cache_dir(),
        )?);
    }
    println!(
        "AO RMSE against the reference ({} rays, every 2nd pixel) after k frames; '{}' at {}x{} per eye, {} r = {} m, on {}",
        args.rays,
        scene.name,
        args.width,
        args.height,
        base.ao.technique.name(),
        base.ao.radius,
        gpu.adapter.get_info().name
    );
    print!("{}", vrao::measure::temporal::to_markdown(&points));
    if let Some(path) = &args.out {
        let json = serde_json::to_string_pretty(&points).expect("points serialise");
        std::fs::write(path, json).map_err(|e| Error::Output { path: path.clone(), message: e.to_string() })?;
    }
    Ok(())
}

fn budget(backend: BackendChoice, args: BudgetArgs) -> Result<()> {
    use vrao::measure::budget::{run, BudgetRun};
    let scene = Scene::load(&args.scene)?;
    let mut settings = args.ao.eye_settings(&scene, args.width, args.height);
    let budget_ms = args.budget_ms.unwrap_or(settings.profile.budget_ms());
    if !(budget_ms.is_finite() && budget_ms > 0.0) {
        return Err(Error::input(format!("--budget-ms {budget_ms} must be a positive number of milliseconds")));
    }
    let occlusion_only = match args.measure.as_str() {
        "frame" => false,
        "occlusion" => true,
        other => return Err(Error::input(format!("--measure '{other}' is not frame or occlusion"))),
    };
    settings.validate()?;
    let fit_file = match &args.fit {
        Some(path) => Some(vrao::measure::bench::read_json(path)?),
        None => None,
    };
    let gpu = Arc::new(Gpu::new(backend)?);
    let timing = args.timing.resolve(&gpu);
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let measure = |settings: &Settings, frames: u32| -> Result<vrao::measure::budget::BudgetReport> {
        let output = if occlusion_only {
            vrao::render::passes::final_occlusion(settings)
                .ok_or_else(|| Error::input("--measure occlusion needs an occlusion technique"))?
        } else {
            Resource::Color
        };
        let mut renderer = Renderer::new(gpu.clone(), &scene, settings)?;
        run(&mut renderer, &eyes, BudgetRun { timing, warmup: args.warmup, frames, budget_ms, output })
    };
    if let (Some(file), Some(path)) = (&fit_file, &args.fit) {
        settings.ao =
            fit_setting(file, path, &gpu, &settings, budget_ms, occlusion_only, |s, frames| measure(s, frames))?;
    }
    let report = measure(&settings, args.frames)?;
    print!("{}", report.to_text());
    let json = serde_json::to_string_pretty(&report).expect("budget report serialises");
    std::fs::write(&args.out, json).map_err(|e| Error::Output { path: args.out.clone(), message: e.to_string() })?;
    println!("wrote {}", args.out.display());
    if report.within_budget() {
        Ok(())
    } else {
        Err(Error::OverBudget(format!(
            "{} over the {budget_ms:.3} ms stereo frame budget",
            report.verdicts.iter().filter(|v| !v.pass).map(|v| v.what.as_str()).collect::<Vec<_>>().join(", ")
        )))
    }
}

/// `--fit`: the bench row with the least AO error whose occlusion cost fits what the
/// budget leaves per eye after the passes every frame pays (measured here with no
/// occlusion), returned as the settings to measure.
fn fit_setting(
    file: &vrao::measure::bench::BenchFile,
    path: &std::path::Path,
    gpu: &Gpu,
    settings: &Settings,
    budget_ms: f64,
    occlusion_only: bool,
    measure: impl Fn(&Settings, u32) -> Result<vrao::measure::budget::BudgetReport>,
) -> Result<AoSettings> {
    let adapter = gpu.adapter.get_info().name;
    if file.adapter != adapter {
        return Err(Error::in_file(
            path,
            format!("was measured on '{}', not on this device '{adapter}'; run vrao bench here first", file.adapter),
        ));
    }
    if (file.width, file.height) != (settings.profile.width, settings.profile.height) {
        eprintln!(
            "warning: {} was measured at {}x{} per eye, this budget is for {}x{}",
            path.display(),
            file.width,
            file.height,
            settings.profile.width,
            settings.profile.height
        );
    }
    // What every frame pays besides the occlusion, per eye (eyes measured alone).
    let base_ms = if occlusion_only {
        0.0
    } else {
        let mut base = settings.clone();
        base.ao.technique = Technique::None;
        let report = measure(&base, 5)?;
        report.verdicts.iter().filter(|v| v.what != "stereo frame").map(|v| v.ms).fold(0.0, f64::max)
    };
    let left_per_eye = budget_ms / 2.0 - base_ms;
    // Errors compare only within one radius (each radius is its own target quantity):
    // take the rows of the radius asked for, or of the bench radius nearest to it.
    let measured: Vec<_> = file.records.iter().filter(|r| r.ao_rmse.is_some_and(f64::is_finite)).collect();
    let Some(radius) = measured
        .iter()
        .map(|r| r.radius_m)
        .min_by(|a, b| (a - settings.ao.radius).abs().total_cmp(&(b - settings.ao.radius).abs()))
    else {
        return Err(Error::in_file(path, "has no rows with an error against the reference"));
    };
    if radius != settings.ao.radius {
        println!("fit: the bench has no rows at r = {} m; using its nearest radius, {radius} m", settings.ao.radius);
    }
    let with_error: Vec<_> = measured.into_iter().filter(|r| r.radius_m == radius).collect();
    let fitting: Vec<_> = with_error.iter().filter(|r| r.occlusion_ms_per_eye <= left_per_eye).collect();
    let chosen = match fitting.iter().min_by(|a, b| a.ao_rmse.unwrap().total_cmp(&b.ao_rmse.unwrap())) {
        Some(r) => {
            println!(
                "fit: {} — AO RMSE {:.4}, the least of the {} of {} bench rows whose occlusion ({:.3} ms per eye) fits the {:.3} ms per eye left after {:.3} ms of the other passes",
                r.setting(),
                r.ao_rmse.unwrap(),
                fitting.len(),
                with_error.len(),
                r.occlusion_ms_per_eye,
                left_per_eye,
                base_ms
            );
            r
        }
        None => {
            let cheapest =
                with_error.iter().min_by(|a, b| a.occlusion_ms_per_eye.total_cmp(&b.occlusion_ms_per_eye)).unwrap();
            println!(
                "fit: no bench row fits the {:.3} ms per eye left after {:.3} ms of the other passes; the cheapest, {} ({:.3} ms per eye), is measured",
                left_per_eye, base_ms, cheapest.setting(), cheapest.occlusion_ms_per_eye
            );
            cheapest
        }
    };
    let mut ao = settings.ao.clone();
    ao.technique = chosen.technique.parse().map_err(|e: String| Error::in_file(path, e))?;
    ao.samples = chosen.samples;
    ao.radius = chosen.radius_m;
    ao.half_res = chosen.resolution == "half";
    ao.depth_peeling = chosen.depth_peeling;
    Ok(ao)
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
        Some(Command::Budget(args)) => budget(cli.backend, args),
        Some(Command::Run(args)) => run(cli.backend, args),
        Some(Command::Temporal(args)) => temporal(cli.backend, args),
        Some(Command::Reprojection(args)) => reprojection(cli.backend, args),
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
