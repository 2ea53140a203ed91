//! The occlusion family (SSAO, HBAO, SSDO, SSDO + bounce, bilateral blur, half-resolution
//! upsampling) on the GPU, against expectations from analysis (`vrao::measure::analytic`):
//! an open plane is unoccluded, a 90° crease darkens towards its edge as the estimators'
//! expected values and the reference visibility say, SSDO shadows what faces away from a
//! single light, a red wall bleeds red only with the bounce, the blur keeps depth edges,
//! half resolution stays close to full resolution, both eyes agree, nothing is NaN or Inf,
//! and the frame plan says what it left out.
//!
//! Every test prints its measurements (`cargo test --release --test occlusion -- --nocapture`).

mod common;

use glam::{DVec3, Vec3};
use std::collections::BTreeMap;
use std::sync::Arc;
use vrao::measure::analytic::{self, DepthView, Estimator, EstimatorParams, HbaoParams};
use vrao::measure::stereo_consistency::{stereo_consistency, EyeImages};
use vrao::render::graph::FINAL_AO;
use vrao::render::passes::blur::AO_BLURRED;
use vrao::render::passes::composite::HDR;
use vrao::render::passes::gbuffer::DEPTH;
use vrao::render::passes::occlusion::{AO_GEOMETRY, AO_RAW};
use vrao::render::passes::temporal::AO_ACCUMULATED;
use vrao::render::passes::tonemap::COLOR;
use vrao::render::passes::upsample::AO_FULL;
use vrao::render::sampling::{hbao_directions_steps, hemisphere_kernel, HemisphereDensity};
use vrao::render::scene::builtin::{CREASE_WALL_Z, ROOM_MAX, ROOM_MIN};
use vrao::render::scene::{environment, Environment, Scene};
use vrao::render::settings::{AoSettings, BounceForm, Denoise, Noise, Technique};
use vrao::render::stereo::HeadsetProfile;
use vrao::{EyePair, FrameReport, Gpu, HeadPose, Renderer, Resource, Settings};

/// The techniques that compute occlusion.
const AO_TECHNIQUES: [Technique; 5] =
    [Technique::Ssao, Technique::Hbao, Technique::Gtao, Technique::Ssdo, Technique::SsdoBounce];
/// Names of the passes that compute occlusion.
const AO_PASSES: [&str; 5] = ["ssao", "hbao", "gtao", "ssdo", "ssdo-bounce"];

fn settings(width: u32, height: u32, ao: AoSettings) -> Settings {
    Settings { profile: HeadsetProfile::with_size("test", width, height), ao, ..Settings::default() }
}

fn ao(technique: Technique, samples: u32, radius: f32) -> AoSettings {
    AoSettings { technique, samples, radius, ..AoSettings::default() }
}

/// One rendered stereo frame: the eyes, the depth, every pixel's world position and the
/// requested outputs read back (one Vec per eye layer, RGBA interleaved).
struct Frame {
    width: u32,
    height: u32,
    eyes: EyePair,
    /// World position per layer and pixel; `None` on the sky.
    world: Vec<Vec<Option<DVec3>>>,
    outputs: BTreeMap<Resource, Vec<Vec<f32>>>,
    report: FrameReport,
}

fn render(gpu: &Arc<Gpu>, scene: &Scene, s: &Settings, head: &HeadPose, outputs: &[Resource]) -> Frame {
    let mut renderer = Renderer::new(gpu.clone(), scene, s).unwrap();
    let eyes = s.profile.eyes(head, s.near);
    let mut wanted = outputs.to_vec();
    wanted.push(DEPTH);
    let report = renderer.render(&eyes.eyes, &wanted).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    let (w, h) = (s.profile.width, s.profile.height);
    let world = common::world_positions(&depth, &eyes.eyes, w, h, s.near);
    let outputs = outputs.iter().map(|&r| (r, renderer.read_f32(r).unwrap())).collect();
    Frame { width: w, height: h, eyes, world, outputs, report }
}

impl Frame {
    fn index(&self, x: u32, y: u32) -> usize {
        (y * self.width + x) as usize
    }
    fn world(&self, layer: usize, x: u32, y: u32) -> Option<DVec3> {
        self.world[layer][self.index(x, y)]
    }
    /// Alpha (AO) of a full-resolution output at a pixel.
    fn ao(&self, r: Resource, layer: usize, x: u32, y: u32) -> f64 {
        self.outputs[&r][layer][4 * self.index(x, y) + 3] as f64
    }
    fn rgb(&self, r: Resource, layer: usize, x: u32, y: u32) -> [f32; 3] {
        let i = 4 * self.index(x, y);
        let v = &self.outputs[&r][layer];
        [v[i], v[i + 1], v[i + 2]]
    }
    fn pixels(&self) -> impl Iterator<Item = (usize, u32, u32)> + '_ {
        let (w, h) = (self.width, self.height);
        (0..2usize).flat_map(move |l| (0..h).flat_map(move |y| (0..w).map(move |x| (l, x, y))))
    }
    /// Where a world point lands in `layer`, as a pixel, if on screen.
    fn pixel_of(&self, layer: usize, p: DVec3) -> Option<(u32, u32)> {
        let (uv, _) = self.eyes.eyes[layer].project(p, self.eyes.near)?;
        let (x, y) = (uv[0] * self.width as f64, uv[1] * self.height as f64);
        (x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64).then_some((x as u32, y as u32))
    }
    /// Whether a world point projects inside `layer` with `margin` (in uv) to spare.
    fn on_screen(&self, layer: usize, p: DVec3, margin: f64) -> bool {
        self.eyes.eyes[layer]
            .project(p, self.eyes.near)
            .is_some_and(|(uv, _)| uv.iter().all(|&c| c >= margin && c <= 1.0 - margin))
    }
    fn forward(&self, layer: usize) -> DVec3 {
        self.eyes.eyes[layer].pose.orientation * DVec3::NEG_Z
    }
}

fn mean(values: impl IntoIterator<Item = f64>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in values {
        sum += v;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// The blur's effect on a field that is smooth within each surface: a normalised
/// separable Gaussian (σ = radius / 2, taps within ±radius, off-image taps skipped) that
/// only averages pixels of the same surface class. On a plane the renderer's bilateral
/// weights (src/render/passes/blur/bilateral.wgsl: tangent-plane distance and normal agreement) are 1
/// between same-plane pixels and vanish across a crease or a depth step, so this is what
/// the blur does to an expectation image. Class 0 pixels are neither changed nor used.
fn same_surface_blur(values: &[f64], class: &[u8], width: u32, height: u32, radius: i32) -> Vec<f64> {
    let sigma = (radius as f64 * 0.5).max(0.5);
    let (w, h) = (width as i32, height as i32);
    let pass = |input: &[f64], axis: (i32, i32)| -> Vec<f64> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if class[i as usize] == 0 {
                    return input[i as usize];
                }
                let (mut sum, mut total) = (0.0, 0.0);
                for k in -radius..=radius {
                    let (qx, qy) = (x + axis.0 * k, y + axis.1 * k);
                    if qx < 0 || qy < 0 || qx >= w || qy >= h {
                        continue;
                    }
                    let q = (qy * w + qx) as usize;
                    if class[q] == class[i as usize] {
                        let weight = (-(k * k) as f64 / (2.0 * sigma * sigma)).exp();
                        sum += weight * input[q];
                        total += weight;
                    }
                }
                sum / total
            })
            .collect()
    };
    pass(&pass(values, (1, 0)), (0, 1))
}

// ---------------------------------------------------------------------------------------
// Open plane

