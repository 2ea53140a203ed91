//! Each technique's error against the reference tracer on the 90° crease, where the
//! reference is known in closed form (the tracer's own tests check it against that).

use crate::common;

use vrao::measure::bench::{error_figures, ErrorFigures};
use vrao::measure::reference::{trace, ReferenceSettings};
use vrao_ao::plug::FINAL_AO;
use vrao_ao::Technique;
use vrao_render::{BounceForm, HeadsetProfile, Renderer, Scene, Settings};

const SIZE: (u32, u32) = (128, 112);
const RADIUS: f32 = 0.5;

fn errors(
    technique: Technique,
    samples: u32,
    form: BounceForm,
    reference: &vrao::measure::reference::ReferenceImage,
) -> ErrorFigures {
    let (gpu, _one_at_a_time) = common::gpu();
    let scene = Scene::load("builtin:crease").unwrap();
    let mut settings = Settings { profile: HeadsetProfile::with_size("test", SIZE.0, SIZE.1), ..Settings::default() };
    settings.ao.technique = technique;
    settings.ao.samples = samples;
    settings.ao.radius = RADIUS;
    settings.point_ssdo.bounce_form = form;
    let output = FINAL_AO;
    let mut renderer = Renderer::new(gpu, &scene, &settings).unwrap();
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    renderer.render(&eyes.eyes, &[output]).unwrap();
    error_figures(technique, &renderer.read_f32(output).unwrap(), reference)
}

#[test]
fn every_technique_stays_within_its_stated_error_of_the_reference_on_the_crease() {
    let scene = Scene::load("builtin:crease").unwrap();
    let settings = Settings { profile: HeadsetProfile::with_size("test", SIZE.0, SIZE.1), ..Settings::default() };
    let eyes = settings.profile.eyes(&scene.head.pose_at(0.0), settings.near);
    let reference_settings =
        ReferenceSettings { radius: RADIUS as f64, rays_per_pixel: 256, stride: 2, near: settings.near };
    let reference = trace(&scene, &eyes.eyes, SIZE, &reference_settings, &mut |_| {}).unwrap();
    assert!(reference.stats.noise < 0.01, "reference noise {}", reference.stats.noise);
    let mut ambient = Vec::new();
    for (technique, bound) in BOUNDS {
        for samples in [12, 36] {
            let e = errors(technique, samples, BounceForm::Direction, &reference);
            println!("{} N={samples}: {e:?}", technique.name());
            assert!(
                e.ao_rmse.is_finite() && e.ao_rmse < bound,
                "{} N={samples}: {e:?} (bound {bound})",
                technique.name()
            );
            assert!(e.ao_ssim > 0.8, "{} N={samples}: {e:?}", technique.name());
            ambient.push((technique, samples, e.ambient_rel_rmse.expect("the crease has an environment")));
        }
    }
    // The reference includes the light the lit wall bounces onto the floor: only the
    // bounce brings it, so it must bring the ambient light closer to the reference, in
    // either form; the direction form (the default) closer than the patch form of
    // Ritschel et al. 2009.
    let of = |t, n| ambient.iter().find(|(a, b, _)| *a == t && *b == n).unwrap().2;
    // The forms are the point-sampled SSDO's (the bitmask SSDO weighs its sectors alone).
    for n in [12, 36] {
        let points = |technique, form| errors(technique, n, form, &reference).ambient_rel_rmse.unwrap();
        let plain = points(Technique::SsdoPoints, BounceForm::Direction);
        let direction = points(Technique::SsdoPointsBounce, BounceForm::Direction);
        let patch = points(Technique::SsdoPointsBounce, BounceForm::Patch);
        println!(
            "N={n}: ambient rel. RMSE ssdo {:.4}, ssdo-bounce {:.4}; ssdo-points {plain:.4}, bounce patch {patch:.4}, direction {direction:.4}",
            of(Technique::Ssdo, n),
            of(Technique::SsdoBounce, n)
        );
        assert!(of(Technique::SsdoBounce, n) < of(Technique::Ssdo, n), "{ambient:?}");
        assert!(patch < plain, "patch form {patch} against ssdo-points {plain}");
        assert!(direction < patch, "direction form {direction} not closer than the patch form ({patch})");
    }
}

/// Stated bounds on the AO RMSE against the reference's hard cut-off AO, the one target
/// every technique is scored against (both eyes, sky excluded, 128×112 per eye, r =
/// 0.5 m). What a correct estimator leaves on the crease: SSAO's and SSDO's systematic
/// bias against the reference (their samples crowd towards the centre and see less of
/// the wall than rays of length r: `analytic.rs`), ≈ 0.05 measured on lavapipe, and
/// HBAO's linear falloff plus its slice bias, ≈ 0.055–0.06 (≈ 0.03 against the falloff
/// reference); plus up to 0.03 of per-pixel noise and edge error after the blur. A broken
/// estimator (self-occlusion of the floor, a wrong radius scale, a flipped normal) lands
/// above 0.1.
const BOUNDS: [(Technique, f64); 4] =
    [(Technique::Ssao, 0.08), (Technique::Hbao, 0.08), (Technique::Ssdo, 0.08), (Technique::SsdoBounce, 0.08)];
