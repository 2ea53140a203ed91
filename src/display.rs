//! The desktop window (winit) with its egui panel, showing the headset session in one of
//! seed 003's display modes (§5.2): `mirror` (both eyes side by side, as the headset's
//! compositor shows them) or `single-pass` (the scene rendered once more, mono, from the
//! head's viewpoint at the window's size). `none` never opens a window (see `main.rs`).
//!
//! Each redraw steps the headset frame loop once, then draws the picture and the panel.
//! A minimised (0×0) window keeps the headset running and skips presenting; a lost or
//! outdated surface is reconfigured.

use crate::app::{BufferView, FrameLoop, RunSummary};
use crate::error::{Error, Result};
use crate::gpu::kernel::shader_module;
use crate::gpu::Gpu;
use crate::graph::Resource;
use crate::renderer::Renderer;
use crate::scene::Scene;
use crate::settings::{BounceForm, DisplayMode, Quality, Settings, Technique};
use crate::stereo::{EyePair, Fov, HeadPose};
use std::path::PathBuf;
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

pub struct WindowOptions {
    pub mode: DisplayMode,
    /// Initial inner size in physical pixels.
    pub size: (u32, u32),
    /// Save the window's last picture (panel included) to this PNG.
    pub screenshot: Option<PathBuf>,
    /// What the picture shows of each eye at first (the panel can change it).
    pub show: BufferView,
}

/// Opens the window and runs the session until the headset ends it or the window closes.
pub fn run_window(mut frame_loop: FrameLoop, scene: &Scene, options: WindowOptions) -> Result<RunSummary> {
    frame_loop.buffer_view = options.show;
    let event_loop = EventLoop::new().map_err(|e| Error::Device(format!("cannot open a desktop window: {e}")))?;
    let mut app = WindowApp { frame_loop, scene: scene.clone(), options, window: None, error: None, finished: false };
    event_loop.run_app(&mut app).map_err(|e| Error::Device(format!("the window's event loop failed: {e}")))?;
    app.frame_loop.end()?;
    if let Some(e) = app.error {
        return Err(e);
    }
    Ok(RunSummary::of(&app.frame_loop))
}

struct WindowApp {
    frame_loop: FrameLoop,
    scene: Scene,
    options: WindowOptions,
    window: Option<WindowState>,
    error: Option<Error>,
    finished: bool,
}

/// Everything that exists only while the window does.
struct WindowState {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    blit: Blit,
    egui_ctx: egui::Context,
    egui_winit: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    panel: PanelState,
    /// The mono renderer of the single-pass mode, at the picture's size.
    mono: Option<Renderer>,
    /// The panel's last tessellation, for the screenshot.
    last_paint: Option<(Vec<egui::ClippedPrimitive>, egui_wgpu::ScreenDescriptor)>,
}

/// Width of the egui side panel in points.
const PANEL_WIDTH: f32 = 300.0;

/// What the panel edits: a copy of the settings, applied when it changes.
struct PanelState {
    settings: Settings,
    quality: Option<Quality>,
    mode: DisplayMode,
    /// The buffer the picture shows of each eye.
    show: BufferView,
    /// Presented, reprojected and dropped frames per second, from the counters' change
    /// over the last second.
    rates: [f64; 3],
    rate_base: Option<(std::time::Instant, crate::headset::FrameCounters)>,
    /// Governor changes already taken into the panel's settings.
    governor_changes_seen: usize,
}

impl PanelState {
    fn update_rates(&mut self, counters: &crate::headset::FrameCounters) {
        let now = std::time::Instant::now();
        match self.rate_base {
            Some((since, base)) if now.duration_since(since).as_secs_f64() >= 1.0 => {
                let dt = now.duration_since(since).as_secs_f64();
                self.rates = [
                    counters.presented.saturating_sub(base.presented) as f64 / dt,
                    counters.reprojected.saturating_sub(base.reprojected) as f64 / dt,
                    counters.dropped.saturating_sub(base.dropped) as f64 / dt,
                ];
                self.rate_base = Some((now, *counters));
            }
            Some(_) => {}
            None => self.rate_base = Some((now, *counters)),
        }
    }
}

/// What the panel shows besides the settings it edits.
struct PanelInfo<'a> {
    history: &'a crate::app::PassHistory,
    budget_ms: f64,
    governor: Option<&'a crate::governor::Governor>,
}

