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
use std::sync::Arc;

use crate::bvp::Solution;
use crate::growth::{
    self, GrowthStats, Observer, ObserverError, SensitivityRow, SeriesRow, Snapshot,
};
use crate::model::rule::GrowthRule;
use crate::rundir::growth::{snapshot_name_at, SNAPSHOT_DIR};
use crate::rundir::summary::{ElasticSummary, GrowthSummary, RunStatus, SnapshotEntry, Summary};
use crate::scene::sweep::Sweep;
use crate::scene::{Scene, SceneError};
use crate::sweep::{run_sweep, RunRecord, SweepOptions, SweepReport};
use crate::{Error, Origin, Subject};

impl Scene {
    /// Read, validate and return the scene in the TOML file `path` (the keys are listed by
    /// `eyeshell keys` and in [`crate::scene::KEYS`]).
    ///
    /// # Errors
    /// [`SceneError::Read`] for a file that cannot be read, [`SceneError::Syntax`] for one
    /// that is not TOML, and the other [`SceneError`] variants for a key that is not a
    /// scene key, of the wrong type or out of range ([`SceneError::key`],
    /// [`SceneError::value`] and [`SceneError::origin`] say which, as written, where);
    /// [`SceneError::IsSweep`] for a file with a `[sweep]` table.
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
    /// # Errors
    /// A [`SceneError`] for a key that is not a scene key ([`SceneError::UnknownKey`]), a
    /// value of the wrong type ([`SceneError::WrongType`]) or out of range
    /// ([`SceneError::Invalid`]), its origin the override (`--set key=value`).
    ///
    /// ```
    /// let mut scene = eyeshell::Scene::default_scene();
    /// scene.set("fibres.D", 200)?;
    /// assert_eq!(scene.params.d, 200.0);
    /// assert!(scene.set("fibres.D", -1).is_err());
    /// assert_eq!(scene.params.d, 200.0);
    /// // The error blames the value set, not the scene it was set on.
    /// let e = scene.set("fibres.D", -1).unwrap_err().to_string();
    /// assert!(e.starts_with("--set fibres.D=-1: fibres.D"), "{e}");
    /// # Ok::<(), eyeshell::scene::SceneError>(())
    /// ```
    pub fn set(&mut self, key: &str, value: impl std::fmt::Display) -> Result<(), SceneError> {
        self.set_all([(key, value)])
    }

    /// Set every `(key, value)` of `assignments` as [`Scene::set`] sets one, in order, then
    /// validate once: keys that are only valid together (`growth.t_end` and
    /// `output.times`) are set together. On an error the scene is left as it was.
    ///
    /// # Errors
    /// As [`Scene::set`], for the first assignment that does not apply or validate.
    ///
    /// ```
    /// let mut scene = eyeshell::Scene::default_scene();
    /// scene.set_all([("growth.t_end", "0.2"), ("output.times", "[0.1, 0.2]")])?;
    /// assert_eq!(scene.growth.as_ref().unwrap().t_end, 0.2);
    /// # Ok::<(), eyeshell::scene::SceneError>(())
    /// ```
    pub fn set_all<K: AsRef<str>, V: std::fmt::Display>(
        &mut self,
        assignments: impl IntoIterator<Item = (K, V)>,
    ) -> Result<(), SceneError> {
        let mut changed = self.clone();
        let texts: Vec<String> = assignments
            .into_iter()
            .map(|(key, value)| format!("{}={value}", key.as_ref()))
            .collect();
        changed.apply_overrides_and_validate(&texts)?;
        changed.resolve_optics()?;
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
    ///
    /// # Errors
    /// [`Error::Scene`] or [`Error::Model`] (the user's: [`Error::is_user_error`]) for a
    /// scene whose problem cannot be built, e.g. ΔP above the cornea's limit;
    /// [`Error::Bvp`] or [`Error::Sundials`] when the solve fails (Newton does not
    /// converge, `solver.max_seconds` runs out), [`Error::stage`] `Solve`.
    pub fn solve(&self) -> Result<Solution, Error> {
        Ok(self.elastic_problem()?.solve()?)
    }

    /// Grow the eye of the scene from t = 0 to `growth.t_end`, handing every snapshot to
    /// `observer` as it comes (`&mut ()` for none), and return the run.
    ///
    /// # Errors
    /// [`Error::Input`] about the key `growth` for a scene without a `[growth]` section,
    /// [`Error::Scene`] or [`Error::Model`] for a problem that cannot be built;
    /// [`Error::Growth`] when the run stops (an integrator's failure, the observer's
    /// error, `solver.max_seconds`), with the time and the work done.
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
        let Some(problem) = self.growth_problem()? else {
            return Err(Error::input(
                Subject::Key("growth".into()),
                format!(
                    "{}: the scene has no [growth] section (set a growth key, e.g. growth.eta0)",
                    self.origin
                ),
            )
            .with_origin(Origin::Scene(self.origin.clone())));
        };
        let mut record = Record {
            inner: observer,
            snapshots: Vec::new(),
            history: Vec::new(),
            sensitivities: Vec::new(),
        };
        let stats = growth::grow(&problem, &mut record)?;
        Ok(Growth {
            stats,
            series: record.snapshots.iter().map(|s| s.series).collect(),
            last: record.snapshots.last().cloned(),
            snapshots: record.snapshots,
            history: record.history,
            sensitivities: record.sensitivities,
        })
    }

