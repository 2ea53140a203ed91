//! The peer (Bevy 0.19's SSAO, `peers/bevy`) read and scored right: on an open plane the
//! reference is 1 everywhere, and Bevy's AO there is its known 0.84 (too few sectors of
//! its visibility bitmask see the whole hemisphere), so its bias must come out near
//! −0.16 and its AO image must be that constant, not sky, noise or a shifted frame.
//!
//! Needs the peer program, its own Cargo project (a cold build of Bevy takes a quarter of an
//! hour), so the test is ignored by default: `.ci/peer` builds the peer, names it in
//! `VRAO_PEER_BEVY` and runs this test with `--ignored`.

use std::path::PathBuf;
use vrao::measure::bench::ReferenceOptions;
use vrao::measure::peer::{run_peer, scene_for_peer, Family, PeerOptions};
use vrao_render::renderer::TimingChoice;
use vrao_render::{BackendChoice, HeadsetProfile, Scene, Settings};

#[test]
#[ignore = "needs the Bevy peer: bash .ci/peer builds it and runs this test"]
fn bevy_on_an_open_plane_reads_its_known_084_against_a_reference_of_1() {
    let peer = std::env::var_os("VRAO_PEER_BEVY")
        .map(PathBuf::from)
        .expect("VRAO_PEER_BEVY names the peer program (bash .ci/peer builds it and sets it)");
    let out = crate::common::temp_dir("peer-plane");
    let scene = Scene::load("builtin:plane").unwrap();
    let base = Settings { profile: HeadsetProfile::with_size("vive", 96, 104), ..Settings::default() };
    let gltf = out.join("plane.glb");
    vrao::test_assets::gltf_write::write(&scene_for_peer(&scene), &gltf, &Default::default()).unwrap();
    let options = PeerOptions {
        backend: BackendChoice::Auto,
        peer,
        presets: vec!["high".into()],
        samples: vec![24],
        half_res: vec![false],
        timing: TimingChoice::Serial,
        warmup: 1,
        frames: 1,
        rounds: 1,
        reference: ReferenceOptions { rays_per_pixel: 64, stride: 4, cache: out.join("cache") },
        out: out.to_path_buf(),
        gltf,
        interrupt: Default::default(),
    };
    let run = run_peer(&scene, &base, &options).unwrap();
    let bevy = run.rows.iter().find(|r| r.family == Family::Bevy).unwrap();
    let vrao = run.rows.iter().find(|r| r.family == Family::Vrao).unwrap();
    // The AO Bevy wrote: on the floor below the horizon, one value near 0.84.
    let ao: Vec<f32> = std::fs::read(out.join("peer-work/round-0/ao_high_left.f32"))
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(ao.len(), 96 * 104);
    let floor: Vec<f32> = ao[96 * 80..].to_vec();
    let mean = floor.iter().sum::<f32>() / floor.len() as f32;
    assert!((mean - 0.84).abs() < 0.04, "Bevy's AO on the open floor: {mean}");
    // Scored against the reference (1 on an open plane): bias −0.16, RMSE about as much.
    assert!((bevy.error.ao_bias + 0.16).abs() < 0.04, "Bevy's bias {}", bevy.error.ao_bias);
    assert!((bevy.error.ao_rmse - 0.16).abs() < 0.05, "Bevy's RMSE {}", bevy.error.ao_rmse);
    // vrao's GTAO sees the open plane as open.
    assert!(vrao.error.ao_bias.abs() < 0.03, "vrao's bias {}", vrao.error.ao_bias);
    assert!(bevy.ms_stereo > 0.0 && vrao.ms_stereo > 0.0);
}
