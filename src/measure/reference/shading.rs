//! The estimators at one surface point: stratified cosine-weighted directions, one ray
//! each, and the direct-light model of `src/render/passes/direct/direct.wgsl` at the points they hit,
//! with directional light shadowed by a shadow ray (what the GPU's shadow maps
//! approximate). A sender's albedo is its base colour × texture × vertex colour, its
//! emission the emissive factor × emission texture, its direct light taken about its
//! normal-mapped normal; the receiver's hemisphere is about its vertex normal.

use super::geometry::{sample_texture, SceneGeometry, Surface};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use vrao_render::scene::{Environment, Light, Scene};

/// A direction counts as below the surface (occluded at distance 0) when its cosine with
/// the geometric normal is below this. Zero would do for exact arithmetic; the margin
/// keeps a flat surface whose f32 geometric normal is a hair off its stored vertex normal
/// from darkening at grazing directions (whose rays then leave through the offset origin).
const BELOW_SURFACE: f64 = -1e-6;

/// Ray origins leave a hit point along the geometric normal by this times the largest
/// coordinate magnitude of its triangle: 64 f32 ulps, far above the rounding of a point
/// reconstructed from barycentrics, far below any occlusion radius that makes sense there.
pub(crate) const OFFSET_ULPS: f32 = 64.0 * f32::EPSILON;

/// A small deterministic generator (PCG-XSH-RR 64/32), one stream per pixel.
#[derive(Clone, Debug)]
pub(crate) struct Rng {
    state: u64,
}

impl Rng {
    const MULTIPLIER: u64 = 6364136223846793005;
    const INCREMENT: u64 = 1442695040888963407;

    pub(super) fn new(seed: u64) -> Rng {
        let mut rng = Rng { state: 0 };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    pub(super) fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULTIPLIER).wrapping_add(Self::INCREMENT);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1) with 32 random bits.
    pub(super) fn next_f64(&mut self) -> f64 {
        self.next_u32() as f64 * (1.0 / 4294967296.0)
    }
}

/// SplitMix64's finaliser: a well-mixed 64-bit hash of `x`.
fn mix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e3779b97f4a7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d049bb133111eb);
    x ^ (x >> 31)
}

/// The seed of a pixel's stream: a hash of the eye layer and the full-resolution pixel,
/// so the same pixel gets the same directions whatever the stride or thread.
pub(crate) fn pixel_seed(layer: u32, x: u32, y: u32) -> u64 {
    mix64(mix64(mix64(0x7672_616f_5f72_6566 ^ layer as u64) ^ x as u64) ^ y as u64)
}

/// Shirley and Chiu's concentric map from the unit square onto the unit disk; it keeps
/// strata compact, so a jittered grid on the square stays stratified on the disk.
pub(crate) fn concentric_disk(u: f64, v: f64) -> (f64, f64) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() { (a, PI / 4.0 * (b / a)) } else { (b, PI / 2.0 - PI / 4.0 * (a / b)) };
    (r * phi.cos(), r * phi.sin())
}

/// Two unit tangents completing unit `n` to an orthonormal frame (Duff et al. 2017,
/// "Building an Orthonormal Basis, Revisited"): no branch on a helper axis, exact at
/// the poles.
pub(crate) fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), DVec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// Points of the unit square for `count` directions: a jittered k × k grid (k = ⌊√count⌋)
/// and the remaining count − k² uniform. Every point is uniform over its own stratum or the
/// square, so the mean over all of them is an unbiased estimate of the integral.
pub(crate) fn stratified_points(count: u32, rng: &mut Rng, out: &mut Vec<(f64, f64)>) {
    out.clear();
    let mut k = (count as f64).sqrt() as u32;
    while k * k > count {
        k -= 1;
    }
    while (k + 1) * (k + 1) <= count {
        k += 1;
    }
    for j in 0..k {
        for i in 0..k {
            let u = (i as f64 + rng.next_f64()) / k as f64;
            let v = (j as f64 + rng.next_f64()) / k as f64;
            out.push((u, v));
        }
    }
    while (out.len() as u32) < count {
        out.push((rng.next_f64(), rng.next_f64()));
    }
}

