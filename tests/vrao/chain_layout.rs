//! The AO chain's layout: GTAO, SSAO and HBAO keep every chain texture single-channel
//! (`R16Float`) where the device writes it, with the same AO to the bit as the
//! four-channel chain and a quarter of its bytes; SSDO keeps its light in four.

use crate::common;

use common::occlusion::{ao, render, settings};
use vrao_ao::plug::{ChainLayout, FINAL_AO};
use vrao_ao::{AoSettings, Denoise, Resolution, Technique};
use vrao_render::scene::Scene;

/// The chain's variants a frame can take: every technique without light at full and half
/// resolution, with the tile denoise, the bilateral blur and temporal accumulation.
fn variants() -> Vec<AoSettings> {
    let mut all = Vec::new();
    for technique in [Technique::Gtao, Technique::Ssao, Technique::Hbao] {
        for resolution in [Resolution::Full, Resolution::Half] {
            all.push(AoSettings { resolution, ..ao(technique, 12, 0.5) });
        }
    }
    all.push(AoSettings { denoise: Denoise::Bilateral, ..ao(Technique::Gtao, 12, 0.5) });
    let temporal = vrao_ao::Temporal { enabled: true, ..vrao_ao::Temporal::default() };
    all.push(AoSettings { temporal, ..ao(Technique::Gtao, 12, 0.5) });
    all
}

#[test]
fn the_scalar_chain_holds_the_four_channel_chains_ao_to_the_bit_in_a_quarter_of_the_bytes() {
    let (scalar, four, _lock) = common::shared_and_four_channel_gpus();
    assert!(scalar.caps.scalar_chain, "lavapipe, like every desktop Vulkan GPU, writes R16Float storage");
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    for ao in variants() {
        let s = settings(48, 40, ao.clone());
        let frame_a = render(&scalar, &scene, &s, &head, &[FINAL_AO]);
        let frame_b = render(&four, &scene, &s, &head, &[FINAL_AO]);
        let (a, b) = (&frame_a.outputs[&FINAL_AO], &frame_b.outputs[&FINAL_AO]);
        let differing = a.iter().flatten().zip(b.iter().flatten()).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
        assert_eq!(differing, 0, "{ao:?}: {differing} values differ between the chain layouts");
        let open = a.iter().flatten().skip(3).step_by(4).filter(|v| **v < 0.99).count();
        assert!(open > 100, "{ao:?}: the frame has occlusion to compare ({open} occluded pixels)");
        // The declared traffic of the frames just rendered: each chain texture a quarter of
        // the bytes (the plans are the same; the layouts differ).
        let half = ao.resolution.is_half();
        let layout = |gpu: &vrao_ao::plug::Gpu| ChainLayout::of(ao.technique.carries_light(), gpu.caps.scalar_chain);
        let small = frame_a.report.plan.occlusion_traffic(layout(&scalar), half);
        let large = frame_b.report.plan.occlusion_traffic(layout(&four), half);
        eprintln!("{:?} {:?}: {small:?} vs {large:?}", ao.technique, ao.resolution);
        assert!(small.written < 0.5 * large.written && small.read < large.read, "{small:?} vs {large:?}");
    }
}

#[test]
fn ssdo_keeps_its_light_in_four_channels_on_a_device_that_writes_one() {
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let s = settings(40, 32, ao(Technique::Ssdo, 12, 0.5));
    let f = render(&gpu, &scene, &s, &scene.head.pose_at(0.0), &[FINAL_AO]);
    let light = f.outputs[&FINAL_AO].iter().flatten().enumerate().filter(|(i, v)| i % 4 < 3 && **v > 0.0).count();
    assert!(light > 100, "SSDO's gathered light survives the chain ({light} lit channels)");
}
