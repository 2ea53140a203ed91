//! A live frame-budget governor: moves the occlusion between the settings of a measured
//! cost/error frontier so that each stereo frame's GPU time stays inside the headset's
//! frame period. Pure bookkeeping (no GPU): the frame loop feeds it each frame's measured
//! GPU time and applies the level it returns.
//!
//! The rules are Valve's adaptive quality (Vlachos, "Advanced VR Rendering Performance",
//! GDC 2016): drop two levels as soon as a frame takes more than 90 % of the period (or
//! a rising trend predicts an overrun), raise one level only after a calm stretch below
//! 70 %, and only when the next level's predicted time stays under 90 % — so a steady
//! load settles on one level instead of oscillating.
//!
//! ## The display's rate
//! The period is the display's refresh period (an OpenXR runtime's refresh rate, else the
//! shortest display period it predicted: [`crate::xr::DisplayRate`]), never the period a
//! runtime predicts for a frame: that one stretches to whole refreshes when frames are late
//! (Monado predicts 100 ms on a 50 ms display), and a raise judged against it would
//! predict a frame slower than one refresh and keep the application at half rate. A frame
//! whose predicted period spans more than one refresh ([`Governor::observe_paced`]) missed
//! refreshes: it is a reason to drop (once the frames after a change had time to reach the
//! runtime's pacing) and never counts as calm. So is a frame that missed its predicted
//! display time on the headset's clock ([`Observation::late_ms`], the frame loop's
//! estimate from when it was submitted and its GPU time): what the runtime shows late,
//! whatever the GPU time says against the period.
//!
//! ## Prediction model
//! A frame's GPU time is T = R + A: the AO passes A and everything else R. At level i
//! the AO costs are taken to scale with the frontier's per-eye cost c (measured by
//! `vrao bench`, possibly on another device): at level j, A_j = A_i · c_j / c_i, and R
//! does not depend on the level, so the predicted frame is R + A_i · c_j / c_i.
//! A_i is the measured AO time when the frame loop has one ([`Governor::observe_with_ao`],
//! from the AO passes' timestamps); otherwise it is estimated as the level's frontier
//! cost for both eyes, 2 c_i × [`GovernorConfig::frontier_scale`] (1: the frontier was
//! measured on this device), capped at T. The cap makes a frontier measured on a slower
//! device (the built-in one is lavapipe's) scale the whole frame, which over-predicts
//! a raise: safe, if timid. Where a raise still turns out costlier than predicted (the
//! device's cost ratios differ from the frontier's), the level keeps the ratio measured /
//! predicted of its first frame as a factor on later predictions, so the same load does
//! not try that raise again.

use crate::error::{Error, Result};
use crate::formats::bench_file::{BenchFile, BenchRecord};
use serde::Serialize;
use std::collections::VecDeque;
use std::path::Path;
use vrao_ao::{AoSettings, Foveation, Technique};

/// The bench committed with vrao: the furnished room, gtao/ssao/hbao × 12–64 samples ×
/// full/half × temporal at r = 0.3 m, 540x600 per eye on lavapipe.
const BUILTIN_JSON: &str = include_str!("../../assets/governor/frontier.json");
const BUILTIN_PATH: &str = "assets/governor/frontier.json";
/// The one radius the built-in bench measured.
pub const BUILTIN_RADIUS_M: f32 = 0.3;

/// One setting on the frontier.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// [`BenchRecord::setting`] at the radius the run applies (a level keeps the host's
    /// radius: [`Level::apply`]), e.g. "gtao N=24 r=0.51 m half" from a bench measured at
    /// 0.3 m: the label says what is rendered, [`Frontier::radius_m`] what was measured.
    pub setting: String,
    /// The technique of the setting.
    pub technique: Technique,
    /// Samples per pixel (N).
    pub samples: u32,
    /// Occlusion at half resolution.
    pub half_res: bool,
    /// Temporal accumulation on.
    pub temporal: bool,
    /// Fixed foveation (a bench swept with `--foveation` offers foveated levels).
    pub foveation: Foveation,
    /// AO RMSE against the reference.
    pub ao_rmse: f64,
    /// Occlusion cost per eye on the bench's device.
    pub ms_per_eye: f64,
}