#[test]
fn open_plane_is_unoccluded_for_every_technique() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:plane").unwrap();
    let head = scene.head.pose_at(0.0);
    // The defaults (r = 0.5 m, 24 taps) and a wide, dense kernel (r = 2 m, 64 taps) that
    // reaches far along the grazing floor towards the horizon.
    for (samples, radius) in [(24, 0.5), (64, 2.0)] {
        for technique in AO_TECHNIQUES {
            let s = settings(96, 108, ao(technique, samples, radius));
            let f = render(&gpu, &scene, &s, &head, &[AO_RAW, AO_BLURRED]);
            for r in [AO_RAW, AO_BLURRED] {
                let mut worst = (f64::INFINITY, 0, 0, 0);
                let mut covered = 0;
                for (l, x, y) in f.pixels() {
                    if f.world(l, x, y).is_none() {
                        continue;
                    }
                    covered += 1;
                    let a = f.ao(r, l, x, y);
                    if a.is_nan() || a < worst.0 {
                        worst = (a, l, x, y);
                    }
                }
                let (a, l, x, y) = worst;
                eprintln!(
                    "plane {} N={samples} r={radius} {}: min AO {a:.4} at eye {l} ({x}, {y}) {:?}",
                    technique.name(),
                    r.name(),
                    f.world(l, x, y)
                );
                assert!(covered > 96 * 108, "the floor fills about half of each eye");
                // An open plane occludes nothing: every estimator's expectation is exactly
                // 1 (SSAO/SSDO samples sit above the plane by the normal bias; HBAO's
                // horizons stay at the tangent plane, below its angle bias). 0.98 leaves
                // room for f16 storage and depth reconstruction at grazing angles only.
                assert!(
                    a >= 0.98,
                    "{} (N={samples}, r={radius} m) {}: AO {a} < 0.98 on the open plane at eye {l} pixel ({x}, {y}), world {:?}",
                    technique.name(),
                    r.name(),
                    f.world(l, x, y)
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// 90° crease

const CREASE_SIZE: (u32, u32) = (160, 180);
const CREASE_RADIUS: f64 = 1.0;
const CREASE_SAMPLES: u32 = 64;
/// Bins of distance to the crease line (metres).
const CREASE_BIN: f64 = 0.1;
const CREASE_BINS: usize = 13;

/// Eye on the crease's bisector plane, 2.5 m from the crease line and looking at it, so
/// floor and wall are mirror images, both seen at 45°, and a floor strip of 1 m in
/// front of the wall spans about 28 rows at 180 rows.
fn crease_head() -> HeadPose {
    let target = DVec3::new(0.0, 0.0, CREASE_WALL_Z);
    let d = 2.5 / 2f64.sqrt();
    HeadPose::look_at(target + DVec3::new(0.0, d, d), target).unwrap()
}

/// 1 = floor, 2 = wall, 0 = neither (sky, the crease line itself, anything else).
fn crease_class(p: Option<DVec3>) -> u8 {
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
fn crease_distance(p: DVec3, class: u8) -> f64 {
    if class == 1 {
        p.z - CREASE_WALL_Z
    } else {
        p.y
    }
}

/// Per-bin means of one crease measurement.
#[derive(Debug, Default, Clone)]
struct CreaseBin {
    lo: f64,
    pixels: usize,
    raw: f64,
    blurred: f64,
    /// The estimator's expectation at each pixel, simulated on the CPU (SSAO and SSDO:
    /// depth tests against the crease; HBAO: its march), and blurred like the AO.
    expected_raw: f64,
    expected_blurred: f64,
    /// SSAO and SSDO: the closed forms
    /// `analytic::ss{a,d}o_crease_expectation_with_depth_scale`.
    closed_raw: f64,
    /// Reference visibility (hits within r) and with HBAO's linear falloff, per pixel and
    /// blurred like the AO.
    reference: f64,
    falloff_raw: f64,
    falloff_blurred: f64,
    /// Pixels whose whole 11×11 blur window lies on modelled pixels.
    blurred_pixels: usize,
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
fn measure_crease(gpu: &Arc<Gpu>, technique: Technique) -> Vec<CreaseBin> {
    let scene = Scene::load("builtin:crease").unwrap();
    let (w, h) = CREASE_SIZE;
    let mut settings = settings(w, h, ao(technique, CREASE_SAMPLES, CREASE_RADIUS as f32));
    settings.ao.noise = Noise::Halton;
    // The blur is simulated below as a same-surface box of the bilateral's radius.
    settings.ao.denoise = Denoise::Bilateral;
    let f = render(gpu, &scene, &settings, &crease_head(), &[AO_RAW, AO_BLURRED]);
    let r = CREASE_RADIUS;
    // SSAO and SSDO by their depth-test simulation, HBAO by its march (None).
    let estimator = match technique {
        Technique::Ssao => Some((Estimator::Ssao, hemisphere_kernel(CREASE_SAMPLES, HemisphereDensity::Cosine))),
        Technique::Ssdo | Technique::SsdoBounce => {
            Some((Estimator::Ssdo, hemisphere_kernel(CREASE_SAMPLES, HemisphereDensity::Uniform)))
        }
        Technique::Hbao | Technique::Gtao => None,
        other => panic!("no crease expectation for {}", other.name()),
    };
    let (directions, steps) = hbao_directions_steps(CREASE_SAMPLES);
    let hbao = HbaoParams { radius: r, bias: 0.02, directions, steps, rotations: 28 };
    let rects = analytic::crease_rects();
    let hit = |o: DVec3, d: DVec3| analytic::first_hit(&rects, o, d);
    let blur = settings.ao.blur_radius as i32;
    let mut bins: Vec<CreaseBin> =
        (0..CREASE_BINS).map(|i| CreaseBin { lo: i as f64 * CREASE_BIN, ..Default::default() }).collect();
    for layer in 0..2 {
        let n = (w * h) as usize;
        let class: Vec<u8> = f.world[layer].iter().map(|p| crease_class(*p)).collect();
        let mut modelled = vec![false; n];
        let mut expected = vec![1.0; n];
        let mut closed = vec![1.0; n];
        let mut falloff = vec![1.0; n];
        let view = DepthView { eye: f.eyes.eyes[layer].pose.position, forward: f.forward(layer) };
        for i in 0..n {
            let (c, Some(p)) = (class[i], f.world[layer][i]) else { continue };
            if c == 0 {
                continue;
            }
            let d = crease_distance(p, c);
            // The part of the other surface within r of P is a half disc of radius
            // √(r² − d²) around the foot of P on the crease line; it (with 0.2 m to
            // spare for the wall points that hide samples just behind the wall) must be
            // on screen. Checked along its rim every 15°.
            let rim = (r * r - d * d).max(0.0).sqrt() + 0.2;
            let on_screen = (0..=12).all(|k| {
                let (sin, cos) = (k as f64 * std::f64::consts::PI / 12.0).sin_cos();
                let q = if c == 1 {
                    DVec3::new(p.x + rim * cos, rim * sin, CREASE_WALL_Z)
                } else {
                    DVec3::new(p.x + rim * cos, 0.0, CREASE_WALL_Z + rim * sin)
                };
                f.on_screen(layer, q, 0.005)
            });
            modelled[i] = p.x.abs() <= 3.0 && (d >= r || on_screen);
            falloff[i] = analytic::crease_visibility_falloff(d, r);
            if d < r * 1.05 {
                let normal = if c == 1 { DVec3::Y } else { DVec3::Z };
                expected[i] = match &estimator {
                    Some((est, kernel)) => {
                        // Depth per metre behind the other surface along the ray to P.
                        let e = (p - view.eye).normalize();
                        let other_normal = if c == 1 { DVec3::Z } else { DVec3::Y };
                        let k = e.dot(view.forward) / e.dot(other_normal).abs();
                        closed[i] = match est {
                            Estimator::Ssao => {
                                analytic::ssao_crease_expectation_with_depth_scale(d, r, 0.02, kernel, k)
                            }
                            Estimator::Ssdo => {
                                analytic::ssdo_crease_expectation_with_depth_scale(d, r, 0.02, kernel, k)
                            }
                        };
                        let params = EstimatorParams {
                            estimator: *est,
                            radius: r,
                            bias: 0.02,
                            range_check: true,
                            rotations: 24,
                        };
                        analytic::screen_space_expectation(&params, p, normal, kernel, &view, hit)
                    }
                    // GTAO estimates the reference itself (no simulation of its own).
                    None if technique == Technique::Gtao => analytic::crease_visibility(d, r),
                    None => {
                        let pixel = (i as u32 % w, i as u32 / w);
                        analytic::hbao_expectation(&hbao, &f.eyes.eyes[layer], (w, h), pixel, normal, hit)
                    }
                };
            }
        }
        let expected_blurred = same_surface_blur(&expected, &class, w, h, blur);
        let falloff_blurred = same_surface_blur(&falloff, &class, w, h, blur);
        for y in 0..h {
            for x in 0..w {
                let i = f.index(x, y);
                if !modelled[i] {
                    continue;
                }
                let near_other = |radius: i32, want: &dyn Fn(usize) -> bool| {
                    (-radius..=radius).all(|dy| {
                        (-radius..=radius).all(|dx| {
                            let (qx, qy) = (x as i32 + dx, y as i32 + dy);
                            qx < 0
                                || qy < 0
                                || qx >= w as i32
                                || qy >= h as i32
                                || want((qy as u32 * w + qx as u32) as usize)
                        })
                    })
                };
                // More than 3 px from anything that is not this surface.
                if !near_other(3, &|q| class[q] == class[i]) {
                    continue;
                }
                let d = crease_distance(f.world[layer][i].unwrap(), class[i]);
                let bin = (d / CREASE_BIN) as usize;
                if bin >= CREASE_BINS {
                    continue;
                }
                let b = &mut bins[bin];
                b.pixels += 1;
                b.raw += f.ao(AO_RAW, layer, x, y);
                b.expected_raw += expected[i];
                b.closed_raw += closed[i];
                b.reference += analytic::crease_visibility(d, r);
                b.falloff_raw += falloff[i];
                let window_ok = near_other(blur, &|q| class[q] != class[i] || modelled[q]);
                if window_ok {
                    b.blurred_pixels += 1;
                    b.blurred += f.ao(AO_BLURRED, layer, x, y);
                    b.expected_blurred += expected_blurred[i];
                    b.falloff_blurred += falloff_blurred[i];
                }
            }
        }
    }
    for b in &mut bins {
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
    eprintln!(
        "crease {}: distance | px raw expected closed-form | px blurred expected | reference, falloff reference raw blurred",
        technique.name()
    );
    for b in &bins {
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
    bins
}

/// The crease darkens towards its edge: blurred AO per bin never rises by more than the
/// noise (0.01) towards the wall, and the bin nearest the wall is clearly darker than
/// the open floor beyond r.
fn assert_falls_towards_the_edge(name: &str, bins: &[CreaseBin]) {
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
fn assert_bins(
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
const EXPECTATION_TOLERANCE: f64 = 0.01;

#[test]
fn crease_ssao_matches_its_expected_value() {
    let (gpu, _guard) = common::gpu();
    let bins = measure_crease(&gpu, Technique::Ssao);
    assert_falls_towards_the_edge("ssao", &bins);
    assert_bins("ssao", "raw vs simulated", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.expected_raw));
    // The closed form takes the depth tolerance at the depth scale of the ray through P
    // instead of each sample's ray: no difference at this size (checked against the
    // simulation in analytic's unit tests to 0.005).
    assert_bins("ssao", "raw vs closed form", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.closed_raw));
    // Blur is linear, so the blurred AO is compared with the same blur applied to the
    // expectation image.
    assert_bins("ssao", "blurred vs simulated", &bins, EXPECTATION_TOLERANCE, |b| {
        (b.blurred_pixels, b.blurred, b.expected_blurred)
    });
    // SSAO's samples crowd towards P (lengths r(0.1 + 0.9t²)), so it is lighter than the
    // reference within r (hits within r); it must not be darker.
    for b in bins.iter().filter(|b| b.pixels >= 100) {
        assert!(b.raw >= b.reference - EXPECTATION_TOLERANCE, "ssao darker than the reference at {:.1} m: {b:?}", b.lo);
    }
}

#[test]
fn crease_hbao_matches_its_expected_value_and_approximates_the_reference() {
    let (gpu, _guard) = common::gpu();
    let bins = measure_crease(&gpu, Technique::Hbao);
    assert_falls_towards_the_edge("hbao", &bins);
    assert_bins("hbao", "raw vs simulated", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.expected_raw));
    assert_bins("hbao", "blurred vs simulated", &bins, EXPECTATION_TOLERANCE, |b| {
        (b.blurred_pixels, b.blurred, b.expected_blurred)
    });
    // Against the hard cut-off reference, the quantity HBAO's cosine-weighted (sin²h)
    // horizon integral tends to on a thick wall. The tolerance bounds HBAO's own bias on
    // this view (its expectation, `hbao_expectation`, asserted first): the slice
    // geometry (a screen line through P contains the view ray, so it meets the wall along
    // a tilted line whose horizon is lower than a vertical slice's), the horizon rising
    // only at 4 × 6 taps, and the angle bias sin h₀ = 5 · bias. These biases lighten, so
    // HBAO must not be darker than the reference beyond the noise.
    assert_bins("hbao", "expectation vs reference", &bins, HBAO_BIAS_TOLERANCE, |b| {
        (b.blurred_pixels, b.expected_blurred, b.reference)
    });
    assert_bins("hbao", "blurred vs reference", &bins, HBAO_BIAS_TOLERANCE + 0.01, |b| {
        (b.blurred_pixels, b.blurred, b.reference)
    });
    for b in bins.iter().filter(|b| b.blurred_pixels >= 100) {
        assert!(
            b.blurred >= b.reference - EXPECTATION_TOLERANCE,
            "hbao darker than the reference at {:.1} m: {b:?}",
            b.lo
        );
    }
}

#[test]
fn crease_gtao_matches_the_reference() {
    let (gpu, _guard) = common::gpu();
    let bins = measure_crease(&gpu, Technique::Gtao);
    assert_falls_towards_the_edge("gtao", &bins);
    // GTAO estimates the hard cut-off visibility itself: per bin within GTAO_TOLERANCE
    // of the closed form, raw and denoised, and never darker beyond the noise.
    assert_bins("gtao", "raw vs reference", &bins, GTAO_TOLERANCE, |b| (b.pixels, b.raw, b.reference));
    assert_bins("gtao", "blurred vs reference", &bins, GTAO_TOLERANCE, |b| (b.blurred_pixels, b.blurred, b.reference));
}

/// GTAO's bias and noise per bin on the crease view (4 × 6 samples per pixel): the
/// slices' tilt against the wall, as for HBAO, but without HBAO's angle bias.
const GTAO_TOLERANCE: f64 = 0.05;

/// HBAO's expected value above the hard cut-off reference on the crease view, per bin:
/// measured up to 0.156 (at 0.1–0.2 m from the crease line; there HBAO reads about what
/// the linear-falloff reference does, 0.76 against 0.61), so HBAO stays biased light on
/// this view even without its falloff. GTAO, on the same view, is within 0.05.
const HBAO_BIAS_TOLERANCE: f64 = 0.17;

#[test]
fn crease_ssdo_matches_its_expected_value_and_the_falloff_reference() {
    let (gpu, _guard) = common::gpu();
    let bins = measure_crease(&gpu, Technique::Ssdo);
    assert_falls_towards_the_edge("ssdo", &bins);
    assert_bins("ssdo", "raw vs simulated", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.expected_raw));
    assert_bins("ssdo", "raw vs closed form", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.closed_raw));
    assert_bins("ssdo", "blurred vs simulated", &bins, EXPECTATION_TOLERANCE, |b| {
        (b.blurred_pixels, b.blurred, b.expected_blurred)
    });
    // SSDO's λ uniform in [0, r] makes its continuous expectation exactly the falloff
    // reference (`crease_visibility_falloff` docs). Tolerance 0.06 = 0.05 + 0.01: the
    // 64-sample kernel's own deviation from the continuum plus the depth bias (samples
    // must be 0.02 r behind the wall, the occluder 0.02 r above the floor) is at most
    // 0.045 at x ≥ 0.1 m (`ssdo_crease_expectation` against `crease_visibility_falloff`;
    // 0.03 per bin here), asserted first, plus the noise allowance above.
    assert_bins("ssdo", "expectation vs falloff reference", &bins, 0.05, |b| {
        (b.blurred_pixels, b.expected_blurred, b.falloff_blurred)
    });
    assert_bins("ssdo", "blurred vs falloff reference", &bins, 0.06, |b| {
        (b.blurred_pixels, b.blurred, b.falloff_blurred)
    });
}

// ---------------------------------------------------------------------------------------
// SSDO with a single light

/// A lat-long environment that is black except a cap of `radius_deg` around `towards`.
fn single_light_environment(towards: Vec3, radius_deg: f32, radiance: f32) -> Environment {
    let (w, h) = (128u32, 64u32);
    let cos_radius = radius_deg.to_radians().cos();
    let towards = towards.normalize();
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let dir = environment::direction((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            if dir.dot(towards) >= cos_radius {
                [radiance; 3]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    Environment::from_texels(w, h, texels, 1.0).unwrap()
}

#[test]
fn ssdo_shadows_the_side_away_from_a_single_light_where_ssao_cannot() {
    let (gpu, _guard) = common::gpu();
    // The sphere on the floor, lit only by a bright patch of sky up and to the right
    // (+X, 45° above the horizon, 30° across); no sun, no other light.
    let mut scene = Scene::load("builtin:sphere").unwrap();
    scene.lights.clear();
    scene.environment = Some(single_light_environment(Vec3::new(1.0, 1.0, 0.0), 30.0, 8.0));
    // From above and in front, so the floor on both sides of the sphere is in view.
    let head = HeadPose::look_at(DVec3::new(0.0, 3.2, 3.6), DVec3::new(0.0, 0.3, 0.0)).unwrap();
    let luminance_of = |technique: Technique| {
        let s = settings(160, 180, ao(technique, 64, 1.5));
        let f = render(&gpu, &scene, &s, &head, &[HDR]);
        // Floor beside the sphere, on the side away from the light (−X) and on the lit
        // side (+X), mirror images of each other for this eye.
        let (mut away, mut lit) = (Vec::new(), Vec::new());
        for (l, x, y) in f.pixels() {
            let Some(p) = f.world(l, x, y) else { continue };
            // Inside the sphere's shadow on the −X side, (X + 1)²/2 + Z² < 1 for a light at
            // 45° above +X; the +X side mirrors it.
            if p.y.abs() > 1e-3 || p.z.abs() > 0.5 || !(1.1..=1.6).contains(&p.x.abs()) {
                continue;
            }
            let lum = analytic::luminance(f.rgb(HDR, l, x, y));
            if p.x < 0.0 {
                away.push(lum)
            } else {
                lit.push(lum)
            }
        }
        assert!(
            away.len() > 100 && lit.len() > 100,
            "floor beside the sphere is visible: {} {}",
            away.len(),
            lit.len()
        );
        (mean(away), mean(lit))
    };
    let (ssao_away, ssao_lit) = luminance_of(Technique::Ssao);
    let (ssdo_away, ssdo_lit) = luminance_of(Technique::Ssdo);
    let (ssao_ratio, ssdo_ratio) = (ssao_away / ssao_lit, ssdo_away / ssdo_lit);
    eprintln!(
        "single light: floor luminance away from / towards the light: ssao {ssao_away:.4} / {ssao_lit:.4} \
         (ratio {ssao_ratio:.3}), ssdo {ssdo_away:.4} / {ssdo_lit:.4} (ratio {ssdo_ratio:.3})"
    );
    // SSAO scales the unshadowed ambient irradiance by a direction-blind AO, so the two
    // sides, mirror images of each other for this eye, come out alike (within 5 %: the
    // eyes sit ±32 mm off the mirror plane and the rotation noise differs).
    assert!((ssao_ratio - 1.0).abs() < 0.05, "ssao differs between the sides: {ssao_away} vs {ssao_lit}");
    // SSDO blocks the light's directions where the sphere stands between floor and light:
    // the side away from the light is darker than the lit side by clearly more than
    // under SSAO (comparing each technique with itself cancels any overall difference
    // in how the two gather the unoccluded ambient) ...
    assert!(
        ssdo_ratio < ssao_ratio - 0.08,
        "ssdo does not shadow the side away from the light: ratio {ssdo_ratio:.3} vs ssao {ssao_ratio:.3}"
    );
    // ... and that side is darker under SSDO than under SSAO.
    assert!(ssdo_away < ssao_away, "the side away from the light is not darker under ssdo: {ssdo_away} vs {ssao_away}");
}

#[test]
fn ssdo_on_an_open_plane_gathers_the_unoccluded_ambient() {
    let (gpu, _guard) = common::gpu();
    // On an open plane nothing is occluded, so SSDO's gathered irradiance must be the
    // ambient irradiance the composite uses without occlusion (technique none). Lights
    // are removed so the image is ambient only: albedo / π × irradiance.
    let mut scene = Scene::load("builtin:plane").unwrap();
    scene.lights.clear();
    let head = scene.head.pose_at(0.0);
    let floor_luminance = |scene: &Scene, technique: Technique, samples: u32| {
        let f = render(&gpu, scene, &settings(96, 108, ao(technique, samples, 0.5)), &head, &[HDR]);
        mean(
            f.pixels()
                .filter(|&(l, x, y)| f.world(l, x, y).is_some())
                .map(|(l, x, y)| analytic::luminance(f.rgb(HDR, l, x, y))),
        )
    };
    let mut failures = Vec::new();
    // A constant environment L: the irradiance is π L for any normal, which every
    // correctly normalised quadrature reproduces exactly whatever its directions; only
    // f16 storage and the SH projection's texel sums (< 0.5 %) remain. Tolerance 2 %.
    let texels = vec![[1.0f32; 3]; 64 * 32];
    scene.environment = Some(Environment::from_texels(64, 32, texels, 1.0).unwrap());
    let unoccluded = floor_luminance(&scene, Technique::None, 24);
    for samples in [12, 24, 36, 64] {
        let ssdo = floor_luminance(&scene, Technique::Ssdo, samples);
        let ratio = ssdo / unoccluded;
        eprintln!("constant sky, N = {samples}: ssdo / unoccluded floor luminance = {ratio:.4}");
        if (ratio - 1.0).abs() > 0.02 {
            failures.push(format!("constant environment, N = {samples}: ssdo / unoccluded = {ratio:.3}"));
        }
    }
    // The single bright patch of the shadow test: the irradiance of a floor that sees
    // all of it. SSDO's 64 rotated directions integrate a band-limited radiance to about
    // 1 % once averaged over the floor's rotations; tolerance 5 %.
    scene.environment = Some(single_light_environment(Vec3::new(1.0, 1.0, 0.0), 30.0, 8.0));
    let unoccluded = floor_luminance(&scene, Technique::None, 64);
    let ssdo = floor_luminance(&scene, Technique::Ssdo, 64);
    let ratio = ssdo / unoccluded;
    eprintln!("single light, N = 64: ssdo / unoccluded floor luminance = {ratio:.4}");
    if (ratio - 1.0).abs() > 0.05 {
        failures.push(format!("single bright patch, N = 64: ssdo / unoccluded = {ratio:.3}"));
    }
    assert!(failures.is_empty(), "ssdo does not reproduce the unoccluded ambient on an open plane: {failures:#?}");
}

// ---------------------------------------------------------------------------------------
// Bounce

#[test]
fn red_wall_bleeds_red_only_with_the_bounce() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    // Looking down at the foot of the red (−X) wall, from the middle of the room.
    let head = HeadPose::look_at(DVec3::new(0.6, 1.6, -0.8), DVec3::new(ROOM_MIN.x + 0.3, 0.0, -2.6)).unwrap();
    let run_form = |technique: Technique, bounce: f32, form: BounceForm| {
        let mut a = ao(technique, 64, 1.0);
        a.bounce = bounce;
        a.bounce_form = form;
        render(&gpu, &scene, &settings(128, 144, a), &head, &[HDR, AO_RAW])
    };
    let run = |technique: Technique, bounce: f32| run_form(technique, bounce, BounceForm::Direction);
    let ssdo = run(Technique::Ssdo, 1.0);
    let bounce = run(Technique::SsdoBounce, 1.0);
    let bounce_off = run(Technique::SsdoBounce, 0.0);
    let patch = run_form(Technique::SsdoBounce, 1.0, BounceForm::Patch);
    // Floor within 0.45 m of the red wall, away from the other walls.
    let near_red_wall =
        |p: DVec3| p.y.abs() < 1e-3 && p.x < ROOM_MIN.x + 0.45 && p.z < ROOM_MAX.z - 1.0 && p.z > ROOM_MIN.z + 0.5;
    let measure = |f: &Frame| {
        let (mut hdr, mut raw, mut n) = ([0.0f64; 3], [0.0f64; 3], 0);
        for (l, x, y) in f.pixels() {
            if !f.world(l, x, y).is_some_and(near_red_wall) {
                continue;
            }
            n += 1;
            let (c, a) = (f.rgb(HDR, l, x, y), f.rgb(AO_RAW, l, x, y));
            for i in 0..3 {
                hdr[i] += c[i] as f64;
                raw[i] += a[i] as f64;
            }
        }
        assert!(n > 200, "floor by the red wall is visible ({n} px)");
        (hdr.map(|v| v / n as f64), raw.map(|v| v / n as f64))
    };
    let (ssdo_hdr, ssdo_raw) = measure(&ssdo);
    let (bounce_hdr, bounce_raw) = measure(&bounce);
    let (off_hdr, off_raw) = measure(&bounce_off);
    let (_, patch_raw) = measure(&patch);
    let ratio = |c: [f64; 3]| c[0] / c[1];
    let gained: Vec<f64> = (0..3).map(|i| bounce_raw[i] - ssdo_raw[i]).collect();
    // The patch form of Ritschel et al. 2009 carries the same red, less of it
    // (tests/reference_error.rs compares both with the reference).
    let patch_gained: Vec<f64> = (0..3).map(|i| patch_raw[i] - ssdo_raw[i]).collect();
    eprintln!("bounce: patch form gained {patch_gained:.3?}");
    assert!(
        patch_gained[0] > 0.005 && patch_gained[0] > 3.0 * patch_gained[1].max(patch_gained[2]).max(0.0),
        "the patch-form bounce is not red: {patch_gained:?}"
    );
    eprintln!(
        "bounce: floor by the red wall, hdr r/g: ssdo {:.3}, ssdo-bounce {:.3}, bounce 0 {:.3}; \
         ao-raw rgb: ssdo {ssdo_raw:.3?}, ssdo-bounce {bounce_raw:.3?} (gained {gained:.3?}), bounce 0 {off_raw:.3?}",
        ratio(ssdo_hdr),
        ratio(bounce_hdr),
        ratio(off_hdr)
    );
    // The room's ambient sky is bluish, so its floor is not grey to begin with; what the
    // bounce adds is measured against plain SSDO, which gathers the same sky through the
    // same samples (same kernel and rotations), so the difference of the gathered
    // irradiance (AoRaw rgb) is the bounce alone. It carries the red wall's colour
    // (albedo 0.75, 0.1, 0.1 under a white light): red at least 3× green and blue, and
    // enough of it to see: a 3 % rise of the floor's r/g in the final image.
    assert!(
        gained[0] > 0.01 && gained[0] > 3.0 * gained[1].max(gained[2]).max(0.0),
        "the bounce is not red: {gained:?}"
    );
    assert!(ratio(bounce_hdr) > 1.03 * ratio(ssdo_hdr), "no red bleeding: r/g {bounce_hdr:?} vs {ssdo_hdr:?}");
    // Bounce strength 0 is SSDO exactly (the same pass runs).
    for r in [HDR, AO_RAW] {
        let worst = ssdo.outputs[&r]
            .iter()
            .flatten()
            .zip(bounce_off.outputs[&r].iter().flatten())
            .map(|(x, y)| (x - y).abs())
            .fold(0f32, f32::max);
        assert!(worst <= 1e-3, "ssdo-bounce with bounce 0 differs from ssdo in {} by {worst}", r.name());
    }
    // With the bounce, the occluder probe reads distances packed with the direct light
    // instead of the depth buffer (one fetch for both): it must block exactly the same
    // directions, so the visibility (AoRaw alpha) is SSDO's to the f16 target's precision.
    let alpha =
        |f: &Frame| f.outputs[&AO_RAW].iter().flat_map(|l| l.iter().skip(3).step_by(4).copied()).collect::<Vec<f32>>();
    let worst = alpha(&ssdo).iter().zip(alpha(&bounce)).map(|(x, y)| (x - y).abs()).fold(0f32, f32::max);
    assert!(worst <= 1e-3, "the bounce changed which directions are blocked: visibility differs by {worst}");
}

// ---------------------------------------------------------------------------------------
// Bilateral blur

#[test]
fn blur_keeps_a_depth_edge() {
    let (gpu, _guard) = common::gpu();
    // A wall 4 m ahead, and 2 m ahead of it a panel covering the left half of the view
    // (its right edge at x = 0), both facing the eye: a vertical depth step down the
    // middle of each image. Without the range check, SSAO darkens the far wall beside
    // the step (samples in front of the wall that project onto the much closer panel
    // count as occluded, the classic halo): strongly occluded on the far side of the
    // edge, unoccluded (AO = 1) on the panel itself.
    let scene = common::bare_scene(vec![
        common::square("wall", DVec3::new(0.0, 0.0, -4.0), 12.0, 0),
        common::square("panel", DVec3::new(-3.0, 0.0, -2.0), 6.0, 0),
    ]);
    let mut a = ao(Technique::Ssao, 32, 1.0);
    a.range_check = false;
    let s = settings(128, 144, a);
    let f = render(&gpu, &scene, &s, &HeadPose::IDENTITY, &[AO_RAW, AO_BLURRED]);
    let (w, h) = (f.width, f.height);
    let blur = s.ao.blur_radius as i32;
    let (mut near, mut far) =
        ((Vec::new(), Vec::new(), Vec::new(), Vec::new()), (Vec::new(), Vec::new(), Vec::new(), Vec::new()));
    for layer in 0..2 {
        // 1 = panel (about 2 m away), 2 = wall (about 4 m).
        let class: Vec<u8> = f.world[layer].iter().map(|p| p.map_or(0, |p| if p.z > -3.0 { 1 } else { 2 })).collect();
        let raw: Vec<f64> = (0..w * h).map(|i| f.outputs[&AO_RAW][layer][4 * i as usize + 3] as f64).collect();
        let same = same_surface_blur(&raw, &class, w, h, blur);
        // A geometry-unaware blur of the same raw AO, to show the test would catch one.
        let naive = same_surface_blur(&raw, &vec![1; raw.len()], w, h, blur);
        for y in 0..h as i32 {
            for x in 0..w as i32 {
                let i = (y as u32 * w + x as u32) as usize;
                let c = class[i];
                // Pixels 1–2 px from the silhouette (Chebyshev), far from the image edge.
                if c == 0 || x < 16 || y < 16 || x >= w as i32 - 16 || y >= h as i32 - 16 {
                    continue;
                }
                let dist = (1..=3)
                    .find(|&k| {
                        (-k..=k)
                            .any(|dy| (-k..=k).any(|dx| class[((y + dy) as u32 * w + (x + dx) as u32) as usize] != c))
                    })
                    .unwrap_or(99);
                if !(1..=2).contains(&dist) {
                    continue;
                }
                let blurred = f.ao(AO_BLURRED, layer, x as u32, y as u32);
                let side = if c == 1 { &mut near } else { &mut far };
                side.0.push(raw[i]);
                side.1.push(blurred);
                side.2.push(same[i]);
                side.3.push(naive[i]);
            }
        }
    }
    let m = |v: &Vec<f64>| mean(v.iter().copied());
    let (near_raw, near_blur, near_same, near_naive) = (m(&near.0), m(&near.1), m(&near.2), m(&near.3));
    let (far_raw, far_blur, far_same, far_naive) = (m(&far.0), m(&far.1), m(&far.2), m(&far.3));
    eprintln!(
        "blur edge ({} near px, {} far px): near raw {near_raw:.3} blurred {near_blur:.3} same-surface {near_same:.3} naive {near_naive:.3}; \
         far raw {far_raw:.3} blurred {far_blur:.3} same-surface {far_same:.3} naive {far_naive:.3}",
        near.0.len(),
        far.0.len()
    );
    assert!(near.0.len() > 200 && far.0.len() > 200, "the silhouette is visible");
    // The case has contrast: unoccluded panel, strongly occluded wall beside it.
    assert!(near_raw > 0.97 && near_raw - far_raw > 0.3, "no contrast across the edge: {near_raw} vs {far_raw}");
    // A blur that ignored the edge would pull the panel down and the wall up; this
    // shows by how much (the test's power), measured on the same raw AO.
    assert!(near_naive < near_same - 0.05, "the case cannot tell a leaking blur: naive {near_naive}");
    // The blurred panel stays at its own surface's average (≈ 1), within 0.02.
    assert!(near_blur >= near_same - 0.02, "blur pulls the panel towards the wall: {near_blur} vs {near_same}");
    // The blurred wall rises no more than averaging over the wall itself allows (the
    // halo fades away from the edge, so even a perfect blur lifts it a little).
    assert!(far_blur <= far_same + 0.03, "blur pulls the wall towards the panel: {far_blur} vs {far_same}");
    // Hence the jump across the silhouette survives: a blur that keeps to each surface
    // leaves about 2/3 of it here (the halo fades away from the edge, so averaging over
    // the wall alone lifts the wall side), the naive blur about 1/7.
    assert!(
        near_blur - far_blur >= 0.5 * (near_raw - far_raw),
        "the edge is blurred away: jump {:.3} blurred vs {:.3} raw",
        near_blur - far_blur,
        near_raw - far_raw
    );
}

// ---------------------------------------------------------------------------------------
// Half resolution

#[test]
fn half_resolution_stays_close_to_full_resolution() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in [Technique::Ssao, Technique::Hbao, Technique::Ssdo] {
        let full = settings(128, 144, ao(technique, 24, 1.0));
        let mut half = full.clone();
        half.ao.half_res = true;
        let f = render(&gpu, &scene, &full, &head, &[AO_BLURRED]);
        let g = render(&gpu, &scene, &half, &head, &[AO_FULL]);
        let pairs: Vec<(f64, f64)> = f
            .pixels()
            .filter(|&(l, x, y)| f.world(l, x, y).is_some())
            .map(|(l, x, y)| (f.ao(AO_BLURRED, l, x, y), g.ao(AO_FULL, l, x, y)))
            .collect();
        let diffs: Vec<f64> = pairs.iter().map(|(a, b)| (a - b).abs()).collect();
        let mad = mean(diffs.iter().copied());
        let mad_occluded = mean(pairs.iter().filter(|(a, b)| a.min(*b) < 0.95).map(|(a, b)| (a - b).abs()));
        let signed = mean(pairs.iter().map(|(a, b)| a - b));
        let bad = diffs.iter().filter(|d| **d > 0.2).count() as f64 / diffs.len() as f64;
        eprintln!(
            "half res {}: mean |full − half| {mad:.4} (occluded px {mad_occluded:.4}), mean full − half {signed:+.4}, \
             {:.2} % of pixels off by > 0.2",
            technique.name(),
            bad * 100.0
        );
        // Both estimate the same per-pixel expectation (same world-space radius and
        // estimator). They differ by (a) the rotation noise left after the blur, different
        // in the two because different pixels are sampled (about ±0.01–0.02 per pixel at
        // 24 taps; the crease bins show the blurred AO within 0.004 of its expectation
        // on average), and (b) interpolation: half resolution knows AO every second
        // pixel, and where AO changes fast (contact shadows at the room's corners and
        // box: 0.3 over about 10 px at this size) the 3×3 joint bilateral upsampling
        // misses curvature and thin features by a few hundredths. Over every non-sky
        // pixel (most of them unoccluded, where both are 1) the mean |difference| must
        // stay below 0.03; over occluded pixels (AO < 0.95 in either) below 0.06, twice
        // what (a) and (b) give. A broken upsampler (wrong neighbour, a pixel offset,
        // weights across depth edges, a cleared last row or column) makes bands along
        // every edge: many pixels off by more than 0.2 (allowed: 0.5 %).
        assert!(mad < 0.03, "{}: mean |full − half| = {mad}", technique.name());
        assert!(mad_occluded < 0.06, "{}: mean |full − half| on occluded pixels = {mad_occluded}", technique.name());
        assert!(signed.abs() < 0.01, "{}: half resolution is biased ({signed:+.4})", technique.name());
        assert!(bad < 0.005, "{}: {:.2} % of pixels differ by > 0.2", technique.name(), bad * 100.0);
    }
}

#[test]
fn odd_sizes_work_at_half_resolution() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in AO_TECHNIQUES {
        let mut a = ao(technique, 12, 0.5);
        a.half_res = true;
        let s = settings(97, 109, a);
        let outputs = [AO_RAW, AO_BLURRED, AO_FULL, HDR];
        let f = render(&gpu, &scene, &s, &head, &outputs);
        for (r, (w, h)) in [(AO_RAW, (49, 55)), (AO_BLURRED, (49, 55)), (AO_FULL, (97, 109))] {
            for layer in &f.outputs[&r] {
                assert_eq!(layer.len(), w * h * 4, "{} {}: not {w}×{h}", technique.name(), r.name());
                assert!(layer.iter().all(|v| v.is_finite()), "{} {}: not finite", technique.name(), r.name());
                assert!(layer.chunks(4).all(|p| (0.0..=1.0).contains(&p[3])), "{}: AO out of range", r.name());
            }
        }
        // The last row and column of the full-res AO carry values, not a cleared edge.
        let last_column_lit = (0..109).filter(|&y| f.world(0, 96, y).is_some()).all(|y| f.ao(AO_FULL, 0, 96, y) > 0.0);
        assert!(last_column_lit, "{}: last column of ao-full is empty", technique.name());
    }
}

// ---------------------------------------------------------------------------------------
// Stereo consistency

#[test]
fn both_eyes_see_the_same_occlusion_on_the_same_surface() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in AO_TECHNIQUES {
        let s = settings(128, 144, ao(technique, 32, 1.0));
        let f = render(&gpu, &scene, &s, &head, &[AO_BLURRED]);
        let (mut diffs, mut signed, mut occluded, mut unmatched) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let margin = 16;
        for y in margin..f.height - margin {
            for x in margin..f.width - margin {
                let Some(p) = f.world(0, x, y) else { continue };
                let Some((rx, ry)) = f.pixel_of(1, p) else { continue };
                if rx < margin || ry < margin || rx >= f.width - margin || ry >= f.height - margin {
                    continue;
                }
                // Same surface: the right eye sees a point within 1 % of the distance.
                let Some(q) = f.world(1, rx, ry) else { continue };
                if (q - p).length() > 0.01 * (p - f.eyes.eyes[0].pose.position).length() {
                    continue;
                }
                let (left, right) = (f.ao(AO_BLURRED, 0, x, y), f.ao(AO_BLURRED, 1, rx, ry));
                let d = left - right;
                diffs.push(d.abs());
                signed.push(d);
                if left.min(right) < 0.95 {
                    occluded.push(d.abs());
                    // The same pixel of the right eye (no reprojection): what a test that
                    // ignored parallax would compare.
                    unmatched.push((left - f.ao(AO_BLURRED, 1, x, y)).abs());
                }
            }
        }
        let (mad, bias) = (mean(diffs.iter().copied()), mean(signed.iter().copied()));
        let (mad_occluded, mad_unmatched) = (mean(occluded.iter().copied()), mean(unmatched.iter().copied()));
        eprintln!(
            "stereo {}: {} matched px, mean |left − right| {mad:.4}, mean left − right {bias:+.4}; \
             {} occluded px (AO < 0.95): mean |left − right| {mad_occluded:.4}, same pixel without reprojection {mad_unmatched:.4}",
            technique.name(),
            diffs.len(),
            occluded.len()
        );
        assert!(diffs.len() > 5000, "too few matched pixels ({})", diffs.len());
        // The eyes see the same surface from 64 mm apart, so the per-pixel expectation
        // agrees up to the screen-space view dependence, which is small at this baseline
        // (the crease bins match an eye-specific expectation to 0.004 in both eyes). What
        // differs is the rotation noise: the same surface point falls on different pixels,
        // hence different rotations; after the 11×11 blur about ±0.01 per pixel remains.
        // Tolerances: mean |left − right| below 0.03 over occluded pixels (AO < 0.95 in
        // either eye: where there is something to disagree about) and below 0.015 over
        // all matched pixels, no systematic difference (|mean left − right| < 0.01).
        // Comparing the same pixel of both eyes without reprojection gives 0.08–0.10 on
        // occluded pixels, so an eye rendered with the other eye's view, a swapped layer
        // or a parallax error fails.
        assert!(mad_occluded < 0.03, "{}: eyes disagree where occluded: {mad_occluded}", technique.name());
        assert!(mad < 0.015, "{}: eyes disagree, mean |left − right| = {mad}", technique.name());
        assert!(bias.abs() < 0.01, "{}: one eye is systematically darker ({bias:+.4})", technique.name());
        assert!(occluded.len() > 1000 && mad_unmatched > 2.0 * 0.03, "the case cannot tell misaligned eyes");
    }
}

/// `builtin:flipped-normals`: a ball whose silhouette pixels carry normals turned into
/// the body. No technique, at full or half resolution, may read AO exactly 0 there, and
/// no shaded pixel may be pure black (before the fix, SSDO's half-resolution upsample
/// rejected every neighbour on such a pixel and fell back to a sky texel's irradiance 0).
#[test]
fn flipped_normals_give_no_zero_ao_and_no_black_pixel() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:flipped-normals").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in AO_TECHNIQUES {
        for half_res in [false, true] {
            let mut a = ao(technique, 12, scene.suggested_ao_radius());
            a.half_res = half_res;
            let s = settings(270, 300, a);
            // The final full-resolution AO.
            let final_ao = if half_res { AO_FULL } else { AO_BLURRED };
            let f = render(&gpu, &scene, &s, &head, &[final_ao, HDR]);
            let (mut surface, mut zero_ao, mut black) = (0, Vec::new(), Vec::new());
            for (l, x, y) in f.pixels() {
                if f.world(l, x, y).is_none() {
                    continue;
                }
                surface += 1;
                if f.ao(final_ao, l, x, y) <= 0.0 {
                    zero_ao.push((l, x, y));
                }
                if f.rgb(HDR, l, x, y).iter().all(|&c| c <= 0.0) {
                    black.push((l, x, y));
                }
            }
            let case = format!("{} {}", technique.name(), if half_res { "half" } else { "full" });
            eprintln!("flipped normals {case}: {surface} surface px, {} AO 0, {} black", zero_ao.len(), black.len());
            assert!(surface > 270 * 300 / 2, "{case}: the scene fills too little of the view");
            assert!(zero_ao.is_empty(), "{case}: AO exactly 0 at {:?}", &zero_ao[..zero_ao.len().min(5)]);
            assert!(black.is_empty(), "{case}: pure black at {:?}", &black[..black.len().min(5)]);
        }
    }
}

/// Every pixel of both eyes is computed once, whatever the split of a technique's
/// dispatch (GTAO runs the inner-border band and the rest as two dispatches): each
/// pixel with a surface has its geometry written, at odd sizes too.
#[test]
fn every_pixel_is_computed_in_both_eyes() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in AO_TECHNIQUES {
        let s = settings(97, 109, ao(technique, 12, 0.5));
        let f = render(&gpu, &scene, &s, &head, &[AO_GEOMETRY, AO_RAW]);
        let missing: Vec<_> = f
            .pixels()
            // The geometry's distance (.a) is > 0 wherever a pixel was computed; NaN or 0
            // means never written.
            .filter(|&(l, x, y)| {
                f.world(l, x, y).is_some()
                    && f.ao(AO_GEOMETRY, l, x, y).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            })
            .collect();
        assert!(
            missing.is_empty(),
            "{}: {} pixels never computed, first {:?}",
            technique.name(),
            missing.len(),
            missing.first()
        );
    }
}

/// The right eye takes the left eye's value wherever the left eye sees the same surface
/// point: GTAO's march, and at half resolution the AO-only techniques' upsample (SSDO's
/// denoise, its vertical pass). The share of stereo-inconsistent points
/// (the bench's measure: AO differing by more than 0.02 between the eyes,
/// `vrao::measure::stereo_consistency`) falls below ½ of what it is with independent eyes
/// (measured on the furnished room: GTAO full 1.8 → 0.9 %, half 3.3 → 0.5 %; SSAO half,
/// where the march does not reuse, 3.1 → 0.3 %).
#[test]
fn the_right_eye_reuses_the_left_eye_where_it_sees_the_same_point() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let head = scene.head.pose_at(0.0);
    for (technique, half_res) in [(Technique::Gtao, false), (Technique::Gtao, true), (Technique::Ssao, true)] {
        let mut shares = [0.0; 2];
        for (i, reuse) in [false, true].into_iter().enumerate() {
            let mut a = ao(technique, 24, 0.3);
            (a.stereo_reuse, a.half_res) = (reuse, half_res);
            let s = settings(540, 600, a);
            let final_ao = if half_res { AO_FULL } else { AO_BLURRED };
            let f = render(&gpu, &scene, &s, &head, &[final_ao, DEPTH]);
            let depth = &f.outputs[&DEPTH];
            let ao: Vec<Vec<f32>> = f.outputs[&final_ao].iter().map(|l| l.chunks(4).map(|p| p[3]).collect()).collect();
            let images = [0, 1].map(|l| EyeImages { depth: &depth[l], ao: &ao[l] });
            let c = stereo_consistency(&f.eyes.eyes, images, (f.width, f.height), f.eyes.near);
            eprintln!("{technique:?} stereo reuse {reuse}, half {half_res}: {c:?}");
            assert!(c.compared > 50_000, "too few points compared ({})", c.compared);
            shares[i] = c.inconsistent.unwrap();
        }
        let [independent, reused] = shares;
        assert!(
            reused < 0.5 * independent,
            "{technique:?}, half {half_res}: {:.1} % inconsistent with reuse, {:.1} % with independent eyes",
            100.0 * reused,
            100.0 * independent
        );
    }
}

