//! The desktop window (winit) with its egui panel, showing the headset session in one of
//! Belonogov 2018's display modes (§5.2): `mirror` (both eyes side by side, as the headset's
//! compositor shows them) or `single-pass` (the scene rendered once more, mono, from the
//! head's viewpoint at the window's size). `none` never opens a window (see `main.rs`).
//!
//! Each redraw steps the headset frame loop once, then draws the picture and the panel.
//! A minimised (0×0) window keeps the headset running and skips presenting; a lost or
//! outdated surface is reconfigured.

use super::panel::{panel_ui, PanelInfo, PanelState, PANEL_WIDTH};
use super::picture::Blit;
use crate::app::{BufferView, FrameLoop, RunSummary};
use crate::error::{Error, Result};
use std::path::PathBuf;
use std::sync::Arc;
use vrao_ao::plug::Gpu;
use vrao_ao::{EyePair, Fov, HeadPose, Quality};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::renderer::Renderer;
use vrao_render::scene::Scene;
use vrao_render::settings::DisplayMode;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

/// How the desktop window is opened and what it shows.
pub struct WindowOptions {
    /// Mirror both eyes, or render a mono view at the window's size.
    pub mode: DisplayMode,
    /// Initial inner size in physical pixels.
    pub size: (u32, u32),
    /// Save the window's last picture (panel included) to this PNG.
    pub screenshot: Option<PathBuf>,
    /// What the picture shows of each eye at first (the panel can change it).
    pub show: BufferView,
}

/// winit's OS errors lead with a place in winit's own source ("os error at
/// …/winit-0.30.13/src/platform_impl/linux/mod.rs:765: "), a build path that means
/// nothing to the user: keep the system's reason alone.
fn without_source_location(message: String) -> String {
    match message.strip_prefix("os error at ").and_then(|rest| rest.split_once(": ")) {
        Some((_, reason)) => reason.to_string(),
        None => message,
    }
}

/// Connects to the desktop's display (winit's event loop, once per process): the check
/// a session makes before it opens its headset, so that a machine without a display is
/// refused at once (`Error::Unavailable`, one line), not after the runtime, session and
/// pipelines were made.
pub fn open_event_loop() -> Result<EventLoop<()>> {
    EventLoop::new().map_err(|e| {
        Error::Unavailable(format!(
            "cannot open a desktop window ({}); without a display, run with --display none",
            without_source_location(e.to_string())
        ))
    })
}

/// Opens the window on `event_loop` ([`open_event_loop`]) and runs the session until the
/// headset ends it or the window closes.
pub fn run_window(
    event_loop: EventLoop<()>,
    mut frame_loop: FrameLoop,
    scene: &Scene,
    options: WindowOptions,
) -> Result<RunSummary> {
    frame_loop.buffer_view = options.show;
    let mut app = WindowApp { frame_loop, scene: scene.clone(), options, window: None, error: None, finished: false };
    event_loop.run_app(&mut app).map_err(|e| {
        Error::Unavailable(format!("the window's event loop failed: {}", without_source_location(e.to_string())))
    })?;
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
        Ok(self.frame_loop.gpu.take_error()?)
    }
}

