//! Tests of `metrics.rs`.

use super::*;

/// Deterministic pseudo-random numbers in [0, 1) (xorshift), so tests need no crate.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Approximately normal, zero mean, unit variance (sum of 12 uniforms − 6).
    fn gauss(&mut self) -> f64 {
        (0..12).map(|_| self.next()).sum::<f64>() - 6.0
    }
}

/// A smooth test image with structure in 0..1: gradients and a few blobs, like AO.
fn test_image(w: usize, h: usize) -> Vec<f32> {
    let mut v = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f64 / w as f64, y as f64 / h as f64);
            let blob = (-((fx - 0.4).powi(2) + (fy - 0.6).powi(2)) * 20.0).exp();
            let ripple = 0.15 * (fx * 17.0).sin() * (fy * 11.0).cos();
            v.push((0.3 + 0.3 * fx + 0.3 * blob + ripple).clamp(0.0, 1.0) as f32);
        }
    }
    v
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn pointwise_basic_values() {
    let a = [0.0f32, 1.0, 2.0, 3.0];
    let b = [0.0f32, 1.0, 2.0, 7.0];
    assert!(close(rmse(&a, &b, None).unwrap(), 2.0, 1e-12));
    assert!(close(mean_abs(&a, &b, None).unwrap(), 1.0, 1e-12));
    assert!(close(max_abs(&a, &b, None).unwrap(), 4.0, 1e-12));
    assert!(close(psnr(&a, &b, None, 4.0).unwrap(), 20.0 * 2f64.log10(), 1e-12));
    assert_eq!(psnr(&a, &a, None, 1.0), Some(f64::INFINITY));
    let mask = [true, true, true, false];
    assert_eq!(rmse(&a, &b, Some(&mask)), Some(0.0));
    assert_eq!(error_stats(&a, &b, Some(&mask)).unwrap().count, 3);
}

#[test]
fn pointwise_total_on_bad_input() {
    let e: [f32; 0] = [];
    assert_eq!(rmse(&e, &e, None), None);
    assert_eq!(mean_abs(&e, &e, None), None);
    assert_eq!(max_abs(&e, &e, None), None);
    assert_eq!(psnr(&e, &e, None, 1.0), None);
    let a = [1.0f32, 2.0];
    assert_eq!(rmse(&a, &a[..1], None), None, "length mismatch");
    assert_eq!(rmse(&a, &a, Some(&[true])), None, "mask length mismatch");
    assert_eq!(rmse(&a, &a, Some(&[false, false])), None, "all masked");
    assert_eq!(psnr(&a, &a, None, 0.0), None);
    assert_eq!(psnr(&a, &a, None, f64::NAN), None);
    let nan = [f32::NAN, 2.0];
    let s = error_stats(&nan, &a, None).unwrap();
    assert_eq!((s.rmse, s.mean_abs, s.max_abs, s.non_finite), (f64::INFINITY, f64::INFINITY, f64::INFINITY, 1));
    assert_eq!(psnr(&nan, &a, None, 1.0), Some(f64::NEG_INFINITY));
    // A masked-out NaN does not count.
    assert_eq!(rmse(&nan, &a, Some(&[false, true])), Some(0.0));
    assert_eq!(rmse(&[f32::INFINITY], &[f32::INFINITY], None), Some(f64::INFINITY));
}

#[test]
fn noise_correction_in_quadrature() {
    assert!(close(noise_corrected_rmse(5.0, 3.0), 4.0, 1e-12));
    assert_eq!(noise_corrected_rmse(0.02, 0.03), 0.0);
    assert_eq!(noise_corrected_rmse(0.02, 0.0), 0.02);
    assert!(noise_corrected_rmse(f64::NAN, 0.1).is_nan());
    assert!(noise_corrected_rmse(0.1, f64::NAN).is_nan());
    assert_eq!(noise_corrected_rmse(f64::INFINITY, 1.0), f64::INFINITY);
    assert_eq!(noise_corrected_rmse(1.0, f64::INFINITY), 0.0);
    assert!(close(noise_corrected_rmse(1e300, 6e299), 8e299, 1e286));
    // Monte Carlo check of the quadrature claim: image = truth + e, ref = truth + n.
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let n = 200_000;
    let (img, refn): (Vec<f32>, Vec<f32>) =
        (0..n).map(|_| ((0.04 * rng.gauss()) as f32, (0.03 * rng.gauss()) as f32)).unzip();
    let measured = rmse(&img, &refn, None).unwrap();
    assert!(close(measured, 0.05, 1e-3), "{measured}");
    assert!(close(noise_corrected_rmse(measured, 0.03), 0.04, 1.5e-3));
}

