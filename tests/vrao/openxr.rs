//! The OpenXR headset: the fall back without a runtime (CI: the real loader, no runtime),
//! the swapchain blit's colour encoding and depth copy, and — ignored unless run with
//! `--ignored` against a runtime (`XR_RUNTIME_JSON`, e.g. Monado with
//! `XRT_COMPOSITOR_NULL=1`, which runs headless on lavapipe) — a real session of a few
//! hundred frames, `--frames`, each eye's visibility mask, and a lost session's fall back.
//!
//! A process may hold one OpenXR instance at a time, and these tests change
//! `XR_RUNTIME_JSON`: every test holds the one GPU lock for its whole run.

#![cfg(feature = "xr")]

use crate::common;

use std::path::PathBuf;
use std::sync::Arc;
use vrao::xr::openxr::{
    probe_runtime, EyeBlit, OpenXrHeadset, OpenXrOptions, SessionPhase, SwapchainLayout, Unavailable,
};
use vrao::xr::simulated::{SimulatedOptions, TimeMode};
use vrao::xr::{Headset, SubmittedFrame};
use vrao_ao::plug::{read_layers, read_layers_f32, Gpu, LayeredTarget, DEPTH};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::Scene;
use vrao_render::settings::Settings;
use vrao_render::{BackendChoice, HeadsetProfile};

const RUNTIME_VAR: &str = "XR_RUNTIME_JSON";

/// Points the loader at a runtime manifest that does not exist (so no runtime answers,
/// whatever is installed) until dropped.
struct NoRuntime(Option<std::ffi::OsString>);

impl NoRuntime {
    fn set() -> NoRuntime {
        let saved = std::env::var_os(RUNTIME_VAR);
        std::env::set_var(RUNTIME_VAR, "/nonexistent/vrao-test/no_runtime.json");
        NoRuntime(saved)
    }
}

impl Drop for NoRuntime {
    fn drop(&mut self) {
        match self.0.take() {
            Some(value) => std::env::set_var(RUNTIME_VAR, value),
            None => std::env::remove_var(RUNTIME_VAR),
        }
    }
}

/// The runtime the ignored session tests run against (`XR_RUNTIME_JSON` when set,
/// otherwise the loader's active runtime): its name. Fails the test when none answers.
fn require_runtime() -> String {
    // As the CLI does: Mesa's WSI probe complains on headless machines without it.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    if let Some(path) = std::env::var_os(RUNTIME_VAR).map(PathBuf::from) {
        assert!(path.is_file(), "{RUNTIME_VAR}={} is not a runtime manifest", path.display());
    }
    probe_runtime().unwrap_or_else(|e| {
        panic!(
            "this test needs an OpenXR runtime: {e} (set {RUNTIME_VAR} to a runtime's manifest, e.g. Monado's with \
             XRT_COMPOSITOR_NULL=1)"
        )
    })
}

fn small_simulated(frames: Option<u64>) -> SimulatedOptions {
    let scene = Scene::load("builtin:room").unwrap();
    SimulatedOptions {
        profile: HeadsetProfile::with_size("vive", 48, 40),
        near: 0.05,
        path: scene.head.clone(),
        motion: Default::default(),
        time: TimeMode::Virtual { render_ms: vec![5.0] },
        reprojection: Default::default(),
        compose: false,
        frames,
    }
}

