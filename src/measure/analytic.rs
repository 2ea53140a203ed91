//! Ground truth for the occlusion tests, computed on the CPU in f64.
//!
//! Two kinds of expectation live here:
//!
//! - The *reference* ambient occlusion: cosine-weighted visibility within a radius r,
//!   V(P) = 1 − (1/π) ∫_Ω [the ray from P along ω hits geometry within r] cos θ dω,
//!   optionally with HBAO's linear attenuation W(d) = max(0, 1 − d/r) on each occluded
//!   direction ([`crease_visibility`], [`crease_visibility_falloff`] in closed form,
//!   [`visibility_by_ray_casting`] by quadrature for any geometry made of [`Rect`]s).
//! - The *expected value of a screen-space estimator*: what SSAO, SSDO or HBAO computes
//!   at a pixel on average over the per-pixel kernel rotation ([`ssao_crease_expectation`],
//!   [`ssdo_crease_expectation`] in closed form on the 90° crease, exact in the rotation;
//!   [`screen_space_expectation`] and [`hbao_expectation`] by running the estimator's
//!   test on the CPU for any eye and geometry). These are not the reference: SSAO's
//!   sample lengths crowd towards the centre, so it sees less of a wall than a ray of
//!   length r does, and HBAO's slices contain the view ray rather than the normal.
//!
//! Closed forms on the crease use the projected-disk view of the cosine-weighted
//! hemisphere: projecting a unit direction ω onto the tangent plane maps the measure
//! cos θ dω to area on the unit disk, so a cosine-weighted fraction of directions is an
//! area on the disk divided by π.

use glam::DVec3;
use std::f64::consts::{PI, TAU};
use vrao_ao::Eye;
use vrao_render::scene::builtin::{CREASE_FLOOR_END_Z, CREASE_HALF_WIDTH, CREASE_WALL_HEIGHT, CREASE_WALL_Z};

pub use crate::measure::metrics::luminance;

/// GLSL/WGSL `smoothstep`: 0 below `edge0`, 1 above `edge1`, Hermite in between.
pub fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Reference AO at a floor point at horizontal distance `distance_to_wall` (x) from an
/// infinite vertical wall standing on the floor (a 90° concave crease), cosine-weighted
/// about the floor normal, counting wall hits within `radius` (r).
///
/// A direction whose projection onto the floor is (u, v), with u towards the wall, meets
/// the wall plane at distance x / u; it is occluded when x / u ≤ r, i.e. u ≥ a = x / r.
/// That is a circular segment of the unit disk, so
/// V = 1 − (acos a − a √(1 − a²)) / π for a < 1 and V = 1 for a ≥ 1.
/// At the crease line (x → 0⁺) every direction leaning towards the wall hits it within
/// any r, which is exactly half of the cosine-weighted hemisphere: V → 1/2.
///
/// Valid for a wall at least r high and reaching at least r to each side of the point
/// (the builtin crease: 5 m high, ±5 m wide). `radius` must be > 0; x ≤ 0 is the crease line.
pub fn crease_visibility(distance_to_wall: f64, radius: f64) -> f64 {
    let a = (distance_to_wall.max(0.0) / radius).min(1.0);
    let segment = a.acos() - a * (1.0 - a * a).max(0.0).sqrt();
    1.0 - segment / PI
}

/// As [`crease_visibility`], with each occluded direction weighted by HBAO's attenuation
/// W(d) = max(0, 1 − d / r) at its hit distance d = x / u:
/// O = (1/π) ∫∫_{u ≥ a} (1 − a/u) du dv = (2/π) ∫_a^1 (1 − a/u) √(1 − u²) du
///   = (acos a + a √(1 − a²) − 2a ln((1 + √(1 − a²)) / a)) / π.
/// Same limits: 1/2 at the crease line, 1 from x = r on. Because W ≤ 1 it is never below
/// [`crease_visibility`].
///
/// It is also the exact continuous expectation of SSDO's test on the crease: a sample at
/// a distance λ uniform in [0, r] along a direction that meets the wall at d is behind
/// the wall with probability max(0, 1 − d / r) = W(d).
pub fn crease_visibility_falloff(distance_to_wall: f64, radius: f64) -> f64 {
    let a = (distance_to_wall.max(0.0) / radius).min(1.0);
    if a >= 1.0 {
        return 1.0;
    }
    let s = (1.0 - a * a).sqrt();
    // a ln((1 + s) / a) → 0 as a → 0; guard the 0 · ∞ form.
    let log_term = if a > 0.0 { a * ((1.0 + s) / a).ln() } else { 0.0 };
    let occlusion = (a.acos() + a * s - 2.0 * log_term) / PI;
    1.0 - occlusion
}

