//! Denoising and upsampling of the occlusion on the GPU: the bilateral blur keeps a depth
//! edge, half resolution stays close to full resolution and works at odd sizes, and the
//! composite's inline upsample of half-resolution occlusion matches the full-resolution
//! image.
//!
//! `cargo test --release --test occlusion_denoise -- --nocapture` shows what the tests measure.

use crate::common;

use common::occlusion::{ao, ao_techniques, mean, render, same_surface_blur, settings, Frame};
use glam::DVec3;
use vrao_ao::plug::{AO_BLURRED, AO_FULL, AO_RAW};
use vrao_ao::{AoSettings, HeadPose, Technique};
use vrao_render::passes::composite::HDR;
use vrao_render::scene::Scene;

// ---------------------------------------------------------------------------------------
// Bilateral blur

#[test]
fn blur_keeps_a_depth_edge() {
    let (gpu, _guard) = common::gpu();
    let (f, blur) = render_depth_step(&gpu);
    let (near, far) = edge_sides(&f, blur);
    let m = |v: &Vec<f64>| mean(v.iter().copied());
    let (near_raw, near_blur, near_same, near_naive) = (m(&near.raw), m(&near.blurred), m(&near.same), m(&near.naive));
    let (far_raw, far_blur, far_same, far_naive) = (m(&far.raw), m(&far.blurred), m(&far.same), m(&far.naive));
    eprintln!(
        "blur edge ({} near px, {} far px): near raw {near_raw:.3} blurred {near_blur:.3} same-surface {near_same:.3} naive {near_naive:.3}; \
         far raw {far_raw:.3} blurred {far_blur:.3} same-surface {far_same:.3} naive {far_naive:.3}",
        near.raw.len(),
        far.raw.len()
    );
    assert!(near.raw.len() > 200 && far.raw.len() > 200, "the silhouette is visible");
    // The case has contrast: unoccluded panel, strongly occluded wall beside it.
    assert!(near_raw > 0.97 && near_raw - far_raw > 0.3, "no contrast across the edge: {near_raw} vs {far_raw}");
    // A blur that ignored the edge would pull the panel down and the wall up; this
    // shows by how much (the test's power), measured on the same raw AO.
    assert!(near_naive < near_same - 0.05, "the case cannot tell a leaking blur: naive {near_naive}");
    // The blurred panel stays at its own surface's average (≈ 1), within 0.02.
    assert!(near_blur >= near_same - 0.02, "blur pulls the panel towards the wall: {near_blur} vs {near_same}");
    // The blurred wall rises no more than averaging over the wall itself allows (the
    // halo fades away from the edge, so even a perfect blur lifts it a little).
    assert!(far_blur <= far_same + 0.03, "blur pulls the wall towards the panel: {far_blur} vs {far_same}");
    // Hence the jump across the silhouette survives: a blur that keeps to each surface
    // leaves about 2/3 of it here (the halo fades away from the edge, so averaging over
    // the wall alone lifts the wall side), the naive blur about 1/7.
    assert!(
        near_blur - far_blur >= 0.5 * (near_raw - far_raw),
        "the edge is blurred away: jump {:.3} blurred vs {:.3} raw",
        near_blur - far_blur,
        near_raw - far_raw
    );
}

/// Renders a depth step with SSAO without the range check; returns the frame and the
/// blur radius.
///
/// A wall 4 m ahead, and 2 m ahead of it a panel covering the left half of the view
/// (its right edge at x = 0), both facing the eye: a vertical depth step down the
/// middle of each image. Without the range check, SSAO darkens the far wall beside
/// the step (samples in front of the wall that project onto the much closer panel
/// count as occluded, the classic halo): strongly occluded on the far side of the
/// edge, unoccluded (AO = 1) on the panel itself.
fn render_depth_step(gpu: &std::sync::Arc<vrao_ao::plug::Gpu>) -> (Frame, i32) {
    let scene = common::bare_scene(vec![
        common::square("wall", DVec3::new(0.0, 0.0, -4.0), 12.0, 0),
        common::square("panel", DVec3::new(-3.0, 0.0, -2.0), 6.0, 0),
    ]);
    let mut a = ao(Technique::Ssao, 32, 1.0);
    a.range_check = false;
    let s = settings(128, 144, a);
    let f = render(gpu, &scene, &s, &HeadPose::IDENTITY, &[AO_RAW, AO_BLURRED]);
    (f, s.ao.blur_radius as i32)
}

