//! Render settings, validated once so passes can trust them: the engine's AO settings
//! ([`vrao_ao::AoSettings`]) and the renderer's own around them.

use crate::headset::HeadsetProfile;
use crate::scene::Scene;
use vrao_ao::plug::DEFAULT_NEAR;
use vrao_ao::{AoSettings, Error, Result};

/// A scene's default occlusion radius is this fraction of its bounding-box diagonal
/// ([`Scene::suggested_ao_radius`]), kept within [`AO_RADIUS_MIN`]..=[`AO_RADIUS_MAX`].
pub const AO_RADIUS_OF_DIAGONAL: f64 = 0.08;
/// The smallest default occlusion radius, metres: 8 % of a 6 mm diagonal, so a model of
/// a few millimetres (framed whole: `Aabb::framing_pose`) gets a radius smaller than itself.
pub const AO_RADIUS_MIN: f32 = 0.0005;
/// The largest default occlusion radius, metres: room-scale detail, even in a cathedral.
pub const AO_RADIUS_MAX: f32 = 1.0;
/// The most virtual point lights the reflective shadow maps gather per pixel.
pub const RSM_SAMPLES_MAX: u32 = 1024;
/// Linear exposure applied before tone mapping, by default.
pub const DEFAULT_EXPOSURE: f32 = 1.0;
/// Reinhard's white point, by default.
pub const DEFAULT_WHITE_POINT: f32 = 4.0;

/// The occlusion radius the default scene ([`crate::scene::RENDER_DEFAULT`], what `vrao render` draws
/// when no scene is named) suggests ([`Scene::suggested_ao_radius`]): [`Settings::default`]
/// is that command's setting with no options. A constant, so that no default builds a
/// scene; a test keeps it equal to the scene's suggestion.
pub const DEFAULT_SCENE_AO_RADIUS: f32 = 0.675_763_25;
/// The RSM gather radius the default scene suggests (the shadow pass's `suggested_rsm_radius`).
pub const DEFAULT_SCENE_RSM_RADIUS: f32 = 2.111_760_1;

/// How the G-buffer reaches both eye layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StereoMode {
    /// Multiview when the adapter has it, one pass per eye otherwise.
    #[default]
    Auto,
    /// One render pass writes both layers (`view_index` selects the eye).
    Multiview,
    /// One render pass per eye layer.
    Multipass,
}

impl StereoMode {
    /// Every mode, the default first.
    pub const ALL: [StereoMode; 3] = [StereoMode::Auto, StereoMode::Multiview, StereoMode::Multipass];
    /// The mode's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            StereoMode::Auto => "auto",
            StereoMode::Multiview => "multiview",
            StereoMode::Multipass => "multipass",
        }
    }
}

vrao_ao::impl_choice!(StereoMode, DisplayMode);

/// What the desktop window shows (Belonogov 2018 §5.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DisplayMode {
    /// No window: the headset alone.
    #[default]
    None,
    /// Both eye images side by side, as the headset shows them.
    Mirror,
    /// The scene rendered once more in mono from the head's viewpoint at the window's size.
    SinglePass,
}

impl DisplayMode {
    /// Every mode, in the order the CLI lists them.
    pub const ALL: [DisplayMode; 3] = [DisplayMode::None, DisplayMode::Mirror, DisplayMode::SinglePass];
    /// The mode's command-line name (`none`, `mirror`, `single-pass`).
    pub fn name(self) -> &'static str {
        match self {
            DisplayMode::None => "none",
            DisplayMode::Mirror => "mirror",
            DisplayMode::SinglePass => "single-pass",
        }
    }
}

/// Everything a frame is rendered with: the headset, the stereo path, tone mapping,
/// occlusion and shadows. Start from [`Settings::default`] and change what you need;
/// [`Settings::validate`] (also run by
/// `Renderer::new`) rejects values out of range
/// with a one-line error.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The headset's per-eye size, refresh rate, IPD and fields of view.
    pub profile: HeadsetProfile,
    /// How the G-buffer reaches both eye layers.
    pub stereo: StereoMode,
    /// Near plane in metres (the far plane is at infinity).
    pub near: f64,
    /// Linear exposure applied before tone mapping.
    pub exposure: f32,
    /// Reinhard's L_white: the smallest (exposed) luminance mapped to white.
    pub white_point: f32,
    /// Ambient occlusion: technique, samples, radius, denoise, resolution, temporal.
    pub ao: AoSettings,
    /// The point-sampled SSDO's own options (`ssdo-points*`, the renderer's pass).
    pub point_ssdo: PointSsdoSettings,
    /// Shadow maps and reflective shadow maps of directional lights.
    pub shadows: ShadowSettings,
}

