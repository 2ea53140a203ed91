//! Distant lighting: an equirectangular (lat-long) radiance map plus its irradiance as
//! nine spherical-harmonic coefficients (Ramamoorthi & Hanrahan 2001, "An Efficient
//! Representation for Irradiance Environment Maps").
//!
//! Layout: texel (x, y) has its centre at u = (x + 0.5) / width, v = (y + 0.5) / height.
//! Row 0 is straight up (+Y) and the last row straight down; v maps linearly to the polar
//! angle θ = π v from +Y. u maps to the azimuth φ = 2π (u − 0.5) turning from −Z towards
//! +X: the image centre is −Z (ahead of a default view), u = 0.75 is +X (to its right),
//! and the left/right edges are +Z. This is how a panorama is viewed from inside, so the
//! usual HDRIs (Poly Haven, three.js examples) appear the right way round.

use glam::Vec3;
use std::f32::consts::{PI, TAU};
use std::path::Path;
use vrao_ao::{Error, Result};

/// Largest finite f16: texels are uploaded as `Rgba16Float`, so anything above would
/// become infinity on the GPU.
pub const MAX_RADIANCE: f32 = 65504.0;

/// Distant light as an equirectangular radiance map with its SH9 irradiance (layout in the module docs).
#[derive(Clone, Debug)]
pub struct Environment {
    /// Texels per row (azimuth).
    pub width: u32,
    /// Rows (polar angle, top row straight up).
    pub height: u32,
    /// Linear RGB radiance, row-major from the top (+Y) row; finite, in [0, `MAX_RADIANCE`].
    /// Not scaled by `intensity`.
    pub texels: Vec<[f32; 3]>,
    /// Multiplier applied to everything this map emits (by `sample` and `irradiance`, and
    /// by the renderer when it reads `texels` or `irradiance_sh`).
    pub intensity: f32,
    /// Irradiance coefficients E_lm = A_l L_lm in the order (0,0), (1,−1), (1,0), (1,1),
    /// (2,−2), (2,−1), (2,0), (2,1), (2,2) for the basis in [`sh9_basis`]; the cosine
    /// convolution is already applied, `intensity` is not.
    pub irradiance_sh: [Vec3; 9],
}

impl Environment {
    /// An environment from raw texels. Non-finite or negative texels become 0, +∞ and
    /// values above `MAX_RADIANCE` become `MAX_RADIANCE`, so a stray 1e30 or NaN in an
    /// HDR file cannot reach the GPU. `intensity` must be finite and ≥ 0.
    pub fn from_texels(width: u32, height: u32, mut texels: Vec<[f32; 3]>, intensity: f32) -> Result<Environment> {
        if width == 0 || height == 0 || texels.len() as u64 != width as u64 * height as u64 {
            return Err(Error::input(format!(
                "environment of {width}×{height} texels needs {} values, got {}",
                width as u64 * height as u64,
                texels.len()
            )));
        }
        if !intensity.is_finite() || intensity < 0.0 {
            return Err(Error::input(format!("environment intensity {intensity} must be finite and ≥ 0")));
        }
        for texel in &mut texels {
            for c in texel.iter_mut() {
                *c = match *c {
                    c if c == f32::INFINITY => MAX_RADIANCE,
                    c if c.is_nan() || c < 0.0 => 0.0,
                    c => c.min(MAX_RADIANCE),
                };
            }
        }
        let mut env = Environment { width, height, texels, intensity, irradiance_sh: [Vec3::ZERO; 9] };
        env.irradiance_sh = env.project_irradiance();
        Ok(env)
    }

