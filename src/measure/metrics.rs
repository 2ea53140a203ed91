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
    let shift = valid_means(a, b, n, &valid)?;

    // Horizontally filtered rows of [w, w·a, w·b, w·a², w·b², w·a·b] in a ring of kh rows, so
    // memory stays at kh × ow entries however large the image is.
    let mut ring: Vec<[f64; 6]> = vec![[0.0; 6]; kh * ow];
    let mut row_terms: Vec<[f64; 6]> = vec![[0.0; 6]; width];
    let mut filter_row = |y: usize, ring: &mut Vec<[f64; 6]>| {
        for (x, t) in row_terms.iter_mut().enumerate() {
            let i = y * width + x;
            *t = if valid(i) { centred_terms(a[i], b[i], shift) } else { [0.0; 6] };
        }
        let slot = (y % kh) * ow;
        filter_horizontally(&row_terms, &gx, &mut ring[slot..slot + ow]);
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
            let s = filter_vertically(&ring, &gy, oy, ox, ow);
            if s[0] < 0.5 * full_weight {
                continue;
            }
            sum += window_ssim(&s, shift, c1, c2);
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

/// The means of `a` and `b` over the first `n` pixels that are `valid`, or `None` when
/// none is.
fn valid_means(a: &[f32], b: &[f32], n: usize, valid: &impl Fn(usize) -> bool) -> Option<(f64, f64)> {
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
    Some((shift_a, shift_b))
}

/// One valid pixel's terms [1, p, q, p², q², p·q] of its values relative to each image's
/// mean (`shift`).
fn centred_terms(a: f32, b: f32, shift: (f64, f64)) -> [f64; 6] {
    let (p, q) = (a as f64 - shift.0, b as f64 - shift.1);
    [1.0, p, q, p * p, q * q, p * q]
}

/// A row's terms filtered by the horizontal Gaussian `gx`, one entry of `out` per window
/// position ("valid" filtering: `out` is `gx.len() − 1` shorter than the row).
fn filter_horizontally(row_terms: &[[f64; 6]], gx: &[f64], out: &mut [[f64; 6]]) {
    for (ox, o) in out.iter_mut().enumerate() {
        let mut s = [0.0f64; 6];
        for (k, g) in gx.iter().enumerate() {
            let t = &row_terms[ox + k];
            for c in 0..6 {
                s[c] += g * t[c];
            }
        }
        *o = s;
    }
}

/// The window at (`ox`, `oy`): the ring's horizontally filtered rows `oy..oy + kh`
/// (`kh = gy.len()`, each `ow` entries) filtered by the vertical Gaussian `gy`.
fn filter_vertically(ring: &[[f64; 6]], gy: &[f64], oy: usize, ox: usize, ow: usize) -> [f64; 6] {
    let kh = gy.len();
    let mut s = [0.0f64; 6];
    for (k, g) in gy.iter().enumerate() {
        let t = &ring[((oy + k) % kh) * ow + ox];
        for c in 0..6 {
            s[c] += g * t[c];
        }
    }
    s
}

/// One window's SSIM from its weighted sums `s` (weight first, see [`centred_terms`]),
/// the images' mean `shift` and the constants `c1`, `c2`.
fn window_ssim(s: &[f64; 6], shift: (f64, f64), c1: f64, c2: f64) -> f64 {
    let w = s[0];
    let (da, db) = (s[1] / w, s[2] / w);
    let var_a = (s[3] / w - da * da).max(0.0);
    let var_b = (s[4] / w - db * db).max(0.0);
    // Rounding may break |cov| ≤ σaσb (Cauchy–Schwarz); restore it.
    let bound = (var_a * var_b).sqrt();
    let cov = (s[5] / w - da * db).clamp(-bound, bound);
    let (mu_a, mu_b) = (da + shift.0, db + shift.1);
    let num = (2.0 * mu_a * mu_b + c1) * (2.0 * cov + c2);
    let den = (mu_a * mu_a + mu_b * mu_b + c1) * (var_a + var_b + c2);
    num / den
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
mod tests;