#[test]
fn without_a_runtime_the_library_reports_it_and_falls_back_to_the_simulated_headset() {
    let _one_at_a_time = common::gpu_lock();
    let _no_runtime = NoRuntime::set();
    let ci = std::env::var_os("CI").is_some();
    let expect_no_runtime = |what: &str, why: &Unavailable| match why {
        Unavailable::NoRuntime(_) => {}
        // Without CI's loader package, a missing loader is the other honest answer.
        Unavailable::NoLoader(_) if !ci => {}
        other => panic!("{what}: expected 'no OpenXR runtime', got {other:?}"),
    };
    expect_no_runtime("probe", &probe_runtime().unwrap_err());
    let options = OpenXrOptions::from_simulated(&small_simulated(Some(3)), None);
    match OpenXrHeadset::open(options) {
        Ok(_) => panic!("an OpenXR headset opened with no runtime"),
        Err(why) => expect_no_runtime("open", &why),
    }

    let (mut headset, gpu, message) = vrao::app::open_headset(
        vrao::app::HeadsetChoice::Auto,
        small_simulated(Some(3)),
        None,
        BackendChoice::Auto,
        &Default::default(),
    )
    .expect("the fall back opens");
    assert!(message.contains("using the simulated headset"), "{message}");
    assert!(message.contains(if ci { "no OpenXR runtime" } else { "no OpenXR" }), "{message}");
    assert_eq!(message.lines().count(), 1, "one line: {message}");
    assert!(headset.describe().starts_with("simulated headset"), "{}", headset.describe());
    let mut frames = 0;
    while let Some(request) = headset.wait_frame(&gpu).unwrap() {
        headset.submit(&gpu, &request, None).unwrap();
        frames += 1;
    }
    assert_eq!(frames, 3);
    headset.end(&gpu).unwrap();

    let err = vrao::app::open_headset(
        vrao::app::HeadsetChoice::OpenXr,
        small_simulated(Some(3)),
        None,
        BackendChoice::Auto,
        &Default::default(),
    )
    .err()
    .expect("OpenXR alone without a runtime is an error");
    assert!(matches!(err, vrao::app::HeadsetError::OpenXrUnavailable(_)), "{err}");
    let err = vrao::Error::from(err);
    assert_eq!(err.exit_code(), 2, "{err}");
    let text = err.to_string();
    assert!(text.starts_with("OpenXR headset: ") && text.contains("no OpenXR"), "{text}");
    assert!(!text.contains("no usable GPU"), "an absent runtime is not a GPU problem: {text}");
}

/// Depth32Float cannot be written by copies: a full-screen pass writes a different
/// spread of depths in (0, 1] into each layer.
fn fill_depth(gpu: &Gpu, depth: &LayeredTarget) {
    let module = gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("test depth"),
        source: wgpu::ShaderSource::Wgsl(
            "struct L { layer: f32 }
             @vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
                 let c = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
                 return vec4<f32>(c * 2.0 - 1.0, 0.0, 1.0);
             }
             @fragment fn fs_left(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
                 return 1.0 / (1.0 + 0.37 * floor(p.x) + 2.9 * floor(p.y));
             }
             @fragment fn fs_right(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
                 return fract(0.013 * floor(p.x) + 0.071 * floor(p.y)) * 0.999 + 1e-4;
             }"
            .into(),
        ),
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (layer, entry) in ["fs_left", "fs_right"].into_iter().enumerate() {
        let pipeline = gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("test depth"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("test depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth.layer_views[layer],
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.draw(0..3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.take_error().unwrap();
}

/// 2-layer colour (sRGB-encoded bytes in Rgba8Unorm) and depth targets with every byte
/// value and a spread of depths, as the renderer would hand them over.
fn eye_targets(gpu: &Gpu, (width, height): (u32, u32)) -> (LayeredTarget, LayeredTarget, Vec<Vec<u8>>, Vec<Vec<f32>>) {
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let color = LayeredTarget::new(&gpu.device, "eye colour", COLOR.format(), (width, height, 2), usage);
    let depth_usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT;
    let depth = LayeredTarget::new(&gpu.device, "eye depth", DEPTH.format(), (width, height, 2), depth_usage);
    let texels = (width * height) as usize;
    let color_bytes: Vec<Vec<u8>> = (0..2)
        .map(|layer| {
            (0..texels)
                .flat_map(|i| {
                    let v = (i * 7 + layer * 101) as u8;
                    [v, v.wrapping_add(85), v.wrapping_add(170), 255]
                })
                .collect()
        })
        .collect();
    for (layer, bytes) in color_bytes.iter().enumerate() {
        let origin = wgpu::Origin3d { x: 0, y: 0, z: layer as u32 };
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &color.texture,
                mip_level: 0,
                origin,
                aspect: wgpu::TextureAspect::All,
            },
            bytes,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * 4), rows_per_image: Some(height) },
            size,
        );
    }
    fill_depth(gpu, &depth);
    let depths = read_layers_f32(gpu, &depth).unwrap();
    (color, depth, color_bytes, depths)
}

