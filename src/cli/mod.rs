//! The binary's subcommands, one file each: each parses its options and calls one
//! library function. This file holds the options several of them share.

pub(crate) mod bench;
pub(crate) mod budget;
pub(crate) mod info;
pub(crate) mod peer;
pub(crate) mod render;
pub(crate) mod reprojection;
pub(crate) mod run;
pub(crate) mod table;
pub(crate) mod temporal;

/// A flag that the first Ctrl-C (SIGINT) or SIGTERM sets, saying `first` on stderr, for
/// the command to end cleanly; a second one runs `second` (its last cleaning up) and stops
/// the process at once (130, as a shell reports an interrupted command). At once means
/// `_exit`, not `exit`: `exit` runs the C libraries' destructors (Mesa's, LLVM's) while the
/// main thread may still be tearing the device down, which killed vrao with a signal
/// instead of 130 (seen once in four CI runs).
pub(crate) fn interrupt_on_signals(
    first: &'static str,
    second: impl Fn() + Send + 'static,
) -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let interrupt = std::sync::Arc::new(AtomicBool::new(false));
    let flag = interrupt.clone();
    let installed = ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::Relaxed) {
            second();
            // SAFETY: `_exit` only ends the process; it touches no state of this one.
            unsafe { libc::_exit(vrao::error::EXIT_INTERRUPTED) };
        }
        eprintln!("interrupted: {first} (again to stop at once)");
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C will stop vrao at once, without cleaning up: {e}");
    }
    interrupt
}

/// A clap value parser for a setting chosen by name ([`Choice`]): the engine and the
/// renderer have no command line, so the CLI offers their settings' names itself.
pub(crate) fn choice<T: Choice + Send + Sync>() -> impl clap::builder::TypedValueParser<Value = T> {
    let values =
        T::all().iter().map(|v| clap::builder::PossibleValue::new(v.name()).aliases(v.aliases().iter().copied()));
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(values).map(|name| T::from_name(&name).expect("clap checked the name"))
}

use clap::Args;
use glam::DVec3;
use vrao_ao::{
    AoSettings, Choice, Denoise, Foveation, GtaoSettings, Noise, Quality, Technique, Temporal, TemporalBlend,
};
use vrao_render::passes::shadow::suggested_rsm_radius;
use vrao_render::settings::{ShadowSettings, AO_RADIUS_MAX, AO_RADIUS_MIN, AO_RADIUS_OF_DIAGONAL};
use vrao_render::{BounceForm, HeadsetProfile, PointSsdoSettings, Scene, Settings};

/// Help heading of the shadow options (part of every command that renders).
const SHADOW_HEADING: &str = "Shadows and reflective shadow maps";

/// A switch: on or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum OnOff {
    On,
    Off,
}

impl OnOff {
    pub(crate) fn on(self) -> bool {
        self == OnOff::On
    }
}

impl From<bool> for OnOff {
    fn from(on: bool) -> OnOff {
        if on {
            OnOff::On
        } else {
            OnOff::Off
        }
    }
}

/// Shadow options for directional lights.
#[derive(Args, Clone)]
pub(crate) struct LightArgs {
    /// Shadow maps with 3×3 PCF for the directional lights: on or off (a scene with no
    /// directional light has none either way).
    #[arg(long, help_heading = SHADOW_HEADING, value_enum, default_value_t = OnOff::from(ShadowSettings::default().enabled))]
    shadows: OnOff,
    /// Texels along each side of the square light-space maps, 16..=8192.
    #[arg(long, allow_negative_numbers = true, help_heading = SHADOW_HEADING, default_value_t = ShadowSettings::default().size)]
    shadow_size: u32,
    /// One bounce of the directional lights from reflective shadow maps: on or off.
    #[arg(long, help_heading = SHADOW_HEADING, value_enum, default_value_t = OnOff::from(ShadowSettings::default().rsm))]
    rsm: OnOff,
    /// Virtual point lights gathered per pixel and light by the reflective shadow maps,
    /// 1..=1024.
    #[arg(long, allow_negative_numbers = true, help_heading = SHADOW_HEADING, default_value_t = ShadowSettings::default().rsm_samples)]
    rsm_samples: u32,
    /// RSM gather radius in metres (default: a quarter of the scene's diagonal, within 0.1..=4 m).
    #[arg(long, help_heading = SHADOW_HEADING, allow_negative_numbers = true)]
    rsm_radius: Option<f32>,
}

