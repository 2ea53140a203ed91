//! Scatter plots (error against time) rendered to RGBA images and PNG files.
//!
//! No font or plotting crate: text uses the built-in bitmap font in [`font`] drawn at an
//! integer scale picked from the image size, shapes and lines are anti-aliased by coverage
//! from signed distances. A [`ScatterPlot`] has any number of [`Series`] (each with its own
//! colour and marker shape: circle, square, diamond, triangle up, triangle down, repeating),
//! an optional Pareto front drawn as a line through its points in x order, and an optional
//! dashed vertical line (the frame budget) with a label.
//!
//! Axes get "nice" ticks: 1-2-5 steps on a linear axis; decades (with 2–9 minor marks, or
//! 1-2-5 / 1–9 labels on short ranges) on a logarithmic x axis. Ranges cover every finite
//! point and the vertical line with a 5 % margin. Non-finite points, and points with x ≤ 0
//! on a log axis, are skipped; a single point or equal coordinates get a range around the
//! value. Rendering never panics, whatever the data or the image size.

pub mod font;

use std::path::Path;

use image::{ImageFormat, Rgba, RgbaImage};

use crate::render::error::{Error, Result};

/// Colour of the Pareto-front line.
pub const PARETO_COLOR: [u8; 3] = [70, 70, 70];
/// Colour of the dashed vertical (budget) line and its label.
pub const BUDGET_COLOR: [u8; 3] = [196, 0, 110];

const BACKGROUND: [u8; 3] = [255, 255, 255];
const TEXT: [u8; 3] = [30, 30, 30];
const TICK_TEXT: [u8; 3] = [70, 70, 70];
const AXIS: [u8; 3] = [110, 110, 110];
const GRID: [u8; 3] = [232, 232, 232];
const LEGEND_BORDER: [u8; 3] = [200, 200, 200];

/// One set of points with a colour and a legend label.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    pub label: String,
    pub color: [u8; 3],
    /// `(x, y)` data points; non-finite ones are skipped.
    pub points: Vec<(f64, f64)>,
}

/// A scatter plot; see the module documentation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScatterPlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Points of the Pareto front, joined by a line in x order (they need not be sorted).
    pub pareto: Vec<(f64, f64)>,
    /// A dashed vertical line at this x with its label, e.g. the frame budget.
    pub vertical_line: Option<(f64, String)>,
    /// Logarithmic x axis.
    pub log_x: bool,
}

impl ScatterPlot {
    /// Draws the plot into a `width × height` RGBA image (opaque).
    pub fn render(&self, width: u32, height: u32) -> RgbaImage {
        let mut img = RgbaImage::from_pixel(width, height, rgba(BACKGROUND));
        if width == 0 || height == 0 {
            return img;
        }
        let layout = self.layout(width, height);
        self.draw(&mut img, &layout);
        img
    }

    /// Renders and writes a PNG file.
    pub fn save_png(&self, path: &Path, width: u32, height: u32) -> Result<()> {
        self.render(width, height)
            .save_with_format(path, ImageFormat::Png)
            .map_err(|e| Error::Output { path: path.to_path_buf(), message: format!("writing the plot: {e}") })
    }

    /// Points of all series that can be drawn.
    fn drawable(&self, p: (f64, f64)) -> bool {
        p.0.is_finite() && p.1.is_finite() && (!self.log_x || p.0 > 0.0)
    }

    fn vline_x(&self) -> Option<f64> {
        self.vertical_line.as_ref().map(|(x, _)| *x).filter(|&x| x.is_finite() && (!self.log_x || x > 0.0))
    }

    fn layout(&self, width: u32, height: u32) -> Layout {
        let (w, h) = (width as i64, height as i64);
        let s = ((width.min(height) as f64 / 400.0).round() as i64).clamp(1, 8);
        let pad = 8 * s;
        let line_h = font::CELL_H as i64 * s;
        let tick_len = 4 * s;

        let title = fit_text(&self.title, s + 1, s, w - 2 * pad - 1);
        let top = pad + if title.text.is_empty() { 0 } else { font::CELL_H as i64 * title.scale + 6 * s };
        let x_title = fit_text(&self.x_label, s, s, w - 2 * pad);
        let bottom = h - pad - if x_title.text.is_empty() { 0 } else { line_h + 4 * s } - line_h - 3 * s - tick_len;

        let points = self.series.iter().flat_map(|s| s.points.iter().copied()).chain(self.pareto.iter().copied());
        let finite: Vec<(f64, f64)> = points.filter(|&p| self.drawable(p)).collect();
        let x_axis = Axis::covering(finite.iter().map(|p| p.0).chain(self.vline_x()), self.log_x);
        let y_axis = Axis::covering(finite.iter().map(|p| p.1), false);

        // Vertical layout is known, so the y ticks and their label widths fix the left edge.
        let y_ticks = choose_ticks(&y_axis, (bottom - top) as f64, s, false);
        let y_title = fit_text(&self.y_label, s, s, (bottom - top).max(0));
        let y_label_w = y_ticks.major.iter().map(|t| text_px(&t.label, s)).max().unwrap_or(0);
        let left = pad + if y_title.text.is_empty() { 0 } else { line_h + 6 * s } + y_label_w + 3 * s + tick_len;
        let right = w - (16 * s).max(pad);
        let x_ticks = choose_ticks(&x_axis, (right - left) as f64, s, true);
        Layout { s, pad, left, top, right, bottom, x_axis, y_axis, x_ticks, y_ticks, title, x_title, y_title }
    }

