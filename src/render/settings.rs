//! Render settings, validated once so passes can trust them.

use crate::render::error::{Error, Result};
pub use crate::render::passes::gtao::GtaoSettings;
use crate::render::passes::shadow::suggested_rsm_radius;
use crate::render::scene::{Scene, RENDER_DEFAULT};
use crate::render::stereo::{HeadsetProfile, DEFAULT_NEAR};
use std::sync::OnceLock;

/// A scene's default occlusion radius is this fraction of its bounding-box diagonal
/// ([`Scene::suggested_ao_radius`]), kept within [`AO_RADIUS_MIN`]..=[`AO_RADIUS_MAX`].
pub const AO_RADIUS_OF_DIAGONAL: f64 = 0.08;
/// The smallest default occlusion radius, metres (a scene of a few centimetres).
pub const AO_RADIUS_MIN: f32 = 0.01;
/// The largest default occlusion radius, metres: room-scale detail, even in a cathedral.
pub const AO_RADIUS_MAX: f32 = 1.0;
/// The most depth taps per pixel an occlusion technique takes (`--samples`).
pub const SAMPLES_MAX: u32 = 256;
/// The most virtual point lights the reflective shadow maps gather per pixel.
pub const RSM_SAMPLES_MAX: u32 = 1024;
/// Linear exposure applied before tone mapping, by default.
pub const DEFAULT_EXPOSURE: f32 = 1.0;
/// Reinhard's white point, by default.
pub const DEFAULT_WHITE_POINT: f32 = 4.0;

/// The occlusion and RSM radii that the default scene ([`RENDER_DEFAULT`], what `vrao
/// render` draws when no scene is named) suggests: [`Settings::default`] is that
/// command's setting with no options, so its radii are the default scene's. Built once.
fn default_scene_radii() -> (f32, f32) {
    static RADII: OnceLock<(f32, f32)> = OnceLock::new();
    *RADII.get_or_init(|| {
        let scene = Scene::load(RENDER_DEFAULT).expect("the default scene is built in");
        (scene.suggested_ao_radius(), suggested_rsm_radius(&scene))
    })
}

/// How the G-buffer reaches both eye layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum StereoMode {
    /// Multiview when the adapter has it, one pass per eye otherwise.
    #[default]
    Auto,
    /// One render pass writes both layers (`view_index` selects the eye).
    Multiview,
    /// One render pass per eye layer.
    Multipass,
}

/// What the desktop window shows (Belonogov 2018 §5.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
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

/// The occlusion technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum Technique {
    /// No occlusion pass: the ambient term is unoccluded.
    None,
    /// Normal-oriented hemisphere SSAO (Belonogov 2018 §3.2, the Czech SSDO thesis ch. 3).
    Ssao,
    /// Horizon-based AO, directions × steps ray-marched in depth (Belonogov 2018 §3.3).
    Hbao,
    /// Ground-truth AO over screen-space slices with a visibility bitmask and a thickness
    /// (Jimenez et al. 2016, Therrien et al. 2023). The default: the most accurate per
    /// millisecond.
    #[default]
    Gtao,
    /// Screen-space directional occlusion of the environment (Ritschel et al. 2009 eq. 1).
    Ssdo,
    /// SSDO plus one indirect bounce in the same loop (Ritschel et al. 2009 eq. 2).
    SsdoBounce,
    /// Benchmark baseline, not an occlusion: SSAO's depth taps with no arithmetic.
    FetchOnly,
}