impl LightArgs {
    pub(crate) fn settings(&self, scene: &Scene) -> ShadowSettings {
        ShadowSettings {
            enabled: self.shadows.on(),
            size: self.shadow_size,
            rsm: self.rsm.on(),
            rsm_samples: self.rsm_samples,
            rsm_radius: self.rsm_radius.unwrap_or_else(|| suggested_rsm_radius(scene)),
        }
    }
}

/// GTAO's free parameters (its pass's own settings) and the stereo reuse (the render
/// commands and the bench).
#[derive(Args, Clone)]
pub(crate) struct GtaoArgs {
    /// GTAO: the slab behind each depth sample that counts as solid, as a fraction of the
    /// radius (thin objects stop occluding behind themselves).
    #[arg(long, allow_negative_numbers = true, default_value_t = GtaoSettings::default().thickness)]
    thickness: f32,
    /// GTAO: the share of its stratum a solid depth sample blocks on its own surface's
    /// plane, 0..=1 (0: its point alone, and the footprint's code compiled out; few
    /// samples then step over thin occluders).
    #[arg(long, allow_negative_numbers = true, default_value_t = GtaoSettings::default().footprint)]
    footprint: f32,
    /// GTAO: the samples' spread along a half-slice, 1..=2: sample t ∈ (0, 1) lies at
    /// r · t ((2 − P) + (P − 1) t), even at 1, quadratic (crowded near the pixel) at 2.
    #[arg(long, allow_negative_numbers = true, default_value_t = GtaoSettings::default().step_power)]
    step_power: f32,
    /// GTAO: successive samples whose distances differ by less than this fraction of the
    /// radius lie on one continuous surface, which also blocks the angles between them
    /// (0: never).
    #[arg(long, allow_negative_numbers = true, default_value_t = GtaoSettings::default().connect)]
    connect: f32,
    /// Compute both eyes on their own; by default the right eye takes the left eye's value
    /// wherever the left eye sees the same surface point (every technique's march or
    /// samples; at half resolution the upsampled AO, or SSDO's denoise).
    #[arg(long)]
    independent_eyes: bool,
    /// GTAO: march the right eye's pixels the left eye cannot give in the left eye's
    /// dispatch (listed from the depth first, copied after) instead of a dispatch of their
    /// own; for measuring on a GPU (off by default).
    #[arg(long)]
    fold_right_eye: bool,
    /// With two depth layers: the second layer's minimum separation behind the first, as a
    /// fraction of the radius, 0..=1 (0: the next surface, a closed object's own back).
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().layer_separation)]
    layer_separation: f32,
}

impl GtaoArgs {
    /// GTAO's own settings as given.
    pub(crate) fn settings(&self) -> GtaoSettings {
        GtaoSettings {
            thickness: self.thickness,
            footprint: self.footprint,
            step_power: self.step_power,
            connect: self.connect,
            fold_right_eye: self.fold_right_eye,
            ..GtaoSettings::default()
        }
    }

    pub(crate) fn apply(&self, ao: &mut AoSettings) {
        ao.gtao = self.settings();
        ao.stereo_reuse = !self.independent_eyes;
        ao.layer_separation = self.layer_separation;
    }
}