    fn draw(&self, img: &mut RgbaImage, l: &Layout) {
        let s = l.s;
        let (w, h) = (img.width() as i64, img.height() as i64);
        let whole = Rect { x0: 0, y0: 0, x1: w, y1: h };
        if !l.title.text.is_empty() {
            // Faux bold: the title drawn twice, one pixel apart.
            let tw = text_px(&l.title.text, l.title.scale) + 1;
            for dx in 0..2 {
                draw_text(img, whole, (w - tw) / 2 + dx, l.pad, &l.title.text, l.title.scale, TEXT);
            }
        }
        if l.right - l.left < 2 || l.bottom - l.top < 2 {
            return; // too small for a plot area
        }
        let area = Rect { x0: l.left, y0: l.top, x1: l.right, y1: l.bottom };

        // Grid and minor ticks.
        for t in &l.x_ticks.major {
            let x = l.px(t.value).floor() as i64;
            fill_rect(img, area, x, l.top, x + 1, l.bottom, GRID, 1.0);
        }
        for t in &l.y_ticks.major {
            let y = l.py(t.value).floor() as i64;
            fill_rect(img, area, l.left, y, l.right, y + 1, GRID, 1.0);
        }

        // Budget line, dashed, under the data.
        let vline = self.vline_x().map(|v| l.px(v));
        if let Some(x) = vline {
            let x0 = (x - s as f64 / 2.0).round() as i64;
            let (on, off) = (7 * s, 4 * s);
            let mut y = l.top;
            while y < l.bottom {
                fill_rect(img, area, x0, y, x0 + s, (y + on).min(l.bottom), BUDGET_COLOR, 1.0);
                y += on + off;
            }
        }

        // Pareto front.
        let mut front: Vec<(f64, f64)> = self.pareto.iter().copied().filter(|&p| self.drawable(p)).collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let front_px: Vec<(f64, f64)> = front.iter().map(|&(x, y)| (l.px(x), l.py(y))).collect();
        stroke_polyline(img, area, &front_px, 0.9 * s as f64, PARETO_COLOR);

        // Points.
        let radius = 2.6 * s as f64 + 0.4;
        for (i, series) in self.series.iter().enumerate() {
            let marker = Marker::for_series(i);
            for &p in series.points.iter().filter(|&&p| self.drawable(p)) {
                let (x, y) = (l.px(p.0), l.py(p.1));
                fill_marker(img, area, marker, x, y, radius + 0.8 * s as f64, BACKGROUND);
                fill_marker(img, area, marker, x, y, radius, series.color);
            }
        }

        // Frame and ticks.
        let t = (s / 2).max(1);
        fill_rect(img, whole, l.left - t, l.top - t, l.right + t, l.top, AXIS, 1.0);
        fill_rect(img, whole, l.left - t, l.bottom, l.right + t, l.bottom + t, AXIS, 1.0);
        fill_rect(img, whole, l.left - t, l.top, l.left, l.bottom, AXIS, 1.0);
        fill_rect(img, whole, l.right, l.top, l.right + t, l.bottom, AXIS, 1.0);
        let tick_len = 4 * s;
        let cap = font::CAP_H as i64 * s;
        for x in l.x_ticks.minor.iter().map(|&v| l.px(v).floor() as i64) {
            fill_rect(img, whole, x, l.bottom + t, x + t, l.bottom + t + tick_len / 2, AXIS, 1.0);
        }
        for tk in &l.x_ticks.major {
            let x = l.px(tk.value).floor() as i64;
            fill_rect(img, whole, x, l.bottom + t, x + t, l.bottom + t + tick_len, AXIS, 1.0);
            let tw = text_px(&tk.label, s);
            let tx = (x - tw / 2).clamp(0, (w - tw).max(0));
            draw_text(img, whole, tx, l.bottom + tick_len + 3 * s, &tk.label, s, TICK_TEXT);
        }
        for tk in &l.y_ticks.major {
            let y = l.py(tk.value).floor() as i64;
            fill_rect(img, whole, l.left - t - tick_len, y, l.left - t, y + t, AXIS, 1.0);
            let tw = text_px(&tk.label, s);
            let ty = (y - cap / 2).clamp(0, (h - cap).max(0));
            draw_text(img, whole, l.left - t - tick_len - 3 * s - tw, ty, &tk.label, s, TICK_TEXT);
        }

        // Axis titles.
        if !l.x_title.text.is_empty() {
            let tw = text_px(&l.x_title.text, s);
            let tx = ((l.left + l.right - tw) / 2).clamp(l.pad.min(w - tw).max(0), (w - tw - l.pad).max(0));
            draw_text(img, whole, tx, h - l.pad - font::CELL_H as i64 * s, &l.x_title.text, s, TEXT);
        }
        if !l.y_title.text.is_empty() {
            let tw = text_px(&l.y_title.text, s);
            let ty = (l.top + l.bottom + tw) / 2;
            draw_text_up(img, whole, l.pad, ty, &l.y_title.text, s, TEXT);
        }

        // Obstacles for placing the legend: data, the front, the budget line and its label.
        let mut obstacles: Vec<(f64, f64, f64)> = Vec::new();
        for series in &self.series {
            obstacles.extend(series.points.iter().filter(|&&p| self.drawable(p)).map(|&p| (l.px(p.0), l.py(p.1), 1.0)));
        }
        for seg in front_px.windows(2) {
            let n = ((seg[1].0 - seg[0].0).hypot(seg[1].1 - seg[0].1) / 4.0).ceil().min(2000.0) as usize;
            for k in 0..=n {
                let f = k as f64 / n.max(1) as f64;
                obstacles.push((seg[0].0 + f * (seg[1].0 - seg[0].0), seg[0].1 + f * (seg[1].1 - seg[0].1), 0.5));
            }
        }

        // Budget label beside the line's top, on a translucent backing.
        if let (Some(x), Some((_, label))) = (vline, self.vertical_line.as_ref()) {
            let label = fit_text(label, s, s, l.right - l.left - 8 * s);
            if !label.text.is_empty() {
                let tw = text_px(&label.text, s);
                let gap = 5 * s;
                let mut tx = x.round() as i64 + gap;
                if tx + tw > l.right - 3 * s {
                    tx = x.round() as i64 - gap - tw;
                }
                let tx = tx.clamp(l.left + 3 * s, (l.right - 3 * s - tw).max(l.left + 3 * s));
                let ty = l.top + 5 * s;
                let b = Rect { x0: tx - 2 * s, y0: ty - 2 * s, x1: tx + tw + 2 * s, y1: ty + line_h_px(s) };
                fill_rect(img, area, b.x0, b.y0, b.x1, b.y1, BACKGROUND, 0.85);
                draw_text(img, area, tx, ty, &label.text, s, BUDGET_COLOR);
                for yy in (b.y0..b.y1).step_by(2) {
                    for xx in (b.x0..b.x1).step_by(2) {
                        obstacles.push((xx as f64, yy as f64, 4.0));
                    }
                }
            }
            let n = ((l.bottom - l.top) / 4).max(1);
            obstacles.extend((0..=n).map(|k| (x, l.top as f64 + k as f64 * 4.0, 0.3)));
        }

        self.draw_legend(img, l, area, &obstacles);
    }

