//! The OpenXR session's life cycle as a pure state machine: fed session state changes
//! and the application's wishes, it answers which runtime calls to make and whether the
//! next turn of the frame loop runs a frame, waits for events, or ends the run.
//! `session.rs` only carries out its answers, so every fault path is testable without a
//! runtime. Time is passed in (since the session was created) for the same reason.

use super::SessionPhase;
use std::time::Duration;

/// How long a session may stay before its first READY before vrao gives up on it.
pub const READY_TIMEOUT: Duration = Duration::from_secs(30);
/// How long the runtime may take from xrRequestExitSession to EXITING.
pub const EXIT_TIMEOUT: Duration = Duration::from_secs(5);
/// How long a session the runtime stopped by itself waits for EXITING or a new READY.
/// Runtimes stop a session to end it (EXITING follows at once) or to hand the display
/// elsewhere for a moment; waiting longer would only hang `vrao run`.
pub const STOPPED_TIMEOUT: Duration = Duration::from_secs(10);

/// What happened to the session.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Event {
    /// XrEventDataSessionStateChanged.
    State(SessionPhase),
    /// XrEventDataInstanceLossPending.
    InstanceLossPending,
    /// The user quit (window closed, `Headset::request_exit`, `end`).
    ExitRequested,
    /// The caller's cancellation token was set (Ctrl-C, SIGTERM): an exit request that
    /// also records the state the session was in.
    Interrupted,
    /// `--frames N` frames were rendered.
    FramesReached,
    /// A runtime call failed (the text says which and why).
    Failed(String),
}

/// A runtime call the session must make now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// xrBeginSession.
    BeginSession,
    /// xrEndSession.
    EndSession,
    /// xrRequestExitSession.
    RequestExit,
}

/// What the frame loop does next.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Turn {
    /// xrWaitFrame + xrBeginFrame; the frame goes to the application.
    Frame,
    /// xrWaitFrame + xrBeginFrame + xrEndFrame with no layer: the session still runs
    /// until the runtime stops it, but vrao is leaving.
    EmptyFrame,
    /// The session is not running: poll events again shortly (no xrWaitFrame).
    Poll,
    /// The run ends: tear the session down; `wait_frame` returns `None`.
    Leave,
    /// The session is lost: tear it down and continue on the fall back when the options
    /// give one.
    Lose(String),
}

/// The session's life cycle. See the module comment.
#[derive(Clone, Debug, Default)]
pub struct SessionMachine {
    /// States seen, in order, without consecutive repeats.
    states: Vec<SessionPhase>,
    /// Between xrBeginSession and xrEndSession.
    running: bool,
    ever_ready: bool,
    /// The user or `--frames` wants the run to end.
    exit_wanted: bool,
    /// When xrRequestExitSession was made.
    exit_asked_at: Option<Duration>,
    /// When the runtime stopped the session without being asked to.
    stopped_at: Option<Duration>,
    /// The state the session was in when the run was interrupted (`Some(None)`: before
    /// any state was reported).
    interrupted_in: Option<Option<SessionPhase>>,
    /// The verdict once the run is over (`Leave` or `Lose`).
    over: Option<Turn>,
    /// How the run ended, in words.
    ending: Option<String>,
    loss_reason: Option<String>,
}

impl SessionMachine {
    /// A machine before any event (no state seen yet).
    pub fn new() -> SessionMachine {
        SessionMachine::default()
    }

    /// Takes in one event at `at` (time since the session was created) and answers the
    /// runtime calls to make, in order. A failing call is fed back as [`Event::Failed`].
    pub fn feed(&mut self, event: Event, at: Duration) -> Vec<Action> {
        if let Event::State(phase) = event {
            if self.states.last() != Some(&phase) {
                self.states.push(phase);
            }
        }
        if self.over.is_some() {
            return Vec::new();
        }
        match event {
            Event::State(phase) => self.on_state(phase, at),
            Event::InstanceLossPending => {
                self.fail("the runtime is going away (instance loss pending)".into());
                Vec::new()
            }
            Event::ExitRequested | Event::FramesReached => self.exit(at),
            Event::Interrupted => {
                self.interrupted_in.get_or_insert(self.states.last().copied());
                self.exit(at)
            }
            Event::Failed(why) => {
                self.fail(why);
                Vec::new()
            }
        }
    }

