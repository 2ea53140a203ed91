//! What a run did (`vrao run --report`), summarized from the frame loop once it ended.

use crate::app::governor::GovernorChange;
use crate::app::{FrameLoop, SERIAL_EVERY};
use crate::formats::output::{count, significant};
use crate::formats::spans::{summarize, RightEyeTilesReport};
use crate::stats;
use std::sync::atomic::Ordering;
use vrao_ao::AoSettings;

/// What a run did (`vrao run --report`): frames rendered and in flight, the frame budget
/// and how often it was missed, the headset's counters and per-pass medians.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunSummary {
    /// The headset's name (simulated profile or OpenXR runtime and system).
    pub headset: String,
    /// The GPU adapter's name.
    pub adapter: String,
    /// Frames rendered and handed to the headset.
    pub frames_rendered: u64,
    /// The most frames the GPU worked on at once, and the limit.
    pub frames_in_flight_max: usize,
    /// The renderer's limit on frames in flight.
    pub frames_in_flight_limit: usize,
    /// The display's refresh period (ms) at the end of the run: the frame budget each
    /// frame's GPU time is judged against (the period when the frame was rendered).
    pub budget_ms: f64,
    /// Which rate governed the budget and where it came from: the OpenXR runtime's
    /// refresh rate (XR_FB_display_refresh_rate) or shortest predicted display period,
    /// the simulated headset's refresh rate, or the profile's while no frame came.
    pub budget_source: String,
    /// The shortest refresh period of the run (ms).
    pub budget_ms_min: f64,
    /// The longest refresh period of the run (ms).
    pub budget_ms_max: f64,
    /// How often the refresh period changed during the run.
    pub budget_changes: u64,
    /// Frames the headset predicted a display period for spanning more than one refresh
    /// (an OpenXR runtime stretches it when frames are late): each missed a refresh or
    /// more, and each is a reason for the governor to lower, never to raise.
    pub stretched_frames: u64,
    /// Timed frames whose GPU time exceeded `budget_ms`.
    pub over_budget_frames: u64,
    /// Frames whose GPU time came back.
    pub timed_frames: u64,
    /// Timed frames whose GPU work finished (seen done, or else at the earliest) after
    /// their predicted display time on the headset's clock: shown late (or dropped) by the
    /// runtime, whatever their GPU time against the budget.
    pub late_frames: u64,
    /// Timed frames judged so: 0 where the headset gives no clock (`late_clock` says why).
    pub clocked_frames: u64,
    /// The clock frames were judged late against, or why none was.
    pub late_clock: String,
    /// Medians over the run ([`crate::stats`]; 0 when no frame was timed): GPU
    /// time per frame (both eyes), CPU encode time per frame, and their ratio.
    pub gpu_frame_ms_median: f64,
    /// Median CPU encode time per frame (ms).
    pub cpu_encode_ms_median: f64,
    /// `cpu_encode_ms_median` / `gpu_frame_ms_median`.
    pub cpu_encode_share_of_gpu: f64,
    /// How the passes were timed: pipelined, and on a CPU adapter every
    /// [`SERIAL_EVERY`]th frame serial (one submission per pass).
    pub timing: String,
    /// The simulated compositor's frame counters (submitted, presented, reprojected,
    /// dropped, latency); `None` for an OpenXR session, whose runtime does not say what it
    /// presented or reprojected (see `openxr` for what it does say). After a lost OpenXR
    /// session, the simulated headset's counters from then on.
    pub counters: Option<crate::xr::FrameCounters>,
    /// (pass, median GPU ms for both eyes) over the recent frames.
    pub pass_medians_ms: Vec<(String, f64)>,
    /// Whether Ctrl-C or SIGTERM (the session's interrupt flag) ended the run.
    pub interrupted: bool,
    /// The session state the run was in when it was interrupted (OpenXR: the
    /// XrSessionState, e.g. `FOCUSED`, `IDLE`; the simulated headset: `running`).
    pub interrupted_in: Option<String>,
    /// The budget governor: on or off, every change it made, and the AO setting the run
    /// ended with.
    pub governor: String,
    /// Every change the governor made, in order.
    pub governor_changes: Vec<GovernorChange>,
    /// The AO setting of the last frame, e.g. `gtao N=24 r=0.3 m half`.
    pub final_ao_setting: String,
    /// The OpenXR session's states, layers and loss reason (OpenXR headsets only).
    pub openxr: Option<crate::xr::openxr::OpenXrReport>,
    /// Why the run was refused before its headset or window opened (the command exits
    /// 2): the report is written anyway when one was asked for. `None` for a run.
    pub refused: Option<String>,
    /// The lens's visibility mask: where it comes from, and whether the passes skipped
    /// it (`--mask`); "none" for a headset without one.
    pub visibility_mask: String,
    /// The share of each eye's pixels the mask hid in the last frame (left, right; empty
    /// with `--mask off`, without a mask or without a frame).
    pub hidden_share_per_eye: Vec<f64>,
    /// Per pass, the right eye's tiles computed rather than copied from the left eye in
    /// the last frame, read back from the indirect dispatches once the run has ended;
    /// empty where the right eye reused nothing.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub right_eye_tiles: Vec<RightEyeTilesReport>,
}