impl Technique {
    /// The technique's command-line name (`ssao`, `hbao`, …), also used in file names and reports.
    pub fn name(self) -> &'static str {
        match self {
            Technique::None => "none",
            Technique::Ssao => "ssao",
            Technique::Hbao => "hbao",
            Technique::Ssdo => "ssdo",
            Technique::SsdoBounce => "ssdo-bounce",
            Technique::FetchOnly => "fetch-only",
            Technique::Gtao => "gtao",
        }
    }
    /// True for the techniques whose occlusion targets carry gathered light in rgb
    /// (SSDO's directional occlusion of the environment, with or without its bounce); the
    /// others write AO in alpha alone (rgb 0), so the denoise filters alpha alone for them.
    pub fn carries_light(self) -> bool {
        matches!(self, Technique::Ssdo | Technique::SsdoBounce)
    }

    /// Every technique, in the order the CLI and the bench list them (declaration order).
    pub const ALL: [Technique; 7] = [
        Technique::None,
        Technique::Ssao,
        Technique::Hbao,
        Technique::Gtao,
        Technique::Ssdo,
        Technique::SsdoBounce,
        Technique::FetchOnly,
    ];

    /// Every technique, in the order the CLI and the bench list them ([`Technique::ALL`]).
    pub fn all() -> &'static [Technique] {
        &Technique::ALL
    }

    /// The techniques that estimate occlusion (neither `none` nor the fetch-only
    /// baseline), the default first, then in [`Technique::all`]'s order: what `vrao bench`
    /// sweeps unless told otherwise.
    pub fn estimators() -> Vec<Technique> {
        let default = Technique::default();
        let others = Technique::all()
            .iter()
            .copied()
            .filter(|&t| ![default, Technique::None, Technique::FetchOnly].contains(&t));
        std::iter::once(default).chain(others).collect()
    }
}

/// Bench files name their techniques, and the governor and `vrao budget --fit` read them
/// back; the names are the command line's ([`Technique::name`]).
impl std::str::FromStr for Technique {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Technique::ALL.into_iter().find(|t| t.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Technique::all().iter().map(|t| t.name()).collect();
            Error::input(format!("unknown technique '{s}' (expected one of {})", names.join(", ")))
        })
    }
}

/// Sampling quality presets: Belonogov 2018's kernel sizes N = 12, 24, 36, 64.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum Quality {
    /// N = 12.
    Low,
    /// N = 24 (the default).
    #[default]
    Medium,
    /// N = 36.
    High,
    /// N = 64.
    Ultra,
}

impl Quality {
    /// Every preset, lowest first.
    pub const ALL: [Quality; 4] = [Quality::Low, Quality::Medium, Quality::High, Quality::Ultra];
    /// The preset's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Low => "low",
            Quality::Medium => "medium",
            Quality::High => "high",
            Quality::Ultra => "ultra",
        }
    }
    /// Depth taps per pixel (SSAO/SSDO samples; HBAO directions × steps).
    pub fn samples(self) -> u32 {
        match self {
            Quality::Low => 12,
            Quality::Medium => 24,
            Quality::High => 36,
            Quality::Ultra => 64,
        }
    }
}

/// Where each pixel's kernel rotation comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum Noise {
    /// A 5×5 tile of rotations repeated over the screen (Belonogov 2018).
    #[cfg_attr(feature = "app", value(name = "tiled", alias = "tiled5x5"))]
    Tiled5x5,
    /// A per-pixel rotation from a Halton sequence in bases 2 and 3 (the Czech SSDO thesis).
    #[default]
    Halton,
}

/// How SSDO's bounce weighs a blocking sample's sender.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
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

/// The spatial denoise of the occlusion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum Denoise {
    /// Edge-aware box over the 4×4 noise tile, 5 taps per axis in two passes
    /// (src/render/passes/blur/denoise.wgsl).
    #[default]
    Tile,
    /// Separable geometry-aware bilateral blur of `blur_radius` (11×11 at 5; the Czech SSDO
    /// thesis).
    Bilateral,
}

impl Denoise {
    /// Both denoisers, the default first.
    pub const ALL: [Denoise; 2] = [Denoise::Tile, Denoise::Bilateral];
    /// The denoiser's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Denoise::Tile => "tile",
            Denoise::Bilateral => "bilateral",
        }
    }
}

/// Fixed foveated occlusion: every eye's AO at its full sample count near the eye's
/// view axis and fewer samples towards the image's edges, where the flat projection
/// spends more pixels per degree than at the centre, the lens squeezes them together
/// and the eye, looking ahead through the lens, resolves less. The map is in degrees
/// off each eye's own view axis, so it follows every headset profile's and every
/// runtime's asymmetric field of view (its centre lies towards the nose, where the
/// axis meets the image).
/// Levels order by how much they save: `Off < Low < High`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum Foveation {
    /// Every pixel at the full sample count.
    #[default]
    Off,
    /// Full rate within 25° of the axis, down to half the samples at 40° and beyond.
    Low,
    /// Full rate within 15° of the axis, down to half the samples at 30° and beyond: the
    /// same floor as `low` over most of the image.
    High,
}

