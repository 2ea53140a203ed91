//! Headsets the render loop drives: the real one through OpenXR (`openxr.rs`) and the
//! simulated one (`simulated.rs`) that always runs, with a compositor that reprojects the
//! newest frame when a new one misses its vsync (`reproject.rs`, `compositor.rs`).

pub mod openxr;
pub mod profiles;
pub mod simulated;

use crate::error::Result;
use serde::Serialize;
use vrao_ao::plug::{Gpu, LayeredTarget};
use vrao_ao::EyePair;

/// One frame the headset asks the application to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRequest {
    /// The frame's number, counting from 0 in the order the headset handed frames out.
    pub index: u64,
    /// When the frame's photons are predicted to reach the eyes, in seconds on the
    /// headset's clock; the eye poses are predicted for this time.
    pub display_time: f64,
    /// Both eyes' poses and fields of view, predicted for `display_time`.
    pub eyes: EyePair,
    /// Per-eye size the headset wants, in pixels.
    pub size: (u32, u32),
    /// False when the headset will not show this frame (OpenXR's shouldRender): the
    /// application submits without rendering.
    pub should_render: bool,
    /// The display period the headset predicts for this frame (ms): OpenXR's
    /// predictedDisplayPeriod, the simulated headset's refresh interval. A runtime
    /// stretches it to whole refreshes when the application's frames are late (Monado:
    /// 100 ms on a 50 ms display), so it is not the budget: a period longer than
    /// `refresh_period_ms` means missed refreshes. `None` while the headset has not said.
    pub display_period_ms: Option<f64>,
    /// The display's refresh period (ms), the frame budget: the runtime's refresh rate
    /// (XR_FB_display_refresh_rate) where it offers one, else the shortest predicted
    /// display period so far ([`DisplayRate`]); the simulated headset's refresh interval.
    /// `None` while unknown (the profile's rate stands).
    pub refresh_period_ms: Option<f64>,
}

/// Refreshes of a display with period `refresh_ms` that a frame period of `period_ms`
/// skips: the whole refreshes it spans beyond the first, rounded (a 100 ms period on a
/// 50 ms display misses 1, 150 ms misses 2, 70 ms none: jitter, not a miss). 0 when
/// either is not a positive finite number.
pub fn missed_refreshes(period_ms: f64, refresh_ms: f64) -> u64 {
    if !(period_ms.is_finite() && refresh_ms.is_finite() && period_ms > 0.0 && refresh_ms > 0.0) {
        return 0;
    }
    ((period_ms / refresh_ms).round() as u64).saturating_sub(1)
}

/// The display's refresh period as a runtime tells it, and the refreshes missed between
/// the frames it hands out. The refresh rate the runtime reports (XR_FB_display_refresh_rate)
/// wins; without one, the shortest predicted display period seen so far stands for it,
/// never a longer one (a runtime stretches its predicted period when frames are late),
/// and never the period predicted for the first frame, before any frame was shown
/// (Monado predicts 16 ms there and 50 ms after it on its 20 Hz display: the budget
/// locked at 16 ms and counted every frame late).
/// Pure bookkeeping: the OpenXR headset feeds it each frame's predicted display time and
/// period.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DisplayRate {
    /// The rate the runtime reports (Hz), when it has the extension.
    reported_hz: Option<f64>,
    /// The shortest predicted display period seen (ms).
    shortest_ms: Option<f64>,
    /// The previous frame's predicted display time (ns); `None` before the first frame.
    last_display_ns: Option<i64>,
    /// Refreshes missed so far.
    missed: u64,
}

impl DisplayRate {
    /// No rate reported, no frame seen.
    pub fn new() -> DisplayRate {
        DisplayRate::default()
    }

    /// The refresh rate the runtime reports (at the start, and at each change event); a
    /// rate that is not a positive finite number is ignored.
    pub fn set_reported_hz(&mut self, hz: Option<f32>) {
        if let Some(hz) = hz.map(f64::from).filter(|hz| hz.is_finite() && *hz > 0.0) {
            self.reported_hz = Some(hz);
        }
    }