    /// Loads a Radiance `.hdr` lat-long map (a regular file of at most
    /// [`crate::files::MAX_FILE_BYTES`], sides up to [`super::limits::MAX_TEXTURE_SIDE`]).
    pub fn load_hdr(path: &Path, intensity: f32) -> Result<Environment> {
        let bytes = crate::files::read_regular_file(path, crate::files::MAX_FILE_BYTES)?;
        let decoder = image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes))
            .map_err(|e| Error::in_file(path, format!("not a valid Radiance HDR file: {e}")))?;
        // From the header, before the texels are allocated.
        let (width, height) = image::ImageDecoder::dimensions(&decoder);
        if let Some(trouble) = super::limits::texture_side_trouble(width, height) {
            return Err(Error::in_file(path, format!("environment map of {trouble}")));
        }
        let image = image::DynamicImage::from_decoder(decoder)
            .map_err(|e| Error::in_file(path, format!("cannot decode HDR environment: {e}")))?
            .into_rgb32f();
        let (width, height) = image.dimensions();
        let texels = image.pixels().map(|p| p.0).collect();
        Environment::from_texels(width, height, texels, intensity).map_err(|e| Error::in_file(path, e.to_string()))
    }

    /// A procedural daylight sky of 128×64 texels: pale blue-grey at the horizon, bluer
    /// towards the zenith, a dim brownish-grey ground below. There is no sun disc: the
    /// scene's directional light is the sun, and a disc would count it twice.
    pub fn default_sky() -> Environment {
        let (width, height) = (128u32, 64u32);
        let horizon = Vec3::new(0.75, 0.8, 0.9) * 0.6;
        let zenith = Vec3::new(0.3, 0.45, 0.8) * 0.6;
        let ground = Vec3::new(0.22, 0.2, 0.18);
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let up = direction((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32).y;
                let colour = if up >= 0.0 {
                    horizon.lerp(zenith, up.sqrt())
                } else {
                    // Fade into the ground over the first ~6° so the horizon is not a step.
                    horizon.lerp(ground, (-up * 10.0).min(1.0))
                };
                colour.to_array()
            })
            .collect();
        // The inputs are fixed, finite and in range, so this cannot fail.
        Environment::from_texels(width, height, texels, 1.0).expect("the default sky is valid")
    }

    /// Radiance (times `intensity`) arriving from `dir` (need not be unit length; a zero
    /// or non-finite direction reads straight up). Bilinear, wrapping around in azimuth.
    pub fn sample(&self, dir: Vec3) -> Vec3 {
        let d = dir.try_normalize().unwrap_or(Vec3::Y);
        let u = d.x.atan2(-d.z) / TAU + 0.5;
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        let (w, h) = (self.width as i64, self.height as i64);
        let x = u * w as f32 - 0.5;
        let y = (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |x: i64, y: i64| Vec3::from(self.texels[(y.min(h - 1) * w + x.rem_euclid(w)) as usize]);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = texel(x0, y0).lerp(texel(x0 + 1, y0), fx);
        let bottom = texel(x0, y0 + 1).lerp(texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy) * self.intensity
    }

    /// `irradiance_sh` times `intensity`: evaluate with [`sh9_basis`] to get E(n) (clamp
    /// the result at 0, as [`Environment::irradiance`] does). The shaders take it as
    /// [`Environment::irradiance_quadratic`].
    pub fn irradiance_sh_scaled(&self) -> [Vec3; 9] {
        self.irradiance_sh.map(|c| c * self.intensity)
    }

    /// Radiance (times `intensity`) as nine SH coefficients, low-passed to its first two
    /// bands (weights 1, 0.75, 0: band 1 as a three-band Hann window has it, band 2
    /// dropped): the pre-filtered environment SSDO reads once per sample direction
    /// (Ritschel et al. 2009 ask for a pre-smoothed map). A linear function of the direction, so SSDO
    /// sums it from the directions' first moments alone (the band-2 moments cost SSDO a
    /// noticeable share of its time, docs/records/2026-11-29/measurements-in-code.md, sh-band-2; the window
    /// gave band 2 only a quarter weight anyway). Evaluate with [`sh9_basis`] and clamp at 0.
    pub fn radiance_sh_prefiltered(&self) -> [Vec3; 9] {
        vrao_ao::plug::prefiltered_radiance(&self.irradiance_sh_scaled())
    }

    /// The pre-filtered radiance of [`Environment::radiance_sh_prefiltered`] in the
    /// quadratic layout of [`sh9_quadratic`], whose second-order rows (4..10) are zero:
    /// a sum of L over weighted directions needs only Σc and Σcω (SSDO).
    pub fn radiance_quadratic(&self) -> [Vec3; 10] {
        sh9_quadratic(&self.radiance_sh_prefiltered())
    }

    /// The irradiance of [`Environment::irradiance_sh_scaled`] as a quadratic polynomial
    /// in the unit normal (see [`sh9_quadratic`]; clamp the result at 0).
    pub fn irradiance_quadratic(&self) -> [Vec3; 10] {
        sh9_quadratic(&self.irradiance_sh_scaled())
    }

    /// Irradiance E(n) (times `intensity`) on a surface with unit normal `n` that sees the
    /// whole environment: ∫ L(ω) max(0, n·ω) dω, so a constant radiance L gives π L.
    /// Clamped at 0 because nine coefficients can ring slightly negative opposite a sun.
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        let basis = sh9_basis(n.try_normalize().unwrap_or(Vec3::Y));
        let e: Vec3 = self.irradiance_sh_scaled().iter().zip(basis).map(|(c, y)| *c * y).sum();
        e.max(Vec3::ZERO)
    }

    /// Projects the radiance onto nine SH functions, weighting each texel by its exact
    /// solid angle (2π/width)·(cos θ_top − cos θ_bottom), then applies the clamped-cosine
    /// kernel A_0 = π, A_1 = 2π/3, A_2 = π/4.
    fn project_irradiance(&self) -> [Vec3; 9] {
        const KERNEL: [f32; 9] =
            [PI, TAU / 3.0, TAU / 3.0, TAU / 3.0, PI / 4.0, PI / 4.0, PI / 4.0, PI / 4.0, PI / 4.0];
        let (w, h) = (self.width as usize, self.height as usize);
        // Accumulate in f64: a 1k map sums half a million terms.
        let mut sum = [[0f64; 3]; 9];
        let theta = |row: usize| std::f64::consts::PI * row as f64 / h as f64;
        for y in 0..h {
            let solid_angle = std::f64::consts::TAU / w as f64 * (theta(y).cos() - theta(y + 1).cos());
            for x in 0..w {
                let dir = direction((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let radiance = self.texels[y * w + x];
                for (acc, basis) in sum.iter_mut().zip(sh9_basis(dir)) {
                    let weight = basis as f64 * solid_angle;
                    for c in 0..3 {
                        acc[c] += radiance[c] as f64 * weight;
                    }
                }
            }
        }
        std::array::from_fn(|i| Vec3::from_array(sum[i].map(|c| c as f32)) * KERNEL[i])
    }
}

/// The unit direction at lat-long coordinates (u, v) in [0, 1]² (see the module docs).
pub fn direction(u: f32, v: f32) -> Vec3 {
    let (theta, phi) = (PI * v, TAU * (u - 0.5));
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// The nine real spherical harmonics up to band 2 at unit direction `d`.
pub fn sh9_basis(d: Vec3) -> [f32; 9] {
    let Vec3 { x, y, z } = d;
    [
        0.282_095,
        0.488_603 * y,
        0.488_603 * z,
        0.488_603 * x,
        1.092_548 * x * y,
        1.092_548 * y * z,
        0.315_392 * (3.0 * z * z - 1.0),
        1.092_548 * x * z,
        0.546_274 * (x * x - y * y),
    ]
}

pub(crate) use vrao_ao::plug::sh9_quadratic;

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;
    use vrao_ao::plug::quadratic_in_view;

    fn uniform(width: u32, height: u32, radiance: f32) -> Environment {
        let texels = vec![[radiance; 3]; (width * height) as usize];
        Environment::from_texels(width, height, texels, 1.0).unwrap()
    }

    fn directions() -> impl Iterator<Item = Vec3> {
        (0..50).map(|i| direction((i as f32 * 0.618_034).fract(), (i as f32 + 0.5) / 50.0))
    }

    /// A 32×16 map with a different pattern per channel: every SH band is non-zero.
    fn patterned() -> Environment {
        let texels: Vec<[f32; 3]> =
            (0..32 * 16).map(|i| [(i % 7) as f32, (i % 5) as f32 * 0.3, (i % 11) as f32]).collect();
        Environment::from_texels(32, 16, texels, 1.5).unwrap()
    }

    /// An eye's orientation turned about all three axes.
    fn turned_view() -> Mat3 {
        Mat3::from_quat(glam::Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.2))
    }

    /// A quadratic of `sh9_quadratic`'s layout evaluated at direction `d`.
    fn eval_quadratic(q: &[Vec3; 10], d: Vec3) -> Vec3 {
        let Vec3 { x, y, z } = d;
        let monomials = [1.0, x, y, z, x * x, y * y, z * z, x * y, x * z, y * z];
        q.iter().zip(monomials).map(|(c, m)| *c * m).sum()
    }

    #[test]
    fn quadratic_form_equals_the_sh_expansion() {
        let env = patterned();
        let (sh, q) = (env.radiance_sh_prefiltered(), env.radiance_quadratic());
        for dir in [Vec3::X, -Vec3::Z, Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::new(-0.7, 0.1, 0.2).normalize()] {
            let from_sh: Vec3 = sh.iter().zip(sh9_basis(dir)).map(|(c, y)| *c * y).sum();
            let from_q = eval_quadratic(&q, dir);
            assert!((from_sh - from_q).abs().max_element() < 1e-4 * (1.0 + from_sh.abs().max_element()), "{dir}");
        }
    }

    #[test]
    fn view_space_quadratic_is_the_world_one_turned() {
        let env = patterned();
        let world_from_view = turned_view();
        let (world, view) = (env.radiance_quadratic(), quadratic_in_view(&env.radiance_quadratic(), world_from_view));
        let irradiance = quadratic_in_view(&env.irradiance_quadratic(), world_from_view);
        for v in [Vec3::X, -Vec3::Z, Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::new(-0.7, 0.1, 0.2).normalize()] {
            let (expected, got) = (eval_quadratic(&world, world_from_view * v), eval_quadratic(&view, v));
            assert!(
                (expected - got).abs().max_element() < 1e-4 * (1.0 + expected.abs().max_element()),
                "{v}: {expected} vs {got}"
            );
            let (expected, got) = (env.irradiance(world_from_view * v), eval_quadratic(&irradiance, v).max(Vec3::ZERO));
            assert!(
                (expected - got).abs().max_element() < 1e-4 * (1.0 + expected.abs().max_element()),
                "E {v}: {expected} vs {got}"
            );
        }
    }

    #[test]
    fn prefiltered_radiance_is_linear_in_the_direction() {
        // SSDO (irradiance.wgsl `linear_sum`) reads only rows 0..4: the rest must vanish,
        // in the world and turned into a view.
        let env = patterned();
        for q in [env.radiance_quadratic(), quadratic_in_view(&env.radiance_quadratic(), turned_view())] {
            assert!(q[4..].iter().all(|c| c.abs().max_element() < 1e-6), "{q:?}");
            assert!(q[1..4].iter().any(|c| c.abs().max_element() > 1e-3), "the map's gradient survives: {q:?}");
        }
    }

    #[test]
    fn prefiltered_radiance_of_a_constant_sky_is_that_constant() {
        let env = Environment::from_texels(16, 8, vec![[0.5, 1.0, 2.0]; 128], 2.0).unwrap();
        let sh = env.radiance_sh_prefiltered();
        for dir in [Vec3::X, Vec3::Y, -Vec3::Y, Vec3::new(0.3, -0.5, 0.8).normalize()] {
            let l: Vec3 = sh.iter().zip(sh9_basis(dir)).map(|(c, y)| *c * y).sum();
            // Within 1 %: the SH projection of a 16×8 map is a coarse quadrature.
            let expected = Vec3::new(1.0, 2.0, 4.0);
            assert!(((l - expected) / expected).abs().max_element() < 0.01, "{dir}: {l}");
        }
    }

    #[test]
    fn constant_radiance_gives_pi_everywhere() {
        let env = uniform(64, 32, 1.0);
        for n in directions() {
            let e = env.irradiance(n);
            assert!((e - Vec3::splat(PI)).abs().max_element() < 0.01 * PI, "E({n}) = {e}");
        }
        let brighter = Environment { intensity: 2.0, ..env };
        assert!((brighter.irradiance(Vec3::X).x - 2.0 * PI).abs() < 0.02 * PI);
    }

    #[test]
    fn upper_hemisphere_light_lights_upward_faces() {
        let (w, h) = (64u32, 32u32);
        let texels = (0..w * h).map(|i| if i < w * h / 2 { [1.0; 3] } else { [0.0; 3] }).collect();
        let env = Environment::from_texels(w, h, texels, 1.0).unwrap();
        let (up, down) = (env.irradiance(Vec3::Y).x, env.irradiance(Vec3::NEG_Y).x);
        // Band 2 of a hemisphere step vanishes, so nine coefficients are exact here up to
        // the texel discretisation: π up, 0 down, π/2 sideways.
        assert!((up - PI).abs() < 0.1 && down < 0.1, "up {up}, down {down}");
        let side = env.irradiance(Vec3::X).x;
        assert!((side - PI / 2.0).abs() < 0.05, "a vertical face sees half: {side}");
    }

    #[test]
    fn direction_and_sample_agree() {
        let (w, h) = (16u32, 8u32);
        let texels = (0..w * h).map(|i| [i as f32, 0.0, 0.0]).collect();
        let env = Environment::from_texels(w, h, texels, 1.0).unwrap();
        for y in 0..h {
            for x in 0..w {
                let d = direction((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                assert!((env.sample(d).x - (y * w + x) as f32).abs() < 1e-3, "texel ({x}, {y})");
            }
        }
        assert!(direction(0.5, 0.5).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(direction(0.75, 0.5).abs_diff_eq(Vec3::X, 1e-6));
        assert!(direction(0.3, 0.0).abs_diff_eq(Vec3::Y, 1e-6));
        assert!(env.sample(Vec3::ZERO).is_finite() && env.sample(Vec3::NAN).is_finite());
    }

    #[test]
    fn extreme_texels_are_clamped() {
        let texels = vec![[f32::NAN, f32::INFINITY, -3.0], [1e30, f32::NEG_INFINITY, 0.5]];
        let env = Environment::from_texels(2, 1, texels, 1.0).unwrap();
        assert_eq!(env.texels, vec![[0.0, MAX_RADIANCE, 0.0], [MAX_RADIANCE, 0.0, 0.5]]);
        assert!(env.irradiance_sh.iter().all(|c| c.is_finite()));
        assert!(Environment::from_texels(2, 2, vec![[0.0; 3]; 3], 1.0).is_err());
        assert!(Environment::from_texels(1, 1, vec![[0.0; 3]], f32::NAN).is_err());
    }

    #[test]
    fn default_sky_is_brighter_above_than_below() {
        let sky = Environment::default_sky();
        assert_eq!((sky.width, sky.height), (128, 64));
        let (zenith, horizon, ground) = (sky.sample(Vec3::Y), sky.sample(Vec3::NEG_Z), sky.sample(Vec3::NEG_Y));
        assert!(zenith.z > zenith.x, "zenith is blue: {zenith}");
        assert!(horizon.x > 0.4 && ground.max_element() < 0.25, "horizon {horizon}, ground {ground}");
        assert!(sky.irradiance(Vec3::Y).x > sky.irradiance(Vec3::NEG_Y).x);
    }

    #[test]
    fn malformed_hdr_names_the_file() {
        let path = std::env::temp_dir().join(format!("vrao-bad-{}.hdr", std::process::id()));
        std::fs::write(&path, b"#?RADIANCE\nnot really\n").unwrap();
        let err = Environment::load_hdr(&path, 1.0).unwrap_err().to_string();
        std::fs::remove_file(&path).ok();
        assert!(err.contains(&path.display().to_string()), "{err}");
    }
}