/// The scene's lights in anchored coordinates, as the direct pass reads them.
pub(crate) enum AnchoredLight {
    /// `towards` is the unit direction towards the light (−direction).
    Directional { towards: Vec3, radiance: Vec3 },
    /// Point and spot lights; a spot has `cone` = (unit axis, cos outer cone, ramp scale)
    /// as [`vrao_render::scene::spot_ramp`] gives them.
    Point { position: Vec3, radiance: Vec3, cone: Option<(Vec3, f32, f32)> },
}

pub(crate) struct Lighting<'a> {
    pub lights: Vec<AnchoredLight>,
    pub environment: Option<&'a Environment>,
}

impl<'a> Lighting<'a> {
    pub(super) fn new(scene: &'a Scene, anchor: DVec3) -> Lighting<'a> {
        let lights = scene
            .lights
            .iter()
            .map(|light| match *light {
                Light::Directional { direction, color, intensity } => AnchoredLight::Directional {
                    towards: -direction.as_dvec3().normalize_or_zero().as_vec3(),
                    radiance: color * intensity,
                },
                Light::Point { position, color, intensity } => AnchoredLight::Point {
                    position: (position - anchor).as_vec3(),
                    radiance: color * intensity,
                    cone: None,
                },
                Light::Spot { position, direction, color, intensity, inner_cone, outer_cone } => AnchoredLight::Point {
                    position: (position - anchor).as_vec3(),
                    radiance: color * intensity,
                    cone: {
                        let (cos_outer, scale) = vrao_render::scene::spot_ramp(inner_cone, outer_cone);
                        Some((direction.normalize_or_zero(), cos_outer, scale))
                    },
                },
            })
            .collect();
        Lighting { lights, environment: scene.environment.as_ref() }
    }

    /// Irradiance from the lights at `surface` as the direct pass computes it with shadows
    /// on, about the surface's lighting normal ([`SceneGeometry::lighting_normal`]: the
    /// normal texture's where it has one): each directional light that faces that normal
    /// counts only when a shadow ray towards it (leaving along the geometric normal on the
    /// light's side, past the surface's own triangle) hits nothing. Point lights have no
    /// shadow maps on the GPU and none here either.
    pub(super) fn shadowed_irradiance(&self, geometry: &SceneGeometry, surface: &Surface) -> Vec3 {
        let n = geometry.lighting_normal(surface);
        let offset = OFFSET_ULPS * surface.magnitude.max(f32::MIN_POSITIVE);
        let mut e = Vec3::ZERO;
        for light in &self.lights {
            match *light {
                AnchoredLight::Directional { towards, radiance } => {
                    let cos = n.dot(towards);
                    if cos > 0.0 {
                        let side = if surface.geometric.dot(towards) >= 0.0 { 1.0 } else { -1.0 };
                        let origin = surface.position + surface.geometric * (side * offset);
                        if geometry.closest(origin, towards, 0.0, f32::INFINITY, surface.prim).is_none() {
                            e += radiance * cos;
                        }
                    }
                }
                AnchoredLight::Point { position, radiance, cone } => {
                    let to_light = position - surface.position;
                    let d2 = to_light.length_squared().max(1e-4);
                    let l = to_light / d2.sqrt();
                    // glTF's spot falloff, as the direct pass computes it.
                    let falloff = cone.map_or(1.0, |(axis, cos_outer, scale)| {
                        let ramp = ((axis.dot(-l) - cos_outer) * scale).clamp(0.0, 1.0);
                        ramp * ramp
                    });
                    e += radiance * falloff * n.dot(l).max(0.0) / d2;
                }
            }
        }
        e
    }
}

/// Linear albedo at a surface: the material's diffuse times its texture times the
/// interpolated vertex colour, clamped to [0, 1] as the G-buffer stores it.
pub(crate) fn albedo(geometry: &SceneGeometry, surface: &Surface) -> Vec3 {
    let m = &geometry.materials[surface.material];
    let mut a = m.diffuse * surface.color.truncate();
    if let Some(t) = &m.texture {
        a *= sample_texture(t, t.sampling.pick(surface.uvs));
    }
    let a = a.clamp(Vec3::ZERO, Vec3::ONE);
    if a.is_finite() {
        a
    } else {
        Vec3::ZERO
    }
}

/// Emitted radiance at a surface: the material's emission times its emission texture
/// (glTF `emissiveTexture`, sRGB). Vertex colours do not tint it (glTF's `COLOR_0`
/// multiplies the base colour only).
pub(crate) fn emission(geometry: &SceneGeometry, surface: &Surface) -> Vec3 {
    let m = &geometry.materials[surface.material];
    match &m.emissive_texture {
        Some(t) if m.emissive != Vec3::ZERO => m.emissive * sample_texture(t, t.sampling.pick(surface.uvs)),
        _ => m.emissive,
    }
}

/// Outgoing radiance of the direct model at a surface seen along `dir` (from the point
/// that looks at it): albedo/π · Σ E (directional lights shadowed) + emission; zero on a
/// back face (the ray arrives from the side its geometric normal, oriented like the
/// vertex normal, points away from).
pub(crate) fn direct_out(geometry: &SceneGeometry, lighting: &Lighting, surface: &Surface, dir: Vec3) -> Vec3 {
    let front = if surface.geometric.dot(surface.shading) >= 0.0 { surface.geometric } else { -surface.geometric };
    if front.dot(dir) >= 0.0 {
        return Vec3::ZERO;
    }
    let irradiance = lighting.shadowed_irradiance(geometry, surface);
    let l = albedo(geometry, surface) / std::f32::consts::PI * irradiance + emission(geometry, surface);
    if l.is_finite() {
        l
    } else {
        Vec3::ZERO
    }
}

/// The estimates at one visible surface point.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PointEstimate {
    pub ao: f64,
    pub ao_falloff: f64,
    pub ao_std_error: f64,
    pub environment_visible: [f64; 3],
    pub bounce: [f64; 3],
    pub unoccluded: [f64; 3],
    /// Standard errors of environment_visible + bounce and of bounce: r, g, b, luminance.
    pub ambient_std_error: [f64; 4],
    pub bounce_std_error: [f64; 4],
    /// Rays traced (directions below the surface need none).
    pub rays: u64,
}