    /// Grow with `rule`, a growth rule given in code (a [`GrowthRule`] trait object: Rust's,
    /// or Python's), instead of the one `stimulus.rule` chooses (docs/MODEL.md §6, "Growth
    /// rules"). The rule is the scene's until a key of the built-in rules (`stimulus.rule`,
    /// `stimulus.baseline`, the gains) is set, which chooses a built-in rule again; other
    /// keys leave it. Refused (bad input) for a scene that does not grow. The scene's TOML
    /// and summary name the keys, not this rule.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use eyeshell::model::rule::BlueSurface;
    ///
    /// let mut scene = eyeshell::Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/const.toml"))?;
    /// scene.set("solver.nodes", 51)?;
    /// let builtin = scene.grow(&mut ())?;
    /// scene.set_rule(Arc::new(BlueSurface))?; // the paper's rule, as a value
    /// scene.set("growth.Gamma", 8)?; // keeps the rule given
    /// assert!(!scene.growth.as_ref().unwrap().stimulus.is_builtin());
    /// let given = scene.grow(&mut ())?;
    /// let axial = |g: &eyeshell::Growth| g.series.iter().map(|r| r.axial_length).collect::<Vec<_>>();
    /// assert_eq!(axial(&builtin), axial(&given)); // the same arithmetic: bit for bit
    /// scene.set("stimulus.rule", "blue-surface")?; // a built-in rule again
    /// assert!(scene.growth.as_ref().unwrap().stimulus.is_builtin());
    /// assert!(eyeshell::Scene::default_scene().set_rule(Arc::new(BlueSurface)).is_err());
    /// # Ok::<(), eyeshell::Error>(())
    /// ```
    pub fn set_rule(&mut self, rule: Arc<dyn GrowthRule>) -> Result<(), Error> {
        let Some(growth) = self.growth.as_mut() else {
            return Err(Error::input(
                crate::error::Subject::Key("stimulus.rule".into()),
                format!(
                    "{}: a growth rule needs a growing scene (set a growth key, e.g. growth.eta0)",
                    self.origin
                ),
            ));
        };
        growth.stimulus.set_rule(rule);
        Ok(())
    }