/// Where a [`Foveation`] level lowers the sample count: the full count within
/// `full_rate_deg` of an eye's view axis, then falling linearly in the tangent of the
/// angle to `edge_rate` of it at `edge_deg` and beyond. Pixels take whole counts: one
/// between two counts takes the higher one with the probability of its fraction (a 4×4
/// ordered dither the denoise averages), so the map has no seam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FoveationMap {
    /// Angle off the view axis within which every pixel spends its full count (degrees).
    pub full_rate_deg: f32,
    /// Angle from which on pixels spend `edge_rate` of it (degrees).
    pub edge_deg: f32,
    /// The share of the full count spent at and beyond `edge_deg`, in (0, 1].
    pub edge_rate: f32,
}

impl Foveation {
    /// Every level, off first.
    pub const ALL: [Foveation; 3] = [Foveation::Off, Foveation::Low, Foveation::High];

    /// The level's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Foveation::Off => "off",
            Foveation::Low => "low",
            Foveation::High => "high",
        }
    }

    /// The level's map (every level's numbers live here).
    pub fn map(self) -> FoveationMap {
        match self {
            Foveation::Off => FoveationMap { full_rate_deg: 90.0, edge_deg: 90.0, edge_rate: 1.0 },
            Foveation::Low => FoveationMap { full_rate_deg: 25.0, edge_deg: 40.0, edge_rate: 0.5 },
            // Half, not less: a marching technique's half is one of its two slices with
            // every step (unbiased: the slices turn with the noise tile); a third took
            // steps too, which lightened the edges (GTAO N = 24 half, furnished and
            // Sibenik at 540×600: FLIP 1.05–1.14× of off against 1.01–1.04× at a half)
            // and saved little more, the per-pixel set-up and denoise staying the same.
            Foveation::High => FoveationMap { full_rate_deg: 15.0, edge_deg: 30.0, edge_rate: 0.5 },
        }
    }
}

impl FoveationMap {
    /// The share of the full sample count a pixel `angle_deg` off its eye's view axis
    /// spends (what the occlusion shaders' `foveation_rate` computes).
    pub fn rate(&self, angle_deg: f32) -> f32 {
        if self.edge_rate >= 1.0 || angle_deg <= self.full_rate_deg {
            return 1.0;
        }
        let (inner, outer) = (self.full_rate_deg.to_radians().tan(), self.edge_deg.to_radians().tan());
        let tan = angle_deg.min(89.0).to_radians().tan();
        let t = ((tan - inner) / (outer - inner).max(1e-6)).clamp(0.0, 1.0);
        1.0 + (self.edge_rate - 1.0) * t
    }
}

/// Occlusion parameters shared by every technique.
#[derive(Clone, Debug, PartialEq)]
pub struct AoSettings {
    /// Which technique estimates the occlusion.
    pub technique: Technique,
    /// Depth taps per pixel, 1..=256 (a quality preset sets it).
    pub samples: u32,
    /// World-space radius r (SSAO/SSDO r_max, HBAO R), metres.
    pub radius: f32,
    /// Occlusion weight: 0 leaves the ambient untouched, 1 applies the full occlusion.
    pub strength: f32,
    /// Depth bias against self-occlusion, as a fraction of the radius.
    pub bias: f32,
    /// Range check: an occluder farther than the radius from the pixel counts less
    /// (SSAO's depth constraint) instead of darkening distant backgrounds.
    pub range_check: bool,
    /// SSDO bounce strength (scales each sender's weight); 0 turns the bounce off.
    pub bounce: f32,
    /// How the bounce weighs its senders.
    pub bounce_form: BounceForm,
    /// Where each pixel's kernel rotation comes from.
    pub noise: Noise,
    /// Compute occlusion at half resolution per axis and upsample (3×3 joint bilateral).
    pub half_res: bool,
    /// Depth peeling for SSDO (Ritschel et al. 2009 §4): a second depth layer, and a sample
    /// occludes only between the first and second layer (inside an object). Off by default.
    pub depth_peeling: bool,
    /// Which spatial denoise runs.
    pub denoise: Denoise,
    /// The bilateral blur's radius in full-resolution pixels (5 = 11×11; at half
    /// resolution 3 taps either side cover the same footprint); 0 turns any denoise off.
    pub blur_radius: u32,
    /// The blur's depth edge: a neighbour this far off the centre's tangent plane, as a
    /// fraction of the centre's distance, loses most of its weight. Near 0 every
    /// neighbour's weight vanishes and the centre value is kept.
    pub blur_plane_sigma: f32,
    /// Temporal accumulation by reverse reprojection (Lin's NCTU thesis §3.1).
    pub temporal: Temporal,
    /// GTAO's own parameters (passes/gtao).
    pub gtao: GtaoSettings,
    /// With two views, the right eye takes the left eye's value wherever the left eye
    /// sees the same surface point: GTAO's march (the right eye marches only the rest and
    /// costs a fraction) and, at half resolution, the AO-only techniques' upsample
    /// (`passes::upsample::reuses_left_eye_upsample`) or SSDO's denoise (its vertical pass).
    /// Off: each eye computes everything alone.
    pub stereo_reuse: bool,
    /// Fixed foveated occlusion: fewer samples towards each eye's image edges.
    pub foveation: Foveation,
}