    /// One frame the runtime handed out: its predicted display time and period (ns).
    /// Returns the refreshes missed since the previous frame (the gap between their
    /// display times in refreshes, beyond one).
    pub fn frame(&mut self, display_time_ns: i64, predicted_period_ns: i64) -> u64 {
        // The first frame's period is a guess made before the display ran.
        if predicted_period_ns > 0 && self.last_display_ns.is_some() {
            let ms = predicted_period_ns as f64 / 1e6;
            self.shortest_ms = Some(self.shortest_ms.map_or(ms, |s| s.min(ms)));
        }
        let missed = match (self.last_display_ns, self.period_ms()) {
            (Some(last), Some(refresh_ms)) if display_time_ns > last => {
                missed_refreshes((display_time_ns - last) as f64 / 1e6, refresh_ms)
            }
            _ => 0,
        };
        self.last_display_ns = Some(display_time_ns);
        self.missed += missed;
        missed
    }

    /// The display's refresh period (ms): the reported rate's, else the shortest
    /// predicted period seen; `None` before either.
    pub fn period_ms(&self) -> Option<f64> {
        self.reported_hz.map(|hz| 1000.0 / hz).or(self.shortest_ms)
    }

    /// Refreshes missed between the frames seen so far.
    pub fn missed(&self) -> u64 {
        self.missed
    }

    /// Where [`DisplayRate::period_ms`] comes from, in words; `None` before it is known.
    pub fn source(&self) -> Option<String> {
        match (self.reported_hz, self.shortest_ms) {
            (Some(hz), _) => Some(format!("the display's refresh rate, {hz} Hz (XR_FB_display_refresh_rate)")),
            (None, Some(_)) => Some(
                "the shortest display period the runtime predicted (xrWaitFrame; it offers no \
                 XR_FB_display_refresh_rate)"
                    .into(),
            ),
            (None, None) => None,
        }
    }
}

/// What the application hands to the headset: both eyes' colour and depth (2-layer
/// targets, layer 0 = left) and the eyes they were rendered for.
pub struct SubmittedFrame<'a> {
    /// Colour, sRGB-encoded, one layer per eye.
    pub color: &'a LayeredTarget,
    /// Reversed-Z depth (infinite far plane), one layer per eye; the positional warp reads it.
    pub depth: &'a LayeredTarget,
    /// The eyes the frame was rendered for.
    pub eyes: &'a EyePair,
    /// Near plane (m) the depth was rendered with.
    pub near: f64,
}

/// The time (headset clock, s) by which a frame's GPU work was finished at the earliest:
/// its work started no earlier than it was submitted (`submitted_at`) and than the frame
/// before it finished (`previous_finish`: the GPU runs frames one after another), and took
/// `gpu_ms`. A lower bound, so that a frame counted late surely was.
pub fn earliest_finish(submitted_at: f64, previous_finish: Option<f64>, gpu_ms: f64) -> f64 {
    let start = previous_finish.filter(|f| f.is_finite()).map_or(submitted_at, |f| f.max(submitted_at));
    start + gpu_ms.max(0.0) / 1e3
}

/// Frame timing counters, as SteamVR's frame timing reports them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameCounters {
    /// Vsyncs that showed a new frame rendered for exactly that vsync.
    pub presented: u64,
    /// Vsyncs that showed an older frame warped to the vsync's pose (no new frame was
    /// ready in time, or the one shown was rendered for an earlier vsync).
    pub reprojected: u64,
    /// Submitted frames that never reached the display (a newer one replaced them).
    pub dropped: u64,
    /// Frames the application submitted.
    pub submitted: u64,
    /// Latency from pose sampling to display, over displayed vsyncs (ms).
    pub latency_median_ms: f64,
    /// 95th percentile of the same latency (ms).
    pub latency_p95_ms: f64,
}

impl FrameCounters {
    /// Sets the latency median and 95th percentile from the latency samples (ms), by
    /// [`crate::stats`]'s one definition whichever headset measured them; with
    /// no samples both stay as they are (0 before any frame was shown).
    pub fn set_latency(&mut self, samples_ms: &[f64]) {
        let sorted = crate::stats::Sorted::new(samples_ms.iter().copied());
        if let (Some(median), Some(p95)) = (sorted.median(), sorted.quantile(0.95)) {
            (self.latency_median_ms, self.latency_p95_ms) = (median, p95);
        }
    }
}