impl RunSummary {
    /// Summarizes the loop as it stands (call it when the loop has ended).
    pub fn of(frame_loop: &FrameLoop) -> RunSummary {
        let gpu_frame_ms_median = stats::median(&frame_loop.gpu_frame_ms).unwrap_or(0.0);
        let openxr = frame_loop.headset.openxr_report();
        let interrupted = frame_loop.exit_requested.load(Ordering::Relaxed);
        // The loop saw the interrupt before a frame, or the OpenXR headset saw it while
        // it waited for the runtime.
        let interrupted_in = frame_loop
            .interrupted_in
            .clone()
            .or_else(|| openxr.as_ref().and_then(|r| r.interrupted_in.clone()))
            .or_else(|| interrupted.then(|| frame_loop.headset.session_state()));
        let simulated_counters = openxr.as_ref().is_none_or(|r| r.fell_back);
        let cpu_encode_ms_median = stats::median(&frame_loop.cpu_encode_ms).unwrap_or(0.0);
        RunSummary {
            headset: frame_loop.headset.describe(),
            adapter: frame_loop.gpu.info.name.clone(),
            frames_rendered: frame_loop.frames,
            frames_in_flight_max: frame_loop.renderer.frames_in_flight_max(),
            frames_in_flight_limit: frame_loop.renderer.frames_in_flight_limit(),
            budget_ms: frame_loop.budget_ms,
            budget_source: frame_loop.headset.display_rate_source(),
            budget_ms_min: frame_loop.budget_range_ms.0,
            budget_ms_max: frame_loop.budget_range_ms.1,
            budget_changes: frame_loop.budget_changes,
            stretched_frames: frame_loop.stretched_frames,
            over_budget_frames: frame_loop.over_budget_frames,
            timed_frames: frame_loop.timed_frames,
            late_frames: frame_loop.late_frames,
            clocked_frames: frame_loop.clocked_frames,
            // Judged while the session ran: a runtime's clock is gone once it has ended.
            late_clock: if frame_loop.clocked_frames > 0 {
                "the headset's clock (each frame's work seen done by a thread waiting on it)".into()
            } else {
                format!("none: {}", frame_loop.headset.no_clock_reason())
            },
            gpu_frame_ms_median,
            cpu_encode_ms_median,
            cpu_encode_share_of_gpu: if gpu_frame_ms_median > 0.0 {
                cpu_encode_ms_median / gpu_frame_ms_median
            } else {
                0.0
            },
            timing: if frame_loop.cpu_adapter() {
                format!("pipelined; every {SERIAL_EVERY}th frame serial for the per-pass medians (CPU adapter)")
            } else {
                "pipelined".into()
            },
            counters: simulated_counters.then(|| frame_loop.headset.counters()),
            pass_medians_ms: pass_medians(frame_loop),
            interrupted,
            interrupted_in,
            governor: if frame_loop.governor.is_some() { "on" } else { "off" }.into(),
            governor_changes: frame_loop.governor.as_ref().map(|g| g.changes().to_vec()).unwrap_or_default(),
            final_ao_setting: ao_setting(&frame_loop.renderer.settings().ao),
            openxr,
            refused: None,
            visibility_mask: mask_description(
                frame_loop.headset.visibility_mask(),
                frame_loop.renderer.settings().ao.mask,
            ),
            hidden_share_per_eye: frame_loop.renderer.hidden_share().iter().copied().filter(|s| *s > 0.0).collect(),
            right_eye_tiles: frame_loop.renderer.right_eye_tiles().iter().map(RightEyeTilesReport::from).collect(),
        }
    }