/// Everything the estimator reads that does not change between pixels.
pub(crate) struct Estimator<'a> {
    pub geometry: &'a SceneGeometry,
    pub lighting: &'a Lighting<'a>,
    pub radius: f64,
    pub rays_per_pixel: u32,
}

impl Estimator<'_> {
    /// The estimates at `surface`, seen along unit `view_dir` (from the eye towards it).
    ///
    /// The hemisphere is cosine-weighted about the shading normal, flipped to face the
    /// eye as the G-buffer does; ray origins leave along the geometric normal flipped to
    /// the eye's side. A direction below the geometric surface counts as occluded at
    /// distance 0: the surface itself is in the way.
    pub(super) fn estimate(
        &self,
        surface: &Surface,
        view_dir: Vec3,
        rng: &mut Rng,
        points: &mut Vec<(f64, f64)>,
    ) -> PointEstimate {
        let frame = Hemisphere::at(surface, view_dir);
        stratified_points(self.rays_per_pixel, rng, points);
        let mut sums = RaySums::default();
        for &(u, v) in points.iter() {
            self.trace(surface, &frame, (u, v), &mut sums);
        }
        self.point_estimate(&sums, frame.ns)
    }

    /// Traces the ray of stratified point `(u, v)` (mapped cosine-weighted onto the
    /// hemisphere) and adds what it found to `sums`: an occluder's direct light, or the
    /// environment through an open direction.
    fn trace(&self, surface: &Surface, frame: &Hemisphere, (u, v): (f64, f64), sums: &mut RaySums) {
        let (t, b, ns, ng) = (frame.t, frame.b, frame.ns, frame.ng);
        let (x, y) = concentric_disk(u, v);
        let z = (1.0 - x * x - y * y).max(0.0).sqrt();
        let dir = (t * x + b * y + ns * z).normalize();
        if dir.dot(ng) < BELOW_SURFACE {
            sums.occluded += 1;
            sums.attenuated += 1.0;
            return;
        }
        let dir32 = dir.as_vec3();
        sums.rays += 1;
        match self.geometry.closest(frame.origin, dir32, 0.0, self.radius as f32, surface.prim) {
            Some(hit) => {
                sums.occluded += 1;
                sums.attenuated += (1.0 - hit.t as f64 / self.radius).clamp(0.0, 1.0);
                let sender = self.geometry.surface(&hit);
                let sent = direct_out(self.geometry, self.lighting, &sender, dir32).as_dvec3();
                sums.bounce += sent;
                let sq = squares(sent);
                for (k, s) in sq.into_iter().enumerate() {
                    sums.ambient2[k] += s;
                    sums.bounce2[k] += s;
                }
            }
            None => {
                if let Some(env) = self.lighting.environment {
                    let seen = env.sample(dir32).as_dvec3();
                    sums.visible_env += seen;
                    let sq = squares(seen);
                    for (sum, s) in sums.ambient2.iter_mut().zip(sq) {
                        *sum += s;
                    }
                }
            }
        }
    }

    /// The point's estimates from its rays' sums; `ns` is the shading normal the
    /// hemisphere was taken about.
    fn point_estimate(&self, sums: &RaySums, ns: DVec3) -> PointEstimate {
        let m = self.rays_per_pixel as f64;
        let p = sums.occluded as f64 / m;
        // Sample standard deviation of the 0/1 occlusion indicator over √M. For one ray
        // there is no spread to measure: state the largest a 0/1 variable can have.
        let ao_std_error = if self.rays_per_pixel > 1 { (p * (1.0 - p) / (m - 1.0)).max(0.0).sqrt() } else { 0.5 };
        // With the cosine-weighted pdf cos θ / π, ∫ f cos θ dω ≈ (π / M) Σ f.
        let scale = PI / m;
        let unoccluded = self.lighting.environment.map_or(Vec3::ZERO, |env| env.irradiance(ns.as_vec3()));
        PointEstimate {
            ao: 1.0 - p,
            ao_falloff: (1.0 - sums.attenuated / m).clamp(0.0, 1.0),
            ao_std_error,
            environment_visible: (sums.visible_env * scale).to_array(),
            bounce: (sums.bounce * scale).to_array(),
            unoccluded: unoccluded.as_dvec3().to_array(),
            ambient_std_error: self.std_error(sums.visible_env + sums.bounce, sums.ambient2),
            bounce_std_error: self.std_error(sums.bounce, sums.bounce2),
            rays: sums.rays,
        }
    }

    /// The standard error of (π / M) Σ x from the rays' own spread (0 for one ray), per
    /// channel and for luminance, from the sum of x and of its squares.
    fn std_error(&self, sum: DVec3, sum2: [f64; 4]) -> [f64; 4] {
        let m = self.rays_per_pixel as f64;
        let lum = 0.2126 * sum.x + 0.7152 * sum.y + 0.0722 * sum.z;
        let sums = [sum.x, sum.y, sum.z, lum];
        std::array::from_fn(|k| {
            if self.rays_per_pixel < 2 {
                return 0.0;
            }
            let variance = ((sum2[k] - sums[k] * sums[k] / m) / (m - 1.0)).max(0.0);
            PI * (variance / m).sqrt()
        })
    }
}