/// Brute-force check of the two closed forms: a midpoint rule with n × n points over the
/// polar angle θ ∈ [0, π/2] (from the floor normal) and the azimuth φ ∈ [0, 2π) (from the
/// direction towards the wall), integrating cos θ sin θ over the occluded directions.
/// Independent of the projected-disk argument; its error is O(1/n) because the
/// integrand is discontinuous (about 2e-3 at n = 400).
pub fn crease_visibility_quadrature(distance_to_wall: f64, radius: f64, falloff: bool, n: usize) -> f64 {
    let x = distance_to_wall.max(0.0);
    let (dt, dp) = (0.5 * PI / n as f64, TAU / n as f64);
    let mut occlusion = 0.0;
    for i in 0..n {
        let theta = (i as f64 + 0.5) * dt;
        let (sin_t, cos_t) = theta.sin_cos();
        for j in 0..n {
            let phi = (j as f64 + 0.5) * dp;
            let towards_wall = sin_t * phi.cos();
            if towards_wall <= 0.0 {
                continue;
            }
            let d = x / towards_wall;
            if d <= radius {
                let w = if falloff { 1.0 - d / radius } else { 1.0 };
                occlusion += w * cos_t * sin_t * dt * dp;
            }
        }
    }
    1.0 - occlusion / PI
}

/// A parallelogram `corner + a u + b v` for a, b in [0, 1]; rays hit it from both sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// One corner (m).
    pub corner: DVec3,
    /// First edge from `corner` (m).
    pub u: DVec3,
    /// Second edge from `corner` (m).
    pub v: DVec3,
}

impl Rect {
    /// Distance t > 0 along `dir` (any length: t is in units of `dir`) at which the ray
    /// from `origin` meets the rectangle, if it does.
    pub fn hit(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let m = self.u.cross(self.v);
        let mm = m.length_squared();
        let denom = dir.dot(m);
        if denom.abs() <= 1e-15 * dir.length() * mm.sqrt() {
            return None;
        }
        let t = (self.corner - origin).dot(m) / denom;
        // A ray starting on the surface does not hit it again.
        if t.is_nan() || t <= 1e-9 {
            return None;
        }
        let p = origin + dir * t - self.corner;
        let a = p.cross(self.v).dot(m) / mm;
        let b = self.u.cross(p).dot(m) / mm;
        let eps = 1e-12;
        ((-eps..=1.0 + eps).contains(&a) && (-eps..=1.0 + eps).contains(&b)).then_some(t)
    }
}

/// The nearest hit among `rects` (distance in units of `dir`).
pub fn first_hit(rects: &[Rect], origin: DVec3, dir: DVec3) -> Option<f64> {
    rects.iter().filter_map(|r| r.hit(origin, dir)).min_by(f64::total_cmp)
}

/// The builtin "crease" scene as rectangles: [floor (y = 0), wall (z = `CREASE_WALL_Z`)].
pub fn crease_rects() -> [Rect; 2] {
    let corner = DVec3::new(-CREASE_HALF_WIDTH, 0.0, CREASE_WALL_Z);
    let width = DVec3::X * (2.0 * CREASE_HALF_WIDTH);
    [
        Rect { corner, u: DVec3::Z * (CREASE_FLOOR_END_Z - CREASE_WALL_Z), v: width },
        Rect { corner, u: width, v: DVec3::Y * CREASE_WALL_HEIGHT },
    ]
}

/// Two unit tangents completing the unit `normal` to a right-handed frame (t, b, n).
pub fn tangent_frame(normal: DVec3) -> (DVec3, DVec3) {
    let helper = if normal.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t = helper.cross(normal).normalize();
    (t, normal.cross(t))
}

