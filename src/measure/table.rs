//! The GPU table (`vrao table`): the budget measurement of [`crate::measure::budget`] swept
//! over scene × technique × quality preset × AO resolution × foveation, one renderer per
//! scene whose settings change per row, written as one Markdown file.
//!
//! Each row renders rounds of (stereo frame, left eye alone, right eye alone) of whole
//! frames and keeps every pass's median, as `vrao budget` does; the table shows the left
//! eye's AO passes, the AO chain for the left eye alone and for the stereo frame (their
//! ratio is the right eye's marginal cost), and the stereo frame against the budget.

use crate::error::{Error, Result};
use crate::measure::bench::Resolution;
use crate::measure::budget::{self, BudgetReport, BudgetRun, PassTimes, Scope};
use std::fmt::Write as _;
use std::sync::Arc;
use vrao_ao::plug::BLUR_PASS;
use vrao_ao::{AoSettings, Foveation, Quality, Technique};
use vrao_render::passes::tonemap::COLOR;
use vrao_render::passes::{composite, shadow};
use vrao_render::renderer::{Renderer, TimingChoice};
use vrao_render::scene::Scene;
use vrao_render::settings::{Settings, ShadowSettings};
use vrao_render::{BackendChoice, HeadsetProfile};

/// The most scenes one table takes (each loads its own renderer).
pub const SCENES_MAX: usize = 16;

/// What [`run_table`] sweeps and how it measures each row.
#[derive(Clone, Debug)]
pub struct TableOptions {
    /// Which wgpu backend to ask for.
    pub backend: BackendChoice,
    /// Serial, pipelined or auto (serial on CPU adapters, pipelined timestamps on GPUs).
    pub timing: TimingChoice,
    /// Per-eye width in pixels.
    pub width: u32,
    /// Per-eye height in pixels.
    pub height: u32,
    /// Measured rounds per row (each: the stereo frame, then each eye alone).
    pub frames: u32,
    /// Rounds discarded before timing, per row.
    pub warmup: u32,
    /// The stereo frame budget in ms; `None`: the headset's refresh interval.
    pub budget_ms: Option<f64>,
    /// Techniques, in table order.
    pub techniques: Vec<Technique>,
    /// Quality presets, in table order.
    pub qualities: Vec<Quality>,
    /// AO resolutions, in table order.
    pub resolutions: Vec<Resolution>,
    /// Foveation settings, in table order.
    pub foveations: Vec<Foveation>,
}

impl TableOptions {
    /// The headset the table is measured for: a Vive-class profile at the asked size.
    pub fn profile(&self) -> HeadsetProfile {
        HeadsetProfile::with_size("vive", self.width, self.height)
    }

    /// The stereo frame budget in ms (the asked one, or the headset's refresh interval).
    pub fn budget_ms(&self) -> f64 {
        self.budget_ms.unwrap_or(self.profile().budget_ms())
    }

    /// Checks every option without a device or a scene, so that a bad value fails
    /// before any work: the size, the frame counts, the budget, and every list non-empty,
    /// free of repeats and (techniques) of occlusion techniques only.
    pub fn validate(&self) -> Result<()> {
        Settings { profile: self.profile(), ..Settings::default() }.validate()?;
        crate::measure::check_frames(self.warmup, self.frames)?;
        let budget_ms = self.budget_ms();
        if !(budget_ms.is_finite() && budget_ms > 0.0) {
            return Err(Error::input(format!("the frame budget {budget_ms} ms must be a positive number")));
        }
        if self.techniques.contains(&Technique::None) {
            return Err(Error::input("the table needs occlusion techniques; 'none' has no AO chain to time"));
        }
        check_list("techniques", &self.techniques)?;
        check_list("qualities", &self.qualities)?;
        check_list("resolutions", &self.resolutions)?;
        check_list("foveations", &self.foveations)
    }

    /// The rows of one scene, in table order (technique, then preset, resolution,
    /// foveation).
    pub fn cases(&self) -> Vec<TableCase> {
        let mut cases = Vec::new();
        for &technique in &self.techniques {
            for &quality in &self.qualities {
                for &resolution in &self.resolutions {
                    for &foveation in &self.foveations {
                        cases.push(TableCase { technique, quality, resolution, foveation });
                    }
                }
            }
        }
        cases
    }
}

