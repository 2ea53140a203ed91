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
    /// [`Self::ao_rmse`] over the pixels within [`CENTRAL_FIELD_DEG`] of each eye's view
    /// axis: where the eye looks through the lens, and where fixed foveation keeps the
    /// full rate. `None` when no traced pixel lies there.
    pub ao_rmse_central: Option<f64>,
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
    /// plus one bounce of direct light from surfaces within r, with the reference's own
    /// noise taken out in quadrature (as for `ao_rmse`). Comparable across techniques;
    /// `None` when the reference has no ambient light at all.
    pub ambient_rel_rmse: Option<f64>,
    /// The same per colour channel (r, g, b), each relative to its own mean; `None` as
    /// above.
    #[serde(default)]
    pub ambient_rel_rmse_rgb: Option<[f64; 3]>,
    /// Mean ꟻLIP of the AO against the reference AO ([`metrics::flip_mean`]) on the
    /// reference's grid, at the headset's pixels per degree over the grid's spacing.
    pub flip_mean: Option<f64>,
    /// RMSE against the screen-space limit (the march over this frame's depth buffer):
    /// the estimator's own error (the limit's small noise left in; see
    /// docs/records/2026-11-29/measurements-in-code.md, limit-noise).
    pub ao_rmse_vs_limit: Option<f64>,
    /// The screen-space limit's RMSE against the reference (the reference's noise taken
    /// out, as for `ao_rmse`): the error no depth-buffer method can remove. The same for
    /// every row of a radius.
    pub limit_rmse: Option<f64>,
    /// The screen-space limit's mean bias against the reference.
    pub limit_bias: Option<f64>,
    /// The two-layer screen-space limit's RMSE against the reference (the march with the
    /// renderer's second depth layer, `screen_limit`; noise taken out as for
    /// `limit_rmse`): what a second layer leaves. Set by the bench, `None` otherwise.
    #[serde(default)]
    pub limit_two_layer_rmse: Option<f64>,
    /// The two-layer limit's mean bias against the reference.
    #[serde(default)]
    pub limit_two_layer_bias: Option<f64>,
    /// RMSE (noise not taken out) over the pixels within [`BORDER_PX`] of an eye's outer,
    /// top or bottom border, where samples that leave the image count as open: with
    /// `ao_rmse`, what a guard band could win. `None` when no such pixel is covered.
    pub ao_rmse_outer_border: Option<f64>,
    /// [`Self::ao_rmse`] over the whole rectangle, the pixels the lens hides included
    /// (every figure else counts only those it shows): for continuity with the figures
    /// before the mask, on rows with the mask off. Set by the bench, `None` otherwise.
    #[serde(default)]
    pub ao_rmse_whole: Option<f64>,
    /// Halos: the share (0..1) of the pixels beside a depth edge (`near_depth_edge`)
    /// that are too dark by more than [`HALO_DARKER`]. `None` when there is no edge.
    pub halo_share: Option<f64>,
}

/// Half the angle of the central field [`ErrorFigures::ao_rmse_central`] covers: the
/// central 20° of each eye, where it looks ahead through the lens.
pub const CENTRAL_FIELD_DEG: f64 = 10.0;

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
pub fn pixels_per_degree(fov: &vrao_ao::Fov, width: u32) -> f64 {
    width as f64 / (fov.right as f64 - fov.left as f64).to_degrees()
}

/// Compares the occlusion a frame produced (per layer, RGBA at the full image size) with
/// the reference on its grid of traced pixels; FLIP at the pixels per degree and the
/// central field of the project's Vive-class headset profile at the reference's size
/// (what [`score`] takes from the frame's eyes), no screen-space limit.
pub fn error_figures(technique: Technique, occlusion: &[Vec<f32>], reference: &ReferenceImage) -> ErrorFigures {
    let profile = vrao_render::HeadsetProfile::with_size("vive", reference.width, reference.height);
    let fovs = [profile.fov_left, profile.fov_right];
    score(technique, occlusion, reference, None, pixels_per_degree(&profile.fov_left, reference.width), &fovs)
}