impl ApplicationHandler for WindowApp {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        match WindowState::new(event_loop, &self.frame_loop, &self.options) {
            Ok(state) => {
                state.window.request_redraw();
                self.window = Some(state);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(state) = self.window.as_mut() else { return };
        let response = state.egui_winit.on_window_event(&state.window, &event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => state.resize(&self.frame_loop.gpu, size.width, size.height),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            _ => {
                if response.repaint {
                    state.window.request_redraw();
                }
            }
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        // The headset wants frames continuously, whether or not anything changed.
        if let Some(state) = &self.window {
            state.window.request_redraw();
        }
    }
}

impl WindowApp {
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        if self.finished {
            return Ok(());
        }
        let step = self.frame_loop.step()?;
        let state = self.window.as_mut().expect("redraw comes with a window");
        let last = step.is_none();
        if let Some(step) = &step {
            if state.panel.mode == DisplayMode::SinglePass {
                state.render_mono(&self.frame_loop, &self.scene, &step.request.eyes)?;
            }
        }
        state.draw(&mut self.frame_loop)?;
        if last {
            if let Some(path) = &self.options.screenshot {
                state.screenshot(&self.frame_loop, path)?;
            }
            self.finished = true;
            event_loop.exit();
        }
        self.frame_loop.gpu.take_error()
    }
}

impl WindowState {
    fn new(event_loop: &ActiveEventLoop, frame_loop: &FrameLoop, options: &WindowOptions) -> Result<WindowState> {
        let gpu = &frame_loop.gpu;
        let attributes = Window::default_attributes()
            .with_title(format!("vrao — {}", frame_loop.headset.describe()))
            .with_inner_size(winit::dpi::PhysicalSize::new(options.size.0, options.size.1));
        let window = Arc::new(
            event_loop.create_window(attributes).map_err(|e| Error::Device(format!("cannot create a window: {e}")))?,
        );
        let surface = gpu
            .instance
            .create_surface(window.clone())
            .map_err(|e| Error::Device(format!("cannot draw into the window: {e}")))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        // The eye images hold sRGB-encoded values: a non-sRGB surface shows them as they are.
        let format =
            caps.formats.iter().copied().find(|f| !f.is_srgb()).or_else(|| caps.formats.first().copied()).ok_or_else(
                || Error::Device(format!("{} cannot present to this window", gpu.adapter.get_info().name)),
            )?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoNoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        if size.width > 0 && size.height > 0 {
            surface.configure(&gpu.device, &config);
        }
        let egui_ctx = egui::Context::default();
        let egui_winit = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        let egui_renderer = egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        let settings = frame_loop.renderer.settings().clone();
        let quality = Quality::ALL.into_iter().find(|q| q.samples() == settings.ao.samples);
        Ok(WindowState {
            window,
            surface,
            config,
            blit: Blit::new(gpu, format),
            egui_ctx,
            egui_winit,
            egui_renderer,
            panel: PanelState {
                settings,
                quality,
                mode: options.mode,
                show: frame_loop.buffer_view,
                rates: [0.0; 3],
                rate_base: None,
                governor_changes_seen: 0,
            },
            mono: None,
            last_paint: None,
        })
    }

    fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) {
        // 0×0 is a minimised window: keep the old configuration and skip presenting.
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&gpu.device, &self.config);
        }
    }

    fn minimised(&self) -> bool {
        let size = self.window.inner_size();
        size.width == 0 || size.height == 0
    }

    /// The picture area (right of the panel) in physical pixels: x, y, width, height.
    fn picture_area(&self, panel_width_px: f32) -> (f32, f32, f32, f32) {
        let (w, h) = (self.config.width as f32, self.config.height as f32);
        let x = panel_width_px.min(w - 1.0).max(0.0);
        (x, 0.0, (w - x).max(1.0), h)
    }

    /// Renders the mono view of the single-pass mode at the picture's size.
    fn render_mono(&mut self, frame_loop: &FrameLoop, scene: &Scene, eyes: &EyePair) -> Result<()> {
        let panel_px = PANEL_WIDTH * self.window.scale_factor() as f32;
        let (_, _, w, h) = self.picture_area(panel_px);
        let (w, h) = ((w as u32).max(1), (h as u32).max(1));
        let mut settings = self.panel.settings.clone();
        settings.profile.width = w;
        settings.profile.height = h;
        let stale = self.mono.as_ref().is_none_or(|m| {
            let p = &m.settings().profile;
            (p.width, p.height) != (w, h)
        });
        if stale {
            self.mono = Some(Renderer::new(frame_loop.gpu.clone(), scene, &settings)?);
        }
        let mono = self.mono.as_mut().expect("made above");
        mono.set_settings(&settings)?;
        // The head: midway between the eyes, looking their way; the headset's vertical
        // field of view, and the horizontal one the window's aspect gives.
        let [left, right] = eyes.eyes;
        let head =
            HeadPose { position: (left.pose.position + right.pose.position) * 0.5, orientation: left.pose.orientation };
        let tan_up = (left.fov.up as f64).tan();
        let tan_side = tan_up * w as f64 / h as f64;
        let fov =
            Fov { left: -(tan_side.atan() as f32), right: tan_side.atan() as f32, up: left.fov.up, down: -left.fov.up };
        mono.render(&[EyePair::mono(&head, fov)], &[Resource::Color])?;
        Ok(())
    }

    /// Runs the panel, then draws the picture and the panel into the surface.
    fn draw(&mut self, frame_loop: &mut FrameLoop) -> Result<()> {
        let gpu = frame_loop.gpu.clone();
        let raw_input = self.egui_winit.take_egui_input(&self.window);
        let counters = frame_loop.headset.counters();
        self.panel.update_rates(&counters);
        // The governor's changes become the panel's settings, so that the panel shows
        // what runs and edits start from it.
        if let Some(governor) = &frame_loop.governor {
            if governor.changes().len() != self.panel.governor_changes_seen {
                self.panel.governor_changes_seen = governor.changes().len();
                self.panel.settings.ao = frame_loop.renderer.settings().ao.clone();
                self.panel.quality = Quality::ALL.into_iter().find(|q| q.samples() == self.panel.settings.ao.samples);
            }
        }
        let mut changed = false;
        let panel = &mut self.panel;
        let info = PanelInfo {
            history: &frame_loop.history,
            budget_ms: frame_loop.budget_ms,
            governor: frame_loop.governor.as_ref(),
        };
        let full_output = self.egui_ctx.run_ui(raw_input, |ui| {
            changed = panel_ui(ui, panel, &info, &counters);
        });
        self.egui_winit.handle_platform_output(&self.window, full_output.platform_output);
        // The next frame also produces the buffer shown (shown from then on).
        frame_loop.buffer_view = self.panel.show;
        if changed {
            match frame_loop.renderer.set_settings(&self.panel.settings) {
                Ok(()) => {}
                Err(e) => log::warn!("panel: {e}"),
            }
        }
        if self.minimised() {
            return Ok(());
        }
        let pixels_per_point = full_output.pixels_per_point;
        let paint_jobs = self.egui_ctx.tessellate(full_output.shapes, pixels_per_point);
        let screen =
            egui_wgpu::ScreenDescriptor { size_in_pixels: [self.config.width, self.config.height], pixels_per_point };
        for (id, deltas) in &full_output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer.update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame) | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => frame,
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&gpu.device, &self.config);
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                // A lost surface is made anew from the window.
                self.surface = gpu
                    .instance
                    .create_surface(self.window.clone())
                    .map_err(|e| Error::Device(format!("cannot recreate the window surface: {e}")))?;
                self.surface.configure(&gpu.device, &self.config);
                return Ok(());
            }
            other => {
                log::warn!("window surface: {other:?}; skipping this picture");
                return Ok(());
            }
        };
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.encode_picture(frame_loop, &view, &paint_jobs, &screen);
        for id in &full_output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        self.last_paint = Some((paint_jobs, screen));
        gpu.queue.present(frame);
        Ok(())
    }
}