/// The engine's default AO settings with `scene`'s own occlusion radius
/// ([`Scene::suggested_ao_radius`]), as `vrao render` sets them up for a scene when no
/// radius is given.
pub fn ao_fitted_to(scene: &Scene) -> AoSettings {
    AoSettings { radius: scene.suggested_ao_radius(), ..AoSettings::default() }
}

/// The options of the seeds' point-sampled SSDO (`ssdo-points`, `ssdo-points-bounce`:
/// passes/ssdo), which only this renderer runs; the engine's techniques ignore them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PointSsdoSettings {
    /// How the bounce weighs its senders.
    pub bounce_form: BounceForm,
    /// Depth peeling (Ritschel et al. 2009 §4): a second depth layer, and a sample occludes
    /// only between the first and second layer (inside an object). Off by default.
    pub depth_peeling: bool,
}

/// How the point-sampled SSDO's bounce weighs a blocking sample's sender.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BounceForm {
    /// Ritschel et al. 2009 eq. 2: a patch of area π r²/N × strength at the sender pixel,
    /// weighted by the sender and receiver cosines over d² (as a disc's solid angle, so a
    /// sender touching the receiver stays bounded).
    Patch,
    /// The sender's radiance through the blocked direction's share of the hemisphere,
    /// 2π/N, × the receiver's cosine towards the sender, as eq. 1 treats unblocked
    /// directions: for diffuse senders the radiance arriving along a direction does not
    /// depend on the sender's orientation or distance. Against the reference's bounce it
    /// roughly halves eq. 2's low bias and error (red wall, crease, Cornell box), and it
    /// needs no sender normal.
    #[default]
    Direction,
}

impl BounceForm {
    /// Both forms, the default first.
    pub const ALL: [BounceForm; 2] = [BounceForm::Direction, BounceForm::Patch];
    /// The form's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            BounceForm::Patch => "patch",
            BounceForm::Direction => "direction",
        }
    }
}

vrao_ao::impl_choice!(BounceForm);

/// Shadow maps with PCF (the Czech SSDO thesis) and reflective shadow maps (Lin's NCTU thesis)
/// for the scene's directional lights (passes/shadow.rs, passes/rsm.rs). A scene without a
/// directional light has neither, whatever these say.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Shadow the directional lights' direct light (`--shadows on|off`).
    pub enabled: bool,
    /// Texels along each side of the square light-space maps (`--shadow-size`).
    pub size: u32,
    /// Add one bounce of the directional lights from reflective shadow maps (`--rsm on|off`).
    pub rsm: bool,
    /// Virtual point lights gathered per pixel and light (`--rsm-samples`).
    pub rsm_samples: u32,
    /// Gather radius around each pixel in the light's image plane, metres (`--rsm-radius`).
    pub rsm_radius: f32,
}

/// Shadows on (2048² maps), no RSM; the RSM radius is the default scene's
/// (the shadow pass's `suggested_rsm_radius`), as `vrao render` sets it with no options.
impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings { enabled: true, size: 2048, rsm: false, rsm_samples: 64, rsm_radius: DEFAULT_SCENE_RSM_RADIUS }
    }
}

impl ShadowSettings {
    /// Checks the map size, the RSM samples and the RSM radius.
    pub fn validate(&self) -> Result<()> {
        if !(16..=8192).contains(&self.size) {
            return Err(Error::input(format!("shadow map size {} is not within 16..=8192", self.size)));
        }
        if !(1..=RSM_SAMPLES_MAX).contains(&self.rsm_samples) {
            return Err(Error::input(format!("RSM samples {} is not within 1..={RSM_SAMPLES_MAX}", self.rsm_samples)));
        }
        if !(self.rsm_radius.is_finite() && self.rsm_radius > 0.0 && self.rsm_radius <= 1e6) {
            return Err(Error::input(format!("RSM radius {} m must be a finite number in (0, 1e6]", self.rsm_radius)));
        }
        Ok(())
    }
}

