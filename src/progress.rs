//! The progress bar of `eyeshell grow`: an observer of the growth run, shown each event
//! after the run directory's writer (`rundir::run::grow_with`), that draws a bar on stderr.
//! The library writes no terminal output; the bar is the command line's.

use std::io::IsTerminal;

use eyeshell::growth::{Observer, ObserverError, Snapshot};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Should a growth run show a progress bar? Only on a terminal: not with `--quiet`, not
/// when stderr is redirected, not when the environment variable `CI` is set.
pub fn wanted(quiet: bool) -> bool {
    !quiet && std::io::stderr().is_terminal() && std::env::var_os("CI").is_none()
}

/// Shows the run's progress (t / t_end) and its last snapshot.
pub struct GrowthProgress {
    bar: ProgressBar,
}

impl GrowthProgress {
    /// A bar on stderr when `show` (see [`wanted`]), else a hidden one that draws nothing.
    /// `before` is what it says until the run reports (with `solver.tol` the mesh choice
    /// comes first, and can take longer than the run): its spinner turns meanwhile.
    pub fn new(show: bool, before: Option<&str>) -> Self {
        let bar = if show {
            let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(
                "{spinner} growing [{bar:40}] {percent:>3}% {elapsed_precise} {msg}",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            if before.is_some() {
                bar.enable_steady_tick(std::time::Duration::from_millis(120));
            }
            bar
        } else {
            ProgressBar::hidden()
        };
        if let Some(message) = before {
            bar.set_message(message.to_string());
        }
        GrowthProgress { bar }
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

impl Observer for GrowthProgress {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.bar.set_message(format!(
            "t = {:.4}: axial length {:.4} mm, {}",
            s.t,
            s.series.axial_length,
            s.series.class.as_str()
        ));
        Ok(())
    }

    fn progress(&mut self, t: f64, t_end: f64) -> Result<(), ObserverError> {
        if t_end > 0.0 && t.is_finite() {
            let at = (t / t_end).clamp(0.0, 1.0) * 1000.0;
            self.bar.set_position(at.round() as u64);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use eyeshell::growth::SeriesRow;
    use eyeshell::model::stimulus::Refraction;

    #[test]
    fn the_bar_follows_t_and_shows_the_last_snapshot() {
        let row = SeriesRow {
            t: 0.5,
            axial_length: 23.0,
            equatorial_radius: 11.0,
            retina_minus_blue: 0.1,
            retina_minus_red: -0.5,
            class: Refraction::Emmetropic,
            refraction_d: 0.1,
            drive: -0.1,
            defocus_d: f64::NAN,
        };
        let snap = Snapshot {
            t: 0.5,
            fields: vec![],
            growth: vec![],
            series: row,
            peripheral: vec![],
            through: vec![],
        };
        let mut bar = GrowthProgress::new(false, Some("choosing the mesh"));
        assert_eq!(bar.bar.message(), "choosing the mesh");
        bar.snapshot(&snap).unwrap();
        bar.progress(0.25, 1.0).unwrap();
        assert_eq!(bar.bar.position(), 250);
        bar.progress(f64::NAN, 1.0).unwrap(); // ignored
        bar.progress(3.0, 0.0).unwrap(); // ignored: no end
        assert_eq!(bar.bar.position(), 250);
        assert_eq!(
            bar.bar.message(),
            "t = 0.5000: axial length 23.0000 mm, emmetropic"
        );
        bar.finish();
        // --quiet: no bar whatever the terminal.
        assert!(!wanted(true));
    }
}