impl Level {
    /// `ao` with this level's technique, samples, resolution and temporal accumulation,
    /// and the stronger of its foveation and `ao`'s (the user's choice is a floor: the
    /// governor adds foveation where a level was measured with it, never takes it away);
    /// everything else (radius, strength, …) is kept.
    pub fn apply(&self, ao: &AoSettings) -> AoSettings {
        let mut out = ao.clone();
        out.technique = self.technique;
        out.samples = self.samples;
        out.resolution = vrao_ao::Resolution::from_half_res(self.half_res);
        out.temporal.enabled = self.temporal;
        out.foveation = self.foveation.max(ao.foveation);
        out
    }
}

/// The levels the governor moves between, cheapest (most error) first, each strictly
/// costlier and strictly more accurate than the one before.
#[derive(Clone, Debug, PartialEq)]
pub struct Frontier {
    levels: Vec<Level>,
    radius_m: f32,
}

impl Frontier {
    /// The Pareto-optimal rows of `file` at its radius nearest to `radius` (errors only
    /// compare within one radius), labelled at `radius`, the radius a run applies with
    /// them. Rows without a finite error or a positive cost, depth-
    /// peeled rows (a [`Level`] cannot express peeling) and non-occlusion techniques
    /// (none, fetch-only, rsm) are left out. A bench without such rows is `Error::Input`.
    pub fn from_bench(file: &BenchFile, radius: f32) -> Result<Frontier> {
        let usable: Vec<(&BenchRecord, Technique)> = file
            .records
            .iter()
            .filter(|r| r.ao_rmse.is_some_and(f64::is_finite))
            .filter(|r| r.occlusion_ms_per_eye.is_finite() && r.occlusion_ms_per_eye > 0.0)
            .filter(|r| !r.depth_peeling)
            .filter_map(|r| r.technique.parse::<Technique>().ok().map(|t| (r, t)))
            .filter(|(_, t)| !matches!(t, Technique::None | Technique::FetchOnly))
            .collect();
        let Some(nearest) =
            usable.iter().map(|(r, _)| r.radius_m).min_by(|a, b| (a - radius).abs().total_cmp(&(b - radius).abs()))
        else {
            return Err(Error::input(format!(
                "the bench of '{}' on '{}' ({} rows; {}) has no occlusion rows with an AO error and a positive time to govern with (measure with a reference)",
                file.scene,
                file.adapter,
                file.records.len(),
                if file.command.is_empty() { "no command recorded" } else { file.command.as_str() }
            )));
        };
        let mut rows: Vec<_> = usable.into_iter().filter(|(r, _)| r.radius_m == nearest).collect();
        rows.sort_by(|(a, _), (b, _)| {
            a.occlusion_ms_per_eye
                .total_cmp(&b.occlusion_ms_per_eye)
                .then(a.ao_rmse.unwrap().total_cmp(&b.ao_rmse.unwrap()))
        });
        let mut levels: Vec<Level> = Vec::new();
        for (r, technique) in rows {
            let (ms, rmse) = (r.occlusion_ms_per_eye, r.ao_rmse.unwrap());
            // Sorted by time then error: a row is kept only when it beats every cheaper
            // kept row on error, and is strictly costlier than the last one.
            if levels.last().is_some_and(|l| rmse >= l.ao_rmse || ms <= l.ms_per_eye) {
                continue;
            }
            // Labelled with the radius rendered, not the bench's (a level never sets it).
            let applied = BenchRecord { radius_m: radius, ..r.clone() };
            levels.push(Level {
                setting: applied.setting(),
                technique,
                samples: r.samples,
                half_res: r.resolution.is_half(),
                temporal: r.temporal,
                foveation: r.foveation,
                ao_rmse: rmse,
                ms_per_eye: ms,
            });
        }
        Ok(Frontier { levels, radius_m: nearest })
    }

