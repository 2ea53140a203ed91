//! The CPU ray tracer that computes ground truth for the GPU occlusion techniques.
//!
//! For every traced pixel of every eye it follows the pixel's centre ray
//! ([`vrao_ao::Eye::pixel_ray`], from the near plane on, as the rasteriser clips) to
//! the first surface and there estimates, with the same M stratified cosine-weighted
//! directions about the shading normal, one ray each:
//!
//! - `ao`: V = 1 − (1/π) ∫ [hit within r] cos θ dω (the test oracle `measure::analytic` computes it in closed form);
//! - `ao_falloff`: the same with each occluded direction weighted by W(d) = max(0, 1 − d/r);
//! - `environment_visible`: ∫ L_env(ω) [no hit within r] cos θ dω from the real lat-long
//!   map ([`Environment::sample`](vrao_render::scene::Environment::sample)), what SSDO approximates;
//! - `bounce`: ∫ [hit within r] L_direct(hit, towards the receiver) cos θ dω, one bounce of
//!   the direct model of `src/render/passes/direct/direct.wgsl` (albedo/π · Σ light irradiance + emission, at
//!   the hit triangle's interpolated albedo (base colour × texture × vertex colour), its
//!   normal-mapped normal (the interpolated vertex normal without a normal texture) and
//!   its emission (× emission texture); zero on a back face), directional
//!   lights shadowed by a shadow ray from the hit (the truth the GPU's shadow maps
//!   approximate; with `--shadows off` on the GPU the difference shows up as error);
//! - `unoccluded`: the environment's SH9 irradiance E(n) the GPU uses (0 without one).
//!
//! Conventions, chosen to match the G-buffer: the shading normal (interpolated vertex
//! normal) is flipped to face the eye; ray origins leave the surface along the geometric
//! normal (flipped to the eye's side) by 64 f32 ulps of the triangle's coordinates, and
//! the surface's own triangle is never hit, so a flat surface never occludes itself (an
//! open plane gives exactly 1). A direction about the shading normal that points below the
//! geometric surface (possible where vertex normals bend away from the faces) counts as
//! occluded at distance 0 (weight 1, no environment, no bounce): the surface itself blocks
//! it. Texture v = 0 is the top row of the image, as [`vrao_render::scene::Mesh::uvs`] says;
//! textures are sampled as their sampler says (transform, wrap per axis, magnification
//! filter) at their full-size level (`geometry.rs`). The normal texture tilts only the
//! light a bounce's sender reflects: the AO, like every estimate's hemisphere, is of the
//! geometry (the interpolated vertex normal), and the occlusion texture is no part of the
//! reference (the bench scores the screen-space AO).
//!
//! Sampling: a jittered ⌊√M⌋² grid (plus uniform points for the rest of M) mapped onto
//! the disk by the concentric map and lifted to the hemisphere, from a PCG32 stream seeded
//! by a hash of (eye layer, pixel), so results are reproducible bit for bit and do not
//! depend on threads or stride. Each pixel states its own noise: `ao_std_error` is the
//! sample standard deviation of the 0/1 occlusion over √M. Stratification makes the actual
//! error smaller than that, so it is a conservative bound, except where all M rays agree
//! (it is then 0, while a sliver of occluder smaller than one stratum may still have been
//! missed); [`ReferenceStats::noise`] is its RMS over the hit pixels.
//!
//! Geometry: every triangle in f32 relative to an f64 anchor at the mean eye position
//! (exact to about 1e-7 of the distance from the eyes wherever the scene sits in the
//! world), in a BVH from the [`obvhs`] crate. Of the two maintained Rust BVH crates,
//! obvhs (0.4) builds with PLOC plus reinsertion, traverses an 8-wide compressed BVH (CWBVH)
//! with SSE, shrinks the ray's tmax as hits are found, takes a closure for the primitive
//! test (so ours is a watertight one, `geometry.rs`) and uses glam 0.34 itself. `bvh`
//! (0.13) is built on nalgebra and hands out candidate primitives (a list, or an iterator
//! in box order) with no ray extent, so a ray of length r cannot stop early. Both build
//! about as fast, and obvhs traces far faster (docs/records/2026-11-29/measurements-in-code.md,
//! reference-bvh). Pixel rows are the work units of a rayon parallel iterator over all
//! cores.
//!
//! [`trace_cached`] keeps results on disk keyed by an FNV-1a hash of everything that
//! determines them; [`ProgressBar`] shows progress on a terminal (indicatif).

