//! The AO settings a host chooses: the technique, its sample count and radius, the
//! denoise, the resolution, temporal accumulation and foveation. Validated once so the
//! passes can trust them; every default lives here.

use crate::error::{Error, Result};
pub use crate::technique::Technique;

/// The occlusion radius of [`AoSettings::default`], in the host's world units.
pub(crate) const DEFAULT_RADIUS: f32 = 0.5;
/// The most depth taps per pixel an occlusion technique takes (`--samples`).
pub(crate) const SAMPLES_MAX: u32 = 256;

/// A setting chosen by name from a fixed list: what a command line, a file or a panel
/// offers (the engine has no command line; its host's wraps these).
pub trait Choice: Copy + PartialEq + std::fmt::Debug + 'static {
    /// Every value, in the order lists show them.
    fn all() -> &'static [Self];
    /// The value's name (lower case, words joined by `-`).
    fn name(self) -> &'static str;
    /// Other spellings a parser accepts for it.
    fn aliases(self) -> &'static [&'static str] {
        &[]
    }
    /// The value named `name` (or one of its aliases).
    fn from_name(name: &str) -> Option<Self> {
        Self::all().iter().copied().find(|v| v.name() == name || v.aliases().contains(&name))
    }
}

/// Implements [`Choice`] (and `Display`, as the name) for enums with an inherent `ALL`
/// and `name`.
#[macro_export]
#[doc(hidden)]
macro_rules! impl_choice {
    ($($t:ty),* $(,)?) => {$(
        impl $crate::Choice for $t {
            fn all() -> &'static [Self] {
                &<$t>::ALL
            }
            fn name(self) -> &'static str {
                <$t>::name(self)
            }
        }
        impl ::std::fmt::Display for $t {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(<$t>::name(*self))
            }
        }
    )*};
}

crate::impl_choice!(Technique, Quality, Denoise, Foveation, TemporalBlend, Resolution);

/// The resolution the occlusion runs at.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Resolution {
    /// The view's own size.
    #[default]
    Full,
    /// Half the size per axis (rounded up), then upsampled joint-bilaterally to full
    /// resolution: about a quarter of the technique's cost.
    Half,
}

impl Resolution {
    /// Both, full first.
    pub const ALL: [Resolution; 2] = [Resolution::Full, Resolution::Half];

    /// `Half` when `half` is true.
    pub fn from_half_res(half: bool) -> Resolution {
        if half {
            Resolution::Half
        } else {
            Resolution::Full
        }
    }

    /// Whether this is half resolution.
    pub fn is_half(self) -> bool {
        self == Resolution::Half
    }

    /// `full` or `half`: the name the command line, reports, tables and bench files use.
    pub fn name(self) -> &'static str {
        match self {
            Resolution::Full => "full",
            Resolution::Half => "half",
        }
    }
}

impl std::fmt::Display for Noise {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Choice for Noise {
    fn all() -> &'static [Self] {
        &Noise::ALL
    }
    fn name(self) -> &'static str {
        Noise::name(self)
    }
    fn aliases(self) -> &'static [&'static str] {
        match self {
            Noise::Tiled5x5 => &["tiled5x5"],
            Noise::Halton => &[],
        }
    }
}

/// Sampling quality presets: Belonogov 2018's kernel sizes N = 12, 24, 36, 64.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Quality {
    /// N = 12.
    Low,
    /// N = 24 (the default).
    #[default]
    Medium,
    /// N = 36.
    High,
    /// N = 64, and two depth layers.
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

    /// Depth layers the preset reads ([`AoSettings::layers`]): two at ultra, whose 64
    /// taps resolve what the second layer frees (GTAO's error on the furnished room
    /// 17–40 % lower, every other scene and pose measured within +3 %), one below, where
    /// two layers gained less than a depth pass per eye costs
    /// (docs/records/2026-11-29/two-layers.md, the presets).
    pub fn layers(self) -> u32 {
        match self {
            Quality::Low | Quality::Medium | Quality::High => 1,
            Quality::Ultra => 2,
        }
    }

    /// `ao` with the preset's taps and depth layers.
    pub fn apply(self, ao: &mut AoSettings) {
        ao.samples = self.samples();
        ao.layers = self.layers();
    }

    /// The preset whose taps and depth layers `ao` has, if any.
    pub fn of(ao: &AoSettings) -> Option<Quality> {
        Quality::ALL.into_iter().find(|q| q.samples() == ao.samples && q.layers() == ao.layers)
    }
}

/// Where each pixel's kernel rotation comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Noise {
    /// A 5×5 tile of rotations repeated over the screen (Belonogov 2018).
    Tiled5x5,
    /// A per-pixel rotation from a Halton sequence in bases 2 and 3 (the Czech SSDO thesis).
    #[default]
    Halton,
}

impl Noise {
    /// Both sources, the default last.
    pub const ALL: [Noise; 2] = [Noise::Tiled5x5, Noise::Halton];
    /// The source's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Noise::Tiled5x5 => "tiled",
            Noise::Halton => "halton",
        }
    }
}