/// Refuses an empty list or one that names a value twice (a row measured twice).
fn check_list<T: PartialEq + std::fmt::Debug>(what: &str, list: &[T]) -> Result<()> {
    if list.is_empty() {
        return Err(Error::input(format!("the table needs at least one of its {what}")));
    }
    match crate::measure::named_twice(list) {
        Some(v) => Err(Error::input(format!("{what} name {} twice", format!("{v:?}").to_lowercase()))),
        None => Ok(()),
    }
}

/// One row's setting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableCase {
    /// The occlusion technique.
    pub technique: Technique,
    /// The quality preset (its depth taps per pixel and depth layers).
    pub quality: Quality,
    /// The resolution the occlusion runs at.
    pub resolution: Resolution,
    /// Fixed foveated occlusion.
    pub foveation: Foveation,
}

impl TableCase {
    /// `base` with this row's occlusion setting.
    pub fn settings(&self, base: &Settings) -> Settings {
        let mut settings = base.clone();
        settings.ao.technique = self.technique;
        self.quality.apply(&mut settings.ao);
        settings.ao.resolution = self.resolution;
        settings.ao.foveation = self.foveation;
        settings
    }
}

/// One measured row: its setting, the budget run, and which passes make its AO chain.
#[derive(Clone, Debug)]
pub struct TableRow {
    /// The setting measured.
    pub case: TableCase,
    /// The pass that ran the technique.
    pub pass: &'static str,
    /// The AO chain's passes: those the frame graph marks as occlusion cost (technique,
    /// depth peel, temporal, denoise, upsample as they ran), plus the composite at half
    /// resolution, which upsamples the occlusion inline.
    pub chain: Vec<&'static str>,
    /// Every pass's medians for the stereo frame and each eye alone, and the verdicts.
    pub report: BudgetReport,
    /// At half resolution, when the same case ran at full resolution too: what the
    /// composite's inline upsampling costs, the left eye alone and the stereo frame (this
    /// row's composite minus the full-resolution row's, as `vrao bench --frame` takes
    /// it). The chain then counts it instead of the whole composite, whose shading every
    /// frame pays at any AO resolution.
    pub inline_upsampling: Option<[f64; 2]>,
}

impl TableRow {
    fn times(&self, pass: &str) -> Option<&PassTimes> {
        self.report.passes.iter().find(|p| p.pass == pass)
    }

    /// Median ms of `pass` for the left eye alone; `None` when it did not run.
    pub fn left_ms(&self, pass: &str) -> Option<f64> {
        self.times(pass).and_then(|p| p.left.as_ref()).map(|s| s.median_ms)
    }

    /// The left eye alone's passes outside `shown`, summed.
    pub fn left_rest_ms(&self, shown: &[&str]) -> f64 {
        let rest = self.report.passes.iter().filter(|p| !shown.contains(&p.pass.as_str()));
        rest.filter_map(|p| p.left.as_ref()).map(|s| s.median_ms).sum()
    }

    /// Median ms of `pass` for `scope`; `None` when it did not run.
    fn scope_ms(&self, pass: &str, scope: Scope) -> Option<f64> {
        let p = self.times(pass)?;
        let span = match scope {
            Scope::LeftEye => &p.left,
            Scope::RightEye => &p.right,
            Scope::StereoFrame => &p.stereo,
        };
        span.as_ref().map(|s| s.median_ms)
    }

    /// The AO chain's ms for `scope` (the left eye alone or the stereo frame): its
    /// passes, with the composite's inline upsampling in place of the whole composite
    /// where it is known ([`TableRow::inline_upsampling`]).
    pub fn chain_ms(&self, scope: Scope) -> f64 {
        let inline =
            self.inline_upsampling.map(|[left, stereo]| if scope == Scope::StereoFrame { stereo } else { left });
        self.chain
            .iter()
            .filter_map(|&pass| match inline {
                Some(ms) if pass == composite::NAME => Some(ms),
                _ => self.scope_ms(pass, scope),
            })
            .sum()
    }

    /// The stereo AO chain over the left eye alone's: 1 + the right eye's marginal cost.
    pub fn stereo_over_left(&self) -> f64 {
        self.chain_ms(Scope::StereoFrame) / self.chain_ms(Scope::LeftEye)
    }

    /// The whole stereo frame's verdict against the budget.
    pub fn stereo_frame(&self) -> &budget::Verdict {
        self.report.verdicts.iter().find(|v| v.what == Scope::StereoFrame).expect("budget::run gives every scope")
    }
}