mod cache;
mod geometry;
mod progress;
pub mod screen_limit;
mod shading;
#[cfg(test)]
mod tests;

pub use cache::{
    cache_file, cache_key, default_cache_dir, read_cache, trace_cached, trace_cached_visible, write_cache,
    FORMAT_VERSION,
};
pub use progress::ProgressBar;

use crate::error::{Error, Result};
use geometry::SceneGeometry;
use glam::DVec3;
use rayon::prelude::*;
use shading::{pixel_seed, Estimator, Lighting, Rng};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};
use vrao_ao::plug::DEFAULT_NEAR;
use vrao_ao::Eye;
use vrao_render::scene::Scene;

/// Bumped whenever the tracer's results change for the same inputs (it is part of the
/// cache key, so older cache files are recomputed). 3: textures wrap per axis as their
/// sampler says (v repeated, not clamped, by default), filter nearest or linear, move by
/// `KHR_texture_transform`; vertex colours, emission and normal textures.
pub const TRACER_VERSION: u32 = 3;

/// Most rays per pixel accepted.
pub const MAX_RAYS_PER_PIXEL: u32 = 65_536;

/// What to trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Occlusion radius r in metres (finite, > 0).
    pub radius: f64,
    /// Directions M per pixel (1..=[`MAX_RAYS_PER_PIXEL`]); a square number stratifies best.
    pub rays_per_pixel: u32,
    /// Trace every `stride`-th pixel in x and y (≥ 1; 1 traces every pixel).
    pub stride: u32,
    /// Near plane in metres: surfaces closer along the view axis are clipped, as on the GPU.
    pub near: f64,
}

impl ReferenceSettings {
    /// `radius` with 256 rays per pixel, every pixel, the default near plane.
    pub fn new(radius: f64) -> ReferenceSettings {
        ReferenceSettings { radius, rays_per_pixel: 256, stride: 1, near: DEFAULT_NEAR }
    }

    /// Checks every field; the error names the field and value.
    pub fn validate(&self) -> Result<()> {
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(Error::input(format!("reference radius {} must be finite and > 0", self.radius)));
        }
        if !(1..=MAX_RAYS_PER_PIXEL).contains(&self.rays_per_pixel) {
            return Err(Error::input(format!(
                "reference rays per pixel {} must be in 1..={MAX_RAYS_PER_PIXEL}",
                self.rays_per_pixel
            )));
        }
        if self.stride == 0 {
            return Err(Error::input("reference stride must be ≥ 1"));
        }
        if !(self.near.is_finite() && self.near > 0.0) {
            return Err(Error::input(format!("reference near plane {} must be finite and > 0", self.near)));
        }
        Ok(())
    }
}

