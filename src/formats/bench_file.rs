//! The bench's file format (`vrao bench --out`, JSON): plain data that `measure` writes
//! and the governor in `app` reads its frontier from, so it lives below both.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use vrao_ao::{AoSettings, Foveation, Technique};
use vrao_render::settings::RSM_SAMPLES_MAX;

/// The occlusion's resolution: bench files name it `full` or `half`
/// ([`Resolution::name`]), as they always have.
pub use vrao_ao::Resolution;

/// One row as written to CSV, JSON and Markdown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchRecord {
    /// Technique name as on the command line (`ssao`, `hbao`, `gtao`, `ssdo`, …).
    pub technique: String,
    /// Samples per pixel (N) the case asked for.
    pub samples: u32,
    /// Occlusion radius in metres.
    pub radius_m: f32,
    /// The resolution the occlusion ran at (`full` or `half` in the file).
    #[serde(with = "crate::formats::by_name")]
    pub resolution: Resolution,
    /// Fixed foveation (`off`, `low` or `high`; `off` in files written before it existed).
    #[serde(default, with = "crate::formats::by_name")]
    pub foveation: Foveation,
    /// Whether the passes skipped the pixels the lens hides (`false` in files written
    /// before the mask existed, which computed and scored the whole rectangle).
    #[serde(default)]
    pub mask: bool,
    /// RMSE over the whole rectangle, hidden pixels included, as files before the mask
    /// scored every row (`ao_rmse` counts the pixels the lens shows); rows with the
    /// mask off only.
    #[serde(default)]
    pub ao_rmse_whole: Option<f64>,
    /// Median GPU ms per eye of the technique's own pass.
    pub technique_ms_per_eye: f64,
    /// Median GPU ms per eye of the bilateral blur (0 when off).
    pub blur_ms_per_eye: f64,
    /// Median GPU ms per eye of the half-to-full upsample (0 at full resolution).
    pub upsample_ms_per_eye: f64,
    /// Technique + blur + upsample per eye: the occlusion's cost.
    pub occlusion_ms_per_eye: f64,
    /// p75 / p25 of the technique pass: the run-to-run spread.
    pub p75_over_p25: f64,
    /// RMSE against the reference's hard cut-off AO (`measure::bench::ErrorFigures::ao_rmse`).
    pub ao_rmse: Option<f64>,
    /// The same within 10° of each eye's view axis (`measure::bench::ErrorFigures::ao_rmse_central`).
    #[serde(default)]
    pub ao_rmse_central: Option<f64>,
    /// Mean estimate − reference over hit pixels, both eyes.
    #[serde(default)]
    pub ao_bias: Option<f64>,
    /// The bias over pixels whose reference AO is below 0.8.
    #[serde(default)]
    pub ao_bias_dark: Option<f64>,
    /// RMSE against the reference's linear-falloff AO.
    #[serde(default)]
    pub ao_rmse_falloff: Option<f64>,
    /// RMSE against the screen-space limit (estimator error).
    #[serde(default)]
    pub ao_rmse_vs_limit: Option<f64>,
    /// The screen-space limit's RMSE and bias against the reference (screen-space error;
    /// the same for every row of a radius).
    #[serde(default)]
    pub limit_rmse: Option<f64>,
    /// Mean (limit − reference) AO: > 0 the screen-space limit is too light.
    #[serde(default)]
    pub limit_bias: Option<f64>,
    /// The two-layer screen-space limit's RMSE against the reference (the march with the
    /// renderer's second depth layer; the same for every row of a radius).
    #[serde(default)]
    pub limit_two_layer_rmse: Option<f64>,
    /// The two-layer limit's mean bias against the reference.
    #[serde(default)]
    pub limit_two_layer_bias: Option<f64>,
    /// RMSE within 40 px of the outer, top and bottom borders (`measure::bench::ErrorFigures::ao_rmse_outer_border`).
    #[serde(default)]
    pub ao_rmse_outer_border: Option<f64>,
    /// Share of the pixels beside depth edges too dark by more than 0.1 (`measure::bench::ErrorFigures::halo_share`).
    #[serde(default)]
    pub halo_share: Option<f64>,
    /// Mean ꟻLIP of the AO against the reference AO at the headset's pixels per degree.
    #[serde(default)]
    pub flip_mean: Option<f64>,
    /// Share (0..1) of the points both eyes see whose AO differs by more than 0.02:
    /// overall, within 40 px of the inner (nasal) border, and farther than 40 px from
    /// every border.
    #[serde(default)]
    pub stereo_inconsistent: Option<f64>,
    /// [`Self::stereo_inconsistent`] within 40 px of the inner (nasal) border.
    #[serde(default)]
    pub stereo_inconsistent_inner_border: Option<f64>,
    /// [`Self::stereo_inconsistent`] farther than 40 px from every border.
    #[serde(default)]
    pub stereo_inconsistent_interior: Option<f64>,
    /// The share of the right eye's tiles (workgroups of 64 occlusion pixels) its march
    /// computed rather than took from the left eye, of the tiles a full eye dispatches,
    /// read back from the indirect dispatch's arguments in the last measured frame: the
    /// same on every machine. `None` where the right eye reused nothing (one view,
    /// `--independent-eyes`, a technique without the reuse).
    #[serde(default)]
    pub right_eye_tiles_share: Option<f64>,
    /// The same for the upsampling's right eye (quads it upsampled itself; half
    /// resolution: the upsample pass's, or in a whole frame the composite's).
    #[serde(default)]
    pub right_eye_upsample_share: Option<f64>,
    /// Mean SSIM of the AO against the reference (1 = identical).
    pub ao_ssim: Option<f64>,
    /// RMSE of the ambient light's luminance relative to the reference's mean, the
    /// reference's noise taken out.
    pub ambient_rel_rmse: Option<f64>,
    /// On the Pareto front of AO RMSE against occlusion ms per eye.
    pub pareto: bool,
    /// SSDO with depth peeling; its second-layer pass is in `occlusion_ms_per_eye`.
    #[serde(default)]
    pub depth_peeling: bool,
    /// Depth layers the occlusion read (1 or 2; 1 in files written before two existed);
    /// with 2 the peel of the second layer is in `occlusion_ms_per_eye`.
    #[serde(default = "one_layer")]
    pub layers: u32,
    /// Median GPU ms per eye of the depth-peeling pass (0 without peeling).
    #[serde(default)]
    pub peel_ms_per_eye: f64,
    /// One-bounce irradiance against the reference's bounce (ssdo-bounce, rsm rows).
    #[serde(default)]
    pub bounce_rel_rmse: Option<f64>,
    /// Mean relative bias of the one-bounce irradiance against the reference's.
    #[serde(default)]
    pub bounce_rel_bias: Option<f64>,
    /// [`Self::ambient_rel_rmse`] per colour channel (red, green, blue).
    #[serde(default)]
    pub ambient_rel_rmse_r: Option<f64>,
    /// See [`Self::ambient_rel_rmse_r`].
    #[serde(default)]
    pub ambient_rel_rmse_g: Option<f64>,
    /// See [`Self::ambient_rel_rmse_r`].
    #[serde(default)]
    pub ambient_rel_rmse_b: Option<f64>,
    /// The bounce's screen-space limit's relative RMSE against the reference's bounce
    /// (what a depth-buffer bounce can reach at best).
    #[serde(default)]
    pub bounce_limit_rel_rmse: Option<f64>,
    /// [`Self::bounce_rel_rmse`] per colour channel (red, green, blue).
    #[serde(default)]
    pub bounce_rel_rmse_r: Option<f64>,
    /// See [`Self::bounce_rel_rmse_r`].
    #[serde(default)]
    pub bounce_rel_rmse_g: Option<f64>,
    /// See [`Self::bounce_rel_rmse_r`].
    #[serde(default)]
    pub bounce_rel_rmse_b: Option<f64>,
    /// Temporal accumulation on; its pass is in `occlusion_ms_per_eye`.
    #[serde(default)]
    pub temporal: bool,
    /// The composite (bench `--frame`; 0 without). At half resolution it upsamples the
    /// occlusion inline, as every frame does.
    #[serde(default)]
    pub composite_ms_per_eye: f64,
    /// Half-resolution rows with `--frame`: what upsampling costs a frame, this row's
    /// composite minus the composite of the same case at full resolution (measured in
    /// the same sweep). Frames do not run the stand-alone upsample pass.
    #[serde(default)]
    pub frame_upsample_ms_per_eye: Option<f64>,
    /// The measured frames' passes besides the occlusion, per eye (the G-buffer; with
    /// `--frame` also shadows, direct light and composite): what the occlusion shares
    /// the frame budget with. None in files written before it was recorded.
    #[serde(default)]
    pub other_ms_per_eye: Option<f64>,
}