/// [`error_figures`] with the screen-space limit of the same frame and radius (the limit
/// columns are `None` without it), FLIP at `pixels_per_degree` of the full image and the
/// central field of each layer's field of view in `fovs`.
pub fn score(
    technique: Technique,
    occlusion: &[Vec<f32>],
    reference: &ReferenceImage,
    limit: Option<&ScreenLimit>,
    pixels_per_degree: f64,
    fovs: &[vrao_ao::Fov],
) -> ErrorFigures {
    let limit = limit.filter(|l| l.grid_size() == reference.grid_size() && l.layers.len() >= reference.layers.len());
    let (gw, gh) = reference.grid_size();
    let grid_ppd = pixels_per_degree / reference.stride.max(1) as f64;
    let mut cells = Vec::new();
    let (mut ssim_sum, mut flip_sum, mut flip_pixels) = (0.0, 0.0, 0usize);
    for (layer, image) in occlusion.iter().enumerate().take(reference.layers.len()) {
        let fov = fovs.get(layer).copied();
        let eye = eye_cells(technique, image, reference, layer, limit, fov);
        let (ssim, flip) = eye_similarity(&eye, (gw as usize, gh as usize), grid_ppd);
        ssim_sum += ssim;
        // FLIP is pooled over both eyes' hit pixels.
        if let Some((mean, hits)) = flip {
            flip_sum += mean * hits as f64;
            flip_pixels += hits;
        }
        cells.extend(eye);
    }
    let hits = cells.iter().filter(|c| c.hit).count().max(1) as f64;
    let noise = (cells.iter().map(|c| c.noise2).sum::<f64>() / hits).sqrt();
    let (ao_rmse_vs_limit, limit_rmse, limit_bias) = limit_figures(&cells);
    ErrorFigures {
        ao_rmse_whole: None,
        ao_rmse_outer_border: cells
            .iter()
            .any(|c| c.outer_border)
            .then(|| rmse(&cells, |c| c.ao, |c| c.ref_ao, |c| c.outer_border))
            .flatten(),
        halo_share: halo_share(&cells),
        ao_rmse: corrected_rmse(&cells, |c| c.ao, |c| c.ref_ao, |c| c.hit, noise),
        ao_rmse_central: cells
            .iter()
            .any(|c| c.central)
            .then(|| corrected_rmse(&cells, |c| c.ao, |c| c.ref_ao, |c| c.central, noise)),
        ao_bias: mean_difference(&cells, |c| c.ao, |c| c.ref_ao, |c| c.hit).unwrap_or(f64::NAN),
        ao_bias_dark: mean_difference(&cells, |c| c.ao, |c| c.ref_ao, |c| c.hit && c.ref_ao < DARK_REFERENCE),
        ao_rmse_falloff: corrected_rmse(&cells, |c| c.ao, |c| c.ref_falloff, |c| c.hit, noise),
        ao_ssim: ssim_sum / reference.layers.len().max(1) as f64,
        ambient_rel_rmse: ambient_rel_rmse(&cells, hits, 3),
        ambient_rel_rmse_rgb: {
            let rgb = [0, 1, 2].map(|k| ambient_rel_rmse(&cells, hits, k));
            rgb.iter().all(Option::is_some).then(|| rgb.map(|v| v.unwrap_or(f64::NAN)))
        },
        flip_mean: (flip_pixels > 0).then(|| flip_sum / flip_pixels as f64),
        ao_rmse_vs_limit,
        limit_rmse,
        limit_bias,
        limit_two_layer_rmse: None,
        limit_two_layer_bias: None,
    }
}

/// A screen-space limit's (RMSE, bias) against `reference` over the cells both hit, the
/// reference's noise taken out of the RMSE in quadrature (as `limit_rmse`); `None` when
/// the grids differ or no cell is hit.
pub fn limit_against_reference(limit: &ScreenLimit, reference: &ReferenceImage) -> (Option<f64>, Option<f64>) {
    if limit.grid_size() != reference.grid_size() || limit.layers.len() < reference.layers.len() {
        return (None, None);
    }
    let (gw, gh) = reference.grid_size();
    let (mut n, mut sum, mut sum_sq, mut noise2) = (0usize, 0f64, 0f64, 0f64);
    for layer in 0..reference.layers.len() {
        for j in 0..gh {
            for i in 0..gw {
                let (r, l) = (reference.get(layer, i, j), limit.get(layer, i, j));
                if !(r.hit && l.hit) {
                    continue;
                }
                let d = l.ao as f64 - r.ao as f64;
                n += 1;
                sum += d;
                sum_sq += d * d;
                noise2 += (r.ao_std_error as f64).powi(2);
            }
        }
    }
    if n == 0 {
        return (None, None);
    }
    let n = n as f64;
    (Some(metrics::noise_corrected_rmse((sum_sq / n).sqrt(), (noise2 / n).sqrt())), Some(sum / n))
}

