//! Image error measures for comparing GPU occlusion output against the CPU reference.
//!
//! Images are scalar `f32` planes stored row-major (`width × height`, index `y * width + x`).
//! Every measure takes an optional mask of the pixels to include (`true` = compared), e.g. to
//! leave the sky out. All functions are total: they never panic and report what they cannot
//! measure through their return type:
//!
//! - `None` when the inputs do not fit together (lengths differ, the mask has another length,
//!   `width × height` is not the length), when no pixel is included, or when a parameter such
//!   as the PSNR peak or the SSIM dynamic range is not a finite positive number.
//! - Non-finite pixel values (NaN, ±∞) in an included pixel are *infinitely wrong* for the
//!   pointwise measures: [`rmse`], [`mean_abs`] and [`max_abs`] return `Some(f64::INFINITY)`
//!   and [`psnr`] `Some(f64::NEG_INFINITY)`, so broken output never looks good in a table or
//!   on a Pareto plot. [`ssim`] cannot express that on its −1..1 scale and instead leaves such
//!   pixels out like masked ones; pair it with [`rmse`] to catch them.
//!
//! All accumulation is in `f64`.

/// Rec. 709 / sRGB luminance of a linear RGB colour.
pub fn luminance(rgb: [f32; 3]) -> f64 {
    0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64
}

/// Side of the standard SSIM window (Wang et al. 2004): 11 × 11.
pub const SSIM_WINDOW: usize = 11;
/// Standard deviation of the SSIM Gaussian window, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;
/// SSIM luminance constant factor: `C1 = (K1 · L)²`.
pub const SSIM_K1: f64 = 0.01;
/// SSIM contrast constant factor: `C2 = (K2 · L)²`.
pub const SSIM_K2: f64 = 0.03;

/// Pointwise error statistics over the compared pixels, from one pass over the images.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// Number of pixels compared (included by the mask).
    pub count: usize,
    /// Root mean square of `a − b`; `+∞` if any compared pixel is non-finite.
    pub rmse: f64,
    /// Mean of `|a − b|`; `+∞` if any compared pixel is non-finite.
    pub mean_abs: f64,
    /// Largest `|a − b|`; `+∞` if any compared pixel is non-finite.
    pub max_abs: f64,
    /// Number of compared pixels where `a` or `b` is NaN or infinite.
    pub non_finite: usize,
}

/// Whether the mask (if any) has the images' length.
fn mask_fits(len: usize, mask: Option<&[bool]>) -> bool {
    mask.is_none_or(|m| m.len() == len)
}