    /// The summary of a session interrupted (in `state`) before its first frame: the
    /// headset opened and was ended, nothing was rendered.
    pub fn before_frames(
        headset: &dyn crate::xr::Headset,
        gpu: &vrao_ao::plug::Gpu,
        settings: &vrao_render::settings::Settings,
        state: String,
        frames_in_flight: usize,
    ) -> RunSummary {
        let openxr = headset.openxr_report();
        // The display's rate where the headset knows it (an OpenXR runtime's reported
        // rate); otherwise the profile's, and the source says so.
        let budget_ms = headset.refresh_period_ms().filter(|ms| ms.is_finite() && *ms > 0.0);
        let budget_ms = budget_ms.unwrap_or(settings.profile.budget_ms());
        RunSummary {
            frames_in_flight_limit: frames_in_flight,
            counters: openxr.as_ref().is_none_or(|r| r.fell_back).then(|| headset.counters()),
            interrupted: true,
            interrupted_in: Some(state),
            final_ao_setting: ao_setting(&settings.ao),
            openxr,
            ..RunSummary::nothing_rendered(
                headset.describe(),
                gpu.info.name.clone(),
                budget_ms,
                headset.display_rate_source(),
            )
        }
    }

    /// What every run that rendered no frame reports alike: no frames, no timings, the
    /// budget it would have had, the governor not started.
    fn nothing_rendered(headset: String, adapter: String, budget_ms: f64, budget_source: String) -> RunSummary {
        RunSummary {
            headset,
            adapter,
            frames_rendered: 0,
            frames_in_flight_max: 0,
            frames_in_flight_limit: 0,
            budget_ms,
            budget_source,
            budget_ms_min: budget_ms,
            budget_ms_max: budget_ms,
            budget_changes: 0,
            stretched_frames: 0,
            over_budget_frames: 0,
            timed_frames: 0,
            late_frames: 0,
            clocked_frames: 0,
            late_clock: "none: no frame was rendered".into(),
            gpu_frame_ms_median: 0.0,
            cpu_encode_ms_median: 0.0,
            cpu_encode_share_of_gpu: 0.0,
            timing: "no frame was rendered".into(),
            counters: None,
            pass_medians_ms: Vec::new(),
            interrupted: false,
            interrupted_in: None,
            governor: "not started".into(),
            governor_changes: Vec::new(),
            final_ao_setting: String::new(),
            openxr: None,
            refused: None,
            visibility_mask: "none".into(),
            hidden_share_per_eye: Vec::new(),
            right_eye_tiles: Vec::new(),
        }
    }

    /// The report of a run refused before its headset or window opened, for `why` (one
    /// line): nothing was rendered; the budget is the profile's (`profile`, with the
    /// `--refresh` given) where it names one, 0 otherwise.
    pub fn refused(profile: Option<&vrao_render::HeadsetProfile>, why: &str) -> RunSummary {
        let budget_ms = profile.map_or(0.0, |p| p.budget_ms());
        let budget_source = match profile {
            Some(p) => {
                format!("the '{}' profile's {} Hz (the run was refused before a headset opened)", p.name, p.refresh_hz)
            }
            None => "none (the run was refused before a headset opened)".into(),
        };
        RunSummary {
            refused: Some(why.to_string()),
            ..RunSummary::nothing_rendered(
                "none (the run was refused before a headset opened)".into(),
                "none".into(),
                budget_ms,
                budget_source,
            )
        }
    }