    /// A bench JSON's frontier; `origin`, the file, is named in errors (with the line
    /// where the JSON is malformed).
    pub fn from_json(text: &str, origin: &Path, radius: f32) -> Result<Frontier> {
        let file = BenchFile::from_json(text, origin)?;
        Frontier::from_bench(&file, radius).map_err(|e| Error::in_file(origin, e.to_string()))
    }

    /// The frontier of the bench committed at `assets/governor/frontier.json`, labelled
    /// at the radius it was measured at.
    pub fn builtin() -> Frontier {
        Frontier::builtin_at(BUILTIN_RADIUS_M)
    }

    /// The built-in frontier for a run at `radius`: the levels measured at
    /// [`BUILTIN_RADIUS_M`], labelled at `radius` (see [`Frontier::from_bench`]).
    pub fn builtin_at(radius: f32) -> Frontier {
        Frontier::from_json(BUILTIN_JSON, Path::new(BUILTIN_PATH), radius).expect("the built-in frontier parses")
    }

    /// The level nearest the setting `ao` asks for, where the governor starts: the level
    /// with the same technique, samples, resolution and temporal accumulation if there is
    /// one; else the nearest by, in order, technique (a technique is what the user chose
    /// first), samples (by their ratio), resolution, then temporal accumulation; equal
    /// candidates go to the cheaper level (a start over budget costs a dropped frame, one
    /// under it a raise later).
    pub fn nearest(&self, ao: &AoSettings) -> usize {
        let key = |l: &Level| {
            let samples = (f64::from(l.samples.max(1)) / f64::from(ao.samples.max(1))).log2().abs();
            (
                l.technique != ao.technique,
                samples,
                l.half_res != ao.resolution.is_half(),
                l.temporal != ao.temporal.enabled,
            )
        };
        // `min_by` keeps the first of equals, and levels run cheapest first.
        self.levels
            .iter()
            .enumerate()
            .min_by(|(_, a), (_, b)| {
                let (a, b) = (key(a), key(b));
                a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)).then(a.3.cmp(&b.3))
            })
            .map_or(0, |(i, _)| i)
    }

    /// Every level, cheapest (most error) first.
    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// Never 0.
    pub fn len(&self) -> usize {
        self.levels.len()
    }

    /// Always false (a frontier has at least one level); here for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.levels.is_empty()
    }

    /// The least-error level's index.
    pub fn top(&self) -> usize {
        self.levels.len() - 1
    }

    /// The bench radius the levels were measured at.
    pub fn radius_m(&self) -> f32 {
        self.radius_m
    }
}

/// When the governor changes level. `Default` is Valve's adaptive quality at 90 Hz.
#[derive(Clone, Debug, PartialEq)]
pub struct GovernorConfig {
    /// The display's frame period (the whole stereo frame's GPU budget).
    pub period_ms: f64,
    /// Drop on a frame above this share of the period.
    pub drop_above: f64,
    /// Frames below this share of the period count as calm.
    pub raise_below: f64,
    /// Consecutive calm frames before a raise.
    pub calm_frames_to_raise: usize,
    /// Frames since the last change before a raise.
    pub min_frames_between_raises: u64,
    /// Levels to drop on a frame over `drop_above` (≥ 1).
    pub drop_step: usize,
    /// Levels to raise after enough calm frames (≥ 1).
    pub raise_step: usize,
    /// Measurements of this many frames after a change's frame are ignored: GPU times
    /// arrive a frame or two late, so those frames may still have had the old level.
    pub settle_frames: u64,
    /// This GPU's AO ms per frontier ms, for the AO estimate when no AO time is measured
    /// (1: the frontier was benched on this device).
    pub frontier_scale: f64,
    /// Frames after a change's frame whose stretched display period is no reason to drop
    /// again: their GPU times come one to three frames late, and the runtime's predicted
    /// period follows the application's frame times a frame or more after that.
    pub stretch_settle_frames: u64,
}

