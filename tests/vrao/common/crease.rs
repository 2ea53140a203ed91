//! The 90° crease (`builtin:crease`): one technique's AO binned by distance to the crease
//! line, next to its expectations from analysis (`vrao::measure::analytic`), and the
//! assertions on those bins. Shared by tests/occlusion_ssao_ssdo.rs and
//! tests/occlusion_hbao_gtao.rs.

use super::occlusion::{ao, render, same_surface_blur, settings, Frame};
use glam::DVec3;
use std::sync::Arc;
use vrao::measure::analytic::{self, DepthView, Estimator, EstimatorParams, HbaoParams, Rect};
use vrao_ao::plug::{hbao_directions_steps, hemisphere_kernel, Gpu, HemisphereDensity, AO_BLURRED, AO_RAW};
use vrao_ao::{Denoise, HeadPose, Noise, Technique};
use vrao_render::scene::builtin::CREASE_WALL_Z;
use vrao_render::scene::Scene;

pub(crate) const CREASE_SIZE: (u32, u32) = (160, 180);
pub(crate) const CREASE_RADIUS: f64 = 1.0;
pub(crate) const CREASE_SAMPLES: u32 = 64;
/// Bins of distance to the crease line (metres).
pub(crate) const CREASE_BIN: f64 = 0.1;
pub(crate) const CREASE_BINS: usize = 13;

/// Eye on the crease's bisector plane, 2.5 m from the crease line and looking at it, so
/// floor and wall are mirror images, both seen at 45°, and a floor strip of 1 m in
/// front of the wall spans about 28 rows at 180 rows.
pub(crate) fn crease_head() -> HeadPose {
    let target = DVec3::new(0.0, 0.0, CREASE_WALL_Z);
    let d = 2.5 / 2f64.sqrt();
    HeadPose::look_at(target + DVec3::new(0.0, d, d), target).unwrap()
}

/// 1 = floor, 2 = wall, 0 = neither (sky, the crease line itself, anything else).
pub(crate) fn crease_class(p: Option<DVec3>) -> u8 {
    let Some(p) = p else { return 0 };
    let on_floor = p.y.abs() < 1e-3 && p.z > CREASE_WALL_Z + 1e-3;
    let on_wall = (p.z - CREASE_WALL_Z).abs() < 1e-3 && p.y > 1e-3;
    match (on_floor, on_wall) {
        (true, false) => 1,
        (false, true) => 2,
        _ => 0,
    }
}

/// Distance from a floor or wall point to the crease line.
pub(crate) fn crease_distance(p: DVec3, class: u8) -> f64 {
    if class == 1 {
        p.z - CREASE_WALL_Z
    } else {
        p.y
    }
}

/// Per-bin means of one crease measurement.
#[derive(Debug, Default, Clone)]
pub(crate) struct CreaseBin {
    pub lo: f64,
    pub pixels: usize,
    pub raw: f64,
    pub blurred: f64,
    /// The estimator's expectation at each pixel, simulated on the CPU (SSAO and SSDO:
    /// depth tests against the crease; HBAO: its march), and blurred like the AO.
    pub expected_raw: f64,
    pub expected_blurred: f64,
    /// SSAO and SSDO: the closed forms
    /// `analytic::ss{a,d}o_crease_expectation_with_depth_scale`.
    pub closed_raw: f64,
    /// Reference visibility (hits within r) and with HBAO's linear falloff, per pixel and
    /// blurred like the AO.
    pub reference: f64,
    pub falloff_raw: f64,
    pub falloff_blurred: f64,
    /// Pixels whose whole 11×11 blur window lies on modelled pixels.
    pub blurred_pixels: usize,
}

/// Renders the crease with `technique` (64 taps, r = 1 m, the default bias 0.02 and blur
/// 5) and bins floor and wall pixels of both eyes by their distance to the crease line.
///
/// Pixels used: on the floor or the wall, |X| ≤ 3 m (the wall is ±5 m wide, so it is
/// infinite within r), more than 3 px from the other surface (the crease line, where the
/// depth probe's pixel quantisation decides between floor and wall), and with the whole
/// part of the other surface within r on screen in that eye (screen-space methods miss
/// off-screen occluders). For the blurred comparison every same-surface pixel of the
/// 11×11 window must be modelled too.
pub(crate) fn measure_crease(gpu: &Arc<Gpu>, technique: Technique) -> Vec<CreaseBin> {
    let scene = Scene::load("builtin:crease").unwrap();
    let (w, h) = CREASE_SIZE;
    let mut settings = settings(w, h, ao(technique, CREASE_SAMPLES, CREASE_RADIUS as f32));
    settings.ao.noise = Noise::Halton;
    // The blur is simulated below as a same-surface box of the bilateral's radius.
    settings.ao.denoise = Denoise::Bilateral;
    let f = render(gpu, &scene, &settings, &crease_head(), &[AO_RAW, AO_BLURRED]);
    let expectation = CreaseExpectation::new(technique);
    let blur = settings.ao.blur_radius as i32;
    let mut bins: Vec<CreaseBin> =
        (0..CREASE_BINS).map(|i| CreaseBin { lo: i as f64 * CREASE_BIN, ..Default::default() }).collect();
    for layer in 0..2 {
        let model = model_layer(&f, layer, &expectation);
        bin_layer(&mut bins, &f, layer, &model, blur);
    }
    average_bins(&mut bins);
    print_bins(technique, &bins);
    bins
}