/// How the temporal pass blends the new frame into the history.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum TemporalBlend {
    /// The running mean of the last `max_frames` frames: each frame's rotated pattern
    /// counts equally, so N frames of n samples approach one frame of N·n.
    #[default]
    Average,
    /// Lin's NCTU thesis eqs. 4–5: c = 1 − saturate(|V_{t−1} − V_t|)/(1 + bias),
    /// V = c·V_{t−1} + (1 − c)·V_t.
    Confidence,
}

/// Temporal accumulation settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Temporal {
    /// Accumulate occlusion over frames (off by default).
    pub enabled: bool,
    /// Disocclusion threshold ε in metres on the world-position distance (Lin's NCTU
    /// thesis eq. 3). The pass also allows two pixel footprints at the pixel's distance (an
    /// extension: a fixed ε would reject every distant pixel, whose neighbour is
    /// centimetres away).
    pub epsilon_m: f32,
    /// How a pixel's history and this frame's value are blended.
    pub blend: TemporalBlend,
    /// Frames after which a pixel counts as converged: the mean stops growing and
    /// becomes a moving average over this many frames.
    pub max_frames: u32,
    /// The confidence bias of Lin's NCTU thesis (only for the confidence blend).
    pub confidence_bias: f32,
    /// Motion-adaptive window of the running mean: a pixel that moved m occlusion
    /// pixels since the last frame keeps at most max_frames / (1 + m / motion_px)
    /// frames (at least 4). Screen-space occlusion changes with the view, so a long
    /// mean lags a turning head (ghosting); a still head keeps the whole window. 0 = off.
    pub motion_px: f32,
    /// In a scene that moves: reproject each pixel by its motion vector (its object's
    /// motion and the eye's) and keep only a short history, clamped to this frame's
    /// neighbourhood, within the AO radius of a moving object. Off: the eyes alone, as
    /// in a still scene (what `vrao temporal --motion` compares against).
    pub object_motion: bool,
}

impl Default for Temporal {
    fn default() -> Self {
        Temporal {
            enabled: false,
            epsilon_m: 0.02,
            blend: TemporalBlend::Average,
            max_frames: 16,
            confidence_bias: 0.1,
            motion_px: 0.5,
            object_motion: true,
        }
    }
}

/// What `vrao render` uses with no options: GTAO at the medium preset (N = 24) and full
/// resolution, the tile denoise, no temporal accumulation, and the default scene's radius
/// (8 % of the furnished room's diagonal; [`AoSettings::fitted_to`] fits another scene).
impl Default for AoSettings {
    fn default() -> Self {
        AoSettings {
            technique: Technique::default(),
            samples: Quality::default().samples(),
            radius: default_scene_radii().0,
            strength: 1.0,
            bias: 0.02,
            range_check: true,
            bounce: 1.0,
            bounce_form: BounceForm::Direction,
            noise: Noise::Halton,
            half_res: false,
            depth_peeling: false,
            denoise: Denoise::Tile,
            blur_radius: 5,
            blur_plane_sigma: 0.02,
            temporal: Temporal::default(),
            gtao: GtaoSettings::default(),
            stereo_reuse: true,
            foveation: Foveation::Off,
        }
    }
}

