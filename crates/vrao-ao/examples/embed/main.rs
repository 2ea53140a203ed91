//! vrao's AO inside someone else's wgpu renderer. This program opens its own wgpu device,
//! draws its own geometry with its own depth prepass (depth and view-space normals, both
//! eyes in a 2-layer array), then asks vrao's [`AoEngine`] for the ambient occlusion of
//! both eyes and writes it as `OUT/embed_ao_left.png` and `OUT/embed_ao_right.png`.
//! Then it hands the engine its light as well (a sky as nine SH coefficients and a
//! direct-light texture) and asks for SSDO with one bounce: the ambient light of both
//! eyes, beside the AO, as `OUT/embed_ambient_left.png` and `OUT/embed_ambient_right.png`.
//!
//! ```text
//! cargo run --release -p vrao-ao --example embed -- [OUT] [--standard-depth] [--no-normals] [--msaa N] [--layers N] [--hand MODE] [--time] [--time-setup]
//! ```
//!
//! The command line is handled like vrao's: `--help` prints the usage and exits 0; an
//! unknown option or a second folder is one line naming it and exit 2, as is a folder
//! that cannot be written (named); any other failure exits 1.
//!
//! `--hand left-out` adds a hand-sized box over the step, marked in the stencil of a
//! `Depth24PlusStencil8` depth buffer and handed to the engine as casting no AO (the step
//! below it keeps its AO, as without the hand); `--hand casting` draws it like the rest
//! (its halo on the step, for comparison).
//! `--standard-depth` stores depth as `Depth24Plus` with a finite far plane instead of
//! reversed-Z `Depth32Float`; `--no-normals` lets the engine rebuild normals from depth;
//! `--msaa 4` draws the prepass with 4 samples per pixel (2 and 8 too), as a forward
//! renderer with MSAA does, and hands the engine the multisampled depth and normals, which
//! it resolves itself (a 2-layer multisampled texture needs the adapter's
//! `MULTISAMPLE_ARRAY`; the program says so when it lacks it).
//! `--layers 2` also draws the host's depth peel (the same prepass drawing back faces:
//! the surface behind each pixel's first one, for the example's closed boxes) and hands
//! it to the engine as its second layer (`AoFrame::second_layer`, `AoSettings::layers`).
//! It exits non-zero when the AO is not finite, outside 0..1, or shows no occlusion.
//! `--time` also times whole frames at 1080×1200 per eye, interleaved: the host's prepass
//! alone, and with the engine (host normals, rebuilt normals), median wall-clock ms.

mod host;

use host::{demo_eyes, demo_geometry, demo_hand, DepthPrepass, HostDepth, HAND_STENCIL};
use vrao_ao::AoOutputFormat;
use vrao_ao::{
    AoConfig, AoEngine, AoFrame, DepthConvention, HostExclusion, HostLight, HostNormals, NormalEncoding, NormalSpace,
    ViewMatrices,
};
use vrao_ao::{AoSettings, Technique};

const WIDTH: u32 = 320;
const HEIGHT: u32 = 360;

const USAGE: &str = "\
vrao's AO engine inside a host's own wgpu renderer: writes OUT/embed_ao_left.png and OUT/embed_ao_right.png

Usage: embed [OUT] [OPTIONS]

Arguments:
  [OUT]             folder for the PNG files (default: out)

Options:
  --standard-depth  Depth24Plus with a finite far plane instead of reversed-Z Depth32Float
  --no-normals      let the engine rebuild normals from depth
  --msaa N          draw the prepass with N samples per pixel (1, 2, 4 or 8; default 1)
  --layers N        depth layers the engine reads: 1, or 2 with the host's back-face peel (default 1)
  --hand MODE       add a hand over the step: left-out (marked in the stencil, casting no AO) or casting
  --time            also time whole frames at 1080x1200 per eye (host prepass alone and with the engine)
  --time-setup      also time AoEngine::new, the first frame, a resize and the frame after it
  -h, --help        print this and exit
";