impl WindowState {
    /// The images the picture shows and how to draw them: the two eyes (mirror), the
    /// mono view, or each eye's buffer that the panel's "show" picks.
    fn picture_images<'a>(&'a self, frame_loop: &'a FrameLoop) -> (PictureKind, Vec<&'a wgpu::TextureView>) {
        if self.panel.show != BufferView::Eyes {
            let target =
                self.panel.show.resource(frame_loop.renderer.settings()).and_then(|r| frame_loop.renderer.target(r));
            return (
                PictureKind::of(self.panel.show),
                target.map(|t| t.layer_views.iter().take(2).collect()).unwrap_or_default(),
            );
        }
        let images = match self.panel.mode {
            DisplayMode::SinglePass => match self.mono.as_ref().and_then(|m| m.target(Resource::Color)) {
                Some(target) => vec![&target.layer_views[0]],
                None => vec![],
            },
            _ => {
                // What the headset shows (the compositor's output), else the eye buffers.
                let target = frame_loop.headset.display_image().or_else(|| frame_loop.renderer.target(Resource::Color));
                target.map(|t| t.layer_views.iter().take(2).collect()).unwrap_or_default()
            }
        };
        (PictureKind::Eye, images)
    }

    /// Records and submits the picture (eye images fitted into the area right of the
    /// panel, aspect kept) and the panel on top, into `view`.
    fn encode_picture(
        &mut self,
        frame_loop: &FrameLoop,
        view: &wgpu::TextureView,
        paint_jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let gpu = &frame_loop.gpu;
        let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("window") });
        let buffers = self.egui_renderer.update_buffers(&gpu.device, &gpu.queue, &mut encoder, paint_jobs, screen);
        let (kind, images) = self.picture_images(frame_loop);
        let eye_aspect = {
            let p = &frame_loop.renderer.settings().profile;
            p.width as f32 / p.height as f32
        };
        let (ax, ay, aw, ah) = self.picture_area(PANEL_WIDTH * screen.pixels_per_point);
        let bind_groups: Vec<wgpu::BindGroup> = images.iter().map(|v| self.blit.bind_group(gpu, kind, v)).collect();
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("window"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view,
                        resolve_target: None,
                        depth_slice: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.02, g: 0.02, b: 0.02, a: 1.0 }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            let count = bind_groups.len().max(1) as f32;
            for (i, group) in bind_groups.iter().enumerate() {
                // Each image gets an equal slot; within it, the largest rectangle of its aspect.
                let mono = self.panel.mode == DisplayMode::SinglePass && kind == PictureKind::Eye;
                let aspect = if mono { aw / ah } else { eye_aspect };
                let (slot_w, slot_h) = (aw / count, ah);
                let (w, h) =
                    if slot_w / slot_h > aspect { (slot_h * aspect, slot_h) } else { (slot_w, slot_w / aspect) };
                let x = ax + slot_w * i as f32 + (slot_w - w) * 0.5;
                let y = ay + (slot_h - h) * 0.5;
                pass.set_viewport(x, y, w.max(1.0), h.max(1.0), 0.0, 1.0);
                pass.set_pipeline(self.blit.pipeline(kind));
                pass.set_bind_group(0, group, &[]);
                pass.draw(0..3, 0..1);
            }
            pass.set_viewport(0.0, 0.0, self.config.width as f32, self.config.height as f32, 0.0, 1.0);
            self.egui_renderer.render(&mut pass, paint_jobs, screen);
        }
        gpu.queue.submit(buffers.into_iter().chain([encoder.finish()]));
    }

    /// Draws the last picture again into an offscreen texture and saves it as a PNG.
    fn screenshot(&mut self, frame_loop: &FrameLoop, path: &std::path::Path) -> Result<()> {
        let gpu = frame_loop.gpu.clone();
        let Some((paint_jobs, screen)) = self.last_paint.take() else {
            return Err(Error::Output { path: path.to_path_buf(), message: "the window never drew a picture".into() });
        };
        let (width, height) = (self.config.width, self.config.height);
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.encode_picture(frame_loop, &view, &paint_jobs, &screen);
        let target = crate::gpu::targets::LayeredTarget {
            layer_views: vec![],
            array_view: texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }),
            texture,
            format: self.config.format,
            width,
            height,
            layers: 1,
        };
        let mut pixels = crate::gpu::readback::read_layers(&gpu, &target)?.remove(0);
        if matches!(self.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb) {
            pixels.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        pixels.chunks_exact_mut(4).for_each(|p| p[3] = 255);
        image::save_buffer(path, &pixels, width, height, image::ColorType::Rgba8)
            .map_err(|e| Error::Output { path: path.to_path_buf(), message: e.to_string() })
    }
}

/// How a picture image is drawn: the eye image filtered, or a buffer texel for texel
/// (shaders/mirror.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PictureKind {
    Eye,
    Occlusion,
    Normals,
    Depth,
}