/// Bench files written before two depth layers read one.
fn one_layer() -> u32 {
    1
}

impl BenchRecord {
    /// The row's setting in one line, e.g. `ssao N=16 r=0.5 m full`, for tables and logs.
    pub fn setting(&self) -> String {
        let peel = match (self.depth_peeling, self.layers) {
            (true, _) => " peeled",
            (false, 2) => " 2 layers",
            _ => "",
        };
        let temporal = if self.temporal { " temporal" } else { "" };
        let r = crate::formats::output::significant(self.radius_m as f64, 2);
        let foveation = match self.foveation {
            Foveation::Off => String::new(),
            level => format!(" foveation {}", level.name()),
        };
        format!("{}{peel}{temporal} N={} r={r} m {}{foveation}", self.technique, self.samples, self.resolution)
    }
}

/// A whole sweep: where it ran, how, and every row.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchFile {
    /// Scene name or file the sweep rendered.
    pub scene: String,
    /// GPU adapter name as wgpu reports it.
    pub adapter: String,
    /// wgpu backend (e.g. `Vulkan`).
    pub backend: String,
    /// Driver name and version as the adapter reports them.
    pub driver: String,
    /// Width of each eye's image in pixels.
    pub width: u32,
    /// Height of each eye's image in pixels.
    pub height: u32,
    /// Timing mode, lower case (`serial` or `pipelined`): how passes were submitted.
    pub timing: String,
    /// Frames rendered and discarded before timing began, per case.
    pub warmup: u32,
    /// Frames timed per case (the medians are over these).
    pub frames: u32,
    /// The reference tracer's settings and noise, when errors were measured.
    pub reference: Option<ReferenceInfo>,
    /// How the screen-space limit was marched, when errors were measured.
    #[serde(default)]
    pub limit: Option<LimitInfo>,
    /// Pixels per degree of the eyes (FLIP uses this over the reference's stride).
    #[serde(default)]
    pub pixels_per_degree: Option<f64>,
    /// vrao's version (and git commit when it could be read) that measured this.
    #[serde(default)]
    pub version: String,
    /// The command line that measured this.
    #[serde(default)]
    pub command: String,
    /// One row per measured case, in sweep order.
    pub records: Vec<BenchRecord>,
}

