//! The *screen-space limit*: the AO that a brute-force march over a frame's own depth
//! buffer gives, for the pixels of a [`ReferenceImage`]'s grid.
//!
//! Screen space sees one depth layer per eye. What no depth-buffer method can know (the
//! back of anything, what lies behind a surface, what is off the image) is as unknown
//! here as it is to SSAO or HBAO; everything else is sampled far more finely than any
//! real-time estimator does. The gap between the ray-traced reference and this limit is
//! *screen-space error* (no estimator can remove it); the gap between a technique and
//! this limit is *estimator error* (sampling, falloffs, bias).
//!
//! At a grid pixel with depth d > 0 the receiver P is the view-space position the GPU
//! reconstructs (`stereo::view_position_from_depth` at the pixel centre, as
//! `shaders/common.wgsl` does) and n the G-buffer's view-space normal, flipped to face the
//! eye. M cosine-weighted directions about n (a jittered ⌊√M⌋² grid mapped by the
//! concentric map, as the reference tracer draws them, from a PCG32 stream seeded by the
//! eye layer and pixel: deterministic and independent of threads) are each marched to
//! length r in S evenly spaced steps t_k = r (k + ξ) / S, k = 0..S, with one jitter ξ per
//! ray. A step Q is *blocked* when, at the pixel Q projects to, the depth buffer's visible
//! surface lies in front of Q by less than the thickness (0 < dist(Q) − dist(surface) <
//! thickness, distances along −z), and that surface point S (reconstructed at its pixel
//! centre) is above the receiver's tangent plane: (S − P)·n > 1 % of r. That last test is
//! the guard against self-intersection: the depth buffer is piecewise constant per pixel,
//! so on a sloped or grazing surface a step just above the surface often lands "behind"
//! a neighbouring pixel of the same surface; a surface point in (or below) the receiver's
//! own tangent plane cannot occlude the upper hemisphere, whatever the discretisation
//! says. The 1 % of r costs occluders lower than that, which only the near-horizontal
//! directions can reach (cosine weight ≲ 1e-4 of the hemisphere). A ray is blocked at its
//! first blocked step; steps off the image, in front of the near plane or on the sky are
//! open (the ray stops when it leaves the image: the image of a segment is a segment, and
//! the image is convex). AO = unblocked rays / M, as the reference's 1 − (1/π)∫\[hit\]cos θ dω.
//!
//! The bounce's limit (with the frame's direct light, [`EyeBuffers::direct`]): each
//! blocked ray brings the direct light leaving the surface S it was blocked by when S
//! faces P (its normal towards P), (π / M) Σ L_direct(S), as the reference's one bounce
//! from surfaces within r: what SSDO's bounce could reach from the same buffers.
//!
//! Thickness: the depth buffer cannot say how deep anything is. A step counts only within
//! a finite thickness behind the visible surface, so an object in front of a far wall does
//! not shadow the wall (the halo of infinite thickness) and a thin slab stops occluding a
//! little behind itself. It must exceed one step's depth change (r / S along the view axis
//! at most), or a ray could step over a surface it crosses without a step landing behind
//! it; the default is r / 4 (six steps at S = 24), scaled with r rather than fixed in
//! metres so that it stays above that floor for any radius and stays small next to the
//! region the occlusion integrates over.
//!
//! The *two-layer limit* ([`EyeBuffers::second`]): with a second depth layer (the next
//! surface behind the visible one, at least a minimum separation behind it, as the
//! renderer's depth peel writes it), what lies behind a visible surface is no longer a
//! guess where that layer has a surface: a step Q counts as inside where, at its pixel,
//! its path lies between the first surface and the second (the back of a closed object,
//! or the next object behind). Those spans can be far thinner than a step (a 6 mm slat's
//! back face), so there the test is the step's *segment*: the distances the ray covers
//! from the previous step (or the receiver) to Q overlap the span, where a point test
//! would step over it. Where the second layer has no surface (nothing behind, or the sky)
//! the thickness guess and the point test apply exactly as in the one-layer limit, so
//! the two limits differ only at pixels with a second surface.
//!
//! *Cards*: an alpha-tested surface (a leaf, a grille, a fence; the G-buffer marks it in
//! its normal's w, as GTAO reads it) is a sheet with no inside, in both limits: a step
//! counts as blocked there only where the ray's segment from the previous step crosses
//! the card's plane (through its point at that pixel, with its G-buffer normal). Neither
//! a thickness nor the span to a second layer (the floor under a grille) lies behind a
//! card.

use super::shading::{concentric_disk, orthonormal_basis, pixel_seed, stratified_points, Rng};
use super::{grid_size, pixel_of, ReferenceImage};
use crate::error::{Error, Result};
use glam::DVec3;
use rayon::prelude::*;
use vrao_ao::Fov;

