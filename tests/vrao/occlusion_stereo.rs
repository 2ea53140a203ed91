//! Stereo consistency of the occlusion on the GPU: both eyes see the same occlusion on
//! the same surface, the right eye reuses the left eye's AO where it sees the same point
//! (in the AO the bench scores and in the composite a headset shows), and a march that
//! leaves an eye's image through its inner border goes on in the other eye's layer.
//!
//! `cargo test --release --test occlusion_stereo -- --nocapture` shows what the tests measure.

use crate::common;

use common::occlusion::{ao, ao_techniques, mean, render, settings};
use glam::DVec3;
use vrao::measure::stereo_consistency::{stereo_consistency, EyeImages};
use vrao_ao::plug::{AO_BLURRED, AO_FULL, AO_RAW, DEPTH};
use vrao_ao::{HeadPose, Technique};
use vrao_render::passes::composite::HDR;
use vrao_render::scene::Scene;

// ---------------------------------------------------------------------------------------
// Stereo consistency

#[test]
fn both_eyes_see_the_same_occlusion_on_the_same_surface() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for technique in ao_techniques() {
        let s = settings(128, 144, ao(technique, 32, 1.0));
        let f = render(&gpu, &scene, &s, &head, &[AO_BLURRED]);
        let (mut diffs, mut signed, mut occluded, mut unmatched) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let margin = 16;
        for y in margin..f.height - margin {
            for x in margin..f.width - margin {
                let Some(p) = f.world(0, x, y) else { continue };
                let Some((rx, ry)) = f.pixel_of(1, p) else { continue };
                if rx < margin || ry < margin || rx >= f.width - margin || ry >= f.height - margin {
                    continue;
                }
                // Same surface: the right eye sees a point within 1 % of the distance.
                let Some(q) = f.world(1, rx, ry) else { continue };
                if (q - p).length() > 0.01 * (p - f.eyes.eyes[0].pose.position).length() {
                    continue;
                }
                let (left, right) = (f.ao(AO_BLURRED, 0, x, y), f.ao(AO_BLURRED, 1, rx, ry));
                let d = left - right;
                diffs.push(d.abs());
                signed.push(d);
                if left.min(right) < 0.95 {
                    occluded.push(d.abs());
                    // The same pixel of the right eye (no reprojection): what a test that
                    // ignored parallax would compare.
                    unmatched.push((left - f.ao(AO_BLURRED, 1, x, y)).abs());
                }
            }
        }
        let (mad, bias) = (mean(diffs.iter().copied()), mean(signed.iter().copied()));
        let (mad_occluded, mad_unmatched) = (mean(occluded.iter().copied()), mean(unmatched.iter().copied()));
        eprintln!(
            "stereo {}: {} matched px, mean |left − right| {mad:.4}, mean left − right {bias:+.4}; \
             {} occluded px (AO < 0.95): mean |left − right| {mad_occluded:.4}, same pixel without reprojection {mad_unmatched:.4}",
            technique.name(),
            diffs.len(),
            occluded.len()
        );
        assert!(diffs.len() > 5000, "too few matched pixels ({})", diffs.len());
        // The eyes see the same surface from 64 mm apart, so the per-pixel expectation
        // agrees up to the screen-space view dependence, which is small at this baseline
        // (the crease bins match an eye-specific expectation to 0.004 in both eyes). What
        // differs is the rotation noise: the same surface point falls on different pixels,
        // hence different rotations; after the 11×11 blur about ±0.01 per pixel remains.
        // Tolerances: mean |left − right| below 0.03 over occluded pixels (AO < 0.95 in
        // either eye: where there is something to disagree about) and below 0.015 over
        // all matched pixels, no systematic difference (|mean left − right| < 0.01).
        // Comparing the same pixel of both eyes without reprojection gives 0.08–0.10 on
        // occluded pixels, so an eye rendered with the other eye's view, a swapped layer
        // or a parallax error fails.
        assert!(mad_occluded < 0.03, "{}: eyes disagree where occluded: {mad_occluded}", technique.name());
        assert!(mad < 0.015, "{}: eyes disagree, mean |left − right| = {mad}", technique.name());
        assert!(bias.abs() < 0.01, "{}: one eye is systematically darker ({bias:+.4})", technique.name());
        assert!(occluded.len() > 1000 && mad_unmatched > 2.0 * 0.03, "the case cannot tell misaligned eyes");
    }
}