impl Default for GovernorConfig {
    fn default() -> Self {
        GovernorConfig::for_refresh_hz(90.0)
    }
}

impl GovernorConfig {
    /// The default thresholds for a display at `hz` (period 1000 / hz ms).
    pub fn for_refresh_hz(hz: f64) -> GovernorConfig {
        GovernorConfig {
            period_ms: 1000.0 / hz,
            drop_above: 0.9,
            raise_below: 0.7,
            calm_frames_to_raise: 10,
            min_frames_between_raises: 8,
            drop_step: 2,
            raise_step: 1,
            settle_frames: 2,
            frontier_scale: 1.0,
            stretch_settle_frames: 8,
        }
    }

    /// Checks every value; the error (`Error::Input`) names the field and the value.
    pub fn validate(&self) -> Result<()> {
        let c = self;
        if !(c.period_ms.is_finite() && c.period_ms > 0.0) {
            return Err(Error::input(format!("governor period {} ms must be a positive finite number", c.period_ms)));
        }
        if !(c.raise_below.is_finite()
            && c.drop_above.is_finite()
            && 0.0 < c.raise_below
            && c.raise_below < c.drop_above)
        {
            return Err(Error::input(format!(
                "governor thresholds raise below {} and drop above {} must satisfy 0 < raise < drop",
                c.raise_below, c.drop_above
            )));
        }
        if c.calm_frames_to_raise == 0 || c.drop_step == 0 || c.raise_step == 0 {
            return Err(Error::input(format!(
                "governor calm frames {}, drop step {} and raise step {} must be at least 1",
                c.calm_frames_to_raise, c.drop_step, c.raise_step
            )));
        }
        if !(c.frontier_scale.is_finite() && c.frontier_scale > 0.0) {
            return Err(Error::input(format!(
                "governor frontier scale {} must be a positive finite number",
                c.frontier_scale
            )));
        }
        Ok(())
    }
}

/// One level change, for the run report and the panel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GovernorChange {
    /// The measured frame that triggered it; the change applies to the next frame the
    /// loop renders.
    pub frame: u64,
    /// [`Level::setting`] before and after.
    pub from: String,
    /// The level's setting after the change.
    pub to: String,
    /// The measured or predicted time and the threshold it crossed.
    pub reason: String,
    /// The display's refresh period (ms) the change was judged against.
    pub period_ms: f64,
    /// A raise's predicted frame time at the new level (ms, with the level's correction);
    /// `None` for a drop.
    pub predicted_ms: Option<f64>,
}

/// What the frame loop knows of one frame once its GPU time is back.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Observation {
    /// The whole frame's GPU time (both eyes), ms.
    pub gpu_ms: f64,
    /// The AO passes' share of it, when measured.
    pub ao_ms: Option<f64>,
    /// The display period the headset predicted for the frame (OpenXR's
    /// predictedDisplayPeriod), ms.
    pub predicted_period_ms: Option<f64>,
    /// How far (ms) the frame's GPU work finished after its predicted display time on the
    /// headset's clock (positive: it missed it); `None` where the headset has no clock.
    pub late_ms: Option<f64>,
}

#[derive(Clone, Copy, Debug)]
struct Sample {
    frame: u64,
    gpu_ms: f64,
    ao_ms: Option<f64>,
    /// The display period the headset predicted for the frame (ms), if it said.
    predicted_period_ms: Option<f64>,
    /// By how much the frame missed its display time (ms, > 0), if it did.
    late_ms: Option<f64>,
}

