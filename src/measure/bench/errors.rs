//! A row's error against the reference tracer: AO RMSE and bias, halos at depth edges,
//! the screen-space limit and FLIP.

// The bench's types and imports (this file is a part of bench.rs split out for size).
use super::*;

/// How far one row's occlusion is from the reference tracer's, on the pixels the
/// reference traced (both eyes; sky excluded). Every technique is scored against the same
/// target: the reference's `ao`, cosine-weighted visibility within r with a hard cut-off.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorFigures {
    /// RMSE of the AO (`.a`) against the reference's hard cut-off AO, with the reference's
    /// own noise taken out in quadrature.
    pub ao_rmse: f64,
    /// Mean of (estimate − reference): > 0 is too light, < 0 too dark.
    pub ao_bias: f64,
    /// The same over the pixels where the reference is below [`DARK_REFERENCE`]: how well
    /// the occluded places (creases, contacts) come out. `None` when there are none.
    pub ao_bias_dark: Option<f64>,
    /// RMSE against the reference's linear-falloff AO (each occluded direction weighted by
    /// 1 − d/r), noise taken out as for `ao_rmse`: a second figure, for every technique.
    pub ao_rmse_falloff: f64,
    /// Mean SSIM of the AO images against the reference (1 = identical), per eye averaged.
    pub ao_ssim: f64,
    /// RMSE of the ambient light's luminance (what the composite multiplies by albedo/π)
    /// relative to the reference's mean: environment light that gets through within r
    /// plus one bounce of direct light from surfaces within r. Comparable across
    /// techniques; `None` when the reference has no ambient light at all.
    pub ambient_rel_rmse: Option<f64>,
    /// Mean ꟻLIP of the AO against the reference AO ([`metrics::flip_mean`]) on the
    /// reference's grid, at the headset's pixels per degree over the grid's spacing.
    pub flip_mean: Option<f64>,
    /// RMSE against the screen-space limit (the march over this frame's depth buffer):
    /// the estimator's own error (the limit's small noise, ~0.01 at 64 stratified rays,
    /// left in).
    pub ao_rmse_vs_limit: Option<f64>,
    /// The screen-space limit's RMSE against the reference (the reference's noise taken
    /// out, as for `ao_rmse`): the error no depth-buffer method can remove. The same for
    /// every row of a radius.
    pub limit_rmse: Option<f64>,
    /// The screen-space limit's mean bias against the reference.
    pub limit_bias: Option<f64>,
    /// RMSE (noise not taken out) over the pixels within [`BORDER_PX`] of an eye's outer,
    /// top or bottom border, where samples that leave the image count as open: with
    /// `ao_rmse`, what a guard band could win. `None` when no such pixel is covered.
    pub ao_rmse_outer_border: Option<f64>,
    /// Halos: the share (0..1) of the pixels beside a depth edge (`near_depth_edge`)
    /// that are too dark by more than [`HALO_DARKER`]. `None` when there is no edge.
    pub halo_share: Option<f64>,
}

/// How much darker than the reference a pixel beside a depth edge must be to count as
/// part of a halo.
pub const HALO_DARKER: f32 = 0.1;

/// Whether grid cell (i, j) of an eye's reference lies beside a depth edge: a neighbour
/// within one cell sees the sky, or the depth along a row or column is not locally
/// linear (second difference above 10 % of the depth; a sloped floor is linear in the
/// pixel coordinate only to first order, far below that).
pub(super) fn near_depth_edge(pixels: &[ReferencePixel], (gw, gh): (usize, usize), i: usize, j: usize) -> bool {
    let depth = |x: usize, y: usize| pixels[y * gw + x].hit.then_some(pixels[y * gw + x].depth as f64);
    let Some(d) = depth(i, j) else { return false };
    let bent = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (a + b - 2.0 * d).abs() > 0.1 * d,
        _ => true,
    };
    let (left, right) = (i.checked_sub(1), (i + 1 < gw).then_some(i + 1));
    let (up, down) = (j.checked_sub(1), (j + 1 < gh).then_some(j + 1));
    let horizontal = left.is_some() && right.is_some() && bent(depth(left.unwrap(), j), depth(right.unwrap(), j));
    let vertical = up.is_some() && down.is_some() && bent(depth(i, up.unwrap()), depth(i, down.unwrap()));
    horizontal || vertical
}

/// Reference AO below which a pixel counts as occluded for [`ErrorFigures::ao_bias_dark`].
pub const DARK_REFERENCE: f32 = 0.8;