/// Where a surface point's rays leave from: the hemisphere about the shading normal `ns`
/// (with tangents `t`, `b`), flipped to face the eye as the G-buffer does, and the ray
/// origin pushed off the surface along the geometric normal `ng` on the eye's side.
struct Hemisphere {
    ng: DVec3,
    ns: DVec3,
    t: DVec3,
    b: DVec3,
    origin: Vec3,
}

impl Hemisphere {
    /// The hemisphere at `surface`, seen along unit `view_dir` (from the eye towards it).
    fn at(surface: &Surface, view_dir: Vec3) -> Hemisphere {
        let mut ng = surface.geometric.as_dvec3();
        if ng.dot(view_dir.as_dvec3()) > 0.0 {
            ng = -ng;
        }
        let mut ns = surface.shading.as_dvec3();
        if ns.dot(-view_dir.as_dvec3()) < 0.0 {
            ns = -ns;
        }
        let ns = ns.normalize();
        let (t, b) = orthonormal_basis(ns);
        let offset = OFFSET_ULPS * surface.magnitude.max(f32::MIN_POSITIVE);
        let origin = surface.position + ng.as_vec3() * offset;
        Hemisphere { ng, ns, t, b, origin }
    }
}

/// What one point's rays found, summed as they are traced.
#[derive(Default)]
struct RaySums {
    /// Directions blocked (below the surface or hitting within the radius).
    occluded: u64,
    /// Σ of each direction's occlusion with distance falloff (1 at the surface).
    attenuated: f64,
    /// Rays traced.
    rays: u64,
    /// The environment's radiance through the open directions.
    visible_env: DVec3,
    /// The occluders' outgoing direct light.
    bounce: DVec3,
    /// Sums of squares per ray (r, g, b, luminance) for the light's standard errors.
    ambient2: [f64; 4],
    bounce2: [f64; 4],
}

