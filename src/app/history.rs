//! Per-pass GPU times of the most recent frames, for the panel's profiler graph and the
//! run summary's per-pass medians.

use std::collections::VecDeque;
use vrao_ao::plug::FrameTiming;

/// Per-pass GPU times of recent frames (as they come back from the GPU, a few frames
/// after they were submitted), for the profiler graph.
#[derive(Clone, Debug, Default)]
pub struct PassHistory {
    /// The most recent frames' GPU times, oldest first, at most `capacity`.
    pub frames: VecDeque<FrameTiming>,
    /// CPU time spent encoding each recent frame (ms), newest last.
    pub cpu_encode_ms: VecDeque<f64>,
    /// How many frames (and CPU encode times) are kept.
    pub capacity: usize,
}

impl PassHistory {
    /// An empty history keeping the last `capacity` frames.
    pub fn new(capacity: usize) -> PassHistory {
        PassHistory { frames: VecDeque::with_capacity(capacity), cpu_encode_ms: VecDeque::new(), capacity }
    }

    /// Adds a frame's GPU times, dropping the oldest when full.
    pub fn push(&mut self, timing: FrameTiming) {
        push_bounded(&mut self.frames, timing, self.capacity);
    }

    /// Adds a frame's CPU encode time (ms), dropping the oldest when full.
    pub fn push_cpu_encode(&mut self, ms: f64) {
        push_bounded(&mut self.cpu_encode_ms, ms, self.capacity);
    }
}

fn push_bounded<T>(queue: &mut VecDeque<T>, value: T, capacity: usize) {
    if queue.len() == capacity {
        queue.pop_front();
    }
    queue.push_back(value);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_history_keeps_the_newest_frames() {
        let mut history = PassHistory::new(2);
        for frame in 0..3 {
            history.push(FrameTiming { frame, ..FrameTiming::default() });
            history.push_cpu_encode(frame as f64);
        }
        assert_eq!(history.frames.iter().map(|f| f.frame).collect::<Vec<_>>(), [1, 2]);
        assert_eq!(history.cpu_encode_ms, [1.0, 2.0]);
    }
}