/// The reference at one pixel. On the sky (`hit` false) the occlusion values are 1 and
/// everything else 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferencePixel {
    /// A surface was hit through this pixel.
    pub hit: bool,
    /// View-space depth (−z in metres, what the depth buffer encodes as near / depth); 0 on the sky.
    pub depth: f32,
    /// Cosine-weighted visibility within r (1 = unoccluded).
    pub ao: f32,
    /// The same with each occluded direction weighted by 1 − d/r (linear falloff).
    pub ao_falloff: f32,
    /// Standard error of `ao` as estimated from its own samples (conservative, see the module docs).
    pub ao_std_error: f32,
    /// Linear RGB irradiance from the environment through the unoccluded directions.
    pub environment_visible: [f32; 3],
    /// Linear RGB one-bounce irradiance from surfaces within r.
    pub bounce: [f32; 3],
    /// Linear RGB irradiance of the whole environment (SH9), for normalising.
    pub unoccluded: [f32; 3],
    /// Standard errors of the ambient light (`environment_visible` + `bounce`, from the
    /// same rays) as estimated from its samples: r, g, b and luminance
    /// (`metrics::luminance`); what the bench takes out of the ambient light's error.
    pub ambient_std_error: [f32; 4],
    /// The same for `bounce` alone.
    pub bounce_std_error: [f32; 4],
}

impl ReferencePixel {
    /// A pixel that sees the sky: no hit, AO 1, no light.
    pub const SKY: ReferencePixel = ReferencePixel {
        hit: false,
        depth: 0.0,
        ao: 1.0,
        ao_falloff: 1.0,
        ao_std_error: 0.0,
        environment_visible: [0.0; 3],
        bounce: [0.0; 3],
        unoccluded: [0.0; 3],
        ambient_std_error: [0.0; 4],
        bounce_std_error: [0.0; 4],
    };
}

/// What a trace cost and how noisy it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceStats {
    /// Primary and occlusion rays traced.
    pub rays: u64,
    /// Wall-clock seconds of the whole trace, BVH build included.
    pub seconds: f64,
    /// Of which building the BVH.
    pub build_seconds: f64,
    /// `rays / seconds`.
    pub rays_per_second: f64,
    /// RMS of `ao_std_error` over the hit pixels (0 when none is hit).
    pub noise: f64,
    /// Pixels (over all eyes) that hit a surface.
    pub hit_pixels: u64,
    /// True when the image was read from a cache file (the other numbers are the original trace's).
    pub from_cache: bool,
}

/// Reference values for a grid of pixels of each eye.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceImage {
    /// Size of the GPU image per eye.
    pub width: u32,
    /// Size of the GPU image per eye (pixels).
    pub height: u32,
    /// Every `stride`-th GPU pixel in x and y was traced.
    pub stride: u32,
    /// Per eye (layer 0 = left, 1 = right): a row-major grid of
    /// [`grid_size`](Self::grid_size) cells; cell (i, j) is the GPU pixel [`pixel_of`](Self::pixel_of)(i, j).
    pub layers: Vec<Vec<ReferencePixel>>,
    /// How the trace went: time, rays, noise, cache.
    pub stats: ReferenceStats,
}

impl ReferenceImage {
    /// Cells per row and column: ⌈width / stride⌉ × ⌈height / stride⌉.
    pub fn grid_size(&self) -> (u32, u32) {
        grid_size((self.width, self.height), self.stride)
    }

    /// The GPU pixel of grid cell (i, j): (i·stride + stride/2, j·stride + stride/2),
    /// clamped to the image.
    pub fn pixel_of(&self, i: u32, j: u32) -> (u32, u32) {
        pixel_of((self.width, self.height), self.stride, i, j)
    }

    /// The cell of `layer` at grid (i, j).
    pub fn get(&self, layer: usize, i: u32, j: u32) -> &ReferencePixel {
        let (gw, _) = self.grid_size();
        &self.layers[layer][(j * gw + i) as usize]
    }

    /// This image with every cell whose pixel the lens hides turned to sky, so that the
    /// scores count only what the eye can see. `coverage` holds each layer's pixels (0:
    /// hidden; `None`: all shown), `width` × `height` row by row.
    pub fn visible_only(&self, coverage: &[Option<Vec<u8>>]) -> ReferenceImage {
        let mut image = self.clone();
        let (gw, gh) = self.grid_size();
        for (layer, cells) in image.layers.iter_mut().enumerate() {
            let Some(Some(shown)) = coverage.get(layer) else { continue };
            for j in 0..gh {
                for i in 0..gw {
                    let (x, y) = self.pixel_of(i, j);
                    if shown[(y * self.width + x) as usize] == 0 {
                        cells[(j * gw + i) as usize] = ReferencePixel::SKY;
                    }
                }
            }
        }
        image
    }
}

