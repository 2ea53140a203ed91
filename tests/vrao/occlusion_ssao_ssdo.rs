//! SSAO and SSDO (with and without the bounce) on the GPU: on a 90° crease SSAO and the
//! point-sampled SSDO (`ssdo-points`) match their expected values (simulated on the CPU
//! and in closed form, `vrao::measure::analytic`), `ssdo-points` also the falloff
//! reference, and SSDO on GTAO's bitmask (`ssdo`) has GTAO's occlusion exactly; both
//! SSDOs shadow what faces away from a single light where SSAO cannot and gather the
//! unoccluded ambient on an open plane; a red wall bleeds red only with the bounce.
//!
//! `cargo test --release --test occlusion_ssao_ssdo -- --nocapture` shows what the tests measure.

use crate::common;

use common::crease::{assert_bins, assert_falls_towards_the_edge, measure_crease, EXPECTATION_TOLERANCE};
use common::occlusion::{ao, mean, render, settings, Frame};
use glam::{DVec3, Vec3};
use vrao::measure::analytic;
use vrao_ao::plug::AO_RAW;
use vrao_ao::{HeadPose, Technique};
use vrao_render::passes::composite::HDR;
use vrao_render::scene::builtin::{ROOM_MAX, ROOM_MIN};
use vrao_render::scene::{environment, Environment, Scene};
use vrao_render::BounceForm;

// ---------------------------------------------------------------------------------------
// 90° crease (tests/common/crease.rs)

#[test]
fn crease_ssao_matches_its_expected_value() {
    let (gpu, _guard) = common::gpu();
    let bins = measure_crease(&gpu, Technique::Ssao);
    assert_falls_towards_the_edge("ssao", &bins);
    assert_bins("ssao", "raw vs simulated", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.expected_raw));
    // The closed form takes the depth tolerance at the depth scale of the ray through P
    // instead of each sample's ray: no difference at this size (checked against the
    // simulation in analytic's unit tests to 0.005).
    assert_bins("ssao", "raw vs closed form", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.closed_raw));
    // Blur is linear, so the blurred AO is compared with the same blur applied to the
    // expectation image.
    assert_bins("ssao", "blurred vs simulated", &bins, EXPECTATION_TOLERANCE, |b| {
        (b.blurred_pixels, b.blurred, b.expected_blurred)
    });
    // SSAO's samples crowd towards P (lengths r(0.1 + 0.9t²)), so it is lighter than the
    // reference within r (hits within r); it must not be darker.
    for b in bins.iter().filter(|b| b.pixels >= 100) {
        assert!(b.raw >= b.reference - EXPECTATION_TOLERANCE, "ssao darker than the reference at {:.1} m: {b:?}", b.lo);
    }
}

#[test]
fn ssdo_on_the_bitmask_has_gtao_s_occlusion_exactly() {
    // The same march (gtao.wgsl) with the same noise: the visibility in AoRaw's alpha is
    // GTAO's, bit for bit up to the f16 target, with and without the bounce, and the
    // gathered light in rgb is finite and not negative.
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    let alpha_and_rgb = |technique: Technique| {
        let f = render(&gpu, &scene, &settings(96, 108, ao(technique, 24, 0.8)), &head, &[AO_RAW]);
        let texels: Vec<f32> = f.outputs[&AO_RAW].iter().flatten().copied().collect();
        texels
    };
    let gtao = alpha_and_rgb(Technique::Gtao);
    for technique in [Technique::Ssdo, Technique::SsdoBounce] {
        let ssdo = alpha_and_rgb(technique);
        let worst = gtao.chunks(4).zip(ssdo.chunks(4)).map(|(g, s)| (g[3] - s[3]).abs()).fold(0f32, f32::max);
        eprintln!("{}: largest AO difference from gtao {worst}", technique.name());
        assert!(worst <= 1e-3, "{} AO differs from gtao's by {worst}", technique.name());
        assert!(
            ssdo.chunks(4).all(|t| t[..3].iter().all(|c| c.is_finite() && *c >= 0.0)),
            "{}: gathered light not finite or negative",
            technique.name()
        );
        assert!(ssdo.chunks(4).any(|t| t[0] > 0.0), "{}: no light gathered", technique.name());
    }
}