impl Sample {
    /// Refreshes of a display of period `refresh_ms` the frame's predicted period missed.
    fn missed(&self, refresh_ms: f64) -> u64 {
        self.predicted_period_ms.map_or(0, |p| crate::xr::missed_refreshes(p, refresh_ms))
    }
}

/// Frames a rising trend is fitted over.
const TREND_FRAMES: usize = 4;

/// The governor's state: the level in use and the recent frames measured at it.
#[derive(Clone, Debug)]
pub struct Governor {
    frontier: Frontier,
    config: GovernorConfig,
    level: usize,
    changes: Vec<GovernorChange>,
    /// Valid measurements at the current level, newest last.
    recent: VecDeque<Sample>,
    last_frame: Option<u64>,
    last_change_frame: Option<u64>,
    /// Per level: measured / predicted time of the first frame after the last raise into
    /// it (≥ 1), multiplied into later predictions for it.
    correction: Vec<f64>,
    /// After a raise: the uncorrected prediction, checked against its first frame.
    raise_check: Option<f64>,
}

impl Governor {
    /// Starts at `start_level` (clamped to the top); a bad configuration or an empty
    /// frontier is `Error::Input`.
    pub fn new(frontier: Frontier, config: GovernorConfig, start_level: usize) -> Result<Governor> {
        config.validate()?;
        if frontier.is_empty() {
            return Err(Error::input("the governor needs a frontier with at least one level"));
        }
        let level = start_level.min(frontier.top());
        let correction = vec![1.0; frontier.len()];
        Ok(Governor {
            frontier,
            config,
            level,
            changes: Vec::new(),
            recent: VecDeque::new(),
            last_frame: None,
            last_change_frame: None,
            correction,
            raise_check: None,
        })
    }

    /// Index of the current level in the frontier.
    pub fn level(&self) -> usize {
        self.level
    }

    /// The current level.
    pub fn current(&self) -> &Level {
        &self.frontier.levels[self.level]
    }

    /// Every change made so far, in order.
    pub fn changes(&self) -> &[GovernorChange] {
        &self.changes
    }

    /// The frontier the governor moves along.
    pub fn frontier(&self) -> &Frontier {
        &self.frontier
    }

    /// The thresholds it runs with.
    pub fn config(&self) -> &GovernorConfig {
        &self.config
    }

    /// Follows the display: from now on frames are judged against `period_ms`, the
    /// display's refresh period (which may change at any frame: a Quest switching between
    /// 72, 90 and 120 Hz). Never a period the runtime predicted for a frame and stretched
    /// because frames were late: give that to [`Governor::observe_paced`].
    /// The frames measured so far stay: a shorter period drops on the next frame over
    /// it, a longer one raises as soon as the calm frames fit. A non-positive or
    /// non-finite period is ignored (returns false); returns whether the period changed.
    pub fn set_period_ms(&mut self, period_ms: f64) -> bool {
        if !(period_ms.is_finite() && period_ms > 0.0) || period_ms == self.config.period_ms {
            return false;
        }
        self.config.period_ms = period_ms;
        true
    }

    /// Feeds the whole frame's GPU time (both eyes) of frame `frame`; returns the change
    /// to apply from the next frame the loop renders, if any. Frames must come in order
    /// (an earlier or repeated one is ignored) and may come late; the measurements of the
    /// `settle_frames` frames after a change's `frame` are ignored, so a loop whose times
    /// arrive later than that must raise it.
    pub fn observe(&mut self, frame: u64, gpu_ms: f64) -> Option<GovernorChange> {
        self.observe_paced(frame, gpu_ms, None, None)
    }

    /// [`Governor::observe`] with the AO passes' measured share of `gpu_ms`, which makes
    /// the raise prediction exact where the AO cost follows the frontier's ratios.
    pub fn observe_with_ao(&mut self, frame: u64, gpu_ms: f64, ao_ms: f64) -> Option<GovernorChange> {
        self.observe_paced(frame, gpu_ms, Some(ao_ms), None)
    }

