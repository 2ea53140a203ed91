//! Scatter plots (error against time) drawn with plotters into PNG files.
//!
//! Both axes start at 0 and are linear, so a 2 % difference looks like one. Every point
//! carries its own text label (its setting), placed beside it where it overlaps no other
//! label or point if such a place is near. A [`ScatterPlot`] has any number of
//! [`Series`] (one colour each, named in a legend right of the plot), an optional Pareto
//! front (a line through its points in x order) and an optional dashed vertical line
//! (the budget) with a label. Non-finite points are skipped.
//!
//! Text: `Backend` wraps plotters' bitmap backend and draws text itself, with ab_glyph
//! and the Hack font that `epaint_default_fonts` embeds. No system font lookup (a bare
//! machine draws the same plot), and each glyph keeps its side bearing, which plotters'
//! own `ab_glyph` text path (0.3.7) drops.

use std::path::Path;

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use image::RgbImage;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind};

use crate::error::{Error, Result};

/// Colour of the Pareto-front line.
pub const PARETO_COLOR: [u8; 3] = [70, 70, 70];
/// Colour of the dashed vertical (budget) line and its label.
pub const BUDGET_COLOR: [u8; 3] = [196, 0, 110];
/// Below this size there is no room for axes, labels and legend.
pub const MIN_SIZE: (u32, u32) = (320, 200);

const FONT: &str = "sans-serif";
const TEXT: RGBColor = RGBColor(30, 30, 30);
const LABEL_TEXT: RGBColor = RGBColor(60, 60, 60);
const GRID: RGBColor = RGBColor(232, 232, 232);

/// One point and the text drawn beside it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Point {
    /// x in data units (ms on the bench plots).
    pub x: f64,
    /// y in data units (an error figure on the bench plots).
    pub y: f64,
    /// Text drawn beside the point (empty: none).
    pub label: String,
}

/// One set of points with a colour and a legend label.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// sRGB colour of the points.
    pub color: [u8; 3],
    /// The points; non-finite ones are skipped.
    pub points: Vec<Point>,
}

/// A scatter plot; see the module documentation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScatterPlot {
    /// Title above the plot.
    pub title: String,
    /// x-axis caption.
    pub x_label: String,
    /// y-axis caption.
    pub y_label: String,
    /// The point sets, each in its colour, named in the legend.
    pub series: Vec<Series>,
    /// Points of the Pareto front, joined by a line in x order (they need not be sorted).
    pub pareto: Vec<(f64, f64)>,
    /// A dashed vertical line at this x with its label (lines split at '\n').
    pub vertical_line: Option<(f64, String)>,
}

/// Where things landed in the image, in pixels (for tests and for label placement).
#[derive(Clone, Debug, Default)]
pub struct Drawn {
    /// Each drawn point's centre, series by series in order.
    pub points: Vec<(i32, i32)>,
    /// Each drawn point's label box (x0, y0, x1, y1), in the same order.
    pub labels: Vec<(i32, i32, i32, i32)>,
    /// The budget line's column, when drawn.
    pub vertical_line: Option<i32>,
    /// The plotting area (x0, y0, x1, y1).
    pub area: (i32, i32, i32, i32),
}