#[test]
fn pareto_front_basic() {
    let pts = [(10.0, 0.5), (5.0, 0.9), (20.0, 0.1), (12.0, 0.6), (5.0, 1.0), (30.0, 0.1)];
    // (12, 0.6) is dominated by (10, 0.5); (5, 1.0) by (5, 0.9); (30, 0.1) by (20, 0.1).
    assert_eq!(pareto_front(&pts), vec![1, 0, 2]);
    assert!(pareto_front(&[]).is_empty());
    assert_eq!(pareto_front(&[(1.0, 1.0)]), vec![0]);
}

#[test]
fn pareto_front_ties_nan_inf() {
    // Identical points do not dominate each other.
    assert_eq!(pareto_front(&[(1.0, 1.0), (1.0, 1.0)]), vec![0, 1]);
    // Equal time, larger error: dominated. Equal error, larger time: dominated.
    assert_eq!(pareto_front(&[(1.0, 2.0), (1.0, 1.0)]), vec![1]);
    assert_eq!(pareto_front(&[(2.0, 1.0), (1.0, 1.0)]), vec![1]);
    // NaN points are never on the front and dominate nothing.
    let pts = [(f64::NAN, 0.0), (1.0, f64::NAN), (3.0, 3.0), (f64::NAN, f64::NAN)];
    assert_eq!(pareto_front(&pts), vec![2]);
    assert!(pareto_front(&[(f64::NAN, 1.0)]).is_empty());
    // Infinite error is on the front only when nothing is at least as fast.
    assert_eq!(pareto_front(&[(1.0, f64::INFINITY), (2.0, 1.0)]), vec![0, 1]);
    assert_eq!(pareto_front(&[(1.0, f64::INFINITY), (1.0, 1.0)]), vec![1]);
    assert_eq!(pareto_front(&[(f64::NEG_INFINITY, 5.0), (0.0, 1.0)]), vec![0, 1]);
}

#[test]
fn pareto_front_matches_brute_force() {
    let mut rng = Rng(12345);
    for trial in 0..50 {
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for _ in 0..trial % 17 {
            let p = ((rng.next() * 5.0).floor(), (rng.next() * 5.0).floor());
            pts.push(if rng.next() < 0.1 { (f64::NAN, p.1) } else { p });
        }
        let dominates = |q: (f64, f64), p: (f64, f64)| q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1);
        let mut expect: Vec<usize> = (0..pts.len())
            .filter(|&i| !pts[i].0.is_nan() && !pts[i].1.is_nan())
            .filter(|&i| !pts.iter().any(|&q| dominates(q, pts[i])))
            .collect();
        expect.sort_by(|&i, &j| pts[i].0.total_cmp(&pts[j].0).then(pts[i].1.total_cmp(&pts[j].1)).then(i.cmp(&j)));
        assert_eq!(pareto_front(&pts), expect, "{pts:?}");
    }
}

#[test]
fn ssim_identical_is_one() {
    let (w, h) = (40, 30);
    let a = test_image(w, h);
    assert!(close(ssim(&a, &a, w, h, None, 1.0).unwrap(), 1.0, 1e-12));
    let c = vec![0.7f32; w * h];
    assert!(close(ssim(&c, &c, w, h, None, 1.0).unwrap(), 1.0, 1e-12));
}

#[test]
fn ssim_decreases_with_noise_and_is_symmetric() {
    let (w, h) = (48, 40);
    let a = test_image(w, h);
    let mut rng = Rng(7);
    let unit: Vec<f64> = (0..w * h).map(|_| rng.gauss()).collect();
    let noisy = |s: f64| -> Vec<f32> { a.iter().zip(&unit).map(|(&v, &u)| (v as f64 + s * u) as f32).collect() };
    let mut last = 1.0;
    for s in [0.01, 0.03, 0.1, 0.3] {
        let b = noisy(s);
        let v = ssim(&a, &b, w, h, None, 1.0).unwrap();
        assert!(v < last, "sigma {s}: {v} !< {last}");
        assert!(close(v, ssim(&b, &a, w, h, None, 1.0).unwrap(), 1e-12), "symmetric");
        last = v;
    }
}