/// What the command line asks for.
#[derive(Clone, Debug, PartialEq)]
struct Args {
    out: std::path::PathBuf,
    standard_depth: bool,
    no_normals: bool,
    /// Samples per pixel of the host's prepass.
    msaa: u32,
    /// Depth layers handed to the engine (2: with the host's back-face peel).
    layers: u32,
    /// A hand over the step, left out of the AO through the stencil, or casting it.
    hand: Option<Hand>,
    time: bool,
    time_setup: bool,
}

/// How `--hand` draws the host's hand.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Hand {
    /// Marked in the stencil and handed to the engine as casting no AO.
    LeftOut,
    /// Drawn like the rest: it casts AO onto the step below it.
    Casting,
}

/// The value of `--hand`.
fn parse_hand(value: Option<&str>) -> Result<Hand, String> {
    match value {
        Some("left-out") => Ok(Hand::LeftOut),
        Some("casting") => Ok(Hand::Casting),
        Some(other) => Err(format!("--hand {other}: the hand is 'left-out' or 'casting'")),
        None => Err("--hand needs 'left-out' or 'casting'".into()),
    }
}

/// What [`parse_args`] found instead of a run.
#[derive(Debug, PartialEq)]
enum Parsed {
    Run(Args),
    Help,
}

/// Why the program stopped: a usage or output problem (exit 2, as vrao's command line
/// exits on bad input) or a failure of the run (exit 1).
#[derive(Debug)]
enum Failure {
    Usage(String),
    Output { path: std::path::PathBuf, message: String },
    Run(Box<dyn std::error::Error>),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Usage(message) => write!(f, "{message} (see --help)"),
            Failure::Output { path, message } => write!(f, "{}: {message}", path.display()),
            Failure::Run(e) => write!(f, "{e}"),
        }
    }
}

impl<E: Into<Box<dyn std::error::Error>>> From<E> for Failure {
    fn from(e: E) -> Failure {
        Failure::Run(e.into())
    }
}

/// The value of `--layers`: the depth layers the engine reads.
fn parse_layers(value: Option<&str>) -> Result<u32, String> {
    match value {
        Some("1") => Ok(1),
        Some("2") => Ok(2),
        Some(other) => Err(format!("--layers {other}: the engine reads 1 or 2 depth layers")),
        None => Err("--layers needs a count: 1 or 2".into()),
    }
}

/// The value of `--msaa`: a sample count the engine takes.
fn parse_msaa(value: Option<&str>) -> Result<u32, String> {
    let value = value.ok_or("--msaa needs a sample count: 1, 2, 4 or 8")?;
    match value.parse::<u32>() {
        Ok(n) if AoConfig::SAMPLE_COUNTS.contains(&n) => Ok(n),
        _ => Err(format!("--msaa {value}: the sample count is 1, 2, 4 or 8")),
    }
}

/// The command line (without the program's name), or the one line that refuses it.
fn parse_args(args: &[String]) -> Result<Parsed, String> {
    let mut parsed = Args {
        out: "out".into(),
        standard_depth: false,
        no_normals: false,
        msaa: 1,
        layers: 1,
        hand: None,
        time: false,
        time_setup: false,
    };
    let mut out: Option<&str> = None;
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "-h" | "--help" => return Ok(Parsed::Help),
            "--msaa" => parsed.msaa = parse_msaa(args.next().map(String::as_str))?,
            flag if flag.starts_with("--msaa=") => parsed.msaa = parse_msaa(flag.strip_prefix("--msaa="))?,
            "--layers" => parsed.layers = parse_layers(args.next().map(String::as_str))?,
            flag if flag.starts_with("--layers=") => parsed.layers = parse_layers(flag.strip_prefix("--layers="))?,
            "--hand" => parsed.hand = Some(parse_hand(args.next().map(String::as_str))?),
            flag if flag.starts_with("--hand=") => parsed.hand = Some(parse_hand(flag.strip_prefix("--hand="))?),
            "--standard-depth" => parsed.standard_depth = true,
            "--no-normals" => parsed.no_normals = true,
            "--time" => parsed.time = true,
            "--time-setup" => parsed.time_setup = true,
            // "--" ends the options: what follows is the folder.
            flag if flag.starts_with('-') && flag != "-" => {
                let name = flag.split_once('=').map_or(flag, |(name, _)| name);
                return Err(match name {
                    "--standard-depth" | "--no-normals" | "--time" | "--time-setup" => {
                        format!("{name} takes no value: '{flag}'")
                    }
                    _ => format!("unknown option '{flag}'"),
                });
            }
            "" => return Err("the output folder is an empty name".into()),
            folder => match out {
                None => out = Some(folder),
                Some(first) => return Err(format!("a second output folder '{folder}' (the first is '{first}')")),
            },
        }
    }
    if let Some(out) = out {
        parsed.out = out.into();
    }
    if parsed.hand.is_some() && parsed.msaa > 1 {
        return Err("--hand with --msaa: the example marks its hand in a single-sampled stencil".into());
    }
    if parsed.hand.is_some() && parsed.layers == 2 {
        return Err("--hand with --layers 2: the example peels its room without the hand".into());
    }
    Ok(Parsed::Run(parsed))
}

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let args = match parse_args(&args) {
        Ok(Parsed::Run(args)) => args,
        Ok(Parsed::Help) => {
            print!("{USAGE}");
            return std::process::ExitCode::SUCCESS;
        }
        Err(message) => return fail(Failure::Usage(message)),
    };
    match run(&args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(failure) => fail(failure),
    }
}