impl ScatterPlot {
    /// The axis ranges: from 0 to a little beyond the largest finite value (the vertical
    /// line included), never zoomed in on the data.
    pub fn ranges(&self) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
        let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
        let points: Vec<(f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| (p.x, p.y)))
            .chain(self.pareto.iter().copied())
            .filter(finite)
            .collect();
        let line = self.vertical_line.as_ref().map(|(x, _)| *x).filter(|x| x.is_finite());
        let top = |values: &mut dyn Iterator<Item = f64>| {
            let max = values.fold(0.0f64, f64::max);
            if max > 0.0 && max < f64::MAX / 2.0 {
                max * 1.08
            } else {
                1.0
            }
        };
        let x_max = top(&mut points.iter().map(|p| p.0).chain(line));
        let y_max = top(&mut points.iter().map(|p| p.1));
        (0.0..x_max, 0.0..y_max)
    }

    /// Draws the plot into an RGB image of `width × height` (at least [`MIN_SIZE`]).
    pub fn render(&self, width: u32, height: u32) -> Result<(RgbImage, Drawn)> {
        if width < MIN_SIZE.0 || height < MIN_SIZE.1 {
            return Err(Error::input(format!(
                "a plot needs at least {}x{} pixels, not {width}x{height}",
                MIN_SIZE.0, MIN_SIZE.1
            )));
        }
        let mut buffer = vec![255u8; width as usize * height as usize * 3];
        let drawn = self.draw(&mut buffer, width, height)?;
        let image = RgbImage::from_raw(width, height, buffer).expect("the buffer has width × height RGB pixels");
        Ok((image, drawn))
    }

    /// Renders and writes a PNG file.
    pub fn save_png(&self, path: &Path, width: u32, height: u32) -> Result<()> {
        let (image, _) = self.render(width, height)?;
        image
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|e| Error::Output { path: path.to_path_buf(), message: format!("writing the plot: {e}") })
    }

    /// Draws the whole plot into `buffer` (RGB, `width × height`): axes, budget line,
    /// front, points, their labels and the legend, in that order.
    fn draw(&self, buffer: &mut [u8], width: u32, height: u32) -> Result<Drawn> {
        let root = Backend::new(buffer, (width, height)).into_drawing_area();
        // Sizes follow the image: 1280×800 gets 14 px tick labels and 12 px point labels.
        let scale = Scale::of(width, height);
        let label_style = scale.font(12.0).color(&LABEL_TEXT);

        // The legend sits right of the plot, out of the data's way.
        let legend_w = self.legend_width(&root, &label_style, scale, width);
        let (plot_area, legend_area) = root.split_horizontally(width - legend_w);

        let mut chart = self.draw_axes(&plot_area, scale)?;
        let (ax, ay) = chart.plotting_area().get_pixel_range();
        let mut drawn = Drawn { area: (ax.start, ay.start, ax.end, ay.end), ..Drawn::default() };

        // Budget line under the data.
        let budget = self.draw_budget_line(&mut chart, &root, scale, ay.end)?;
        drawn.vertical_line = budget.map(|(lx, _)| lx);
        let budget_box = budget.map(|(_, label_box)| label_box);

        let radius = scale.px(5.0) as i32;
        drawn.points = self.draw_front_and_points(&mut chart, scale.px(2.0), radius)?;

        // Labels after every point, so a label avoids the points drawn after its own.
        drawn.labels = self.draw_labels(&root, &drawn, &label_style, radius, budget_box)?;

        self.draw_legend(&legend_area, &label_style, scale, ay.start, radius)?;
        root.present().map_err(|e| drawing_failed(&e))?;
        Ok(drawn)
    }

    /// The legend's width: the widest series name plus room for its dot, at most a third
    /// of the image (0 without series).
    fn legend_width(&self, root: &Area<'_>, label_style: &TextStyle, scale: Scale, width: u32) -> u32 {
        self.series
            .iter()
            .map(|s| root.estimate_text_size(&s.label, label_style).map_or(0, |(w, _)| w))
            .max()
            .map_or(0, |w| w + scale.px(48.0))
            .min(width / 3)
    }

    /// Builds the chart on `plot_area` with its caption and draws the axes, grid and
    /// their labels.
    fn draw_axes<'b>(&self, plot_area: &Area<'b>, scale: Scale) -> Result<Chart<'_, 'b>> {
        let font = |size: f64| scale.font(size);
        let (x_range, y_range) = self.ranges();
        let mut chart = ChartBuilder::on(plot_area)
            .caption(&self.title, font(18.0).color(&TEXT))
            .margin(scale.px(12.0))
            .x_label_area_size(scale.px(50.0))
            .y_label_area_size(scale.px(70.0))
            .build_cartesian_2d(x_range, y_range)
            .map_err(|e| drawing_failed(&e))?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .bold_line_style(GRID)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(font(14.0).color(&TEXT))
            .axis_desc_style(font(16.0).color(&TEXT))
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(|e| drawing_failed(&e))?;
        Ok(chart)
    }

    /// Draws the dashed budget line (when there is a finite one) and its label at its foot
    /// (`bottom` is the plotting area's); returns the line's column and the label's box.
    fn draw_budget_line(
        &self,
        chart: &mut Chart<'_, '_>,
        root: &Area<'_>,
        scale: Scale,
        bottom: i32,
    ) -> Result<Option<(i32, LabelBox)>> {
        let Some((x, label)) = self.vertical_line.as_ref().filter(|(x, _)| x.is_finite()) else {
            return Ok(None);
        };
        let px = |v: f64| scale.px(v);
        let (y0, y1) = (chart.y_range().start, chart.y_range().end);
        let style = ShapeStyle::from(rgb(BUDGET_COLOR)).stroke_width(px(2.0));
        chart
            .draw_series(DashedLineSeries::new([(*x, y0), (*x, y1)], px(9.0), px(5.0), style))
            .map_err(|e| drawing_failed(&e))?;
        let (lx, _) = chart.backend_coord(&(*x, y1));
        // The label sits at the foot of the line: errors near 0 are rare, so the data
        // stays clear, and point labels avoid its box (`budget_box`).
        let style = scale.font(14.0).color(&rgb(BUDGET_COLOR));
        let foot = (lx + px(6.0) as i32, bottom - px(6.0) as i32);
        let (x0, y0, x1, _) = draw_lines_above(root, label, &style, foot, px(17.0) as i32)?;
        Ok(Some((lx, (x0, y0, x1, bottom))))
    }

    /// Draws every drawn point's label clear of the points (dots of `radius` px) and of
    /// the budget label's box; returns the labels' boxes.
    fn draw_labels(
        &self,
        root: &Area<'_>,
        drawn: &Drawn,
        label_style: &TextStyle,
        radius: i32,
        budget_box: Option<LabelBox>,
    ) -> Result<Vec<LabelBox>> {
        let texts = self.series.iter().flat_map(|s| &s.points).filter(|p| p.x.is_finite() && p.y.is_finite());
        let labelled: Vec<(&str, (i32, i32))> = texts.map(|p| p.label.as_str()).zip(drawn.points.clone()).collect();
        let mut taken: Vec<LabelBox> =
            drawn.points.iter().map(|&(x, y)| (x - radius, y - radius, x + radius, y + radius)).collect();
        taken.extend(budget_box);
        draw_point_labels(root, &labelled, label_style, radius, taken, drawn.area)
    }

    /// Draws the legend: a dot of `radius` px and the series name per row, from `top` down.
    fn draw_legend(
        &self,
        legend_area: &Area<'_>,
        label_style: &TextStyle,
        scale: Scale,
        top: i32,
        radius: i32,
    ) -> Result<()> {
        let px = |v: f64| scale.px(v);
        let row = px(22.0) as i32;
        for (i, s) in self.series.iter().enumerate() {
            let y = top + row / 2 + i as i32 * row;
            let dot = Circle::new((px(12.0) as i32, y), radius, rgb(s.color).filled());
            legend_area.draw(&dot).map_err(|e| drawing_failed(&e))?;
            legend_area
                .draw_text(&s.label, label_style, (px(24.0) as i32, y - row / 3))
                .map_err(|e| drawing_failed(&e))?;
        }
        Ok(())
    }

    /// Draws the Pareto front (a line `stroke` px wide) and every series' points as dots
    /// of `radius` px; returns the points' pixel positions, series by series.
    fn draw_front_and_points(&self, chart: &mut Chart<'_, '_>, stroke: u32, radius: i32) -> Result<Vec<(i32, i32)>> {
        let mut front: Vec<(f64, f64)> =
            self.pareto.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        let style = ShapeStyle::from(rgb(PARETO_COLOR)).stroke_width(stroke);
        chart.draw_series(LineSeries::new(front, style)).map_err(|e| drawing_failed(&e))?;
        let mut drawn = Vec::new();
        for s in &self.series {
            let colour = rgb(s.color);
            let points = s.points.iter().filter(|p| p.x.is_finite() && p.y.is_finite());
            chart
                .draw_series(points.clone().map(|p| Circle::new((p.x, p.y), radius, colour.filled())))
                .map_err(|e| drawing_failed(&e))?;
            drawn.extend(points.map(|p| chart.backend_coord(&(p.x, p.y))));
        }
        Ok(drawn)
    }
}