/// Reference AO at `point` with unit `normal` for any geometry, by ray casting: the
/// cosine-weighted hemisphere is split into n × n cells of equal cosine-weighted measure
/// (cos θ = √(1 − u₁), φ = 2π u₂, midpoints), and a cell is occluded when its ray hits
/// within `radius` (weighted by 1 − d/r when `falloff`). `hit(origin, unit_dir)` returns
/// the distance to the first surface. Error O(1/n) at the visibility boundary.
pub fn visibility_by_ray_casting(
    point: DVec3,
    normal: DVec3,
    radius: f64,
    falloff: bool,
    n: usize,
    hit: impl Fn(DVec3, DVec3) -> Option<f64>,
) -> f64 {
    let (t, b) = tangent_frame(normal);
    let mut occlusion = 0.0;
    for i in 0..n {
        let u1 = (i as f64 + 0.5) / n as f64;
        let cos_t = (1.0 - u1).sqrt();
        let sin_t = u1.sqrt();
        for j in 0..n {
            let phi = TAU * (j as f64 + 0.5) / n as f64;
            let dir = t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + normal * cos_t;
            if let Some(d) = hit(point, dir) {
                if d <= radius {
                    occlusion += if falloff { 1.0 - d / radius } else { 1.0 };
                }
            }
        }
    }
    1.0 - occlusion / (n * n) as f64
}

/// Fraction of a uniformly random rotation about the normal for which a sample whose
/// horizontal reach (component in the floor plane) is `reach` ends more than `beyond`
/// past the wall plane: the relative azimuth ψ must satisfy reach · cos ψ > beyond.
fn rotation_fraction_past_wall(reach: f64, beyond: f64) -> f64 {
    if reach <= beyond || reach <= 0.0 {
        return 0.0;
    }
    (beyond / reach).clamp(-1.0, 1.0).acos() / PI
}

/// Expected SSAO value (before blur) at a floor point at distance x from the crease's
/// wall, averaged exactly over a uniform rotation of the kernel about the normal.
///
/// `samples` is the kernel as [`vrao_ao::plug::hemisphere_kernel`] makes it: unit
/// directions around +Z (the normal; on the floor the normal is +Y) and a length as a
/// fraction of `radius`. The estimator, as the renderer implements it: sample i lies at
/// P + bias·r·n + sᵢ ωᵢ with sᵢ = lengthᵢ · r; it counts as occluded when the surface the
/// depth buffer holds at its projection is closer to the eye than the sample by more than
/// bias·r; AO = 1 − occluded / N.
///
/// Assumptions on the crease:
/// - The eye and every sample are above the floor and in front of the wall, so the
///   surface seen towards a sample is closer than it exactly when the sample is behind
///   the wall plane (the floor or wall behind a sample in front of the wall is farther).
///   The normal offset bias·r is vertical and does not move a sample towards the wall;
///   it also lifts every sample, and so the wall point that hides it, above the floor's
///   tangent plane by bias·r, which the renderer requires of an occluder.
/// - The depth difference equals the distance behind the wall plane (a view along the
///   wall normal); see [`ssao_crease_expectation_with_depth_scale`] for an oblique view.
/// - The range check never engages: every occluding wall point is within r of P in depth
///   (the wall points that hide a sample lie within r of P).
/// - The wall is infinite (≥ r high, ≥ r to either side) and every sample projects inside
///   the image (screen-space methods see nothing off screen).
/// - The rotation angle is uniform over the pixels averaged; a finite rotation pattern
///   (5×5 tile, Halton) approaches this as more pixels are averaged.
pub fn ssao_crease_expectation(distance_to_wall: f64, radius: f64, bias: f64, samples: &[[f32; 4]]) -> f64 {
    ssao_crease_expectation_with_depth_scale(distance_to_wall, radius, bias, samples, 1.0)
}