/// One technique's expected AO on the crease, computed on the CPU.
struct CreaseExpectation {
    technique: Technique,
    /// SSAO and SSDO by their depth-test simulation, HBAO by its march (None).
    estimator: Option<(Estimator, Vec<[f32; 4]>)>,
    hbao: HbaoParams,
    rects: [Rect; 2],
}

impl CreaseExpectation {
    fn new(technique: Technique) -> Self {
        let estimator = match technique {
            Technique::Ssao => Some((Estimator::Ssao, hemisphere_kernel(CREASE_SAMPLES, HemisphereDensity::Cosine))),
            Technique::SsdoPoints | Technique::SsdoPointsBounce => {
                Some((Estimator::Ssdo, hemisphere_kernel(CREASE_SAMPLES, HemisphereDensity::Uniform)))
            }
            Technique::Hbao | Technique::Gtao | Technique::Ssdo | Technique::SsdoBounce => None,
            other => panic!("no crease expectation for {}", other.name()),
        };
        let (directions, steps) = hbao_directions_steps(CREASE_SAMPLES);
        let hbao = HbaoParams { radius: CREASE_RADIUS, bias: 0.02, directions, steps, rotations: 28 };
        CreaseExpectation { technique, estimator, hbao, rects: analytic::crease_rects() }
    }

    /// The expectation at pixel `i` of `layer`, which shows surface `c` at `d` from the
    /// crease line, and the closed form (SSAO and SSDO; 1 for the others).
    fn at(&self, f: &Frame, view: &DepthView, layer: usize, i: usize, c: u8, d: f64) -> (f64, f64) {
        let p = f.world[layer][i].unwrap();
        let r = CREASE_RADIUS;
        let hit = |o: DVec3, d: DVec3| analytic::first_hit(&self.rects, o, d);
        let normal = if c == 1 { DVec3::Y } else { DVec3::Z };
        match &self.estimator {
            Some((est, kernel)) => {
                // Depth per metre behind the other surface along the ray to P.
                let e = (p - view.eye).normalize();
                let other_normal = if c == 1 { DVec3::Z } else { DVec3::Y };
                let k = e.dot(view.forward) / e.dot(other_normal).abs();
                let closed = match est {
                    Estimator::Ssao => analytic::ssao_crease_expectation_with_depth_scale(d, r, 0.02, kernel, k),
                    Estimator::Ssdo => analytic::ssdo_crease_expectation_with_depth_scale(d, r, 0.02, kernel, k),
                };
                let params =
                    EstimatorParams { estimator: *est, radius: r, bias: 0.02, range_check: true, rotations: 24 };
                (analytic::screen_space_expectation(&params, p, normal, kernel, view, hit), closed)
            }
            // GTAO estimates the reference itself (no simulation of its own).
            None if self.technique == Technique::Gtao => (analytic::crease_visibility(d, r), 1.0),
            None => {
                let (w, h) = CREASE_SIZE;
                let pixel = (i as u32 % w, i as u32 / w);
                (analytic::hbao_expectation(&self.hbao, &f.eyes.eyes[layer], (w, h), pixel, normal, hit), 1.0)
            }
        }
    }
}

/// One eye's per-pixel inputs to the bins.
struct LayerModel {
    /// `crease_class` of each pixel.
    class: Vec<u8>,
    /// Whether the pixel is used (see `measure_crease`).
    modelled: Vec<bool>,
    /// `CreaseExpectation::at`: the expectation and the closed form (1 beyond r).
    expected: Vec<f64>,
    closed: Vec<f64>,
    /// The reference with HBAO's linear falloff.
    falloff: Vec<f64>,
}