/// The headset interface `vrao run` drives; the OpenXR and simulated headsets both
/// implement it.
pub trait Headset {
    /// One line: what this headset is (runtime name, system, profile).
    fn describe(&self) -> String;
    /// Per-eye size the headset recommends.
    fn recommended_size(&self) -> (u32, u32);
    /// Blocks until the application should start the next frame and returns it, or `None`
    /// when the session has ended (the user quit, or the runtime is exiting).
    fn wait_frame(&mut self, gpu: &Gpu) -> Result<Option<FrameRequest>>;
    /// Records what the headset does with a frame's eyes (a copy, say) into the
    /// frame's own encoder, before the frame is submitted; `submit` then need not
    /// submit that work on its own. Headsets that copy in `submit` leave this empty.
    fn record_frame(
        &mut self,
        _gpu: &Gpu,
        _encoder: &mut wgpu::CommandEncoder,
        _request: &FrameRequest,
        _color: &LayeredTarget,
        _depth: &LayeredTarget,
    ) {
    }
    /// Hands over the rendered frame (or `None` when `should_render` was false).
    fn submit(&mut self, gpu: &Gpu, request: &FrameRequest, frame: Option<SubmittedFrame>) -> Result<()>;
    /// What the headset's display shows now (the compositor's output), if it can be read:
    /// the desktop mirror shows this.
    fn display_image(&self) -> Option<&LayeredTarget> {
        None
    }
    /// The counters so far (the run summary prints them).
    fn counters(&self) -> FrameCounters;
    /// Asks the session to end (the user quit): the following `wait_frame` calls return
    /// `None` once the headset has wound down (OpenXR: xrRequestExitSession, then
    /// STOPPING → xrEndSession → EXITING; at once when the session is not running).
    fn request_exit(&mut self);
    /// The state the session is in, in words (OpenXR: the XrSessionState name), for the
    /// report of an interrupted run.
    fn session_state(&self) -> String {
        "running".into()
    }
    /// Where the budget, the display's refresh period ([`FrameRequest::refresh_period_ms`],
    /// [`Headset::refresh_period_ms`]), comes from, for the report. Before the headset
    /// knows it (an OpenXR runtime without XR_FB_display_refresh_rate before its first
    /// frame) it says so: the profile's rate stands then.
    fn display_rate_source(&self) -> String;
    /// The display's refresh period (ms) as far as the headset knows it now: an OpenXR
    /// runtime's reported rate or shortest predicted period, the simulated headset's
    /// refresh interval; `None` before it knows.
    fn refresh_period_ms(&self) -> Option<f64>;
    /// The headset's clock now, in seconds on the clock of [`FrameRequest::display_time`]
    /// (an OpenXR runtime's XrTime through XR_KHR_convert_timespec_time, the simulated
    /// headset's real-time clock), against which a frame's lateness is judged; `None`
    /// where it cannot be read, or is not the clock the GPU's work runs on (the simulated
    /// headset in virtual time, whose compositor judges its frames itself).
    fn now(&self) -> Option<f64> {
        None
    }
    /// Where [`Headset::now`] is `None`: why, for the report.
    fn no_clock_reason(&self) -> String {
        "the headset gives no clock".into()
    }
    /// What the OpenXR session did (`None` for headsets that are not OpenXR). An
    /// OpenXR headset that fell back to the simulated one still reports, with the loss.
    fn openxr_report(&self) -> Option<crate::xr::openxr::OpenXrReport> {
        None
    }
    /// The lens's visibility mask, one view mask per eye, or `None` where the headset has
    /// none. An OpenXR runtime's may change during the session
    /// (`XrEventDataVisibilityMaskChangedKHR`): the frame loop asks every frame and hands a
    /// changed one to the renderer.
    fn visibility_mask(&self) -> Option<&vrao_ao::VisibilityMask> {
        None
    }
    /// Ends the session cleanly.
    fn end(&mut self, gpu: &Gpu) -> Result<()>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missed_refreshes_count_refreshes_of_the_display() {
        assert_eq!(missed_refreshes(100.0, 50.0), 1, "a 100 ms period on a 50 ms display");
        assert_eq!(missed_refreshes(150.0, 50.0), 2);
        assert_eq!(missed_refreshes(50.0, 50.0), 0);
        assert_eq!(missed_refreshes(70.0, 50.0), 0, "jitter rounds to none");
        assert_eq!(missed_refreshes(16.0, 50.0), 0, "shorter than a refresh");
        assert_eq!(missed_refreshes(f64::NAN, 50.0), 0);
        assert_eq!(missed_refreshes(100.0, 0.0), 0);
    }

