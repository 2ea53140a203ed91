//! The frame plan of the occlusion (`--explain`): the final AO is what the AO chain last
//! provided, and the plan says what the occlusion left out and why.
//!
//! `cargo test --release --test occlusion_plan -- --nocapture` shows what the tests measure.

use crate::common;

use common::occlusion::{ao_passes, render, settings};
use vrao_ao::plug::{AO_ACCUMULATED, AO_BLURRED, AO_FULL, AO_RAW, FINAL_AO};
use vrao_ao::{AoSettings, Resolution, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::scene::Scene;
use vrao_render::Renderer;

// ---------------------------------------------------------------------------------------
// The plan (`--explain`)

/// The final AO is the graph's named output: the last texture the AO chain provides for
/// these settings, and the occlusion's cost is the chain's passes (what the governor
/// and the bench time).
#[test]
fn the_final_ao_is_what_the_ao_chain_last_provided() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let cases = [
        // (technique, blur radius, half resolution, temporal) → final AO, occlusion passes
        (Technique::Gtao, 4, false, false, AO_BLURRED, vec!["gtao", "blur"]),
        (Technique::Gtao, 4, true, false, AO_FULL, vec!["gtao", "blur", "upsample"]),
        (Technique::Ssao, 0, false, false, AO_RAW, vec!["ssao"]),
        (Technique::Hbao, 0, false, true, AO_ACCUMULATED, vec!["hbao", "temporal"]),
        (Technique::Ssdo, 4, true, true, AO_FULL, vec!["ssdo", "temporal", "blur", "upsample"]),
    ];
    for (technique, blur_radius, half_res, temporal, expected, chain) in cases {
        let mut ao = AoSettings {
            technique,
            blur_radius,
            resolution: Resolution::from_half_res(half_res),
            ..AoSettings::default()
        };
        ao.temporal.enabled = temporal;
        let renderer = Renderer::new(gpu.clone(), &scene, &settings(64, 72, ao)).unwrap();
        let plan = renderer.plan(2, &[FINAL_AO]).unwrap();
        let label = format!("{technique:?} blur {blur_radius} half {half_res} temporal {temporal}");
        assert_eq!(plan.resolve(FINAL_AO), Some(expected), "{label}\n{plan}");
        assert_eq!(plan.occlusion_passes(), chain, "{label}");
        // The composite of a frame reads the occlusion at occlusion resolution, never the
        // standalone upsample's output: a frame of the eyes alone runs no upsample.
        let frame = renderer.plan(2, &[COLOR]).unwrap();
        assert!(!frame.runs("upsample"), "{label}\n{frame}");
    }
    let none = AoSettings { technique: Technique::None, ..AoSettings::default() };
    let renderer = Renderer::new(gpu.clone(), &scene, &settings(64, 72, none)).unwrap();
    assert!(renderer.plan(2, &[COLOR]).unwrap().resolve(FINAL_AO).is_none());
    let error = renderer.plan(2, &[FINAL_AO]).unwrap_err().to_string();
    assert!(error.contains("final-ao"), "{error}");
}