impl WindowState {
    fn new(event_loop: &ActiveEventLoop, frame_loop: &FrameLoop, options: &WindowOptions) -> Result<WindowState> {
        let gpu = &frame_loop.gpu;
        let attributes = Window::default_attributes()
            .with_title(format!("vrao — {}", frame_loop.headset.describe()))
            .with_inner_size(winit::dpi::PhysicalSize::new(options.size.0, options.size.1));
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| {
            Error::Unavailable(format!("cannot create a window: {}", without_source_location(e.to_string())))
        })?);
        let (instance, adapter) = gpu_instance_adapter(gpu)?;
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| Error::device(format!("cannot draw into the window: {e}")))?;
        let caps = surface.get_capabilities(adapter);
        // The eye images hold sRGB-encoded values: a non-sRGB surface shows them as they are.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| Error::device(format!("{} cannot present to this window", gpu.info.name)))?;
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
        let quality = Quality::of(&settings.ao);
        Ok(WindowState {
            window,
            surface,
            config,
            blit: Blit::new(gpu, format)?,
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
        mono.render(&[EyePair::mono(&head, fov)], &[COLOR])?;
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
                self.panel.quality = Quality::of(&self.panel.settings.ao);
            }
        }
        let mut changed = false;
        let panel = &mut self.panel;
        let info = PanelInfo {
            history: &frame_loop.history,
            budget_ms: frame_loop.budget_ms,
            governor: frame_loop.governor.as_ref(),
            openxr: frame_loop.headset.openxr_report().filter(|r| !r.fell_back),
            hidden_share: frame_loop.renderer.hidden_share(),
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
                self.surface = gpu_instance_adapter(&gpu)?
                    .0
                    .create_surface(self.window.clone())
                    .map_err(|e| Error::device(format!("cannot recreate the window surface: {e}")))?;
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
    /// The images the picture shows: the two eyes (mirror), the mono view, or each eye's
    /// buffer that the panel's "show" picks.
    fn picture_images<'a>(&'a self, frame_loop: &'a FrameLoop) -> Vec<&'a wgpu::TextureView> {
        if self.panel.show != BufferView::Eyes {
            let target =
                self.panel.show.resource(frame_loop.renderer.settings()).and_then(|r| frame_loop.renderer.target(r));
            return target.map(|t| t.layer_views.iter().take(2).collect()).unwrap_or_default();
        }
        match self.panel.mode {
            DisplayMode::SinglePass => match self.mono.as_ref().and_then(|m| m.target(COLOR)) {
                Some(target) => vec![&target.layer_views[0]],
                None => vec![],
            },
            _ => {
                // What the headset shows (the compositor's output), else the eye buffers.
                let target = frame_loop.headset.display_image().or_else(|| frame_loop.renderer.target(COLOR));
                target.map(|t| t.layer_views.iter().take(2).collect()).unwrap_or_default()
            }
        }
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
        let (shown, images) = (self.panel.show, self.picture_images(frame_loop));
        let eye_aspect = {
            let p = &frame_loop.renderer.settings().profile;
            p.width as f32 / p.height as f32
        };
        let (ax, ay, aw, ah) = self.picture_area(PANEL_WIDTH * screen.pixels_per_point);
        let bind_groups: Vec<wgpu::BindGroup> = images.iter().map(|v| self.blit.bind_group(gpu, shown, v)).collect();
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
            for (i, (group, image)) in bind_groups.iter().zip(&images).enumerate() {
                // Each image gets an equal slot; within it, the largest rectangle of its
                // aspect.
                let mono = self.panel.mode == DisplayMode::SinglePass && shown == BufferView::Eyes;
                let aspect = if mono { aw / ah } else { eye_aspect };
                let (slot_w, slot_h) = (aw / count, ah);
                let (w, h) =
                    if slot_w / slot_h > aspect { (slot_h * aspect, slot_h) } else { (slot_w, slot_w / aspect) };
                let x = ax + slot_w * i as f32 + (slot_w - w) * 0.5;
                let y = ay + (slot_h - h) * 0.5;
                pass.set_viewport(x, y, w.max(1.0), h.max(1.0), 0.0, 1.0);
                pass.set_pipeline(self.blit.pipeline(shown, image));
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
        let target = vrao_ao::plug::LayeredTarget {
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
        let mut pixels = vrao_ao::plug::read_layers(&gpu, &target)?.remove(0);
        if matches!(self.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb) {
            pixels.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        pixels.chunks_exact_mut(4).for_each(|p| p[3] = 255);
        image::save_buffer(path, &pixels, width, height, image::ColorType::Rgba8)
            .map_err(|e| Error::Output { path: path.to_path_buf(), message: e.to_string() })
    }
}

/// The instance and adapter a window surface is made with: every `Gpu` vrao opens has
/// them; a host's device ([`Gpu::from_host`]) does not.
fn gpu_instance_adapter(gpu: &Gpu) -> Result<(&wgpu::Instance, &wgpu::Adapter)> {
    match (&gpu.instance, &gpu.adapter) {
        (Some(instance), Some(adapter)) => Ok((instance, adapter)),
        _ => Err(Error::device("a window needs the wgpu instance and adapter vrao opened itself")),
    }
}

#[cfg(test)]
mod tests {
    use super::without_source_location;

    #[test]
    fn window_errors_drop_winits_source_path() {
        let winit = "os error at /home/u/.cargo/registry/src/index/winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor DISPLAY is set";
        assert_eq!(without_source_location(winit.into()), "neither WAYLAND_DISPLAY nor DISPLAY is set");
        assert_eq!(without_source_location("the event loop exited".into()), "the event loop exited");
    }
}