/// At half resolution the right eye takes the left eye's upsampled AO wherever the left
/// eye sees the same point (joint_upsample.wgsl `right_eye_quad`), in the composite that
/// a headset shows (the AO in the HDR target's alpha) as in the upsample pass the bench
/// scores (AoFull). Both hold the same AO in every pixel of both eyes, with the reuse and
/// without it; with it, a right-eye pixel whose point lands on a left-eye pixel of the
/// same surface holds that pixel's AO (f16 rounding apart, and a pixel-boundary rounding
/// between the test's f64 projection and the shader's f32 one at a few pixels).
#[test]
fn the_composite_shows_the_ao_the_bench_scores_and_the_right_eye_takes_the_left_eyes() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let head = scene.head.pose_at(0.0);
    for (technique, reuse) in [(Technique::Gtao, true), (Technique::Hbao, true), (Technique::Gtao, false)] {
        let mut a = ao(technique, 12, 0.3);
        (a.stereo_reuse, a.half_res) = (reuse, true);
        let f = render(&gpu, &scene, &settings(96, 112, a), &head, &[AO_FULL, HDR]);
        let case = format!("{technique:?}, reuse {reuse}");
        let mut surface = 0;
        for (l, x, y) in f.pixels() {
            if f.world(l, x, y).is_none() {
                continue;
            }
            surface += 1;
            let (shown, scored) = (f.ao(HDR, l, x, y), f.ao(AO_FULL, l, x, y));
            assert!((shown - scored).abs() < 2e-3, "{case}: eye {l} ({x}, {y}) shows {shown}, scored {scored}");
        }
        assert!(surface > 10_000, "{case}: {surface} surface pixels");
        if !reuse {
            continue;
        }
        let (mut compared, mut equal) = (0, 0);
        for (x, y) in f.pixels().filter(|&(l, _, _)| l == 1).map(|(_, x, y)| (x, y)) {
            let Some(p) = f.world(1, x, y) else { continue };
            let Some((lx, ly)) = f.pixel_of(0, p) else { continue };
            let Some(q) = f.world(0, lx, ly) else { continue };
            let eye = f.eyes.eyes[0].pose.position;
            if ((q - eye).length() - (p - eye).length()).abs() > 0.005 * (p - eye).length() {
                continue;
            }
            compared += 1;
            let (right, left) = (f.ao(AO_FULL, 1, x, y), f.ao(AO_FULL, 0, lx, ly));
            equal += usize::from((right - left).abs() < 2e-3);
        }
        eprintln!("{case}: {equal} of {compared} right-eye pixels hold the left eye's AO");
        assert!(compared > 5_000, "{case}: only {compared} pixels seen by both eyes");
        assert!(equal as f64 > 0.98 * compared as f64, "{case}: {equal} of {compared} hold the left eye's AO");
    }
}

