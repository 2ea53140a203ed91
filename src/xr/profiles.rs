//! Named headset profiles: per-eye render size (the panel's), per-eye field of view, the
//! refresh rates the headset supports and the one it runs at by default.
//!
//! Fields of view are the frustum tangents a runtime reported for the left eye, as dumped
//! by hmdq into the HMD Geometry Database (<https://risa2000.github.io/hmdgdb/>); that is what
//! an app gets from the runtime (OpenVR's GetProjectionRaw, OpenXR's xrLocateViews). The right
//! eye is the left eye mirrored: each dump's right eye matches that to within 0.3°.

use crate::error::{Error, Result};
use vrao_ao::{Fov, ViewMask, VisibilityMask};
use vrao_render::headset::DEFAULT_IPD;
use vrao_render::HeadsetProfile;

/// The names [`by_name`] knows, as the CLI spells them.
pub const PROFILE_NAMES: [&str; 6] = ["vive", "vive-pro-2", "index", "quest-2", "quest-3", "pico-4"];

/// The profile of a named headset at its default refresh rate; an unknown name is
/// `Error::Input` listing the known ones.
pub fn by_name(name: &str) -> Result<HeadsetProfile> {
    match name {
        "vive" => Ok(HeadsetProfile::vive()),
        "vive-pro-2" => Ok(vive_pro_2()),
        "index" => Ok(index()),
        "quest-2" => Ok(quest_2()),
        "quest-3" => Ok(quest_3()),
        "pico-4" => Ok(pico_4()),
        _ => Err(Error::input(format!("unknown headset profile '{name}' (known: {})", PROFILE_NAMES.join(", ")))),
    }
}

/// A field of view from the tangents of its edges (left and down negative), the form the
/// dumps' "raw LRBT values" take; converting once here keeps their precision.
fn from_tangents(left: f64, right: f64, up: f64, down: f64) -> Fov {
    Fov { left: left.atan() as f32, right: right.atan() as f32, up: up.atan() as f32, down: down.atan() as f32 }
}

fn profile(
    name: &'static str,
    (width, height): (u32, u32),
    refresh_hz: f64,
    refresh_rates_hz: &'static [f64],
    fov_left: Fov,
) -> HeadsetProfile {
    HeadsetProfile {
        name,
        width,
        height,
        refresh_hz,
        refresh_rates_hz,
        // The wearer's IPD, not the headset's: the same 64 mm for every profile so that
        // profiles differ only in display and optics.
        ipd: DEFAULT_IPD,
        fov_left,
        fov_right: fov_left.mirrored(),
    }
}

fn vive_pro_2() -> HeadsetProfile {
    profile(
        "vive-pro-2",
        // The full-resolution mode is 4896×2448 for both eyes (VIVE_PRO_2_MODES in
        // crates/vive-hid/src/lib.rs of https://github.com/CertainLach/VivePro2-Linux-Driver).
        (2448, 2448),
        // The rate of that full-resolution mode, and the one the FOV dump was taken at.
        90.0,
        // The same mode table lists 90 Hz and 120 Hz modes.
        &[90.0, 120.0],
        // 58.3° out, 39.9° nasal, 48.2° up, 48.1° down under SteamVR
        // (https://risa2000.github.io/hmdgdb/hmd_cfgs/VIVEPro2_Native_R90.html).
        from_tangents(-1.616823, 0.837388, 1.119002, -1.115087),
    )
}

fn index() -> HeadsetProfile {
    profile(
        "index",
        // eye_target_width/height_in_pixels in an Index's own config
        // (https://gist.github.com/ChristophHaag/4def7bda0a48fd70eff6dcb6c7d3b44a).
        (1440, 1600),
        // 120 Hz is the Index's base rate; 80 and 90 Hz are for compatibility and 144 Hz is
        // experimental (https://cnews.cz/valve-index-vr-headset-virtualni-realita-uvedeni-specifiakce-cena).
        120.0,
        &[80.0, 90.0, 120.0, 144.0],
        // The Index cants its displays 5° outward; SteamVR's parallel-projection mode reports
        // the equivalent parallel frustum, which is what these parallel eyes need: 54.6° out,
        // 42.1° nasal, 54.4° up, 54.1° down
        // (https://risa2000.github.io/hmdgdb/hmd_cfgs/Index_PP_R144.html).
        from_tangents(-1.538816, 1.055010, 1.413973, -1.408557),
    )
}

