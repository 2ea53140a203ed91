//! A one-line progress bar on stderr for long traces:
//! `\r[#####.....] 42% 1.2 Mrays/s ETA 0:35`.

use super::Progress;
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Cells of the bar between the brackets.
const BAR_CELLS: usize = 30;
/// At most this many redraws a second.
const REDRAW_INTERVAL: Duration = Duration::from_millis(250);

/// Draws [`Progress`] on stderr. On a terminal it redraws one line at most four times a
/// second; otherwise it stays silent until [`finish`](Self::finish), which prints one
/// summary line either way.
pub struct ProgressBar {
    label: String,
    terminal: bool,
    last_draw: Option<Instant>,
    last: Option<Progress>,
    finished: bool,
}

impl ProgressBar {
    /// A bar whose lines start with `label` (e.g. "reference").
    pub fn new(label: &str) -> ProgressBar {
        ProgressBar::with_terminal(label, std::io::stderr().is_terminal())
    }

    fn with_terminal(label: &str, terminal: bool) -> ProgressBar {
        ProgressBar { label: label.to_string(), terminal, last_draw: None, last: None, finished: false }
    }

    /// Records `p` and redraws when on a terminal and the last redraw is old enough.
    pub fn update(&mut self, p: Progress) {
        self.last = Some(p);
        if !self.terminal || self.finished {
            return;
        }
        let now = Instant::now();
        if self.last_draw.is_some_and(|t| now.duration_since(t) < REDRAW_INTERVAL) {
            return;
        }
        self.last_draw = Some(now);
        let mut err = std::io::stderr().lock();
        // A progress bar that cannot be drawn is not worth failing the trace for.
        let _ = write!(err, "\r{} {}", self.label, format_bar(&p));
        let _ = err.flush();
    }

    /// Ends the bar with one summary line (on a terminal in place of the bar) and a
    /// newline. Does nothing the second time.
    pub fn finish(&mut self) {
        if self.finished {
            return;
        }
        self.finished = true;
        let line = self.summary();
        let mut err = std::io::stderr().lock();
        // On a terminal the summary overwrites the bar (and clears what is left of it).
        let _ = if self.terminal { writeln!(err, "\r{line}\x1b[K") } else { writeln!(err, "{line}") };
    }

    /// "reference: 12.3 Mrays in 0:04 (3.1 Mrays/s)".
    pub fn summary(&self) -> String {
        let p = self.last.unwrap_or(Progress { done: 0, total: 0, rays: 0, elapsed: Duration::ZERO });
        format!(
            "{}: {} in {} ({}/s)",
            self.label,
            si(p.rays as f64, "rays"),
            clock(p.elapsed),
            si(rays_per_second(&p), "rays")
        )
    }
}

impl Drop for ProgressBar {
    /// A bar left on a terminal would leave the shell prompt after it.
    fn drop(&mut self) {
        if self.terminal && self.last_draw.is_some() && !self.finished {
            let _ = writeln!(std::io::stderr());
        }
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

/// `[#####.....] 42% 1.2 Mrays/s ETA 0:35` for `p` (no carriage return).
pub fn format_bar(p: &Progress) -> String {
    let fraction = if p.total > 0 { (p.done as f64 / p.total as f64).clamp(0.0, 1.0) } else { 1.0 };
    let filled = ((fraction * BAR_CELLS as f64).floor() as usize).min(BAR_CELLS);
    let bar: String = "#".repeat(filled) + &".".repeat(BAR_CELLS - filled);
    let eta = if p.done >= p.total {
        "done".to_string()
    } else if p.done == 0 {
        "ETA --:--".to_string()
    } else {
        let remaining = p.elapsed.as_secs_f64() * (p.total - p.done) as f64 / p.done as f64;
        format!("ETA {}", clock(Duration::from_secs_f64(remaining.min(1e9))))
    };
    format!("[{bar}] {:>3}% {}/s {eta}", (fraction * 100.0).floor() as u32, si(rays_per_second(p), "rays"))
}

/// A count of `unit` with a metric prefix and one decimal: "950 rays", "1.2 krays", "3.4 Mrays".
fn si(x: f64, unit: &str) -> String {
    let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
    for (scale, prefix) in [(1e9, "G"), (1e6, "M"), (1e3, "k")] {
        if x >= scale {
            return format!("{:.1} {prefix}{unit}", x / scale);
        }
    }
    format!("{x:.0} {unit}")
}

/// m:ss, or h:mm:ss from an hour on.
fn clock(d: Duration) -> String {
    let s = d.as_secs();
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn progress(done: usize, total: usize, rays: u64, secs: f64) -> Progress {
        Progress { done, total, rays, elapsed: Duration::from_secs_f64(secs) }
    }

    #[test]
    fn bar_shows_fraction_rate_and_eta() {
        assert_eq!(
            format_bar(&progress(42, 100, 12_000_000, 10.0)),
            "[############..................]  42% 1.2 Mrays/s ETA 0:13"
        );
        assert_eq!(format_bar(&progress(0, 100, 0, 0.0)), "[..............................]   0% 0 rays/s ETA --:--");
        assert_eq!(format_bar(&progress(7, 7, 900, 1.0)), "[##############################] 100% 900 rays/s done");
        assert_eq!(format_bar(&progress(0, 0, 0, 0.0)), "[##############################] 100% 0 rays/s done");
        assert_eq!(clock(Duration::from_secs(3725)), "1:02:05");
        assert_eq!(si(2.5e9, "rays"), "2.5 Grays");
    }

    #[test]
    fn summary_and_silence_off_a_terminal() {
        let mut bar = ProgressBar::with_terminal("reference", false);
        bar.update(progress(5, 10, 3_400_000, 2.0));
        assert!(bar.last_draw.is_none(), "nothing drawn off a terminal");
        assert_eq!(bar.summary(), "reference: 3.4 Mrays in 0:02 (1.7 Mrays/s)");
        bar.finish();
        bar.finish();
        assert!(bar.finished);
    }
}