/// The squares of a ray's light (r, g, b and its luminance), for the standard errors.
fn squares(c: DVec3) -> [f64; 4] {
    let lum = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    [c.x * c.x, c.y * c.y, c.z * c.z, lum * lum]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_deterministic_and_uniform_enough() {
        let mut a = Rng::new(42);
        let mut b = Rng::new(42);
        let xs: Vec<f64> = (0..10_000).map(|_| a.next_f64()).collect();
        assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x) && x == b.next_f64()));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert_ne!(Rng::new(43).next_u32(), Rng::new(42).next_u32());
        assert_ne!(pixel_seed(0, 1, 2), pixel_seed(0, 2, 1));
        assert_ne!(pixel_seed(0, 1, 2), pixel_seed(1, 1, 2));
    }

    #[test]
    fn concentric_map_stays_in_the_disk_and_covers_it_uniformly() {
        let n = 200;
        let mut inner = 0;
        for j in 0..n {
            for i in 0..n {
                let (x, y) = concentric_disk((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let r2 = x * x + y * y;
                assert!(r2 <= 1.0 + 1e-12);
                inner += (r2 < 0.25) as usize;
            }
        }
        // Area-preserving: a quarter of the points fall inside radius 1/2.
        assert!((inner as f64 / (n * n) as f64 - 0.25).abs() < 0.005);
        assert_eq!(concentric_disk(0.5, 0.5), (0.0, 0.0));
    }

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        for n in [DVec3::Z, -DVec3::Z, DVec3::X, DVec3::new(0.3, -0.4, 0.866).normalize(), DVec3::new(1e-9, 0.0, -1.0)]
        {
            let (t, b) = orthonormal_basis(n.normalize());
            let n = n.normalize();
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-12);
            }
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12, "right-handed");
        }
    }

    #[test]
    fn stratified_points_cover_every_cell_and_any_count() {
        let mut rng = Rng::new(7);
        let mut points = Vec::new();
        for count in [1, 2, 3, 4, 5, 15, 16, 17, 64, 100] {
            stratified_points(count, &mut rng, &mut points);
            assert_eq!(points.len(), count as usize);
            assert!(points.iter().all(|&(u, v)| (0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)));
        }
        stratified_points(16, &mut rng, &mut points);
        let mut cells: Vec<(u32, u32)> = points.iter().map(|&(u, v)| ((u * 4.0) as u32, (v * 4.0) as u32)).collect();
        cells.sort();
        cells.dedup();
        assert_eq!(cells.len(), 16, "one point in each of the 4×4 strata");
    }
}