/// The spatial denoise of the occlusion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
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
            // steps too, which lightened the edges and saved little more, the per-pixel
            // set-up and denoise staying the same (docs/records/2026-11-29/measurements-in-code.md,
            // foveation-high).
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
    /// Where each pixel's kernel rotation comes from.
    pub noise: Noise,
    /// The resolution the occlusion runs at (half: per axis, then upsampled).
    pub resolution: Resolution,
    /// Depth layers the occlusion reads, 1 or 2. With 2, where a second layer is given
    /// (the next surface behind the first, at least `layer_separation` behind it: the
    /// renderer's depth peel, or a host's), GTAO's (and SSDO's) samples occlude only
    /// between the two surfaces instead of a slab `gtao.thickness` deep; the thickness
    /// stays where the second layer has no surface. 1 (the default) reads one layer;
    /// the ultra preset reads two ([`Quality::layers`]).
    pub layers: u32,
    /// The second layer's minimum separation behind the first, as a fraction of the
    /// radius (0..=1; the renderer's peel also keeps 0.1 % of the distance against
    /// rounding).
    pub layer_separation: f32,
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
    /// sees the same surface point: every technique's march or samples (the right eye
    /// estimates only the rest and costs a fraction) and, at half resolution, the AO-only techniques' upsample
    /// (`passes::upsample::reuses_left_eye_upsample`) or SSDO's denoise (its vertical pass).
    /// Off: each eye computes everything alone.
    pub stereo_reuse: bool,
    /// Fixed foveated occlusion: fewer samples towards each eye's image edges.
    pub foveation: Foveation,
    /// Skip the pixels the headset's lens hides (its visibility mask, where the runtime,
    /// the profile or the host gives one): every pass leaves them out and they stay
    /// black. Off: every pixel of the rectangle is computed.
    pub mask: bool,
}

/// How the temporal pass blends the new frame into the history.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TemporalBlend {
    /// The running mean of the last `max_frames` frames: each frame's rotated pattern
    /// counts equally, so N frames of n samples approach one frame of N·n.
    #[default]
    Average,
    /// Lin's NCTU thesis eqs. 4–5: c = 1 − saturate(|V_{t−1} − V_t|)/(1 + bias),
    /// V = c·V_{t−1} + (1 − c)·V_t.
    Confidence,
}

impl TemporalBlend {
    /// Both blends, the default first.
    pub const ALL: [TemporalBlend; 2] = [TemporalBlend::Average, TemporalBlend::Confidence];
    /// The blend's command-line name.
    pub fn name(self) -> &'static str {
        match self {
            TemporalBlend::Average => "average",
            TemporalBlend::Confidence => "confidence",
        }
    }
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

/// GTAO at the medium preset (N = 24) and full resolution, the tile denoise, no temporal
/// accumulation and a radius of `DEFAULT_RADIUS` in the host's units (half a metre when
/// they are metres). Constant: no scene is consulted. A host sets the radius to the
/// scale of the detail it wants shaded; vrao's renderer fits it to each scene.
impl Default for AoSettings {
    fn default() -> Self {
        AoSettings {
            technique: Technique::default(),
            samples: Quality::default().samples(),
            radius: DEFAULT_RADIUS,
            strength: 1.0,
            bias: 0.02,
            range_check: true,
            bounce: 1.0,
            noise: Noise::Halton,
            resolution: Resolution::Full,
            layers: Quality::default().layers(),
            layer_separation: DEFAULT_LAYER_SEPARATION,
            denoise: Denoise::Tile,
            blur_radius: 5,
            blur_plane_sigma: 0.02,
            temporal: Temporal::default(),
            gtao: GtaoSettings::default(),
            stereo_reuse: true,
            foveation: Foveation::Off,
            mask: true,
        }
    }
}

impl AoSettings {
    /// The most samples a technique takes (`SAMPLES_MAX`).
    pub const SAMPLES_MAX: u32 = SAMPLES_MAX;

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
        if !(1..=2).contains(&self.layers) {
            return Err(Error::input(format!("layers {} is not 1 or 2", self.layers)));
        }
        if !(self.layer_separation.is_finite() && (0.0..=1.0).contains(&self.layer_separation)) {
            return Err(Error::input(format!(
                "layer separation {} is not within 0..=1 (a fraction of the radius)",
                self.layer_separation
            )));
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
            technique if technique.gathers_bounce() && !self.bounce_active() => technique.without_bounce().name(),
            technique => technique.name(),
        }
    }

    /// True when the SSDO pass also gathers the bounce.
    pub fn bounce_active(&self) -> bool {
        self.technique.gathers_bounce() && self.bounce > 0.0
    }
}

/// The second depth layer's default minimum separation behind the first, a fraction of
/// the radius (`AoSettings::layer_separation`).
const DEFAULT_LAYER_SEPARATION: f32 = 0.0;