    /// The summary as the few lines `vrao run` prints.
    pub fn to_text(&self) -> String {
        let passes: Vec<String> = self.pass_medians_ms.iter().map(|(p, ms)| format!("{p} {ms:.2}")).collect();
        let mut frames =
            format!("frames: {} rendered (up to {} in flight)", self.frames_rendered, self.frames_in_flight_max);
        if let Some(x) = &self.openxr {
            // Only what OpenXR says: nothing here is "presented" or "reprojected".
            frames += &format!(
                "; OpenXR: {} submitted, {} the runtime said not to render, {} missed (from predicted display times)",
                count(x.layers_submitted, "layer"),
                count(x.not_rendered, "frame"),
                count(x.missed_display_periods, "display period")
            );
        }
        if let Some(c) = &self.counters {
            let after = if self.openxr.is_some() { " (simulated headset, after the loss)" } else { "" };
            frames += &format!(
                "; {} submitted{after}; vsyncs: {} presented, {} reprojected; {} dropped; latency median {:.1} ms, p95 {:.1} ms",
                c.submitted, c.presented, c.reprojected, c.dropped, c.latency_median_ms, c.latency_p95_ms
            );
        }
        let stretched = if self.stretched_frames > 0 {
            format!("; {} at a display period stretched over missed refreshes", count(self.stretched_frames, "frame"))
        } else {
            String::new()
        };
        let late = if self.clocked_frames > 0 {
            format!(
                "; {} of {} late (finished after their predicted display time on the headset's clock)",
                self.late_frames,
                count(self.clocked_frames, "frame")
            )
        } else {
            format!("; late frames not judged ({})", self.late_clock)
        };
        let budget = if self.budget_changes > 0 {
            format!(
                "a {:.2} ms budget ({:.2}..{:.2} ms, {}) from {}",
                self.budget_ms,
                self.budget_ms_min,
                self.budget_ms_max,
                count(self.budget_changes, "change"),
                self.budget_source
            )
        } else {
            format!("a {:.2} ms budget from {}", self.budget_ms, self.budget_source)
        };
        let mask = if self.hidden_share_per_eye.is_empty() {
            format!("visibility mask {}\n", self.visibility_mask)
        } else {
            let shares: Vec<String> = self.hidden_share_per_eye.iter().map(|s| format!("{:.1} %", s * 100.0)).collect();
            format!("visibility mask {}; hidden per eye: {}\n", self.visibility_mask, shares.join(", "))
        };
        let right_eye = if self.right_eye_tiles.is_empty() {
            String::new()
        } else {
            let shares: Vec<String> =
                self.right_eye_tiles.iter().map(|t| format!("{} {:.1} %", t.pass, t.share * 100.0)).collect();
            format!("right eye computed (not copied from the left), share of its tiles: {}\n", shares.join(", "))
        };
        let interrupted = match &self.interrupted_in {
            Some(state) if self.interrupted => format!("\ninterrupted in {state}"),
            _ => String::new(),
        };
        format!(
            "governor {}: {}, AO setting at the end: {}\n{mask}{right_eye}{frames}\nGPU per frame: median {:.2} ms against {budget}, {} of {} over{stretched}{late}; CPU encode median {:.3} ms ({:.1} % of the GPU time)\npass medians (ms, both eyes, {} timing): {}{interrupted}",
            self.governor,
            count(self.governor_changes.len() as u64, "change"),
            self.final_ao_setting,
            self.gpu_frame_ms_median,
            self.over_budget_frames,
            count(self.timed_frames, "timed frame"),
            self.cpu_encode_ms_median,
            100.0 * self.cpu_encode_share_of_gpu,
            self.timing,
            passes.join(", ")
        )
    }
}

/// The mask's source in one line, and whether the passes skip it.
fn mask_description(mask: Option<&vrao_ao::VisibilityMask>, on: bool) -> String {
    let Some(mask) = mask else { return "none (the headset gives no visibility mask)".into() };
    let sources: Vec<&str> = mask.views.iter().map(|v| v.source.as_str()).collect();
    let source = if sources.windows(2).all(|w| w[0] == w[1]) { sources[..1].join("") } else { sources.join("; ") };
    let applied = if on { "applied" } else { "not applied (--mask off)" };
    format!("{applied}: {source}")
}

/// (pass, median GPU ms) over the recent frames; on a CPU adapter over the frames timed
/// pass by pass, whose per-pass times are the true ones there.
fn pass_medians(frame_loop: &FrameLoop) -> Vec<(String, f64)> {
    let frames = &frame_loop.history.frames;
    let serial_only = frames.iter().any(|f| f.serial);
    let spans: Vec<Vec<(String, f64)>> =
        frames.iter().filter(|f| !serial_only || f.serial).map(|f| f.spans.clone()).collect();
    summarize(&spans).into_iter().map(|s| (s.label, s.median_ms)).collect()
}

/// The AO setting in one line, as bench files write theirs: `gtao temporal N=24 r=0.3 m half`.
fn ao_setting(ao: &AoSettings) -> String {
    let temporal = if ao.temporal.enabled { " temporal" } else { "" };
    let r = significant(ao.radius as f64, 3);
    let resolution = ao.resolution;
    format!("{}{temporal} N={} r={r} m {resolution}", ao.technique.name(), ao.samples)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ao_setting_names_technique_samples_radius_and_resolution() {
        let mut ao =
            AoSettings { samples: 24, radius: 0.3, resolution: vrao_ao::Resolution::Half, ..AoSettings::default() };
        ao.temporal.enabled = true;
        assert_eq!(ao_setting(&ao), format!("{} temporal N=24 r=0.3 m half", ao.technique.name()));
        ao.resolution = vrao_ao::Resolution::Full;
        ao.temporal.enabled = false;
        assert!(ao_setting(&ao).ends_with("N=24 r=0.3 m full"), "{}", ao_setting(&ao));
    }
}