/// Default rays per pixel of the march.
pub const DEFAULT_RAYS: u32 = 64;
/// Default steps along each ray.
pub const DEFAULT_STEPS: u32 = 24;
/// Default thickness as a fraction of the radius (see the module docs).
pub const DEFAULT_THICKNESS_OF_RADIUS: f64 = 0.25;
/// Surface points closer to the receiver's tangent plane than this fraction of r do not
/// occlude it (the self-intersection guard).
pub const TANGENT_PLANE_TOLERANCE_OF_RADIUS: f64 = 0.01;

/// Salt of the per-pixel seed, so the march's directions are not the reference's.
const SEED_SALT: u64 = 0x6c69_6d69_745f_6d61;

/// How the limit is marched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitSettings {
    /// Ray length r in metres (the AO radius).
    pub radius: f64,
    /// Cosine-weighted rays per pixel (a square number stratifies best).
    pub rays_per_pixel: u32,
    /// Evenly spaced steps per ray.
    pub steps: u32,
    /// Metres behind the visible surface in which a step counts as inside it.
    pub thickness: f64,
    /// March every `stride`-th pixel (the reference's grid).
    pub stride: u32,
    /// Near plane in metres (what the depth encodes as near / distance).
    pub near: f64,
}

impl LimitSettings {
    /// The defaults (64 rays, 24 steps, thickness r / 4) for `radius` on a grid of `stride`.
    pub fn new(radius: f64, stride: u32, near: f64) -> LimitSettings {
        LimitSettings {
            radius,
            rays_per_pixel: DEFAULT_RAYS,
            steps: DEFAULT_STEPS,
            thickness: radius * DEFAULT_THICKNESS_OF_RADIUS,
            stride,
            near,
        }
    }

    /// The defaults on the grid of `reference`.
    pub fn for_reference(reference: &ReferenceImage, radius: f64, near: f64) -> LimitSettings {
        LimitSettings::new(radius, reference.stride, near)
    }

    /// Checks every field; the error names the field and value.
    pub fn validate(&self) -> Result<()> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.radius) || !positive(self.thickness) || !positive(self.near) {
            return Err(Error::input(format!(
                "screen-space limit: radius {}, thickness {} and near {} must be finite and > 0",
                self.radius, self.thickness, self.near
            )));
        }
        if self.rays_per_pixel == 0 || self.steps == 0 || self.stride == 0 {
            return Err(Error::input("screen-space limit: rays, steps and stride must be ≥ 1"));
        }
        Ok(())
    }
}

/// One eye's G-buffer as read back: reversed-Z depth (one value a pixel, 0 on the sky)
/// and view-space normals (RGBA, w unused), `width × height` row-major.
#[derive(Clone, Copy, Debug)]
pub struct EyeBuffers<'a> {
    /// Reversed-Z depth, one value a pixel (0 on the sky).
    pub depth: &'a [f32],
    /// View-space normals, four floats a pixel; w > 0.5 marks a card (an alpha-tested
    /// surface: module docs), as the G-buffer writes it.
    pub normals: &'a [f32],
    /// The eye's field of view (to turn pixels into view rays).
    pub fov: Fov,
    /// The direct light leaving each pixel's surface (RGBA, a unused), for the bounce's
    /// limit; `None`: no bounce.
    pub direct: Option<&'a [f32]>,
    /// The second depth layer (reversed-Z, one value a pixel, 0 where nothing lies behind
    /// the first): `Some` marches the two-layer limit (module docs), `None` the one-layer.
    pub second: Option<&'a [f32]>,
}

/// The limit at one grid pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitPixel {
    /// The depth buffer has a surface here (false on the sky, where `ao` is 1).
    pub hit: bool,
    /// Share of the rays from the surface that leave the radius unblocked by the depth buffer (1 on the sky).
    pub ao: f32,
    /// Standard error of `ao` from its own rays (√(p(1 − p)/(M − 1)); conservative, as
    /// the reference's: stratification makes the real error smaller).
    pub std_error: f32,
    /// The one-bounce irradiance from the blocking surfaces' direct light (linear RGB; 0
    /// without the direct light).
    pub bounce: [f32; 3],
}

/// The limit for every eye on a grid of `stride`, laid out as a reference image's.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenLimit {
    /// Width of the GPU image per eye (pixels).
    pub width: u32,
    /// Height of the GPU image per eye (pixels).
    pub height: u32,
    /// Every `stride`-th GPU pixel in x and y was marched.
    pub stride: u32,
    /// How the limit was marched.
    pub settings: LimitSettings,
    /// Per eye, row-major over [`grid_size`](Self::grid_size).
    pub layers: Vec<Vec<LimitPixel>>,
}

impl ScreenLimit {
    /// Cells per row and column: ⌈width / stride⌉ × ⌈height / stride⌉.
    pub fn grid_size(&self) -> (u32, u32) {
        grid_size((self.width, self.height), self.stride)
    }

    /// The limit at grid cell (i, j) of eye `layer`.
    pub fn get(&self, layer: usize, i: u32, j: u32) -> &LimitPixel {
        &self.layers[layer][(j * self.grid_size().0 + i) as usize]
    }
}