/// One scene's rows.
#[derive(Clone, Debug)]
pub struct SceneTable {
    /// How the scene was asked for (a file or `builtin:NAME`).
    pub spec: String,
    /// The scene's own name.
    pub name: String,
    /// The occlusion radius of every row (the scene's suggested radius), metres.
    pub radius_m: f32,
    /// The rows, in [`TableOptions::cases`] order.
    pub rows: Vec<TableRow>,
}

/// Everything `vrao table` measured.
#[derive(Clone, Debug)]
pub struct Table {
    /// Adapter name.
    pub adapter: String,
    /// wgpu backend.
    pub backend: String,
    /// Driver and its version.
    pub driver: String,
    /// `serial` or `pipelined`.
    pub timing: String,
    /// Per-eye size in pixels.
    pub width: u32,
    /// Per-eye height in pixels.
    pub height: u32,
    /// Measured rounds per row.
    pub frames: u32,
    /// Warm-up rounds per row.
    pub warmup: u32,
    /// The stereo frame budget (ms).
    pub budget_ms: f64,
    /// One table per scene.
    pub scenes: Vec<SceneTable>,
}

/// The settings every row of `scene` starts from: the headset at the asked size, the
/// default occlusion and shadows with the scene's suggested AO and RSM radii (what `vrao
/// budget` uses with no options).
pub fn base_settings(scene: &Scene, options: &TableOptions) -> Settings {
    Settings {
        profile: options.profile(),
        ao: AoSettings { radius: scene.suggested_ao_radius(), ..AoSettings::default() },
        shadows: ShadowSettings { rsm_radius: shadow::suggested_rsm_radius(scene), ..ShadowSettings::default() },
        ..Settings::default()
    }
}

/// Refuses a table of no scenes or of more than [`SCENES_MAX`].
pub fn check_scene_count(scenes: usize) -> Result<()> {
    if !(1..=SCENES_MAX).contains(&scenes) {
        return Err(Error::input(format!("{scenes} scenes is not within 1..={SCENES_MAX}")));
    }
    Ok(())
}

/// Measures every case of `options` on each of `scenes` (each with how it was asked for)
/// and returns the table. Logs each row at the info level as it is done.
pub fn run_table(scenes: &[(String, Scene)], options: &TableOptions) -> Result<Table> {
    options.validate()?;
    check_scene_count(scenes.len())?;
    let cases = options.cases();
    for (_, scene) in scenes {
        for case in &cases {
            case.settings(&base_settings(scene, options)).validate()?;
        }
    }
    let gpu = Arc::new(vrao_render::open(options.backend)?);
    let timing = options.timing.resolve(&gpu);
    let budget_ms = options.budget_ms();
    let how = BudgetRun { timing, warmup: options.warmup, frames: options.frames, budget_ms, output: COLOR };
    let mut tables = Vec::with_capacity(scenes.len());
    for (spec, scene) in scenes {
        let base = base_settings(scene, options);
        let eyes = base.profile.eyes(&scene.head.pose_at(0.0), base.near);
        // One renderer per scene: its passes hold every variant, so a row only switches
        // settings (Renderer::set_settings) and the scene is uploaded once.
        let mut renderer = Renderer::new(gpu.clone(), scene, &cases[0].settings(&base))?;
        let mut rows = Vec::with_capacity(cases.len());
        for (i, case) in cases.iter().enumerate() {
            let settings = case.settings(&base);
            renderer.set_settings(&settings)?;
            if i == 0 {
                budget::settle(&mut renderer, &eyes, how)?;
            }
            let report = budget::run(&mut renderer, &eyes, how)?;
            let row = TableRow {
                case: *case,
                pass: settings.ao.pass_name(),
                chain: chain(&renderer)?,
                report,
                inline_upsampling: None,
            };
            log::info!(
                "table {}: {}/{} {} {} {} foveation {}: AO chain {:.3} ms left eye, stereo frame {:.3} ms",
                scene.name,
                i + 1,
                cases.len(),
                case.technique.name(),
                case.quality.name(),
                case.resolution.name(),
                case.foveation.name(),
                row.chain_ms(Scope::LeftEye),
                row.stereo_frame().ms
            );
            rows.push(row);
        }
        let upsampling: Vec<_> = rows.iter().map(|row| inline_upsampling(row, &rows)).collect();
        for (row, inline) in rows.iter_mut().zip(upsampling) {
            row.inline_upsampling = inline;
        }
        tables.push(SceneTable { spec: spec.clone(), name: scene.name.clone(), radius_m: base.ao.radius, rows });
    }
    let info = &gpu.info;
    Ok(Table {
        adapter: info.name.clone(),
        backend: format!("{:?}", info.backend),
        driver: format!("{} {}", info.driver, info.driver_info).trim().to_string(),
        timing: format!("{timing:?}").to_lowercase(),
        width: options.width,
        height: options.height,
        frames: options.frames,
        warmup: options.warmup,
        budget_ms,
        scenes: tables,
    })
}