fn model_layer(f: &Frame, layer: usize, expectation: &CreaseExpectation) -> LayerModel {
    let (w, h) = CREASE_SIZE;
    let r = CREASE_RADIUS;
    let n = (w * h) as usize;
    let class: Vec<u8> = f.world[layer].iter().map(|p| crease_class(*p)).collect();
    let mut m = LayerModel {
        class,
        modelled: vec![false; n],
        expected: vec![1.0; n],
        closed: vec![1.0; n],
        falloff: vec![1.0; n],
    };
    let view = DepthView { eye: f.eyes.eyes[layer].pose.position, forward: f.forward(layer) };
    for i in 0..n {
        let (c, Some(p)) = (m.class[i], f.world[layer][i]) else { continue };
        if c == 0 {
            continue;
        }
        let d = crease_distance(p, c);
        m.modelled[i] = p.x.abs() <= 3.0 && (d >= r || other_surface_on_screen(f, layer, p, c, d));
        m.falloff[i] = analytic::crease_visibility_falloff(d, r);
        if d < r * 1.05 {
            (m.expected[i], m.closed[i]) = expectation.at(f, &view, layer, i, c, d);
        }
    }
    m
}

/// Whether the part of the other surface within r of `p` (on surface `c`, `d` from the
/// crease line) is on screen in `layer`: it is a half disc of radius √(r² − d²) around
/// the foot of P on the crease line; it (with 0.2 m to spare for the wall points that
/// hide samples just behind the wall) must be on screen. Checked along its rim every 15°.
fn other_surface_on_screen(f: &Frame, layer: usize, p: DVec3, c: u8, d: f64) -> bool {
    let r = CREASE_RADIUS;
    let rim = (r * r - d * d).max(0.0).sqrt() + 0.2;
    (0..=12).all(|k| {
        let (sin, cos) = (k as f64 * std::f64::consts::PI / 12.0).sin_cos();
        let q = if c == 1 {
            DVec3::new(p.x + rim * cos, rim * sin, CREASE_WALL_Z)
        } else {
            DVec3::new(p.x + rim * cos, 0.0, CREASE_WALL_Z + rim * sin)
        };
        f.on_screen(layer, q, 0.005)
    })
}

/// Adds one eye's modelled pixels more than 3 px from the other surface to the sums of
/// their bins (`average_bins` turns them into means); the blurred sums only where the
/// whole blur window is modelled.
fn bin_layer(bins: &mut [CreaseBin], f: &Frame, layer: usize, m: &LayerModel, blur: i32) {
    let (w, h) = CREASE_SIZE;
    let r = CREASE_RADIUS;
    let expected_blurred = same_surface_blur(&m.expected, &m.class, w, h, blur);
    let falloff_blurred = same_surface_blur(&m.falloff, &m.class, w, h, blur);
    for y in 0..h {
        for x in 0..w {
            let i = f.index(x, y);
            if !m.modelled[i] {
                continue;
            }
            // More than 3 px from anything that is not this surface.
            if !window_all((x, y), 3, |q| m.class[q] == m.class[i]) {
                continue;
            }
            let d = crease_distance(f.world[layer][i].unwrap(), m.class[i]);
            let bin = (d / CREASE_BIN) as usize;
            if bin >= CREASE_BINS {
                continue;
            }
            let b = &mut bins[bin];
            b.pixels += 1;
            b.raw += f.ao(AO_RAW, layer, x, y);
            b.expected_raw += m.expected[i];
            b.closed_raw += m.closed[i];
            b.reference += analytic::crease_visibility(d, r);
            b.falloff_raw += m.falloff[i];
            let window_ok = window_all((x, y), blur, |q| m.class[q] != m.class[i] || m.modelled[q]);
            if window_ok {
                b.blurred_pixels += 1;
                b.blurred += f.ao(AO_BLURRED, layer, x, y);
                b.expected_blurred += expected_blurred[i];
                b.falloff_blurred += falloff_blurred[i];
            }
        }
    }
}

/// Whether `want` holds at every pixel of the square window of `radius` around `(x, y)`
/// that lies inside the image.
fn window_all((x, y): (u32, u32), radius: i32, want: impl Fn(usize) -> bool) -> bool {
    let (w, h) = CREASE_SIZE;
    (-radius..=radius).all(|dy| {
        (-radius..=radius).all(|dx| {
            let (qx, qy) = (x as i32 + dx, y as i32 + dy);
            qx < 0 || qy < 0 || qx >= w as i32 || qy >= h as i32 || want((qy as u32 * w + qx as u32) as usize)
        })
    })
}