/// A march that leaves an eye's image through its inner (nasal) border goes on in the
/// other eye's layer, which sees past that border. On surface points near the inner
/// border that the other eye sees well inside its image, the two eyes' raw AO agree;
/// with those marches stopped at the border instead (checked by hand: gtao.wgsl's band
/// dispatch without lookups) the eye at its border reads lighter by 0.047. Each eye
/// marches on its own here (the right eye's reuse of the left eye would agree anyway).
#[test]
fn marches_past_the_inner_border_continue_in_the_other_eye() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    let mut a = ao(Technique::Gtao, 64, 1.0);
    a.stereo_reuse = false;
    let s = settings(128, 144, a);
    let f = render(&gpu, &scene, &s, &head, &[AO_RAW]);
    let band = 12;
    let (mut signed, mut occlusion) = (Vec::new(), Vec::new());
    // Left eye: inner border on the right; right eye: on the left.
    for (layer, other, columns) in [(0usize, 1usize, (f.width - band)..f.width), (1, 0, 0..band)] {
        for x in columns {
            for y in band..f.height - band {
                let Some(p) = f.world(layer, x, y) else { continue };
                let Some((ox, oy)) = f.pixel_of(other, p) else { continue };
                if ox < band || ox >= f.width - band || oy < band || oy >= f.height - band {
                    continue;
                }
                let Some(q) = f.world(other, ox, oy) else { continue };
                if (q - p).length() > 0.01 * (p - f.eyes.eyes[layer].pose.position).length() {
                    continue;
                }
                let (here, there) = (f.ao(AO_RAW, layer, x, y), f.ao(AO_RAW, other, ox, oy));
                signed.push(here - there);
                occlusion.push(1.0 - there);
            }
        }
    }
    let (bias, occluded) = (mean(signed.iter().copied()), mean(occlusion.iter().copied()));
    eprintln!(
        "inner border: {} matched px, mean (border eye − other eye) {bias:+.4}, mean occlusion seen by the other eye {occluded:.3}",
        signed.len()
    );
    assert!(signed.len() > 500, "too few matched pixels at the inner borders ({})", signed.len());
    assert!(occluded > 0.05, "nothing occluded at the inner borders: the case cannot tell");
    assert!(bias.abs() < 0.015, "the eye at its inner border disagrees with the other eye by {bias:+.4}");
}

