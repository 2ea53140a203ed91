//! Tests of `analytic.rs`.

use super::*;
use vrao_ao::plug::{hemisphere_kernel, HemisphereDensity};

const R: f64 = 1.0;

#[test]
fn luminance_weights_sum_to_one() {
    assert!((luminance([1.0, 1.0, 1.0]) - 1.0).abs() < 1e-12);
    assert!(luminance([0.0, 1.0, 0.0]) > luminance([1.0, 0.0, 0.0]));
    assert_eq!(smoothstep(0.0, 1.0, 2.0), 1.0);
    assert_eq!(smoothstep(0.0, 1.0, -1.0), 0.0);
    assert!((smoothstep(0.0, 1.0, 0.5) - 0.5).abs() < 1e-12);
}

#[test]
fn crease_limits() {
    for r in [0.1, 1.0, 7.0] {
        assert_eq!(crease_visibility(r, r), 1.0);
        assert_eq!(crease_visibility(2.0 * r, r), 1.0);
        assert_eq!(crease_visibility_falloff(r, r), 1.0);
        assert_eq!(crease_visibility_falloff(3.0 * r, r), 1.0);
        // At the crease line half the cosine-weighted hemisphere faces the wall.
        assert!((crease_visibility(0.0, r) - 0.5).abs() < 1e-12);
        assert!((crease_visibility(1e-9 * r, r) - 0.5).abs() < 1e-8);
        assert!((crease_visibility_falloff(0.0, r) - 0.5).abs() < 1e-12);
        assert!((crease_visibility_falloff(1e-9 * r, r) - 0.5).abs() < 1e-6);
    }
    // Scale invariance: only x / r matters.
    assert!((crease_visibility(0.3, 1.0) - crease_visibility(3.0, 10.0)).abs() < 1e-12);
}

#[test]
fn crease_visibility_is_monotone_and_falloff_sees_more() {
    let mut last = (0.0, 0.0);
    for i in 0..=1000 {
        let x = i as f64 / 1000.0 * 1.2 * R;
        let (v, f) = (crease_visibility(x, R), crease_visibility_falloff(x, R));
        assert!(v >= last.0 - 1e-12 && f >= last.1 - 1e-12, "not monotone at x = {x}");
        assert!(f >= v - 1e-12 && (0.5..=1.0).contains(&v) && (0.5..=1.0).contains(&f), "x = {x}: {v} {f}");
        last = (v, f);
    }
    // Some values to pin the closed forms: a = 0.5 gives 1 − (π/3 − √3/4)/π.
    let expected = 1.0 - (PI / 3.0 - 3f64.sqrt() / 4.0) / PI;
    assert!((crease_visibility(0.5, 1.0) - expected).abs() < 1e-12);
}

#[test]
fn closed_forms_match_brute_force_quadrature() {
    for x in [0.0, 0.02, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99] {
        let exact = crease_visibility(x, R);
        let numeric = crease_visibility_quadrature(x, R, false, 600);
        assert!((exact - numeric).abs() < 2e-3, "x = {x}: closed form {exact}, quadrature {numeric}");
        let exact = crease_visibility_falloff(x, R);
        let numeric = crease_visibility_quadrature(x, R, true, 600);
        assert!((exact - numeric).abs() < 2e-3, "falloff x = {x}: closed form {exact}, quadrature {numeric}");
    }
}

#[test]
fn closed_forms_match_ray_casting_against_the_builtin_crease() {
    let rects = crease_rects();
    let hit = |o: DVec3, d: DVec3| first_hit(&rects, o, d);
    for x in [0.05, 0.3, 0.6, 0.95, 1.5] {
        let p = DVec3::new(0.3, 0.0, CREASE_WALL_Z + x);
        for falloff in [false, true] {
            let traced = visibility_by_ray_casting(p, DVec3::Y, R, falloff, 400, hit);
            let exact = if falloff { crease_visibility_falloff(x, R) } else { crease_visibility(x, R) };
            assert!((traced - exact).abs() < 3e-3, "x = {x} falloff {falloff}: traced {traced}, exact {exact}");
        }
        // The wall point at the same distance from the floor sees the same crease.
        let q = DVec3::new(-0.4, x, CREASE_WALL_Z);
        let traced = visibility_by_ray_casting(q, DVec3::Z, R, false, 400, hit);
        assert!((traced - crease_visibility(x, R)).abs() < 3e-3, "wall at {x}: {traced}");
    }
    // An open floor far from the wall is unoccluded.
    let far = DVec3::new(0.0, 0.0, CREASE_WALL_Z + 3.0);
    assert_eq!(visibility_by_ray_casting(far, DVec3::Y, R, false, 64, hit), 1.0);
}