/// Prints the failure in one line and gives its exit code.
fn fail(failure: Failure) -> std::process::ExitCode {
    eprintln!("error: {failure}");
    match failure {
        Failure::Usage(_) | Failure::Output { .. } => std::process::ExitCode::from(2),
        Failure::Run(_) => std::process::ExitCode::FAILURE,
    }
}

/// Writes a grey PNG, naming `path` in its error.
fn save_grey(path: &std::path::Path, width: u32, height: u32, pixels: Vec<u8>) -> Result<(), Failure> {
    let output = |message: String| Failure::Output { path: path.to_path_buf(), message };
    let image = image::GrayImage::from_raw(width, height, pixels).ok_or_else(|| output("image size".into()))?;
    image.save(path).map_err(|e| output(format!("cannot write: {e}")))
}

fn run(args: &Args) -> Result<(), Failure> {
    let out = &args.out;
    let depth_kind =
        if args.standard_depth { HostDepth::StandardFinite { far: 50.0 } } else { HostDepth::ReversedInfinite };
    let with_normals = !args.no_normals;
    std::fs::create_dir_all(out)
        .map_err(|e| Failure::Output { path: out.clone(), message: format!("cannot create this folder: {e}") })?;

    // The host's own device: any adapter with Vulkan (or Metal, DX12) and compute.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's WSI probe complains on headless machines without it.
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    let features = msaa_features(&adapter, args.msaa, depth_kind.format())?;
    let descriptor = wgpu::DeviceDescriptor { required_features: features, ..Default::default() };
    let (device, queue) = pollster::block_on(adapter.request_device(&descriptor))?;
    eprintln!("adapter: {}", adapter.get_info().name);

    // The host's frame: its geometry, its eyes, its depth prepass (with the hand, when
    // asked for: marked in the stencil to be left out, or drawn like the rest).
    let size = (WIDTH, HEIGHT);
    let prepass = match args.hand {
        None => DepthPrepass::multisampled(&device, &demo_geometry(), depth_kind, size, 2, args.msaa),
        Some(Hand::LeftOut) => {
            DepthPrepass::with_marked_hand(&device, &demo_geometry(), &demo_hand(), depth_kind, size)
        }
        Some(Hand::Casting) => {
            DepthPrepass::new(&device, &[demo_geometry(), vec![demo_hand()]].concat(), depth_kind, size)
        }
    };
    // The host's depth peel for a second layer: the same geometry's back faces.
    let peel = (args.layers == 2).then(|| {
        DepthPrepass::multisampled(&device, &demo_geometry(), depth_kind, size, 2, args.msaa).back_faces(&device)
    });
    let near = 0.05;
    let tangents = [[-1.2, 0.9, 1.1, -1.1], [-0.9, 1.2, 1.1, -1.1]];
    let views: Vec<ViewMatrices> = demo_eyes()
        .iter()
        .zip(tangents)
        .map(|(view, t)| ViewMatrices { view: *view, projection: depth_kind.projection(t, near) })
        .collect();

    // vrao's AO engine on the host's device, with vrao's default (tuned GTAO) settings.
    let settings = AoSettings { layers: args.layers, ..AoSettings::default() };
    let config = AoConfig { settings, width: WIDTH, height: HEIGHT, views: 2 };
    let mut engine = AoEngine::new(&device, &queue, &config)?;
    let convention = match depth_kind {
        HostDepth::ReversedInfinite => DepthConvention::REVERSED_INFINITE,
        HostDepth::StandardFinite { .. } => DepthConvention::STANDARD_FINITE,
    };
    let normals = HostNormals { texture: &prepass.normals, space: NormalSpace::View, encoding: NormalEncoding::Signed };
    let mut encoder = device.create_command_encoder(&Default::default());
    prepass.record(&device, &mut encoder, &views);
    if let Some(peel) = &peel {
        peel.record(&device, &mut encoder, &views);
    }
    let frame = AoFrame {
        depth: &prepass.depth,
        depth_convention: convention,
        second_layer: peel.as_ref().map(|p| &p.depth),
        normals: with_normals.then_some(normals),
        views: &views,
        // The example's geometry stands still.
        motion: None,
        light: None,
        // The hand casts no AO: the engine reads the stencil of the depth buffer.
        exclusion: (args.hand == Some(Hand::LeftOut)).then_some(HostExclusion {
            texture: &prepass.depth,
            receive_none: 0,
            cast_none: HAND_STENCIL,
        }),
    };
    let ao = engine.record(&mut encoder, &frame)?.texture.clone();
    queue.submit([encoder.finish()]);
    if args.time {
        time_frames(&device, &queue, depth_kind, convention)?;
    }
    if args.time_setup {
        time_setup(&device, &queue, &prepass, &views, convention)?;
    }
    if let Some(plan) = engine.last_plan() {
        eprint!("{plan}");
    }

    for (layer, name) in ["left", "right"].iter().enumerate() {
        let alpha = host::read_alpha(&device, &queue, &ao, layer as u32);
        if let Some(bad) = alpha.iter().find(|a| !a.is_finite() || !(0.0..=1.0).contains(*a)) {
            return Err(format!("{name} eye: AO value {bad} is not within 0..1").into());
        }
        let mean = alpha.iter().sum::<f32>() / alpha.len() as f32;
        if mean > 0.995 {
            return Err(format!("{name} eye: mean AO {mean:.3} shows no occlusion").into());
        }
        let pixels: Vec<u8> = alpha.iter().map(|a| (a * 255.0).round() as u8).collect();
        let path = out.join(format!("embed_ao_{name}.png"));
        save_grey(&path, WIDTH, HEIGHT, pixels)?;
        eprintln!("{name} eye: mean AO {mean:.3} -> {}", path.display());
    }
    ambient(&device, &queue, &mut engine, &frame, out)
}