/// As [`ssao_crease_expectation`], for an eye whose view-space depth grows by
/// `depth_per_metre` for each metre a point lies behind the wall plane along the ray that
/// sees it (1 when looking along the wall normal; (e·f) / |e·n_wall| for a ray e and view
/// axis f). The depth test "closer by more than bias·r" then means "behind the wall
/// plane by more than bias·r / depth_per_metre".
pub fn ssao_crease_expectation_with_depth_scale(
    distance_to_wall: f64,
    radius: f64,
    bias: f64,
    samples: &[[f32; 4]],
    depth_per_metre: f64,
) -> f64 {
    if samples.is_empty() {
        return 1.0;
    }
    let beyond = distance_to_wall.max(0.0) + bias * radius / depth_per_metre;
    let occluded: f64 = samples
        .iter()
        .map(|k| {
            let sin_t = ((k[0] as f64).powi(2) + (k[1] as f64).powi(2)).sqrt();
            rotation_fraction_past_wall(k[3] as f64 * radius * sin_t, beyond)
        })
        .sum();
    1.0 - occluded / samples.len() as f64
}

/// Expected SSDO visibility (`.a`, before blur) at a floor point at distance x from the
/// crease's wall, averaged exactly over a uniform kernel rotation.
///
/// `samples` is [`vrao_ao::plug::hemisphere_kernel`] with uniform density: directions
/// uniform in solid angle around +Z and λᵢ = lengthᵢ · r. Sample i at P + bias·r·n + λᵢ ωᵢ
/// is blocked when it lies more than bias·r behind the wall plane (the depth test, under
/// the same assumptions as [`ssao_crease_expectation`]); visibility is the cosine-weighted
/// fraction of unblocked directions, Σ cos θᵢ (1 − blockedᵢ) / Σ cos θᵢ. As N grows it
/// tends to [`crease_visibility_falloff`] (plus the bias).
pub fn ssdo_crease_expectation(distance_to_wall: f64, radius: f64, bias: f64, samples: &[[f32; 4]]) -> f64 {
    ssdo_crease_expectation_with_depth_scale(distance_to_wall, radius, bias, samples, 1.0)
}

/// As [`ssdo_crease_expectation`] for an oblique view (see
/// [`ssao_crease_expectation_with_depth_scale`] for `depth_per_metre`).
pub fn ssdo_crease_expectation_with_depth_scale(
    distance_to_wall: f64,
    radius: f64,
    bias: f64,
    samples: &[[f32; 4]],
    depth_per_metre: f64,
) -> f64 {
    let beyond = distance_to_wall.max(0.0) + bias * radius / depth_per_metre;
    let (mut blocked, mut total) = (0.0, 0.0);
    for k in samples {
        let cos_t = (k[2] as f64).max(0.0);
        let sin_t = ((k[0] as f64).powi(2) + (k[1] as f64).powi(2)).sqrt();
        blocked += cos_t * rotation_fraction_past_wall(k[3] as f64 * radius * sin_t, beyond);
        total += cos_t;
    }
    if total > 0.0 {
        1.0 - blocked / total
    } else {
        1.0
    }
}

/// A pinhole eye for screen-space estimators: a point's depth is (p − eye) · forward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthView {
    /// The eye's position (m).
    pub eye: DVec3,
    /// Unit view axis.
    pub forward: DVec3,
}

impl DepthView {
    /// Distance of `p` along the view axis from the eye (m; negative behind it).
    pub fn depth(&self, p: DVec3) -> f64 {
        (p - self.eye).dot(self.forward)
    }

    /// The point the depth buffer holds where `p` projects: the first surface on the ray
    /// from the eye through `p` (which may lie beyond `p`), if any.
    pub fn seen(&self, p: DVec3, hit: &impl Fn(DVec3, DVec3) -> Option<f64>) -> Option<DVec3> {
        let dir = (p - self.eye).normalize();
        hit(self.eye, dir).map(|t| self.eye + dir * t)
    }
}

/// Which screen-space estimator [`screen_space_expectation`] simulates. Both start from
/// P + bias·r·n and test a sample point S against the depth buffer: S is blocked by the
/// visible surface W when depth(S) − depth(W) > bias·r and W rises above P's tangent
/// plane, (W − P)·n > bias·r (the renderer's guard against grazing self-occlusion).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    /// S = P + bias·r·n + s ω, each sample weight 1 (cosine-distributed kernel); the range
    /// check weighs an occluder by smoothstep(0, 1, r / |depth(P) − depth(W)|).
    Ssao,
    /// S = P + bias·r·n + λ ω, weighted by cos θ (uniform kernel); visibility is the
    /// weighted fraction of unblocked samples; the range check ignores an occluder with
    /// |depth(P) − depth(W)| > r.
    Ssdo,
}