/// Sizes that follow the image, in pixels: `unit` scales sizes given for 1280×800.
#[derive(Clone, Copy, Debug)]
struct Scale {
    unit: f64,
}

impl Scale {
    /// The scale of a `width × height` image (never below half of 1280×800's).
    fn of(width: u32, height: u32) -> Scale {
        Scale { unit: (width.min(height) as f64 / 800.0).max(0.5) }
    }

    /// `v` px at 1280×800, in this image's whole pixels (at least 1).
    fn px(self, v: f64) -> u32 {
        (v * self.unit).round().max(1.0) as u32
    }

    /// The plot's font at `size` px at 1280×800.
    fn font(self, size: f64) -> FontDesc<'static> {
        (FONT, size * self.unit).into_font()
    }
}

/// A drawing area in pixels on vrao's text-drawing backend.
type Area<'b> = DrawingArea<Backend<'b>, plotters::coord::Shift>;

/// The plot's chart: f64 axes on vrao's text-drawing backend.
type Chart<'a, 'b> = ChartContext<
    'a,
    Backend<'b>,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// A text's box in pixels: left, top, right, bottom.
type LabelBox = (i32, i32, i32, i32);

/// Why plotters could not draw, as vrao's error.
fn drawing_failed(e: &dyn std::fmt::Display) -> Error {
    Error::Output { path: "plot".into(), message: format!("drawing the plot: {e}") }
}