// ---------------------------------------------------------------------------------------
// Numerics

#[test]
fn no_output_is_ever_nan_or_inf() {
    let (gpu, _guard) = common::gpu();
    let room = Scene::load("builtin:room").unwrap();
    let plane = Scene::load("builtin:plane").unwrap();
    let mut cases: Vec<(&str, &Scene, AoSettings)> = Vec::new();
    for technique in AO_TECHNIQUES {
        for half_res in [false, true] {
            for (name, scene) in [("room", &room), ("plane", &plane)] {
                cases.push((name, scene, AoSettings { half_res, ..ao(technique, 24, 0.5) }));
            }
        }
        // Stiff settings: one sample and a micro radius, every sample and a huge radius,
        // no bias with the strongest strength and widest blur, the tiled noise without range
        // check.
        cases.push(("room", &room, AoSettings { half_res: true, ..ao(technique, 1, 1e-4) }));
        cases.push(("plane", &plane, ao(technique, 256, 1e4)));
        cases.push(("room", &room, AoSettings { bias: 0.0, strength: 4.0, blur_radius: 16, ..ao(technique, 12, 2.0) }));
        cases.push((
            "plane",
            &plane,
            AoSettings { noise: Noise::Tiled5x5, range_check: false, half_res: true, ..ao(technique, 12, 1.0) },
        ));
    }
    for (name, scene, a) in cases {
        let label = format!("{name} {} N={} r={} half={}", a.technique.name(), a.samples, a.radius, a.half_res);
        let (w, h) = if a.half_res { (97, 109) } else { (96, 108) };
        let mut outputs = vec![AO_RAW, HDR];
        if a.blur_radius > 0 {
            outputs.push(AO_BLURRED);
        }
        if a.half_res {
            outputs.push(AO_FULL);
        }
        let f = render(&gpu, scene, &settings(w, h, a), &scene.head.pose_at(0.0), &outputs);
        for r in outputs {
            for layer in &f.outputs[&r] {
                let bad = layer.iter().filter(|v| !v.is_finite()).count();
                assert_eq!(bad, 0, "{label}: {} holds {bad} NaN/Inf values", r.name());
                if r == HDR {
                    assert!(layer.iter().all(|v| *v >= 0.0), "{label}: negative radiance");
                } else {
                    assert!(
                        layer.chunks(4).all(|p| (0.0..=1.0).contains(&p[3])),
                        "{label}: {} AO outside [0, 1]",
                        r.name()
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// The plan (`--explain`)

/// The final AO is the graph's named output: the last texture the AO chain provides for
/// these settings, and the occlusion's cost is the chain's passes (what the governor
/// and the bench time).
#[test]
fn the_final_ao_is_what_the_ao_chain_last_provided() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let cases = [
        // (technique, blur radius, half resolution, temporal) → final AO, occlusion passes
        (Technique::Gtao, 4, false, false, AO_BLURRED, vec!["gtao", "blur"]),
        (Technique::Gtao, 4, true, false, AO_FULL, vec!["gtao", "blur", "upsample"]),
        (Technique::Ssao, 0, false, false, AO_RAW, vec!["ssao"]),
        (Technique::Hbao, 0, false, true, AO_ACCUMULATED, vec!["hbao", "temporal"]),
        (Technique::Ssdo, 4, true, true, AO_FULL, vec!["ssdo", "temporal", "blur", "upsample"]),
    ];
    for (technique, blur_radius, half_res, temporal, expected, chain) in cases {
        let mut ao = AoSettings { technique, blur_radius, half_res, ..AoSettings::default() };
        ao.temporal.enabled = temporal;
        let renderer = Renderer::new(gpu.clone(), &scene, &settings(64, 72, ao)).unwrap();
        let plan = renderer.plan(2, &[FINAL_AO]).unwrap();
        let label = format!("{technique:?} blur {blur_radius} half {half_res} temporal {temporal}");
        assert_eq!(plan.resolve(FINAL_AO), Some(expected), "{label}\n{plan}");
        assert_eq!(plan.occlusion_passes(), chain, "{label}");
        // The composite of a frame reads the occlusion at occlusion resolution, never the
        // standalone upsample's output: a frame of the eyes alone runs no upsample.
        let frame = renderer.plan(2, &[COLOR]).unwrap();
        assert!(!frame.runs("upsample"), "{label}\n{frame}");
    }
    let none = AoSettings { technique: Technique::None, ..AoSettings::default() };
    let renderer = Renderer::new(gpu.clone(), &scene, &settings(64, 72, none)).unwrap();
    assert!(renderer.plan(2, &[COLOR]).unwrap().resolve(FINAL_AO).is_none());
    let error = renderer.plan(2, &[FINAL_AO]).unwrap_err().to_string();
    assert!(error.contains("final-ao"), "{error}");
}

#[test]
fn the_plan_explains_what_occlusion_left_out() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    let plan_for = |a: AoSettings| render(&gpu, &scene, &settings(64, 72, a), &head, &[COLOR]).report.plan;

    let none = plan_for(AoSettings { technique: Technique::None, ..AoSettings::default() });
    eprintln!("technique none:\n{none}");
    for pass in AO_PASSES.iter().chain(&["blur", "upsample"]) {
        assert!(!none.runs(pass), "technique none runs {pass}");
    }
    // One pass per technique is declared; SSDO's is named "ssdo-bounce" only while the
    // bounce is on, so with technique none the SSDO pass is left out as "ssdo".
    for pass in ["ssao", "hbao", "ssdo"] {
        let reason = none.left_out.iter().find(|(n, _)| *n == pass).map(|(_, why)| why.as_str());
        assert!(
            reason.is_some_and(|r| r.contains("none")),
            "technique none: {pass} left out without saying why ({reason:?})"
        );
    }
    assert!(none.runs("composite") && none.runs("tonemap"));

    let off = plan_for(AoSettings { technique: Technique::SsdoBounce, bounce: 0.0, ..AoSettings::default() });
    eprintln!("ssdo-bounce, bounce 0:\n{off}");
    assert!(off.runs("ssdo") && !off.runs("ssdo-bounce"), "bounce 0 runs the plain ssdo pass: {:?}", off.names);
    assert!(
        off.notes.iter().any(|(pass, note)| *pass == "ssdo" && note.contains("bounce") && note.contains("left out")),
        "no note says the bounce is left out: {:?}",
        off.notes
    );

    let on =
        plan_for(AoSettings { technique: Technique::SsdoBounce, bounce: 1.0, half_res: true, ..AoSettings::default() });
    eprintln!("ssdo-bounce, half res:\n{on}");
    assert_eq!(on.names, ["gbuffer", "direct", "ssdo-bounce", "blur", "composite", "tonemap"]);
    assert!(on.notes.iter().all(|(_, note)| !note.contains("bounce left out")));
    // A frame upsamples inside the composite; the upsample pass (a full-resolution
    // occlusion target) runs only when that target itself is asked for.
    assert!(on.notes.iter().any(|(pass, note)| *pass == "composite" && note.contains("upsamples")), "{:?}", on.notes);
    assert!(on.left_out.iter().any(|(pass, why)| *pass == "upsample" && why.contains("ao-full")), "{:?}", on.left_out);
    let half_bounce =
        AoSettings { technique: Technique::SsdoBounce, bounce: 1.0, half_res: true, ..AoSettings::default() };
    let debug = render(&gpu, &scene, &settings(64, 72, half_bounce), &head, &[COLOR, AO_FULL]).report.plan;
    assert!(debug.runs("upsample") && debug.runs("composite"), "{:?}", debug.names);
    for (technique, pass) in [(Technique::Ssao, "ssao"), (Technique::Hbao, "hbao"), (Technique::Ssdo, "ssdo")] {
        let plan = plan_for(AoSettings { technique, blur_radius: 0, ..AoSettings::default() });
        assert!(
            plan.runs(pass) && !plan.runs("blur") && !plan.runs("upsample"),
            "{}: {:?}",
            technique.name(),
            plan.names
        );
        let others: Vec<_> = AO_PASSES.iter().filter(|p| **p != pass && plan.runs(p)).collect();
        assert!(others.is_empty(), "{} also runs {others:?}", technique.name());
    }
}

/// The composite upsamples half-resolution occlusion inline. Its image must match the
/// full-resolution one as closely as the upsampled AO matches (AO differs by ≈ 0.005 on
/// average, and scales only the ambient share of the radiance), so the mean relative
/// radiance difference stays below 1 %; an inline upsample reading the wrong texel or
/// layer would leave contact shadows misplaced by pixels and fail this.
#[test]
fn the_composite_upsamples_half_resolution_occlusion_inline() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in [Technique::Ssao, Technique::Ssdo] {
        let base = AoSettings { technique, samples: 32, radius: 1.0, ..AoSettings::default() };
        let full = render(&gpu, &scene, &settings(128, 144, base.clone()), &head, &[HDR]);
        let half_settings = AoSettings { half_res: true, ..base };
        let half = render(&gpu, &scene, &settings(128, 144, half_settings), &head, &[HDR]);
        assert!(!half.report.plan.runs("upsample"), "the frame upsampled in a pass of its own");
        let (mut diff, mut total) = (0.0, 0.0);
        for layer in 0..2 {
            let (a, b) = (&full.outputs[&HDR][layer], &half.outputs[&HDR][layer]);
            for (x, y) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
                diff += (0..3).map(|c| (x[c] - y[c]).abs() as f64).sum::<f64>();
                total += (0..3).map(|c| x[c].abs() as f64).sum::<f64>();
            }
        }
        let relative = diff / total.max(1e-12);
        eprintln!("{}: half-res composite differs from full-res by {:.4} (relative)", technique.name(), relative);
        assert!(relative < 0.01, "{}: relative difference {relative}", technique.name());
    }
}