    /// [`Governor::observe`] with the AO share when measured, and the display period the
    /// headset predicted for the frame (OpenXR's predictedDisplayPeriod). A predicted
    /// period spanning more than one refresh of the display ([`crate::xr::missed_refreshes`]
    /// against the governor's period) means frames were late: the frame drops like one
    /// over 90 % (unless within [`GovernorConfig::stretch_settle_frames`] of a change) and
    /// never counts as calm.
    pub fn observe_paced(
        &mut self,
        frame: u64,
        gpu_ms: f64,
        ao_ms: Option<f64>,
        predicted_period_ms: Option<f64>,
    ) -> Option<GovernorChange> {
        self.observe_frame(frame, Observation { gpu_ms, ao_ms, predicted_period_ms, late_ms: None })
    }

    /// [`Governor::observe_paced`] with whether the frame missed its predicted display
    /// time on the headset's clock ([`Observation::late_ms`] above 0): a late frame
    /// drops like one over 90 % (unless within [`GovernorConfig::stretch_settle_frames`]
    /// of a change: the frames queued before it still finish late) and never counts as
    /// calm.
    pub fn observe_frame(&mut self, frame: u64, o: Observation) -> Option<GovernorChange> {
        let gpu_ms = o.gpu_ms;
        let ao_ms = o.ao_ms.filter(|ms| ms.is_finite()).map(|ms| ms.clamp(0.0, gpu_ms.max(0.0)));
        let predicted_period_ms = o.predicted_period_ms.filter(|ms| ms.is_finite() && *ms > 0.0);
        let late_ms = o.late_ms.filter(|ms| ms.is_finite() && *ms > 0.0);
        self.observe_sample(Sample { frame, gpu_ms, ao_ms, predicted_period_ms, late_ms })
    }

    /// The frame time predicted at level `to` from a frame `s` measured at the current
    /// level (without the correction factor).
    fn predict(&self, s: &Sample, to: usize) -> f64 {
        let (from, to) = (&self.frontier.levels[self.level], &self.frontier.levels[to]);
        let ao = s.ao_ms.unwrap_or(2.0 * from.ms_per_eye * self.config.frontier_scale).min(s.gpu_ms);
        (s.gpu_ms - ao) + ao * to.ms_per_eye / from.ms_per_eye
    }