#[test]
fn crease_ssdo_points_matches_its_expected_value_and_the_falloff_reference() {
    let (gpu, _guard) = common::gpu();
    let bins = measure_crease(&gpu, Technique::SsdoPoints);
    assert_falls_towards_the_edge("ssdo", &bins);
    assert_bins("ssdo", "raw vs simulated", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.expected_raw));
    assert_bins("ssdo", "raw vs closed form", &bins, EXPECTATION_TOLERANCE, |b| (b.pixels, b.raw, b.closed_raw));
    assert_bins("ssdo", "blurred vs simulated", &bins, EXPECTATION_TOLERANCE, |b| {
        (b.blurred_pixels, b.blurred, b.expected_blurred)
    });
    // SSDO's λ uniform in [0, r] makes its continuous expectation exactly the falloff
    // reference (`crease_visibility_falloff` docs). Tolerance 0.06 = 0.05 + 0.01: the
    // 64-sample kernel's own deviation from the continuum plus the depth bias (samples
    // must be 0.02 r behind the wall, the occluder 0.02 r above the floor) is at most
    // 0.045 at x ≥ 0.1 m (`ssdo_crease_expectation` against `crease_visibility_falloff`;
    // 0.03 per bin here), asserted first, plus the noise allowance above.
    assert_bins("ssdo", "expectation vs falloff reference", &bins, 0.05, |b| {
        (b.blurred_pixels, b.expected_blurred, b.falloff_blurred)
    });
    assert_bins("ssdo", "blurred vs falloff reference", &bins, 0.06, |b| {
        (b.blurred_pixels, b.blurred, b.falloff_blurred)
    });
}

// ---------------------------------------------------------------------------------------
// SSDO with a single light