/// The right eye takes the left eye's value wherever the left eye sees the same surface
/// point: every technique's march or samples, and at half resolution the AO-only
/// techniques' upsample (SSDO's denoise, its vertical pass). The share of
/// stereo-inconsistent points (the bench's measure: AO differing by more than 0.02
/// between the eyes, `vrao::measure::stereo_consistency`) falls below 0.6 of what it is
/// with independent eyes (measured on the furnished room: GTAO full 1.8 → 0.85 %, half
/// 3.3 → 0.5 %; SSAO half 3.1 → 0.3 %; HBAO full 0.84 → 0.46 %: at full resolution what
/// is left is each eye's own denoise).
#[test]
fn the_right_eye_reuses_the_left_eye_where_it_sees_the_same_point() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let head = scene.head.pose_at(0.0);
    for (technique, half_res) in
        [(Technique::Gtao, false), (Technique::Gtao, true), (Technique::Ssao, true), (Technique::Hbao, false)]
    {
        let mut shares = [0.0; 2];
        for (i, reuse) in [false, true].into_iter().enumerate() {
            let mut a = ao(technique, 24, 0.3);
            (a.stereo_reuse, a.resolution) = (reuse, vrao_ao::Resolution::from_half_res(half_res));
            let s = settings(540, 600, a);
            let final_ao = if half_res { AO_FULL } else { AO_BLURRED };
            let f = render(&gpu, &scene, &s, &head, &[final_ao, DEPTH]);
            let depth = &f.outputs[&DEPTH];
            let ao: Vec<Vec<f32>> = f.outputs[&final_ao].iter().map(|l| l.chunks(4).map(|p| p[3]).collect()).collect();
            let images = [0, 1].map(|l| EyeImages { depth: &depth[l], ao: &ao[l] });
            let c = stereo_consistency(&f.eyes.eyes, images, (f.width, f.height), f.eyes.near);
            eprintln!("{technique:?} stereo reuse {reuse}, half {half_res}: {c:?}");
            assert!(c.compared > 50_000, "too few points compared ({})", c.compared);
            shares[i] = c.inconsistent.unwrap();
        }
        let [independent, reused] = shares;
        assert!(
            reused < 0.6 * independent,
            "{technique:?}, half {half_res}: {:.1} % inconsistent with reuse, {:.1} % with independent eyes",
            100.0 * reused,
            100.0 * independent
        );
    }
}