/// One traced cell of the reference grid beside what the frame (and the screen-space
/// limit) put at its pixel.
struct Cell {
    /// The reference traced a surface here (not the sky).
    hit: bool,
    /// The frame's AO (alpha), the reference's hard cut-off AO and its linear-falloff AO.
    ao: f32,
    ref_ao: f32,
    ref_falloff: f32,
    /// The reference AO's variance (its standard error squared; 0 on the sky).
    noise2: f64,
    /// The screen-space limit's AO (1 without a limit) and whether both it and the
    /// reference hit a surface.
    limit_ao: f32,
    limit_hit: bool,
    /// The frame's ambient light and the reference's: r, g, b and luminance, and the
    /// reference's variance of each.
    ambient: [f32; 4],
    ref_ambient: [f32; 4],
    ambient_noise2: [f64; 4],
    /// A hit within [`BORDER_PX`] of the eye's outer, top or bottom border.
    outer_border: bool,
    /// A hit beside a depth edge ([`near_depth_edge`]).
    beside_edge: bool,
    /// A hit within [`CENTRAL_FIELD_DEG`] of the eye's view axis.
    central: bool,
}

/// The cells of eye `layer`, row by row, from its occlusion `image` (RGBA at the full
/// image size); `fov`, the eye's field of view, places its central field (none without).
fn eye_cells(
    technique: Technique,
    image: &[f32],
    reference: &ReferenceImage,
    layer: usize,
    limit: Option<&ScreenLimit>,
    fov: Option<vrao_ao::Fov>,
) -> Vec<Cell> {
    let (w, h) = (reference.width as usize, reference.height as usize);
    // A pixel centre's tangents off the view axis, as the projection lays them out.
    let central_tan2 = CENTRAL_FIELD_DEG.to_radians().tan().powi(2);
    let central = |x: usize, y: usize| {
        fov.is_some_and(|fov| {
            let [left, right, up, down] = fov.tangents();
            let tan_x = left + (right - left) * (x as f64 + 0.5) / w as f64;
            let tan_y = up + (down - up) * (y as f64 + 0.5) / h as f64;
            tan_x * tan_x + tan_y * tan_y <= central_tan2
        })
    };
    let (gw, gh) = reference.grid_size();
    let pixels = &reference.layers[layer];
    let mut cells = Vec::with_capacity(pixels.len());
    for gy in 0..gh {
        for gx in 0..gw {
            let r = &pixels[(gy * gw + gx) as usize];
            let (x, y) = reference.pixel_of(gx, gy);
            let (x, y) = ((x as usize).min(w - 1), (y as usize).min(h - 1));
            let texel = &image[(y * w + x) * 4..(y * w + x) * 4 + 4];
            // Layer 0 is the left eye: its outer border is on the left.
            let outer = if layer == 0 { x } else { w - 1 - x };
            let l = limit.map(|l| *l.get(layer, gx, gy));
            let ambient = if technique.carries_light() {
                [texel[0], texel[1], texel[2]]
            } else {
                r.unoccluded.map(|c| c * texel[3])
            };
            let truth = [0, 1, 2].map(|c| r.environment_visible[c] + r.bounce[c]);
            cells.push(Cell {
                hit: r.hit,
                ao: texel[3],
                ref_ao: r.ao,
                ref_falloff: r.ao_falloff,
                noise2: if r.hit { (r.ao_std_error as f64).powi(2) } else { 0.0 },
                limit_ao: l.map_or(1.0, |l| l.ao),
                limit_hit: r.hit && l.is_some_and(|l| l.hit),
                ambient: [ambient[0], ambient[1], ambient[2], luminance(ambient) as f32],
                ref_ambient: [truth[0], truth[1], truth[2], luminance(truth) as f32],
                ambient_noise2: if r.hit { r.ambient_std_error.map(|e| (e as f64).powi(2)) } else { [0.0; 4] },
                outer_border: r.hit && outer.min(y).min(h - 1 - y) < BORDER_PX as usize,
                beside_edge: r.hit && near_depth_edge(pixels, (gw as usize, gh as usize), gx as usize, gy as usize),
                central: r.hit && central(x, y),
            });
        }
    }
    cells
}

/// One eye's SSIM of the AO against the reference on its grid (`gw × gh` cells), and its
/// mean FLIP at `grid_ppd` pixels per degree with the hit cells it covers (both images
/// with the sky as 1), if FLIP could be taken.
fn eye_similarity(cells: &[Cell], (gw, gh): (usize, usize), grid_ppd: f64) -> (f64, Option<(f64, usize)>) {
    let mask: Vec<bool> = cells.iter().map(|c| c.hit).collect();
    let ao: Vec<f32> = cells.iter().map(|c| c.ao).collect();
    let ref_ao: Vec<f32> = cells.iter().map(|c| c.ref_ao).collect();
    let ssim = metrics::ssim(&ao, &ref_ao, gw, gh, Some(&mask), 1.0).unwrap_or(0.0);
    let sky_is_one =
        |values: &[f32]| -> Vec<f32> { values.iter().zip(&mask).map(|(&v, &hit)| if hit { v } else { 1.0 }).collect() };
    let hits = mask.iter().filter(|&&m| m).count();
    let flip = metrics::flip_mean(&sky_is_one(&ao), &sky_is_one(&ref_ao), gw, gh, Some(&mask), grid_ppd);
    (ssim, flip.map(|mean| (mean, hits)))
}