    /// Ask the growth run for its forward sensitivities to the scene keys `keys` (each once;
    /// [`crate::growth::dae::SensParam`] lists the supported ones), as `eyeshell grow
    /// --sensitivities` does: [`Growth::sensitivities`] then holds one row per recorded
    /// time and key. `error_control`: include them in IDAS's local error test. An empty
    /// list turns them off. Refused (bad input, naming the key) for an unsupported or
    /// repeated key, an integrator other than IDA, or error control without a key (it
    /// would be silently without effect; the command line's `--sensitivity-error-control`
    /// requires `--sensitivities` for the same reason).
    ///
    /// # Errors
    /// [`Error::Input`] naming the key (or the argument `error_control`) for each refusal
    /// above, with the scene's origin where the scene is at fault.
    ///
    /// ```
    /// let mut scene = eyeshell::Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/const.toml"))?;
    /// scene.set("solver.nodes", 101)?;
    /// scene.set_sensitivities(&["growth.Gamma"], false)?;
    /// let growth = scene.grow(&mut ())?;
    /// let last = growth.sensitivities.last().unwrap();
    /// assert_eq!((last.t, last.parameter), (1.0, "growth.Gamma"));
    /// assert!(last.d_axial_length > 0.0); // a later fall of the capacity: a longer eye
    /// # Ok::<(), eyeshell::Error>(())
    /// ```
    pub fn set_sensitivities(
        &mut self,
        keys: &[impl AsRef<str>],
        error_control: bool,
    ) -> Result<(), Error> {
        if keys.is_empty() && error_control {
            return Err(Error::input(
                Subject::Argument("error_control".into()),
                "sensitivity error control needs sensitivities: name the scene keys to differentiate (e.g. growth.eta0)",
            )
            .with_value(true)
            .with_origin(Origin::Argument));
        }
        if keys.is_empty() {
            self.growth_settings.sensitivities = vec![];
            self.growth_settings.sensitivity_error_control = false;
            return Ok(());
        }
        let params = crate::fit::parse_keys(keys, "sensitivities")?;
        crate::fit::check_params(self, &params, "sensitivities")?;
        self.growth_settings.sensitivities = params.iter().filter_map(|p| p.param).collect();
        self.growth_settings.sensitivity_error_control = error_control;
        Ok(())
    }

    /// Fit the parameters `keys` of this growth scene to the observations `data` (start
    /// values: the scene's) by Levenberg–Marquardt on the weighted residuals, the Jacobian
    /// being the run's forward sensitivities, as `eyeshell fit` does ([`crate::fit`]).
    ///
    /// # Errors
    /// [`Error::Input`] for a key that cannot be fitted, a scene that cannot grow or has no
    /// IDA integrator, too few observations or observations outside the run (naming the
    /// key, the data file and the value); [`Error::Growth`] when a run of the fit fails,
    /// [`Error::Failed`] (stage `Fit`) when the iterations end without a result.
    pub fn fit(
        &self,
        data: &crate::fit::Observations,
        keys: &[impl AsRef<str>],
        options: &crate::fit::FitOptions,
    ) -> Result<crate::fit::Fit, Error> {
        self.fit_observed(data, keys, options, &mut ())
    }

    /// [`Scene::fit`], calling `observer.progress(t, t_end)` after every step of every
    /// growth run of the fit: an error from it stops the fit there (a caller's Ctrl-C).
    ///
    /// # Errors
    /// As [`Scene::fit`]; the observer's error stops the run as an [`Error::Growth`].
    pub fn fit_observed(
        &self,
        data: &crate::fit::Observations,
        keys: &[impl AsRef<str>],
        options: &crate::fit::FitOptions,
        observer: &mut dyn Observer,
    ) -> Result<crate::fit::Fit, Error> {
        let params = crate::fit::parse_fit_keys(keys, "fit")?;
        let t_end = self.growth.as_ref().map_or(f64::NAN, |g| g.t_end);
        crate::fit::fit_watched(self, data, &params, options, &mut |_| {}, &mut |t| {
            observer.progress(t, t_end)
        })
    }

