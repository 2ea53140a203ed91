//! The simulated compositor's bookkeeping, without the GPU: a vsync clock and, for every
//! vsync, which submitted frame the display shows and whether it had to be reprojected.
//!
//! A frame is rendered for one vsync (its predicted display time). At each vsync the
//! compositor shows the newest frame that was finished by then and was meant for that
//! vsync or an earlier one: on time it is *presented*; late, or when no new frame is
//! ready and the previous one is shown again, the vsync is *reprojected* (the image is
//! warped to the pose at that vsync). A finished frame that a newer one overtakes before
//! any vsync shows it is *dropped*. Latency is the time from sampling the pose a shown
//! frame was rendered with to the vsync that shows it.

use crate::xr::FrameCounters;
use std::time::{Duration, Instant};

/// Time on the headset: real (a monotonic clock from when the session started) or
/// virtual (advanced only by the caller, for deterministic tests and simulations).
#[derive(Clone, Debug)]
pub enum Clock {
    /// Wall-clock time since the session started.
    Real {
        /// When the session started.
        start: Instant,
    },
    /// Time the caller sets (`advance`, `wait_until`): deterministic tests and simulations.
    Virtual {
        /// The current time in seconds.
        now: f64,
    },
}

impl Clock {
    /// A real clock starting now.
    pub fn real() -> Clock {
        Clock::Real { start: Instant::now() }
    }

    /// Seconds since the session started.
    pub fn now(&self) -> f64 {
        match self {
            Clock::Real { start } => start.elapsed().as_secs_f64(),
            Clock::Virtual { now } => *now,
        }
    }

    /// Waits until time `t` (real: sleeps; virtual: jumps there if it is later).
    pub fn wait_until(&mut self, t: f64) {
        match self {
            Clock::Real { start } => {
                let now = start.elapsed().as_secs_f64();
                if t > now {
                    std::thread::sleep(Duration::from_secs_f64(t - now));
                }
            }
            Clock::Virtual { now } => *now = now.max(t),
        }
    }

    /// Lets `seconds` pass (virtual time only; real time passes by itself).
    pub fn advance(&mut self, seconds: f64) {
        if let Clock::Virtual { now } = self {
            *now += seconds.max(0.0);
        }
    }
}

/// What one vsync showed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VsyncOutcome {
    /// A new frame, rendered for this vsync.
    Presented {
        /// The frame's number ([`FrameRequest::index`](crate::xr::FrameRequest::index)).
        frame: u64,
    },
    /// Frame `frame` warped to this vsync's pose (late, or shown again).
    Reprojected {
        /// The frame's number.
        frame: u64,
    },
    /// Nothing to show yet (before the first frame).
    Empty,
}

#[derive(Clone, Copy, Debug)]
struct Submitted {
    frame: u64,
    /// The vsync it was rendered for.
    target_vsync: u64,
    /// When it was finished (submitted).
    ready: f64,
    /// When its pose was sampled.
    pose_time: f64,
}

/// Vsync bookkeeping of the simulated compositor.
#[derive(Clone, Debug)]
pub struct Compositor {
    period: f64,
    /// The next vsync not yet processed.
    next_vsync: u64,
    pending: Vec<Submitted>,
    shown: Option<Submitted>,
    counters: FrameCounters,
    latencies_ms: Vec<f64>,
}

impl Compositor {
    /// A compositor for a display refreshing at `refresh_hz`; vsync 1 is the first.
    pub fn new(refresh_hz: f64) -> Compositor {
        Compositor {
            period: 1.0 / refresh_hz,
            next_vsync: 1,
            pending: Vec::new(),
            shown: None,
            counters: FrameCounters::default(),
            latencies_ms: Vec::new(),
        }
    }

    /// The display period in seconds.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Time of vsync number `vsync` in seconds (vsync × period).
    pub fn vsync_time(&self, vsync: u64) -> f64 {
        vsync as f64 * self.period
    }

    /// The first vsync strictly after time `t`.
    pub fn vsync_after(&self, t: f64) -> u64 {
        (t / self.period).floor() as u64 + 1
    }

    /// Records a finished frame rendered for `target_vsync`.
    pub fn submit(&mut self, frame: u64, target_vsync: u64, ready: f64, pose_time: f64) {
        self.counters.submitted += 1;
        self.pending.push(Submitted { frame, target_vsync, ready, pose_time });
    }