/// RMSE, mean and max absolute difference and counts in one pass.
///
/// `None` if `a` and `b` differ in length, the mask has another length, or no pixel is
/// included (empty images or everything masked out). See the module notes for NaN.
pub fn error_stats(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> Option<ErrorStats> {
    if a.len() != b.len() || !mask_fits(a.len(), mask) {
        return None;
    }
    let mut count = 0usize;
    let mut non_finite = 0usize;
    let mut sum_sq = 0.0f64;
    let mut sum_abs = 0.0f64;
    let mut max_abs = 0.0f64;
    for i in 0..a.len() {
        if let Some(m) = mask {
            if !m[i] {
                continue;
            }
        }
        count += 1;
        let (x, y) = (a[i] as f64, b[i] as f64);
        if !x.is_finite() || !y.is_finite() {
            non_finite += 1;
            continue;
        }
        let d = (x - y).abs();
        sum_sq += d * d;
        sum_abs += d;
        max_abs = max_abs.max(d);
    }
    if count == 0 {
        return None;
    }
    if non_finite > 0 {
        let inf = f64::INFINITY;
        return Some(ErrorStats { count, rmse: inf, mean_abs: inf, max_abs: inf, non_finite });
    }
    let n = count as f64;
    Some(ErrorStats { count, rmse: (sum_sq / n).sqrt(), mean_abs: sum_abs / n, max_abs, non_finite })
}

/// Root mean square error `sqrt(mean((a − b)²))` over the included pixels.
///
/// `None` for mismatched lengths or no included pixel; `Some(+∞)` if an included pixel is
/// non-finite in either image.
pub fn rmse(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> Option<f64> {
    error_stats(a, b, mask).map(|s| s.rmse)
}

/// Mean absolute error `mean(|a − b|)` over the included pixels (same conventions as [`rmse`]).
pub fn mean_abs(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> Option<f64> {
    error_stats(a, b, mask).map(|s| s.mean_abs)
}

/// Largest absolute difference `max(|a − b|)` over the included pixels (same conventions as
/// [`rmse`]).
pub fn max_abs(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> Option<f64> {
    error_stats(a, b, mask).map(|s| s.max_abs)
}

/// Peak signal-to-noise ratio in dB: `20 · log10(peak / rmse)`.
///
/// `peak` is the largest possible value (1 for occlusion in 0..1). `None` when [`rmse`] is
/// `None` or `peak` is not finite and positive. Identical images give `Some(+∞)`; a
/// non-finite included pixel gives `Some(−∞)`.
pub fn psnr(a: &[f32], b: &[f32], mask: Option<&[bool]>, peak: f64) -> Option<f64> {
    if !(peak.is_finite() && peak > 0.0) {
        return None;
    }
    let e = rmse(a, b, mask)?;
    Some(if e == 0.0 { f64::INFINITY } else { 20.0 * (peak / e).log10() })
}

/// RMSE with the reference's own noise taken out.
///
/// The reference is a Monte Carlo estimate: `ref = truth + n` with zero-mean noise `n` of RMS
/// `reference_noise_rms`, independent of the image under test. Then
/// `E[(img − ref)²] = E[(img − truth)²] + E[n²]` (the cross term vanishes because `n` has zero
/// mean and is independent), i.e. the noise adds in quadrature, and the error against the
/// truth is `sqrt(measured² − noise²)`. Clamped at 0 where sampling makes the measured RMSE
/// smaller than the noise. Signs are ignored (both are magnitudes); NaN in either gives NaN,
/// an infinite `measured_rmse` gives `+∞`.
pub fn noise_corrected_rmse(measured_rmse: f64, reference_noise_rms: f64) -> f64 {
    let (m, n) = (measured_rmse.abs(), reference_noise_rms.abs());
    if m.is_nan() || n.is_nan() {
        return f64::NAN;
    }
    if m.is_infinite() {
        return f64::INFINITY;
    }
    if n >= m {
        return 0.0;
    }
    // m · sqrt((1 − r)(1 + r)) with r = n / m < 1: no overflow of m² for huge values.
    let r = n / m;
    m * ((1.0 - r) * (1.0 + r)).sqrt()
}

/// Indices of the Pareto-optimal points of `(time_ms, error)` pairs (both lower is better).
///
/// A point is on the front when no other point has both a time ≤ and an error ≤ with at least
/// one strictly less. Identical points do not dominate each other, so duplicates on the front
/// are all returned. Points with a NaN coordinate are never on the front and never dominate;
/// infinities compare as usual. The result is sorted by time, then error, then index.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).filter(|&i| !points[i].0.is_nan() && !points[i].1.is_nan()).collect();
    order.sort_by(|&i, &j| {
        let (p, q) = (points[i], points[j]);
        p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)).then(i.cmp(&j))
    });
    let mut front = Vec::new();
    // Smallest error among points with strictly smaller time than the current group.
    let mut best_before = f64::INFINITY;
    let mut any_before = false;
    let mut k = 0;
    while k < order.len() {
        let t = points[order[k]].0;
        let group_min = points[order[k]].1; // sorted: the group's first has its smallest error
        let mut end = k;
        while end < order.len() && points[order[end]].0 == t {
            end += 1;
        }
        // Dominated by an earlier (faster) point when its error is ≤ ours.
        let dominated = any_before && best_before <= group_min;
        if !dominated {
            front.extend(order[k..end].iter().copied().filter(|&i| points[i].1 == group_min));
        }
        if !any_before || group_min < best_before {
            best_before = group_min;
        }
        any_before = true;
        k = end;
    }
    front
}

/// Odd window side for an image side: the standard 11, shrunk for small images.
fn window_side(n: usize) -> usize {
    let k = SSIM_WINDOW.min(n);
    if k.is_multiple_of(2) {
        k - 1
    } else {
        k
    }
}

/// Unnormalised Gaussian weights `exp(−d² / 2σ²)` for offsets `−r..=r`, `k = 2r + 1`.
fn gaussian(k: usize) -> Vec<f64> {
    let r = (k / 2) as f64;
    (0..k).map(|i| (-((i as f64 - r).powi(2)) / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp()).collect()
}

/// Structural similarity (Wang, Bovik, Sheikh, Simoncelli 2004) of two scalar images.
///
/// The standard definition: an 11 × 11 Gaussian window (σ = 1.5, normalised), local means,
/// variances and covariance with population (1/N) weighting, `C1 = (0.01 L)²`,
/// `C2 = (0.03 L)²` with `L = dynamic_range` (1 for occlusion in 0..1), and the mean of
/// `((2μaμb + C1)(2σab + C2)) / ((μa² + μb² + C1)(σa² + σb² + C2))` over the window centres
/// whose window lies inside the image ("valid" filtering, as in the authors' reference code).
/// Without a mask and with finite values this is exactly the published measure.
///
/// Masks: a pixel is *valid* when it is included by the mask and finite in both images. The
/// local statistics are mask-weighted (the Gaussian weights of invalid pixels are set to zero
/// and the rest renormalised), and a window centre counts when its own pixel is valid and
/// the valid pixels carry at least half of the window's Gaussian weight, so statistics are
/// never taken from a sliver of the window at a mask edge.
///
/// Small images: a side shorter than 11 px shrinks the window on that axis to the largest odd
/// size that fits (σ stays 1.5, the Gaussian is truncated), down to 1 px, where SSIM reduces
/// to the luminance term.
///
/// `None` when `width × height` is not the length of `a`, `b` (or the mask), when
/// `dynamic_range` is not finite and positive, when no window centre counts (empty image,
/// everything masked), or when `dynamic_range` is so large (beyond ~1e150) that the constants
/// overflow. Otherwise the result is finite, at most 1 and 1 for identical images; it is
/// symmetric in `a` and `b`.
pub fn ssim(
    a: &[f32],
    b: &[f32],
    width: usize,
    height: usize,
    mask: Option<&[bool]>,
    dynamic_range: f64,
) -> Option<f64> {
    let n = width.checked_mul(height)?;
    if a.len() != n || b.len() != n || !mask_fits(n, mask) {
        return None;
    }
    if !(dynamic_range.is_finite() && dynamic_range > 0.0) || n == 0 {
        return None;
    }
    let c1 = (SSIM_K1 * dynamic_range).powi(2);
    let c2 = (SSIM_K2 * dynamic_range).powi(2);
    let (kw, kh) = (window_side(width), window_side(height));
    let (gx, gy) = (gaussian(kw), gaussian(kh));
    let full_weight: f64 = gx.iter().sum::<f64>() * gy.iter().sum::<f64>();
    let (rx, ry) = (kw / 2, kh / 2);
    let (ow, oh) = (width - kw + 1, height - kh + 1);

    let valid = |i: usize| mask.is_none_or(|m| m[i]) && a[i].is_finite() && b[i].is_finite();
    // Statistics are taken of values relative to each image's mean over the valid pixels, so
    // E[x²] − μ² does not cancel catastrophically for images far from zero; means are shifted
    // back for the luminance term.
    let (mut shift_a, mut shift_b, mut n_valid) = (0.0f64, 0.0f64, 0usize);
    for i in (0..n).filter(|&i| valid(i)) {
        shift_a += a[i] as f64;
        shift_b += b[i] as f64;
        n_valid += 1;
    }
    if n_valid == 0 {
        return None;
    }
    shift_a /= n_valid as f64;
    shift_b /= n_valid as f64;

    // Horizontally filtered rows of [w, w·a, w·b, w·a², w·b², w·a·b] in a ring of kh rows, so
    // memory stays at kh × ow entries however large the image is.
    let mut ring: Vec<[f64; 6]> = vec![[0.0; 6]; kh * ow];
    let mut row_terms: Vec<[f64; 6]> = vec![[0.0; 6]; width];
    let mut filter_row = |y: usize, ring: &mut Vec<[f64; 6]>| {
        for (x, t) in row_terms.iter_mut().enumerate() {
            let i = y * width + x;
            *t = if valid(i) {
                let (p, q) = (a[i] as f64 - shift_a, b[i] as f64 - shift_b);
                [1.0, p, q, p * p, q * q, p * q]
            } else {
                [0.0; 6]
            };
        }
        let slot = (y % kh) * ow;
        for ox in 0..ow {
            let mut s = [0.0f64; 6];
            for (k, g) in gx.iter().enumerate() {
                let t = &row_terms[ox + k];
                for c in 0..6 {
                    s[c] += g * t[c];
                }
            }
            ring[slot + ox] = s;
        }
    };
    for y in 0..kh - 1 {
        filter_row(y, &mut ring);
    }

    let mut sum = 0.0f64;
    let mut count = 0usize;
    for oy in 0..oh {
        filter_row(oy + kh - 1, &mut ring);
        for ox in 0..ow {
            if !valid((oy + ry) * width + ox + rx) {
                continue;
            }
            let mut s = [0.0f64; 6];
            for (k, g) in gy.iter().enumerate() {
                let t = &ring[((oy + k) % kh) * ow + ox];
                for c in 0..6 {
                    s[c] += g * t[c];
                }
            }
            let w = s[0];
            if w < 0.5 * full_weight {
                continue;
            }
            let (da, db) = (s[1] / w, s[2] / w);
            let var_a = (s[3] / w - da * da).max(0.0);
            let var_b = (s[4] / w - db * db).max(0.0);
            // Rounding may break |cov| ≤ σaσb (Cauchy–Schwarz); restore it.
            let bound = (var_a * var_b).sqrt();
            let cov = (s[5] / w - da * db).clamp(-bound, bound);
            let (mu_a, mu_b) = (da + shift_a, db + shift_b);
            let num = (2.0 * mu_a * mu_b + c1) * (2.0 * cov + c2);
            let den = (mu_a * mu_a + mu_b * mu_b + c1) * (var_a + var_b + c2);
            sum += num / den;
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let mean = sum / count as f64;
    // Rounding can leave identical images a hair above 1; SSIM is at most 1 by definition.
    mean.is_finite().then_some(mean.min(1.0))
}

/// Mean ꟻLIP error (NVIDIA's LDR-ꟻLIP, Andersson et al. 2020, through the `nv-flip`
/// crate) of a grey image `test` against `reference`, over the included pixels.
///
/// What it measures: the difference a viewer notices when flipping between the two images
/// at `pixels_per_degree` of visual angle. Both are filtered by contrast sensitivity
/// functions for that viewing resolution (detail finer than the eye resolves there
/// counts less), compared in a perceptually uniform colour space, and edges and points
/// present in one image but not the other count extra. Per pixel it is in [0, 1] (0: no
/// visible difference). Unlike RMSE it tells grain from a smooth offset of the same size:
/// speckle noise scores far higher than a gentle gradient with the same RMSE, which is
/// how a denoised estimate should be judged.
///
/// Values are AO-like in [0, 1] (clamped): each is the linear grey level of a white
/// surface lit by that fraction of the light, sRGB-encoded into 8 bits as a display would
/// show it (ꟻLIP decodes sRGB back to linear before comparing). `width × height` must be
/// the images' length. Pixels outside the mask are still part of the images (set them
/// alike in both, e.g. the sky to 1, so they add no edges) but not of the mean. `None`
/// for mismatched sizes, an empty image, no included pixel or a `pixels_per_degree` that
/// is not finite and positive; `Some(1.0)`, the largest error, when an included pixel of
/// either image is not finite.
pub fn flip_mean(
    test: &[f32],
    reference: &[f32],
    width: usize,
    height: usize,
    mask: Option<&[bool]>,
    pixels_per_degree: f64,
) -> Option<f64> {
    let n = width.checked_mul(height)?;
    if n == 0 || test.len() != n || reference.len() != n || !mask_fits(n, mask) {
        return None;
    }
    if !(pixels_per_degree.is_finite() && pixels_per_degree > 0.0) {
        return None;
    }
    let included = |i: usize| mask.is_none_or(|m| m[i]);
    let count = (0..n).filter(|&i| included(i)).count();
    if count == 0 {
        return None;
    }
    if (0..n).any(|i| included(i) && !(test[i].is_finite() && reference[i].is_finite())) {
        return Some(1.0);
    }
    let grey = |values: &[f32]| -> Vec<u8> {
        values
            .iter()
            .flat_map(|&v| {
                let v = if v.is_finite() { v.clamp(0.0, 1.0) as f64 } else { 0.0 };
                let srgb = if v <= 0.0031308 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
                [(srgb * 255.0).round() as u8; 3]
            })
            .collect()
    };
    let (w, h) = (u32::try_from(width).ok()?, u32::try_from(height).ok()?);
    let reference = nv_flip::FlipImageRgb8::with_data(w, h, &grey(reference));
    let test = nv_flip::FlipImageRgb8::with_data(w, h, &grey(test));
    let error = nv_flip::flip(reference, test, pixels_per_degree as f32).to_vec();
    let sum: f64 = (0..n).filter(|&i| included(i)).map(|i| error[i] as f64).sum();
    Some(sum / count as f64)
}

#[cfg(test)]
mod tests {
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
}
