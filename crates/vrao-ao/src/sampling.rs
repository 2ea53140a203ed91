//! Sample patterns for the occlusion kernels: Halton sequences (the Czech SSDO thesis uses
//! bases 2, 3 and 5), hemisphere kernels for SSAO and SSDO, and HBAO's directions × steps
//! split.

use std::f64::consts::PI;

/// The radical inverse of `index` in `base`: the Halton sequence's `index`-th element.
pub(crate) fn halton(mut index: u32, base: u32) -> f64 {
    let mut result = 0.0;
    let mut fraction = 1.0 / base as f64;
    while index > 0 {
        result += (index % base) as f64 * fraction;
        index /= base;
        fraction /= base as f64;
    }
    result
}

/// How a kernel spreads its directions over the hemisphere around +Z (the normal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HemisphereDensity {
    /// pdf ∝ cos θ: every sample carries equal weight in a cosine-weighted integral (SSAO).
    Cosine,
    /// Uniform in solid angle, each sample covering Δω = 2π/N (SSDO, Ritschel et al. 2009).
    Uniform,
}

/// `n` offsets in the unit hemisphere around +Z, as [x, y, z, length]: xyz is the unit
/// direction and `length` in (0, 1] the fraction of the radius. Directions use Halton
/// bases 2 (azimuth) and 5 (elevation) and lengths base 3, skipping index 0 so no sample
/// sits on the pole. SSAO lengths crowd towards the centre (lerp(0.1, 1, t²), Belonogov 2018
/// §4.6); SSDO's λ is uniform in [0, r_max] (Ritschel et al. 2009).
pub fn hemisphere_kernel(n: u32, density: HemisphereDensity) -> Vec<[f32; 4]> {
    hemisphere_kernel_part(0, n, density)
}

/// Part `part` of a longer kernel: Halton points part·n + 1 ..= (part + 1)·n, so the
/// parts 0..k together are the first k·n points, as stratified as one kernel of k·n.
/// Temporal accumulation gives each frame of its window its own part.
pub(crate) fn hemisphere_kernel_part(part: u32, n: u32, density: HemisphereDensity) -> Vec<[f32; 4]> {
    (part * n + 1..=(part + 1) * n)
        .map(|i| {
            let azimuth = 2.0 * PI * halton(i, 2);
            let u = halton(i, 5);
            let cos_theta = match density {
                HemisphereDensity::Cosine => (1.0 - u).sqrt(),
                HemisphereDensity::Uniform => 1.0 - u,
            };
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            let t = halton(i, 3);
            let length = match density {
                HemisphereDensity::Cosine => 0.1 + 0.9 * t * t,
                HemisphereDensity::Uniform => t.max(0.05),
            };
            [(sin_theta * azimuth.cos()) as f32, (sin_theta * azimuth.sin()) as f32, cos_theta as f32, length as f32]
        })
        .collect()
}

/// HBAO's directions × steps for a budget of `samples` depth taps, so that each preset
/// spends about as many taps as SSAO: 12 → 4×3, 24 → 6×4, 36 → 6×6, 64 → 8×8.
pub fn hbao_directions_steps(samples: u32) -> (u32, u32) {
    let directions = match samples {
        0..=3 => samples.max(1),
        4..=15 => 4,
        16..=48 => 6,
        _ => ((samples as f64).sqrt().round() as u32).max(8),
    };
    (directions, (samples / directions).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_parts_together_are_the_longer_kernel() {
        for density in [HemisphereDensity::Cosine, HemisphereDensity::Uniform] {
            let parts: Vec<[f32; 4]> = (0..4).flat_map(|p| hemisphere_kernel_part(p, 8, density)).collect();
            assert_eq!(parts, hemisphere_kernel(32, density));
            assert_ne!(hemisphere_kernel_part(1, 8, density), hemisphere_kernel_part(0, 8, density));
        }
    }

    #[test]
    fn halton_matches_its_definition() {
        assert_eq!(halton(1, 2), 0.5);
        assert_eq!(halton(2, 2), 0.25);
        assert_eq!(halton(3, 2), 0.75);
        assert!((halton(1, 3) - 1.0 / 3.0).abs() < 1e-15);
        assert!((halton(4, 3) - 4.0 / 9.0).abs() < 1e-15); // 4 = 11₃ → 1/3 + 1/9
        assert!((halton(7, 5) - (2.0 / 5.0 + 1.0 / 25.0)).abs() < 1e-15); // 7 = 12₅
    }

    #[test]
    fn kernels_are_unit_hemisphere_directions() {
        for density in [HemisphereDensity::Cosine, HemisphereDensity::Uniform] {
            for n in [1, 12, 64, 256] {
                let k = hemisphere_kernel(n, density);
                assert_eq!(k.len(), n as usize);
                for s in &k {
                    let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
                    assert!((len - 1.0).abs() < 1e-5 && s[2] >= 0.0 && s[3] > 0.0 && s[3] <= 1.0);
                }
            }
        }
    }

    #[test]
    fn cosine_kernel_estimates_projected_solid_angle() {
        // Mean of cos θ under a cosine pdf is 2/3; under a uniform pdf it is 1/2.
        let mean = |d| hemisphere_kernel(256, d).iter().map(|s| s[2] as f64).sum::<f64>() / 256.0;
        assert!((mean(HemisphereDensity::Cosine) - 2.0 / 3.0).abs() < 0.01);
        assert!((mean(HemisphereDensity::Uniform) - 0.5).abs() < 0.01);
    }

    #[test]
    fn hbao_presets_spend_ssao_tap_counts() {
        assert_eq!(hbao_directions_steps(12), (4, 3));
        assert_eq!(hbao_directions_steps(24), (6, 4));
        assert_eq!(hbao_directions_steps(36), (6, 6));
        assert_eq!(hbao_directions_steps(64), (8, 8));
        assert_eq!(hbao_directions_steps(1), (1, 1));
        assert_eq!(hbao_directions_steps(256), (16, 16));
    }
}