    /// The refraction without growing: of the retina of `solution`, a solve of this scene
    /// (the loaded, ungrown shell: a growth run's retina at t = 0), through the naked eye and
    /// through the lenses worn, at the pole and at each field angle
    /// ([`crate::growth::refraction::of_retina`]): at t = 0, and for optics that change with
    /// age at each table time. The optics are [`Scene::refraction_optics`]'s, so the naked
    /// eye's values at t = 0 are a growth run's first `refraction_D` and peripheral rows.
    ///
    /// # Errors
    /// Bad input about `stimulus.source` for a scene with no optics to compute it with (it
    /// neither grows nor computes its optics), and the optics key to change when the
    /// refraction cannot be traced (a wavelength out of range, a lens a trial lens cannot
    /// be held against).
    ///
    /// ```
    /// let mut scene = eyeshell::Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/const.toml"))?;
    /// scene.set("solver.nodes", 101)?;
    /// let at = scene.refraction(&scene.solve()?)?;
    /// assert_eq!(at[0].t, 0.0);
    /// assert!((at[0].pole_d - 10.46).abs() < 0.01); // the const scene's start
    /// // The shell alone has no eye to refract through: one line naming stimulus.source.
    /// let e = eyeshell::Scene::default_scene().refraction(&scene.solve()?).unwrap_err();
    /// assert!(e.is_user_error() && e.key().as_deref() == Some("stimulus.source"));
    /// assert!(!e.to_string().contains('\n') && e.to_string().contains("no optics"), "{e}");
    /// # Ok::<(), eyeshell::Error>(())
    /// ```
    pub fn refraction(
        &self,
        solution: &Solution,
    ) -> Result<Vec<crate::growth::refraction::RefractionAt>, Error> {
        let Some(spec) = self.refraction_optics() else {
            return Err(Error::input(
                Subject::Key("stimulus.source".into()),
                format!("{}: {}", self.origin, self.no_refraction_optics()),
            )
            .with_value("polynomial")
            .with_origin(Origin::Scene(self.origin.clone())));
        };
        let mut times = spec.times();
        if times.is_empty() {
            times.push(0.0);
        }
        let retina = Scene::retina_of(&solution.rows);
        crate::growth::refraction::of_retina(&spec, self.blue().z_b, &retina, &times).map_err(|e| {
            Error::from(SceneError::Invalid {
                origin: self.origin_of_key(&e.key),
                key: e.key.to_string(),
                value: e.value,
                problem: e.problem,
            })
        })
    }

    /// The text of the summary.json `eyeshell solve` writes for `solution`, a solve of this
    /// scene (a library caller gets the same record without a run directory).
    pub fn solve_summary(&self, solution: &Solution) -> String {
        Summary::Elastic(ElasticSummary::of_solution(self, solution)).to_text()
    }

    /// The text of the summary.json `eyeshell grow` writes for `growth`, a finished growth
    /// of this scene: the snapshots named as `eyeshell grow` names their files.
    pub fn grow_summary(&self, growth: &Growth) -> String {
        let entries: Vec<SnapshotEntry> = growth
            .snapshots
            .iter()
            .enumerate()
            .map(|(k, s)| SnapshotEntry {
                t: s.t,
                file: format!(
                    "{SNAPSHOT_DIR}/{}",
                    snapshot_name_at(k, s.t, self.growth.as_ref().and_then(|g| g.age_of(s.t)))
                ),
            })
            .collect();
        let status = RunStatus::Ok(&growth.stats);
        let last = growth.series.last();
        Summary::Growth(GrowthSummary::new(self, status, &entries, last)).to_text()
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
    /// equatorial radius, the retina against the best-focus surfaces (series.csv).
    pub series: Vec<SeriesRow>,
    /// The last snapshot: every field at every node at t_end.
    pub last: Option<Snapshot>,
    /// Every snapshot, in time order (the files `snapshots/*.csv` of `eyeshell grow`).
    pub snapshots: Vec<Snapshot>,
    /// The series row at every recorded time when `output.history_points` > 0 (history.csv);
    /// empty otherwise.
    pub history: Vec<SeriesRow>,
    /// With [`Scene::set_sensitivities`]: one row per recorded time and parameter, in the
    /// order of sensitivities.csv; empty otherwise.
    pub sensitivities: Vec<SensitivityRow>,
}

/// Keeps the snapshots, the history rows and the sensitivities, and passes everything on.
struct Record<'a> {
    inner: &'a mut dyn Observer,
    snapshots: Vec<Snapshot>,
    history: Vec<SeriesRow>,
    sensitivities: Vec<SensitivityRow>,
}

impl Observer for Record<'_> {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.inner.snapshot(s)?;
        self.snapshots.push(s.clone());
        Ok(())
    }

    fn history(&mut self, row: &SeriesRow) -> Result<(), ObserverError> {
        self.inner.history(row)?;
        self.history.push(*row);
        Ok(())
    }

    fn progress(&mut self, t: f64, t_end: f64) -> Result<(), ObserverError> {
        self.inner.progress(t, t_end)
    }

    fn sensitivities(&mut self, rows: &[SensitivityRow]) -> Result<(), ObserverError> {
        self.inner.sensitivities(rows)?;
        self.sensitivities.extend_from_slice(rows);
        Ok(())
    }
}