/// A value of a cell (its AO, its reference's, …), and whether a cell counts.
type Value = fn(&Cell) -> f32;
type Keep = fn(&Cell) -> bool;

/// RMSE of `a` against `b` over the cells `keep` keeps (`None` when it keeps none).
fn rmse(cells: &[Cell], a: Value, b: Value, keep: Keep) -> Option<f64> {
    let (a, b): (Vec<f32>, Vec<f32>) = cells.iter().map(|c| (a(c), b(c))).unzip();
    let mask: Vec<bool> = cells.iter().map(keep).collect();
    metrics::rmse(&a, &b, Some(&mask))
}

/// [`rmse`] with the reference's own noise (RMS `noise`) taken out in quadrature.
fn corrected_rmse(cells: &[Cell], a: Value, b: Value, keep: Keep, noise: f64) -> f64 {
    metrics::noise_corrected_rmse(rmse(cells, a, b, keep).unwrap_or(f64::NAN), noise)
}

/// Mean of `a − b` over the cells `keep` keeps (`None` when it keeps none).
fn mean_difference(cells: &[Cell], a: Value, b: Value, keep: Keep) -> Option<f64> {
    let kept: Vec<&Cell> = cells.iter().filter(|c| keep(c)).collect();
    let sum: f64 = kept.iter().map(|c| a(c) as f64 - b(c) as f64).sum();
    (!kept.is_empty()).then(|| sum / kept.len() as f64)
}

/// The ambient light's RMSE in channel `k` (0–2 r, g, b; 3 luminance) relative to the
/// reference's mean over the `hits` hit cells, the reference's noise taken out; `None`
/// where the reference has no ambient light in that channel.
fn ambient_rel_rmse(cells: &[Cell], hits: f64, k: usize) -> Option<f64> {
    let kept = cells.iter().filter(|c| c.hit);
    let mean = kept.clone().map(|c| c.ref_ambient[k] as f64).sum::<f64>() / hits;
    let noise = (kept.clone().map(|c| c.ambient_noise2[k]).sum::<f64>() / hits).sqrt();
    let sum2: f64 = kept.map(|c| (c.ambient[k] as f64 - c.ref_ambient[k] as f64).powi(2)).sum();
    (mean > 1e-12).then(|| metrics::noise_corrected_rmse((sum2 / hits).sqrt(), noise) / mean)
}

/// (the frame against the screen-space limit, the limit's noise-corrected RMSE and its
/// bias against the reference), over the cells both hit; all `None` without a limit.
///
/// The limit against the reference has the reference's noise taken out, as `ao_rmse`
/// (so the two compare directly). The limit's own noise is not subtracted: its binomial
/// bound ignores the stratification of its rays and is well above what they leave, so
/// subtracting it would zero real error (docs/records/2026-11-29/measurements-in-code.md, limit-bound).
fn limit_figures(cells: &[Cell]) -> (Option<f64>, Option<f64>, Option<f64>) {
    let both = cells.iter().filter(|c| c.limit_hit).count();
    if both == 0 {
        return (None, None, None);
    }
    let ref_noise2 = cells.iter().filter(|c| c.limit_hit).map(|c| c.noise2).sum::<f64>() / both as f64;
    (
        rmse(cells, |c| c.ao, |c| c.limit_ao, |c| c.limit_hit),
        Some(corrected_rmse(cells, |c| c.limit_ao, |c| c.ref_ao, |c| c.limit_hit, ref_noise2.sqrt())),
        mean_difference(cells, |c| c.limit_ao, |c| c.ref_ao, |c| c.limit_hit),
    )
}

/// The share of the cells beside a depth edge that are darker than the reference by
/// more than [`HALO_DARKER`]; `None` without an edge.
fn halo_share(cells: &[Cell]) -> Option<f64> {
    let edge = cells.iter().filter(|c| c.beside_edge).count();
    let halos = cells.iter().filter(|c| c.beside_edge && c.ao < c.ref_ao - HALO_DARKER).count();
    (edge > 0).then(|| halos as f64 / edge as f64)
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
