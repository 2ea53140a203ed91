//! vrao's peer: Bevy 0.19's screen-space AO on the frames vrao scores.
//!
//! `vrao-peer-bevy JOB` reads a job file that `vrao peer` writes (the glTF scene, the
//! per-eye size, each eye's world-from-view and clip-from-view matrices exactly as vrao
//! builds them, Bevy's presets to run, warm-up and measured frames, an output folder),
//! renders the scene headless with one Bevy camera per eye, each with Bevy's
//! `ScreenSpaceAmbientOcclusion` at the preset, and writes into the output folder:
//!
//! - `peer.json`: the adapter, and per preset and eye every measured frame's time of
//!   Bevy's AO chain (its depth preprocess, main pass and spatial denoise: the three
//!   passes Bevy records together) and the medians;
//! - `ao_<preset>_<eye>.f32`: Bevy's AO texture (the spatially denoised visibility,
//!   before lighting), little-endian f32, row by row from the top-left.
//!
//! How a chain is timed: the render systems this program adds around Bevy's SSAO system
//! in each camera's `Core3d` schedule submit everything recorded before it and wait for
//! the device, then submit its passes alone and wait again (the wall clock from that
//! submission to the end of the wait is the serial time, as vrao's serial timing takes
//! each pass); when the
//! device has timestamp queries inside encoders, a timestamp on either side of the
//! passes gives the GPU time too. The presets are interleaved frame by frame.
//!
//! Job file, one item a line: `scene PATH`, `size W H`, `warmup N`, `frames N`,
//! `presets NAME...` (low, medium, high, ultra), `out DIR`, and per eye
//! `eye NAME` followed by 16 numbers of world-from-view and 16 of clip-from-view
//! (column-major). Exit code 2 on a bad job, 1 when rendering fails.

use bevy::app::PluginsState;
use bevy::asset::{AssetPlugin, LoadState};
use bevy::camera::{CameraProjection, RenderTarget, SubCameraView};
use bevy::core_pipeline::core_3d::main_opaque_pass_3d;
use bevy::core_pipeline::deferred::node::late_deferred_prepass;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::ecs::schedule::ApplyDeferred;
use bevy::gltf::GltfAssetLabel;
use bevy::log::{Level, LogPlugin};
use bevy::math::Vec3A;
use bevy::pbr::{
    ScreenSpaceAmbientOcclusion, ScreenSpaceAmbientOcclusionQualityLevel, ScreenSpaceAmbientOcclusionResources,
};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::renderer::{CurrentView, PendingCommandBuffers, RenderDevice, RenderQueue};
use bevy::render::settings::{RenderCreation, WgpuSettings};
use bevy::render::{RenderApp, RenderPlugin};
use bevy::window::{ExitCondition, WindowPlugin};
use bevy::world_serialization::WorldAssetRoot;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Bounds on what a job may ask for.
const MAX_SIZE: u32 = 8192;
const MAX_FRAMES: u32 = 10_000;
/// Frames the scene may take to load before the job fails.
const MAX_LOAD_FRAMES: u32 = 100_000;
/// Frames rendered after the scene has loaded, before any preset's warm-up (meshes and
/// pipelines reach the render world).
const SETTLE_FRAMES: u32 = 3;

/// One eye of the job: its name and matrices.
#[derive(Clone, Debug)]
struct EyeJob {
    name: String,
    world_from_view: Mat4,
    clip_from_view: Mat4,
}

/// What `vrao peer` asks of one run.
#[derive(Clone, Debug)]
struct Job {
    scene: PathBuf,
    width: u32,
    height: u32,
    warmup: u32,
    frames: u32,
    presets: Vec<Preset>,
    out: PathBuf,
    eyes: Vec<EyeJob>,
}

/// One of Bevy's own quality presets.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Preset {
    Low,
    Medium,
    High,
    Ultra,
}

