//! Headsets the render loop drives: the real one through OpenXR (`openxr.rs`) and the
//! simulated one (`simulated.rs`) that always runs, with a compositor that reprojects the
//! newest frame when a new one misses its vsync (`reproject.rs`, `compositor.rs`).

pub mod openxr;
pub mod profiles;
pub mod simulated;

use crate::render::error::Result;
use crate::render::gpu::layered_target::LayeredTarget;
use crate::render::gpu::Gpu;
use crate::render::stereo::EyePair;
use serde::Serialize;

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
    /// The display period this frame must fit (ms): OpenXR's predicted display period,
    /// the simulated headset's refresh interval. The frame budget follows it frame by
    /// frame; `None` while the headset has not said (the profile's rate stands).
    pub display_period_ms: Option<f64>,
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
    /// Where the display period of [`FrameRequest::display_period_ms`] comes from, for
    /// the report (which rate governed the budget).
    fn display_rate_source(&self) -> String;
    /// What the OpenXR session did (`None` for headsets that are not OpenXR). An
    /// OpenXR headset that fell back to the simulated one still reports, with the loss.
    fn openxr_report(&self) -> Option<crate::xr::openxr::OpenXrReport> {
        None
    }
    /// Ends the session cleanly.
    fn end(&mut self, gpu: &Gpu) -> Result<()>;
}

#[cfg(test)]
mod tests {
    use super::*;

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