/// The device features a prepass with `samples` samples needs: both eyes in one
/// multisampled texture need MULTISAMPLE_ARRAY, and counts other than 1 and 4 the
/// adapter's own format features; refused naming what the adapter lacks.
fn msaa_features(adapter: &wgpu::Adapter, samples: u32, depth: wgpu::TextureFormat) -> Result<wgpu::Features, Failure> {
    let mut features = wgpu::Features::empty();
    if samples > 1 {
        features |= wgpu::Features::MULTISAMPLE_ARRAY;
    }
    if samples != 1 && samples != 4 {
        features |= wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        for format in [depth, wgpu::TextureFormat::Rgba16Float] {
            if !adapter.get_texture_format_features(format).flags.sample_count_supported(samples) {
                return Err(format!(
                    "--msaa {samples}: adapter {} cannot draw {format:?} with {samples} samples",
                    adapter.get_info().name
                )
                .into());
            }
        }
    }
    if !adapter.features().contains(features) {
        return Err(format!(
            "--msaa {samples}: adapter {} lacks {:?}",
            adapter.get_info().name,
            features - adapter.features()
        )
        .into());
    }
    Ok(features)
}

/// SSDO with one bounce from the host's light: a sky (nine SH coefficients of its
/// irradiance in the host's world, +Y up: 1.2 from the zenith, 0.4 from below, bluish) and
/// the direct light leaving every surface (here a stand-in the host would compute from its
/// lights: an even warm 0.3). Writes each eye's ambient irradiance (the output's rgb,
/// what a lighting pass multiplies by albedo/π) and fails unless it is finite, within the
/// unoccluded sky's and not all unoccluded.
fn ambient(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    engine: &mut AoEngine,
    frame: &AoFrame,
    out: &std::path::Path,
) -> Result<(), Failure> {
    let direct = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host direct light"),
        size: wgpu::Extent3d { width: WIDTH, height: HEIGHT, depth_or_array_layers: 2 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let texel: [f32; 4] = [0.3, 0.27, 0.22, 1.0];
    let bytes: Vec<u8> = (0..WIDTH * HEIGHT * 2).flat_map(|_| texel).flat_map(f32::to_le_bytes).collect();
    queue.write_texture(
        direct.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(WIDTH * 16), rows_per_image: Some(HEIGHT) },
        direct.size(),
    );
    // E(n) = a + b n.y for a sky of 1.2 above and 0.4 below (per channel, bluish):
    // c0 = a / Y0, c1 = b / Y1 (Y0 = 0.282095, Y1 = 0.488603 y).
    let (above, below) = ([1.0f32, 1.1, 1.3], [0.3f32, 0.35, 0.4]);
    let mut sh = [[0.0f32; 3]; 9];
    for c in 0..3 {
        sh[0][c] = 0.5 * (above[c] + below[c]) / 0.282_095;
        sh[1][c] = 0.5 * (above[c] - below[c]) / 0.488_603;
    }
    let settings = AoSettings { technique: Technique::SsdoBounce, ..AoSettings::default() };
    engine.set_settings(&settings)?;
    let lit = AoFrame { light: Some(HostLight { direct: Some(&direct), environment_sh: Some(sh) }), ..*frame };
    let mut encoder = device.create_command_encoder(&Default::default());
    let output = engine.record(&mut encoder, &lit)?.texture.clone();
    queue.submit([encoder.finish()]);
    for (layer, name) in ["left", "right"].iter().enumerate() {
        let rgba = host::read_rgba(device, queue, &output, layer as u32);
        if let Some(bad) = rgba.iter().find(|v| !v.is_finite() || **v < 0.0 || **v > 10.0) {
            return Err(format!("{name} eye: ambient value {bad} is not finite or out of range").into());
        }
        let green: Vec<f32> = rgba.chunks(4).map(|t| t[1]).collect();
        let mean = green.iter().sum::<f32>() / green.len() as f32;
        if !(mean > 0.05 && mean < above[1] + 0.3) {
            return Err(format!("{name} eye: mean ambient (green) {mean:.3} is not a lit, occluded sky").into());
        }
        let pixels: Vec<u8> = rgba
            .chunks(4)
            .flat_map(|t| [t[0], t[1], t[2]].map(|c| ((c / 1.6).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0) as u8))
            .collect();
        let path = out.join(format!("embed_ambient_{name}.png"));
        image::save_buffer(&path, &pixels, WIDTH, HEIGHT, image::ExtendedColorType::Rgb8)
            .map_err(|e| Failure::Output { path: path.clone(), message: e.to_string() })?;
        eprintln!("{name} eye: ssdo-bounce mean ambient (green) {mean:.3} -> {}", path.display());
    }
    Ok(())
}