    fn on_state(&mut self, phase: SessionPhase, at: Duration) -> Vec<Action> {
        match phase {
            SessionPhase::Ready if !self.running => {
                if self.exit_wanted {
                    // Asked out while the runtime had stopped us: do not start again.
                    self.finish(Turn::Leave, "left at READY: exit was requested");
                    return Vec::new();
                }
                self.running = true;
                self.ever_ready = true;
                self.stopped_at = None;
                vec![Action::BeginSession]
            }
            SessionPhase::Stopping if self.running => {
                self.running = false;
                if self.exit_asked_at.is_none() {
                    self.stopped_at = Some(at);
                }
                vec![Action::EndSession]
            }
            SessionPhase::LossPending => {
                self.fail("the session is being lost (LOSS_PENDING)".into());
                Vec::new()
            }
            SessionPhase::Exiting => {
                self.finish(Turn::Leave, "EXITING");
                Vec::new()
            }
            _ => Vec::new(),
        }
    }

    fn exit(&mut self, at: Duration) -> Vec<Action> {
        if self.exit_wanted {
            return Vec::new();
        }
        self.exit_wanted = true;
        if self.running {
            // The runtime walks STOPPING → (xrEndSession) → IDLE → EXITING.
            self.exit_asked_at = Some(at);
            vec![Action::RequestExit]
        } else {
            // Nothing runs (before READY, or stopped): xrRequestExitSession would fail
            // with XR_ERROR_SESSION_NOT_RUNNING; destroying the session is the way out.
            self.finish(Turn::Leave, "left a session that was not running");
            Vec::new()
        }
    }

    /// A loss or a failing call: lose the session, or just leave when the run was
    /// ending anyway (no fall back to start then). The reason is kept either way.
    fn fail(&mut self, why: String) {
        self.loss_reason = Some(why.clone());
        if self.exit_wanted {
            self.finish(Turn::Leave, &format!("left while exiting: {why}"));
        } else {
            self.finish(Turn::Lose(why.clone()), &format!("lost: {why}"));
        }
    }

    fn finish(&mut self, verdict: Turn, how: &str) {
        self.running = false;
        self.over = Some(verdict);
        self.ending = Some(how.to_string());
    }

    /// What the frame loop does at `at` (time since the session was created), after the
    /// queued events were fed.
    pub fn turn(&mut self, at: Duration) -> Turn {
        if let Some(verdict) = &self.over {
            return verdict.clone();
        }
        if let Some(asked) = self.exit_asked_at {
            if at.saturating_sub(asked) >= EXIT_TIMEOUT {
                self.finish(
                    Turn::Leave,
                    &format!(
                        "the runtime did not reach EXITING within {} s of the exit request",
                        EXIT_TIMEOUT.as_secs()
                    ),
                );
                return Turn::Leave;
            }
            return if self.running { Turn::EmptyFrame } else { Turn::Poll };
        }
        if self.running {
            return Turn::Frame;
        }
        if let Some(stopped) = self.stopped_at {
            if at.saturating_sub(stopped) >= STOPPED_TIMEOUT {
                self.finish(
                    Turn::Leave,
                    &format!(
                        "the runtime stopped the session and neither ended nor resumed it within {} s",
                        STOPPED_TIMEOUT.as_secs()
                    ),
                );
                return Turn::Leave;
            }
        } else if !self.ever_ready && at >= READY_TIMEOUT {
            self.fail(format!("the session did not become READY within {} s", READY_TIMEOUT.as_secs()));
            return self.turn(at);
        }
        Turn::Poll
    }

    /// The states seen so far, in order, without consecutive repeats.
    pub fn states(&self) -> &[SessionPhase] {
        &self.states
    }

    /// Between xrBeginSession and xrEndSession.
    pub fn running(&self) -> bool {
        self.running
    }

    /// Whether the user or `--frames` asked the run to end.
    pub fn exit_wanted(&self) -> bool {
        self.exit_wanted
    }

    /// Whether the run is over (a `Leave` or `Lose` verdict).
    pub fn is_over(&self) -> bool {
        self.over.is_some()
    }

    /// Why the session was lost or failed, if it was.
    pub fn loss_reason(&self) -> Option<&str> {
        self.loss_reason.as_deref()
    }

    /// How the run ended, once it has.
    pub fn ending(&self) -> Option<&str> {
        self.ending.as_deref()
    }