impl Preset {
    fn parse(name: &str) -> Option<Preset> {
        Some(match name {
            "low" => Preset::Low,
            "medium" => Preset::Medium,
            "high" => Preset::High,
            "ultra" => Preset::Ultra,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Preset::Low => "low",
            Preset::Medium => "medium",
            Preset::High => "high",
            Preset::Ultra => "ultra",
        }
    }

    fn level(self) -> ScreenSpaceAmbientOcclusionQualityLevel {
        match self {
            Preset::Low => ScreenSpaceAmbientOcclusionQualityLevel::Low,
            Preset::Medium => ScreenSpaceAmbientOcclusionQualityLevel::Medium,
            Preset::High => ScreenSpaceAmbientOcclusionQualityLevel::High,
            Preset::Ultra => ScreenSpaceAmbientOcclusionQualityLevel::Ultra,
        }
    }
}

/// Parses the job file's text; every line's error names the line.
fn parse_job(text: &str) -> Result<Job, String> {
    let (mut scene, mut size, mut warmup, mut frames, mut presets, mut out) = (None, None, None, None, None, None);
    let mut eyes = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, rest)) = words.split_first() else { continue };
        let bad = |what: &str| format!("job line {}: {what}", n + 1);
        let count = |s: &str| s.parse::<u32>().map_err(|_| bad(&format!("'{s}' is not a count")));
        match (key, rest) {
            ("scene", [path]) => scene = Some(PathBuf::from(path)),
            ("size", [w, h]) => size = Some((count(w)?, count(h)?)),
            ("warmup", [v]) => warmup = Some(count(v)?),
            ("frames", [v]) => frames = Some(count(v)?),
            ("presets", names) if !names.is_empty() => {
                let list: Option<Vec<Preset>> = names.iter().map(|s| Preset::parse(s)).collect();
                presets = Some(list.ok_or_else(|| bad("presets are low, medium, high, ultra"))?);
            }
            ("out", [dir]) => out = Some(PathBuf::from(dir)),
            ("eye", [name, numbers @ ..]) if numbers.len() == 32 => {
                let values: Result<Vec<f32>, _> = numbers.iter().map(|s| s.parse::<f32>()).collect();
                let values = values.map_err(|_| bad("an eye's matrices are 32 numbers"))?;
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(bad("an eye's matrices must be finite"));
                }
                eyes.push(EyeJob {
                    name: name.to_string(),
                    world_from_view: Mat4::from_cols_slice(&values[..16]),
                    clip_from_view: Mat4::from_cols_slice(&values[16..]),
                });
            }
            _ => return Err(bad(&format!("'{line}' is not an item of a job"))),
        }
    }
    let missing = |what: &str| format!("the job names no {what}");
    let (width, height) = size.ok_or_else(|| missing("size"))?;
    let job = Job {
        scene: scene.ok_or_else(|| missing("scene"))?,
        width,
        height,
        warmup: warmup.unwrap_or(2),
        frames: frames.ok_or_else(|| missing("frame count"))?,
        presets: presets.ok_or_else(|| missing("presets"))?,
        out: out.ok_or_else(|| missing("output folder"))?,
        eyes,
    };
    if !(16..=MAX_SIZE).contains(&job.width) || !(16..=MAX_SIZE).contains(&job.height) {
        return Err(format!("size {}x{} is not within 16..={MAX_SIZE}", job.width, job.height));
    }
    if !(1..=MAX_FRAMES).contains(&job.frames) || job.warmup > MAX_FRAMES {
        return Err(format!("frames must be within 1..={MAX_FRAMES} and warm-up at most {MAX_FRAMES}"));
    }
    if !(1..=2).contains(&job.eyes.len()) {
        return Err("a job has one or two eyes".into());
    }
    if job.eyes.iter().any(|e| e.clip_from_view.w_axis.w != 0.0 || e.clip_from_view.z_axis.w != -1.0) {
        return Err("an eye's clip-from-view is not a perspective projection looking down -Z".into());
    }
    Ok(job)
}

/// A fixed projection: the clip-from-view matrix vrao built for the eye (asymmetric,
/// reversed-Z, infinite far plane), given to Bevy as it is.
#[derive(Clone, Debug)]
struct FixedProjection {
    clip_from_view: Mat4,
}