#[test]
fn ssim_offset_hurts_less_than_noise_of_same_rmse() {
    let (w, h) = (48, 40);
    let a = test_image(w, h);
    let mut rng = Rng(99);
    let noise: Vec<f32> = a.iter().map(|&v| (v as f64 + 0.05 * rng.gauss()) as f32).collect();
    let e = rmse(&a, &noise, None).unwrap();
    let offset: Vec<f32> = a.iter().map(|&v| (v as f64 + e) as f32).collect();
    assert!(close(rmse(&a, &offset, None).unwrap(), e, 1e-6));
    let s_noise = ssim(&a, &noise, w, h, None, 1.0).unwrap();
    let s_offset = ssim(&a, &offset, w, h, None, 1.0).unwrap();
    assert!(s_offset > s_noise, "offset {s_offset} vs noise {s_noise}");
    assert!(s_offset < 1.0);
}

#[test]
fn ssim_hand_computed_tiny_cases() {
    let c1 = 1e-4; // (0.01 · 1)²
    let c2 = 9e-4; // (0.03 · 1)²
                   // 1 × 1: the window shrinks to one pixel; variances vanish, only luminance is left.
    let v = ssim(&[0.5], &[0.25], 1, 1, None, 1.0).unwrap();
    assert!(close(v, (2.0 * 0.5 * 0.25 + c1) / (0.25 + 0.0625 + c1), 1e-12), "{v}");
    // 3 × 1, a = [0, 1, 0], b = 0: one window of weights e^(−1/4.5), 1, e^(−1/4.5).
    let g = (-1.0f64 / 4.5).exp();
    let mu = 1.0 / (1.0 + 2.0 * g); // weighted mean of a
    let var = mu - mu * mu; // E[a²] − μ², a² = a here
    let expect = c1 / (mu * mu + c1) * c2 / (var + c2);
    let v = ssim(&[0.0, 1.0, 0.0], &[0.0; 3], 3, 1, None, 1.0).unwrap();
    assert!(close(v, expect, 1e-12), "{v} vs {expect}");
    // Numbers worked out by hand: g = 0.800737, μ = 0.384397, σ² = 0.236636.
    assert!(close(expect, 6.7633e-4 * 3.7890e-3, 1e-8), "{expect}");
}

/// The window sum written out directly (no separable filter, no ring buffer), 11 × 11.
fn ssim_direct(a: &[f32], b: &[f32], w: usize, h: usize, l: f64) -> f64 {
    let g = gaussian(11);
    let (c1, c2) = ((0.01 * l).powi(2), (0.03 * l).powi(2));
    let mut total = 0.0;
    let mut n = 0;
    for cy in 5..h - 5 {
        for cx in 5..w - 5 {
            let mut wsum = 0.0;
            let (mut ma, mut mb) = (0.0, 0.0);
            for j in 0..11 {
                for i in 0..11 {
                    let k = (cy + j - 5) * w + cx + i - 5;
                    let wt = g[i] * g[j];
                    wsum += wt;
                    ma += wt * a[k] as f64;
                    mb += wt * b[k] as f64;
                }
            }
            ma /= wsum;
            mb /= wsum;
            let (mut va, mut vb, mut cab) = (0.0, 0.0, 0.0);
            for j in 0..11 {
                for i in 0..11 {
                    let k = (cy + j - 5) * w + cx + i - 5;
                    let wt = g[i] * g[j] / wsum;
                    let (da, db) = (a[k] as f64 - ma, b[k] as f64 - mb);
                    va += wt * da * da;
                    vb += wt * db * db;
                    cab += wt * da * db;
                }
            }
            total += (2.0 * ma * mb + c1) * (2.0 * cab + c2) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            n += 1;
        }
    }
    total / n as f64
}