    fn draw_legend(&self, img: &mut RgbaImage, l: &Layout, area: Rect, obstacles: &[(f64, f64, f64)]) {
        let s = l.s;
        let mut entries: Vec<(Option<Marker>, [u8; 3], &str)> = self
            .series
            .iter()
            .enumerate()
            .map(|(i, se)| (Some(Marker::for_series(i)), se.color, se.label.as_str()))
            .collect();
        if self.pareto.iter().any(|&p| self.drawable(p)) {
            entries.push((None, PARETO_COLOR, "Pareto front"));
        }
        if entries.is_empty() {
            return;
        }
        let inner = 6 * s;
        let sample_w = 16 * s;
        let row_h = line_h_px(s) + 3 * s;
        let inset = 6 * s;
        let max_label = (area.x1 - area.x0 - 2 * inset - 2 * inner - sample_w - 5 * s).max(0);
        let labels: Vec<String> = entries.iter().map(|e| fit_text(e.2, s, s, max_label).text).collect();
        let label_w = labels.iter().map(|t| text_px(t, s)).max().unwrap_or(0);
        let bw = 2 * inner + sample_w + 5 * s + label_w;
        let bh = 2 * inner + entries.len() as i64 * row_h - 3 * s;
        if bw > area.x1 - area.x0 - 2 * inset || bh > area.y1 - area.y0 - 2 * inset {
            return; // no room for a legend
        }
        // Corners in order of preference; take the one covering the least.
        let corners = [
            (area.x1 - inset - bw, area.y0 + inset),
            (area.x0 + inset, area.y1 - inset - bh),
            (area.x0 + inset, area.y0 + inset),
            (area.x1 - inset - bw, area.y1 - inset - bh),
        ];
        let margin = 4.0 * s as f64;
        let cost = |&(x0, y0): &(i64, i64)| -> f64 {
            let (x0, y0) = (x0 as f64 - margin, y0 as f64 - margin);
            let (x1, y1) = (x0 + bw as f64 + 2.0 * margin, y0 + bh as f64 + 2.0 * margin);
            obstacles.iter().filter(|o| o.0 >= x0 && o.0 <= x1 && o.1 >= y0 && o.1 <= y1).map(|o| o.2).sum()
        };
        let mut best = corners[0];
        let mut best_cost = cost(&best);
        for c in &corners[1..] {
            let k = cost(c);
            if k < best_cost {
                (best, best_cost) = (*c, k);
            }
        }
        let (x0, y0) = best;
        fill_rect(img, area, x0, y0, x0 + bw, y0 + bh, BACKGROUND, 0.92);
        let t = (s / 2).max(1);
        fill_rect(img, area, x0, y0, x0 + bw, y0 + t, LEGEND_BORDER, 1.0);
        fill_rect(img, area, x0, y0 + bh - t, x0 + bw, y0 + bh, LEGEND_BORDER, 1.0);
        fill_rect(img, area, x0, y0, x0 + t, y0 + bh, LEGEND_BORDER, 1.0);
        fill_rect(img, area, x0 + bw - t, y0, x0 + bw, y0 + bh, LEGEND_BORDER, 1.0);
        let cap = font::CAP_H as i64 * s;
        for (k, ((marker, color, _), label)) in entries.iter().zip(&labels).enumerate() {
            let ty = y0 + inner + k as i64 * row_h;
            let cy = ty as f64 + cap as f64 / 2.0;
            let sx = (x0 + inner) as f64;
            match marker {
                Some(m) => fill_marker(img, area, *m, sx + sample_w as f64 / 2.0, cy, 2.6 * s as f64 + 0.4, *color),
                None => stroke_polyline(img, area, &[(sx, cy), (sx + sample_w as f64, cy)], 0.9 * s as f64, *color),
            }
            draw_text(img, area, x0 + inner + sample_w + 5 * s, ty, label, s, TEXT);
        }
    }
}