impl PictureKind {
    fn of(view: BufferView) -> PictureKind {
        match view {
            BufferView::Eyes => PictureKind::Eye,
            BufferView::FinalAo | BufferView::RawAo => PictureKind::Occlusion,
            BufferView::Normals => PictureKind::Normals,
            BufferView::Depth => PictureKind::Depth,
        }
    }
}

/// The picture's pipelines: a full-screen triangle drawing one 2D view into a viewport,
/// one pipeline per [`PictureKind`].
struct Blit {
    eye: wgpu::RenderPipeline,
    occlusion: wgpu::RenderPipeline,
    normals: wgpu::RenderPipeline,
    depth: wgpu::RenderPipeline,
    eye_layout: wgpu::BindGroupLayout,
    float_layout: wgpu::BindGroupLayout,
    depth_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

/// A bind group layout of one fragment-stage texture or sampler per entry.
fn fragment_layout(gpu: &Gpu, label: &str, entries: &[(u32, wgpu::BindingType)]) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = entries
        .iter()
        .map(|&(binding, ty)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty,
            count: None,
        })
        .collect();
    gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

fn texture_binding(sample_type: wgpu::TextureSampleType) -> wgpu::BindingType {
    wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false }
}

impl Blit {
    fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Blit {
        let device = &gpu.device;
        let eye_layout = fragment_layout(
            gpu,
            "mirror",
            &[
                (0, texture_binding(wgpu::TextureSampleType::Float { filterable: true })),
                (1, wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering)),
            ],
        );
        let float_layout = fragment_layout(
            gpu,
            "buffer view",
            &[(2, texture_binding(wgpu::TextureSampleType::Float { filterable: false }))],
        );
        let depth_layout = fragment_layout(gpu, "depth view", &[(3, texture_binding(wgpu::TextureSampleType::Depth))]);
        let module = shader_module(device, "mirror", &["mirror.wgsl"]);
        let pipeline = |layout: &wgpu::BindGroupLayout, entry_point: &str| {
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry_point),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(entry_point),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    buffers: &[],
                    compilation_options: Default::default(),
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry_point),
                    targets: &[Some(format.into())],
                    compilation_options: Default::default(),
                }),
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })
        };
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("mirror"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Blit {
            eye: pipeline(&eye_layout, "fs_main"),
            occlusion: pipeline(&float_layout, "fs_occlusion"),
            normals: pipeline(&float_layout, "fs_normals"),
            depth: pipeline(&depth_layout, "fs_depth"),
            eye_layout,
            float_layout,
            depth_layout,
            sampler,
        }
    }

    fn pipeline(&self, kind: PictureKind) -> &wgpu::RenderPipeline {
        match kind {
            PictureKind::Eye => &self.eye,
            PictureKind::Occlusion => &self.occlusion,
            PictureKind::Normals => &self.normals,
            PictureKind::Depth => &self.depth,
        }
    }

    fn bind_group(&self, gpu: &Gpu, kind: PictureKind, view: &wgpu::TextureView) -> wgpu::BindGroup {
        let texture = wgpu::BindingResource::TextureView(view);
        let (layout, entries) = match kind {
            PictureKind::Eye => (
                &self.eye_layout,
                vec![
                    wgpu::BindGroupEntry { binding: 0, resource: texture },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                ],
            ),
            PictureKind::Occlusion | PictureKind::Normals => {
                (&self.float_layout, vec![wgpu::BindGroupEntry { binding: 2, resource: texture }])
            }
            PictureKind::Depth => (&self.depth_layout, vec![wgpu::BindGroupEntry { binding: 3, resource: texture }]),
        };
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("mirror"), layout, entries: &entries })
    }
}

/// Colour of pass `i` in the profiler graph.
fn pass_colour(i: usize) -> egui::Color32 {
    const COLOURS: [(u8, u8, u8); 8] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (188, 189, 34),
    ];
    let (r, g, b) = COLOURS[i % COLOURS.len()];
    egui::Color32::from_rgb(r, g, b)
}

