//! The reference tracer's [`Progress`] shown with indicatif: a bar on a terminal
//! (`reference [#####.....]  42% 1.2 Mrays/s ETA 35s`), nothing otherwise, and one
//! summary line in the log (info) at the end either way (logs keep how fast the trace ran).

use super::Progress;
use std::io::IsTerminal;
use std::time::Duration;

/// Draws [`Progress`] on stderr; see the module documentation.
pub struct ProgressBar {
    label: String,
    bar: indicatif::ProgressBar,
    last: Option<Progress>,
    finished: bool,
}

impl ProgressBar {
    /// A bar whose lines start with `label` (e.g. "reference").
    pub fn new(label: &str) -> ProgressBar {
        ProgressBar::with_terminal(label, std::io::stderr().is_terminal())
    }

    fn with_terminal(label: &str, terminal: bool) -> ProgressBar {
        // Hidden off a terminal: a log file gets the summary line, not redraws.
        let target = if terminal {
            indicatif::ProgressDrawTarget::stderr_with_hz(4)
        } else {
            indicatif::ProgressDrawTarget::hidden()
        };
        // No length until the first update: a length of 0 would draw as 100 %.
        let bar = indicatif::ProgressBar::with_draw_target(None, target);
        let style = indicatif::ProgressStyle::with_template("{prefix} [{bar:30}] {percent:>3}% {msg} ETA {eta}")
            .expect("the template is valid")
            .progress_chars("#>.");
        bar.set_style(style);
        bar.set_prefix(label.to_string());
        ProgressBar { label: label.to_string(), bar, last: None, finished: false }
    }

    /// Records `p` and moves the bar (indicatif limits the redraws).
    pub fn update(&mut self, p: Progress) {
        self.last = Some(p);
        // Position last: each setter may redraw, and the last one should show all three.
        self.bar.set_message(format!("{}/s", si(rays_per_second(&p), "rays")));
        self.bar.set_length(p.total as u64);
        self.bar.set_position(p.done as u64);
    }

    /// Clears the bar and logs one summary line (info). Does nothing the second time.
    pub fn finish(&mut self) {
        if std::mem::replace(&mut self.finished, true) {
            return;
        }
        self.bar.finish_and_clear();
        log::info!("{}", self.summary());
    }

    /// "reference: 12.3 Mrays in 0:04 (3.1 Mrays/s)".
    pub fn summary(&self) -> String {
        let p = self.last.unwrap_or(Progress { done: 0, total: 0, rays: 0, elapsed: Duration::ZERO });
        let s = p.elapsed.as_secs();
        format!(
            "{}: {} in {}:{:02} ({}/s)",
            self.label,
            si(p.rays as f64, "rays"),
            s / 60,
            s % 60,
            si(rays_per_second(&p), "rays")
        )
    }
}

fn rays_per_second(p: &Progress) -> f64 {
    let s = p.elapsed.as_secs_f64();
    if s > 0.0 {
        p.rays as f64 / s
    } else {
        0.0
    }
}

/// A count of `unit` with a metric prefix and one decimal: "950 rays", "3.4 Mrays"
/// (indicatif's human counts group digits instead, unreadable at billions of rays).
fn si(x: f64, unit: &str) -> String {
    let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
    for (scale, prefix) in [(1e9, "G"), (1e6, "M"), (1e3, "k")] {
        if x >= scale {
            return format!("{:.1} {prefix}{unit}", x / scale);
        }
    }
    format!("{x:.0} {unit}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn progress(done: usize, total: usize, rays: u64, secs: f64) -> Progress {
        Progress { done, total, rays, elapsed: Duration::from_secs_f64(secs) }
    }

    #[test]
    fn hidden_off_a_terminal_with_a_summary() {
        let mut bar = ProgressBar::with_terminal("reference", false);
        assert!(bar.bar.is_hidden());
        bar.update(progress(5, 10, 3_400_000, 2.0));
        assert_eq!((bar.bar.position(), bar.bar.length()), (5, Some(10)));
        assert_eq!(bar.summary(), "reference: 3.4 Mrays in 0:02 (1.7 Mrays/s)");
        bar.finish();
        bar.finish();
        assert!(bar.bar.is_finished());
        assert_eq!(si(2.5e9, "rays"), "2.5 Grays");
        assert_eq!(si(950.0, "rays"), "950 rays");
    }
}