/// Marches the limit for each eye's buffers at `size` pixels per eye (see the module docs).
pub fn screen_space_limit(eyes: &[EyeBuffers], size: (u32, u32), settings: &LimitSettings) -> Result<ScreenLimit> {
    settings.validate()?;
    let pixels = size.0 as usize * size.1 as usize;
    for (layer, eye) in eyes.iter().enumerate() {
        if eye.depth.len() != pixels
            || eye.normals.len() != pixels * 4
            || eye.direct.is_some_and(|d| d.len() != pixels * 4)
            || eye.second.is_some_and(|d| d.len() != pixels)
        {
            return Err(Error::input(format!(
                "screen-space limit: eye {layer} has {} depth and {} normal values for {}×{} pixels",
                eye.depth.len(),
                eye.normals.len(),
                size.0,
                size.1
            )));
        }
        eye.fov.validate()?;
    }
    let (gw, gh) = grid_size(size, settings.stride);
    let rows: Vec<Vec<LimitPixel>> = (0..eyes.len() * gh as usize)
        .into_par_iter()
        .map(|row| {
            let (layer, j) = (row / gh as usize, (row % gh as usize) as u32);
            let marcher = Marcher::new(&eyes[layer], size, settings);
            let mut points = Vec::with_capacity(settings.rays_per_pixel as usize);
            (0..gw)
                .map(|i| {
                    let (x, y) = pixel_of(size, settings.stride, i, j);
                    marcher.pixel(layer as u32, x, y, &mut points)
                })
                .collect()
        })
        .collect();
    let mut layers = vec![Vec::with_capacity((gw * gh) as usize); eyes.len()];
    for (row, pixels) in rows.into_iter().enumerate() {
        layers[row / gh as usize].extend(pixels);
    }
    Ok(ScreenLimit { width: size.0, height: size.1, stride: settings.stride, settings: *settings, layers })
}

/// One eye's depth buffer as the march reads it.
struct Marcher<'a> {
    eye: &'a EyeBuffers<'a>,
    size: (u32, u32),
    settings: &'a LimitSettings,
    /// Frustum tangents (left, right, up, down).
    tangents: [f64; 4],
}

impl<'a> Marcher<'a> {
    fn new(eye: &'a EyeBuffers<'a>, size: (u32, u32), settings: &'a LimitSettings) -> Marcher<'a> {
        Marcher { eye, size, settings, tangents: eye.fov.tangents() }
    }

    /// Reversed-Z depth at a pixel, `None` on the sky (or a value that is no depth).
    fn depth(&self, x: u32, y: u32) -> Option<f64> {
        let d = self.eye.depth[y as usize * self.size.0 as usize + x as usize] as f64;
        (d.is_finite() && d > 0.0).then_some(d)
    }

    /// The view distance of the second layer at a pixel whose first surface lies at
    /// `first` m, `None` where it has no surface behind the first (or none is given), and
    /// where the surface there faces the eye: the first is a sheet, and the span to the
    /// next object is air (its depth's lowest bit, as the peel marks it).
    fn second_distance(&self, x: u32, y: u32, first: f64) -> Option<f64> {
        let second = self.eye.second?[y as usize * self.size.0 as usize + x as usize];
        let (d, faces_eye) = (second as f64, second.to_bits() & 1 == 1);
        let distance = self.settings.near / d;
        (d.is_finite() && d > 0.0 && distance > first && !faces_eye).then_some(distance)
    }

    /// Where the visible surface at a pixel with depth `d` is a card (the G-buffer
    /// normal's w), its plane there: a point on it and its normal (`None` on solid
    /// surfaces, and on a card whose normal is no direction).
    fn card_plane(&self, x: u32, y: u32, d: f64) -> Option<(DVec3, DVec3)> {
        let k = (y as usize * self.size.0 as usize + x as usize) * 4;
        let n = &self.eye.normals[k..k + 4];
        let normal = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64).try_normalize()?;
        (n[3] > 0.5).then(|| (self.position(x, y, d), normal))
    }

    /// The view-space surface point at the centre of pixel (x, y) with depth `d`.
    fn position(&self, x: u32, y: u32, d: f64) -> DVec3 {
        let uv = [(x as f64 + 0.5) / self.size.0 as f64, (y as f64 + 0.5) / self.size.1 as f64];
        vrao_ao::Fov::view_position_from_depth(uv, d, &self.eye.fov, self.settings.near)
    }

    /// The pixel a view-space point projects to, `None` off the image or not in front.
    fn project(&self, q: DVec3) -> Option<(u32, u32)> {
        let distance = -q.z;
        if distance < self.settings.near {
            return None;
        }
        let [l, r, u, d] = self.tangents;
        let (tan_x, tan_y) = (q.x / distance, q.y / distance);
        let (s, t) = ((tan_x - l) / (r - l), (tan_y - u) / (d - u));
        if !(0.0..1.0).contains(&s) || !(0.0..1.0).contains(&t) {
            return None;
        }
        let x = ((s * self.size.0 as f64) as u32).min(self.size.0 - 1);
        let y = ((t * self.size.1 as f64) as u32).min(self.size.1 - 1);
        Some((x, y))
    }