/// The AO of one side's pixels next to the silhouette.
#[derive(Default)]
struct EdgeSide {
    raw: Vec<f64>,
    /// Blurred on the GPU.
    blurred: Vec<f64>,
    /// The raw AO blurred on the CPU within its own surface.
    same: Vec<f64>,
    /// The raw AO blurred on the CPU across both surfaces.
    naive: Vec<f64>,
}

/// Both eyes' pixels 1–2 px from the silhouette (Chebyshev), far from the image edge:
/// (panel side, wall side).
fn edge_sides(f: &Frame, blur: i32) -> (EdgeSide, EdgeSide) {
    let (w, h) = (f.width, f.height);
    let (mut near, mut far) = (EdgeSide::default(), EdgeSide::default());
    for layer in 0..2 {
        // 1 = panel (about 2 m away), 2 = wall (about 4 m).
        let class: Vec<u8> = f.world[layer].iter().map(|p| p.map_or(0, |p| if p.z > -3.0 { 1 } else { 2 })).collect();
        let raw: Vec<f64> = (0..w * h).map(|i| f.outputs[&AO_RAW][layer][4 * i as usize + 3] as f64).collect();
        let same = same_surface_blur(&raw, &class, w, h, blur);
        // A geometry-unaware blur of the same raw AO, to show the test would catch one.
        let naive = same_surface_blur(&raw, &vec![1; raw.len()], w, h, blur);
        for y in 0..h as i32 {
            for x in 0..w as i32 {
                let i = (y as u32 * w + x as u32) as usize;
                let c = class[i];
                if c == 0 || x < 16 || y < 16 || x >= w as i32 - 16 || y >= h as i32 - 16 {
                    continue;
                }
                if !(1..=2).contains(&silhouette_distance(&class, w, x, y)) {
                    continue;
                }
                let side = if c == 1 { &mut near } else { &mut far };
                side.raw.push(raw[i]);
                side.blurred.push(f.ao(AO_BLURRED, layer, x as u32, y as u32));
                side.same.push(same[i]);
                side.naive.push(naive[i]);
            }
        }
    }
    (near, far)
}

/// Chebyshev distance (up to 3, else 99) from `(x, y)` to a pixel of another class.
fn silhouette_distance(class: &[u8], w: u32, x: i32, y: i32) -> i32 {
    let c = class[(y as u32 * w + x as u32) as usize];
    (1..=3)
        .find(|&k| (-k..=k).any(|dy| (-k..=k).any(|dx| class[((y + dy) as u32 * w + (x + dx) as u32) as usize] != c)))
        .unwrap_or(99)
}

// ---------------------------------------------------------------------------------------
// Half resolution

#[test]
fn half_resolution_stays_close_to_full_resolution() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in [Technique::Ssao, Technique::Hbao, Technique::Ssdo, Technique::SsdoPoints] {
        let full = settings(128, 144, ao(technique, 24, 1.0));
        let mut half = full.clone();
        half.ao.resolution = vrao_ao::Resolution::Half;
        let f = render(&gpu, &scene, &full, &head, &[AO_BLURRED]);
        let g = render(&gpu, &scene, &half, &head, &[AO_FULL]);
        let pairs: Vec<(f64, f64)> = f
            .pixels()
            .filter(|&(l, x, y)| f.world(l, x, y).is_some())
            .map(|(l, x, y)| (f.ao(AO_BLURRED, l, x, y), g.ao(AO_FULL, l, x, y)))
            .collect();
        let diffs: Vec<f64> = pairs.iter().map(|(a, b)| (a - b).abs()).collect();
        let mad = mean(diffs.iter().copied());
        let mad_occluded = mean(pairs.iter().filter(|(a, b)| a.min(*b) < 0.95).map(|(a, b)| (a - b).abs()));
        let signed = mean(pairs.iter().map(|(a, b)| a - b));
        let bad = diffs.iter().filter(|d| **d > 0.2).count() as f64 / diffs.len() as f64;
        eprintln!(
            "half res {}: mean |full − half| {mad:.4} (occluded px {mad_occluded:.4}), mean full − half {signed:+.4}, \
             {:.2} % of pixels off by > 0.2",
            technique.name(),
            bad * 100.0
        );
        // Both estimate the same per-pixel expectation (same world-space radius and
        // estimator). They differ by (a) the rotation noise left after the blur, different
        // in the two because different pixels are sampled (about ±0.01–0.02 per pixel at
        // 24 taps; the crease bins show the blurred AO within 0.004 of its expectation
        // on average), and (b) interpolation: half resolution knows AO every second
        // pixel, and where AO changes fast (contact shadows at the room's corners and
        // box: 0.3 over about 10 px at this size) the 3×3 joint bilateral upsampling
        // misses curvature and thin features by a few hundredths. Over every non-sky
        // pixel (most of them unoccluded, where both are 1) the mean |difference| must
        // stay below 0.03; over occluded pixels (AO < 0.95 in either) below 0.06, twice
        // what (a) and (b) give. A broken upsampler (wrong neighbour, a pixel offset,
        // weights across depth edges, a cleared last row or column) makes bands along
        // every edge: many pixels off by more than 0.2 (allowed: 0.5 %).
        assert!(mad < 0.03, "{}: mean |full − half| = {mad}", technique.name());
        assert!(mad_occluded < 0.06, "{}: mean |full − half| on occluded pixels = {mad_occluded}", technique.name());
        assert!(signed.abs() < 0.01, "{}: half resolution is biased ({signed:+.4})", technique.name());
        assert!(bad < 0.005, "{}: {:.2} % of pixels differ by > 0.2", technique.name(), bad * 100.0);
    }
}