fn quest_2() -> HeadsetProfile {
    profile(
        "quest-2",
        // One 3664×1920 panel split between the eyes (https://mixed.de/?page_id=167331, from
        // Meta's Display Week 2022 talk): 1832×1920 per eye.
        (1832, 1920),
        // Meta: "The default display refresh rate for apps is 72 Hz", and its table of rates
        // per device (60 Hz is for media apps only, so it is left out)
        // (https://developers.meta.com/horizon/documentation/native/android/mobile-display-refresh-rate).
        72.0,
        &[72.0, 80.0, 90.0, 96.0, 100.0, 120.0],
        // Default FOV through the Oculus runtime: 52° out, 45° nasal, 48° up, 50° down
        // (https://risa2000.github.io/hmdgdb/hmd_cfgs/Quest2_Native_R72.html).
        from_tangents(-1.279942, 1.0, 1.110613, -1.191754),
    )
}

fn quest_3() -> HeadsetProfile {
    profile(
        "quest-3",
        // "2 × 2064 × 2208p RGB-stripe LCD+ panels, one per eye"
        // (https://en.wikipedia.org/wiki/Meta_Quest_3).
        (2064, 2208),
        // Default and supported rates: the same Meta page as the Quest 2's
        // (https://developers.meta.com/horizon/documentation/native/android/mobile-display-refresh-rate).
        72.0,
        &[72.0, 80.0, 90.0, 96.0, 100.0, 120.0],
        // Default FOV through the Oculus runtime: 54° out, 40° nasal, 44° up, 54.3° down
        // (https://risa2000.github.io/hmdgdb/hmd_cfgs/MetaQuest3_Native_R72.html).
        from_tangents(-1.376382, 0.839100, 0.965689, -1.428148),
    )
}

fn pico_4() -> HeadsetProfile {
    profile(
        "pico-4",
        // "Resolution 2160x2160 per-eye" (https://xinreality.com/wiki/Pico_4); the runtime's
        // recommended render target in the FOV dump below is also 2160×2160.
        (2160, 2160),
        // Pico's own default is not published where we looked: 90 Hz is the rate the FOV dump
        // was taken at.
        90.0,
        // "Refresh Rate = 72Hz, 90Hz" (https://vrarwiki.com/index.php?diff=cur&oldid=37087&title=PICO_4).
        &[72.0, 90.0],
        // Unlike the others, the runtime reports a symmetric frustum, 52° on every side
        // (https://risa2000.github.io/hmdgdb/hmd_cfgs/PICO4_Native_R90.html); no public
        // per-eye dump with an outward/nasal split was found, so none is made up here.
        from_tangents(-1.279942, 1.279942, 1.279942, -1.279942),
    )
}

/// The share of each eye's render target a headset's own hidden-area mesh covers, where one
/// is published: hmdq's "mesh area" of the left eye's HAM mesh in the HMD Geometry Database
/// (<https://risa2000.github.io/hmdgdb/hmd_cfgs/Vive_Native_R90.html>: 19.10 %;
/// <https://risa2000.github.io/hmdgdb/hmd_cfgs/Quest2_Native_R72.html>: 9.13 %).
fn published_hidden_share(name: &str) -> Option<f64> {
    match name {
        "vive" => Some(0.1910),
        "quest-2" => Some(0.0913),
        _ => None,
    }
}

/// The visibility mask of a profile's eyes. Where the headset's hidden area is published
/// (`published_hidden_share`) the lens shows a superellipse |x|ⁿ + |y|ⁿ ≤ 1 in each eye's
/// rectangle (its four edges touched, the corners cut round, as the dumps' HAM meshes of
/// four corner n-gons are), its n chosen so it hides that share; elsewhere (and for a
/// size or frustum of no named headset) Monado's default for a device without a mask of
/// its own: the four corners cut off from the field of view.
pub fn visibility_mask(profile: &HeadsetProfile) -> VisibilityMask {
    let eye = |fov: &Fov| match published_hidden_share(profile.name) {
        Some(share) => ViewMask::superellipse(
            fov.tangents(),
            superellipse_exponent_hiding(share),
            256,
            format!("the {} lens: {:.1} % hidden as its published hidden-area mesh", profile.name, share * 100.0),
        ),
        None => ViewMask::corner_cut(fov.tangents()),
    };
    VisibilityMask { views: vec![eye(&profile.fov_left), eye(&profile.fov_right)] }
}