/// At half resolution the right eye takes the left eye's upsampled AO wherever the left
/// eye sees the same point (joint_upsample.wgsl `right_eye_quad`), in the composite that
/// a headset shows (the AO in the HDR target's alpha) as in the upsample pass the bench
/// scores (AoFull). Both hold the same AO in every pixel of both eyes, with the reuse and
/// without it; with it, a right-eye pixel whose point lands on a left-eye pixel of the
/// same surface holds that pixel's AO (f16 rounding apart, and a pixel-boundary rounding
/// between the test's f64 projection and the shader's f32 one at a few pixels).
#[test]
fn the_composite_shows_the_ao_the_bench_scores_and_the_right_eye_takes_the_left_eyes() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let head = scene.head.pose_at(0.0);
    for (technique, reuse) in [(Technique::Gtao, true), (Technique::Hbao, true), (Technique::Gtao, false)] {
        let mut a = ao(technique, 12, 0.3);
        (a.stereo_reuse, a.resolution) = (reuse, vrao_ao::Resolution::Half);
        let f = render(&gpu, &scene, &settings(96, 112, a), &head, &[AO_FULL, HDR]);
        let case = format!("{technique:?}, reuse {reuse}");
        let mut surface = 0;
        for (l, x, y) in f.pixels() {
            if f.world(l, x, y).is_none() {
                continue;
            }
            surface += 1;
            let (shown, scored) = (f.ao(HDR, l, x, y), f.ao(AO_FULL, l, x, y));
            assert!((shown - scored).abs() < 2e-3, "{case}: eye {l} ({x}, {y}) shows {shown}, scored {scored}");
        }
        assert!(surface > 10_000, "{case}: {surface} surface pixels");
        if !reuse {
            continue;
        }
        let (mut compared, mut equal) = (0, 0);
        for (x, y) in f.pixels().filter(|&(l, _, _)| l == 1).map(|(_, x, y)| (x, y)) {
            let Some(p) = f.world(1, x, y) else { continue };
            let Some((lx, ly)) = f.pixel_of(0, p) else { continue };
            let Some(q) = f.world(0, lx, ly) else { continue };
            let eye = f.eyes.eyes[0].pose.position;
            if ((q - eye).length() - (p - eye).length()).abs() > 0.005 * (p - eye).length() {
                continue;
            }
            compared += 1;
            let (right, left) = (f.ao(AO_FULL, 1, x, y), f.ao(AO_FULL, 0, lx, ly));
            equal += usize::from((right - left).abs() < 2e-3);
        }
        eprintln!("{case}: {equal} of {compared} right-eye pixels hold the left eye's AO");
        assert!(compared > 5_000, "{case}: only {compared} pixels seen by both eyes");
        assert!(equal as f64 > 0.98 * compared as f64, "{case}: {equal} of {compared} hold the left eye's AO");
    }
}

/// A march that leaves an eye's image through its inner (nasal) border goes on in the
/// other eye's layer, which sees past that border. On surface points near the inner
/// border that the other eye sees well inside its image, the two eyes' raw AO agree;
/// with those marches stopped at the border instead (checked by hand: gtao.wgsl's band
/// dispatch without lookups) the eye at its border reads lighter by 0.047. Each eye
/// marches on its own here (the right eye's reuse of the left eye would agree anyway).
#[test]
fn marches_past_the_inner_border_continue_in_the_other_eye() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    let mut a = ao(Technique::Gtao, 64, 1.0);
    a.stereo_reuse = false;
    let s = settings(128, 144, a);
    let f = render(&gpu, &scene, &s, &head, &[AO_RAW]);
    let band = 12;
    let (mut signed, mut occlusion) = (Vec::new(), Vec::new());
    // Left eye: inner border on the right; right eye: on the left.
    for (layer, other, columns) in [(0usize, 1usize, (f.width - band)..f.width), (1, 0, 0..band)] {
        for x in columns {
            for y in band..f.height - band {
                let Some(p) = f.world(layer, x, y) else { continue };
                let Some((ox, oy)) = f.pixel_of(other, p) else { continue };
                if ox < band || ox >= f.width - band || oy < band || oy >= f.height - band {
                    continue;
                }
                let Some(q) = f.world(other, ox, oy) else { continue };
                if (q - p).length() > 0.01 * (p - f.eyes.eyes[layer].pose.position).length() {
                    continue;
                }
                let (here, there) = (f.ao(AO_RAW, layer, x, y), f.ao(AO_RAW, other, ox, oy));
                signed.push(here - there);
                occlusion.push(1.0 - there);
            }
        }
    }
    let (bias, occluded) = (mean(signed.iter().copied()), mean(occlusion.iter().copied()));
    eprintln!(
        "inner border: {} matched px, mean (border eye − other eye) {bias:+.4}, mean occlusion seen by the other eye {occluded:.3}",
        signed.len()
    );
    assert!(signed.len() > 500, "too few matched pixels at the inner borders ({})", signed.len());
    assert!(occluded > 0.05, "nothing occluded at the inner borders: the case cannot tell");
    assert!(bias.abs() < 0.015, "the eye at its inner border disagrees with the other eye by {bias:+.4}");
}