    /// Processes every vsync up to time `now`; returns what each showed.
    pub fn advance_to(&mut self, now: f64) -> Vec<(u64, VsyncOutcome)> {
        let mut outcomes = Vec::new();
        while self.vsync_time(self.next_vsync) <= now {
            let vsync = self.next_vsync;
            let t = self.vsync_time(vsync);
            // The newest frame finished by this vsync and meant for it or earlier.
            let eligible = |s: &Submitted| s.ready <= t && s.target_vsync <= vsync;
            if let Some(newest) = self.pending.iter().filter(|s| eligible(s)).max_by_key(|s| s.frame).copied() {
                let overtaken = self.pending.iter().filter(|s| eligible(s) && s.frame < newest.frame).count();
                self.counters.dropped += overtaken as u64;
                self.pending.retain(|s| !eligible(s));
                self.shown = Some(newest);
            }
            let outcome = match self.shown {
                Some(s) if s.target_vsync == vsync => VsyncOutcome::Presented { frame: s.frame },
                Some(s) => VsyncOutcome::Reprojected { frame: s.frame },
                None => VsyncOutcome::Empty,
            };
            match outcome {
                VsyncOutcome::Presented { .. } => self.counters.presented += 1,
                VsyncOutcome::Reprojected { .. } => self.counters.reprojected += 1,
                VsyncOutcome::Empty => {}
            }
            if let Some(s) = self.shown {
                self.latencies_ms.push((t - s.pose_time) * 1e3);
            }
            outcomes.push((vsync, outcome));
            self.next_vsync += 1;
        }
        outcomes
    }

    /// Frames submitted but not yet shown count as dropped when the session ends.
    pub fn finish(&mut self) {
        self.counters.dropped += self.pending.len() as u64;
        self.pending.clear();
    }

    /// The counters so far, with the latency median and p95 over the displayed vsyncs.
    pub fn counters(&self) -> FrameCounters {
        let mut c = self.counters;
        c.set_latency(&self.latencies_ms);
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs the frame loop the simulated headset runs with a render time per frame:
    /// wait for the vsync after the last submit, render for the next one, submit.
    fn run(render_ms: &[f64], frames: u64) -> (FrameCounters, Vec<(u64, VsyncOutcome)>) {
        let mut c = Compositor::new(90.0);
        let mut clock = Clock::Virtual { now: 0.0 };
        let mut outcomes = Vec::new();
        for frame in 0..frames {
            let start_vsync = c.vsync_after(clock.now() - 1e-12).max(1);
            clock.wait_until(c.vsync_time(start_vsync));
            outcomes.extend(c.advance_to(clock.now()));
            let pose_time = clock.now();
            clock.advance(render_ms[frame as usize % render_ms.len()] / 1e3);
            c.submit(frame, start_vsync + 1, clock.now(), pose_time);
            outcomes.extend(c.advance_to(clock.now()));
        }
        (c.counters(), outcomes)
    }

    #[test]
    fn a_fast_application_presents_every_vsync_with_one_period_of_latency() {
        let (counters, outcomes) = run(&[3.0], 50);
        assert_eq!(counters.reprojected, 0);
        assert_eq!(counters.dropped, 0);
        assert!(counters.presented >= 49, "{counters:?}");
        assert!(outcomes.iter().skip(1).all(|(_, o)| matches!(o, VsyncOutcome::Presented { .. })));
        assert!((counters.latency_median_ms - 1000.0 / 90.0).abs() < 1e-6, "{counters:?}");
    }

    #[test]
    fn a_frame_that_misses_its_vsync_is_shown_late_and_the_vsyncs_between_are_reprojected() {
        // 25 ms > 2 periods (22.2 ms): each frame is ready after its vsync and the next.
        let (counters, _) = run(&[25.0], 20);
        assert_eq!(counters.presented, 0, "{counters:?}");
        assert!(counters.reprojected >= 40, "{counters:?}");
        // An application slower than the display loses no frames: each is shown once ready.
        assert_eq!(counters.dropped, 0);
    }

    #[test]
    fn a_slow_frame_among_fast_ones_reprojects_only_around_it() {
        let (counters, outcomes) = run(&[5.0, 5.0, 5.0, 30.0], 40);
        assert!(counters.presented > 0 && counters.reprojected > 0, "{counters:?}");
        // Each 30 ms frame misses its vsync and holds the display for about 3 vsyncs.
        let reprojected_per_slow_frame = counters.reprojected as f64 / 10.0;
        assert!((2.0..=4.0).contains(&reprojected_per_slow_frame), "{counters:?} {outcomes:?}");
    }

    #[test]
    fn a_frame_overtaken_before_any_vsync_shows_it_is_dropped() {
        let mut c = Compositor::new(100.0);
        c.submit(0, 1, 0.001, 0.0);
        c.submit(1, 1, 0.002, 0.0);
        let outcomes = c.advance_to(0.0101);
        assert_eq!(outcomes, vec![(1, VsyncOutcome::Presented { frame: 1 })]);
        assert_eq!(c.counters().dropped, 1);
    }

    #[test]
    fn the_same_script_gives_the_same_counters() {
        let script = [4.0, 17.0, 9.0, 31.0, 2.0];
        assert_eq!(run(&script, 100).0, run(&script, 100).0);
    }
}