/// GTAO's default slab behind each depth sample, a fraction of the radius.
const DEFAULT_THICKNESS: f32 = 0.5;
/// GTAO's default share of its stratum a solid depth sample blocks on its own plane.
const DEFAULT_FOOTPRINT: f32 = 0.5;
/// GTAO's default spread of the samples along a half-slice (1 even, 2 quadratic).
const DEFAULT_STEP_POWER: f32 = 1.5;
/// GTAO's default: successive samples closer than this fraction of the radius are joined.
const DEFAULT_CONNECT: f32 = 0.25;
/// The same where the march reads a second depth layer (`GtaoSettings::connect_two_layers`).
const DEFAULT_CONNECT_TWO_LAYERS: f32 = 0.35;

/// GTAO's own settings (`AoSettings::gtao`), and their command-line flags. The defaults
/// are tuned against the reference (scripts/tune-gtao.py and docs/records/2026-11-29/gtao-tuning.md).
#[derive(Clone, Debug, PartialEq)]
pub struct GtaoSettings {
    /// GTAO: the slab behind each depth sample that counts as solid, as a fraction of the
    /// radius (thin objects stop occluding behind themselves).
    // 0.5 × r with the footprint below (0.75 without it, where 0.5 cost RMSE): the
    // least mean RMSE over the furnished room, Sibenik and the Cornell box, and fewer
    // halos on the furnished room (docs/records/2026-11-29/measurements-in-code.md,
    // gtao-thickness).
    pub thickness: f32,
    /// GTAO: the share of its stratum (the stretch of the half-slice its jittered
    /// position stands for) that a solid depth sample blocks, on its own surface's plane
    /// about it, 0..=1 (0: the sample's point alone). Few samples step over thin occluders
    /// and read light; a sample that stands for its stratum blocks, in expectation, what
    /// the stratum holds (docs/records/2026-11-29/measurements-in-code.md, gtao-footprint).
    pub footprint: f32,
    /// GTAO: the samples' spread along a half-slice, 1..=2: sample t ∈ (0, 1) lies at
    /// r · t ((2 − P) + (P − 1) t), even at 1, quadratic (crowded near the pixel) at 2.
    pub step_power: f32,
    /// GTAO: successive samples whose distances differ by less than this fraction of the
    /// radius lie on one continuous surface, which also blocks the angles between them
    /// (0: never).
    pub connect: f32,
    /// GTAO with two depth layers: `connect` where the march reads the second layer. Its
    /// spans are the objects' own depths, far thinner than the slab, so the gaps between
    /// successive samples of one surface are worth joining more generously: 0.35, the
    /// least mean RMSE over the furnished room, Sibenik and the Cornell box with the one
    /// slice of twice the steps two layers march under 32 taps (0.5 was best with 2 × 6;
    /// docs/records/2026-11-29/two-layers.md).
    pub connect_two_layers: f32,
    /// GTAO with the stereo reuse: list the right eye's pixels the left eye cannot give
    /// from the depth before the left eye marches, and march them in the left eye's
    /// dispatch after its tiles (passes/gtao, `FOLDED`), instead of copying first and
    /// marching them in a dispatch of their own. A GPU too wide for one eye then runs
    /// the right eye's few marches beside the left eye's, not as a second dispatch as
    /// long as its longest march; the images are the same (a few pixels at the
    /// same-surface test's edge). Off until a GPU has measured it: on lavapipe, which runs
    /// dispatches one after another, its second full-size pass only costs
    /// (docs/records/2026-11-29/right-eye-lists.md, the fold).
    pub fold_right_eye: bool,
}

impl Default for GtaoSettings {
    fn default() -> Self {
        GtaoSettings {
            thickness: DEFAULT_THICKNESS,
            footprint: DEFAULT_FOOTPRINT,
            step_power: DEFAULT_STEP_POWER,
            connect: DEFAULT_CONNECT,
            connect_two_layers: DEFAULT_CONNECT_TWO_LAYERS,
            fold_right_eye: false,
        }
    }
}

impl GtaoSettings {
    /// Refuses values outside their ranges, naming the value.
    pub fn validate(&self) -> Result<()> {
        if !(self.thickness.is_finite() && (0.0..=100.0).contains(&self.thickness)) {
            return Err(Error::input(format!(
                "thickness {} is not within 0..=100 (a fraction of the radius)",
                self.thickness
            )));
        }
        if !(self.footprint.is_finite() && (0.0..=1.0).contains(&self.footprint)) {
            return Err(Error::input(format!(
                "footprint {} is not within 0..=1 (a share of the sample's stratum)",
                self.footprint
            )));
        }
        if !(self.step_power.is_finite() && (1.0..=2.0).contains(&self.step_power)) {
            return Err(Error::input(format!("step power {} is not within 1..=2", self.step_power)));
        }
        for (name, connect) in [("connect", self.connect), ("two-layer connect", self.connect_two_layers)] {
            if !(connect.is_finite() && (0.0..=100.0).contains(&connect)) {
                return Err(Error::input(format!("{name} {connect} is not within 0..=100 (a fraction of the radius)")));
            }
        }
        Ok(())
    }
}