/// What a host waits for: making the engine (its kernels compile at the first frame),
/// that first frame, a resize and the frame after it (no kernel compiles), and the
/// same before this crate compiled lazily (every technique's kernels at `new`).
fn time_setup(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    prepass: &DepthPrepass,
    views: &[ViewMatrices],
    convention: DepthConvention,
) -> Result<(), Box<dyn std::error::Error>> {
    let ms = |start: std::time::Instant| start.elapsed().as_secs_f64() * 1e3;
    let frame = |engine: &mut AoEngine, depth: &wgpu::Texture| -> Result<f64, Box<dyn std::error::Error>> {
        let started = std::time::Instant::now();
        let mut encoder = device.create_command_encoder(&Default::default());
        let frame = AoFrame {
            depth,
            depth_convention: convention,
            second_layer: None,
            normals: None,
            views,
            motion: None,
            light: None,
            exclusion: None,
        };
        engine.record(&mut encoder, &frame)?;
        queue.submit([encoder.finish()]);
        device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None })?;
        Ok(ms(started))
    };
    let config = AoConfig { settings: AoSettings::default(), width: WIDTH, height: HEIGHT, views: 2 };
    let started = std::time::Instant::now();
    let mut engine = AoEngine::new(device, queue, &config)?;
    let new_ms = ms(started);
    let first_ms = frame(&mut engine, &prepass.depth)?;
    let built = engine.pipelines_built();
    let second_ms = frame(&mut engine, &prepass.depth)?;
    let (width, height) = (WIDTH * 2, HEIGHT * 2);
    let larger = DepthPrepass::new(device, &demo_geometry(), HostDepth::ReversedInfinite, (width, height));
    let started = std::time::Instant::now();
    engine.resize(width, height)?;
    let resize_ms = ms(started);
    let after_resize_ms = frame(&mut engine, &larger.depth)?;
    let eager = vrao_ao::plug::Gpu::from_host(device, queue)?;
    let started = std::time::Instant::now();
    let chain = vrao_ao::plug::ao_chain(&eager, Vec::new());
    let eager_ms = ms(started);
    drop(chain);
    eprintln!(
        "AoEngine::new {new_ms:.1} ms (every technique's kernels at new, as before: {eager_ms:.1} ms, {} kernels)",
        eager.pipelines_built()
    );
    eprintln!("first frame {first_ms:.1} ms ({built} kernels compiled), second {second_ms:.1} ms");
    eprintln!(
        "resize to {width}x{height}: {resize_ms:.3} ms, next frame {after_resize_ms:.1} ms ({} kernels compiled since)",
        engine.pipelines_built() - built
    );
    Ok(())
}