/// Draws the lines of `text` `line_h` apart so that the last one ends at `foot` (its
/// left and bottom); returns the box they cover.
fn draw_lines_above(
    root: &DrawingArea<Backend<'_>, plotters::coord::Shift>,
    text: &str,
    style: &TextStyle,
    (x0, bottom): (i32, i32),
    line_h: i32,
) -> Result<LabelBox> {
    let lines: Vec<&str> = text.lines().collect();
    let y0 = bottom - line_h * lines.len() as i32;
    let mut w = 0;
    for (i, line) in lines.iter().enumerate() {
        root.draw_text(line, style, (x0, y0 + i as i32 * line_h)).map_err(|e| drawing_failed(&e))?;
        w = w.max(root.estimate_text_size(line, style).map_or(0, |(w, _)| w as i32));
    }
    Ok((x0, y0, x0 + w, bottom))
}

/// Draws each (label, point) where it overlaps nothing in `taken` (the points, the
/// budget label, the labels placed before it) inside `area`; a label pushed away from
/// its point gets a thin leader line back to it. Returns the labels' boxes.
fn draw_point_labels(
    root: &DrawingArea<Backend<'_>, plotters::coord::Shift>,
    labelled: &[(&str, (i32, i32))],
    style: &TextStyle,
    radius: i32,
    mut taken: Vec<LabelBox>,
    area: LabelBox,
) -> Result<Vec<LabelBox>> {
    let mut boxes = Vec::with_capacity(labelled.len());
    for &(label, (x, y)) in labelled {
        let (w, h) = root.estimate_text_size(label, style).map_err(|e| drawing_failed(&e))?;
        let (b, beside) = place_label((x, y), (w as i32, h as i32), radius + 3, &taken, area);
        if !beside {
            let to = (x.clamp(b.0, b.2), y.clamp(b.1, b.3));
            root.draw(&PathElement::new([(x, y), to], rgb(PARETO_COLOR).mix(0.4))).map_err(|e| drawing_failed(&e))?;
        }
        root.draw_text(label, style, (b.0, b.1)).map_err(|e| drawing_failed(&e))?;
        taken.push(b);
        boxes.push(b);
    }
    Ok(boxes)
}

