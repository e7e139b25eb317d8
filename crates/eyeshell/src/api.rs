//! The curated entry points: read a [`Scene`], change its keys, [`Scene::solve`] its loaded
//! shell, [`Scene::grow`] its eye, run a [`Sweep`]. They compute and return values; only a
//! sweep writes files (its run directories), as `eyeshell sweep` does.
//!
//! ```
//! use eyeshell::Scene;
//!
//! let mut scene: Scene = "name = 'sphere'\n[solver]\nnodes = 101\n".parse()?;
//! scene.set("pressure.dP", 2.5)?;
//! let sol = scene.solve()?;
//! let r = sol.column("r").unwrap();
//! assert_eq!(r.len(), sol.rows.len());
//! assert!(sol.stats.residual_norm < 1e-8);
//! # Ok::<(), eyeshell::Error>(())
//! ```

use std::path::Path;

use crate::bvp::{self, Solution, COLUMNS};
use crate::growth::{self, GrowthStats, Observer, ObserverError, SeriesRow, Snapshot};
use crate::scene::sweep::Sweep;
use crate::scene::{Scene, SceneError};
use crate::sweep::{run_sweep, RunRecord, SweepOptions, SweepReport};
use crate::Error;

impl Scene {
    /// Read, validate and return the scene in the TOML file `path` (the keys are listed by
    /// `eyeshell keys` and in [`crate::scene::KEYS`]).
    ///
    /// ```
    /// let scene = eyeshell::Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/const.toml"))?;
    /// assert!(scene.growth.is_some());
    /// # Ok::<(), eyeshell::Error>(())
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::from_file(path.as_ref(), &[])
    }

    /// Set `key` to `value` as `--set key=value` would (the value is read as TOML, else
    /// taken as a string: `scene.set("solver.scheme", "trapezoid")`), then validate. On an
    /// error the scene is left as it was.
    ///
    /// ```
    /// let mut scene = eyeshell::Scene::default_scene();
    /// scene.set("fibres.D", 200)?;
    /// assert_eq!(scene.params.d, 200.0);
    /// assert!(scene.set("fibres.D", -1).is_err());
    /// assert_eq!(scene.params.d, 200.0);
    /// # Ok::<(), eyeshell::scene::SceneError>(())
    /// ```
    pub fn set(&mut self, key: &str, value: impl std::fmt::Display) -> Result<(), SceneError> {
        let mut changed = self.clone();
        changed.apply_override(&format!("{key}={value}"))?;
        changed.validate()?;
        *self = changed;
        Ok(())
    }

    /// The scene with every key at its default (the paper's table, docs/MODEL.md §8).
    pub fn default_scene() -> Scene {
        Scene::from_toml_str("", "defaults", &[]).expect("the defaults form a valid scene")
    }

    /// Solve the loaded elastic shell of the scene (its growth keys, if any, are not used).
    ///
    /// The [`Solution`] holds every field at every node ([`Solution::rows`],
    /// [`Solution::column`]), the continuous interpolant ([`Solution::at`]) and the
    /// diagnostics ([`Solution::stats`]: Newton iterations, residual, first integral).
    pub fn solve(&self) -> Result<Solution, Error> {
        Ok(bvp::solve(&self.params, &self.solver, None)?)
    }

    /// Grow the eye of the scene from t = 0 to `growth.t_end`, handing every snapshot to
    /// `observer` as it comes (`&mut ()` for none), and return the run.
    ///
    /// ```
    /// use eyeshell::Scene;
    ///
    /// let mut scene = Scene::default_scene();
    /// scene.set("solver.nodes", 101)?;
    /// scene.set("growth.eta0", 70)?; // any growth key turns growth on (t_end = 1)
    /// let growth = scene.grow(&mut ())?;
    /// let (first, last) = (growth.series[0], growth.series.last().unwrap());
    /// assert_eq!(last.t, 1.0);
    /// assert!(last.axial_length > first.axial_length); // a myopic eye elongates
    /// # Ok::<(), eyeshell::Error>(())
    /// ```
    pub fn grow(&self, observer: &mut dyn Observer) -> Result<Growth, Error> {
        let Some(params) = &self.growth else {
            return Err(Error::input(format!(
                "{}: the scene has no [growth] section (set a growth key, e.g. growth.eta0)",
                self.origin
            )));
        };
        let mut record = Record {
            inner: observer,
            series: Vec::new(),
            last: None,
        };
        let stats = growth::grow(
            &self.params,
            &self.solver,
            params,
            &self.growth_settings,
            &mut record,
        )?;
        Ok(Growth {
            stats,
            series: record.series,
            last: record.last,
        })
    }
}

impl std::str::FromStr for Scene {
    type Err = SceneError;

    /// Parse and validate a scene from TOML text (named `<string>` in messages).
    fn from_str(text: &str) -> Result<Scene, SceneError> {
        Scene::from_toml_str(text, "<string>", &[])
    }
}

/// A growth run: what it cost, the series of its snapshots and the eye at its end.
#[derive(Clone, Debug)]
pub struct Growth {
    pub stats: GrowthStats,
    /// One row per snapshot (t = 0, each output time, t_end), in time order: axial length,
    /// equatorial radius, the retina against the best-focus surfaces.
    pub series: Vec<SeriesRow>,
    /// The last snapshot: every field at every node at t_end.
    pub last: Option<Snapshot>,
}

/// Keeps the series and the last snapshot, and passes everything on.
struct Record<'a> {
    inner: &'a mut dyn Observer,
    series: Vec<SeriesRow>,
    last: Option<Snapshot>,
}

impl Observer for Record<'_> {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.inner.snapshot(s)?;
        self.series.push(s.series);
        self.last = Some(s.clone());
        Ok(())
    }

    fn history(&mut self, row: &SeriesRow) -> Result<(), ObserverError> {
        self.inner.history(row)
    }

    fn progress(&mut self, t: f64, t_end: f64) {
        self.inner.progress(t, t_end);
    }
}

/// No observer: `scene.grow(&mut ())`.
impl Observer for () {
    fn snapshot(&mut self, _s: &Snapshot) -> Result<(), ObserverError> {
        Ok(())
    }
}

impl Solution {
    /// The values of the field `name` (a column of fields.csv: `Sigma`, `kappa`, `r`, `z`,
    /// `theta`, `Q`, …; see [`COLUMNS`]) at every node, or None for an unknown name.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let j = COLUMNS.iter().position(|&c| c == name)?;
        Some(self.rows.iter().map(|r| r.values()[j]).collect())
    }
}

impl Sweep {
    /// Run every run of the sweep into `out` (`out/runs/<name>/`, `sweep.csv`,
    /// `summary.json`), `jobs` at a time (0: one per core), as `eyeshell sweep` does; `done`
    /// is called after each run. A failed run is recorded and the others go on. The runs
    /// are threads of this process ([`InProcess`](crate::sweep::InProcess)), so a run that
    /// aborts ends it; `run_sweep` takes another [`Runner`](crate::sweep::Runner).
    pub fn run(
        &self,
        out: impl AsRef<Path>,
        jobs: usize,
        done: &(dyn Fn(&RunRecord, usize, usize) + Sync),
    ) -> Result<SweepReport, Error> {
        let cancel = std::sync::atomic::AtomicBool::new(false);
        let options = SweepOptions {
            jobs,
            resume: false,
            cancel: &cancel,
            runner: &crate::sweep::InProcess,
        };
        run_sweep(self, out.as_ref(), &options, done)
    }
}