    fn observe_sample(&mut self, s: Sample) -> Option<GovernorChange> {
        if !(s.gpu_ms.is_finite() && s.gpu_ms >= 0.0) || self.last_frame.is_some_and(|f| s.frame <= f) {
            return None;
        }
        self.last_frame = Some(s.frame);
        if self.last_change_frame.is_some_and(|f| s.frame <= f + self.config.settle_frames) {
            return None;
        }
        if let Some(predicted) = self.raise_check.take() {
            self.correction[self.level] = (s.gpu_ms / predicted.max(1e-9)).max(1.0);
        }
        self.recent.push_back(s);
        while self.recent.len() > self.config.calm_frames_to_raise.max(TREND_FRAMES) {
            self.recent.pop_front();
        }
        let c = &self.config;
        let (period, drop_ms, calm_ms) = (c.period_ms, c.drop_above * c.period_ms, c.raise_below * c.period_ms);
        if self.level > 0 {
            let to = self.level.saturating_sub(c.drop_step);
            if s.gpu_ms > drop_ms {
                let reason = format!("frame {:.2} ms > {:.0} % of {:.2} ms", s.gpu_ms, c.drop_above * 100.0, period);
                return Some(self.change(s.frame, to, reason, None));
            }
            let missed = s.missed(period);
            let settled = self.last_change_frame.is_none_or(|f| s.frame > f + c.stretch_settle_frames);
            if let (true, Some(predicted)) = (missed > 0 && settled, s.predicted_period_ms) {
                let reason = format!(
                    "display period {predicted:.2} ms stretched over {} refreshes of {period:.2} ms ({missed} missed)",
                    missed + 1
                );
                return Some(self.change(s.frame, to, reason, None));
            }
            if let (true, Some(late)) = (settled, s.late_ms) {
                let reason =
                    format!("frame {:.2} ms missed its display time by {late:.2} ms (headset clock)", s.gpu_ms);
                return Some(self.change(s.frame, to, reason, None));
            }
            if let Some(reason) = self.trend_overrun() {
                return Some(self.change(s.frame, to, reason, None));
            }
        }
        let c = &self.config;
        let to = (self.level + c.raise_step).min(self.frontier.top());
        // Calm: under 70 % of the display's period, and shown at the display's rate (a
        // stretched period or a late frame means refreshes were missed, whatever the GPU
        // time).
        let calm = self.recent.len() >= c.calm_frames_to_raise
            && self
                .recent
                .iter()
                .rev()
                .take(c.calm_frames_to_raise)
                .all(|r| r.gpu_ms < calm_ms && r.missed(period) == 0 && r.late_ms.is_none());
        let spaced = self.last_change_frame.is_none_or(|f| s.frame >= f + c.min_frames_between_raises);
        if to == self.level || !calm || !spaced {
            return None;
        }
        // The worst calm frame's prediction: a raise must fit all of them.
        let calm_frames = || self.recent.iter().rev().take(self.config.calm_frames_to_raise);
        let predicted = calm_frames().map(|r| self.predict(r, to)).fold(0.0, f64::max);
        let slowest = calm_frames().map(|r| r.gpu_ms).fold(0.0, f64::max);
        let corrected = predicted * self.correction[to];
        if corrected >= drop_ms {
            return None;
        }
        let c = &self.config;
        let reason = format!(
            "{} < {:.0} % of {:.2} ms (slowest {:.2} ms); predicted {:.2} ms < {:.0} % of {:.2} ms",
            crate::formats::output::count(c.calm_frames_to_raise as u64, "frame"),
            c.raise_below * 100.0,
            period,
            slowest,
            corrected,
            c.drop_above * 100.0,
            period
        );
        let change = self.change(s.frame, to, reason, Some(corrected));
        self.raise_check = Some(predicted);
        Some(change)
    }

    /// A drop reason when the last frames rise steadily enough to cross the period by the
    /// first frame a change made now can reach (the frames in flight are already sent).
    fn trend_overrun(&self) -> Option<String> {
        if self.recent.len() < TREND_FRAMES {
            return None;
        }
        let last: Vec<&Sample> = self.recent.iter().skip(self.recent.len() - TREND_FRAMES).collect();
        if !last.windows(2).all(|w| w[1].gpu_ms > w[0].gpu_ms) {
            return None;
        }
        let (first, newest) = (last[0], last[TREND_FRAMES - 1]);
        let slope = (newest.gpu_ms - first.gpu_ms) / (newest.frame - first.frame).max(1) as f64;
        let ahead = self.config.settle_frames + 1;
        let predicted = newest.gpu_ms + slope * ahead as f64;
        (predicted > self.config.period_ms).then(|| {
            format!(
                "frames rising {:.2} → {:.2} ms predict {predicted:.2} ms > {:.2} ms in {ahead} frames",
                first.gpu_ms, newest.gpu_ms, self.config.period_ms
            )
        })
    }

    fn change(&mut self, frame: u64, to: usize, reason: String, predicted_ms: Option<f64>) -> GovernorChange {
        let change = GovernorChange {
            frame,
            from: self.frontier.levels[self.level].setting.clone(),
            to: self.frontier.levels[to].setting.clone(),
            reason,
            period_ms: self.config.period_ms,
            predicted_ms,
        };
        self.level = to;
        self.last_change_frame = Some(frame);
        self.recent.clear();
        self.raise_check = None;
        self.changes.push(change.clone());
        change
    }
}

#[cfg(test)]
mod tests;