/// Sums to means: per pixel, and per pixel with a whole blur window.
fn average_bins(bins: &mut [CreaseBin]) {
    for b in bins {
        let (n, nb) = (b.pixels.max(1) as f64, b.blurred_pixels.max(1) as f64);
        b.raw /= n;
        b.expected_raw /= n;
        b.closed_raw /= n;
        b.reference /= n;
        b.falloff_raw /= n;
        b.blurred /= nb;
        b.expected_blurred /= nb;
        b.falloff_blurred /= nb;
    }
}

fn print_bins(technique: Technique, bins: &[CreaseBin]) {
    eprintln!(
        "crease {}: distance | px raw expected closed-form | px blurred expected | reference, falloff reference raw blurred",
        technique.name()
    );
    for b in bins {
        eprintln!(
            "  [{:.1}, {:.1}) | {:4} {:.3} {:.3} {:.3} | {:4} {:.3} {:.3} | {:.3} {:.3} {:.3}",
            b.lo,
            b.lo + CREASE_BIN,
            b.pixels,
            b.raw,
            b.expected_raw,
            b.closed_raw,
            b.blurred_pixels,
            b.blurred,
            b.expected_blurred,
            b.reference,
            b.falloff_raw,
            b.falloff_blurred
        );
    }
}

/// The crease darkens towards its edge: blurred AO per bin never rises by more than the
/// noise (0.01) towards the wall, and the bin nearest the wall is clearly darker than
/// the open floor beyond r.
pub(crate) fn assert_falls_towards_the_edge(name: &str, bins: &[CreaseBin]) {
    let used: Vec<&CreaseBin> = bins.iter().filter(|b| b.blurred_pixels >= 100).collect();
    assert!(used.len() >= 10, "{name}: too few populated bins ({})", used.len());
    for pair in used.windows(2) {
        assert!(
            pair[1].blurred >= pair[0].blurred - 0.01,
            "{name}: AO rises towards the wall: {:.3} at {:.1} m, {:.3} at {:.1} m",
            pair[0].blurred,
            pair[0].lo,
            pair[1].blurred,
            pair[1].lo
        );
    }
    let (first, last) = (used[0], used[used.len() - 1]);
    assert!(last.lo >= CREASE_RADIUS, "{name}: the bins reach past r");
    assert!(
        first.blurred < last.blurred - 0.1 && last.blurred > 0.98,
        "{name}: no darkening at the crease: {:.3} near it, {:.3} beyond r",
        first.blurred,
        last.blurred
    );
}

/// Asserts `|value − expected| ≤ tolerance` in every bin with at least 100 pixels.
pub(crate) fn assert_bins(
    name: &str,
    what: &str,
    bins: &[CreaseBin],
    tolerance: f64,
    get: impl Fn(&CreaseBin) -> (usize, f64, f64),
) {
    let mut checked = 0;
    for b in bins {
        let (pixels, value, expected) = get(b);
        if pixels < 100 {
            continue;
        }
        checked += 1;
        assert!(
            (value - expected).abs() <= tolerance,
            "{name} {what} at [{:.1}, {:.1}) m ({pixels} px): {value:.3}, expected {expected:.3} ± {tolerance}",
            b.lo,
            b.lo + CREASE_BIN
        );
    }
    assert!(checked >= 10, "{name} {what}: only {checked} bins populated");
}

/// Tolerance of a bin mean against the estimator's own expectation (SSAO, HBAO, SSDO).
///
/// The expectation runs the estimator's test on the CPU (`vrao::measure::analytic`) at each
/// pixel's reconstructed position with the real eye, averaged over kernel rotations, so
/// what remains is: (a) the finite rotation pattern: one pixel's SSAO with 64 taps varies
/// by ±0.02 (one standard deviation) over rotations near the crease, and a bin averages
/// ≥ 100 (mostly ≥ 500) pixels whose R2-sequence rotations are evenly spread, so the bin
/// mean is within about 0.002 of the rotation average; (b) the depth probe reads the
/// surface at the centre of the pixel a sample falls in, not on the ray through the
/// sample: half a pixel on a surface seen at 45° moves the depth tolerance by up to
/// ±0.01 m per sample, which averages out over samples and pixels to well below 0.005;
/// (c) f16 storage (2.5e-4 near 0.8) and 24 (HBAO 28) simulated rotations (≈ 0.002).
/// 0.01 covers these. It is tight enough to catch a wrong parameter: at 0.15 m from
/// the crease a radius 10 % short raises SSAO by 0.016, no bias lowers it by 0.013, a
/// doubled bias raises it by 0.018, half the taps (a shorter kernel) by 0.006.
pub(crate) const EXPECTATION_TOLERANCE: f64 = 0.01;