/// A march from the rest of the image that would cross the inner border (a surface so
/// near that the radius spans more than the band along that border, a quarter of the
/// image) is deferred to the band's pipeline, which looks past the border, so the AO runs
/// on across the band's edge. Looking at the furnished room's shelves from 30 cm, the
/// denoised AO's change from column to column at the band's edge is like its change
/// elsewhere; with those marches stopped at the border (before the deferral) it was six
/// times that, a seam from top to bottom. Both eyes' edges with independent eyes, the
/// left eye's with the reuse (the right eye's listed marches defer alike).
#[test]
fn a_near_surface_shows_no_seam_at_the_inner_band_edge() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let head = HeadPose::look_at(DVec3::new(1.15, 1.6, -5.7), DVec3::new(1.15, 1.4, -6.5)).unwrap();
    // The band is a quarter of the width in whole 8-pixel workgroups (gtao_inner_band).
    let (w, h, band) = (192u32, 216u32, 48u32);
    for reuse in [true, false] {
        let mut a = ao(Technique::Gtao, 24, 0.5);
        (a.stereo_reuse, a.resolution) = (reuse, vrao_ao::Resolution::Full);
        let f = render(&gpu, &scene, &settings(w, h, a), &head, &[AO_BLURRED]);
        // The band's first column: the left eye's inner border is on its right.
        let edges: &[(usize, u32)] = if reuse { &[(0, w - band)] } else { &[(0, w - band), (1, band)] };
        for &(layer, edge) in edges {
            // The mean change of the AO from column x to x + 1 over the rows.
            let step = |x: u32| {
                mean((0..h).map(|y| (f.ao(AO_BLURRED, layer, x + 1, y) - f.ao(AO_BLURRED, layer, x, y)).abs()))
            };
            let at_edge = (edge - 3..edge + 2).map(step).fold(0.0, f64::max);
            let mut elsewhere: Vec<f64> = (edge - 24..edge - 8).chain(edge + 8..edge + 24).map(step).collect();
            elsewhere.sort_by(f64::total_cmp);
            let typical = elsewhere[elsewhere.len() / 2];
            eprintln!("reuse {reuse}, eye {layer}, band edge at column {edge}: largest step {at_edge:.4}, typical {typical:.4}");
            assert!(typical > 0.0, "reuse {reuse}, eye {layer}: a flat image cannot show a seam");
            assert!(
                at_edge < 2.5 * typical,
                "reuse {reuse}, eye {layer}: the AO steps by {at_edge:.4} at the band's edge (column {edge}), {typical:.4} elsewhere"
            );
        }
    }
}