#[test]
fn rect_hits_from_both_sides_and_misses_outside() {
    let r = Rect { corner: DVec3::ZERO, u: DVec3::X, v: DVec3::Y };
    assert_eq!(r.hit(DVec3::new(0.5, 0.5, 2.0), DVec3::NEG_Z), Some(2.0));
    assert_eq!(r.hit(DVec3::new(0.5, 0.5, -2.0), DVec3::Z * 2.0), Some(1.0));
    assert_eq!(r.hit(DVec3::new(1.5, 0.5, 2.0), DVec3::NEG_Z), None);
    assert_eq!(r.hit(DVec3::new(0.5, 0.5, 2.0), DVec3::Z), None);
    assert_eq!(r.hit(DVec3::new(0.5, 0.5, 0.0), DVec3::Z), None, "a ray leaving the surface");
    assert_eq!(r.hit(DVec3::new(0.5, 0.5, 1.0), DVec3::X), None, "parallel");
}

#[test]
fn rotation_fraction_has_the_right_limits() {
    assert_eq!(rotation_fraction_past_wall(1.0, 2.0), 0.0);
    assert!((rotation_fraction_past_wall(1.0, 0.0) - 0.5).abs() < 1e-12);
    assert!((rotation_fraction_past_wall(2.0, 1.0) - 1.0 / 3.0).abs() < 1e-12);
    assert_eq!(rotation_fraction_past_wall(0.0, 0.0), 0.0);
}

#[test]
fn ssao_expectation_limits_and_monotonicity() {
    let kernel = hemisphere_kernel(64, HemisphereDensity::Cosine);
    let bias = 0.02;
    // No sample reaches a wall r away.
    assert_eq!(ssao_crease_expectation(R, R, bias, &kernel), 1.0);
    assert_eq!(ssao_crease_expectation(5.0, R, bias, &kernel), 1.0);
    // At the crease line without bias, every sample is past the wall half the time.
    assert!((ssao_crease_expectation(0.0, R, 0.0, &kernel) - 0.5).abs() < 1e-12);
    let mut last = 0.0;
    for i in 0..=100 {
        let x = i as f64 / 100.0 * R;
        let v = ssao_crease_expectation(x, R, bias, &kernel);
        assert!(v >= last && v <= 1.0 && v > 0.5, "x = {x}: {v}");
        last = v;
        // SSAO's samples are shorter than r, so it sees less of the wall than the
        // reference (to within the kernel's own sampling error).
        assert!(v >= crease_visibility(x, R) - 0.02, "x = {x}: {v} vs {}", crease_visibility(x, R));
    }
    assert!(ssao_crease_expectation(0.5, R, bias, &[]) == 1.0);
}

#[test]
fn ssao_expectation_with_full_length_samples_is_the_reference() {
    // A kernel whose samples all reach r estimates exactly the reference integral,
    // up to how well 256 Halton directions cover the hemisphere.
    let kernel: Vec<[f32; 4]> =
        hemisphere_kernel(256, HemisphereDensity::Cosine).into_iter().map(|[x, y, z, _]| [x, y, z, 1.0]).collect();
    for x in [0.0, 0.1, 0.3, 0.5, 0.8] {
        let v = ssao_crease_expectation(x, R, 0.0, &kernel);
        assert!((v - crease_visibility(x, R)).abs() < 0.01, "x = {x}: {v} vs {}", crease_visibility(x, R));
    }
}

