//! The progress bar of `eyeshell grow`: an observer of the growth run that forwards
//! everything to the observer writing the run directory, and draws a bar on stderr. The
//! library writes no terminal output; the bar is the command line's.

use std::io::IsTerminal;

use eyeshell::growth::{Observer, ObserverError, SeriesRow, Snapshot};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Should a growth run show a progress bar? Only on a terminal: not with `--quiet`, not
/// when stderr is redirected, not when the environment variable `CI` is set.
pub fn wanted(quiet: bool) -> bool {
    !quiet && std::io::stderr().is_terminal() && std::env::var_os("CI").is_none()
}

/// Forwards to `inner` and shows the run's progress (t / t_end) and its last snapshot.
pub struct GrowthProgress<'a> {
    inner: &'a mut dyn Observer,
    bar: ProgressBar,
}

impl<'a> GrowthProgress<'a> {
    /// A bar on stderr when `show` (see [`wanted`]), else a hidden one that draws nothing.
    pub fn new(inner: &'a mut dyn Observer, show: bool) -> Self {
        let bar = if show {
            let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(
                "{spinner} growing [{bar:40}] {percent:>3}% {elapsed_precise} {msg}",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        } else {
            ProgressBar::hidden()
        };
        GrowthProgress { inner, bar }
    }

    /// The run reached its end: the bar goes away.
    pub fn finish(self) {
        self.bar.finish_and_clear();
    }

    /// The run failed: the bar stays where it stopped.
    pub fn abandon(self) {
        self.bar.abandon();
    }
}

impl Observer for GrowthProgress<'_> {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.inner.snapshot(s)?;
        self.bar.set_message(format!(
            "t = {:.4}: axial length {:.4} mm, {}",
            s.t,
            s.series.axial_length,
            s.series.class.as_str()
        ));
        Ok(())
    }

    fn history(&mut self, row: &SeriesRow) -> Result<(), ObserverError> {
        self.inner.history(row)
    }

    fn progress(&mut self, t: f64, t_end: f64) {
        self.inner.progress(t, t_end);
        if t_end > 0.0 && t.is_finite() {
            let at = (t / t_end).clamp(0.0, 1.0) * 1000.0;
            self.bar.set_position(at.round() as u64);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use eyeshell::model::stimulus::Refraction;

    /// Counts what reaches it.
    #[derive(Default)]
    struct Count {
        snapshots: Vec<f64>,
        history: usize,
        progress: Vec<(f64, f64)>,
    }

    impl Observer for Count {
        fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
            self.snapshots.push(s.t);
            Ok(())
        }
        fn history(&mut self, _row: &SeriesRow) -> Result<(), ObserverError> {
            self.history += 1;
            Ok(())
        }
        fn progress(&mut self, t: f64, t_end: f64) {
            self.progress.push((t, t_end));
        }
    }

    #[test]
    fn everything_is_forwarded_to_the_writer() {
        let row = SeriesRow {
            t: 0.5,
            axial_length: 23.0,
            equatorial_radius: 11.0,
            retina_minus_blue: 0.1,
            retina_minus_red: -0.5,
            class: Refraction::Emmetropic,
        };
        let snap = Snapshot {
            t: 0.5,
            fields: vec![],
            growth: vec![],
            series: row,
        };
        let mut inner = Count::default();
        let mut bar = GrowthProgress::new(&mut inner, false);
        bar.snapshot(&snap).unwrap();
        bar.history(&row).unwrap();
        bar.progress(0.5, 1.0);
        bar.progress(f64::NAN, 1.0);
        bar.finish();
        assert_eq!(inner.snapshots, vec![0.5]);
        assert_eq!(inner.history, 1);
        assert_eq!(inner.progress.len(), 2);
        // --quiet: no bar whatever the terminal.
        assert!(!wanted(true));
    }
}