/// Frames of the host's prepass alone and with the engine after it, interleaved so that
/// the machine's state affects each alike; prints each one's median wall-clock ms per eye.
fn time_frames(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    depth_kind: HostDepth,
    convention: DepthConvention,
) -> Result<(), Box<dyn std::error::Error>> {
    const SIZE: (u32, u32) = (1080, 1200);
    const ROUNDS: usize = 9;
    let prepass = DepthPrepass::new(device, &demo_geometry(), depth_kind, SIZE);
    let tangents = [[-1.2, 0.9, 1.1, -1.1], [-0.9, 1.2, 1.1, -1.1]];
    let views: Vec<ViewMatrices> = demo_eyes()
        .iter()
        .zip(tangents)
        .map(|(view, t)| ViewMatrices { view: *view, projection: depth_kind.projection(t, 0.05) })
        .collect();
    let config = AoConfig { settings: AoSettings::default(), width: SIZE.0, height: SIZE.1, views: 2 };
    let mut engine = AoEngine::new(device, queue, &config)?;
    let normals = HostNormals { texture: &prepass.normals, space: NormalSpace::View, encoding: NormalEncoding::Signed };
    let labels = [
        "host prepass alone",
        "prepass + engine, host normals",
        "prepass + engine, rebuilt normals",
        "prepass + engine, host normals, R8Unorm output",
    ];
    let mut times = vec![Vec::new(); labels.len()];
    // One warm-up round, then ROUNDS measured ones.
    for round in 0..=ROUNDS {
        for (kind, samples) in times.iter_mut().enumerate() {
            let started = std::time::Instant::now();
            let mut encoder = device.create_command_encoder(&Default::default());
            prepass.record(device, &mut encoder, &views);
            if kind > 0 {
                let format = if kind == 3 { AoOutputFormat::R8Unorm } else { AoOutputFormat::Rgba16Float };
                engine.set_output_format(Some(format));
                let frame = AoFrame {
                    depth: &prepass.depth,
                    depth_convention: convention,
                    second_layer: None,
                    normals: (kind != 2).then_some(normals),
                    views: &views,
                    motion: None,
                    light: None,
                    exclusion: None,
                };
                engine.record(&mut encoder, &frame)?;
            }
            queue.submit([encoder.finish()]);
            device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None })?;
            if round > 0 {
                samples.push(started.elapsed().as_secs_f64() * 1e3);
            }
        }
    }
    for (label, mut samples) in labels.iter().zip(times) {
        samples.sort_by(f64::total_cmp);
        eprintln!("{label}: {:.2} ms per eye (median of {ROUNDS})", samples[ROUNDS / 2] / 2.0);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(line: &str) -> Result<Parsed, String> {
        parse_args(&line.split_whitespace().map(String::from).collect::<Vec<_>>())
    }

    #[test]
    fn the_command_line_is_handled_like_vraos() {
        let Ok(Parsed::Run(args)) = parse("") else { panic!("no arguments run with the defaults") };
        assert_eq!(args.out, std::path::PathBuf::from("out"));
        let Ok(Parsed::Run(args)) = parse("dir --no-normals --standard-depth --time --time-setup") else { panic!() };
        assert_eq!(
            args,
            Args {
                out: "dir".into(),
                standard_depth: true,
                no_normals: true,
                msaa: 1,
                layers: 1,
                hand: None,
                time: true,
                time_setup: true
            }
        );
        assert!(matches!(parse("--hand left-out"), Ok(Parsed::Run(Args { hand: Some(Hand::LeftOut), .. }))));
        assert!(matches!(parse("--hand=casting"), Ok(Parsed::Run(Args { hand: Some(Hand::Casting), .. }))));
        assert_eq!(parse("--hand up"), Err("--hand up: the hand is 'left-out' or 'casting'".into()));
        assert_eq!(
            parse("--hand left-out --msaa 4"),
            Err("--hand with --msaa: the example marks its hand in a single-sampled stencil".into())
        );
        let Ok(Parsed::Run(args)) = parse("--msaa 4 dir") else { panic!("--msaa takes its count") };
        assert_eq!((args.msaa, args.out), (4, "dir".into()));
        assert!(matches!(parse("--msaa=8"), Ok(Parsed::Run(Args { msaa: 8, .. }))));
        assert_eq!(parse("--msaa 3"), Err("--msaa 3: the sample count is 1, 2, 4 or 8".into()));
        assert_eq!(parse("--msaa"), Err("--msaa needs a sample count: 1, 2, 4 or 8".into()));
        assert!(matches!(parse("--layers 2 --msaa 4"), Ok(Parsed::Run(Args { layers: 2, msaa: 4, .. }))));
        assert!(matches!(parse("--layers=1"), Ok(Parsed::Run(Args { layers: 1, .. }))));
        assert_eq!(parse("--layers 3"), Err("--layers 3: the engine reads 1 or 2 depth layers".into()));
        assert_eq!(parse("--layers"), Err("--layers needs a count: 1 or 2".into()));
        assert_eq!(
            parse("--hand casting --layers 2"),
            Err("--hand with --layers 2: the example peels its room without the hand".into())
        );
        // --help anywhere prints the usage and renders nothing.
        assert_eq!(parse("--help"), Ok(Parsed::Help));
        assert_eq!(parse("dir -h --bogus"), Ok(Parsed::Help));
        assert_eq!(parse("--bogus -h"), Err("unknown option '--bogus'".into()), "in order, as clap reads them");
        // One line naming what is wrong.
        assert_eq!(parse("--bogus"), Err("unknown option '--bogus'".into()));
        assert_eq!(parse("-x"), Err("unknown option '-x'".into()));
        assert_eq!(parse("--time=5"), Err("--time takes no value: '--time=5'".into()));
        assert_eq!(parse("a b"), Err("a second output folder 'b' (the first is 'a')".into()));
        assert!(USAGE.contains("--standard-depth") && USAGE.contains("--help"));
    }

    #[test]
    fn a_write_error_names_the_path_and_exits_2() {
        let path = std::path::Path::new("/proc/no-such-folder/embed_ao_left.png");
        let failure = save_grey(path, 2, 2, vec![0; 4]).unwrap_err();
        let line = failure.to_string();
        assert!(line.starts_with("/proc/no-such-folder/embed_ao_left.png: cannot write"), "{line}");
        assert!(matches!(failure, Failure::Output { .. }));
        assert_eq!(fail(failure), std::process::ExitCode::from(2));
    }
}