#[test]
fn ssdo_expectation_tends_to_the_falloff_reference() {
    let kernel = hemisphere_kernel(256, HemisphereDensity::Uniform);
    for x in [0.0, 0.1, 0.3, 0.5, 0.8, 1.0] {
        let v = ssdo_crease_expectation(x, R, 0.0, &kernel);
        let f = crease_visibility_falloff(x, R);
        assert!((v - f).abs() < 0.015, "x = {x}: ssdo {v}, falloff reference {f}");
    }
    assert_eq!(ssdo_crease_expectation(R, R, 0.02, &kernel), 1.0);
}

#[test]
fn simulated_estimators_match_the_closed_forms() {
    let rects = crease_rects();
    let hit = |o: DVec3, d: DVec3| first_hit(&rects, o, d);
    let ssao_kernel = hemisphere_kernel(32, HemisphereDensity::Cosine);
    let ssdo_kernel = hemisphere_kernel(32, HemisphereDensity::Uniform);
    for x in [0.0, 0.15, 0.4, 0.7, 1.1] {
        let p = DVec3::new(0.2, 0.0, CREASE_WALL_Z + x);
        // An eye far out along the wall normal, barely above the floor, looking at
        // the wall: depth differences are distances behind the wall plane.
        let view = DepthView { eye: DVec3::new(0.2, 0.5, 50.0), forward: DVec3::NEG_Z };
        for (estimator, kernel) in [(Estimator::Ssao, &ssao_kernel), (Estimator::Ssdo, &ssdo_kernel)] {
            let params = EstimatorParams { estimator, radius: R, bias: 0.02, range_check: true, rotations: 720 };
            let simulated = screen_space_expectation(&params, p, DVec3::Y, kernel, &view, hit);
            let closed = match estimator {
                Estimator::Ssao => ssao_crease_expectation(x, R, 0.02, kernel),
                Estimator::Ssdo => ssdo_crease_expectation(x, R, 0.02, kernel),
            };
            assert!((simulated - closed).abs() < 3e-3, "{estimator:?} x = {x}: simulated {simulated}, closed {closed}");
        }
    }
}

#[test]
fn oblique_view_only_rescales_the_bias() {
    // Seen obliquely, the depth tolerance maps to a different distance behind the
    // wall; with zero bias the view does not matter at all.
    let rects = crease_rects();
    let hit = |o: DVec3, d: DVec3| first_hit(&rects, o, d);
    let kernel = hemisphere_kernel(32, HemisphereDensity::Cosine);
    let eye = DVec3::new(0.0, 2.0, -1.5);
    let view = DepthView { eye, forward: (DVec3::new(0.0, 0.0, CREASE_WALL_Z) - eye).normalize() };
    for x in [0.1, 0.4, 0.8] {
        let p = DVec3::new(0.0, 0.0, CREASE_WALL_Z + x);
        let params =
            EstimatorParams { estimator: Estimator::Ssao, radius: R, bias: 0.0, range_check: false, rotations: 720 };
        let simulated = screen_space_expectation(&params, p, DVec3::Y, &kernel, &view, hit);
        let closed = ssao_crease_expectation(x, R, 0.0, &kernel);
        assert!((simulated - closed).abs() < 3e-3, "x = {x}: {simulated} vs {closed}");
        // With a bias, the depth scale along the ray through P stands in for the
        // rays through the samples.
        let e = (p - eye).normalize();
        let k = e.dot(view.forward) / e.z.abs();
        for (estimator, density) in
            [(Estimator::Ssao, HemisphereDensity::Cosine), (Estimator::Ssdo, HemisphereDensity::Uniform)]
        {
            let kernel = hemisphere_kernel(64, density);
            let params = EstimatorParams { estimator, radius: R, bias: 0.02, range_check: true, rotations: 360 };
            let simulated = screen_space_expectation(&params, p, DVec3::Y, &kernel, &view, hit);
            let closed = match estimator {
                Estimator::Ssao => ssao_crease_expectation_with_depth_scale(x, R, 0.02, &kernel, k),
                Estimator::Ssdo => ssdo_crease_expectation_with_depth_scale(x, R, 0.02, &kernel, k),
            };
            assert!((simulated - closed).abs() < 5e-3, "{estimator:?} x = {x}: {simulated} vs {closed} (k = {k})");
        }
    }
}