/// Parameters of [`screen_space_expectation`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorParams {
    /// SSAO or SSDO.
    pub estimator: Estimator,
    /// Sampling radius r (m).
    pub radius: f64,
    /// Fraction of the radius: the depth tolerance (and SSAO's normal offset).
    pub bias: f64,
    /// Apply the estimator's range check (see [`Estimator`]).
    pub range_check: bool,
    /// Kernel rotations about the normal averaged (evenly spaced, midpoints).
    pub rotations: usize,
}

/// The expected AO (SSAO) or visibility `.a` (SSDO) that the screen-space estimator
/// produces at `point` (unit `normal`) seen from `view`, averaged over `rotations`
/// evenly spaced kernel rotations about the normal, by simulating the depth-buffer test
/// with ray casts: the depth buffer at a sample's projection holds the first surface on
/// the eye ray through the sample. Assumes every sample projects inside the image.
pub fn screen_space_expectation(
    params: &EstimatorParams,
    point: DVec3,
    normal: DVec3,
    samples: &[[f32; 4]],
    view: &DepthView,
    hit: impl Fn(DVec3, DVec3) -> Option<f64>,
) -> f64 {
    let (t, b) = tangent_frame(normal);
    let r = params.radius;
    let tolerance = params.bias * r;
    let point_depth = view.depth(point);
    let rotations = params.rotations.max(1);
    let (mut occluded, mut total) = (0.0, 0.0);
    for j in 0..rotations {
        let (sin_b, cos_b) = (TAU * (j as f64 + 0.5) / rotations as f64).sin_cos();
        for k in samples {
            let (kx, ky, kz) = (k[0] as f64, k[1] as f64, k[2] as f64);
            let dir = t * (kx * cos_b - ky * sin_b) + b * (kx * sin_b + ky * cos_b) + normal * kz;
            let length = k[3] as f64 * r;
            let weight = match params.estimator {
                Estimator::Ssao => 1.0,
                Estimator::Ssdo => kz.max(0.0),
            };
            let sample = point + normal * tolerance + dir * length;
            total += weight;
            let Some(seen) = view.seen(sample, &hit) else { continue };
            let seen_depth = view.depth(seen);
            // In front of the sample by more than the tolerance, and rising above the
            // receiver's tangent plane by more than it (no grazing self-occlusion).
            if view.depth(sample) - seen_depth <= tolerance
                || (seen - point).dot(normal) <= tolerance + 1e-5 * point_depth
            {
                continue;
            }
            let gap = (point_depth - seen_depth).abs();
            let range = match (params.range_check, params.estimator) {
                (false, _) => 1.0,
                (true, Estimator::Ssao) if gap > 0.0 => smoothstep(0.0, 1.0, r / gap),
                (true, Estimator::Ssao) => 1.0,
                (true, Estimator::Ssdo) => (gap <= r) as u8 as f64,
            };
            occluded += weight * range;
        }
    }
    if total > 0.0 {
        1.0 - occluded / total
    } else {
        1.0
    }
}

/// HBAO as the renderer runs it (src/render/passes/hbao/hbao.wgsl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HbaoParams {
    /// Sampling radius r (m).
    pub radius: f64,
    /// Fraction of the radius; the angle bias is sin h₀ = min(5 · bias, 0.9).
    pub bias: f64,
    /// Directions marched per rotation.
    pub directions: u32,
    /// Steps along each direction.
    pub steps: u32,
    /// Per-pixel rotations averaged (evenly spaced over 2π).
    pub rotations: u32,
}