/// The label box of `size` for the point at `at`: the first spot (right, left, then
/// farther above and below) that overlaps nothing in `taken` and stays inside `area`,
/// else the right-hand spot (a label is never left out); and whether it is right beside
/// the point.
fn place_label(
    at: (i32, i32),
    size: (i32, i32),
    gap: i32,
    taken: &[(i32, i32, i32, i32)],
    area: (i32, i32, i32, i32),
) -> ((i32, i32, i32, i32), bool) {
    let ((x, y), (w, h)) = (at, size);
    let spot = |k: i32, side: u8| {
        let (d, dy) = (gap + k * h, k * h);
        match side {
            0 => (x + d, y - h / 2 - dy),
            1 => (x - d - w, y - h / 2 - dy),
            2 => (x + d, y - h / 2 + dy),
            _ => (x - d - w, y - h / 2 + dy),
        }
    };
    let boxed = |(x0, y0): (i32, i32)| (x0, y0, x0 + w, y0 + h);
    let free = |b: &(i32, i32, i32, i32)| {
        let inside = b.0 >= area.0 && b.1 >= area.1 && b.2 <= area.2 && b.3 <= area.3;
        inside && taken.iter().all(|t| b.2 <= t.0 || t.2 <= b.0 || b.3 <= t.1 || t.3 <= b.1)
    };
    let spots = (0..4).flat_map(|k| (0..4).map(move |side| (k, side)));
    spots.map(|(k, side)| (boxed(spot(k, side)), k == 0)).find(|(b, _)| free(b)).unwrap_or((boxed(spot(0, 0)), true))
}

/// A tick value without float noise: "0", "0.05", "12.5", "100".
fn tick(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Plotters' bitmap backend with text drawn by ab_glyph (see the module documentation):
/// shapes go straight through, text is laid out here with advances, kerning and bearings.
struct Backend<'a> {
    inner: BitMapBackend<'a>,
    font: FontRef<'static>,
}

type BackendResult = std::result::Result<(), DrawingErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

impl<'a> Backend<'a> {
    fn new(buffer: &'a mut [u8], size: (u32, u32)) -> Self {
        let font = FontRef::try_from_slice(epaint_default_fonts::HACK_REGULAR).expect("Hack is a valid font");
        Backend { inner: BitMapBackend::with_buffer(buffer, size), font }
    }

    /// Each glyph's id and pen x at `size` px, and the line's width and height.
    fn layout(&self, text: &str, size: f64) -> (Vec<(ab_glyph::GlyphId, f32)>, f32, f32) {
        let font = self.font.as_scaled(PxScale::from(size as f32));
        let (mut x, mut prev, mut glyphs) = (0.0f32, None, Vec::new());
        for c in text.chars() {
            let id = font.glyph_id(c);
            if let Some(p) = prev {
                x += font.kern(p, id);
            }
            glyphs.push((id, x));
            x += font.h_advance(id);
            prev = Some(id);
        }
        (glyphs, x, font.height())
    }
}