impl FixedProjection {
    /// The frustum's tangents (left, right, up, down) read back from the matrix.
    fn tangents(&self) -> [f32; 4] {
        let m = &self.clip_from_view;
        let (sx, ox, sy, oy) = (m.x_axis.x, m.z_axis.x, m.y_axis.y, m.z_axis.y);
        [(ox - 1.0) / sx, (ox + 1.0) / sx, (oy + 1.0) / sy, (oy - 1.0) / sy]
    }
}

impl CameraProjection for FixedProjection {
    fn get_clip_from_view(&self) -> Mat4 {
        self.clip_from_view
    }

    fn get_clip_from_view_for_sub(&self, _sub_view: &SubCameraView) -> Mat4 {
        self.clip_from_view
    }

    fn update(&mut self, _width: f32, _height: f32) {}

    fn far(&self) -> f32 {
        // The matrix has no far plane; culling needs one, far beyond any scene vrao scores.
        1.0e5
    }

    fn get_frustum_corners(&self, z_near: f32, z_far: f32) -> [Vec3A; 8] {
        let [l, r, u, d] = self.tangents();
        let corner = |x: f32, y: f32, z: f32| Vec3A::new(x * z.abs(), y * z.abs(), z);
        [
            corner(r, d, z_near),
            corner(r, u, z_near),
            corner(l, u, z_near),
            corner(l, d, z_near),
            corner(r, d, z_far),
            corner(r, u, z_far),
            corner(l, u, z_far),
            corner(l, d, z_far),
        ]
    }
}

/// What the current frame is for, set by the main loop before each update.
#[derive(Clone, Copy, Debug, Default)]
struct FrameTag {
    preset: usize,
    measured: bool,
    readback: bool,
}

/// One measured chain: preset, eye (camera order), wall-clock ms, GPU ms.
#[derive(Clone, Copy, Debug)]
struct Sample {
    preset: usize,
    eye: usize,
    wall_ms: f64,
    gpu_ms: Option<f64>,
}

/// Shared between the main loop and the render systems.
#[derive(Default)]
struct Probe {
    tag: FrameTag,
    samples: Vec<Sample>,
    /// (preset, eye, AO values) of readback frames.
    images: Vec<(usize, usize, Vec<f32>)>,
    timestamps: Option<Timestamps>,
    readback: Option<Readback>,
    timestamp_period: f32,
    has_timestamps: bool,
    error: Option<String>,
}

#[derive(Resource, Clone, Default)]
struct ProbeHandle(Arc<Mutex<Probe>>);

/// A pair of timestamps and the buffers that carry them back.
struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
}

/// The compute pass that copies Bevy's AO texture into a buffer (its texture has no
/// COPY_SRC usage).
struct Readback {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

const READBACK_WGSL: &str = r"
@group(0) @binding(0) var ao: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> values: array<f32>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(ao);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    values[id.y * size.x + id.x] = textureLoad(ao, vec2<i32>(id.xy), 0).r;
}
";

/// Submits what is pending and waits for the device.
fn submit_and_wait(device: &RenderDevice, queue: &RenderQueue, pending: &mut PendingCommandBuffers) {
    let buffers = pending.take();
    queue.submit(buffers);
    let _ = device.wgpu_device().poll(wgpu::PollType::wait_indefinitely());
}

/// Maps `buffer` for reading, waits, and returns its bytes.
fn read_buffer(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, String> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    let _ = device.poll(wgpu::PollType::wait_indefinitely());
    match rx.recv() {
        Ok(Ok(())) => {
            let bytes = slice.get_mapped_range().to_vec();
            buffer.unmap();
            Ok(bytes)
        }
        _ => Err("a readback buffer could not be mapped".into()),
    }
}

/// The eye of the current view: its camera's order, when it is one of the job's.
fn current_eye(
    view: &CurrentView,
    cameras: &Query<&ExtractedCamera, With<ScreenSpaceAmbientOcclusionResources>>,
) -> Option<usize> {
    cameras.get(view.0).ok().and_then(|c| usize::try_from(c.order).ok())
}