/// Where everything goes, from [`ScatterPlot::layout`].
struct Layout {
    /// Text scale (font pixels to image pixels).
    s: i64,
    pad: i64,
    /// Plot area edges in pixels (`left..right`, `top..bottom`).
    left: i64,
    top: i64,
    right: i64,
    bottom: i64,
    x_axis: Axis,
    y_axis: Axis,
    x_ticks: Ticks,
    y_ticks: Ticks,
    title: Fitted,
    x_title: Fitted,
    y_title: Fitted,
}

impl Layout {
    fn px(&self, x: f64) -> f64 {
        self.left as f64 + self.x_axis.unit(x) * (self.right - self.left) as f64
    }
    fn py(&self, y: f64) -> f64 {
        self.bottom as f64 - self.y_axis.unit(y) * (self.bottom - self.top) as f64
    }
}

/// A data range shown on an axis.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
}

impl Axis {
    /// The range covering `values` (finite, positive when `log`) with a 5 % margin.
    fn covering(values: impl Iterator<Item = f64>, log: bool) -> Axis {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values {
            let v = if log { v.log10() } else { v };
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if lo > hi {
            (lo, hi) = (0.0, 1.0); // no data: a unit range (1..10 on a log axis)
        } else if lo == hi {
            let pad = if log {
                0.3
            } else if lo == 0.0 {
                1.0
            } else {
                lo.abs() * 0.1
            };
            (lo, hi) = (lo - pad, hi + pad);
        } else {
            let pad = 0.05 * hi - 0.05 * lo; // no overflow for huge ranges
            (lo, hi) = (lo - pad, hi + pad);
        }
        let (lo, hi) = if log {
            (10f64.powf(lo).clamp(f64::MIN_POSITIVE, f64::MAX), 10f64.powf(hi).clamp(f64::MIN_POSITIVE, f64::MAX))
        } else {
            (lo.clamp(-f64::MAX, f64::MAX), hi.clamp(-f64::MAX, f64::MAX))
        };
        Axis { lo, hi, log }
    }

    /// Position of `v` along the axis, 0 at `lo` and 1 at `hi`.
    fn unit(&self, v: f64) -> f64 {
        let (a, b, x) = if self.log { (self.lo.log10(), self.hi.log10(), v.log10()) } else { (self.lo, self.hi, v) };
        let u = (x - a) / (b - a);
        if u.is_finite() {
            u
        } else {
            0.5
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Tick {
    value: f64,
    label: String,
}

#[derive(Clone, Debug, Default, PartialEq)]
struct Ticks {
    major: Vec<Tick>,
    minor: Vec<f64>,
}

/// Linear tick sets in the 1-2-5 sequence, densest first.
fn linear_candidates(lo: f64, hi: f64) -> Vec<(Vec<f64>, f64)> {
    let span = hi - lo;
    let mut out = Vec::new();
    if !(span.is_finite() && span > 0.0) {
        return out;
    }
    let mut decade = 10f64.powf((span / 60.0).log10().floor());
    for _ in 0..12 {
        for m in [1.0, 2.0, 5.0] {
            let step = m * decade;
            let (first, last) = ((lo / step).ceil(), (hi / step).floor());
            if !(first.is_finite() && last.is_finite()) || last - first > 80.0 {
                continue;
            }
            if last < first {
                return out;
            }
            let values = (0..=(last - first) as i64)
                .map(|k| (first + k as f64) * step)
                .map(|v| if v.abs() < step * 1e-9 { 0.0 } else { v })
                .collect();
            out.push((values, step));
        }
        decade *= 10.0;
    }
    out
}

/// Picks the densest tick set whose labels neither crowd nor overlap along `length` pixels.
fn choose_ticks(axis: &Axis, length: f64, s: i64, horizontal: bool) -> Ticks {
    let unit_px = |v: f64| axis.unit(v) * length;
    let min_spacing = if horizontal { 55.0 } else { 40.0 } * s as f64;
    let fits = |ticks: &[Tick]| -> bool {
        ticks.windows(2).all(|p| {
            let d = (unit_px(p[1].value) - unit_px(p[0].value)).abs();
            let need = if horizontal {
                (text_px(&p[0].label, s) + text_px(&p[1].label, s)) as f64 / 2.0 + 10.0 * s as f64
            } else {
                (font::CELL_H as i64 * s + 6 * s) as f64
            };
            d >= need.max(min_spacing)
        })
    };
    let mut fallback: Option<Ticks> = None;
    let mut consider = |major: Vec<Tick>, minor: Vec<f64>| -> Option<Ticks> {
        if major.len() >= 2 && fits(&major) {
            return Some(Ticks { major, minor });
        }
        if !major.is_empty() && fallback.as_ref().is_none_or(|f| f.major.len() > major.len() || !fits(&f.major)) {
            // Keep the sparsest set seen so far, shown without labels if even it crowds.
            let t = if fits(&major) {
                major
            } else {
                major.into_iter().map(|t| Tick { label: String::new(), ..t }).collect()
            };
            fallback = Some(Ticks { major: t, minor });
        }
        None
    };
    if axis.log && axis.lo > 0.0 && axis.hi > axis.lo {
        let (a, b) = (axis.lo.log10().floor() as i64, axis.hi.log10().ceil() as i64);
        let in_range = |v: f64| v >= axis.lo * (1.0 - 1e-12) && v <= axis.hi * (1.0 + 1e-12);
        let values = |mantissas: &[f64], every: i64| -> Vec<f64> {
            (a..=b)
                .filter(|k| k.rem_euclid(every) == 0)
                .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k as i32)))
                .filter(|&v| in_range(v))
                .collect()
        };
        let labelled = |vs: Vec<f64>| vs.into_iter().map(|v| Tick { value: v, label: log_label(v) }).collect();
        let minor = |every: i64| -> Vec<f64> {
            if every > 1 || (b - a) > 12 {
                return Vec::new();
            }
            values(&[2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1)
        };
        if b - a <= 400 {
            let sets: [(&[f64], i64); 4] = [
                (&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1),
                (&[1.0, 2.0, 3.0, 5.0], 1),
                (&[1.0, 2.0, 5.0], 1),
                (&[1.0], 1),
            ];
            for (mantissas, every) in sets {
                let minor_vals: Vec<f64> = if mantissas.len() < 9 {
                    minor(every).into_iter().filter(|v| !values(mantissas, every).contains(v)).collect()
                } else {
                    Vec::new()
                };
                if let Some(t) = consider(labelled(values(mantissas, every)), minor_vals) {
                    return t;
                }
            }
            for every in [2, 3, 5, 10, 20, 50, 100] {
                if let Some(t) = consider(labelled(values(&[1.0], every)), Vec::new()) {
                    return t;
                }
            }
        }
    }
    for (values, step) in linear_candidates(axis.lo, axis.hi) {
        let major = values.into_iter().map(|v| Tick { value: v, label: linear_label(v, step) }).collect();
        if let Some(t) = consider(major, Vec::new()) {
            return t;
        }
    }
    fallback.unwrap_or_default()
}

/// Uses U+2212 for the minus sign, which the font draws as wide as `+`.
fn with_minus(s: String) -> String {
    s.replacen('-', "\u{2212}", 1)
}

/// A tick label for `v` on a linear axis with tick spacing `step`.
fn linear_label(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs();
    if mag >= 1e6 || step < 1e-5 {
        let digits = (mag.log10().floor() - step.log10().floor()).clamp(0.0, 15.0) as usize;
        let s = format!("{v:.digits$e}");
        return with_minus(s.replacen("e-", "e\u{2212}", 1));
    }
    let decimals = (-step.log10() - 1e-9).ceil().clamp(0.0, 15.0) as usize;
    with_minus(format!("{v:.decimals$}"))
}

/// A tick label for `v = m · 10^k` on a log axis.
fn log_label(v: f64) -> String {
    let k = v.log10().floor();
    if (-4.0..=5.0).contains(&k) {
        let decimals = (-k).max(0.0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.0e}").replacen("e-", "e\u{2212}", 1)
    }
}

/// Text shrunk to fit: the largest scale from `want` down to `min`, then cut with "…".
#[derive(Clone, Debug, PartialEq)]
struct Fitted {
    text: String,
    scale: i64,
}

fn fit_text(text: &str, want: i64, min: i64, max_w: i64) -> Fitted {
    let text = text.trim();
    for scale in (min.max(1)..=want.max(min).max(1)).rev() {
        if text_px(text, scale) <= max_w {
            return Fitted { text: text.to_string(), scale };
        }
    }
    let scale = min.max(1);
    let chars: Vec<char> = text.chars().collect();
    for n in (0..chars.len()).rev() {
        let t: String = chars[..n].iter().collect::<String>().trim_end().to_string() + "…";
        if text_px(&t, scale) <= max_w {
            return Fitted { text: if n == 0 { String::new() } else { t }, scale };
        }
    }
    Fitted { text: String::new(), scale }
}

fn text_px(text: &str, s: i64) -> i64 {
    font::text_width(text) as i64 * s
}

fn line_h_px(s: i64) -> i64 {
    font::CELL_H as i64 * s
}

fn rgba(c: [u8; 3]) -> Rgba<u8> {
    Rgba([c[0], c[1], c[2], 255])
}

/// A pixel rectangle, `x0..x1 × y0..y1`, used for clipping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    x0: i64,
    y0: i64,
    x1: i64,
    y1: i64,
}

impl Rect {
    /// Intersection with the image bounds.
    fn within(self, img: &RgbaImage) -> Rect {
        Rect {
            x0: self.x0.max(0),
            y0: self.y0.max(0),
            x1: self.x1.min(img.width() as i64),
            y1: self.y1.min(img.height() as i64),
        }
    }
}

/// Blends `color` over the pixel with coverage `alpha` (0..1); exact colour at full coverage.
fn blend(img: &mut RgbaImage, x: i64, y: i64, color: [u8; 3], alpha: f64) {
    if x < 0 || y < 0 || x >= img.width() as i64 || y >= img.height() as i64 || alpha <= 0.0 {
        return;
    }
    let p = img.get_pixel_mut(x as u32, y as u32);
    if alpha >= 0.999 {
        *p = rgba(color);
        return;
    }
    for c in 0..3 {
        p[c] = (p[c] as f64 * (1.0 - alpha) + color[c] as f64 * alpha).round() as u8;
    }
}

#[allow(clippy::too_many_arguments)] // a rectangle, its clip, colour and coverage
fn fill_rect(img: &mut RgbaImage, clip: Rect, x0: i64, y0: i64, x1: i64, y1: i64, color: [u8; 3], alpha: f64) {
    let c = clip.within(img);
    for y in y0.max(c.y0)..y1.min(c.y1) {
        for x in x0.max(c.x0)..x1.min(c.x1) {
            blend(img, x, y, color, alpha);
        }
    }
}

/// Text with its cap top-left corner at `(x, y)`.
fn draw_text(img: &mut RgbaImage, clip: Rect, x: i64, y: i64, text: &str, s: i64, color: [u8; 3]) {
    let mut pen = x;
    for ch in text.chars() {
        let g = font::glyph(ch);
        for gy in 0..font::CELL_H {
            for gx in g.left..g.left + g.width {
                if g.ink(gx, gy) {
                    let (px, py) = (pen + (gx - g.left) as i64 * s, y + gy as i64 * s);
                    fill_rect(img, clip, px, py, px + s, py + s, color, 1.0);
                }
            }
        }
        pen += (g.width as i64 + 1) * s;
    }
}

/// Text running upwards (rotated 90° anticlockwise), starting at `(x, y)`: the cap top is at
/// column `x`, the first character's left edge at row `y`.
fn draw_text_up(img: &mut RgbaImage, clip: Rect, x: i64, y: i64, text: &str, s: i64, color: [u8; 3]) {
    let mut pen = 0;
    for ch in text.chars() {
        let g = font::glyph(ch);
        for gy in 0..font::CELL_H {
            for gx in g.left..g.left + g.width {
                if g.ink(gx, gy) {
                    let along = pen + (gx - g.left) as i64 * s;
                    let (px, py) = (x + gy as i64 * s, y - along - s);
                    fill_rect(img, clip, px, py, px + s, py + s, color, 1.0);
                }
            }
        }
        pen += (g.width as i64 + 1) * s;
    }
}

/// Marker shapes, cycled over the series so they differ without colour too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Marker {
    Circle,
    Square,
    Diamond,
    TriangleUp,
    TriangleDown,
}