fn blit_both_eyes(
    gpu: &Gpu,
    color: &LayeredTarget,
    depth: &LayeredTarget,
    out_format: wgpu::TextureFormat,
) -> (LayeredTarget, LayeredTarget) {
    let size = (color.width, color.height, 2);
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let out_color = LayeredTarget::new(&gpu.device, "swapchain colour", out_format, size, usage);
    let out_depth = LayeredTarget::new(&gpu.device, "swapchain depth", wgpu::TextureFormat::Depth32Float, size, usage);
    let blit = EyeBlit::new(&gpu.device, out_format, Some(wgpu::TextureFormat::Depth32Float));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for eye in 0..2 {
        blit.record(
            &gpu.device,
            &mut encoder,
            color,
            depth,
            eye,
            &out_color.layer_views[eye],
            Some(&out_depth.layer_views[eye]),
            (color.width, color.height),
        );
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.take_error().unwrap();
    (out_color, out_depth)
}

fn srgb_to_linear(byte: u8) -> f32 {
    let c = byte as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn the_swapchain_blit_keeps_srgb_bytes_and_depth_exact_and_decodes_for_linear_swapchains() {
    let (gpu, _one_at_a_time) = common::gpu();
    let (color, depth, color_bytes, depths) = eye_targets(&gpu, (64, 40));

    // An sRGB swapchain (the format vrao prefers) ends up with the renderer's bytes.
    let (out_color, out_depth) = blit_both_eyes(&gpu, &color, &depth, wgpu::TextureFormat::Rgba8UnormSrgb);
    let got = read_layers(&gpu, &out_color).unwrap();
    for layer in 0..2 {
        let mismatches = got[layer].iter().zip(&color_bytes[layer]).filter(|(a, b)| a != b).count();
        assert_eq!(mismatches, 0, "layer {layer}: sRGB bytes changed in {mismatches} channels");
    }
    // Reversed-Z depth is copied bit for bit, per eye.
    let got_depth = read_layers_f32(&gpu, &out_depth).unwrap();
    assert_eq!(got_depth, depths);

    // A linear swapchain (float16) holds decoded values: the runtime reads it as linear.
    let (linear, _) = blit_both_eyes(&gpu, &color, &depth, wgpu::TextureFormat::Rgba16Float);
    let values = read_layers_f32(&gpu, &linear).unwrap();
    for layer in 0..2 {
        for (i, (&got, &byte)) in values[layer].iter().zip(&color_bytes[layer]).enumerate() {
            let expected = if i % 4 == 3 { 1.0 } else { srgb_to_linear(byte) };
            assert!((got - expected).abs() <= 1e-3 + expected * 1e-3, "layer {layer} channel {i}: {got} vs {expected}");
        }
    }
    // BGRA swapchains too: same colours, swapped channel order.
    let (bgra, _) = blit_both_eyes(&gpu, &color, &depth, wgpu::TextureFormat::Bgra8UnormSrgb);
    let got = read_layers(&gpu, &bgra).unwrap();
    for (texel, expected) in got[1].chunks_exact(4).zip(color_bytes[1].chunks_exact(4)) {
        assert_eq!([texel[2], texel[1], texel[0], texel[3]], [expected[0], expected[1], expected[2], expected[3]]);
    }
}

/// Renders and submits `frames` frames; returns how many were rendered.
fn run_frames(
    headset: &mut dyn Headset,
    gpu: &Arc<Gpu>,
    renderer: &mut vrao_render::renderer::Renderer,
    frames: u64,
) -> u64 {
    let mut rendered = 0;
    for _ in 0..frames {
        let Some(request) = headset.wait_frame(gpu).expect("wait_frame") else { break };
        if !request.should_render {
            headset.submit(gpu, &request, None).expect("submit");
            continue;
        }
        for eye in &request.eyes.eyes {
            eye.fov.validate().expect("the runtime's fov is a valid frustum");
            assert!(eye.pose.position.is_finite());
        }
        renderer.render(&request.eyes.eyes, &[COLOR, DEPTH]).expect("render");
        let color = renderer.target(COLOR).unwrap();
        let depth = renderer.target(DEPTH).unwrap();
        let frame = SubmittedFrame { color, depth, eyes: &request.eyes, near: request.eyes.near };
        headset.submit(gpu, &request, Some(frame)).expect("submit");
        rendered += 1;
    }
    rendered
}

fn session_options(fallback: Option<SimulatedOptions>) -> OpenXrOptions {
    let simulated = small_simulated(None);
    OpenXrOptions { size: Some((96, 80)), report: false, fallback, ..OpenXrOptions::from_simulated(&simulated, None) }
}

fn renderer_for(headset: &OpenXrHeadset, gpu: &Arc<Gpu>) -> vrao_render::renderer::Renderer {
    let scene = Scene::load("builtin:room").unwrap();
    let (width, height) = headset.recommended_size();
    let settings = Settings { profile: HeadsetProfile::with_size("openxr", width, height), ..Settings::default() };
    vrao_render::renderer::Renderer::new(gpu.clone(), &scene, &settings).unwrap()
}

/// `want` appears in `seen` in order (other states may come between).
fn in_order(seen: &[SessionPhase], want: &[SessionPhase]) -> bool {
    let mut rest = seen.iter();
    want.iter().all(|w| rest.any(|s| s == w))
}

#[test]
fn the_simulated_headset_ends_at_request_exit_and_has_no_openxr_report() {
    let (gpu, _one_at_a_time) = common::gpu();
    let mut headset = vrao::xr::simulated::SimulatedHeadset::new(small_simulated(Some(10))).unwrap();
    assert_eq!(headset.openxr_report(), None);
    let request = headset.wait_frame(&gpu).unwrap().expect("a first frame");
    headset.submit(&gpu, &request, None).unwrap();
    headset.request_exit();
    assert_eq!(headset.wait_frame(&gpu).unwrap(), None, "no frame after request_exit");
    headset.end(&gpu).unwrap();
}

#[test]
#[ignore = "needs an OpenXR runtime (e.g. Monado); run with --ignored"]
fn a_real_session_reaches_focused_submits_depth_and_ends_cleanly() {
    let _one_at_a_time = common::gpu_lock();
    let runtime = require_runtime();
    let (mut headset, gpu) =
        OpenXrHeadset::open(session_options(None)).unwrap_or_else(|e| panic!("{runtime} did not open a session: {e}"));
    eprintln!("{}", headset.describe());
    assert_eq!(headset.recommended_size(), (96, 80));
    let mut renderer = renderer_for(&headset, &gpu);

    const FRAMES: u64 = 300;
    let rendered = run_frames(&mut headset, &gpu, &mut renderer, FRAMES);
    assert!(rendered > FRAMES / 2, "only {rendered} of {FRAMES} frames were rendered");
    assert!(headset.phases().contains(&SessionPhase::Focused), "{:?}", headset.phases());

    // Ask to leave: the runtime walks STOPPING → (xrEndSession) → IDLE → EXITING.
    headset.request_exit();
    let mut after_exit = 0;
    while let Some(request) = headset.wait_frame(&gpu).unwrap() {
        headset.submit(&gpu, &request, None).unwrap();
        after_exit += 1;
        assert!(after_exit < 1000, "the session did not end after xrRequestExitSession");
    }
    headset.end(&gpu).unwrap();

    use SessionPhase::*;
    let phases = headset.phases().to_vec();
    assert!(
        in_order(&phases, &[Idle, Ready, Synchronized, Visible, Focused, Stopping, Idle, Exiting]),
        "session states: {phases:?}"
    );
    assert!(!phases.contains(&LossPending) && headset.lost().is_none(), "{phases:?} {:?}", headset.lost());
    let stats = headset.stats();
    let counters = headset.counters();
    eprintln!("states {phases:?}\nstats {stats:?}\ncounters {counters:?}");
    assert_eq!(counters.submitted, rendered);
    assert_eq!(stats.layers, rendered, "every rendered frame ends with the projection layer");
    assert_eq!(counters.presented, 0, "OpenXR does not say what the compositor presented");
    assert!(headset.submits_depth(), "Monado has XR_KHR_composition_layer_depth: {}", headset.swapchains());
    assert_eq!(stats.layers_with_depth, stats.layers, "every layer carries depth");
    assert_eq!(counters.reprojected, 0, "reprojection is the runtime's and not counted");
    let report = headset.openxr_report().expect("the OpenXR headset reports");
    eprintln!("report {}", serde_json::to_string(&report).unwrap());
    assert_eq!(report.frames_rendered, rendered);
    assert_eq!(report.layers_submitted, rendered);
    assert_eq!(report.depth_layers_submitted, rendered);
    assert_eq!(report.empty_frames, stats.empty_frames);
    // What the runtime said: frames it asked not to render, and its display period (the
    // budget); missed periods are the gaps between predicted display times.
    assert_eq!(report.not_rendered, stats.not_rendered);
    assert_eq!(report.missed_display_periods, stats.missed_display_periods);
    assert!(report.display_period_ms > 0.0, "{report:?}");
    assert!(report.missed_display_periods < stats.frames, "{report:?}");
    assert_eq!(report.interrupted_in, None);
    // XR_FB_display_refresh_rate, where offered: the rate is one the runtime lists.
    if !report.display_refresh_rates_hz.is_empty() {
        let rate = report.display_refresh_rate_hz.expect("a rate is reported with the extension");
        assert!(report.display_refresh_rates_hz.contains(&rate), "{report:?}");
    }
    assert_eq!(report.states_seen, phases.iter().map(|p| p.name()).collect::<Vec<_>>());
    assert_eq!((report.loss_reason, report.ending.as_deref(), report.fell_back), (None, Some("EXITING"), false));
    assert_eq!(report.runtime, runtime);
    drop(renderer);
    drop(headset);
    // The instance is gone: another may be made.
    probe_runtime().expect("a new instance after the session ended");
}

#[test]
#[ignore = "needs an OpenXR runtime (e.g. Monado); run with --ignored"]
fn frames_counts_rendered_frames_then_the_session_walks_to_exiting() {
    let _one_at_a_time = common::gpu_lock();
    require_runtime();
    let options = OpenXrOptions { frames: Some(30), ..session_options(None) };
    let (mut headset, gpu) = OpenXrHeadset::open(options).expect("session");
    let mut renderer = renderer_for(&headset, &gpu);
    // More than asked for: wait_frame returns None after the 30th rendered frame.
    let rendered = run_frames(&mut headset, &gpu, &mut renderer, 1000);
    assert_eq!(rendered, 30);
    assert!(headset.wait_frame(&gpu).unwrap().is_none());
    let report = headset.openxr_report().unwrap();
    assert_eq!(report.frames_rendered, 30);
    assert_eq!(report.layers_submitted, 30);
    assert_eq!(report.ending.as_deref(), Some("EXITING"), "{report:?}");
    assert!(report.states_seen.ends_with(&["STOPPING".into(), "IDLE".into(), "EXITING".into()]), "{report:?}");
    headset.end(&gpu).unwrap();
}

#[test]
#[ignore = "needs an OpenXR runtime (e.g. Monado); run with --ignored"]
fn a_lost_session_continues_on_the_simulated_headset_with_the_same_gpu() {
    let _one_at_a_time = common::gpu_lock();
    require_runtime();
    let (mut headset, gpu) = OpenXrHeadset::open(session_options(Some(small_simulated(None)))).expect("session");
    let mut renderer = renderer_for(&headset, &gpu);
    let before = run_frames(&mut headset, &gpu, &mut renderer, 20);
    assert!(before > 0);
    let runtime_mask = headset.visibility_mask().cloned();
    headset.simulate_loss("test: LOSS_PENDING");
    assert_eq!(headset.lost(), Some("test: LOSS_PENDING"));
    assert!(headset.describe().starts_with("simulated headset"), "{}", headset.describe());
    assert_eq!(headset.recommended_size(), (96, 80), "the fall back keeps the render size");
    // The mask is the fall back's (its profile's lens) from now on.
    let mask = headset.visibility_mask().expect("the simulated headset's profile has a mask");
    assert_ne!(Some(mask), runtime_mask.as_ref());
    // The runtime's instance is gone; the GPU it made keeps rendering.
    probe_runtime().expect("the OpenXR instance was released");
    let after = run_frames(&mut headset, &gpu, &mut renderer, 10);
    assert_eq!(after, 10);
    assert_eq!(headset.counters().submitted, before + after);
    let report = headset.openxr_report().expect("still reported after the fall back");
    assert_eq!(report.loss_reason.as_deref(), Some("test: LOSS_PENDING"));
    assert!(report.fell_back);
    assert_eq!(report.frames_rendered, before);
    assert_eq!(
        report.frames_rendered, report.layers_submitted,
        "a frame counts as rendered once its layer is submitted"
    );
    // The fall back takes the exit request.
    headset.request_exit();
    assert!(headset.wait_frame(&gpu).unwrap().is_none());
    headset.end(&gpu).unwrap();
}

#[test]
#[ignore = "needs an OpenXR runtime (e.g. Monado); run with --ignored"]
fn the_runtime_gives_each_eye_a_visibility_mask() {
    let _one_at_a_time = common::gpu_lock();
    let runtime = require_runtime();
    let (mut headset, gpu) = OpenXrHeadset::open(session_options(None)).expect("session");
    // Read at the start (XR_KHR_visibility_mask), or built from the first frame's fields of
    // view (Monado's default) where vrao does not read the runtime's.
    let mut request = None;
    for _ in 0..100 {
        let Some(r) = headset.wait_frame(&gpu).expect("wait_frame") else { break };
        headset.submit(&gpu, &r, None).expect("submit");
        if r.should_render {
            request = Some(r);
            break;
        }
    }
    let request = request.expect("a frame to render");
    let mask = headset.visibility_mask().cloned().expect("a mask once the first frame is located");
    let report = headset.openxr_report().unwrap();
    assert_eq!(mask.views.len(), 2);
    let (width, height) = headset.recommended_size();
    for (view, eye) in mask.views.iter().zip(&request.eyes.eyes) {
        let share = view.hidden_share(width, height, eye.fov.tangents());
        eprintln!("{:?} eye: {:.4} hidden ({})", eye.side, share, view.source);
        assert!(share > 0.0 && share < 0.5, "{share}");
        assert_eq!(
            view.source.contains("(XR_KHR_visibility_mask)"),
            report.visibility_mask_from_runtime,
            "{}",
            view.source
        );
        if runtime.starts_with("Monado") {
            // Monado's default for a device without its own (the simulated HMD): a corner cut
            // an eighth of the width and height on its legs, 1/32 of the rectangle.
            assert!((share - 0.03125).abs() < 0.003, "{share}");
        }
    }
    assert_eq!(report.visibility_mask_changes, 0, "{report:?}");
    headset.request_exit();
    while let Some(r) = headset.wait_frame(&gpu).unwrap() {
        headset.submit(&gpu, &r, None).unwrap();
    }
    headset.end(&gpu).unwrap();
}

#[test]
#[ignore = "needs an OpenXR runtime (e.g. Monado); run with --ignored"]
fn one_swapchain_per_eye_works_too() {
    let _one_at_a_time = common::gpu_lock();
    require_runtime();
    let options = OpenXrOptions { layout: Some(SwapchainLayout::PerEye), ..session_options(None) };
    let (mut headset, gpu) = OpenXrHeadset::open(options).expect("session");
    assert!(headset.swapchains().contains("one swapchain per eye"), "{}", headset.swapchains());
    let mut renderer = renderer_for(&headset, &gpu);
    let rendered = run_frames(&mut headset, &gpu, &mut renderer, 40);
    assert!(rendered > 20, "{rendered}");
    headset.end(&gpu).unwrap();
    assert!(headset.phases().contains(&SessionPhase::Exiting), "end() walks to EXITING: {:?}", headset.phases());
    assert_eq!(headset.stats().layers_with_depth, rendered);
    assert!(headset.lost().is_none());
}

#[test]
#[ignore = "needs an OpenXR runtime (e.g. Monado); run with --ignored"]
fn an_interrupt_ends_the_session_in_whatever_state_it_is() {
    let _one_at_a_time = common::gpu_lock();
    require_runtime();
    // Before any frame (the session not yet READY or just begun) and while FOCUSED.
    for frames_first in [0, 10] {
        let interrupt = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let options = OpenXrOptions { interrupt: Some(interrupt.clone()), ..session_options(None) };
        let (mut headset, gpu) = OpenXrHeadset::open(options).expect("session");
        let mut renderer = renderer_for(&headset, &gpu);
        run_frames(&mut headset, &gpu, &mut renderer, frames_first);
        interrupt.store(true, std::sync::atomic::Ordering::Relaxed);
        let mut after = 0;
        while let Some(request) = headset.wait_frame(&gpu).unwrap() {
            headset.submit(&gpu, &request, None).unwrap();
            after += 1;
            assert!(after < 1000, "the interrupt did not end the session");
        }
        headset.end(&gpu).unwrap();
        let report = headset.openxr_report().unwrap();
        eprintln!("interrupted after {frames_first} frames: {report:?}");
        assert!(report.interrupted_in.is_some(), "{report:?}");
        assert_eq!(report.loss_reason, None, "{report:?}");
        if frames_first > 0 {
            assert_eq!(report.ending.as_deref(), Some("EXITING"), "a running session walks to EXITING: {report:?}");
        }
        drop(renderer);
        drop(headset);
        probe_runtime().expect("the session and instance were destroyed");
    }
}
