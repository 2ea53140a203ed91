//! Fixed foveated occlusion (`--foveation`) on the GPU: within the full-rate cone around
//! each eye's view axis every technique computes exactly what it computes without
//! foveation; towards the edges it spends fewer samples, which changes values (so the
//! map is live) but neither darkens an open plane nor shifts the mean AO of a furnished
//! room by more than noise; nothing is ever NaN.
//!
//! `cargo test --release --test foveation -- --nocapture` prints the measurements.

use crate::common;

use vrao_ao::plug::{Resource, AO_RAW, DEPTH};
use vrao_ao::{AoSettings, Fov, Foveation, Technique};
use vrao_render::scene::Scene;
use vrao_render::{HeadsetProfile, Renderer, Settings};

const TECHNIQUES: [Technique; 5] =
    [Technique::Gtao, Technique::Hbao, Technique::Ssao, Technique::Ssdo, Technique::SsdoPoints];
const SIZE: (u32, u32) = (160, 180);

/// The raw occlusion (AO in alpha) and the depth of one stereo frame of `scene`.
fn raw_occlusion(
    scene: &Scene,
    technique: Technique,
    foveation: Foveation,
) -> (Vec<Vec<f32>>, Vec<Vec<f32>>, [Fov; 2]) {
    let (gpu, _guard) = common::gpu();
    let ao = AoSettings { technique, foveation, radius: scene.suggested_ao_radius(), ..AoSettings::default() };
    let s = Settings { profile: HeadsetProfile::with_size("vive", SIZE.0, SIZE.1), ao, ..Settings::default() };
    let mut renderer = Renderer::new(gpu.clone(), scene, &s).unwrap();
    let eyes = s.profile.eyes(&scene.head.pose_at(0.0), s.near);
    let outputs: [Resource; 2] = [AO_RAW, DEPTH];
    renderer.render(&eyes.eyes, &outputs).unwrap();
    let raw = renderer.read_f32(AO_RAW).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    (raw, depth, [eyes.eyes[0].fov, eyes.eyes[1].fov])
}

/// The angle (degrees) off the view axis of pixel (x, y)'s centre in an eye of `fov`.
fn off_axis_deg(fov: &Fov, x: u32, y: u32) -> f64 {
    let [left, right, up, down] = fov.tangents();
    let tan_x = left + (right - left) * (x as f64 + 0.5) / SIZE.0 as f64;
    let tan_y = up + (down - up) * (y as f64 + 0.5) / SIZE.1 as f64;
    (tan_x * tan_x + tan_y * tan_y).sqrt().atan().to_degrees()
}

/// Per region (inside the full-rate cone, past the edge angle): pixels on a surface,
/// how many differ between `off` and `on`, and the mean AO of each.
#[derive(Default, Debug)]
struct Region {
    pixels: usize,
    differing: usize,
    sum_off: f64,
    sum_on: f64,
}

impl Region {
    fn mean_difference(&self) -> f64 {
        (self.sum_on - self.sum_off) / self.pixels.max(1) as f64
    }
}

#[test]
fn the_centre_is_untouched_and_the_edges_spend_less_without_bias() {
    let scene = Scene::load("builtin:furnished").unwrap();
    let map = Foveation::High.map();
    for technique in TECHNIQUES {
        let (off, depth, fovs) = raw_occlusion(&scene, technique, Foveation::Off);
        let (on, _, _) = raw_occlusion(&scene, technique, Foveation::High);
        let (mut centre, mut edge) = (Region::default(), Region::default());
        for layer in 0..2 {
            for y in 0..SIZE.1 {
                for x in 0..SIZE.0 {
                    let i = (y * SIZE.0 + x) as usize;
                    let (a, b) = (off[layer][4 * i + 3], on[layer][4 * i + 3]);
                    assert!(b.is_finite() && (0.0..=1.0).contains(&b), "{}: AO {b} at ({x}, {y})", technique.name());
                    if depth[layer][i] <= 0.0 {
                        continue;
                    }
                    let angle = off_axis_deg(&fovs[layer], x, y);
                    // A pixel's count follows its own position, which lies within a
                    // fraction of a degree of its centre's direction.
                    let in_centre = angle < map.full_rate_deg as f64 - 0.5;
                    // GTAO's right eye takes the left eye's value where the left eye
                    // sees the same point (stereo reuse), which may lie off the left
                    // eye's axis: only the left eye's centre is its own.
                    if in_centre && technique == Technique::Gtao && layer == 1 {
                        continue;
                    }
                    // A pixel's count follows its own position, which lies within a
                    // fraction of a degree of its centre's direction.
                    let region = if in_centre {
                        &mut centre
                    } else if angle > map.edge_deg as f64 + 0.5 {
                        &mut edge
                    } else {
                        continue;
                    };
                    region.pixels += 1;
                    region.differing += usize::from(a != b);
                    region.sum_off += a as f64;
                    region.sum_on += b as f64;
                }
            }
        }
        eprintln!("{}: centre {centre:?}, edge {edge:?}", technique.name());
        assert!(centre.pixels > 500 && edge.pixels > 10_000, "{}: the view covers both regions", technique.name());
        // Within the cone the counts are the full ones: the same bits as without foveation.
        assert_eq!(centre.differing, 0, "{}: foveation changed the centre", technique.name());
        // Past the edge angle the counts are a third: the values change…
        assert!(edge.differing * 10 > edge.pixels, "{}: foveation left the edges alone", technique.name());
        // …but fewer samples of the same estimators only add noise: the mean moves far
        // less than the AO itself varies (the room's AO spans 0.3–1).
        let shift = edge.mean_difference();
        assert!(shift.abs() < 0.02, "{}: foveation moved the edges' mean AO by {shift:+.4}", technique.name());
    }
}

#[test]
fn an_open_plane_stays_unoccluded_when_foveated() {
    let scene = Scene::load("builtin:plane").unwrap();
    for technique in TECHNIQUES {
        let (raw, depth, _) = raw_occlusion(&scene, technique, Foveation::High);
        let mut worst = f32::INFINITY;
        for layer in 0..2 {
            for (i, d) in depth[layer].iter().enumerate() {
                if *d > 0.0 {
                    worst = worst.min(raw[layer][4 * i + 3]);
                }
            }
        }
        eprintln!("plane {} foveated: min AO {worst:.4}", technique.name());
        // As without foveation (tests/occlusion_robustness.rs): an open plane occludes nothing.
        assert!(worst >= 0.98, "{}: AO {worst} on the open plane with foveation", technique.name());
    }
}