/// Progress of a trace, reported from the calling thread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Pixels finished, of `total` (over all eyes).
    pub done: usize,
    /// Pixels to trace over all eyes.
    pub total: usize,
    /// Rays traced so far.
    pub rays: u64,
    /// Time since the trace started.
    pub elapsed: Duration,
}

pub(crate) fn grid_size(size: (u32, u32), stride: u32) -> (u32, u32) {
    (size.0.div_ceil(stride), size.1.div_ceil(stride))
}

pub(crate) fn pixel_of(size: (u32, u32), stride: u32, i: u32, j: u32) -> (u32, u32) {
    let at = |k: u32, n: u32| (k as u64 * stride as u64 + stride as u64 / 2).min(n as u64 - 1) as u32;
    (at(i, size.0), at(j, size.1))
}

/// Traces the reference for `eyes` (one layer each) at `size` pixels per eye.
///
/// `progress` is called from the calling thread a few times a second while rayon's
/// threads trace, and once at the end with `done == total`.
pub fn trace(
    scene: &Scene,
    eyes: &[Eye],
    size: (u32, u32),
    settings: &ReferenceSettings,
    progress: &mut dyn FnMut(Progress),
) -> Result<ReferenceImage> {
    trace_visible(scene, eyes, size, settings, None, progress)
}

/// [`trace`] of only the pixels the lens shows: where `coverage` (each eye's pixels, 0
/// hidden, as [`ReferenceImage::visible_only`] takes it) hides a cell's pixel, the cell is
/// sky and no ray is traced. A coverage of the wrong size is `Error::Input`.
pub fn trace_visible(
    scene: &Scene,
    eyes: &[Eye],
    size: (u32, u32),
    settings: &ReferenceSettings,
    coverage: Option<&[Option<Vec<u8>>]>,
    progress: &mut dyn FnMut(Progress),
) -> Result<ReferenceImage> {
    check_trace(eyes, size, settings)?;
    let pixels = size.0 as usize * size.1 as usize;
    if let Some(c) = coverage.into_iter().flatten().flatten().find(|c| c.len() != pixels) {
        return Err(Error::input(format!(
            "a visibility coverage of {} pixels for a {}×{} image",
            c.len(),
            size.0,
            size.1
        )));
    }
    let start = Instant::now();
    let anchor = eyes.iter().map(|e| e.pose.position).sum::<DVec3>() / eyes.len() as f64;
    let geometry = SceneGeometry::build(scene, anchor)?;
    let build_seconds = start.elapsed().as_secs_f64();
    let lighting = Lighting::new(scene, anchor);
    let estimator = Estimator {
        geometry: &geometry,
        lighting: &lighting,
        radius: settings.radius,
        rays_per_pixel: settings.rays_per_pixel,
    };
    let tracer = RowTracer {
        eyes,
        anchor,
        size,
        settings,
        estimator: &estimator,
        grid: grid_size(size, settings.stride),
        coverage,
    };
    let (gw, gh) = tracer.grid;
    let rows_total = eyes.len() * gh as usize;
    let rows_done = AtomicUsize::new(0);
    let rays = AtomicU64::new(0);
    let trace_row = |row: usize| {
        let (pixels, row_rays) = tracer.row(row);
        rays.fetch_add(row_rays, Ordering::Relaxed);
        rows_done.fetch_add(1, Ordering::Relaxed);
        pixels
    };
    let report = || Progress {
        done: rows_done.load(Ordering::Relaxed) * gw as usize,
        total: rows_total * gw as usize,
        rays: rays.load(Ordering::Relaxed),
        elapsed: start.elapsed(),
    };
    let rows = in_parallel_reporting(rows_total, trace_row, || progress(report()));
    progress(report());

    let mut layers: Vec<Vec<ReferencePixel>> = vec![Vec::with_capacity((gw * gh) as usize); eyes.len()];
    for (row, pixels) in rows.into_iter().enumerate() {
        layers[row / gh as usize].extend(pixels);
    }
    let stats = ReferenceStats::of(&layers, rays.into_inner(), start.elapsed().as_secs_f64(), build_seconds);
    Ok(ReferenceImage { width: size.0, height: size.1, stride: settings.stride, layers, stats })
}