/// A half-resolution row's inline upsampling ([`TableRow::inline_upsampling`]) from the
/// full-resolution row of the same case among `rows`; `None` at full resolution or
/// without that row.
fn inline_upsampling(row: &TableRow, rows: &[TableRow]) -> Option<[f64; 2]> {
    if row.case.resolution != Resolution::Half {
        return None;
    }
    let full_case = TableCase { resolution: Resolution::Full, ..row.case };
    let full = rows.iter().find(|f| f.case == full_case)?;
    let excess = |scope: Scope| {
        let (half, full) = (row.scope_ms(composite::NAME, scope)?, full.scope_ms(composite::NAME, scope)?);
        // Timing noise can put a cheap upsampling below zero: it costs at least nothing.
        Some((half - full).max(0.0))
    };
    Some([excess(Scope::LeftEye)?, excess(Scope::StereoFrame)?])
}

/// The AO chain of the renderer's current settings: the occlusion-cost passes of the
/// stereo and the one-eye frame's plans, plus the composite when the occlusion runs at
/// half resolution (the composite then upsamples it inline, as `vrao bench --frame`
/// counts it).
fn chain(renderer: &Renderer) -> Result<Vec<&'static str>> {
    let mut chain: Vec<&'static str> = Vec::new();
    for views in [2, 1] {
        for pass in renderer.plan(views, &[COLOR])?.occlusion_passes() {
            if !chain.contains(&pass) {
                chain.push(pass);
            }
        }
    }
    if renderer.settings().ao.resolution.is_half() {
        chain.push(composite::NAME);
    }
    Ok(chain)
}

/// The table's column headers, in order (the per-pass columns are the left eye alone's).
pub const COLUMNS: [&str; 13] = [
    "technique",
    "preset",
    "AO res",
    "foveation",
    "AO pass ms",
    "denoise ms",
    "composite ms",
    "rest ms",
    "AO chain ms (left eye)",
    "AO chain ms (stereo)",
    "stereo / left",
    "stereo frame ms",
    "verdict",
];

impl Table {
    /// The Markdown file: a header naming the device, the timing, the size, the frames,
    /// the budget, vrao's `version` and the `command` that made it; then one table per
    /// scene, and notes on what the columns hold.
    pub fn to_markdown(&self, version: &str, command: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# vrao GPU table\n");
        let _ = writeln!(s, "- adapter: {} ({}), driver: {}", self.adapter, self.backend, self.driver);
        let _ = writeln!(s, "- timing: {}", self.timing);
        let _ = writeln!(s, "- per eye: {}×{} px", self.width, self.height);
        let _ = writeln!(
            s,
            "- frames: median of {} measured rounds after {} warm-up, each round the stereo frame, then each eye alone",
            self.frames, self.warmup
        );
        let _ = writeln!(s, "- budget: {:.3} ms per stereo frame", self.budget_ms);
        let _ = writeln!(s, "- vrao {version}");
        let _ = writeln!(s, "- command: `{command}`");
        for scene in &self.scenes {
            let _ = writeln!(s, "\n## {} (`{}`), AO radius {:.3} m\n", scene.name, scene.spec, scene.radius_m);
            let _ = writeln!(s, "| {} |", COLUMNS.join(" | "));
            let _ = writeln!(s, "|{}", " --- |".repeat(COLUMNS.len()));
            for row in &scene.rows {
                let _ = writeln!(s, "| {} |", row_cells(row).join(" | "));
            }
        }
        let _ = writeln!(s, "\n## Notes\n");
        let chains: Vec<String> = {
            let mut seen: Vec<String> = Vec::new();
            for row in self.scenes.iter().flat_map(|t| &t.rows) {
                let chain = format!(
                    "{} at {}: {}",
                    row.case.technique.name(),
                    row.case.resolution.name(),
                    row.chain.join(" + ")
                );
                if !seen.contains(&chain) {
                    seen.push(chain);
                }
            }
            seen
        };
        let notes = [
            "Frames are whole (G-buffer, shadows, direct light, AO, composite, tone mapping). Every figure is in ms: a pass's median over the measured rounds, or a sum of such medians (rest, the AO chain, the stereo frame).".to_string(),
            "Timing serial: each pass submitted alone and timed by the wall clock (CPU adapters, whose timestamps misplace work); pipelined: GPU timestamps around each pass of one submission.".to_string(),
            format!(
                "AO pass, denoise (`{}`), composite and rest are the left eye rendered alone; rest is every other pass of its frame, summed.",
                BLUR_PASS
            ),
            "AO chain: the passes the frame graph marks as occlusion cost (the technique, temporal, denoise, upsample as they ran) plus, at half resolution, the composite's inline upsampling of the half-resolution AO: the composite's excess over the same case's at full resolution (scope by scope, at least 0), or the whole composite, marked *, where no full-resolution row was measured. By row kind:".to_string(),
        ];
        for note in notes {
            let _ = writeln!(s, "- {note}");
        }
        for chain in chains {
            let _ = writeln!(s, "  - {chain}");
        }
        let _ = writeln!(
            s,
            "- stereo / left: the AO chain of the stereo frame over the left eye alone's; the right eye costs (ratio − 1) of the left."
        );
        let _ = writeln!(
            s,
            "- verdict: the whole stereo frame against the {:.3} ms budget, with its ratio to it.",
            self.budget_ms
        );
        s
    }
}