/// Occlusion options (shared by every command that renders).
#[derive(Args, Clone)]
pub(crate) struct AoArgs {
    #[command(flatten)]
    pub lights: LightArgs,
    #[arg(value_parser = choice::<Technique>(), long, default_value_t = AoSettings::default().technique, hide_possible_values = true, help = technique_help())]
    technique: Technique,
    /// Sampling preset: low, medium, high or ultra (N = 12, 24, 36, 64 depth taps; ultra
    /// also reads two depth layers).
    #[arg(value_parser = choice::<Quality>(), long, default_value_t = Quality::default(), hide_possible_values = true)]
    quality: Quality,
    /// Depth taps per pixel, 1..=256 (overrides --quality).
    #[arg(long, allow_negative_numbers = true)]
    samples: Option<u32>,
    #[arg(long, allow_negative_numbers = true, help = radius_help())]
    radius: Option<f32>,
    /// Occlusion weight, 0..=4 (1 = full occlusion).
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().strength)]
    strength: f32,
    /// Depth bias as a fraction of the radius.
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().bias)]
    bias: f32,
    /// SSDO bounce strength (ssdo-bounce, ssdo-points-bounce); 0 leaves the bounce out.
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().bounce)]
    bounce: f32,
    /// How ssdo-points-bounce weighs a blocking sample's sender: direction (its solid angle 2π/N ×
    /// the receiver cosine) or patch (Ritschel et al. 2009 eq. 2: area π r²/N, both
    /// cosines, 1/d²).
    #[arg(value_parser = choice::<BounceForm>(), long, default_value_t = PointSsdoSettings::default().bounce_form, hide_possible_values = true)]
    bounce_form: BounceForm,
    /// Compute occlusion at half resolution per axis and upsample it.
    #[arg(long)]
    half_res: bool,
    /// Fixed foveated occlusion: off, low (full rate within 25° of each eye's view axis,
    /// half the samples from 40°) or high (full within 15°, half from 30°).
    #[arg(value_parser = choice::<Foveation>(), long, default_value_t = AoSettings::default().foveation, hide_possible_values = true)]
    foveation: Foveation,
    /// The headset's visibility mask: on (every pass skips the pixels the lens hides; they
    /// stay black) or off (the whole rectangle is computed). The mask comes from the
    /// OpenXR runtime or the simulated headset's profile.
    #[arg(long, value_enum, default_value_t = OnOff::from(AoSettings::default().mask))]
    mask: OnOff,
    /// Point-sampled SSDO quality mode (Ritschel et al. 2009 §4): peel a second depth layer per eye; a
    /// sample then occludes only inside an object (between the layers), which removes the
    /// halos of thin objects in front of a background. Assumes closed geometry.
    #[arg(long)]
    depth_peeling: bool,
    /// Depth layers the occlusion reads, 1 or 2. With 2 the renderer peels a second layer
    /// per eye (the next surface behind the first, --layer-separation behind it) and GTAO
    /// and SSDO count a sample as solid only between the two, not a slab --thickness deep
    /// (kept where nothing lies behind). Costs a depth-only pass per eye and 4 bytes a pixel.
    /// Default: the --quality preset's (1; 2 at ultra).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=2))]
    layers: Option<u32>,
    /// Spatial denoise: tile (edge-aware, 5 taps per axis over the 4×4 noise tile) or
    /// bilateral (separable, --blur px either side).
    #[arg(value_parser = choice::<Denoise>(), long, default_value_t = AoSettings::default().denoise, hide_possible_values = true)]
    denoise: Denoise,
    /// Bilateral blur radius in full-resolution pixels, 0..=16 (5 = 11×11); 0 turns any
    /// denoise off.
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().blur_radius)]
    blur: u32,
    /// Blur depth-edge width as a fraction of the pixel's distance (smaller keeps sharper edges).
    #[arg(long, allow_negative_numbers = true, default_value_t = AoSettings::default().blur_plane_sigma)]
    blur_sigma: f32,
    /// Kernel rotation per pixel: halton (per-pixel low-discrepancy) or tiled (5×5 tile).
    #[arg(value_parser = choice::<Noise>(), long, default_value_t = AoSettings::default().noise, hide_possible_values = true)]
    noise: Noise,
    #[command(flatten)]
    gtao: GtaoArgs,
    /// Turn SSAO's range check (depth constraint) off.
    #[arg(long)]
    no_range_check: bool,
    /// Accumulate occlusion over frames by reverse reprojection; the sampling pattern
    /// changes every frame (SSAO/SSDO: the next part of a longer Halton kernel; HBAO:
    /// turned by the golden angle, its range jittered).
    #[arg(long)]
    temporal: bool,
    /// Temporal disocclusion threshold in metres (plus two pixel footprints).
    #[arg(long, allow_negative_numbers = true, default_value_t = Temporal::default().epsilon_m)]
    temporal_epsilon: f32,
    /// Temporal blend: average (running mean) or confidence (the history weighed by how
    /// well it agrees with the new frame).
    #[arg(value_parser = choice::<TemporalBlend>(), long, default_value_t = Temporal::default().blend, hide_possible_values = true)]
    temporal_blend: TemporalBlend,
    /// Frames after which a pixel counts as converged, 1..=1024.
    #[arg(long, allow_negative_numbers = true, default_value_t = Temporal::default().max_frames)]
    temporal_frames: u32,
    /// Motion-adaptive temporal window: a pixel that moved m pixels since the last frame
    /// averages at most frames / (1 + m / this) frames (at least 4); 0 turns it off.
    #[arg(long, allow_negative_numbers = true, default_value_t = Temporal::default().motion_px)]
    temporal_motion_px: f32,
    /// In a scene that moves, reproject by the eyes alone, ignoring the motion vectors
    /// (moving objects then leave their old AO behind: for comparison).
    #[arg(long)]
    temporal_eyes_only: bool,
}