impl Sweep {
    /// Run every run of the sweep into `out` (`out/runs/<name>/`, `sweep.csv`,
    /// `summary.json`), `jobs` at a time (0: one per core), as `eyeshell sweep` does; `done`
    /// is called after each run. A failed run is recorded and the others go on. The runs
    /// are threads of this process ([`InProcess`](crate::sweep::InProcess)), so a run that
    /// aborts ends it; `run_sweep` takes another [`Runner`](crate::sweep::Runner).
    ///
    /// # Errors
    /// [`Error::Output`] or [`Error::Input`] (about the file) for an `out` that holds
    /// something other than this sweep's runs, [`Error::Io`] when it cannot be written.
    /// A run that fails is not an error: its record says why.
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
            inputs: &[],
        };
        run_sweep(self, out.as_ref(), &options, done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small_growth() -> Scene {
        let mut scene = Scene::default_scene();
        scene.set("solver.nodes", 101).unwrap();
        scene.set("growth.eta0", 70).unwrap(); // any growth key turns growth on
        scene.set("output.history_points", 10).unwrap();
        scene
    }

    /// Stops the run at its `n`-th step.
    struct StopAt {
        n: usize,
        seen: Vec<f64>,
    }

    impl Observer for StopAt {
        fn snapshot(&mut self, _s: &Snapshot) -> Result<(), ObserverError> {
            Ok(())
        }

        fn progress(&mut self, t: f64, _t_end: f64) -> Result<(), ObserverError> {
            self.seen.push(t);
            if self.seen.len() == self.n {
                return Err("stopped by the caller".into());
            }
            Ok(())
        }
    }

    #[test]
    fn an_error_from_progress_stops_the_run_at_that_step() {
        let mut stop = StopAt { n: 3, seen: vec![] };
        let Err(Error::Growth(e)) = small_growth().grow(&mut stop) else {
            panic!("the run went on");
        };
        assert_eq!(stop.seen.len(), 3);
        assert_eq!(e.t, stop.seen[2]);
        assert!(e.t > 0.0 && e.t < 1.0 && e.reason.contains("stopped by the caller"));
    }

    #[test]
    fn an_error_from_progress_stops_a_fit_at_that_step() {
        let scene = small_growth();
        let data = crate::fit::Observations::from_columns(
            &[0.5, 1.0],
            &[24.0, 25.0],
            Some(&[0.1, 0.1]),
            "data",
        )
        .unwrap();
        let mut stop = StopAt { n: 5, seen: vec![] };
        let options = crate::fit::FitOptions::default();
        let e = scene
            .fit_observed(&data, &["growth.eta0"], &options, &mut stop)
            .unwrap_err();
        // Stopped within the first growth run, at the step the observer refused.
        assert_eq!(stop.seen.len(), 5);
        assert!(e.to_string().contains("stopped by the caller"), "{e}");
    }

    #[test]
    fn error_control_without_sensitivities_is_refused() {
        let mut scene = small_growth();
        let e = scene.set_sensitivities(&[] as &[&str], true).unwrap_err();
        assert!(e.is_user_error());
        assert!(e.to_string().contains("needs sensitivities"), "{e}");
        assert!(!scene.growth_settings.sensitivity_error_control);
        scene.set_sensitivities(&[] as &[&str], false).unwrap();
    }

    #[test]
    fn a_growth_keeps_every_snapshot_and_its_history() {
        let scene = small_growth();
        let growth = scene.grow(&mut ()).unwrap();
        let times: Vec<f64> = growth.snapshots.iter().map(|s| s.t).collect();
        assert_eq!(times, [0.0, 0.1, 0.2, 0.4, 1.0]);
        assert_eq!(growth.series.len(), 5);
        // Field for field, NaN included (defocus_D is NaN where the rule reads none).
        assert_eq!(
            format!("{:?}", growth.series[4]),
            format!("{:?}", growth.snapshots[4].series)
        );
        // The history: t = 0, then t_end·k/10 (the snapshot times among them, once each).
        let history: Vec<f64> = growth.history.iter().map(|r| r.t).collect();
        let expected: Vec<f64> = (0..=10).map(|k| k as f64 / 10.0).collect();
        assert_eq!(history, expected);
        let summary: serde_json::Value =
            serde_json::from_str(&scene.grow_summary(&growth)).unwrap();
        assert_eq!(summary["status"], "ok");
        assert_eq!(
            summary["snapshots"][4]["file"],
            "snapshots/snapshot_00004_t1.000000.csv"
        );
    }
}