/// The right eye computes only what the left eye cannot give it (right_eye.wgsl
/// `classify_right_eye`, the FALLBACK of upsample.wgsl and composite.wgsl): counted from
/// the indirect dispatches' arguments, the work is a share of the right eye's tiles; two
/// eyes at one place with one field of view need none of it; independent eyes report
/// nothing.
#[test]
fn the_right_eye_computes_only_the_tiles_the_left_eye_cannot_give() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let head = scene.head.pose_at(0.0);
    let counts_of = |s: &vrao_render::Settings, output| {
        let mut renderer = vrao_render::Renderer::new(gpu.clone(), &scene, s).unwrap();
        renderer.render_and_wait(&s.profile.eyes(&head, s.near).eyes, &[output]).unwrap();
        renderer.right_eye_tiles()
    };
    let counts = |s: &vrao_render::Settings| counts_of(s, if s.ao.resolution.is_half() { AO_FULL } else { AO_BLURRED });
    // Every technique that estimates per pixel from depth, at half and full resolution.
    for (technique, half_res) in [(Technique::Ssao, false), (Technique::Hbao, true), (Technique::Gtao, true)] {
        let mut a = ao(technique, 24, 0.3);
        a.resolution = vrao_ao::Resolution::from_half_res(half_res);
        let tiles = counts(&settings(192, 216, a));
        let passes: Vec<&str> = tiles.iter().map(|t| t.pass).collect();
        let expected: &[&str] = if half_res { &[technique.name(), "upsample"] } else { &[technique.name()] };
        assert_eq!(passes, expected, "{tiles:?}");
        for t in &tiles {
            eprintln!("{}: {} of {} tiles, {} items", t.pass, t.computed, t.total, t.items);
            assert_eq!(t.computed, t.items.div_ceil(64), "64 listed items to a dispatched tile: {t:?}");
            assert!(t.computed > 0 && t.share() < 0.35, "the right eye computes a part of its tiles: {t:?}");
        }
    }
    let mut a = ao(Technique::Gtao, 24, 0.3);
    a.resolution = vrao_ao::Resolution::Half;
    let stereo = settings(192, 216, a.clone());
    // A frame upsamples in its composite, which lists the same quads as the upsampling.
    let upsampled = counts(&stereo);
    let framed = counts_of(&stereo, HDR);
    let passes: Vec<&str> = framed.iter().map(|t| t.pass).collect();
    assert_eq!(passes, ["gtao", "composite"], "{framed:?}");
    assert_eq!((framed[1].computed, framed[1].items), (upsampled[1].computed, upsampled[1].items), "{framed:?}");
    let mut one_place = stereo.clone();
    (one_place.profile.ipd, one_place.profile.fov_right) = (0.0, one_place.profile.fov_left);
    for t in counts(&one_place) {
        assert!(t.items * 100 <= t.total * 64, "eyes at one place with one view share all but a few items: {t:?}");
    }
    a.stereo_reuse = false;
    assert!(counts(&settings(192, 216, a)).is_empty(), "independent eyes list nothing");
}

/// Facing a wall (the plane seen straight down from distance d), what the left eye cannot
/// give the right eye is the strip of its outer side beyond the left eye's inner edge: the
/// columns whose tangent exceeds the left eye's inner tangent less ipd / d. The lists hold
/// exactly those (within a column of f32 rounding against this f64 count): at full
/// resolution the strip's pixels; at half resolution the march's occlusion pixels b whose
/// full-res pixel 2b lies in it, and the upsampling's quads with any pixel in it (their
/// right column, 2b + 1). Nothing the left eye sees is computed again, nothing it misses is
/// left out. The strip widens as the wall comes nearer (this headset's 13 % far away, 21 %
/// at 30 cm): no reuse of the left eye can give it.
#[test]
fn facing_a_wall_the_right_eye_computes_the_strip_the_left_eye_never_sees() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:plane").unwrap();
    let (w, h) = (192u32, 216u32);
    for half_res in [false, true] {
        let mut a = ao(Technique::Gtao, 12, 0.1);
        a.resolution = vrao_ao::Resolution::from_half_res(half_res);
        let s = settings(w, h, a);
        let [outer_left, outer_right, _, _] = s.profile.fov_right.tangents();
        let inner_of_left_eye = s.profile.fov_left.tangents()[1];
        for d in [0.3, 1.0, 4.0] {
            let beyond = |column: u32| {
                let tangent = outer_left + (f64::from(column) + 0.5) / f64::from(w) * (outer_right - outer_left);
                tangent > inner_of_left_eye - s.profile.ipd / d
            };
            let in_strip = |columns: &mut dyn Iterator<Item = u32>, rows: u32| {
                columns.filter(|&c| beyond(c)).count() as u32 * rows
            };
            let expected: Vec<(&str, u32)> = if half_res {
                vec![
                    ("gtao", in_strip(&mut (0..w / 2).map(|b| 2 * b), h / 2)),
                    ("upsample", in_strip(&mut (0..w / 2).map(|b| 2 * b + 1), h / 2)),
                ]
            } else {
                vec![("gtao", in_strip(&mut (0..w), h))]
            };
            let head = HeadPose::look_at(DVec3::new(0.0, d, 0.0), DVec3::ZERO).unwrap();
            let mut renderer = vrao_render::Renderer::new(gpu.clone(), &scene, &s).unwrap();
            let output = if half_res { AO_FULL } else { AO_BLURRED };
            renderer.render_and_wait(&s.profile.eyes(&head, s.near).eyes, &[output]).unwrap();
            let tiles = renderer.right_eye_tiles();
            assert_eq!(tiles.len(), expected.len(), "{tiles:?}");
            for (t, (pass, strip)) in tiles.iter().zip(expected) {
                let (columns, rows) = if half_res { (w / 2, h / 2) } else { (w, h) };
                let share = 100.0 * f64::from(strip) / f64::from(columns * rows);
                eprintln!(
                    "half {half_res}, wall at {d} m, {pass}: {} listed, {strip} in the strip ({share:.1} %)",
                    t.items
                );
                assert_eq!(t.pass, pass);
                assert!(
                    t.items.abs_diff(strip) <= rows,
                    "half {half_res}, wall at {d} m, {pass}: {} listed, the strip holds {strip}",
                    t.items
                );
            }
        }
    }
}