/// Before Bevy's AO: everything recorded so far runs to completion (and the first
/// timestamp is recorded, to be submitted with the AO passes).
fn before_ao(
    view: Res<CurrentView>,
    cameras: Query<&ExtractedCamera, With<ScreenSpaceAmbientOcclusionResources>>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut pending: ResMut<PendingCommandBuffers>,
    probe: Res<ProbeHandle>,
) {
    if current_eye(&view, &cameras).is_none() {
        return;
    }
    submit_and_wait(&device, &queue, &mut pending);
    let mut p = probe.0.lock().unwrap();
    let wgpu_device = device.wgpu_device();
    if p.has_timestamps {
        let stamps = p.timestamps.get_or_insert_with(|| Timestamps {
            set: wgpu_device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("peer timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: wgpu_device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("peer timestamps resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            read: wgpu_device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("peer timestamps read"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        });
        let mut encoder = wgpu_device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.write_timestamp(&stamps.set, 0);
        pending.push_encoder(encoder);
    }
}

/// After Bevy's AO: its passes alone are submitted and waited for, on the clock (the
/// time is kept for a measured frame); the AO texture is read back for a readback frame.
fn after_ao(
    view: Res<CurrentView>,
    cameras: Query<&ExtractedCamera, With<ScreenSpaceAmbientOcclusionResources>>,
    resources: Query<&ScreenSpaceAmbientOcclusionResources>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut pending: ResMut<PendingCommandBuffers>,
    probe: Res<ProbeHandle>,
) {
    let Some(eye) = current_eye(&view, &cameras) else { return };
    let mut p = probe.0.lock().unwrap();
    let wgpu_device = device.wgpu_device();
    if let Some(stamps) = &p.timestamps {
        let mut encoder = wgpu_device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.write_timestamp(&stamps.set, 1);
        encoder.resolve_query_set(&stamps.set, 0..2, &stamps.resolve, 0);
        encoder.copy_buffer_to_buffer(&stamps.resolve, 0, &stamps.read, 0, 16);
        pending.push_encoder(encoder);
    }
    let started = Instant::now();
    submit_and_wait(&device, &queue, &mut pending);
    let wall_ms = started.elapsed().as_secs_f64() * 1000.0;
    let gpu_ms = match &p.timestamps {
        Some(stamps) => match read_buffer(wgpu_device, &stamps.read) {
            Ok(bytes) => {
                let t = |k: usize| u64::from_le_bytes(bytes[k * 8..k * 8 + 8].try_into().unwrap());
                Some(t(1).wrapping_sub(t(0)) as f64 * p.timestamp_period as f64 / 1.0e6)
            }
            Err(e) => {
                p.error = Some(e);
                None
            }
        },
        None => None,
    };
    let tag = p.tag;
    if tag.measured {
        p.samples.push(Sample { preset: tag.preset, eye, wall_ms, gpu_ms });
    }
    if tag.readback {
        let Ok(res) = resources.get(view.0) else {
            p.error = Some("the view has no SSAO texture".into());
            return;
        };
        match read_ao(wgpu_device, &queue, &mut p, &res.screen_space_ambient_occlusion_texture.texture) {
            Ok(values) => p.images.push((tag.preset, eye, values)),
            Err(e) => p.error = Some(e),
        }
    }
}

/// Copies `texture` (R16Float or R32Float) into a buffer with a compute pass and reads it.
fn read_ao(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    p: &mut Probe,
    texture: &wgpu::Texture,
) -> Result<Vec<f32>, String> {
    let readback = p.readback.get_or_insert_with(|| {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("peer readback"),
            source: wgpu::ShaderSource::Wgsl(READBACK_WGSL.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("peer readback"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("peer readback"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("peer readback"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        Readback { pipeline, layout }
    });
    let (w, h) = (texture.width(), texture.height());
    let size = w as u64 * h as u64 * 4;
    let storage = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("peer ao values"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("peer ao read"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("peer readback"),
        layout: &readback.layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
            wgpu::BindGroupEntry { binding: 1, resource: storage.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&readback.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
    encoder.copy_buffer_to_buffer(&storage, 0, &read, 0, size);
    queue.submit([encoder.finish()]);
    let bytes = read_buffer(device, &read)?;
    Ok(bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect())
}

/// The median of `values` (NaN when empty).
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    }
}

fn json_number(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        "null".into()
    }
}

fn json_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn main() {
    let Some(job_path) = std::env::args_os().nth(1) else {
        eprintln!("usage: vrao-peer-bevy JOB_FILE");
        std::process::exit(2);
    };
    let job = match std::fs::read_to_string(&job_path).map_err(|e| e.to_string()).and_then(|t| parse_job(&t)) {
        Ok(job) => job,
        Err(e) => {
            eprintln!("peer: {e}");
            std::process::exit(2);
        }
    };
    if !job.scene.is_file() || !job.out.is_dir() {
        eprintln!("peer: the scene must be a file and the output a folder");
        std::process::exit(2);
    }
    if let Err(e) = run(&job) {
        eprintln!("peer: {e}");
        std::process::exit(1);
    }
}

fn run(job: &Job) -> Result<(), String> {
    let folder = job.scene.parent().unwrap_or(Path::new(".")).to_path_buf();
    let file = job.scene.file_name().ok_or("the scene has no file name")?.to_string_lossy().into_owned();
    let wgpu_settings =
        WgpuSettings { backends: Some(wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY)), ..default() };
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
            .set(AssetPlugin { file_path: folder.to_string_lossy().into_owned(), ..default() })
            .set(RenderPlugin {
                render_creation: RenderCreation::from(wgpu_settings),
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .set(LogPlugin { level: Level::WARN, ..default() })
            .disable::<PipelinedRenderingPlugin>(),
    );
    let probe = ProbeHandle::default();
    app.sub_app_mut(RenderApp).insert_resource(probe.clone()).add_systems(
        Core3d,
        (
            (ApplyDeferred, before_ao).chain().after(late_deferred_prepass).in_set(Core3dSystems::Prepass),
            (ApplyDeferred, after_ao).chain().in_set(Core3dSystems::MainPass).before(main_opaque_pass_3d),
        ),
    );
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();

    let adapter = {
        let render = app.sub_app(RenderApp).world();
        let device = render.resource::<RenderDevice>();
        let queue = render.resource::<RenderQueue>();
        let info = render.resource::<bevy::render::renderer::RenderAdapterInfo>();
        let features = device.features();
        let mut p = probe.0.lock().unwrap();
        p.has_timestamps =
            features.contains(wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
        p.timestamp_period = queue.get_timestamp_period();
        format!("{} ({:?}, {})", info.name, info.backend, info.driver_info)
    };

    // The scene, and one camera per eye rendering into its own image.
    let scene = app.world().resource::<AssetServer>().load(GltfAssetLabel::Scene(0).from_asset(file));
    app.world_mut().spawn(WorldAssetRoot(scene.clone()));
    let mut cameras = Vec::new();
    for (order, eye) in job.eyes.iter().enumerate() {
        let image = Image::new_target_texture(
            job.width,
            job.height,
            bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
            None,
        );
        let handle = app.world_mut().resource_mut::<Assets<Image>>().add(image);
        let entity = app
            .world_mut()
            .spawn((
                Camera3d::default(),
                Camera { order: order as isize, ..default() },
                RenderTarget::Image(handle.into()),
                Projection::custom(FixedProjection { clip_from_view: eye.clip_from_view }),
                Transform::from_matrix(eye.world_from_view),
                Msaa::Off,
                // No tone-mapping look-up tables in this build; the AO is read before it.
                Tonemapping::None,
                ScreenSpaceAmbientOcclusion { quality_level: job.presets[0].level(), ..default() },
            ))
            .id();
        cameras.push(entity);
    }

    // Load: until the scene and everything it names is in, then a few frames more.
    let mut loaded = 0;
    for _ in 0..MAX_LOAD_FRAMES {
        app.update();
        let server = app.world().resource::<AssetServer>();
        if let Some(LoadState::Failed(e)) = server.get_load_state(&scene) {
            return Err(format!("Bevy could not load {}: {e}", job.scene.display()));
        }
        if server.is_loaded_with_dependencies(&scene) {
            loaded += 1;
            if loaded > SETTLE_FRAMES {
                break;
            }
        }
    }
    if loaded <= SETTLE_FRAMES {
        return Err("the scene did not load".into());
    }

    let frame = |app: &mut App, preset: usize, measured: bool, readback: bool| -> Result<(), String> {
        for &camera in &cameras {
            app.world_mut()
                .entity_mut(camera)
                .insert(ScreenSpaceAmbientOcclusion { quality_level: job.presets[preset].level(), ..default() });
        }
        probe.0.lock().unwrap().tag = FrameTag { preset, measured, readback };
        app.update();
        let error = probe.0.lock().unwrap().error.take();
        error.map_or(Ok(()), Err)
    };
    // Every preset is warmed up (its pipeline specialised), then the measured frames go
    // round the presets one frame each.
    for preset in 0..job.presets.len() {
        for _ in 0..job.warmup.max(1) {
            frame(&mut app, preset, false, false)?;
        }
    }
    for _ in 0..job.frames {
        for preset in 0..job.presets.len() {
            frame(&mut app, preset, true, false)?;
        }
    }
    for preset in 0..job.presets.len() {
        frame(&mut app, preset, false, true)?;
    }

    let p = probe.0.lock().unwrap();
    write_outputs(job, &adapter, &p)
}

/// Writes `peer.json` and the AO images.
fn write_outputs(job: &Job, adapter: &str, p: &Probe) -> Result<(), String> {
    let mut json = String::new();
    let _ = write!(
        json,
        "{{\n  \"peer\": \"bevy 0.19.1 ScreenSpaceAmbientOcclusion\",\n  \"adapter\": {},\n  \"width\": {},\n  \"height\": {},\n  \"warmup\": {},\n  \"frames\": {},\n  \"timestamps\": {},\n  \"presets\": [",
        json_string(adapter),
        job.width,
        job.height,
        job.warmup,
        job.frames,
        p.has_timestamps
    );
    for (k, preset) in job.presets.iter().enumerate() {
        let _ = write!(json, "{}\n    {{\"name\": \"{}\", \"eyes\": [", if k > 0 { "," } else { "" }, preset.name());
        for (e, eye) in job.eyes.iter().enumerate() {
            let samples: Vec<&Sample> = p.samples.iter().filter(|s| s.preset == k && s.eye == e).collect();
            if samples.len() != job.frames as usize {
                return Err(format!(
                    "preset {} eye {}: {} of {} frames ran Bevy's AO",
                    preset.name(),
                    eye.name,
                    samples.len(),
                    job.frames
                ));
            }
            let mut wall: Vec<f64> = samples.iter().map(|s| s.wall_ms).collect();
            let mut gpu: Vec<f64> = samples.iter().filter_map(|s| s.gpu_ms).collect();
            let image = p
                .images
                .iter()
                .find(|(pk, pe, _)| *pk == k && *pe == e)
                .map(|(_, _, v)| v)
                .ok_or_else(|| format!("preset {} eye {}: no AO was read back", preset.name(), eye.name))?;
            if image.len() != (job.width * job.height) as usize {
                return Err(format!("the AO read back has {} values, not {}x{}", image.len(), job.width, job.height));
            }
            if image.iter().all(|&v| v == 0.0) {
                return Err(format!(
                    "preset {} eye {}: Bevy's AO texture is all zero (did its passes run?)",
                    preset.name(),
                    eye.name
                ));
            }
            let file = format!("ao_{}_{}.f32", preset.name(), eye.name);
            let bytes: Vec<u8> = image.iter().flat_map(|v| v.to_le_bytes()).collect();
            std::fs::write(job.out.join(&file), bytes).map_err(|e| format!("writing {file}: {e}"))?;
            let list = |v: &[f64]| v.iter().map(|x| json_number(*x)).collect::<Vec<_>>().join(", ");
            let _ = write!(
                json,
                "{}\n      {{\"eye\": {}, \"ao\": {}, \"wall_ms\": [{}], \"gpu_ms\": [{}], \"median_wall_ms\": {}, \"median_gpu_ms\": {}}}",
                if e > 0 { "," } else { "" },
                json_string(&eye.name),
                json_string(&file),
                list(&wall),
                list(&gpu),
                json_number(median(&mut wall)),
                json_number(median(&mut gpu))
            );
        }
        json.push_str("\n    ]}");
    }
    json.push_str("\n  ]\n}\n");
    std::fs::write(job.out.join("peer.json"), json).map_err(|e| format!("writing peer.json: {e}"))
}