impl BenchFile {
    /// Parses a bench JSON and checks every record ([`BenchFile::validate`]); errors name
    /// `origin` (and the line where the JSON is malformed).
    pub fn from_json(text: &str, origin: &Path) -> Result<BenchFile> {
        let file: BenchFile = serde_json::from_str(text)
            .map_err(|e| Error::at_line(origin, e.line(), format!("not a vrao bench file: {e}")))?;
        file.validate(origin)?;
        Ok(file)
    }

    /// Checks what a bench run could have written: at least one record, and in each a
    /// known technique, samples in range, a positive radius, and finite non-negative times
    /// and errors. The error names `origin`, the record (1-based, with its setting) and
    /// the value.
    pub fn validate(&self, origin: &Path) -> Result<()> {
        if self.records.is_empty() {
            return Err(Error::in_file(origin, "holds no bench records"));
        }
        for (i, record) in self.records.iter().enumerate() {
            if let Err(Problem(trouble)) = record.check() {
                let message = format!("record {} ({}): {trouble}", i + 1, record.setting());
                return Err(Error::in_file(origin, message));
            }
        }
        Ok(())
    }
}

/// What is wrong with a record, for the caller to name the file and the record with.
struct Problem(String);

impl BenchRecord {
    /// What is wrong with this record, if anything (see [`BenchFile::validate`]).
    fn check(&self) -> std::result::Result<(), Problem> {
        // Rows of reflective shadow maps carry "rsm" and their VPL count as samples.
        let rsm = self.technique == vrao_render::passes::rsm::NAME;
        if !rsm && self.technique.parse::<Technique>().is_err() {
            return Err(Problem(format!("unknown technique '{}'", self.technique)));
        }
        let samples_max = if rsm { RSM_SAMPLES_MAX } else { AoSettings::SAMPLES_MAX };
        if !(1..=samples_max).contains(&self.samples) {
            return Err(Problem(format!("samples {} is not within 1..={samples_max}", self.samples)));
        }
        if !(self.radius_m.is_finite() && self.radius_m > 0.0) {
            return Err(Problem(format!("radius {} m is not a positive number", self.radius_m)));
        }
        let times = [
            ("technique_ms_per_eye", self.technique_ms_per_eye),
            ("blur_ms_per_eye", self.blur_ms_per_eye),
            ("upsample_ms_per_eye", self.upsample_ms_per_eye),
            ("occlusion_ms_per_eye", self.occlusion_ms_per_eye),
            ("p75_over_p25", self.p75_over_p25),
        ];
        let errors = [("ao_rmse", self.ao_rmse), ("ao_bias", self.ao_bias)];
        let present = errors.iter().filter_map(|(name, v)| v.map(|v| (*name, v)));
        for (name, value) in times.into_iter().chain(present) {
            // A bias may be negative; nothing else a bench writes is.
            let negative_allowed = name == "ao_bias";
            if !value.is_finite() || (!negative_allowed && value < 0.0) {
                return Err(Problem(format!("{name} {value} is not a finite, non-negative number")));
            }
        }
        Ok(())
    }
}