impl AoSettings {
    /// The defaults with `scene`'s own occlusion radius ([`Scene::suggested_ao_radius`]),
    /// as `vrao render` sets them up for a scene when no radius is given.
    pub fn fitted_to(scene: &Scene) -> AoSettings {
        AoSettings { radius: scene.suggested_ao_radius(), ..AoSettings::default() }
    }

    /// Checks every value's range; the error names the value and its range.
    pub fn validate(&self) -> Result<()> {
        if !(1..=SAMPLES_MAX).contains(&self.samples) {
            return Err(Error::input(format!("samples {} is not within 1..={SAMPLES_MAX}", self.samples)));
        }
        if !(self.radius.is_finite() && self.radius > 0.0 && self.radius <= 1e6) {
            return Err(Error::input(format!("radius {} m must be a finite number in (0, 1e6]", self.radius)));
        }
        if !(self.strength.is_finite() && (0.0..=4.0).contains(&self.strength)) {
            return Err(Error::input(format!("strength {} is not within 0..=4", self.strength)));
        }
        if !(self.bias.is_finite() && (0.0..1.0).contains(&self.bias)) {
            return Err(Error::input(format!("bias {} is not within 0..1 (a fraction of the radius)", self.bias)));
        }
        if !(self.bounce.is_finite() && (0.0..=100.0).contains(&self.bounce)) {
            return Err(Error::input(format!("bounce {} is not within 0..=100", self.bounce)));
        }
        let t = &self.temporal;
        if !(t.epsilon_m.is_finite() && t.epsilon_m >= 0.0) {
            return Err(Error::input(format!("temporal epsilon {} m must be finite and ≥ 0", t.epsilon_m)));
        }
        if !(1..=1024).contains(&t.max_frames) {
            return Err(Error::input(format!("temporal frame cap {} is not within 1..=1024", t.max_frames)));
        }
        if !(t.motion_px.is_finite() && t.motion_px >= 0.0) {
            return Err(Error::input(format!("temporal motion scale {} px must be finite and ≥ 0", t.motion_px)));
        }
        if !(t.confidence_bias.is_finite() && t.confidence_bias >= 0.0) {
            return Err(Error::input(format!("temporal confidence bias {} must be finite and ≥ 0", t.confidence_bias)));
        }
        if !(self.blur_plane_sigma.is_finite() && (0.0..=10.0).contains(&self.blur_plane_sigma)) {
            return Err(Error::input(format!("blur plane sigma {} is not within 0..=10", self.blur_plane_sigma)));
        }
        self.gtao.validate()?;
        if self.blur_radius > 16 {
            return Err(Error::input(format!("blur radius {} px is not within 0..=16", self.blur_radius)));
        }
        Ok(())
    }

    /// The graph pass that runs the technique: SSDO is `ssdo-bounce` only while the
    /// bounce strength is above 0.
    pub fn pass_name(&self) -> &'static str {
        match self.technique {
            Technique::SsdoBounce if !self.bounce_active() => Technique::Ssdo.name(),
            technique => technique.name(),
        }
    }

    /// True when the SSDO pass also gathers the bounce.
    pub fn bounce_active(&self) -> bool {
        self.technique == Technique::SsdoBounce && self.bounce > 0.0
    }
}

/// Everything a frame is rendered with: the headset, the stereo path, tone mapping,
/// occlusion and shadows. Start from [`Settings::default`] and change what you need;
/// [`Settings::validate`] (also run by
/// [`Renderer::new`](crate::render::renderer::Renderer::new)) rejects values out of range
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
    /// Shadow maps and reflective shadow maps of directional lights.
    pub shadows: ShadowSettings,
}

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
/// ([`suggested_rsm_radius`]), as `vrao render` sets it with no options.
impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings { enabled: true, size: 2048, rsm: false, rsm_samples: 64, rsm_radius: default_scene_radii().1 }
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
            ao: AoSettings::default(),
            shadows: ShadowSettings::default(),
        }
    }
}

impl Settings {
    /// Checks every value; the error names the setting and the value.
    pub fn validate(&self) -> Result<()> {
        let p = &self.profile;
        if p.width == 0 || p.height == 0 || p.width > 8192 || p.height > 8192 {
            return Err(Error::input(format!("eye size {}x{} is not within 1..=8192", p.width, p.height)));
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