    /// The state the session was in when [`Event::Interrupted`] came, in words (`None`:
    /// not interrupted).
    pub fn interrupted_in(&self) -> Option<String> {
        self.interrupted_in.map(|phase| match phase {
            Some(phase) => phase.name().to_string(),
            None => "before the first session state".to_string(),
        })
    }
}

/// `--frames N` counts rendered frames: those submitted with an image. Frames the
/// runtime hands out but says not to render (shouldRender false), and the empty frames
/// run while leaving, do not count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameBudget {
    /// Stop after this many rendered frames (`None`: no limit).
    pub limit: Option<u64>,
    /// Frames submitted with an image so far.
    pub rendered: u64,
}

impl FrameBudget {
    /// A budget of `limit` rendered frames, none rendered yet.
    pub fn new(limit: Option<u64>) -> FrameBudget {
        FrameBudget { limit, rendered: 0 }
    }

    /// Counts one submitted frame.
    pub fn submitted(&mut self, with_image: bool) {
        if with_image {
            self.rendered += 1;
        }
    }

    /// True once `limit` frames have been rendered.
    pub fn reached(&self) -> bool {
        self.limit.is_some_and(|n| self.rendered >= n)
    }

    /// Frames still to render (`None`: no limit).
    pub fn remaining(&self) -> Option<u64> {
        self.limit.map(|n| n.saturating_sub(self.rendered))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Action::*;
    use SessionPhase::*;

    fn s(secs: f64) -> Duration {
        Duration::from_secs_f64(secs)
    }

    /// Feeds the states at time `at`; returns every action, in order.
    fn states(m: &mut SessionMachine, phases: &[SessionPhase], at: f64) -> Vec<Action> {
        phases.iter().flat_map(|&p| m.feed(Event::State(p), s(at))).collect()
    }

    /// A session that began and reached FOCUSED at t = 1 s.
    fn focused() -> SessionMachine {
        let mut m = SessionMachine::new();
        assert_eq!(m.turn(s(0.0)), Turn::Poll);
        assert_eq!(states(&mut m, &[Idle, Ready], 1.0), [BeginSession]);
        assert_eq!(m.turn(s(1.0)), Turn::Frame);
        assert_eq!(states(&mut m, &[Synchronized, Visible, Focused], 1.0), []);
        assert_eq!(m.turn(s(1.0)), Turn::Frame);
        m
    }

    #[test]
    fn normal_start_and_user_exit() {
        let mut m = focused();
        assert_eq!(m.feed(Event::ExitRequested, s(2.0)), [RequestExit]);
        // Asking again changes nothing.
        assert_eq!(m.feed(Event::ExitRequested, s(2.0)), []);
        assert_eq!(m.turn(s(2.0)), Turn::EmptyFrame, "frames still run until STOPPING, empty");
        assert_eq!(states(&mut m, &[Visible, Synchronized, Stopping], 2.1), [EndSession]);
        assert!(!m.running());
        assert_eq!(m.turn(s(2.1)), Turn::Poll, "no xrWaitFrame once ended");
        assert_eq!(states(&mut m, &[Idle], 2.1), []);
        assert_eq!(m.turn(s(2.1)), Turn::Poll);
        assert_eq!(states(&mut m, &[Exiting], 2.2), []);
        assert_eq!(m.turn(s(2.2)), Turn::Leave);
        assert_eq!(m.turn(s(100.0)), Turn::Leave, "the verdict stays");
        assert_eq!(m.loss_reason(), None);
        assert_eq!(m.ending(), Some("EXITING"));
        assert_eq!(
            m.states(),
            [Idle, Ready, Synchronized, Visible, Focused, Visible, Synchronized, Stopping, Idle, Exiting]
        );
    }

    #[test]
    fn frames_reached_while_running_exits_like_the_user() {
        let mut m = focused();
        assert_eq!(m.feed(Event::FramesReached, s(2.0)), [RequestExit]);
        assert_eq!(m.turn(s(2.0)), Turn::EmptyFrame);
        assert_eq!(states(&mut m, &[Stopping, Idle, Exiting], 2.1), [EndSession]);
        assert_eq!(m.turn(s(2.1)), Turn::Leave);
    }

    #[test]
    fn an_exit_request_the_runtime_never_completes_ends_after_the_timeout() {
        let mut m = focused();
        assert_eq!(m.feed(Event::ExitRequested, s(2.0)), [RequestExit]);
        assert_eq!(m.turn(s(2.0) + EXIT_TIMEOUT - s(0.01)), Turn::EmptyFrame);
        assert_eq!(m.turn(s(2.0) + EXIT_TIMEOUT), Turn::Leave);
        assert_eq!(m.loss_reason(), None);
        // Stopped but no EXITING: the same bound.
        let mut m = focused();
        assert_eq!(m.feed(Event::ExitRequested, s(2.0)), [RequestExit]);
        assert_eq!(states(&mut m, &[Stopping, Idle], 2.1), [EndSession]);
        assert_eq!(m.turn(s(3.0)), Turn::Poll);
        assert_eq!(m.turn(s(2.0) + EXIT_TIMEOUT), Turn::Leave);
    }

    #[test]
    fn the_runtime_stopping_the_session_by_itself_ends_at_exiting() {
        let mut m = focused();
        assert_eq!(states(&mut m, &[Visible, Synchronized, Stopping], 5.0), [EndSession]);
        assert_eq!(m.turn(s(5.0)), Turn::Poll, "no xrWaitFrame after STOPPING");
        assert_eq!(states(&mut m, &[Idle], 5.0), []);
        assert_eq!(m.turn(s(6.0)), Turn::Poll, "IDLE after STOPPING: poll events, no xrWaitFrame");
        assert_eq!(states(&mut m, &[Exiting], 6.0), []);
        assert_eq!(m.turn(s(6.0)), Turn::Leave);
        assert_eq!(m.loss_reason(), None);
    }

    #[test]
    fn the_runtime_stopping_the_session_by_itself_then_ready_begins_it_again() {
        let mut m = focused();
        assert_eq!(states(&mut m, &[Stopping, Idle], 5.0), [EndSession]);
        assert_eq!(m.turn(s(5.0)), Turn::Poll);
        assert_eq!(states(&mut m, &[Ready], 8.0), [BeginSession]);
        assert_eq!(m.turn(s(8.0)), Turn::Frame);
        // The stop's timeout no longer applies.
        assert_eq!(states(&mut m, &[Synchronized, Focused], 8.0), []);
        assert_eq!(m.turn(s(5.0) + STOPPED_TIMEOUT * 2), Turn::Frame);
        // And a later stop ends cleanly again.
        assert_eq!(states(&mut m, &[Stopping], 40.0), [EndSession]);
        assert_eq!(states(&mut m, &[Idle, Exiting], 40.0), []);
        assert_eq!(m.turn(s(40.0)), Turn::Leave);
    }

    #[test]
    fn a_session_the_runtime_stopped_and_left_idle_ends_after_a_bounded_wait() {
        let mut m = focused();
        assert_eq!(states(&mut m, &[Stopping, Idle], 5.0), [EndSession]);
        assert_eq!(m.turn(s(5.0) + STOPPED_TIMEOUT - s(0.01)), Turn::Poll);
        assert_eq!(m.turn(s(5.0) + STOPPED_TIMEOUT), Turn::Leave);
        assert_eq!(m.loss_reason(), None, "the session ended cleanly (xrEndSession was made)");
    }

    #[test]
    fn exit_requested_while_the_runtime_has_the_session_stopped_leaves_at_once() {
        let mut m = focused();
        assert_eq!(states(&mut m, &[Stopping], 5.0), [EndSession]);
        // STOPPING, then the user quits: no xrRequestExitSession (not running).
        assert_eq!(m.feed(Event::ExitRequested, s(5.1)), []);
        assert_eq!(m.turn(s(5.1)), Turn::Leave);
        // IDLE, then --frames reached: the same.
        let mut m = focused();
        assert_eq!(states(&mut m, &[Stopping, Idle], 5.0), [EndSession]);
        assert_eq!(m.feed(Event::FramesReached, s(5.1)), []);
        assert_eq!(m.turn(s(5.1)), Turn::Leave);
        // A READY after that does not begin the session again.
        assert_eq!(states(&mut m, &[Ready], 5.2), []);
        assert_eq!(m.turn(s(5.2)), Turn::Leave);
    }

    #[test]
    fn loss_pending_mid_session_loses_it_with_the_reason() {
        let mut m = focused();
        assert_eq!(states(&mut m, &[LossPending], 3.0), []);
        let why = "the session is being lost (LOSS_PENDING)";
        assert_eq!(m.turn(s(3.0)), Turn::Lose(why.into()));
        assert_eq!(m.loss_reason(), Some(why));
        // Nothing more is asked of the runtime.
        assert_eq!(states(&mut m, &[Stopping, Exiting], 3.0), []);
        assert_eq!(m.turn(s(3.0)), Turn::Lose(why.into()));
        assert_eq!(*m.states().last().unwrap(), Exiting, "states are still recorded");
    }

    #[test]
    fn instance_loss_pending_loses_the_session() {
        let mut m = focused();
        assert_eq!(m.feed(Event::InstanceLossPending, s(3.0)), []);
        let why = "the runtime is going away (instance loss pending)";
        assert_eq!(m.turn(s(3.0)), Turn::Lose(why.into()));
        assert_eq!(m.loss_reason(), Some(why));
        // Before READY too.
        let mut m = SessionMachine::new();
        assert_eq!(m.feed(Event::InstanceLossPending, s(0.5)), []);
        assert_eq!(m.turn(s(0.5)), Turn::Lose(why.into()));
    }

    #[test]
    fn a_loss_while_exiting_leaves_with_the_reason_and_no_fall_back() {
        let mut m = focused();
        assert_eq!(m.feed(Event::FramesReached, s(2.0)), [RequestExit]);
        assert_eq!(states(&mut m, &[LossPending], 2.1), []);
        assert_eq!(m.turn(s(2.1)), Turn::Leave);
        assert_eq!(m.loss_reason(), Some("the session is being lost (LOSS_PENDING)"));
    }

    #[test]
    fn frames_reached_before_ready_leaves_at_once() {
        let mut m = SessionMachine::new();
        assert_eq!(states(&mut m, &[Idle], 0.1), []);
        assert_eq!(m.turn(s(0.1)), Turn::Poll);
        assert_eq!(m.feed(Event::FramesReached, s(0.2)), []);
        assert_eq!(m.turn(s(0.2)), Turn::Leave);
        assert_eq!(states(&mut m, &[Ready], 0.3), [], "no xrBeginSession after leaving");
        assert_eq!(m.turn(s(0.3)), Turn::Leave);
        // With no state seen at all (--frames 0).
        let mut m = SessionMachine::new();
        assert_eq!(m.feed(Event::FramesReached, s(0.0)), []);
        assert_eq!(m.turn(s(0.0)), Turn::Leave);
    }

    #[test]
    fn exit_requested_before_ready_leaves_at_once() {
        let mut m = SessionMachine::new();
        assert_eq!(states(&mut m, &[Idle], 0.1), []);
        assert_eq!(m.feed(Event::ExitRequested, s(0.2)), []);
        assert_eq!(m.turn(s(0.2)), Turn::Leave);
        assert_eq!(m.loss_reason(), None);
        assert_eq!(m.states(), [Idle]);
    }

    #[test]
    fn a_session_that_never_becomes_ready_is_lost_after_the_timeout() {
        let mut m = SessionMachine::new();
        assert_eq!(states(&mut m, &[Idle], 0.1), []);
        assert_eq!(m.turn(READY_TIMEOUT - s(0.01)), Turn::Poll);
        let why = "the session did not become READY within 30 s";
        assert_eq!(m.turn(READY_TIMEOUT), Turn::Lose(why.into()));
        assert_eq!(m.loss_reason(), Some(why));
    }

    #[test]
    fn a_failing_runtime_call_loses_the_session() {
        // xrBeginSession fails.
        let mut m = SessionMachine::new();
        assert_eq!(states(&mut m, &[Idle, Ready], 0.1), [BeginSession]);
        assert_eq!(m.feed(Event::Failed("xrBeginSession: XR_ERROR_RUNTIME_FAILURE".into()), s(0.1)), []);
        assert_eq!(m.turn(s(0.1)), Turn::Lose("xrBeginSession: XR_ERROR_RUNTIME_FAILURE".into()));
        // xrWaitFrame fails mid-session.
        let mut m = focused();
        assert_eq!(m.feed(Event::Failed("xrWaitFrame: XR_ERROR_SESSION_LOST".into()), s(3.0)), []);
        assert_eq!(m.turn(s(3.0)), Turn::Lose("xrWaitFrame: XR_ERROR_SESSION_LOST".into()));
        assert_eq!(m.loss_reason(), Some("xrWaitFrame: XR_ERROR_SESSION_LOST"));
        assert!(m.is_over());
        // xrRequestExitSession fails: the run was ending, so it ends (no fall back).
        let mut m = focused();
        assert_eq!(m.feed(Event::ExitRequested, s(3.0)), [RequestExit]);
        assert_eq!(m.feed(Event::Failed("xrRequestExitSession: XR_ERROR_SESSION_LOST".into()), s(3.0)), []);
        assert_eq!(m.turn(s(3.0)), Turn::Leave);
        assert_eq!(m.loss_reason(), Some("xrRequestExitSession: XR_ERROR_SESSION_LOST"));
    }

    /// Every place a session can be in, reached by the runtime's events from a fresh
    /// machine, with whether xrBeginSession made it run.
    fn in_each_state() -> Vec<(&'static str, SessionMachine, bool)> {
        let at = |phases: &[SessionPhase]| {
            let mut m = SessionMachine::new();
            states(&mut m, phases, 1.0);
            m
        };
        vec![
            ("before the first session state", SessionMachine::new(), false),
            ("IDLE", at(&[Idle]), false),
            ("READY", at(&[Idle, Ready]), true),
            ("SYNCHRONIZED", at(&[Idle, Ready, Synchronized]), true),
            ("VISIBLE", at(&[Idle, Ready, Synchronized, Visible]), true),
            ("FOCUSED", at(&[Idle, Ready, Synchronized, Visible, Focused]), true),
            ("STOPPING", at(&[Idle, Ready, Synchronized, Focused, Stopping]), false),
            ("IDLE", at(&[Idle, Ready, Synchronized, Focused, Stopping, Idle]), false),
        ]
    }

    #[test]
    fn an_interrupt_ends_the_run_from_every_state_and_records_it() {
        for (state, mut m, running) in in_each_state() {
            let actions = m.feed(Event::Interrupted, s(2.0));
            assert_eq!(m.interrupted_in().as_deref(), Some(state));
            if running {
                // A running session is asked to exit; frames run empty until the runtime
                // stops it, then xrEndSession, then EXITING.
                assert_eq!(actions, [RequestExit], "{state}");
                assert_eq!(m.turn(s(2.0)), Turn::EmptyFrame, "{state}");
                assert_eq!(states(&mut m, &[Stopping], 2.05), [EndSession], "{state}");
                assert_eq!(states(&mut m, &[Idle, Exiting], 2.1), [], "{state}");
            } else {
                // Not running (before READY, stopped, idle): no wait for the runtime.
                assert_eq!(actions, [], "{state}");
            }
            assert_eq!(m.turn(s(2.1)), Turn::Leave, "{state}: the run ends");
            assert_eq!(m.loss_reason(), None, "{state}");
            // A second interrupt keeps the first state.
            m.feed(Event::Interrupted, s(2.2));
            assert_eq!(m.interrupted_in().as_deref(), Some(state));
        }
    }

    #[test]
    fn an_interrupt_the_runtime_never_answers_still_ends_within_the_exit_timeout() {
        for (state, mut m, running) in in_each_state() {
            m.feed(Event::Interrupted, s(2.0));
            let expected = if running { Turn::EmptyFrame } else { Turn::Leave };
            assert_eq!(m.turn(s(2.0) + EXIT_TIMEOUT - s(0.01)), expected, "{state}");
            assert_eq!(m.turn(s(2.0) + EXIT_TIMEOUT), Turn::Leave, "{state}");
        }
        assert_eq!(SessionMachine::new().interrupted_in(), None, "not interrupted");
    }

    #[test]
    fn states_seen_drop_consecutive_repeats() {
        let mut m = SessionMachine::new();
        states(&mut m, &[Idle, Idle, Ready, Ready, Synchronized, Focused, Focused], 0.1);
        assert_eq!(m.states(), [Idle, Ready, Synchronized, Focused]);
    }

    #[test]
    fn frames_count_rendered_frames_only() {
        let mut budget = FrameBudget::new(Some(2));
        assert!(!budget.reached());
        budget.submitted(false); // shouldRender false: handed out, not rendered
        budget.submitted(false);
        budget.submitted(false);
        assert!(!budget.reached(), "frames the runtime handed out do not count");
        assert_eq!(budget.remaining(), Some(2));
        budget.submitted(true);
        assert!(!budget.reached());
        budget.submitted(true);
        assert!(budget.reached());
        assert_eq!(budget.remaining(), Some(0));
        assert!(FrameBudget::new(Some(0)).reached(), "a frame limit of 0 is reached at once");
        let mut unlimited = FrameBudget::new(None);
        unlimited.submitted(true);
        assert!(!unlimited.reached());
        assert_eq!(unlimited.remaining(), None);
    }
}
