//! The headset's visibility mask on the GPU: the pixels the lens hides are left out by
//! every pass and hold defined values (colour black, AO 1, depth the sky's), and the
//! pixels it shows far from its edge come out exactly as without the mask, at full and
//! half resolution and with foveation.
//!
//! `cargo test --release --test visibility_mask -- --nocapture` prints the measurements.

use crate::common;

use vrao_ao::plug::{Resource, DEPTH, FINAL_AO};
use vrao_ao::{AoSettings, Foveation, Resolution, Technique, ViewMask, VisibilityMask};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::Scene;
use vrao_render::{HeadsetProfile, Renderer, Settings};

const SIZE: (u32, u32) = (160, 180);

/// Distance (pixels) from the mask's hidden pixels beyond which a shown pixel must not
/// change: more than the march, denoise and upsampling reach at this size.
const UNTOUCHED_BEYOND_PX: f64 = 48.0;

struct Frame {
    ao: Vec<Vec<f32>>,
    color: Vec<Vec<u8>>,
    depth: Vec<Vec<f32>>,
    hidden_share: Vec<f64>,
}

fn render(scene: &Scene, ao: &AoSettings, mask: Option<&VisibilityMask>) -> Frame {
    let (gpu, _guard) = common::gpu();
    let s =
        Settings { profile: HeadsetProfile::with_size("vive", SIZE.0, SIZE.1), ao: ao.clone(), ..Settings::default() };
    let mut renderer = Renderer::new(gpu.clone(), scene, &s).unwrap();
    renderer.set_visibility_mask(mask.cloned());
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    let outputs: [Resource; 3] = [FINAL_AO, COLOR, DEPTH];
    renderer.render(&eyes.eyes, &outputs).unwrap();
    Frame {
        ao: renderer.read_f32(FINAL_AO).unwrap(),
        color: renderer.read_bytes(COLOR).unwrap(),
        depth: renderer.read_f32(DEPTH).unwrap(),
        hidden_share: renderer.hidden_share().to_vec(),
    }
}

/// The ellipse touching the rectangle's edges (21.5 % hidden) for both eyes of the profile.
fn lens(profile: &HeadsetProfile) -> VisibilityMask {
    let view = |fov: &vrao_ao::Fov| ViewMask::superellipse(fov.tangents(), 2.0, 128, "test ellipse");
    VisibilityMask { views: vec![view(&profile.fov_left), view(&profile.fov_right)] }
}

/// Per pixel, the distance to the nearest hidden pixel (brute force over the hidden ones).
fn distance_to_hidden(coverage: &[u8]) -> Vec<f64> {
    let hidden: Vec<(f64, f64)> = (0..coverage.len())
        .filter(|&i| coverage[i] == 0)
        .map(|i| ((i as u32 % SIZE.0) as f64, (i as u32 / SIZE.0) as f64))
        .collect();
    (0..coverage.len())
        .map(|i| {
            let (x, y) = ((i as u32 % SIZE.0) as f64, (i as u32 / SIZE.0) as f64);
            hidden.iter().map(|(hx, hy)| (hx - x).hypot(hy - y)).fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn hidden_pixels_are_black_and_unoccluded_and_the_rest_is_untouched() {
    let scene = Scene::load("builtin:furnished").unwrap();
    let profile = HeadsetProfile::with_size("vive", SIZE.0, SIZE.1);
    let mask = lens(&profile);
    let eyes = profile.eyes(&scene.head.pose_at(0.0), 0.05);
    let coverage: Vec<Vec<u8>> =
        mask.views.iter().zip(&eyes.eyes).map(|(v, e)| v.coverage(SIZE.0, SIZE.1, e.fov.tangents())).collect();
    let distance: Vec<Vec<f64>> = coverage.iter().map(|c| distance_to_hidden(c)).collect();
    for (resolution, foveation) in
        [(Resolution::Full, Foveation::Off), (Resolution::Half, Foveation::Off), (Resolution::Half, Foveation::High)]
    {
        let ao = AoSettings {
            technique: Technique::Gtao,
            radius: scene.suggested_ao_radius(),
            resolution,
            foveation,
            ..AoSettings::default()
        };
        let open = render(&scene, &ao, None);
        let masked = render(&scene, &ao, Some(&mask));
        let off = render(&scene, &AoSettings { mask: false, ..ao.clone() }, Some(&mask));
        let what = format!("{} foveation {}", resolution.name(), foveation.name());
        for layer in 0..2 {
            let share = coverage[layer].iter().filter(|&&c| c == 0).count() as f64 / coverage[layer].len() as f64;
            assert!(
                (masked.hidden_share[layer] - share).abs() < 1e-9,
                "{what}: hidden share {:?}",
                masked.hidden_share
            );
            assert!((share - (1.0 - std::f64::consts::FRAC_PI_4)).abs() < 0.01, "{share}");
            let (mut hidden_on_geometry, mut compared, mut far) = (0, 0, 0);
            for i in 0..coverage[layer].len() {
                let (a_open, a_masked) = (open.ao[layer][4 * i + 3], masked.ao[layer][4 * i + 3]);
                assert!(a_masked.is_finite() && (0.0..=1.0).contains(&a_masked), "{what}: AO {a_masked}");
                // With the mask switched off the mask given changes nothing.
                assert_eq!(off.ao[layer][4 * i + 3], a_open, "{what}: --mask off differs at {i}");
                if coverage[layer][i] == 0 {
                    hidden_on_geometry += usize::from(open.depth[layer][i] > 0.0);
                    assert_eq!(masked.depth[layer][i], 0.0, "{what}: a hidden pixel kept a surface's depth");
                    assert_eq!(a_masked, 1.0, "{what}: a hidden pixel's AO is not the neutral 1");
                    assert_eq!(
                        &masked.color[layer][4 * i..4 * i + 3],
                        &[0, 0, 0],
                        "{what}: a hidden pixel is not black"
                    );
                } else {
                    // Shown pixels keep their surface.
                    assert_eq!(masked.depth[layer][i], open.depth[layer][i], "{what}: depth changed at {i}");
                    compared += 1;
                    if distance[layer][i] > UNTOUCHED_BEYOND_PX {
                        far += 1;
                        assert!((a_masked - a_open).abs() < 1e-5, "{what}: AO {a_open} → {a_masked} at {i}");
                        assert_eq!(
                            &masked.color[layer][4 * i..4 * i + 4],
                            &open.color[layer][4 * i..4 * i + 4],
                            "{what}: colour changed at {i}"
                        );
                    }
                }
            }
            println!("{what}, eye {layer}: {hidden_on_geometry} hidden pixels on geometry, {compared} shown, {far} far from the edge");
            assert!(hidden_on_geometry > 1000, "{what}: the mask must hide geometry for the test to mean anything");
            assert!(far > 1000, "{what}: too few pixels far from the edge ({far})");
        }
    }
}