/// The side panel: settings (those that do not apply to the chosen technique disabled),
/// display mode, frame rates, the governor and the profiler graph. Returns whether a
/// setting changed.
fn panel_ui(
    ui: &mut egui::Ui,
    panel: &mut PanelState,
    info: &PanelInfo,
    counters: &crate::headset::FrameCounters,
) -> bool {
    let before = (panel.settings.ao.clone(), panel.quality, panel.settings.shadows.clone());
    egui::Panel::left("vrao panel").exact_size(PANEL_WIDTH).resizable(false).show(ui, |ui| {
        ui.heading("vrao");
        let ao = &mut panel.settings.ao;
        egui::ComboBox::from_label("technique").selected_text(ao.technique.name()).show_ui(ui, |ui| {
            for t in [Technique::None, Technique::Ssao, Technique::Hbao, Technique::Gtao, Technique::Ssdo, Technique::SsdoBounce] {
                ui.selectable_value(&mut ao.technique, t, t.name());
            }
        });
        let any = ao.technique != Technique::None;
        let ssdo = matches!(ao.technique, Technique::Ssdo | Technique::SsdoBounce);
        let bounce = ao.technique == Technique::SsdoBounce;
        ui.add_enabled_ui(any, |ui| {
            let quality_text = panel.quality.map_or("custom", |q| q.name());
            egui::ComboBox::from_label("quality").selected_text(quality_text).show_ui(ui, |ui| {
                for q in Quality::ALL {
                    if ui.selectable_value(&mut panel.quality, Some(q), q.name()).clicked() {
                        ao.samples = q.samples();
                    }
                }
            });
            if ui.add(egui::Slider::new(&mut ao.samples, 1..=256).text("samples")).changed() {
                panel.quality = Quality::ALL.into_iter().find(|q| q.samples() == ao.samples);
            }
            ui.add(egui::Slider::new(&mut ao.radius, 0.01..=4.0).logarithmic(true).text("radius m"));
            ui.add(egui::Slider::new(&mut ao.strength, 0.0..=4.0).text("strength"));
            ui.checkbox(&mut ao.half_res, "half resolution");
            ui.checkbox(&mut ao.temporal.enabled, "temporal accumulation");
        });
        ui.add_enabled(bounce, egui::Slider::new(&mut ao.bounce, 0.0..=4.0).text("bounce"));
        let mut patch = ao.bounce_form == BounceForm::Patch;
        if ui.add_enabled(bounce, egui::Checkbox::new(&mut patch, "bounce as Ritschel et al.'s patches")).changed() {
            ao.bounce_form = if patch { BounceForm::Patch } else { BounceForm::Direction };
        }
        ui.add_enabled(ssdo, egui::Checkbox::new(&mut ao.depth_peeling, "depth peeling (SSDO)"));
        ui.checkbox(&mut panel.settings.shadows.enabled, "shadows (directional lights)");
        ui.checkbox(&mut panel.settings.shadows.rsm, "reflective shadow maps (sun bounce)");
        ui.separator();
        ui.label("display");
        ui.horizontal(|ui| {
            ui.radio_value(&mut panel.mode, DisplayMode::Mirror, "mirror");
            ui.radio_value(&mut panel.mode, DisplayMode::SinglePass, "single-pass");
        });
        egui::ComboBox::from_label("show (each eye)").selected_text(buffer_label(panel.show)).show_ui(ui, |ui| {
            for view in BufferView::ALL {
                ui.selectable_value(&mut panel.show, view, buffer_label(view));
            }
        });
        if panel.show != BufferView::Eyes && panel.show.resource(&panel.settings).is_none() {
            ui.small("no AO buffer: the technique is none");
        }
        ui.separator();
        let [presented, reprojected, dropped] = panel.rates;
        ui.label(format!(
            "per second: {presented:.0} presented, {reprojected:.0} reprojected, {dropped:.1} dropped\nlatency: median {:.1} ms, p95 {:.1} ms",
            counters.latency_median_ms, counters.latency_p95_ms
        ));
        ui.separator();
        match info.governor {
            Some(governor) => {
                ui.label(format!(
                    "governor: level {} of {}: {}",
                    governor.level(),
                    governor.frontier().top(),
                    governor.current().setting
                ));
                for change in governor.changes().iter().rev().take(4) {
                    ui.small(format!("frame {}: {} -> {} ({})", change.frame, change.from, change.to, change.reason));
                }
            }
            None => {
                ui.label("governor: off");
            }
        }
        ui.separator();
        profiler_ui(ui, info);
    });
    (panel.settings.ao.clone(), panel.quality, panel.settings.shadows.clone()) != before
}