/// Pixels per degree of an eye `width` pixels across its horizontal field of view (the
/// mean over the field: a Vive-class 1080-pixel eye over ~97.5° has ~11.1).
pub fn pixels_per_degree(fov: &crate::render::stereo::Fov, width: u32) -> f64 {
    width as f64 / (fov.right as f64 - fov.left as f64).to_degrees()
}

/// Compares the occlusion a frame produced (per layer, RGBA at the full image size) with
/// the reference on its grid of traced pixels; FLIP at the pixels per degree of the
/// project's Vive-class headset profile at the reference's size (what [`score`] takes
/// from the frame's eyes), no screen-space limit.
pub fn error_figures(technique: Technique, occlusion: &[Vec<f32>], reference: &ReferenceImage) -> ErrorFigures {
    let profile = crate::render::stereo::HeadsetProfile::with_size("vive", reference.width, reference.height);
    score(technique, occlusion, reference, None, pixels_per_degree(&profile.fov_left, reference.width))
}

/// [`error_figures`] with the screen-space limit of the same frame and radius (the limit
/// columns are `None` without it) and FLIP at `pixels_per_degree` of the full image.
pub fn score(
    technique: Technique,
    occlusion: &[Vec<f32>],
    reference: &ReferenceImage,
    limit: Option<&ScreenLimit>,
    pixels_per_degree: f64,
) -> ErrorFigures {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let (gw, gh) = reference.grid_size();
    let (gw, gh) = (gw as usize, gh as usize);
    let limit = limit.filter(|l| l.grid_size() == reference.grid_size() && l.layers.len() >= reference.layers.len());
    let (mut gpu_ao, mut ref_ao, mut falloff, mut noise2, mut mask) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut limit_ao, mut limit_mask) = (Vec::new(), Vec::new());
    let (mut gpu_ambient, mut ref_ambient) = (Vec::new(), Vec::new());
    let (mut ssim_sum, mut flip_sum, mut flip_pixels) = (0.0, 0.0, 0usize);
    let (mut outer_border, mut beside_edge) = (Vec::new(), Vec::new());
    for (layer, pixels) in reference.layers.iter().enumerate() {
        let image = &occlusion[layer];
        let first = gpu_ao.len();
        for gy in 0..gh {
            for gx in 0..gw {
                let r = &pixels[gy * gw + gx];
                let (x, y) = reference.pixel_of(gx as u32, gy as u32);
                let (x, y) = ((x as usize).min(w - 1), (y as usize).min(h - 1));
                let texel = &image[(y * w + x) * 4..(y * w + x) * 4 + 4];
                // Layer 0 is the left eye: its outer border is on the left.
                let outer = if layer == 0 { x } else { w - 1 - x };
                outer_border.push(r.hit && outer.min(y).min(h - 1 - y) < BORDER_PX as usize);
                beside_edge.push(r.hit && near_depth_edge(pixels, (gw, gh), gx, gy));
                gpu_ao.push(texel[3]);
                ref_ao.push(r.ao);
                falloff.push(r.ao_falloff);
                mask.push(r.hit);
                noise2.push(if r.hit { (r.ao_std_error as f64).powi(2) } else { 0.0 });
                let l = limit.map(|l| *l.get(layer, gx as u32, gy as u32));
                limit_ao.push(l.map_or(1.0, |l| l.ao));
                limit_mask.push(r.hit && l.is_some_and(|l| l.hit));
                let ambient = if technique.carries_light() {
                    [texel[0], texel[1], texel[2]]
                } else {
                    r.unoccluded.map(|c| c * texel[3])
                };
                let truth = [0, 1, 2].map(|c| r.environment_visible[c] + r.bounce[c]);
                gpu_ambient.push(luminance(ambient) as f32);
                ref_ambient.push(luminance(truth) as f32);
            }
        }
        let range = first..gpu_ao.len();
        ssim_sum +=
            metrics::ssim(&gpu_ao[range.clone()], &ref_ao[range.clone()], gw, gh, Some(&mask[range.clone()]), 1.0)
                .unwrap_or(0.0);
        // FLIP on this eye's grid, the sky 1 in both; pooled over both eyes' hit pixels.
        let sky_is_one = |values: &[f32]| -> Vec<f32> {
            values.iter().zip(&mask[range.clone()]).map(|(&v, &hit)| if hit { v } else { 1.0 }).collect()
        };
        let grid_ppd = pixels_per_degree / reference.stride.max(1) as f64;
        let (test, truth) = (sky_is_one(&gpu_ao[range.clone()]), sky_is_one(&ref_ao[range.clone()]));
        let hits = mask[range.clone()].iter().filter(|&&m| m).count();
        if let Some(mean) = metrics::flip_mean(&test, &truth, gw, gh, Some(&mask[range]), grid_ppd) {
            flip_sum += mean * hits as f64;
            flip_pixels += hits;
        }
    }
    let hit_count = mask.iter().filter(|&&m| m).count();
    let hits = hit_count.max(1) as f64;
    let noise = (noise2.iter().sum::<f64>() / hits).sqrt();
    let corrected = |a: &[f32], b: &[f32], mask: &[bool], noise: f64| {
        metrics::noise_corrected_rmse(metrics::rmse(a, b, Some(mask)).unwrap_or(f64::NAN), noise)
    };
    let mean_difference = |a: &[f32], b: &[f32], keep: &dyn Fn(usize) -> bool| {
        let (mut n, mut sum) = (0usize, 0f64);
        for i in (0..a.len()).filter(|&i| keep(i)) {
            n += 1;
            sum += a[i] as f64 - b[i] as f64;
        }
        (n > 0).then(|| sum / n as f64)
    };
    let ao_bias = mean_difference(&gpu_ao, &ref_ao, &|i| mask[i]).unwrap_or(f64::NAN);
    let ao_bias_dark = mean_difference(&gpu_ao, &ref_ao, &|i| mask[i] && ref_ao[i] < DARK_REFERENCE);
    let mean_ambient = ref_ambient.iter().zip(&mask).filter(|(_, &m)| m).map(|(&a, _)| a as f64).sum::<f64>() / hits;
    let ambient_rel_rmse = (mean_ambient > 1e-12)
        .then(|| metrics::rmse(&gpu_ambient, &ref_ambient, Some(&mask)).map(|e| e / mean_ambient))
        .flatten();
    // The limit against the reference with the reference's noise taken out, as `ao_rmse`
    // (so the two compare directly). The limit's own noise is not subtracted: its
    // binomial bound ignores the stratification of its rays and is several times what
    // they leave (on the crease the limit and a 64-ray reference differ by an RMSE of
    // 0.011 while each one's bound is ~0.03), so subtracting it would zero real error.
    let (ao_rmse_vs_limit, limit_rmse, limit_bias) = match limit {
        Some(_) if limit_mask.iter().any(|&m| m) => {
            let n = limit_mask.iter().filter(|&&m| m).count() as f64;
            let ref_noise2 = noise2.iter().zip(&limit_mask).filter(|(_, &m)| m).map(|(v, _)| v).sum::<f64>() / n;
            (
                metrics::rmse(&gpu_ao, &limit_ao, Some(&limit_mask)),
                Some(corrected(&limit_ao, &ref_ao, &limit_mask, ref_noise2.sqrt())),
                mean_difference(&limit_ao, &ref_ao, &|i| limit_mask[i]),
            )
        }
        _ => (None, None, None),
    };
    let edge_pixels = beside_edge.iter().filter(|&&e| e).count();
    let halos = (0..gpu_ao.len()).filter(|&i| beside_edge[i] && gpu_ao[i] < ref_ao[i] - HALO_DARKER).count();
    ErrorFigures {
        ao_rmse_outer_border: outer_border
            .iter()
            .any(|&b| b)
            .then(|| metrics::rmse(&gpu_ao, &ref_ao, Some(&outer_border)))
            .flatten(),
        halo_share: (edge_pixels > 0).then(|| halos as f64 / edge_pixels as f64),
        ao_rmse: corrected(&gpu_ao, &ref_ao, &mask, noise),
        ao_bias,
        ao_bias_dark,
        ao_rmse_falloff: corrected(&gpu_ao, &falloff, &mask, noise),
        ao_ssim: ssim_sum / reference.layers.len().max(1) as f64,
        ambient_rel_rmse,
        flip_mean: (flip_pixels > 0).then(|| flip_sum / flip_pixels as f64),
        ao_rmse_vs_limit,
        limit_rmse,
        limit_bias,
    }
}

impl LimitInfo {
    /// The defaults every bench uses.
    pub fn defaults() -> LimitInfo {
        use crate::measure::reference::screen_limit::{DEFAULT_RAYS, DEFAULT_STEPS, DEFAULT_THICKNESS_OF_RADIUS};
        LimitInfo {
            rays_per_pixel: DEFAULT_RAYS,
            steps: DEFAULT_STEPS,
            thickness_of_radius: DEFAULT_THICKNESS_OF_RADIUS,
        }
    }
}