/// GTAO's right eye folded into the left eye's dispatch (`GtaoSettings::fold_right_eye`:
/// listed from the depth before the left eye marches, marched after the left eye's tiles,
/// copied last) is the copied-first right eye: the same pixels listed, the same AO but
/// for a few pixels at the same-surface test's edge (the left eye's distances read from
/// its depth instead of its AoGeometry's half floats), the left eye untouched. GTAO and
/// SSDO on its march, full and half resolution, at the scene's pose and 30 cm from a wall.
#[test]
fn the_folded_right_eye_is_the_copied_first_right_eye() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:furnished").unwrap();
    let wall = HeadPose::look_at(DVec3::new(1.15, 1.6, -5.7), DVec3::new(1.15, 1.4, -6.5)).unwrap();
    let frame = |s: &vrao_render::Settings, head: &HeadPose| {
        let mut renderer = vrao_render::Renderer::new(gpu.clone(), &scene, s).unwrap();
        renderer.render_and_wait(&s.profile.eyes(head, s.near).eyes, &[AO_RAW]).unwrap();
        let tiles: Vec<(u32, u32)> =
            renderer.right_eye_tiles().iter().filter(|t| t.pass != "upsample").map(|t| (t.computed, t.items)).collect();
        (renderer.read_f32(AO_RAW).unwrap(), tiles)
    };
    for head in [scene.head.pose_at(0.0), wall] {
        for (technique, half_res) in [(Technique::Gtao, false), (Technique::Gtao, true), (Technique::Ssdo, true)] {
            let mut a = ao(technique, 24, 0.3);
            a.resolution = vrao_ao::Resolution::from_half_res(half_res);
            let copied_first = settings(192, 216, a.clone());
            a.gtao.fold_right_eye = true;
            let folded = settings(192, 216, a);
            let ((before, listed_before), (after, listed_after)) = (frame(&copied_first, &head), frame(&folded, &head));
            let case = format!("{technique:?}, half {half_res}, head {head:?}");
            assert!(before[0] == after[0], "{case}: the left eye changed");
            assert!(
                !listed_after.is_empty() && listed_before == listed_after,
                "{case}: {listed_before:?} against {listed_after:?}"
            );
            let differing =
                before[1].chunks(4).zip(after[1].chunks(4)).filter(|(b, a)| (b[3] - a[3]).abs() > 1e-6).count();
            let pixels = before[1].len() / 4;
            eprintln!("{case}: {listed_after:?} listed, {differing} of {pixels} right-eye pixels differ");
            assert!(differing * 500 < pixels, "{case}: {differing} of {pixels} right-eye pixels differ");
        }
    }
}