/// Refuses what cannot be traced: bad settings, an empty image, no eye, an eye with an
/// invalid field of view or a pose that is not finite.
fn check_trace(eyes: &[Eye], size: (u32, u32), settings: &ReferenceSettings) -> Result<()> {
    settings.validate()?;
    if size.0 == 0 || size.1 == 0 {
        return Err(Error::input(format!("reference image size {}×{} is empty", size.0, size.1)));
    }
    if eyes.is_empty() {
        return Err(Error::input("reference needs at least one eye"));
    }
    for eye in eyes {
        eye.fov.validate()?;
        if !eye.pose.position.is_finite() || !eye.pose.orientation.is_finite() {
            return Err(Error::input(format!("eye pose {:?} is not finite", eye.pose)));
        }
    }
    Ok(())
}

/// `work(0..count)` on rayon's threads, in order, while this thread calls `report` a few
/// times a second until the results arrive. A panic in `work` is raised here.
fn in_parallel_reporting<T: Send>(
    count: usize,
    work: impl Fn(usize) -> T + Sync + Send,
    mut report: impl FnMut(),
) -> Vec<T> {
    std::thread::scope(|s| {
        let (sender, receiver) = std::sync::mpsc::channel();
        let worker = s.spawn(move || {
            let results = (0..count).into_par_iter().map(work).collect::<Vec<_>>();
            // The receiver outlives this thread (it joins it below).
            let _ = sender.send(results);
        });
        loop {
            report();
            match receiver.recv_timeout(Duration::from_millis(100)) {
                Ok(results) => break results,
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
                // The worker panicked before sending: re-raise its panic here.
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => match worker.join() {
                    Err(panic) => std::panic::resume_unwind(panic),
                    Ok(()) => unreachable!("the worker sends before it returns"),
                },
            }
        }
    })
}

/// Traces rows of the reference grid: row `r` is grid row `r % gh` of eye `r / gh`.
struct RowTracer<'a> {
    eyes: &'a [Eye],
    /// The f64 origin the geometry is stored relative to.
    anchor: DVec3,
    size: (u32, u32),
    settings: &'a ReferenceSettings,
    estimator: &'a Estimator<'a>,
    /// Grid cells across and down.
    grid: (u32, u32),
    /// Each eye's pixels the lens shows (0: hidden, traced as sky), or `None`.
    coverage: Option<&'a [Option<Vec<u8>>]>,
}

