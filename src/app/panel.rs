//! The window's side panel (egui): the settings it edits (those the technique does not
//! use disabled), the display mode and buffer view, frame rates, the governor's level and
//! changes, and the per-pass GPU profiler against the frame budget.

use super::governor::Governor;
use super::{BufferView, PassHistory};
use crate::xr::FrameCounters;
use vrao_ao::{AoSettings, Foveation, Quality, Resolution, Technique};
use vrao_render::settings::{DisplayMode, Settings};
use vrao_render::{BounceForm, PointSsdoSettings};

/// Width of the egui side panel in points.
pub(super) const PANEL_WIDTH: f32 = 300.0;

/// What the panel edits: a copy of the settings, applied when it changes.
pub(super) struct PanelState {
    pub(super) settings: Settings,
    pub(super) quality: Option<Quality>,
    pub(super) mode: DisplayMode,
    /// The buffer the picture shows of each eye.
    pub(super) show: BufferView,
    /// Presented, reprojected and dropped frames per second, from the counters' change
    /// over the last second.
    pub(super) rates: [f64; 3],
    pub(super) rate_base: Option<(std::time::Instant, FrameCounters)>,
    /// Governor changes already taken into the panel's settings.
    pub(super) governor_changes_seen: usize,
}

impl PanelState {
    pub(super) fn update_rates(&mut self, counters: &FrameCounters) {
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
pub(super) struct PanelInfo<'a> {
    pub(super) history: &'a PassHistory,
    pub(super) budget_ms: f64,
    pub(super) governor: Option<&'a Governor>,
    /// What an OpenXR session said so far (`None` for the simulated headset, and after a
    /// lost session, whose simulated counters then apply).
    pub(super) openxr: Option<crate::xr::openxr::OpenXrReport>,
    /// The share of each eye the visibility mask hid in the last frame (empty: none).
    pub(super) hidden_share: &'a [f64],
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
pub(super) fn panel_ui(ui: &mut egui::Ui, panel: &mut PanelState, info: &PanelInfo, counters: &FrameCounters) -> bool {
    let edited = |p: &PanelState| (p.settings.ao.clone(), p.settings.point_ssdo, p.quality, p.settings.shadows.clone());
    let before = edited(panel);
    egui::Panel::left("vrao panel").exact_size(PANEL_WIDTH).resizable(false).show(ui, |ui| {
        ui.heading("vrao");
        settings_ui(ui, panel);
        ui.separator();
        display_ui(ui, panel);
        ui.separator();
        frame_rates_ui(ui, panel.rates, info, counters);
        mask_ui(ui, info.hidden_share);
        ui.separator();
        governor_ui(ui, info.governor);
        ui.separator();
        profiler_ui(ui, info);
    });
    edited(panel) != before
}

/// The settings the panel edits: technique, its parameters, bounce and shadows.
fn settings_ui(ui: &mut egui::Ui, panel: &mut PanelState) {
    let ao = &mut panel.settings.ao;
    technique_ui(ui, ao);
    let any = ao.technique != Technique::None;
    ui.add_enabled_ui(any, |ui| ao_parameters_ui(ui, ao, &mut panel.quality));
    bounce_ui(ui, ao, &mut panel.settings.point_ssdo);
    ui.checkbox(&mut panel.settings.shadows.enabled, "shadows (directional lights)");
    ui.checkbox(&mut panel.settings.shadows.rsm, "reflective shadow maps (sun bounce)");
}

/// The technique's combo box.
fn technique_ui(ui: &mut egui::Ui, ao: &mut AoSettings) {
    egui::ComboBox::from_label("technique").selected_text(ao.technique.name()).show_ui(ui, |ui| {
        // Every technique but the bench's fetch-only baseline, which is not an occlusion.
        for &t in Technique::all().iter().filter(|t| **t != Technique::FetchOnly) {
            ui.selectable_value(&mut ao.technique, t, t.name());
        }
    });
}

/// The parameters every technique shares: quality (or samples), radius, strength,
/// resolution, temporal accumulation and foveation.
fn ao_parameters_ui(ui: &mut egui::Ui, ao: &mut AoSettings, quality: &mut Option<Quality>) {
    let quality_text = quality.map_or("custom", |q| q.name());
    egui::ComboBox::from_label("quality").selected_text(quality_text).show_ui(ui, |ui| {
        for q in Quality::ALL {
            if ui.selectable_value(quality, Some(q), q.name()).clicked() {
                q.apply(ao);
            }
        }
    });
    if ui.add(egui::Slider::new(&mut ao.samples, 1..=256).text("samples")).changed() {
        *quality = Quality::of(ao);
    }
    ui.add(egui::Slider::new(&mut ao.radius, 0.01..=4.0).logarithmic(true).text("radius m"));
    ui.add(egui::Slider::new(&mut ao.strength, 0.0..=4.0).text("strength"));
    let mut half = ao.resolution.is_half();
    if ui.checkbox(&mut half, "half resolution").changed() {
        ao.resolution = Resolution::from_half_res(half);
    }
    ui.checkbox(&mut ao.temporal.enabled, "temporal accumulation");
    egui::ComboBox::from_label("foveation").selected_text(ao.foveation.name()).show_ui(ui, |ui| {
        for level in Foveation::ALL {
            ui.selectable_value(&mut ao.foveation, level, level.name());
        }
    });
    ui.checkbox(&mut ao.mask, "skip what the lens hides (mask)");
}

/// What the visibility mask hides of each eye.
fn mask_ui(ui: &mut egui::Ui, hidden_share: &[f64]) {
    if hidden_share.iter().any(|&s| s > 0.0) {
        let shares: Vec<String> = hidden_share.iter().map(|s| format!("{:.1} %", s * 100.0)).collect();
        ui.label(format!("lens mask hides {} (left, right)", shares.join(", ")));
    } else {
        ui.label("lens mask: none applied");
    }
}

/// The SSDO settings: bounce strength and form, and depth peeling (disabled for the
/// techniques that do not use them).
fn bounce_ui(ui: &mut egui::Ui, ao: &mut AoSettings, point_ssdo: &mut PointSsdoSettings) {
    let points = matches!(ao.technique, Technique::SsdoPoints | Technique::SsdoPointsBounce);
    let bounce = ao.technique.gathers_bounce();
    ui.add_enabled(bounce, egui::Slider::new(&mut ao.bounce, 0.0..=4.0).text("bounce"));
    let mut patch = point_ssdo.bounce_form == BounceForm::Patch;
    if ui
        .add_enabled(bounce && points, egui::Checkbox::new(&mut patch, "bounce as Ritschel et al.'s patches"))
        .changed()
    {
        point_ssdo.bounce_form = if patch { BounceForm::Patch } else { BounceForm::Direction };
    }
    ui.add_enabled(points, egui::Checkbox::new(&mut point_ssdo.depth_peeling, "depth peeling (point-sampled SSDO)"));
}

/// The display mode and the buffer view shown of each eye.
fn display_ui(ui: &mut egui::Ui, panel: &mut PanelState) {
    ui.label("display");
    ui.horizontal(|ui| {
        ui.radio_value(&mut panel.mode, DisplayMode::Mirror, "mirror");
        ui.radio_value(&mut panel.mode, DisplayMode::SinglePass, "single-pass");
    });
    egui::ComboBox::from_label("show (each eye)").selected_text(buffer_label(panel.show)).show_ui(ui, |ui| {
        for &view in <BufferView as clap::ValueEnum>::value_variants() {
            ui.selectable_value(&mut panel.show, view, buffer_label(view));
        }
    });
    if panel.show != BufferView::Eyes && panel.show.resource(&panel.settings).is_none() {
        ui.small("no AO buffer: the technique is none");
    }
}

/// What OpenXR reported, or the simulated headset's frame rates and latency.
fn frame_rates_ui(ui: &mut egui::Ui, rates: [f64; 3], info: &PanelInfo, counters: &FrameCounters) {
    match &info.openxr {
        // OpenXR does not say what its compositor presented or reprojected.
        Some(x) => ui.label(format!(
            "OpenXR: {} submitted, {} not to render, {} missed; period {:.2} ms",
            crate::formats::output::count(x.layers_submitted, "layer"),
            x.not_rendered,
            crate::formats::output::count(x.missed_display_periods, "display period"),
            x.display_period_ms
        )),
        None => {
            let [presented, reprojected, dropped] = rates;
            ui.label(format!(
                "per second: {presented:.0} presented, {reprojected:.0} reprojected, {dropped:.1} dropped\nlatency: median {:.1} ms, p95 {:.1} ms",
                counters.latency_median_ms, counters.latency_p95_ms
            ))
        }
    };
}

/// The governor's level and its latest changes, or that it is off.
fn governor_ui(ui: &mut egui::Ui, governor: Option<&Governor>) {
    match governor {
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
    let frames: Vec<&vrao_ao::plug::FrameTiming> = history.frames.iter().filter(|f| !serial_only || f.serial).collect();
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