#[test]
fn ssim_matches_direct_definition() {
    let (w, h) = (29, 23);
    let a = test_image(w, h);
    let mut rng = Rng(4242);
    let b: Vec<f32> = a.iter().map(|&v| (v as f64 * 0.9 + 0.08 * rng.gauss()) as f32).collect();
    let fast = ssim(&a, &b, w, h, None, 1.0).unwrap();
    let slow = ssim_direct(&a, &b, w, h, 1.0);
    assert!(close(fast, slow, 1e-10), "{fast} vs {slow}");
    // Another dynamic range scales the constants.
    let fast = ssim(&a, &b, w, h, None, 255.0).unwrap();
    assert!(close(fast, ssim_direct(&a, &b, w, h, 255.0), 1e-10));
}

#[test]
fn ssim_known_value() {
    // a(x, y) = ((x·7 + y·13) mod 17) / 16, b(x, y) = ((x·5 + y·3) mod 11) / 10 on 16 × 12,
    // computed independently (a direct NumPy transcription of Wang et al.'s definition).
    let (w, h) = (16, 12);
    let a: Vec<f32> = (0..w * h).map(|i| ((i % w * 7 + i / w * 13) % 17) as f32 / 16.0).collect();
    let b: Vec<f32> = (0..w * h).map(|i| ((i % w * 5 + i / w * 3) % 11) as f32 / 10.0).collect();
    let v = ssim(&a, &b, w, h, None, 1.0).unwrap();
    assert!(close(v, SSIM_KNOWN, 1e-9), "{v}");
}
const SSIM_KNOWN: f64 = 0.211_319_414_214_969;

#[test]
fn ssim_masks() {
    let (w, h) = (40, 32);
    let a = test_image(w, h);
    let mut b = a.clone();
    // Garbage in the right half, masked out: SSIM over the left half stays 1.
    for y in 0..h {
        for x in w / 2..w {
            b[y * w + x] = if (x + y) % 2 == 0 { f32::NAN } else { 5.0 };
        }
    }
    let mask: Vec<bool> = (0..w * h).map(|i| i % w < w / 2).collect();
    assert!(close(ssim(&a, &b, w, h, Some(&mask), 1.0).unwrap(), 1.0, 1e-12));
    // All masked, or mask length wrong: None.
    assert_eq!(ssim(&a, &b, w, h, Some(&vec![false; w * h]), 1.0), None);
    assert_eq!(ssim(&a, &b, w, h, Some(&[true]), 1.0), None);
    // A mask of all true equals no mask.
    let c: Vec<f32> = a.iter().map(|&v| v * 0.8 + 0.1).collect();
    let full = vec![true; w * h];
    assert_eq!(ssim(&a, &c, w, h, Some(&full), 1.0), ssim(&a, &c, w, h, None, 1.0));
    // NaN pixels are left out like masked ones; the result stays finite.
    let mut d = c.clone();
    d[5 * w + 7] = f32::NAN;
    let v = ssim(&a, &d, w, h, None, 1.0).unwrap();
    assert!(v.is_finite() && v <= 1.0);
    // Entirely NaN: nothing to compare.
    assert_eq!(ssim(&a, &vec![f32::NAN; w * h], w, h, None, 1.0), None);
}