impl Marker {
    fn for_series(i: usize) -> Marker {
        [Marker::Circle, Marker::Square, Marker::Diamond, Marker::TriangleUp, Marker::TriangleDown][i % 5]
    }

    /// Approximate signed distance from the shape's edge (negative inside), image y down.
    fn sdf(self, dx: f64, dy: f64, r: f64) -> f64 {
        let (c30, s30) = (0.866_025_403_784_438_6, 0.5);
        match self {
            Marker::Circle => dx.hypot(dy) - r,
            Marker::Square => dx.abs().max(dy.abs()) - 0.88 * r,
            Marker::Diamond => (dx.abs() + dy.abs()) * std::f64::consts::FRAC_1_SQRT_2 - 0.85 * r,
            Marker::TriangleUp | Marker::TriangleDown => {
                let dy = if self == Marker::TriangleUp { dy - 0.15 * r } else { -dy - 0.15 * r };
                let big = 1.25 * r; // circumradius
                let d = dy.max(c30 * dx - s30 * dy).max(-c30 * dx - s30 * dy);
                d - big / 2.0
            }
        }
    }
}

fn fill_marker(img: &mut RgbaImage, clip: Rect, m: Marker, cx: f64, cy: f64, r: f64, color: [u8; 3]) {
    if !(cx.is_finite() && cy.is_finite() && r.is_finite()) {
        return;
    }
    let c = clip.within(img);
    let reach = 1.5 * r + 2.0;
    let (x0, x1) = (((cx - reach).floor() as i64).max(c.x0), ((cx + reach).ceil() as i64).min(c.x1));
    let (y0, y1) = (((cy - reach).floor() as i64).max(c.y0), ((cy + reach).ceil() as i64).min(c.y1));
    for y in y0..y1 {
        for x in x0..x1 {
            let d = m.sdf(x as f64 + 0.5 - cx, y as f64 + 0.5 - cy, r);
            blend(img, x, y, color, (0.5 - d).clamp(0.0, 1.0));
        }
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (abx, aby) = (b.0 - a.0, b.1 - a.1);
    let len2 = abx * abx + aby * aby;
    let t = if len2 > 0.0 { (((p.0 - a.0) * abx + (p.1 - a.1) * aby) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p.0 - a.0 - t * abx).hypot(p.1 - a.1 - t * aby)
}

/// An anti-aliased polyline of half-width `hw`; joints are not blended twice.
fn stroke_polyline(img: &mut RgbaImage, clip: Rect, pts: &[(f64, f64)], hw: f64, color: [u8; 3]) {
    let pts: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
    if pts.len() < 2 {
        return;
    }
    let c = clip.within(img);
    let reach = hw + 1.0;
    let bx0 = (pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) - reach).floor().max(c.x0 as f64) as i64;
    let bx1 = (pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max) + reach).ceil().min(c.x1 as f64) as i64;
    let by0 = (pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min) - reach).floor().max(c.y0 as f64) as i64;
    let by1 = (pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max) + reach).ceil().min(c.y1 as f64) as i64;
    if bx1 <= bx0 || by1 <= by0 {
        return;
    }
    let bw = (bx1 - bx0) as usize;
    let mut cover = vec![0.0f64; bw * (by1 - by0) as usize];
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let x0 = ((a.0.min(b.0) - reach).floor() as i64).max(bx0);
        let x1 = ((a.0.max(b.0) + reach).ceil() as i64).min(bx1);
        let y0 = ((a.1.min(b.1) - reach).floor() as i64).max(by0);
        let y1 = ((a.1.max(b.1) + reach).ceil() as i64).min(by1);
        for y in y0..y1 {
            for x in x0..x1 {
                let d = segment_distance((x as f64 + 0.5, y as f64 + 0.5), a, b);
                let k = (y - by0) as usize * bw + (x - bx0) as usize;
                cover[k] = cover[k].max((hw + 0.5 - d).clamp(0.0, 1.0));
            }
        }
    }
    for y in by0..by1 {
        for x in bx0..bx1 {
            blend(img, x, y, color, cover[(y - by0) as usize * bw + (x - bx0) as usize]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> ScatterPlot {
        let techniques: [(&str, [u8; 3], f64, f64); 4] = [
            ("SSAO full", [31, 119, 180], 14.0, 0.09),
            ("HBAO full", [255, 127, 14], 22.0, 0.06),
            ("SSDO full", [44, 160, 44], 30.0, 0.05),
            ("SSAO half", [214, 39, 40], 5.0, 0.12),
        ];
        let series: Vec<Series> = techniques
            .iter()
            .map(|&(label, color, ms, err)| Series {
                label: label.into(),
                color,
                points: [12.0, 24.0, 36.0, 64.0]
                    .iter()
                    .map(|&n| (ms * n / 12.0, err * (12.0 / n).sqrt() + 0.01))
                    .collect(),
            })
            .collect();
        let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.points.iter().copied()).collect();
        let pareto = crate::measure::metrics::pareto_front(&all).into_iter().map(|i| all[i]).collect();
        ScatterPlot {
            title: "crease: AO error against time, 1080×1200 per eye, llvmpipe (LLVM 19.1.7, 256 bits)".into(),
            x_label: "occlusion ms per eye (technique + blur + upsample)".into(),
            y_label: "AO RMSE vs reference".into(),
            series,
            pareto,
            vertical_line: Some((5.55, "budget 5.55 ms/eye".into())),
            log_x: true,
        }
    }

    fn count_color(img: &RgbaImage, c: [u8; 3]) -> usize {
        img.pixels().filter(|p| p.0 == [c[0], c[1], c[2], 255]).count()
    }

    #[test]
    fn renders_requested_size_with_every_series_colour() {
        let plot = example();
        let img = plot.render(900, 600);
        assert_eq!(img.dimensions(), (900, 600));
        for s in &plot.series {
            assert!(count_color(&img, s.color) > 20, "{}", s.label);
        }
        assert!(count_color(&img, PARETO_COLOR) > 20);
        assert!(count_color(&img, BUDGET_COLOR) > 20);
    }

    #[test]
    fn budget_line_column_is_dashed() {
        for log_x in [false, true] {
            let mut plot = example();
            plot.log_x = log_x;
            // Outside the data: the x range grows to show it.
            plot.vertical_line = Some((400.0, "budget".into()));
            let img = plot.render(800, 500);
            let l = plot.layout(800, 500);
            let x = l.px(400.0).floor() as u32;
            assert!(x > l.left as u32 && x < l.right as u32, "inside the plot area");
            let on: Vec<bool> =
                (l.top as u32..l.bottom as u32).map(|y| img.get_pixel(x, y).0[..3] == BUDGET_COLOR).collect();
            let n_on = on.iter().filter(|&&b| b).count();
            assert!(n_on > on.len() / 3 && n_on < on.len(), "dashed: {n_on} of {}", on.len());
        }
    }

    #[test]
    fn degenerate_data_renders() {
        let one = ScatterPlot {
            series: vec![Series { label: "one".into(), color: [10, 200, 30], points: vec![(3.0, 0.5)] }],
            ..Default::default()
        };
        let img = one.render(400, 300);
        assert!(count_color(&img, [10, 200, 30]) > 4);

        let nasty = ScatterPlot {
            title: "NaN and friends".into(),
            series: vec![
                Series {
                    label: "bad".into(),
                    color: [200, 0, 0],
                    points: vec![(f64::NAN, 1.0), (1.0, f64::INFINITY), (f64::NEG_INFINITY, 0.0), (-1.0, 2.0)],
                },
                Series {
                    label: "same x".into(),
                    color: [0, 0, 200],
                    points: vec![(2.0, 1.0), (2.0, 3.0), (2.0, -1.0)],
                },
                Series { label: "empty".into(), color: [0, 200, 0], points: vec![] },
                Series { label: "huge".into(), color: [0, 90, 90], points: vec![(1e-300, -1e308), (1e300, 1e308)] },
            ],
            pareto: vec![(f64::NAN, f64::NAN), (0.0, 0.0)],
            vertical_line: Some((f64::NAN, "nan".into())),
            log_x: true,
            ..Default::default()
        };
        for (w, h) in [(640, 480), (50, 40), (1, 1), (0, 0), (3000, 20), (20, 3000)] {
            let img = nasty.render(w, h);
            assert_eq!(img.dimensions(), (w, h));
            let img = ScatterPlot { log_x: false, ..nasty.clone() }.render(w, h);
            assert_eq!(img.dimensions(), (w, h));
        }
        assert!(count_color(&nasty.render(640, 480), [0, 0, 200]) > 4);
        let empty = ScatterPlot::default().render(300, 200);
        assert_eq!(empty.dimensions(), (300, 200));
    }

    #[test]
    fn nice_ticks() {
        let t = choose_ticks(&Axis { lo: 0.0, hi: 1.0, log: false }, 600.0, 1, true);
        let labels: Vec<&str> = t.major.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["0", "0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7", "0.8", "0.9", "1.0"]);
        let t = choose_ticks(&Axis { lo: 0.5, hi: 2000.0, log: true }, 600.0, 1, true);
        let labels: Vec<&str> = t.major.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["1", "10", "100", "1000"]);
        assert!(t.minor.contains(&20.0));
        let t = choose_ticks(&Axis { lo: -3.0, hi: 7.0, log: false }, 300.0, 1, false);
        assert!(t.major.iter().any(|t| t.label == "\u{2212}2"), "{t:?}");
        assert_eq!(linear_label(2.5e-7, 5e-8), "2.5e\u{2212}7");
        assert_eq!(log_label(0.002), "0.002");
        assert_eq!(log_label(1e-7), "1e\u{2212}7");
    }

    #[test]
    fn text_fits() {
        let f = fit_text("a long title that does not fit", 3, 1, 60);
        assert!(text_px(&f.text, f.scale) <= 60 && f.text.ends_with('…'));
        assert_eq!(fit_text("x", 3, 1, 0).text, "");
        assert_eq!(fit_text("short", 3, 1, 1000), Fitted { text: "short".into(), scale: 3 });
    }

    #[test]
    fn saves_png() {
        let path = std::env::temp_dir().join(format!("vrao_plot_test_{}.png", std::process::id()));
        example().save_png(&path, 320, 200).unwrap();
        let back = image::open(&path).unwrap();
        assert_eq!((back.width(), back.height()), (320, 200));
        std::fs::remove_file(&path).ok();
        let bad = Path::new("/nonexistent-dir/x/plot.png");
        assert!(matches!(example().save_png(bad, 10, 10), Err(Error::Output { .. })));
    }

    /// Writes the example to /tmp/plot_example.png for a look: `VRAO_PLOT_EXAMPLE=1`.
    #[test]
    fn example_png() {
        if std::env::var_os("VRAO_PLOT_EXAMPLE").is_some() {
            example().save_png(Path::new("/tmp/plot_example.png"), 1280, 800).unwrap();
            ScatterPlot { log_x: false, ..example() }
                .save_png(Path::new("/tmp/plot_example_lin.png"), 640, 400)
                .unwrap();
        }
    }
}