#[test]
fn odd_sizes_work_at_half_resolution() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in ao_techniques() {
        let mut a = ao(technique, 12, 0.5);
        a.resolution = vrao_ao::Resolution::Half;
        let s = settings(97, 109, a);
        let outputs = [AO_RAW, AO_BLURRED, AO_FULL, HDR];
        let f = render(&gpu, &scene, &s, &head, &outputs);
        for (r, (w, h)) in [(AO_RAW, (49, 55)), (AO_BLURRED, (49, 55)), (AO_FULL, (97, 109))] {
            for layer in &f.outputs[&r] {
                assert_eq!(layer.len(), w * h * 4, "{} {}: not {w}×{h}", technique.name(), r.name());
                assert!(layer.iter().all(|v| v.is_finite()), "{} {}: not finite", technique.name(), r.name());
                assert!(layer.chunks(4).all(|p| (0.0..=1.0).contains(&p[3])), "{}: AO out of range", r.name());
            }
        }
        // The last row and column of the full-res AO carry values, not a cleared edge.
        let last_column_lit = (0..109).filter(|&y| f.world(0, 96, y).is_some()).all(|y| f.ao(AO_FULL, 0, 96, y) > 0.0);
        assert!(last_column_lit, "{}: last column of ao-full is empty", technique.name());
    }
}

/// The composite upsamples half-resolution occlusion inline. Its image must match the
/// full-resolution one as closely as the upsampled AO matches (AO differs by ≈ 0.005 on
/// average, and scales only the ambient share of the radiance), so the mean relative
/// radiance difference stays below 1 %; an inline upsample reading the wrong texel or
/// layer would leave contact shadows misplaced by pixels and fail this.
#[test]
fn the_composite_upsamples_half_resolution_occlusion_inline() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in [Technique::Ssao, Technique::Ssdo, Technique::SsdoPoints] {
        let base = AoSettings { technique, samples: 32, radius: 1.0, ..AoSettings::default() };
        let full = render(&gpu, &scene, &settings(128, 144, base.clone()), &head, &[HDR]);
        let half_settings = AoSettings { resolution: vrao_ao::Resolution::Half, ..base };
        let half = render(&gpu, &scene, &settings(128, 144, half_settings), &head, &[HDR]);
        assert!(!half.report.plan.runs("upsample"), "the frame upsampled in a pass of its own");
        let (mut diff, mut total) = (0.0, 0.0);
        for layer in 0..2 {
            let (a, b) = (&full.outputs[&HDR][layer], &half.outputs[&HDR][layer]);
            for (x, y) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
                diff += (0..3).map(|c| (x[c] - y[c]).abs() as f64).sum::<f64>();
                total += (0..3).map(|c| x[c].abs() as f64).sum::<f64>();
            }
        }
        let relative = diff / total.max(1e-12);
        eprintln!("{}: half-res composite differs from full-res by {:.4} (relative)", technique.name(), relative);
        assert!(relative < 0.01, "{}: relative difference {relative}", technique.name());
    }
}