#[test]
fn ssim_total_on_odd_shapes() {
    assert_eq!(ssim(&[], &[], 0, 0, None, 1.0), None);
    assert_eq!(ssim(&[], &[], 0, 5, None, 1.0), None);
    assert_eq!(ssim(&[1.0], &[1.0], 2, 1, None, 1.0), None, "size mismatch");
    assert_eq!(ssim(&[1.0], &[1.0], usize::MAX, 2, None, 1.0), None, "overflow");
    assert_eq!(ssim(&[1.0], &[1.0], 1, 1, None, 0.0), None);
    assert_eq!(ssim(&[1.0], &[1.0], 1, 1, None, f64::INFINITY), None);
    let mut rng = Rng(3);
    for (w, h) in [(1, 1), (1, 7), (2, 2), (4, 3), (10, 10), (11, 11), (12, 5), (64, 1), (3, 40)] {
        let a: Vec<f32> = (0..w * h).map(|_| rng.next() as f32).collect();
        let b: Vec<f32> = (0..w * h).map(|_| rng.next() as f32).collect();
        let v = ssim(&a, &b, w, h, None, 1.0).unwrap();
        assert!(v.is_finite() && (-1.0..=1.0).contains(&v), "{w}×{h}: {v}");
        assert!(close(ssim(&a, &a, w, h, None, 1.0).unwrap(), 1.0, 1e-12), "{w}×{h}");
    }
    // Extreme values stay finite; a dynamic range whose constants overflow gives None.
    let big = [f32::MAX, -f32::MAX, f32::MAX, 0.0];
    let v = ssim(&big, &[0.0, f32::MAX, 1.0, -f32::MAX], 2, 2, None, 1.0).unwrap();
    assert!(v.is_finite() && v <= 1.0, "{v}");
    assert!(close(ssim(&big, &big, 2, 2, None, 1.0).unwrap(), 1.0, 1e-12));
    assert_eq!(ssim(&[0.5], &[0.5], 1, 1, None, 1e300), None);
}
#[test]
fn flip_is_zero_for_identical_images_and_larger_for_noise_than_for_a_smooth_error_of_the_same_mean_and_size() {
    let (w, h) = (64, 48);
    let ppd = 11.0;
    let reference = vec![0.5f32; w * h];
    assert_eq!(flip_mean(&reference, &reference, w, h, None, ppd), Some(0.0));
    let mut rng = Rng(11);
    let gradient: Vec<f32> = (0..w * h).map(|i| 0.4 + 0.2 * (i % w) as f32 / (w - 1) as f32).collect();
    assert_eq!(flip_mean(&gradient, &gradient, w, h, None, ppd), Some(0.0));
    // Smooth: a sine across the image, amplitude 0.1 √2. Noisy: ±0.1 per pixel at
    // random. Both have mean 0.5 and RMSE 0.1 against the flat reference.
    let smooth: Vec<f32> = (0..w * h)
        .map(|i| 0.5 + 0.1 * 2f32.sqrt() * (std::f32::consts::TAU * (i % w) as f32 / w as f32).sin())
        .collect();
    let noisy: Vec<f32> = (0..w * h).map(|_| if rng.next() < 0.5 { 0.4 } else { 0.6 }).collect();
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    assert!((mean(&smooth) - 0.5).abs() < 1e-3 && (mean(&noisy) - 0.5).abs() < 0.02);
    assert!((rmse(&smooth, &reference, None).unwrap() - 0.1).abs() < 1e-3);
    assert!((rmse(&noisy, &reference, None).unwrap() - 0.1).abs() < 1e-6);
    let (flip_smooth, flip_noisy) = (
        flip_mean(&smooth, &reference, w, h, None, ppd).unwrap(),
        flip_mean(&noisy, &reference, w, h, None, ppd).unwrap(),
    );
    assert!(flip_smooth > 0.0 && flip_noisy > 1.3 * flip_smooth, "smooth {flip_smooth}, noisy {flip_noisy}");
}

#[test]
fn flip_is_total_and_counts_only_the_included_pixels() {
    let (w, h) = (16, 12);
    let a = vec![0.5f32; w * h];
    let mut b = a.clone();
    for v in &mut b[..w * h / 2] {
        *v = 0.9; // the top half differs
    }
    let top: Vec<bool> = (0..w * h).map(|i| i < w * h / 2).collect();
    let bottom: Vec<bool> = top.iter().map(|t| !t).collect();
    let (on_top, below) =
        (flip_mean(&b, &a, w, h, Some(&top), 10.0).unwrap(), flip_mean(&b, &a, w, h, Some(&bottom), 10.0).unwrap());
    assert!(on_top > below, "{on_top} {below}");
    assert_eq!(flip_mean(&a, &a, w, h + 1, None, 10.0), None);
    assert_eq!(flip_mean(&a, &a, w, h, Some(&vec![false; w * h]), 10.0), None);
    assert_eq!(flip_mean(&a, &a, w, h, None, 0.0), None);
    assert_eq!(flip_mean(&[], &[], 0, 0, None, 10.0), None);
    let mut nan = a.clone();
    nan[3] = f32::NAN;
    assert_eq!(flip_mean(&nan, &a, w, h, None, 10.0), Some(1.0));
}