    /// Whether the step from `from` to `q` counts as inside what the depth buffer shows
    /// at Q's pixel (`pixel`, depth `surface_depth`): crossing a card's plane, overlapping
    /// the span to the second layer, or within the thickness behind the surface (module
    /// docs).
    fn inside(&self, from: DVec3, q: DVec3, (qx, qy): (u32, u32), surface_depth: f64) -> bool {
        let first = self.settings.near / surface_depth;
        if let Some((on_card, normal)) = self.card_plane(qx, qy, surface_depth) {
            // A card has no inside: the segment from the previous step to Q crosses its plane.
            return (from - on_card).dot(normal) * (q - on_card).dot(normal) <= 0.0;
        }
        match self.second_distance(qx, qy, first) {
            // The segment overlaps the span between the layers (a span may be thinner
            // than a step).
            Some(back) => (-from.z).min(-q.z) < back && (-from.z).max(-q.z) > first,
            None => {
                let behind = -q.z - first;
                behind > 0.0 && behind < self.settings.thickness
            }
        }
    }

    fn pixel(&self, layer: u32, x: u32, y: u32, points: &mut Vec<(f64, f64)>) -> LimitPixel {
        let Some(d) = self.depth(x, y) else {
            return LimitPixel { hit: false, ao: 1.0, std_error: 0.0, bounce: [0.0; 3] };
        };
        let s = self.settings;
        let p = self.position(x, y, d);
        let towards_eye = (-p).normalize();
        let k = (y as usize * self.size.0 as usize + x as usize) * 4;
        let raw =
            DVec3::new(self.eye.normals[k] as f64, self.eye.normals[k + 1] as f64, self.eye.normals[k + 2] as f64);
        // A normal that is no direction (zero, NaN) falls back to the view direction;
        // one that faces away is flipped, as the reference flips its shading normal.
        let mut n = raw.try_normalize().unwrap_or(towards_eye);
        if n.dot(towards_eye) < 0.0 {
            n = -n;
        }
        let (t, b) = orthonormal_basis(n);
        let mut rng = Rng::new(pixel_seed(layer, x, y) ^ SEED_SALT);
        stratified_points(s.rays_per_pixel, &mut rng, points);
        let tolerance = s.radius * TANGENT_PLANE_TOLERANCE_OF_RADIUS;
        let mut blocked = 0u32;
        let mut bounce = DVec3::ZERO;
        for &(u, v) in points.iter() {
            let (dx, dy) = concentric_disk(u, v);
            let dz = (1.0 - dx * dx - dy * dy).max(0.0).sqrt();
            let dir = (t * dx + b * dy + n * dz).normalize();
            let jitter = rng.next_f64();
            // The ray's previous step (the receiver before the first).
            let mut previous = p;
            for step in 0..s.steps {
                let q = p + dir * (s.radius * (step as f64 + jitter) / s.steps as f64);
                let from = std::mem::replace(&mut previous, q);
                let Some((qx, qy)) = self.project(q) else {
                    break; // off the image (or in front of the near plane): open
                };
                let Some(surface_depth) = self.depth(qx, qy) else {
                    continue; // the sky: nothing in front of Q
                };
                if !self.inside(from, q, (qx, qy), surface_depth) {
                    continue;
                }
                let surface = self.position(qx, qy, surface_depth);
                if (surface - p).dot(n) <= tolerance {
                    continue; // the receiver's own plane (or below it)
                }
                blocked += 1;
                if let Some(direct) = self.eye.direct {
                    // The blocking surface sends its direct light when it faces P.
                    let k = (qy as usize * self.size.0 as usize + qx as usize) * 4;
                    let normals = &self.eye.normals;
                    let normal = DVec3::new(normals[k] as f64, normals[k + 1] as f64, normals[k + 2] as f64);
                    if normal.dot(p - surface) > 0.0 {
                        bounce += DVec3::new(direct[k] as f64, direct[k + 1] as f64, direct[k + 2] as f64);
                    }
                }
                break;
            }
        }
        let m = s.rays_per_pixel as f64;
        let occluded = blocked as f64 / m;
        let std_error =
            if s.rays_per_pixel > 1 { (occluded * (1.0 - occluded) / (m - 1.0)).max(0.0).sqrt() } else { 0.5 };
        let bounce = (bounce * (std::f64::consts::PI / m)).as_vec3().to_array();
        LimitPixel { hit: true, ao: (1.0 - occluded) as f32, std_error: std_error as f32, bounce }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::analytic::{crease_visibility, first_hit, visibility_by_ray_casting, Rect};

    const NEAR: f64 = 0.05;

    fn fov() -> Fov {
        let a = 40f32.to_radians();
        Fov { left: -a, right: a, up: a, down: -a }
    }

    /// Depth and view-space normals of `rects` (given in view space: the eye at the
    /// origin looking down −z) through each pixel centre, as the G-buffer would write them.
    fn rasterise(rects: &[Rect], size: (u32, u32)) -> (Vec<f32>, Vec<f32>) {
        let [l, r, u, d] = fov().tangents();
        let (mut depth, mut normals) = (Vec::new(), Vec::new());
        for y in 0..size.1 {
            for x in 0..size.0 {
                let (s, t) = ((x as f64 + 0.5) / size.0 as f64, (y as f64 + 0.5) / size.1 as f64);
                let dir = DVec3::new(l + (r - l) * s, u + (d - u) * t, -1.0);
                let hit = rects
                    .iter()
                    .filter_map(|rect| rect.hit(DVec3::ZERO, dir).map(|t| (t, rect)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                match hit {
                    Some((t, rect)) => {
                        // dir.z = −1, so t is the view distance.
                        depth.push((NEAR / t) as f32);
                        let mut n = rect.u.cross(rect.v).normalize();
                        if n.dot(dir) > 0.0 {
                            n = -n;
                        }
                        normals.extend([n.x as f32, n.y as f32, n.z as f32, 0.0]);
                    }
                    None => {
                        depth.push(0.0);
                        normals.extend([0.0; 4]);
                    }
                }
            }
        }
        (depth, normals)
    }

    /// The second depth layer of `rects` as the renderer's peel writes it: through each
    /// pixel centre, the nearest surface farther than the first by `separation` of its
    /// distance (reversed-Z, 0 where there is none), marked as a back face (its lowest
    /// bit clear).
    fn second_layer(rects: &[Rect], size: (u32, u32), separation: f64) -> Vec<f32> {
        let [l, r, u, d] = fov().tangents();
        let mut second = Vec::new();
        for y in 0..size.1 {
            for x in 0..size.0 {
                let (s, t) = ((x as f64 + 0.5) / size.0 as f64, (y as f64 + 0.5) / size.1 as f64);
                let dir = DVec3::new(l + (r - l) * s, u + (d - u) * t, -1.0);
                let hits: Vec<f64> = rects.iter().filter_map(|rect| rect.hit(DVec3::ZERO, dir)).collect();
                let first = hits.iter().copied().fold(f64::INFINITY, f64::min);
                let next =
                    hits.iter().copied().filter(|&t| t > first * (1.0 + separation)).fold(f64::INFINITY, f64::min);
                second.push(if next.is_finite() { f32::from_bits(((NEAR / next) as f32).to_bits() & !1) } else { 0.0 });
            }
        }
        second
    }

    fn limit(rects: &[Rect], size: (u32, u32), settings: LimitSettings) -> (ScreenLimit, Vec<f32>) {
        let (depth, normals) = rasterise(rects, size);
        let eye = EyeBuffers { depth: &depth, normals: &normals, fov: fov(), direct: None, second: None };
        (screen_space_limit(&[eye], size, &settings).unwrap(), depth)
    }

    /// A view-space position of grid cell (i, j), from the depth the test wrote.
    fn position(depth: &[f32], size: (u32, u32), stride: u32, i: u32, j: u32) -> DVec3 {
        let (x, y) = pixel_of(size, stride, i, j);
        let uv = [(x as f64 + 0.5) / size.0 as f64, (y as f64 + 0.5) / size.1 as f64];
        vrao_ao::Fov::view_position_from_depth(uv, depth[(y * size.0 + x) as usize] as f64, &fov(), NEAR)
    }

    #[test]
    fn an_open_plane_is_unoccluded_at_every_pixel_even_seen_at_a_grazing_angle() {
        // A floor 1.6 m below the eye, seen from 0° to 40° below the horizon, and a
        // plane tilted about two axes.
        let floor = Rect {
            corner: DVec3::new(-50.0, -1.6, 0.0),
            u: DVec3::new(100.0, 0.0, 0.0),
            v: DVec3::new(0.0, 0.0, -100.0),
        };
        let tilted = Rect {
            corner: DVec3::new(-20.0, -8.0, -3.0),
            u: DVec3::new(40.0, 4.0, -6.0),
            v: DVec3::new(3.0, 30.0, -12.0),
        };
        for (plane, radius) in [(floor, 0.5), (floor, 3.0), (tilted, 0.4)] {
            let size = (48, 40);
            let (limit, _) = limit(&[plane], size, LimitSettings::new(radius, 2, NEAR));
            let hits: Vec<&LimitPixel> = limit.layers[0].iter().filter(|p| p.hit).collect();
            assert!(hits.len() > 200, "{}", hits.len());
            for p in hits {
                assert_eq!(p.ao, 1.0, "r = {radius}: {p:?}");
            }
        }
    }

    /// `rects` given in world space, moved into the view space of an eye at `pose`.
    fn into_view(rects: &[Rect], pose: &vrao_ao::HeadPose) -> Vec<Rect> {
        let view = pose.world_from_local().inverse();
        rects
            .iter()
            .map(|r| Rect {
                corner: view.transform_point3(r.corner),
                u: view.transform_vector3(r.u),
                v: view.transform_vector3(r.v),
            })
            .collect()
    }

    #[test]
    fn a_90_degree_crease_gives_the_analytic_visibility() {
        // The floor y = 0 (z ≥ 0) and a wall z = 0 (y ≥ 0), seen from the open side at 45°
        // down; floor pixels within the middle of the image across (rays of receivers
        // near the side borders leave the image: open, as they must be for a screen-space
        // method, but not analytic).
        let floor =
            Rect { corner: DVec3::new(-20.0, 0.0, 0.0), u: DVec3::new(40.0, 0.0, 0.0), v: DVec3::new(0.0, 0.0, 20.0) };
        let wall =
            Rect { corner: DVec3::new(-20.0, 0.0, 0.0), u: DVec3::new(40.0, 0.0, 0.0), v: DVec3::new(0.0, 20.0, 0.0) };
        let pose = vrao_ao::HeadPose::look_at(DVec3::new(0.0, 1.0, 1.0), DVec3::ZERO).unwrap();
        let (size, stride, radius) = ((96, 96), 2, 0.6);
        let settings = LimitSettings { rays_per_pixel: 256, steps: 48, ..LimitSettings::new(radius, stride, NEAR) };
        let (limit, depth) = limit(&into_view(&[floor, wall], &pose), size, settings);
        let (gw, gh) = limit.grid_size();
        let (mut n, mut sum, mut sum_sq, mut darkest) = (0, 0.0, 0.0, 1.0f64);
        for j in 0..gh {
            for i in 0..gw {
                let p = pose.world_from_local().transform_point3(position(&depth, size, stride, i, j));
                if p.y.abs() > 1e-4 || p.x.abs() > 0.3 || p.z < 1e-3 || p.z > 0.9 {
                    continue;
                }
                let expected = crease_visibility(p.z, radius);
                let got = limit.get(0, i, j).ao as f64;
                darkest = darkest.min(got);
                n += 1;
                sum += got - expected;
                sum_sq += (got - expected).powi(2);
            }
        }
        assert!(n > 50, "{n} floor pixels");
        let (bias, rmse) = (sum / n as f64, (sum_sq / n as f64).sqrt());
        assert!(bias.abs() < 0.02 && rmse < 0.05, "bias {bias}, RMSE {rmse} over {n} pixels");
        assert!(darkest < 0.65, "the crease darkens: {darkest}");
    }

    /// The thin-slab scenes: a floor 3 m below the eye (looking straight down) and the top
    /// of a plate 0.5 m above it covering x > 0.
    fn floor_and_plate_top() -> (Rect, Rect) {
        let floor = Rect {
            corner: DVec3::new(-20.0, -20.0, -3.0),
            u: DVec3::new(40.0, 0.0, 0.0),
            v: DVec3::new(0.0, 40.0, 0.0),
        };
        let plate =
            Rect { corner: DVec3::new(0.0, -20.0, -2.5), u: DVec3::new(20.0, 0.0, 0.0), v: DVec3::new(0.0, 40.0, 0.0) };
        (floor, plate)
    }

    /// Floor receivers within 0.3 m of the plate's edge, near the image centre row.
    fn beside_the_plate(p: DVec3) -> bool {
        (p.z + 3.0).abs() <= 1e-4 && (-0.3..-0.02).contains(&p.x) && p.y.abs() <= 0.5
    }

    /// The grid cells of `depth` (`size`, every `stride`-th pixel) whose receiver lies
    /// beside the plate, each with its visibility within `radius` ray cast in `scene`
    /// (`rays` rays): what the thin-slab tests compare the limits with.
    fn receivers_beside_the_plate(
        depth: &[f32],
        (size, stride): ((u32, u32), u32),
        scene: &[Rect],
        radius: f64,
        rays: usize,
    ) -> Vec<((u32, u32), f64)> {
        let (gw, gh) = grid_size(size, stride);
        let mut receivers = Vec::new();
        for j in 0..gh {
            for i in 0..gw {
                let p = position(depth, size, stride, i, j);
                if beside_the_plate(p) {
                    let truth =
                        visibility_by_ray_casting(p, DVec3::Z, radius, false, rays, |o, d| first_hit(scene, o, d));
                    receivers.push(((i, j), truth));
                }
            }
        }
        assert!(receivers.len() > 10, "{} receivers", receivers.len());
        receivers
    }

    /// The mean of `f` over `receivers`.
    fn mean_over(receivers: &[((u32, u32), f64)], f: impl Fn((u32, u32), f64) -> f64) -> f64 {
        receivers.iter().map(|&(cell, truth)| f(cell, truth)).sum::<f64>() / receivers.len() as f64
    }

    #[test]
    fn a_thin_slab_stops_occluding_behind_itself_within_the_thickness() {
        // The eye looks straight down at a floor 3 m away; a thin horizontal plate 0.5 m
        // above the floor covers x > 0. Receivers on the floor just beside the plate see it
        // overhead on one side. Ray traced, only the rays that cross the plate are blocked;
        // with a thickness above the plate's height the depth buffer makes it a solid block
        // down to the floor, which also blocks the rays passing under it.
        let (floor, plate) = floor_and_plate_top();
        let (size, stride, radius) = ((96, 96), 2, 1.0);
        let base = LimitSettings { rays_per_pixel: 256, steps: 48, ..LimitSettings::new(radius, stride, NEAR) };
        let (thin, depth) = limit(&[floor, plate], size, LimitSettings { thickness: 0.05, ..base });
        let (solid, _) = limit(&[floor, plate], size, LimitSettings { thickness: 10.0, ..base });
        let receivers = receivers_beside_the_plate(&depth, (size, stride), &[floor, plate], radius, 200);
        let thin_error = mean_over(&receivers, |(i, j), truth| (thin.get(0, i, j).ao as f64 - truth).abs());
        let solid_gap = mean_over(&receivers, |(i, j), truth| truth - solid.get(0, i, j).ao as f64);
        assert!(thin_error < 0.03, "thin thickness: mean |limit − truth| {thin_error}");
        assert!(solid_gap > 0.1, "a thickness above the plate's height darkens by only {solid_gap}");
    }

    #[test]
    fn a_second_layer_frees_the_space_under_a_thin_slab_that_one_layer_fills() {
        // The eye looks straight down at a floor 3 m away; a closed slab 4 cm thick (its
        // top 0.5 m above the floor) covers x > 0. One layer sees only the slab's top and
        // takes r / 4 = 0.25 m behind it as solid: floor receivers beside the slab lose
        // the rays that pass under it. The second layer is the slab's underside, so the
        // two-layer limit blocks only the 4 cm the slab fills, as the ray tracer does.
        let (floor, top) = floor_and_plate_top();
        let bottom = Rect { corner: DVec3::new(0.0, -20.0, -2.54), ..top };
        let side = Rect {
            corner: DVec3::new(0.0, -20.0, -2.5),
            u: DVec3::new(0.0, 0.0, -0.04),
            v: DVec3::new(0.0, 40.0, 0.0),
        };
        let scene = [floor, top, bottom, side];
        let (size, stride, radius) = ((96, 96), 2, 1.0);
        let settings = LimitSettings { rays_per_pixel: 256, steps: 24, ..LimitSettings::new(radius, stride, NEAR) };
        let (depth, normals) = rasterise(&scene, size);
        let second = second_layer(&scene, size, 1e-3);
        let one = EyeBuffers { depth: &depth, normals: &normals, fov: fov(), direct: None, second: None };
        let two = EyeBuffers { second: Some(&second), ..one };
        let one = screen_space_limit(&[one], size, &settings).unwrap();
        let two = screen_space_limit(&[two], size, &settings).unwrap();
        let receivers = receivers_beside_the_plate(&depth, (size, stride), &scene, radius, 400);
        let one_error = mean_over(&receivers, |(i, j), truth| (one.get(0, i, j).ao as f64 - truth).abs());
        let one_bias = mean_over(&receivers, |(i, j), truth| one.get(0, i, j).ao as f64 - truth);
        let two_error = mean_over(&receivers, |(i, j), truth| (two.get(0, i, j).ao as f64 - truth).abs());
        assert!(two_error < 0.03, "two layers: mean |limit − truth| {two_error}");
        assert!(one_bias < -0.05, "one layer should over-occlude under the slab: bias {one_bias}");
        assert!(one_error > 2.0 * two_error, "one layer {one_error} against two {two_error}");
    }

    #[test]
    fn a_card_blocks_only_the_rays_that_cross_it_with_one_layer_or_two() {
        // The plate of the thin-slab scenes as a card (alpha-tested, no thickness: a
        // grille's plate), 0.5 m over the floor. One layer would take r / 4 behind it as
        // solid, two layers the whole span down to the floor (the peel's next surface);
        // marked as a card in the normals' w, only the rays crossing it are blocked.
        let (floor, plate) = floor_and_plate_top();
        let scene = [floor, plate];
        let (size, stride, radius) = ((96, 96), 2, 1.0);
        let settings = LimitSettings { rays_per_pixel: 256, steps: 24, ..LimitSettings::new(radius, stride, NEAR) };
        let (depth, solid_normals) = rasterise(&scene, size);
        let second = second_layer(&scene, size, 1e-3);
        let mut card_normals = solid_normals.clone();
        for (n, &d) in card_normals.chunks_exact_mut(4).zip(&depth) {
            n[3] = if d > 0.0 && (NEAR / d as f64 - 2.5).abs() < 1e-3 { 1.0 } else { 0.0 };
        }
        assert!(card_normals.chunks_exact(4).any(|n| n[3] == 1.0) && second.iter().any(|&d| d > 0.0));
        let marches = [
            (&solid_normals, None),
            (&solid_normals, Some(&second[..])),
            (&card_normals, None),
            (&card_normals, Some(&second[..])),
        ]
        .map(|(normals, second)| {
            let eye = EyeBuffers { depth: &depth, normals, fov: fov(), direct: None, second };
            screen_space_limit(&[eye], size, &settings).unwrap()
        });
        let receivers = receivers_beside_the_plate(&depth, (size, stride), &scene, radius, 400);
        let [solid_one, solid_two, card_one, card_two] =
            marches.map(|limit| mean_over(&receivers, |(i, j), truth| limit.get(0, i, j).ao as f64 - truth));
        println!("beside a card 0.5 m up, limit − truth: as solid {solid_one:+.3} (one layer), {solid_two:+.3} (two); as a card {card_one:+.3}, {card_two:+.3}");
        assert!(solid_one < -0.02 && solid_two < -0.1, "as solid, the plate over-occludes: {solid_one}, {solid_two}");
        assert!(card_one.abs() < 0.03 && card_two.abs() < 0.03, "as a card: bias {card_one}, {card_two}");
    }

    #[test]
    fn behind_a_sheet_the_two_layer_limit_keeps_the_thickness() {
        // The plate alone, with no underside: a sheet 0.5 m over the floor. Its second
        // layer is the floor, a face towards the eye (the peel's lowest bit set): the
        // span down to it is air, so the two-layer limit is the one-layer limit there,
        // pixel for pixel. Marked as a back face, the half-metre span reads as solid.
        let (floor, plate) = floor_and_plate_top();
        let scene = [floor, plate];
        let (size, stride, radius) = ((64, 64), 2, 1.0);
        let settings = LimitSettings { rays_per_pixel: 64, steps: 24, ..LimitSettings::new(radius, stride, NEAR) };
        let (depth, normals) = rasterise(&scene, size);
        let back = second_layer(&scene, size, 1e-3);
        let front: Vec<f32> = back.iter().map(|&d| if d > 0.0 { f32::from_bits(d.to_bits() | 1) } else { d }).collect();
        assert!(back.iter().any(|&d| d > 0.0));
        let one = EyeBuffers { depth: &depth, normals: &normals, fov: fov(), direct: None, second: None };
        let [one, front, back] = [None, Some(&front[..]), Some(&back[..])]
            .map(|second| screen_space_limit(&[EyeBuffers { second, ..one }], size, &settings).unwrap());
        assert_eq!(one, front);
        let receivers = receivers_beside_the_plate(&depth, (size, stride), &scene, radius, 100);
        let gap = mean_over(&receivers, |(i, j), _| (one.get(0, i, j).ao - back.get(0, i, j).ao) as f64);
        assert!(gap > 0.02, "the span under the sheet taken as solid darkens by only {gap}");
    }

    #[test]
    fn without_a_surface_behind_the_two_layer_limit_is_the_one_layer_limit() {
        // A crease (floor and wall) has nothing behind either: an all-empty second layer
        // falls back to the thickness at every step, pixel for pixel.
        let floor =
            Rect { corner: DVec3::new(-20.0, 0.0, 0.0), u: DVec3::new(40.0, 0.0, 0.0), v: DVec3::new(0.0, 0.0, 20.0) };
        let wall =
            Rect { corner: DVec3::new(-20.0, 0.0, 0.0), u: DVec3::new(40.0, 0.0, 0.0), v: DVec3::new(0.0, 20.0, 0.0) };
        let pose = vrao_ao::HeadPose::look_at(DVec3::new(0.0, 1.0, 1.0), DVec3::ZERO).unwrap();
        let scene = into_view(&[floor, wall], &pose);
        let size = (40, 36);
        let (depth, normals) = rasterise(&scene, size);
        let second = second_layer(&scene, size, 1e-3);
        assert!(second.iter().all(|&d| d == 0.0));
        let one = EyeBuffers { depth: &depth, normals: &normals, fov: fov(), direct: None, second: None };
        let two = EyeBuffers { second: Some(&second), ..one };
        let settings = LimitSettings::new(0.6, 2, NEAR);
        assert_eq!(
            screen_space_limit(&[one], size, &settings).unwrap(),
            screen_space_limit(&[two], size, &settings).unwrap()
        );
        let short = EyeBuffers { second: Some(&second[..10]), ..one };
        assert!(screen_space_limit(&[short], size, &settings).is_err());
    }

    #[test]
    fn the_sky_is_open_and_mismatched_buffers_are_refused() {
        let size = (8, 6);
        let (depth, normals) = (vec![0.0; 48], vec![0.0; 192]);
        let eye = EyeBuffers { depth: &depth, normals: &normals, fov: fov(), direct: None, second: None };
        let limit = screen_space_limit(&[eye, eye], size, &LimitSettings::new(1.0, 1, NEAR)).unwrap();
        assert!(limit.layers.iter().flatten().all(|p| !p.hit && p.ao == 1.0));
        let short = EyeBuffers { depth: &depth[..40], ..eye };
        assert!(screen_space_limit(&[short], size, &LimitSettings::new(1.0, 1, NEAR)).is_err());
        assert!(screen_space_limit(
            &[eye],
            size,
            &LimitSettings { thickness: 0.0, ..LimitSettings::new(1.0, 1, NEAR) }
        )
        .is_err());
    }
}
