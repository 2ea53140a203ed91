//! GPU timestamps around passes, read back frames later without a stall: the scopes go
//! through `wgpu-profiler`, which keeps a ring of query sets and readback buffers and
//! hands back a frame's times once its buffers have mapped.

use super::Gpu;
use crate::error::{Error, Result};
use std::collections::VecDeque;

/// One finished frame's spans: (label, GPU milliseconds) in the order they were
/// recorded; per-eye spans ([`FrameTiming::is_per_eye`]) lie inside their pass's span.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameTiming {
    /// The renderer's frame number the spans belong to.
    pub frame: u64,
    /// (label, GPU ms) of every span, in recording order.
    pub spans: Vec<(String, f64)>,
    /// GPU time of the whole frame: the sum of its passes' spans (not the per-eye ones).
    pub total_ms: f64,
    /// Whether the frame's passes went to the GPU one submission each (true per-pass
    /// times on lavapipe; see vrao-render's `Timing::Serial`).
    pub serial: bool,
}

/// An open span; hand it back to [`SpanRecorder::end`] on the same encoder.
pub struct Span(wgpu_profiler::GpuProfilerQuery);

/// Where the passes' timestamp spans go: a driver's own [`PassTimer`], or the
/// `wgpu_profiler::GpuProfiler` a host already keeps (its frames then hold the AO
/// chain's passes under their names, nested in whatever scope the host opened).
pub trait SpanRecorder {
    /// Opens a span labelled `label` on `encoder`.
    fn begin(&self, encoder: &mut wgpu::CommandEncoder, label: &str) -> Span;
    /// Closes `span` on `encoder`.
    fn end(&self, encoder: &mut wgpu::CommandEncoder, span: Span);
}

impl SpanRecorder for wgpu_profiler::GpuProfiler {
    fn begin(&self, encoder: &mut wgpu::CommandEncoder, label: &str) -> Span {
        Span(self.begin_query(label, encoder))
    }

    fn end(&self, encoder: &mut wgpu::CommandEncoder, span: Span) {
        self.end_query(encoder, span.0);
    }
}

impl SpanRecorder for PassTimer {
    fn begin(&self, encoder: &mut wgpu::CommandEncoder, label: &str) -> Span {
        self.profiler.begin(encoder, label)
    }

    fn end(&self, encoder: &mut wgpu::CommandEncoder, span: Span) {
        self.profiler.end(encoder, span);
    }
}

/// Timestamp spans of every frame in flight.
pub struct PassTimer {
    profiler: wgpu_profiler::GpuProfiler,
    /// Frames whose spans were submitted and are not yet read back, oldest first (the
    /// profiler returns frames in this order).
    pending: VecDeque<u64>,
    timestamp_period: f32,
}

/// The profiler never drops a frame as long as fewer than this many are pending; the
/// renderer keeps far fewer in flight.
const MAX_PENDING_FRAMES: usize = 16;

impl PassTimer {
    /// Timestamps where the adapter has them (inside encoders); a no-op otherwise.
    pub fn new(gpu: &Gpu) -> Result<PassTimer> {
        let settings = wgpu_profiler::GpuProfilerSettings {
            enable_timer_queries: gpu.caps.timestamps,
            enable_debug_groups: false,
            max_num_pending_frames: MAX_PENDING_FRAMES,
        };
        let profiler = wgpu_profiler::GpuProfiler::new(&gpu.device, settings)
            .map_err(|e| Error::Gpu(format!("GPU profiler: {e}")))?;
        Ok(PassTimer { profiler, pending: VecDeque::new(), timestamp_period: gpu.queue.get_timestamp_period() })
    }

    /// A timer that records no queries (the AO engine on a host's encoder, which the
    /// engine does not submit).
    pub fn disabled(gpu: &Gpu) -> Result<PassTimer> {
        let settings = wgpu_profiler::GpuProfilerSettings {
            enable_timer_queries: false,
            enable_debug_groups: false,
            max_num_pending_frames: MAX_PENDING_FRAMES,
        };
        let profiler = wgpu_profiler::GpuProfiler::new(&gpu.device, settings)
            .map_err(|e| Error::Gpu(format!("GPU profiler: {e}")))?;
        Ok(PassTimer { profiler, pending: VecDeque::new(), timestamp_period: 1.0 })
    }

    /// Whether timestamp queries are on (false where the device has none: spans then read 0 frames).
    pub fn enabled(&self) -> bool {
        self.profiler.settings().enable_timer_queries
    }

    /// Copies the frame's queries towards their readback buffers; record it in the
    /// frame's last encoder.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.profiler.resolve_queries(encoder);
    }

    /// Closes `frame` after its last submission and starts mapping its results.
    pub fn end_frame(&mut self, frame: u64) -> Result<()> {
        self.profiler.end_frame().map_err(|e| Error::Gpu(format!("GPU profiler: {e}")))?;
        if self.enabled() {
            self.pending.push_back(frame);
        }
        Ok(())
    }

    /// Frames whose spans have been read back since the last call (poll the device for
    /// them to arrive); never waits.
    pub fn finished(&mut self) -> Vec<FrameTiming> {
        let mut done = Vec::new();
        while let Some(results) = self.profiler.process_finished_frame(self.timestamp_period) {
            let Some(frame) = self.pending.pop_front() else { break };
            let mut spans = Vec::new();
            flatten(&results, &mut spans);
            // A pass's per-eye spans lie inside its own span: only passes add up.
            let total_ms = spans.iter().filter(|(label, _)| !FrameTiming::is_per_eye(label)).map(|(_, ms)| ms).sum();
            done.push(FrameTiming { frame, spans, total_ms, serial: false });
        }
        done
    }

    /// Frames submitted whose spans have not come back yet.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }
}

fn flatten(results: &[wgpu_profiler::GpuTimerQueryResult], out: &mut Vec<(String, f64)>) {
    for r in results {
        if let Some(time) = &r.time {
            out.push((r.label.clone(), (time.end - time.start).max(0.0) * 1e3));
        }
        flatten(&r.nested_queries, out);
    }
}

impl FrameTiming {
    /// Per-eye spans (a pass run once per eye) are labelled "`<pass> left`" / "`<pass> right`".
    pub fn is_per_eye(label: &str) -> bool {
        label.ends_with(" left") || label.ends_with(" right")
    }

    /// The summed GPU ms of `passes` in one frame's `spans`, or the first of them that has no
    /// span: every pass that runs is timed under its name, so a missing one means a name
    /// and its span disagree, and counting it as 0 ms would hide that.
    pub fn passes_ms<'a>(spans: &[(String, f64)], passes: &[&'a str]) -> std::result::Result<f64, &'a str> {
        passes.iter().try_fold(0.0, |sum, &pass| match spans.iter().find(|(label, _)| label == pass) {
            Some((_, ms)) => Ok(sum + ms),
            None => Err(pass),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_times_add_up_and_a_missing_span_is_named() {
        let spans = vec![("ssao".to_string(), 1.5), ("ssao left".to_string(), 0.75), ("blur".to_string(), 0.25)];
        assert_eq!(FrameTiming::passes_ms(&spans, &["ssao", "blur"]), Ok(1.75));
        assert_eq!(FrameTiming::passes_ms(&spans, &[]), Ok(0.0));
        assert_eq!(FrameTiming::passes_ms(&spans, &["ssao", "upsample"]), Err("upsample"));
    }
}