/// A lat-long environment that is black except a cap of `radius_deg` around `towards`.
fn single_light_environment(towards: Vec3, radius_deg: f32, radiance: f32) -> Environment {
    let (w, h) = (128u32, 64u32);
    let cos_radius = radius_deg.to_radians().cos();
    let towards = towards.normalize();
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let dir = environment::direction((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            if dir.dot(towards) >= cos_radius {
                [radiance; 3]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    Environment::from_texels(w, h, texels, 1.0).unwrap()
}

#[test]
fn ssdo_shadows_the_side_away_from_a_single_light_where_ssao_cannot() {
    let (gpu, _guard) = common::gpu();
    // The sphere on the floor, lit only by a bright patch of sky up and to the right
    // (+X, 45° above the horizon, 30° across); no sun, no other light.
    let mut scene = Scene::load("builtin:sphere").unwrap();
    scene.lights.clear();
    scene.environment = Some(single_light_environment(Vec3::new(1.0, 1.0, 0.0), 30.0, 8.0));
    // From above and in front, so the floor on both sides of the sphere is in view.
    let head = HeadPose::look_at(DVec3::new(0.0, 3.2, 3.6), DVec3::new(0.0, 0.3, 0.0)).unwrap();
    let luminance_of = |technique: Technique| {
        let s = settings(160, 180, ao(technique, 64, 1.5));
        let f = render(&gpu, &scene, &s, &head, &[HDR]);
        // Floor beside the sphere, on the side away from the light (−X) and on the lit
        // side (+X), mirror images of each other for this eye.
        let (mut away, mut lit) = (Vec::new(), Vec::new());
        for (l, x, y) in f.pixels() {
            let Some(p) = f.world(l, x, y) else { continue };
            // Inside the sphere's shadow on the −X side, (X + 1)²/2 + Z² < 1 for a light at
            // 45° above +X; the +X side mirrors it.
            if p.y.abs() > 1e-3 || p.z.abs() > 0.5 || !(1.1..=1.6).contains(&p.x.abs()) {
                continue;
            }
            let lum = analytic::luminance(f.rgb(HDR, l, x, y));
            if p.x < 0.0 {
                away.push(lum)
            } else {
                lit.push(lum)
            }
        }
        assert!(
            away.len() > 100 && lit.len() > 100,
            "floor beside the sphere is visible: {} {}",
            away.len(),
            lit.len()
        );
        (mean(away), mean(lit))
    };
    let (ssao_away, ssao_lit) = luminance_of(Technique::Ssao);
    let ssao_ratio = ssao_away / ssao_lit;
    // SSAO scales the unshadowed ambient irradiance by a direction-blind AO, so the two
    // sides, mirror images of each other for this eye, come out alike (within 5 %: the
    // eyes sit ±32 mm off the mirror plane and the rotation noise differs).
    assert!((ssao_ratio - 1.0).abs() < 0.05, "ssao differs between the sides: {ssao_away} vs {ssao_lit}");
    for technique in [Technique::Ssdo, Technique::SsdoPoints] {
        let name = technique.name();
        let (ssdo_away, ssdo_lit) = luminance_of(technique);
        let ssdo_ratio = ssdo_away / ssdo_lit;
        eprintln!(
            "single light: floor luminance away from / towards the light: ssao {ssao_away:.4} / {ssao_lit:.4} \
         (ratio {ssao_ratio:.3}), {name} {ssdo_away:.4} / {ssdo_lit:.4} (ratio {ssdo_ratio:.3})"
        );
        // SSDO blocks the light's directions where the sphere stands between floor and light:
        // the side away from the light is darker than the lit side by clearly more than
        // under SSAO (comparing each technique with itself cancels any overall difference
        // in how the two gather the unoccluded ambient) ...
        assert!(
            ssdo_ratio < ssao_ratio - 0.08,
            "{name} does not shadow the side away from the light: ratio {ssdo_ratio:.3} vs ssao {ssao_ratio:.3}"
        );
        // ... and that side is darker under SSDO than under SSAO.
        assert!(
            ssdo_away < ssao_away,
            "the side away from the light is not darker under {name}: {ssdo_away} vs {ssao_away}"
        );
    }
}

#[test]
fn ssdo_on_an_open_plane_gathers_the_unoccluded_ambient() {
    let (gpu, _guard) = common::gpu();
    // On an open plane nothing is occluded, so SSDO's gathered irradiance must be the
    // ambient irradiance the composite uses without occlusion (technique none). Lights
    // are removed so the image is ambient only: albedo / π × irradiance.
    let mut scene = Scene::load("builtin:plane").unwrap();
    scene.lights.clear();
    let head = scene.head.pose_at(0.0);
    let floor_luminance = |scene: &Scene, technique: Technique, samples: u32| {
        let f = render(&gpu, scene, &settings(96, 108, ao(technique, samples, 0.5)), &head, &[HDR]);
        mean(
            f.pixels()
                .filter(|&(l, x, y)| f.world(l, x, y).is_some())
                .map(|(l, x, y)| analytic::luminance(f.rgb(HDR, l, x, y))),
        )
    };
    let mut failures = Vec::new();
    // A constant environment L: the irradiance is π L for any normal, which every
    // correctly normalised quadrature reproduces exactly whatever its directions; only
    // f16 storage and the SH projection's texel sums (< 0.5 %) remain. Tolerance 2 %.
    let texels = vec![[1.0f32; 3]; 64 * 32];
    scene.environment = Some(Environment::from_texels(64, 32, texels, 1.0).unwrap());
    let unoccluded = floor_luminance(&scene, Technique::None, 24);
    for technique in [Technique::Ssdo, Technique::SsdoPoints] {
        for samples in [12, 24, 36, 64] {
            let ssdo = floor_luminance(&scene, technique, samples);
            let ratio = ssdo / unoccluded;
            let name = technique.name();
            eprintln!("constant sky, N = {samples}: {name} / unoccluded floor luminance = {ratio:.4}");
            if (ratio - 1.0).abs() > 0.02 {
                failures.push(format!("constant environment, N = {samples}: {name} / unoccluded = {ratio:.3}"));
            }
        }
    }
    // The single bright patch of the shadow test: the irradiance of a floor that sees
    // all of it. SSDO's 64 rotated directions integrate a band-limited radiance to about
    // 1 % once averaged over the floor's rotations; tolerance 5 %.
    scene.environment = Some(single_light_environment(Vec3::new(1.0, 1.0, 0.0), 30.0, 8.0));
    let unoccluded = floor_luminance(&scene, Technique::None, 64);
    for technique in [Technique::Ssdo, Technique::SsdoPoints] {
        let ssdo = floor_luminance(&scene, technique, 64);
        let ratio = ssdo / unoccluded;
        let name = technique.name();
        eprintln!("single light, N = 64: {name} / unoccluded floor luminance = {ratio:.4}");
        if (ratio - 1.0).abs() > 0.05 {
            failures.push(format!("single bright patch, N = 64: {name} / unoccluded = {ratio:.3}"));
        }
    }
    assert!(failures.is_empty(), "ssdo does not reproduce the unoccluded ambient on an open plane: {failures:#?}");
}

// ---------------------------------------------------------------------------------------
// Bounce

#[test]
fn red_wall_bleeds_red_only_with_the_bounce() {
    let (gpu, _guard) = common::gpu();
    red_wall_bleeds(&gpu, Technique::Ssdo, Technique::SsdoBounce);
    red_wall_bleeds(&gpu, Technique::SsdoPoints, Technique::SsdoPointsBounce);
}

fn red_wall_bleeds(gpu: &std::sync::Arc<vrao_ao::plug::Gpu>, plain: Technique, with_bounce: Technique) {
    eprintln!("{} and {}:", plain.name(), with_bounce.name());
    let frames = RedWallFrames::render(gpu, plain, with_bounce);
    let (ssdo_hdr, ssdo_raw) = floor_by_the_red_wall(&frames.ssdo);
    let (bounce_hdr, bounce_raw) = floor_by_the_red_wall(&frames.bounce);
    let (off_hdr, off_raw) = floor_by_the_red_wall(&frames.bounce_off);
    let (_, patch_raw) = floor_by_the_red_wall(&frames.patch);
    let ratio = |c: [f64; 3]| c[0] / c[1];
    let gained: Vec<f64> = (0..3).map(|i| bounce_raw[i] - ssdo_raw[i]).collect();
    assert_patch_form_is_red(with_bounce, ssdo_raw, patch_raw);
    eprintln!(
        "bounce: floor by the red wall, hdr r/g: ssdo {:.3}, ssdo-bounce {:.3}, bounce 0 {:.3}; \
         ao-raw rgb: ssdo {ssdo_raw:.3?}, ssdo-bounce {bounce_raw:.3?} (gained {gained:.3?}), bounce 0 {off_raw:.3?}",
        ratio(ssdo_hdr),
        ratio(bounce_hdr),
        ratio(off_hdr)
    );
    // The room's ambient sky is bluish, so its floor is not grey to begin with; what the
    // bounce adds is measured against plain SSDO, which gathers the same sky through the
    // same samples (same kernel and rotations), so the difference of the gathered
    // irradiance (AoRaw rgb) is the bounce alone. It carries the red wall's colour
    // (albedo 0.75, 0.1, 0.1 under a white light): red at least 3× green and blue, and
    // enough of it to see: a 3 % rise of the floor's r/g in the final image.
    assert!(
        gained[0] > 0.01 && gained[0] > 3.0 * gained[1].max(gained[2]).max(0.0),
        "the bounce is not red: {gained:?}"
    );
    assert!(ratio(bounce_hdr) > 1.03 * ratio(ssdo_hdr), "no red bleeding: r/g {bounce_hdr:?} vs {ssdo_hdr:?}");
    assert_bounce_zero_is_ssdo(&frames.ssdo, &frames.bounce_off);
    assert_bounce_blocks_the_same_directions(&frames.ssdo, &frames.bounce);
}

/// The four renders `red_wall_bleeds` compares, each once.
struct RedWallFrames {
    ssdo: Frame,
    bounce: Frame,
    bounce_off: Frame,
    /// With the patch form of the bounce.
    patch: Frame,
}

impl RedWallFrames {
    fn render(gpu: &std::sync::Arc<vrao_ao::plug::Gpu>, plain: Technique, with_bounce: Technique) -> Self {
        let scene = Scene::load("builtin:room").unwrap();
        // Looking down at the foot of the red (−X) wall, from the middle of the room.
        let head = HeadPose::look_at(DVec3::new(0.6, 1.6, -0.8), DVec3::new(ROOM_MIN.x + 0.3, 0.0, -2.6)).unwrap();
        let run_form = |technique: Technique, bounce: f32, form: BounceForm| {
            let mut a = ao(technique, 64, 1.0);
            a.bounce = bounce;
            let mut s = settings(128, 144, a);
            s.point_ssdo.bounce_form = form;
            render(gpu, &scene, &s, &head, &[HDR, AO_RAW])
        };
        let run = |technique: Technique, bounce: f32| run_form(technique, bounce, BounceForm::Direction);
        let ssdo = run(plain, 1.0);
        let bounce = run(with_bounce, 1.0);
        let bounce_off = run(with_bounce, 0.0);
        // The bounce form is the point-sampled SSDO's; the bitmask's senders have none.
        let patch = run_form(with_bounce, 1.0, BounceForm::Patch);
        RedWallFrames { ssdo, bounce, bounce_off, patch }
    }
}

/// Mean HDR and AoRaw rgb over the floor within 0.45 m of the red wall, away from the
/// other walls.
fn floor_by_the_red_wall(f: &Frame) -> ([f64; 3], [f64; 3]) {
    let near_red_wall =
        |p: DVec3| p.y.abs() < 1e-3 && p.x < ROOM_MIN.x + 0.45 && p.z < ROOM_MAX.z - 1.0 && p.z > ROOM_MIN.z + 0.5;
    let (mut hdr, mut raw, mut n) = ([0.0f64; 3], [0.0f64; 3], 0);
    for (l, x, y) in f.pixels() {
        if !f.world(l, x, y).is_some_and(near_red_wall) {
            continue;
        }
        n += 1;
        let (c, a) = (f.rgb(HDR, l, x, y), f.rgb(AO_RAW, l, x, y));
        for i in 0..3 {
            hdr[i] += c[i] as f64;
            raw[i] += a[i] as f64;
        }
    }
    assert!(n > 200, "floor by the red wall is visible ({n} px)");
    (hdr.map(|v| v / n as f64), raw.map(|v| v / n as f64))
}

/// The patch form of Ritschel et al. 2009 carries the same red, less of it
/// (tests/reference_error.rs compares both with the reference).
fn assert_patch_form_is_red(with_bounce: Technique, ssdo_raw: [f64; 3], patch_raw: [f64; 3]) {
    let patch_gained: Vec<f64> = (0..3).map(|i| patch_raw[i] - ssdo_raw[i]).collect();
    eprintln!("bounce: patch form gained {patch_gained:.3?}");
    if with_bounce == Technique::SsdoPointsBounce {
        assert!(
            patch_gained[0] > 0.005 && patch_gained[0] > 3.0 * patch_gained[1].max(patch_gained[2]).max(0.0),
            "the patch-form bounce is not red: {patch_gained:?}"
        );
    }
}

/// Bounce strength 0 is SSDO exactly (the same pass runs).
fn assert_bounce_zero_is_ssdo(ssdo: &Frame, bounce_off: &Frame) {
    for r in [HDR, AO_RAW] {
        let worst = ssdo.outputs[&r]
            .iter()
            .flatten()
            .zip(bounce_off.outputs[&r].iter().flatten())
            .map(|(x, y)| (x - y).abs())
            .fold(0f32, f32::max);
        assert!(worst <= 1e-3, "ssdo-bounce with bounce 0 differs from ssdo in {} by {worst}", r.name());
    }
}

/// With the bounce, the occluder probe reads distances packed with the direct light
/// instead of the depth buffer (one fetch for both): it must block exactly the same
/// directions, so the visibility (AoRaw alpha) is SSDO's to the f16 target's precision.
fn assert_bounce_blocks_the_same_directions(ssdo: &Frame, bounce: &Frame) {
    let alpha =
        |f: &Frame| f.outputs[&AO_RAW].iter().flat_map(|l| l.iter().skip(3).step_by(4).copied()).collect::<Vec<f32>>();
    let worst = alpha(ssdo).iter().zip(alpha(bounce)).map(|(x, y)| (x - y).abs()).fold(0f32, f32::max);
    assert!(worst <= 1e-3, "the bounce changed which directions are blocked: visibility differs by {worst}");
}