impl DrawingBackend for Backend<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> BackendResult {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> BackendResult {
        self.inner.present()
    }
    fn draw_pixel(&mut self, point: BackendCoord, color: BackendColor) -> BackendResult {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(&mut self, from: BackendCoord, to: BackendCoord, style: &S) -> BackendResult {
        self.inner.draw_line(from, to, style)
    }
    fn draw_rect<S: BackendStyle>(&mut self, a: BackendCoord, b: BackendCoord, style: &S, fill: bool) -> BackendResult {
        self.inner.draw_rect(a, b, style, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        v: I,
        style: &S,
    ) -> BackendResult {
        self.inner.fill_polygon(v, style)
    }
    fn draw_circle<S: BackendStyle>(&mut self, c: BackendCoord, r: u32, style: &S, fill: bool) -> BackendResult {
        self.inner.draw_circle(c, r, style, fill)
    }

    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> std::result::Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let (_, w, h) = self.layout(text, style.size());
        Ok((w.ceil() as u32, h.ceil() as u32))
    }

    fn draw_text<S: BackendTextStyle>(&mut self, text: &str, style: &S, pos: BackendCoord) -> BackendResult {
        let (glyphs, w, h) = self.layout(text, style.size());
        let anchor = style.anchor();
        let dx = match anchor.h_pos {
            HPos::Left => 0.0,
            HPos::Center => -w / 2.0,
            HPos::Right => -w,
        };
        let dy = match anchor.v_pos {
            VPos::Top => 0.0,
            VPos::Center => -h / 2.0,
            VPos::Bottom => -h,
        };
        let (color, transform) = (style.color(), style.transform());
        let font = self.font.as_scaled(PxScale::from(style.size() as f32));
        let ascent = font.ascent();
        for (id, x) in glyphs {
            let glyph = id.with_scale_and_position(font.scale(), ab_glyph::point(x + dx, ascent + dy));
            let Some(outline) = font.outline_glyph(glyph) else { continue };
            let min = outline.px_bounds().min;
            let mut pixels = Vec::new();
            outline
                .draw(|gx, gy, coverage| pixels.push((gx as i32 + min.x as i32, gy as i32 + min.y as i32, coverage)));
            for (x, y, coverage) in pixels {
                // Rotation (the y axis title) turns the glyphs about the anchor point.
                let (x, y) = transform.transform(x, y);
                let c = BackendColor { alpha: color.alpha * coverage.min(1.0) as f64, rgb: color.rgb };
                self.inner.draw_pixel((pos.0 + x, pos.1 + y), c)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> ScatterPlot {
        let techniques: [(&str, [u8; 3], f64, f64); 3] = [
            ("ssao full", [31, 119, 180], 14.0, 0.09),
            ("hbao full", [255, 127, 14], 22.0, 0.06),
            ("gtao half", [44, 160, 44], 8.0, 0.05),
        ];
        let series: Vec<Series> = techniques
            .iter()
            .map(|&(label, color, ms, err)| Series {
                label: label.into(),
                color,
                points: [12.0, 24.0, 64.0]
                    .iter()
                    .map(|&n| Point {
                        x: ms * n / 12.0,
                        y: err * (12.0 / n).sqrt() + 0.01,
                        label: format!("{label} N={n}"),
                    })
                    .collect(),
            })
            .collect();
        let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.points.iter().map(|p| (p.x, p.y))).collect();
        let pareto = crate::measure::metrics::pareto_front(&all).into_iter().map(|i| all[i]).collect();
        ScatterPlot {
            title: "crease: AO error against time".into(),
            x_label: "occlusion ms per eye".into(),
            y_label: "AO RMSE vs reference".into(),
            series,
            pareto,
            vertical_line: Some((30.0, "occlusion budget\n30 ms per eye".into())),
        }
    }

    fn is(img: &RgbImage, (x, y): (i32, i32), c: [u8; 3]) -> bool {
        img.get_pixel(x as u32, y as u32).0 == c
    }

    #[test]
    fn axes_start_at_zero_and_are_not_zoomed() {
        // Errors 0.100 and 0.102: a zoomed axis would spread them over the whole height.
        let plot = ScatterPlot {
            series: vec![Series {
                label: "a".into(),
                color: [200, 0, 0],
                points: vec![
                    Point { x: 10.0, y: 0.100, label: "one".into() },
                    Point { x: 12.0, y: 0.102, label: "two".into() },
                ],
            }],
            ..Default::default()
        };
        let (x, y) = plot.ranges();
        assert_eq!((x.start, y.start), (0.0, 0.0));
        assert!(y.end < 0.12 && x.end < 14.0, "{x:?} {y:?}");
        let (_, drawn) = plot.render(640, 400).unwrap();
        let (_, y0, _, y1) = drawn.area;
        let dy = (drawn.points[0].1 - drawn.points[1].1).abs();
        assert!(dy * 20 < y1 - y0, "2 % apart is drawn close: {dy} px of {}", y1 - y0);
    }

    #[test]
    fn points_labels_and_budget_line_land_where_they_belong() {
        let plot = example();
        let (img, drawn) = plot.render(1280, 800).unwrap();
        assert_eq!(img.dimensions(), (1280, 800));
        let colours = plot.series.iter().flat_map(|s| s.points.iter().map(|_| s.color));
        assert_eq!(drawn.points.len(), 9);
        for (&p, c) in drawn.points.iter().zip(colours) {
            assert!(is(&img, p, c), "point at {p:?} is drawn in its colour");
        }
        // Every label has dark text pixels inside its box, and no two boxes overlap here.
        assert_eq!(drawn.labels.len(), 9);
        for (i, b) in drawn.labels.iter().enumerate() {
            let dark = (b.0..b.2)
                .flat_map(|x| (b.1..b.3).map(move |y| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x as u32, y as u32).0.iter().all(|&v| v < 140))
                .count();
            assert!(dark > 10, "label {i} drawn: {dark} dark pixels");
            for o in &drawn.labels[..i] {
                assert!(b.2 <= o.0 || o.2 <= b.0 || b.3 <= o.1 || o.3 <= b.1, "{b:?} overlaps {o:?}");
            }
        }
        // The budget line is dashed: some of its column is budget-coloured, not all of it.
        let x = drawn.vertical_line.expect("budget line drawn");
        let (_, y0, _, y1) = drawn.area;
        let on = (y0 + 40..y1).filter(|&y| is(&img, (x, y), BUDGET_COLOR)).count() as i32;
        assert!(on > (y1 - y0) / 3 && on < y1 - y0 - 40, "dashed: {on} of {}", y1 - y0);
    }

    #[test]
    fn degenerate_data_renders_and_small_images_are_refused() {
        let nasty = ScatterPlot {
            series: vec![
                Series {
                    label: "bad".into(),
                    color: [200, 0, 0],
                    points: vec![
                        Point { x: f64::NAN, y: 1.0, label: "nan".into() },
                        Point { x: 1.0, y: f64::INFINITY, label: "inf".into() },
                        Point { x: 2.0, y: 1.0, label: "fine".into() },
                    ],
                },
                Series { label: "empty".into(), color: [0, 200, 0], points: vec![] },
            ],
            pareto: vec![(f64::NAN, f64::NAN), (0.0, 0.0)],
            vertical_line: Some((f64::NAN, "nan".into())),
            ..Default::default()
        };
        let (_, drawn) = nasty.render(640, 480).unwrap();
        assert_eq!(drawn.points.len(), 1);
        assert!(drawn.vertical_line.is_none());
        assert!(ScatterPlot::default().render(400, 300).is_ok());
        assert!(matches!(nasty.render(100, 100), Err(Error::Engine(vrao_ao::Error::Input { .. }))));
    }

    #[test]
    fn saves_png() {
        let path = std::env::temp_dir().join(format!("vrao_plot_test_{}.png", std::process::id()));
        example().save_png(&path, 640, 400).unwrap();
        let back = image::open(&path).unwrap();
        assert_eq!((back.width(), back.height()), (640, 400));
        std::fs::remove_file(&path).ok();
        let bad = Path::new("/nonexistent-dir/x/plot.png");
        assert!(matches!(example().save_png(bad, 640, 400), Err(Error::Output { .. })));
    }

    #[test]
    fn ticks_have_no_float_noise() {
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(100.0), "100");
    }
}