#[test]
fn the_plan_explains_what_occlusion_left_out() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let head = scene.head.pose_at(0.0);
    let plan_for = |a: AoSettings| render(&gpu, &scene, &settings(64, 72, a), &head, &[COLOR]).report.plan;

    let none = plan_for(AoSettings { technique: Technique::None, ..AoSettings::default() });
    eprintln!("technique none:\n{none}");
    for pass in ao_passes().iter().chain(&["blur", "upsample"]) {
        assert!(!none.runs(pass), "technique none runs {pass}");
    }
    // One pass per technique is declared; SSDO's is named "ssdo-bounce" only while the
    // bounce is on, so with technique none the SSDO pass is left out as "ssdo".
    for pass in ["ssao", "hbao", "ssdo"] {
        let reason = none.left_out.iter().find(|(n, _)| *n == pass).map(|(_, why)| why.as_str());
        assert!(
            reason.is_some_and(|r| r.contains("none")),
            "technique none: {pass} left out without saying why ({reason:?})"
        );
    }
    assert!(none.runs("composite") && none.runs("tonemap"));

    let off = plan_for(AoSettings { technique: Technique::SsdoBounce, bounce: 0.0, ..AoSettings::default() });
    eprintln!("ssdo-bounce, bounce 0:\n{off}");
    assert!(off.runs("ssdo") && !off.runs("ssdo-bounce"), "bounce 0 runs the plain ssdo pass: {:?}", off.names);
    assert!(
        off.notes.iter().any(|(pass, note)| *pass == "ssdo" && note.contains("bounce") && note.contains("left out")),
        "no note says the bounce is left out: {:?}",
        off.notes
    );

    let on = plan_for(AoSettings {
        technique: Technique::SsdoBounce,
        bounce: 1.0,
        resolution: Resolution::Half,
        ..AoSettings::default()
    });
    eprintln!("ssdo-bounce, half res:\n{on}");
    assert_eq!(on.names, ["gbuffer", "direct", "ssdo-bounce", "blur", "composite", "tonemap"]);
    assert!(on.notes.iter().all(|(_, note)| !note.contains("bounce left out")));
    // A frame upsamples inside the composite; the upsample pass (a full-resolution
    // occlusion target) runs only when that target itself is asked for.
    assert!(on.notes.iter().any(|(pass, note)| *pass == "composite" && note.contains("upsamples")), "{:?}", on.notes);
    assert!(on.left_out.iter().any(|(pass, why)| *pass == "upsample" && why.contains("ao-full")), "{:?}", on.left_out);
    let half_bounce = AoSettings {
        technique: Technique::SsdoBounce,
        bounce: 1.0,
        resolution: Resolution::Half,
        ..AoSettings::default()
    };
    let debug = render(&gpu, &scene, &settings(64, 72, half_bounce), &head, &[COLOR, AO_FULL]).report.plan;
    assert!(debug.runs("upsample") && debug.runs("composite"), "{:?}", debug.names);
    for (technique, pass) in [(Technique::Ssao, "ssao"), (Technique::Hbao, "hbao"), (Technique::Ssdo, "ssdo")] {
        let plan = plan_for(AoSettings { technique, blur_radius: 0, ..AoSettings::default() });
        assert!(
            plan.runs(pass) && !plan.runs("blur") && !plan.runs("upsample"),
            "{}: {:?}",
            technique.name(),
            plan.names
        );
        let others: Vec<_> = ao_passes().into_iter().filter(|p| *p != pass && plan.runs(p)).collect();
        assert!(others.is_empty(), "{} also runs {others:?}", technique.name());
    }
}

/// `--fold-right-eye` is said in the plan wherever it is asked for: done for GTAO and SSDO
/// (their shared march), and of no effect for the other techniques, for one view or with
/// independent eyes, never dropped in silence.
#[test]
fn the_plan_says_where_the_folded_right_eye_applies() {
    let (gpu, _guard) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let note_of = |technique: Technique, stereo_reuse: bool, views: u32| {
        let mut ao = AoSettings { technique, stereo_reuse, ..AoSettings::default() };
        ao.gtao.fold_right_eye = true;
        let renderer = Renderer::new(gpu.clone(), &scene, &settings(64, 72, ao)).unwrap();
        let plan = renderer.plan(views, &[COLOR]).unwrap();
        let notes: Vec<String> =
            plan.notes.iter().filter(|(_, note)| note.contains("fold-right-eye")).map(|(_, n)| n.clone()).collect();
        assert_eq!(notes.len(), 1, "{technique:?}: one note on the fold, not {notes:?}");
        notes[0].clone()
    };
    for technique in [Technique::Gtao, Technique::Ssdo] {
        assert!(note_of(technique, true, 2).contains("left eye's dispatch"), "{technique:?}");
        assert!(note_of(technique, false, 2).contains("no effect"), "{technique:?} with independent eyes");
        assert!(note_of(technique, true, 1).contains("no effect"), "{technique:?} with one view");
    }
    for technique in [Technique::Ssao, Technique::Hbao, Technique::FetchOnly, Technique::SsdoPoints] {
        assert!(note_of(technique, true, 2).contains("no effect"), "{technique:?}");
    }
}