/// Exactly what `vrao render` uses with no options (the one place its defaults come
/// from): a Vive-class headset (1080×1200 per eye, IPD 64 mm), the G-buffer path the
/// adapter supports best, exposure 1 and white point 4, [`AoSettings::default`] and
/// [`ShadowSettings::default`].
impl Default for Settings {
    fn default() -> Self {
        Settings {
            profile: HeadsetProfile::vive(),
            stereo: StereoMode::Auto,
            near: DEFAULT_NEAR,
            exposure: DEFAULT_EXPOSURE,
            white_point: DEFAULT_WHITE_POINT,
            ao: AoSettings { radius: DEFAULT_SCENE_AO_RADIUS, ..AoSettings::default() },
            point_ssdo: PointSsdoSettings::default(),
            shadows: ShadowSettings::default(),
        }
    }
}

/// The widest and tallest eye image, in pixels, the renderer takes.
pub const EYE_SIDE_MAX: u32 = 8192;

impl Settings {
    /// Checks every value; the error names the setting and the value.
    pub fn validate(&self) -> Result<()> {
        let p = &self.profile;
        if !(1..=EYE_SIDE_MAX).contains(&p.width) || !(1..=EYE_SIDE_MAX).contains(&p.height) {
            return Err(Error::input(format!("eye size {}x{} is not within 1..={EYE_SIDE_MAX}", p.width, p.height)));
        }
        if !(p.ipd.is_finite() && (0.0..=1.0).contains(&p.ipd)) {
            return Err(Error::input(format!("ipd {} m is not within 0..=1 m", p.ipd)));
        }
        for fov in [p.fov_left, p.fov_right] {
            fov.validate().map_err(Error::input)?;
        }
        if !(self.near.is_finite() && self.near > 0.0) {
            return Err(Error::input(format!("near plane {} m must be a positive finite number", self.near)));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(Error::input(format!("exposure {} must be a positive finite number", self.exposure)));
        }
        if !(self.white_point.is_finite() && self.white_point > 0.0) {
            return Err(Error::input(format!("white point {} must be a positive finite number", self.white_point)));
        }
        self.ao.validate()?;
        self.shadows.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::shadow::suggested_rsm_radius;
    use crate::scene::RENDER_DEFAULT;
    use vrao_ao::Foveation;

    #[test]
    fn the_default_radii_are_the_default_scene_s_suggestions() {
        let scene = Scene::load(RENDER_DEFAULT).unwrap();
        assert_eq!(
            (DEFAULT_SCENE_AO_RADIUS, DEFAULT_SCENE_RSM_RADIUS),
            (scene.suggested_ao_radius(), suggested_rsm_radius(&scene))
        );
    }

    #[test]
    fn foveation_maps_keep_full_rate_near_the_axis_and_fall_monotonically_to_their_edge_rate() {
        for level in Foveation::ALL {
            let map = level.map();
            assert_eq!(map.rate(0.0), 1.0);
            assert_eq!(map.rate(map.full_rate_deg), 1.0);
            assert!((map.rate(map.edge_deg + 10.0) - map.edge_rate).abs() < 1e-6, "{}", level.name());
            let rates: Vec<f32> = (0..=90).map(|deg| map.rate(deg as f32)).collect();
            assert!(rates.windows(2).all(|w| w[1] <= w[0]), "{}: not monotone", level.name());
            assert!(rates.iter().all(|r| (map.edge_rate..=1.0).contains(r)));
        }
        assert!(Foveation::Off.map().rate(80.0) == 1.0);
        // Each level spends no more than the one before at any angle, and less somewhere.
        let (low, high) = (Foveation::Low.map(), Foveation::High.map());
        assert!((0..=90).all(|deg| high.rate(deg as f32) <= low.rate(deg as f32)));
        assert!(high.rate(30.0) < low.rate(30.0));
    }
}