/// One row's cells, in [`COLUMNS`] order; a pass that did not run is `-`.
fn row_cells(row: &TableRow) -> Vec<String> {
    let ms = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    let shown = [row.pass, BLUR_PASS, composite::NAME];
    let frame = row.stereo_frame();
    let ratio = frame.ms / frame.budget_ms;
    let whole = if row.chain.contains(&composite::NAME) && row.inline_upsampling.is_none() { "*" } else { "" };
    vec![
        row.case.technique.name().to_string(),
        format!("{} ({})", row.case.quality.name(), row.case.quality.samples()),
        row.case.resolution.name().to_string(),
        row.case.foveation.name().to_string(),
        ms(row.left_ms(row.pass)),
        ms(row.left_ms(BLUR_PASS)),
        ms(row.left_ms(composite::NAME)),
        ms(Some(row.left_rest_ms(&shown))),
        // * : the chain counts the whole composite (no full-resolution row to subtract).
        format!("{}{whole}", ms(Some(row.chain_ms(Scope::LeftEye)))),
        format!("{}{whole}", ms(Some(row.chain_ms(Scope::StereoFrame)))),
        format!("{:.2}×", row.stereo_over_left()),
        ms(Some(frame.ms)),
        format!("{} ({ratio:.2}×)", if frame.pass { "PASS" } else { "FAIL" }),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options() -> TableOptions {
        TableOptions {
            backend: BackendChoice::Auto,
            timing: TimingChoice::Auto,
            width: 48,
            height: 54,
            frames: 1,
            warmup: 0,
            budget_ms: None,
            techniques: vec![Technique::Gtao, Technique::Ssao],
            qualities: vec![Quality::Low],
            resolutions: vec![Resolution::Full, Resolution::Half],
            foveations: vec![Foveation::Off, Foveation::High],
        }
    }

    #[test]
    fn cases_cover_every_combination_in_table_order() {
        let cases = options().cases();
        assert_eq!(cases.len(), 8);
        assert_eq!(cases[0].technique, Technique::Gtao);
        assert_eq!((cases[1].resolution, cases[1].foveation), (Resolution::Full, Foveation::High));
        assert_eq!(cases[7].technique, Technique::Ssao);
    }

    #[test]
    fn bad_options_are_refused_naming_the_value() {
        let bad = |change: fn(&mut TableOptions)| {
            let mut o = options();
            change(&mut o);
            o.validate().unwrap_err().to_string()
        };
        assert!(bad(|o| o.width = 0).contains("0x54"));
        assert!(bad(|o| o.frames = 0).contains("0 measured frames"));
        assert!(bad(|o| o.budget_ms = Some(-1.0)).contains("-1 ms"));
        assert!(bad(|o| o.techniques.push(Technique::None)).contains("'none'"));
        assert!(bad(|o| o.qualities.clear()).contains("qualities"));
        assert!(bad(|o| o.foveations.push(Foveation::Off)).contains("foveations name off twice"));
        assert!(options().validate().is_ok());
    }
}