impl RowTracer<'_> {
    /// The pixels of one row and the rays traced for them.
    fn row(&self, row: usize) -> (Vec<ReferencePixel>, u64) {
        let (gw, gh) = self.grid;
        let (layer, j) = (row / gh as usize, (row % gh as usize) as u32);
        let eye = Eye { pose: self.eyes[layer].pose.sanitized(), ..self.eyes[layer] };
        let mut points = Vec::with_capacity(self.settings.rays_per_pixel as usize);
        let mut rays = 0u64;
        let pixels = (0..gw)
            .map(|i| {
                let (x, y) = pixel_of(self.size, self.settings.stride, i, j);
                let shown = self.coverage.and_then(|c| c.get(layer)).and_then(|c| c.as_ref());
                if shown.is_some_and(|shown| shown[(y * self.size.0 + x) as usize] == 0) {
                    return ReferencePixel::SKY;
                }
                let (pixel, pixel_rays) = self.pixel(&eye, layer, (x, y), &mut points);
                rays += pixel_rays;
                pixel
            })
            .collect();
        (pixels, rays)
    }

    /// The reference at pixel (x, y) of `eye` (layer `layer`) and the rays it took;
    /// `points` is scratch space for the estimator.
    fn pixel(
        &self,
        eye: &Eye,
        layer: usize,
        (x, y): (u32, u32),
        points: &mut Vec<(f64, f64)>,
    ) -> (ReferencePixel, u64) {
        let geometry = self.estimator.geometry;
        let origin = (eye.pose.position - self.anchor).as_vec3();
        let forward = eye.pose.orientation * DVec3::NEG_Z;
        let dir = vrao_ao::Eye::pixel_ray(eye, self.size, (x as f64 + 0.5, y as f64 + 0.5));
        let along = dir.dot(forward);
        let dir32 = dir.as_vec3();
        let tmin = (self.settings.near / along) as f32;
        let Some(hit) = geometry.closest(origin, dir32, tmin, f32::INFINITY, u32::MAX) else {
            return (ReferencePixel::SKY, 1);
        };
        let surface = geometry.surface(&hit);
        let mut rng = Rng::new(pixel_seed(layer as u32, x, y));
        let e = self.estimator.estimate(&surface, dir32, &mut rng, points);
        let rgb = |c: [f64; 3]| c.map(|v| if v.is_finite() { v as f32 } else { 0.0 });
        let pixel = ReferencePixel {
            hit: true,
            depth: (hit.t as f64 * along) as f32,
            ao: e.ao as f32,
            ao_falloff: e.ao_falloff as f32,
            ao_std_error: e.ao_std_error as f32,
            environment_visible: rgb(e.environment_visible),
            bounce: rgb(e.bounce),
            unoccluded: rgb(e.unoccluded),
            ambient_std_error: e.ambient_std_error.map(|v| if v.is_finite() { v as f32 } else { 0.0 }),
            bounce_std_error: e.bounce_std_error.map(|v| if v.is_finite() { v as f32 } else { 0.0 }),
        };
        // The primary ray and the estimator's.
        (pixel, 1 + e.rays)
    }
}

impl ReferenceStats {
    /// The statistics of a finished trace of `layers`: `rays` traced in `seconds`, of
    /// which `build_seconds` built the BVH.
    fn of(layers: &[Vec<ReferencePixel>], rays: u64, seconds: f64, build_seconds: f64) -> ReferenceStats {
        let (mut hit_pixels, mut variance) = (0u64, 0f64);
        for p in layers.iter().flatten().filter(|p| p.hit) {
            hit_pixels += 1;
            variance += (p.ao_std_error as f64).powi(2);
        }
        ReferenceStats {
            rays,
            seconds,
            build_seconds,
            rays_per_second: if seconds > 0.0 { rays as f64 / seconds } else { 0.0 },
            noise: if hit_pixels > 0 { (variance / hit_pixels as f64).sqrt() } else { 0.0 },
            hit_pixels,
            from_cache: false,
        }
    }
}

/// The world-space point a hit pixel of `image` sees: along the pixel's centre ray to its
/// recorded depth. `None` on the sky.
pub fn world_position(image: &ReferenceImage, eye: &Eye, layer: usize, i: u32, j: u32) -> Option<DVec3> {
    let p = image.get(layer, i, j);
    if !p.hit {
        return None;
    }
    let (x, y) = image.pixel_of(i, j);
    let eye = Eye { pose: eye.pose.sanitized(), ..*eye };
    let dir = vrao_ao::Eye::pixel_ray(&eye, (image.width, image.height), (x as f64 + 0.5, y as f64 + 0.5));
    let along = dir.dot(eye.pose.orientation * DVec3::NEG_Z);
    Some(eye.pose.position + dir * (p.depth as f64 / along))
}