/// The panel's name of a buffer view.
fn buffer_label(view: BufferView) -> &'static str {
    match view {
        BufferView::Eyes => "eye images",
        BufferView::FinalAo => "final AO",
        BufferView::RawAo => "raw AO",
        BufferView::Depth => "depth",
        BufferView::Normals => "normals",
    }
}

/// The profiler: one stacked bar per recent frame, a colour per pass, against the frame
/// budget (and 90 % of it, where the governor drops a level), with each frame's CPU
/// encode time as a white tick. On a CPU adapter only the frames submitted pass by pass
/// are drawn: timestamps within one submission credit work to the wrong pass there.
fn profiler_ui(ui: &mut egui::Ui, info: &PanelInfo) {
    let history = info.history;
    let serial_only = history.frames.iter().any(|f| f.serial);
    let frames: Vec<&crate::gpu::timing::FrameTiming> =
        history.frames.iter().filter(|f| !serial_only || f.serial).collect();
    let mut passes: Vec<String> = Vec::new();
    for frame in &frames {
        for (name, _) in &frame.spans {
            if !passes.contains(name) && !name.ends_with(" left") && !name.ends_with(" right") {
                passes.push(name.clone());
            }
        }
    }
    let max_ms = frames.iter().map(|f| f.total_ms).fold(info.budget_ms, f64::max).max(1e-3);
    let which = if serial_only { ", frames timed pass by pass" } else { "" };
    ui.label(format!("GPU ms per frame, both eyes{which} (top {max_ms:.1} ms)"));
    let (response, painter) = ui.allocate_painter(egui::vec2(ui.available_width(), 120.0), egui::Sense::hover());
    let rect = response.rect;
    painter.rect_filled(rect, 0.0, egui::Color32::from_gray(20));
    let y_of = |ms: f64| rect.bottom() - (ms / max_ms) as f32 * rect.height();
    let n = history.capacity.max(1) as f32;
    let bar_width = rect.width() / n;
    let step = (n / frames.len().max(1) as f32).max(1.0);
    for (i, frame) in frames.iter().enumerate() {
        let x = rect.left() + i as f32 * bar_width * step;
        let mut y = rect.bottom();
        for (k, pass) in passes.iter().enumerate() {
            let ms = frame.spans.iter().find(|(name, _)| name == pass).map_or(0.0, |(_, ms)| *ms);
            let h = (ms / max_ms) as f32 * rect.height();
            let bar = egui::Rect::from_min_max(egui::pos2(x, y - h), egui::pos2(x + (bar_width * step).max(1.0), y));
            painter.rect_filled(bar, 0.0, pass_colour(k));
            y -= h;
        }
    }
    for (i, ms) in history.cpu_encode_ms.iter().enumerate() {
        let x = rect.left() + i as f32 * bar_width;
        let y = y_of(*ms);
        painter.line_segment([egui::pos2(x, y), egui::pos2(x + bar_width.max(1.0), y)], (1.0, egui::Color32::WHITE));
    }
    for (fraction, colour) in [(1.0, egui::Color32::RED), (0.9, egui::Color32::YELLOW)] {
        let y = y_of(info.budget_ms * fraction);
        painter.line_segment([egui::pos2(rect.left(), y), egui::pos2(rect.right(), y)], (1.0, colour));
    }
    ui.small(format!("red: the {:.2} ms budget; yellow: 90 % of it; white: CPU encode", info.budget_ms));
    let cpu = history.cpu_encode_ms.iter().copied().fold(0.0, f64::max);
    let latest = frames.last();
    ui.label(format!("last frame: GPU {:.2} ms; CPU encode up to {cpu:.3} ms", latest.map_or(0.0, |f| f.total_ms)));
    for (k, pass) in passes.iter().enumerate() {
        let ms = latest.and_then(|f| f.spans.iter().find(|(n, _)| n == pass)).map_or(0.0, |(_, ms)| *ms);
        ui.horizontal(|ui| {
            let (swatch, painter) = ui.allocate_painter(egui::vec2(10.0, 10.0), egui::Sense::hover());
            painter.rect_filled(swatch.rect, 0.0, pass_colour(k));
            ui.label(format!("{pass}: {ms:.2} ms"));
        });
    }
    if passes.is_empty() {
        ui.label("(no GPU timestamps yet, or none on this adapter)");
    }
}