/// `--technique`'s help: the techniques of the engine's table ([`Technique::help_list`]).
fn technique_help() -> String {
    format!("Occlusion technique: {}", Technique::help_list())
}

/// `--radius`'s help, with the library's figures for the default.
fn radius_help() -> String {
    format!(
        "Occlusion radius in metres (default: {} % of the scene's diagonal, within {}..={} m)",
        AO_RADIUS_OF_DIAGONAL * 100.0,
        AO_RADIUS_MIN,
        AO_RADIUS_MAX
    )
}

impl AoArgs {
    /// Settings for a Vive-class headset at `width`×`height` per eye with these occlusion,
    /// shadow and RSM options (the commands that render frames share this).
    pub(crate) fn eye_settings(&self, scene: &Scene, width: u32, height: u32) -> Settings {
        Settings {
            profile: HeadsetProfile::with_size("vive", width, height),
            ao: self.settings(scene),
            point_ssdo: self.point_ssdo(),
            shadows: self.lights.settings(scene),
            ..Settings::default()
        }
    }

    /// The point-sampled SSDO's options (`--bounce-form`, `--depth-peeling`).
    pub(crate) fn point_ssdo(&self) -> PointSsdoSettings {
        PointSsdoSettings { bounce_form: self.bounce_form, depth_peeling: self.depth_peeling }
    }

    pub(crate) fn settings(&self, scene: &Scene) -> AoSettings {
        AoSettings {
            technique: self.technique,
            samples: self.samples.unwrap_or(self.quality.samples()),
            radius: self.radius.unwrap_or_else(|| scene.suggested_ao_radius()),
            strength: self.strength,
            bias: self.bias,
            range_check: !self.no_range_check,
            bounce: self.bounce,
            noise: self.noise,
            resolution: vrao_ao::Resolution::from_half_res(self.half_res),
            layers: self.layers.unwrap_or(self.quality.layers()),
            layer_separation: self.gtao.layer_separation,
            denoise: self.denoise,
            blur_radius: self.blur,
            blur_plane_sigma: self.blur_sigma,
            temporal: Temporal {
                enabled: self.temporal,
                epsilon_m: self.temporal_epsilon,
                blend: self.temporal_blend,
                max_frames: self.temporal_frames,
                motion_px: self.temporal_motion_px,
                object_motion: !self.temporal_eyes_only,
                ..Default::default()
            },
            gtao: self.gtao.settings(),
            stereo_reuse: !self.gtao.independent_eyes,
            foveation: self.foveation,
            mask: self.mask.on(),
        }
    }
}

/// The largest scene time the options take (seconds: about 11.6 days).
pub(crate) const MAX_SCENE_TIME_S: f64 = 1e6;

/// A scene time in seconds: finite, within 0..=[`MAX_SCENE_TIME_S`].
pub(crate) fn parse_scene_time(s: &str) -> Result<f64, String> {
    let t: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if !(0.0..=MAX_SCENE_TIME_S).contains(&t) {
        return Err(format!("{t} s is not within 0..={MAX_SCENE_TIME_S} s"));
    }
    Ok(t)
}

/// `X,Y,Z` in metres, each finite and within the scene's coordinate bound (a pose a
/// scene file would refuse is refused here too, not rendered as sky).
pub(crate) fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("'{s}' is not X,Y,Z"));
    }
    let mut v = [0.0; 3];
    for (slot, part) in v.iter_mut().zip(&parts) {
        *slot = part.parse::<f64>().map_err(|_| format!("'{part}' in '{s}' is not a number"))?;
        if !slot.is_finite() {
            return Err(format!("'{part}' in '{s}' is not finite"));
        }
        if let Some(trouble) = vrao_render::scene::limits::coordinate_trouble(&format!("'{part}' in '{s}'"), *slot) {
            return Err(trouble);
        }
    }
    Ok(DVec3::from_array(v))
}

/// A frame budget in milliseconds: finite and positive.
pub(crate) fn parse_budget_ms(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(ms) if ms.is_finite() && ms > 0.0 => Ok(ms),
        _ => Err(format!("'{s}' is not a positive number of milliseconds")),
    }
}

/// The `--scene` help every command shares.
pub(crate) const SCENE_HELP: &str = "A scene file (.toml), a bare .obj, a glTF (.gltf, .glb), or builtin:NAME (plane, crease, room, sphere, box, furnished, columns, flipped-normals, grille, moving)";