/// The exponent n whose superellipse |x|ⁿ + |y|ⁿ ≤ 1 leaves `share` of the square
/// [−1, 1]² outside it (n ≥ 2: between the inscribed ellipse's 21.5 % and none).
fn superellipse_exponent_hiding(share: f64) -> f64 {
    // The area inside, by the midpoint rule on its quarter: ∫₀¹ (1 − xⁿ)^(1/n) dx.
    let hidden = |n: f64| {
        const STEPS: usize = 4096;
        let quarter: f64 = (0..STEPS)
            .map(|i| {
                let x = (i as f64 + 0.5) / STEPS as f64;
                (1.0 - x.powf(n)).max(0.0).powf(1.0 / n)
            })
            .sum::<f64>()
            / STEPS as f64;
        1.0 - quarter
    };
    let (mut lo, mut hi) = (2.0, 64.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if hidden(mid) > share {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn degrees(fov: &Fov) -> [f64; 4] {
        [fov.left, fov.right, fov.up, fov.down].map(|a| (a as f64).to_degrees())
    }

    #[test]
    fn every_name_resolves_to_a_profile_of_that_name_and_panel_size() {
        let sizes = [
            ("vive", 1080, 1200),
            ("vive-pro-2", 2448, 2448),
            ("index", 1440, 1600),
            ("quest-2", 1832, 1920),
            ("quest-3", 2064, 2208),
            ("pico-4", 2160, 2160),
        ];
        for (name, (expected, width, height)) in PROFILE_NAMES.iter().zip(sizes) {
            assert_eq!(*name, expected);
            let p = by_name(name).unwrap();
            assert_eq!(p.name, *name);
            assert_eq!((p.width, p.height), (width, height), "{name}");
            assert_eq!(p.ipd, 0.064, "{name}");
        }
    }

    #[test]
    fn vive_is_the_existing_vive_frustum_at_90_hz() {
        let p = by_name("vive").unwrap();
        assert_eq!(p, HeadsetProfile::vive());
        assert_eq!(p, HeadsetProfile::with_size("vive", 1080, 1200));
        assert_eq!((p.refresh_hz, p.refresh_rates_hz), (90.0, &[90.0][..]));
    }

    #[test]
    fn left_eye_is_wider_outward_and_the_right_eye_mirrors_it() {
        for name in PROFILE_NAMES {
            let p = by_name(name).unwrap();
            p.fov_left.validate().unwrap();
            p.fov_right.validate().unwrap();
            let [left, right, _, _] = degrees(&p.fov_left);
            let (outward, nasal) = (-left, right);
            if name == "pico-4" {
                // Its runtime reports a symmetric frustum (see pico_4).
                assert!((outward - nasal).abs() < 1e-4, "{name}: {outward}° out, {nasal}° nasal");
            } else {
                assert!(outward > nasal + 5.0, "{name}: {outward}° out, {nasal}° nasal");
            }
            assert_eq!(p.fov_right, p.fov_left.mirrored(), "{name}");
            // The right eye's outward side is its right side.
            assert_eq!(p.fov_right.right, -p.fov_left.left, "{name}");
        }
    }

    #[test]
    fn per_eye_totals_are_between_80_and_130_degrees() {
        for name in PROFILE_NAMES {
            let p = by_name(name).unwrap();
            for fov in [p.fov_left, p.fov_right] {
                let [left, right, up, down] = degrees(&fov);
                let (horizontal, vertical) = (right - left, up - down);
                assert!((80.0..=130.0).contains(&horizontal), "{name}: horizontal {horizontal}°");
                assert!((80.0..=130.0).contains(&vertical), "{name}: vertical {vertical}°");
            }
        }
    }

    #[test]
    fn tangents_give_the_dumped_angles() {
        // The Quest 2 dump prints its angles as whole degrees: 52 out, 45 nasal, 48 up, 50 down.
        let got = degrees(&by_name("quest-2").unwrap().fov_left);
        for (g, e) in got.iter().zip([-52.0, 45.0, 48.0, -50.0]) {
            assert!((g - e).abs() < 0.01, "{got:?}");
        }
    }

    #[test]
    fn default_rate_is_a_supported_one_and_budget_follows_the_rate() {
        for name in PROFILE_NAMES {
            let p = by_name(name).unwrap();
            assert!(p.refresh_rates_hz.contains(&p.refresh_hz), "{name}");
            assert!((p.budget_ms() - 1000.0 / p.refresh_hz).abs() < 1e-12, "{name}");
        }
        let index = by_name("index").unwrap();
        assert!((index.budget_ms() - 8.333).abs() < 1e-3);
        let fast = index.with_refresh(144.0).unwrap();
        assert_eq!(fast.refresh_hz, 144.0);
        assert!((fast.budget_ms() - 6.944).abs() < 1e-3);
        assert_eq!(by_name("vive").unwrap().budget_ms(), 1000.0 / 90.0);
    }

    #[test]
    fn unknown_name_is_one_line_naming_it_and_every_known_name() {
        let err = by_name("rift-cv1").unwrap_err();
        assert_eq!(err.exit_code(), crate::error::EXIT_INPUT);
        let err = err.to_string();
        assert!(!err.contains('\n'), "{err}");
        assert!(err.contains("'rift-cv1'"), "{err}");
        for name in PROFILE_NAMES {
            assert!(err.contains(name), "{err} lacks {name}");
        }
        assert!(by_name("Index").is_err(), "names are exact");
    }

    #[test]
    fn with_render_size_keeps_the_field_of_view_and_rate() {
        let p = by_name("quest-3").unwrap();
        let small = p.with_render_size(1032, 1104);
        assert_eq!((small.width, small.height), (1032, 1104));
        assert_eq!((small.fov_left, small.fov_right), (p.fov_left, p.fov_right));
        assert_eq!(
            (small.name, small.refresh_hz, small.refresh_rates_hz, small.ipd),
            (p.name, p.refresh_hz, p.refresh_rates_hz, p.ipd)
        );
    }

    #[test]
    fn with_refresh_takes_sane_rates_and_rejects_others_in_one_line() {
        let p = by_name("pico-4").unwrap();
        assert_eq!(p.with_refresh(72.0).unwrap().refresh_hz, 72.0);
        // A rate the product does not list but a runtime may run at (Monado: 20 Hz).
        assert_eq!(by_name("vive").unwrap().with_refresh(20.0).unwrap().budget_ms(), 50.0);
        assert_eq!(p.with_refresh(120.0).unwrap().refresh_hz, 120.0);
        for bad in [5.0, 501.0, f64::NAN, 0.0, -90.0] {
            let err = p.with_refresh(bad).unwrap_err().to_string();
            assert!(!err.contains('\n'), "{err}");
            assert!(err.contains("10..=500 Hz") && err.contains("pico-4") && err.contains("72, 90"), "{err}");
        }
        let quest = by_name("quest-2").unwrap().with_refresh(120.0).unwrap();
        assert_eq!(quest.budget_ms(), 1000.0 / 120.0);
        assert_eq!(quest.fov_left, by_name("quest-2").unwrap().fov_left);
    }

    #[test]
    fn profile_masks_hide_the_published_share_or_monados_corners() {
        for name in PROFILE_NAMES {
            let p = by_name(name).unwrap();
            let mask = visibility_mask(&p);
            assert_eq!(mask.views.len(), 2);
            let (w, h) = (p.width / 8, p.height / 8);
            for (view, fov) in mask.views.iter().zip([p.fov_left, p.fov_right]) {
                let share = view.hidden_share(w, h, fov.tangents());
                let expected = published_hidden_share(name).unwrap_or(0.03125);
                assert!((share - expected).abs() < 0.006, "{name}: {share} hidden, expected {expected}");
            }
        }
    }
}