/// The expected HBAO value at full-resolution `pixel` of `eye` (image `size`), averaged
/// over a uniform per-pixel rotation, by running the estimator on the CPU against the
/// surfaces `hit` returns for each pixel's centre ray: `directions` screen directions
/// turned by the rotation α; along each, `steps` taps at max(((s + j) / steps)² R_px,
/// s + 1) pixels, where R_px is the radius in pixels at the receiver's depth and the
/// jitter j = fract(7α / 2π) comes with the rotation, as on the GPU; a tap snaps to the
/// pixel it falls in; a tap within r whose elevation above the tangent plane, sin h,
/// exceeds the running horizon (which starts at the angle bias) adds sin²h − sin²h_prev.
/// AO = 1 − (occlusion summed over directions) / directions.
///
/// In the continuum (infinitely many steps, no angle bias, vertical slices with uniform
/// azimuths) this is the hard cut-off visibility [`crease_visibility`] when the wall is
/// thick, as the crease's is. HBAO's expected value differs from that by its
/// discretisation (the horizon rises only at taps), the angle bias, and the perspective:
/// uniform screen directions are not uniform azimuths on a surface seen obliquely, and a
/// screen line is not a vertical slice.
pub fn hbao_expectation(
    params: &HbaoParams,
    eye: &Eye,
    size: (u32, u32),
    pixel: (u32, u32),
    normal: DVec3,
    hit: impl Fn(DVec3, DVec3) -> Option<f64>,
) -> f64 {
    let origin = eye.pose.position;
    let surface = |x: f64, y: f64| {
        let dir = vrao_ao::Eye::pixel_ray(eye, size, (x, y));
        hit(origin, dir).map(|t| origin + dir * t)
    };
    let Some(p) = surface(pixel.0 as f64 + 0.5, pixel.1 as f64 + 0.5) else { return 1.0 };
    let forward = eye.pose.orientation * DVec3::NEG_Z;
    let [l, r, _, _] = eye.fov.tangents();
    let metres_per_pixel = (r - l) / size.0 as f64 * (p - origin).dot(forward);
    let radius_px = params.radius / metres_per_pixel.max(1e-30);
    let steps = params.steps.max(1);
    let directions = params.directions.max(1);
    let march_px = radius_px.min((size.0 + size.1) as f64);
    let sin_bias = (5.0 * params.bias).min(0.9);
    let rotations = params.rotations.max(1);
    let mut total = 0.0;
    for i in 0..rotations {
        let alpha = TAU * (i as f64 + 0.5) / rotations as f64;
        let jitter = (alpha / TAU * 7.0).fract();
        let mut occlusion = 0.0;
        for d in 0..directions {
            let angle = alpha + TAU * d as f64 / directions as f64;
            let dir = (angle.cos(), angle.sin());
            let mut max_sin = sin_bias;
            for s in 0..steps {
                let t = (s as f64 + jitter) / steps as f64;
                let reach = (t * t * march_px).max(s as f64 + 1.0);
                let q = (pixel.0 as f64 + 0.5 + dir.0 * reach, pixel.1 as f64 + 0.5 + dir.1 * reach);
                // Off the image the GPU asks the other eye, which sees about the same
                // surface: here the scene itself answers.
                let Some(tap) = surface(q.0.floor() + 0.5, q.1.floor() + 0.5) else { continue };
                let h = tap - p;
                let dist = h.length();
                if dist < 1e-20 || dist > params.radius {
                    continue;
                }
                let sin_h = h.dot(normal) / dist;
                if sin_h > max_sin {
                    occlusion += sin_h * sin_h - max_sin * max_sin;
                    max_sin = sin_h;
                }
            }
        }
        total += 1.0 - occlusion / directions as f64;
    }
    total / rotations as f64
}

/// The continuum limit of HBAO on the crease with vertical slices at uniform azimuths:
/// the mean over azimuths ψ (from the wall normal) of 1 − (1 − D/r)²₊ with
/// D = x / cos ψ. Equal to [`crease_visibility_falloff`] (checked in the tests below).
pub fn crease_hbao_slices(distance_to_wall: f64, radius: f64, azimuths: usize) -> f64 {
    let mut occlusion = 0.0;
    for i in 0..azimuths {
        let psi = TAU * (i as f64 + 0.5) / azimuths as f64;
        let c = psi.cos();
        if c > 0.0 {
            let d = distance_to_wall.max(0.0) / c;
            if d < radius {
                occlusion += (1.0 - d / radius).powi(2);
            }
        }
    }
    1.0 - occlusion / azimuths as f64
}

#[cfg(test)]
mod tests;