/// The screen-space limit's march (the reference tracer's `LimitSettings`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LimitInfo {
    /// Rays marched per pixel.
    pub rays_per_pixel: u32,
    /// Steps along each ray.
    pub steps: u32,
    /// Thickness as a fraction of the radius.
    pub thickness_of_radius: f64,
}

/// The reference tracer's settings and noise, when errors were measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo {
    /// Rays traced per pixel.
    pub rays_per_pixel: u32,
    /// Every `stride`-th pixel in x and y was traced (1: all).
    pub stride: u32,
    /// RMS over hit pixels of the reference AO's standard error (worst radius).
    pub ao_noise_rms: f64,
    /// Tracer throughput on this machine (rays per second, all cores), when it traced.
    pub rays_per_second: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::Resolution;
    use crate::formats::output::significant;

    #[test]
    fn resolutions_keep_their_names_in_files() {
        #[derive(serde::Serialize, serde::Deserialize, Debug, PartialEq)]
        struct InFile(#[serde(with = "crate::formats::by_name")] Resolution);
        for (r, name) in [(Resolution::Full, "full"), (Resolution::Half, "half")] {
            assert_eq!(r.name(), name);
            assert_eq!(r.to_string(), name);
            assert_eq!(serde_json::to_string(&InFile(r)).unwrap(), format!("\"{name}\""));
            assert_eq!(serde_json::from_str::<InFile>(&format!("\"{name}\"")).unwrap(), InFile(r));
        }
        assert!(serde_json::from_str::<InFile>("\"quarter\"").is_err());
        assert!(Resolution::from_half_res(true).is_half() && !Resolution::from_half_res(false).is_half());
    }

    #[test]
    fn significant_digits_without_float_noise() {
        assert_eq!(significant(0.25612497f32 as f64, 2), "0.26");
        assert_eq!(significant(0.5f32 as f64, 2), "0.5");
        assert_eq!(significant(12.3, 2), "12");
        assert_eq!(significant(0.004987, 2), "0.005");
        assert_eq!(significant(0.0996, 2), "0.1");
        assert_eq!(significant(0.0, 2), "0");
    }
}