    #[test]
    fn the_display_rate_is_the_reported_one_else_the_shortest_period_never_a_stretched_one() {
        const MS: i64 = 1_000_000;
        // Without XR_FB_display_refresh_rate: Monado-like, 50 ms, then stretched to 100 ms.
        let mut rate = DisplayRate::new();
        assert_eq!((rate.period_ms(), rate.source()), (None, None), "nothing before the first frame");
        // Monado predicts 16 ms for its first frame, before its display ran.
        assert_eq!(rate.frame(950 * MS, 16 * MS), 0);
        assert_eq!(rate.period_ms(), None, "the first frame's guess is not the display's period");
        assert_eq!(rate.frame(1000 * MS, 50 * MS), 0, "50 ms after the first frame: nothing missed");
        assert_eq!(rate.period_ms(), Some(50.0));
        assert_eq!(rate.frame(1050 * MS, 50 * MS), 0);
        // Frames late: the runtime predicts 100 ms and displays 100 ms apart.
        assert_eq!(rate.frame(1150 * MS, 100 * MS), 1, "100 ms on a 50 ms display: one refresh missed");
        assert_eq!(rate.frame(1250 * MS, 100 * MS), 1);
        assert_eq!(rate.frame(1400 * MS, 150 * MS), 2);
        assert_eq!(rate.period_ms(), Some(50.0), "the stretched period never becomes the display's");
        assert_eq!(rate.missed(), 4);
        assert!(rate.source().unwrap().contains("shortest"), "{:?}", rate.source());
        // A repeated or earlier display time misses nothing.
        assert_eq!(rate.frame(1400 * MS, 50 * MS), 0);
        // With the extension: its rate wins over a shorter predicted period (Monado's
        // 16 ms before its first frames) and over a stretched one.
        let mut rate = DisplayRate::new();
        rate.set_reported_hz(Some(20.0));
        assert_eq!(rate.period_ms(), Some(50.0), "known before the first frame");
        assert_eq!(rate.frame(0, 16 * MS), 0);
        assert_eq!(rate.frame(100 * MS, 100 * MS), 1);
        assert_eq!(rate.period_ms(), Some(50.0));
        assert!(rate.source().unwrap().contains("20 Hz (XR_FB_display_refresh_rate)"), "{:?}", rate.source());
        rate.set_reported_hz(Some(0.0));
        assert_eq!(rate.period_ms(), Some(50.0), "a rate of 0 is ignored");
        rate.set_reported_hz(Some(40.0));
        assert_eq!(rate.period_ms(), Some(25.0), "a change event moves it");
    }

    #[test]
    fn a_frame_finishes_no_earlier_than_its_submission_and_the_frame_before_plus_its_gpu_time() {
        // Submitted at 1.000 s, 8 ms of GPU work, the GPU idle: done at 1.008 s.
        assert!((earliest_finish(1.0, None, 8.0) - 1.008).abs() < 1e-12);
        assert!((earliest_finish(1.0, Some(0.99), 8.0) - 1.008).abs() < 1e-12);
        // Queued behind a frame finishing at 1.010 s: done at 1.018 s.
        assert!((earliest_finish(1.0, Some(1.010), 8.0) - 1.018).abs() < 1e-12);
        assert_eq!(earliest_finish(1.0, Some(f64::NAN), -3.0), 1.0, "no negative time, no NaN");
    }

    #[test]
    fn latency_percentiles_interpolate_between_ranks() {
        let mut counters = FrameCounters::default();
        counters.set_latency(&[]);
        assert_eq!((counters.latency_median_ms, counters.latency_p95_ms), (0.0, 0.0));
        // 1..=5 ms: the median 3, the 95th percentile 4 + 0.8 × (5 − 4) (nearest rank said 5).
        counters.set_latency(&[5.0, 1.0, 4.0, 2.0, 3.0]);
        assert_eq!(counters.latency_median_ms, 3.0);
        assert!((counters.latency_p95_ms - 4.8).abs() < 1e-12);
    }
}