#[test]
fn open_floor_is_unoccluded_for_both_estimators() {
    let rects = crease_rects();
    let hit = |o: DVec3, d: DVec3| first_hit(&rects, o, d);
    // Every sample lies in front of the eye (a sample behind it would be off screen).
    let view = DepthView { eye: DVec3::new(0.0, 1.2, 4.0), forward: DVec3::new(0.0, -1.2, -7.0).normalize() };
    let p = DVec3::new(0.0, 0.0, CREASE_WALL_Z + 2.5);
    for (estimator, density) in
        [(Estimator::Ssao, HemisphereDensity::Cosine), (Estimator::Ssdo, HemisphereDensity::Uniform)]
    {
        let params = EstimatorParams { estimator, radius: R, bias: 0.02, range_check: true, rotations: 16 };
        let v = screen_space_expectation(&params, p, DVec3::Y, &hemisphere_kernel(64, density), &view, hit);
        assert_eq!(v, 1.0, "{estimator:?}");
    }
}

#[test]
fn hbao_slices_integrate_to_the_falloff_reference() {
    for x in [0.0, 0.05, 0.2, 0.5, 0.8, 1.0, 1.5] {
        let slices = crease_hbao_slices(x, R, 20_000);
        let falloff = crease_visibility_falloff(x, R);
        assert!((slices - falloff).abs() < 1e-4, "x = {x}: slices {slices}, falloff {falloff}");
    }
}

fn crease_eye() -> Eye {
    use vrao_ao::EyeSide;
    use vrao_render::HeadsetProfile;
    let target = DVec3::new(0.0, 0.0, CREASE_WALL_Z);
    let pose = vrao_ao::HeadPose::look_at(target + DVec3::new(0.0, 1.8, 1.8), target).unwrap();
    Eye { side: EyeSide::Left, pose, fov: HeadsetProfile::with_size("t", 160, 180).fov_left }
}

#[test]
fn hbao_on_an_open_floor_is_one_and_on_the_crease_near_the_reference() {
    let rects = crease_rects();
    let hit = |o: DVec3, d: DVec3| first_hit(&rects, o, d);
    let eye = crease_eye();
    let size = (160, 180);
    let params = HbaoParams { radius: R, bias: 0.02, directions: 8, steps: 8, rotations: 56 };
    let mut last = 0.0;
    // Walk down the middle column from the crease line towards the eye.
    let mut seen = 0;
    for y in 95..180 {
        let dir = vrao_ao::Eye::pixel_ray(&eye, size, (80.5, y as f64 + 0.5));
        let Some(t) = hit(eye.pose.position, dir) else { continue };
        let p = eye.pose.position + dir * t;
        if p.y.abs() > 1e-9 {
            continue;
        }
        let x = p.z - CREASE_WALL_Z;
        let v = hbao_expectation(&params, &eye, size, (80, y), DVec3::Y, hit);
        if x > R {
            assert_eq!(v, 1.0, "open floor at x = {x}");
        } else if x > 0.1 {
            // Discretisation, angle bias and perspective keep HBAO light of the hard
            // cut-off reference by at most 0.17 (as in tests/occlusion_hbao_gtao.rs on the same
            // crease); it never darkens more than the reference.
            let f = crease_visibility(x, R);
            assert!(v - f < 0.17 && v >= f - 0.02, "x = {x}: hbao {v}, reference {f}");
            seen += 1;
        }
        assert!(v >= last - 0.01, "not monotone at x = {x}");
        last = v;
    }
    assert!(seen > 10);
}

#[test]
fn pixel_ray_matches_projection() {
    let eye = crease_eye();
    let size = (160, 180);
    let p = DVec3::new(0.3, 0.0, CREASE_WALL_Z + 0.4);
    let (uv, _) = eye.project(p, 0.05).unwrap();
    let dir = vrao_ao::Eye::pixel_ray(&eye, size, (uv[0] * 160.0, uv[1] * 180.0));
    assert!(dir.dot((p - eye.pose.position).normalize()) > 1.0 - 1e-12);
}
