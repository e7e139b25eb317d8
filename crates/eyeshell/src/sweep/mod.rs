//! Running a sweep ([`crate::scene::sweep::Sweep`]): every run in parallel across the cores
//! (rayon), each into its own directory, and a table of the results kept up to date.
//!
//! Layout of the output directory:
//! - `runs/<name>/`: an ordinary run directory (`eyeshell solve` or `eyeshell grow` output),
//!   plus `scene.toml` (the run's effective scene) and, once it has finished, `result.json`;
//! - `sweep.csv`: one row per run (status, swept values, final axial length, class, solver
//!   statistics, error), rewritten after every run (for more than [`TABLE_EVERY_RUN`] runs,
//!   at most every [`TABLE_INTERVAL`]);
//! - `summary.json`: the same as JSON with the sweep's status (`running`, `ok`, `partial`
//!   when some runs failed, `interrupted`);
//! - `population.json`, `population.csv` (and `sobol.csv`): for a sampled sweep
//!   (`[sweep.sample]`), the cohort's statistics once every run has ended ([`population`]);
//! - `shards/K.json`: with `--shard K/N` ([`run_shard`]), the record of shard K, which
//!   writes neither sweep.csv nor summary.json; [`merge`] writes them from the runs.
//!
//! A run that fails keeps what it wrote and its error goes into the table; the others go
//! on. How a run is executed is the caller's choice ([`Runner`]): on a thread of this
//! process by default ([`InProcess`]), where an abort would end the whole sweep, or in a
//! process of its own (the command line). When `cancel` is raised (Ctrl-C), no new run
//! starts, the running ones finish and the table says which runs did not run. With
//! `resume`, a run whose directory holds a `result.json`, the same `scene.toml` and the
//! files result.json lists, unchanged, is not run again ([`resume`]); the directory is
//! checked first ([`target`]).
//!
//! - [`run`]: one run, executed ([`execute`]) by a [`Runner`];
//! - [`files`]: the files a run wrote, recorded in result.json and verified on resume;
//! - [`resume`]: which runs of an earlier sweep are reused;
//! - [`shard`]: one shard of a sweep (`--shard K/N`), and the merge of the shards' runs;
//! - [`target`]: the output directory, refused when resuming would read or write outside
//!   it, or mix a sweep with something else;
//! - [`twin`]: runs that are the same run, solved once and copied to each.

pub mod compact;
pub mod files;
pub mod population;
pub mod resume;
pub mod run;
pub mod shard;
pub mod target;
pub mod twin;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use rayon::prelude::*;

use crate::rundir::summary::{SweepRunEntry, SweepSummary};
use crate::rundir::table::{csv_bytes, QuoteStyle};
use crate::rundir::{self, format_value, write_atomic, OutputError, Summary};
use crate::scene::sample::PerRun;
use crate::scene::sweep::{Sweep, SweepPlan};
use crate::Error;

use resume::Reuse;
pub use run::{execute, run_scene, InProcess, RunFailure, Runner};
pub use shard::{merge, Shard, ShardRecord, SHARDS_DIR};

/// The run directories, under the sweep's directory.
pub const RUNS_DIR: &str = "runs";
/// The results table.
pub const TABLE_FILE: &str = "sweep.csv";
/// A run's effective scene.
pub const SCENE_FILE: &str = "scene.toml";
/// A finished run's results.
pub const RESULT_FILE: &str = "result.json";

/// How the sweep is run.
pub struct SweepOptions<'a> {
    /// Runs at once (threads); 0: one per core.
    pub jobs: usize,
    /// Reuse finished runs of an earlier sweep into the same directory.
    pub resume: bool,
    /// Raised to stop starting runs.
    pub cancel: &'a AtomicBool,
    /// How each run is executed: `&InProcess`, or a runner that isolates runs.
    pub runner: &'a dyn Runner,
    /// What the sweep is made from (its scene file): a fresh sweep's directory may not be,
    /// hold or lie inside one of them ([`crate::rundir::owner::admit`]).
    pub inputs: &'a [&'a Path],
}

/// The final state of one run, for the table (and its result.json).
pub use crate::rundir::summary::RunResult;

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum RunStatus {
    /// Not started yet (or never: the sweep was interrupted).
    Pending,
    Ok,
    /// Finished in an earlier sweep and reused (`resume`).
    Reused,
    /// Stopped by an error: the message, and the results up to then if any.
    Failed(String),
}

/// The most characters of a failed run's message (or of why a run ran again) that a line
/// of the command line quotes; the run's summary.json and sweep.csv keep it whole.
pub const SHOWN_MESSAGE: usize = 300;

impl RunStatus {
    /// A failed run's message as one bounded line ([`crate::text::excerpt`]): what every
    /// report of a sweep prints, however many lines or characters the message has.
    pub fn message_line(&self) -> Option<String> {
        match self {
            RunStatus::Failed(m) => Some(crate::text::excerpt(m.trim(), SHOWN_MESSAGE)),
            _ => None,
        }
    }

    fn as_str(&self) -> &'static str {
        match self {
            RunStatus::Pending => "not run",
            RunStatus::Ok => "ok",
            RunStatus::Reused => "reused",
            RunStatus::Failed(_) => "failed",
        }
    }
}

/// One row of the table.
#[derive(Clone, Debug)]
pub struct RunRecord {
    pub name: String,
    /// The run directory, relative to the sweep's.
    pub dir: String,
    /// The swept values, in the order of [`Sweep::keys`].
    pub values: Vec<String>,
    pub status: RunStatus,
    pub result: Option<RunResult>,
    /// Why a run an earlier sweep had finished ran again (`resume`): "its scene changed",
    /// "fields.csv was changed after the run wrote it", ...
    pub rerun: Option<String>,
}

impl RunRecord {
    /// "ok: axial length 23.5809 mm, emmetropic (0.41 s)", "FAILED: why", ..., followed by
    /// "; ran again: why" when a finished run of an earlier sweep could not be reused.
    pub fn status_text(&self) -> String {
        let status = self.outcome_text();
        match &self.rerun {
            Some(why) => format!(
                "{status}; ran again: {}",
                crate::text::excerpt(why, SHOWN_MESSAGE)
            ),
            None => status,
        }
    }

    fn outcome_text(&self) -> String {
        match (&self.status, &self.result) {
            (status @ RunStatus::Failed(_), _) => {
                format!("FAILED: {}", status.message_line().unwrap_or_default())
            }
            (s, Some(x)) => format!(
                "{}: axial length {:.4} mm, {} ({:.2} s)",
                s.as_str(),
                x.eye.number("axial_length"),
                x.eye.class(),
                x.wall_seconds
            ),
            (s, None) => s.as_str().to_string(),
        }
    }
}

/// The outcome of a sweep.
#[derive(Clone, Debug)]
pub struct SweepReport {
    pub records: Vec<RunRecord>,
    pub interrupted: bool,
    pub dir: PathBuf,
}

impl SweepReport {
    /// The runs that failed.
    pub fn failed(&self) -> impl Iterator<Item = &RunRecord> {
        self.records
            .iter()
            .filter(|r| matches!(r.status, RunStatus::Failed(_)))
    }

    /// "ok", "partial", "interrupted" (or "running" while it runs).
    pub fn status(&self) -> &'static str {
        if self.interrupted {
            "interrupted"
        } else if self.failed().next().is_some() {
            "partial"
        } else if self.records.iter().any(|r| r.status == RunStatus::Pending) {
            "running"
        } else {
            "ok"
        }
    }
}

/// Run every run of `sweep` into `out`; `done(record, finished, total)` is called as each
/// run ends. Errors are those of the sweep's own files and directory (a refusal of `out` is
/// bad input, see [`target`]); a run's failure is a row.
pub fn run_sweep(
    sweep: &Sweep,
    out: &Path,
    options: &SweepOptions<'_>,
    done: &(dyn Fn(&RunRecord, usize, usize) + Sync),
) -> Result<SweepReport, Error> {
    target::refuse_running_shards(out)?;
    // The sweep's directory, owned and locked until the sweep ends.
    let names: std::collections::HashSet<&str> =
        sweep.runs.iter().map(|r| r.name.as_str()).collect();
    let mut owned = target::prepare(&|n| names.contains(n), out, options.resume, options.inputs)?;
    if sweep.sample.as_ref().map(|s| s.per_run) == Some(PerRun::Table) {
        let (report, series) = compact::run(sweep, out, &mut owned, options, done)?;
        let ages = sweep
            .runs
            .first()
            .is_some_and(|r| compact::counts_ages(&r.scene));
        let text = |r: &RunRecord| {
            series
                .get(&r.name)
                .map(|rows| compact::series_text(rows, ages))
        };
        write_population_with(sweep.into(), &report, &text)?;
        return Ok(report);
    }
    let all: Vec<usize> = (0..sweep.runs.len()).collect();
    let report = run_some(
        sweep,
        &all,
        out,
        options,
        &|r| write_tables(sweep.into(), r),
        done,
    )?;
    write_population(sweep.into(), &report)?;
    Ok(report)
}

/// A sampled sweep's population results ([`population`]), once every run has ended (an
/// interrupted sweep writes none: its cohort is not the one described); None otherwise.
pub fn write_population(
    head: Head<'_>,
    report: &SweepReport,
) -> Result<Option<population::Written>, OutputError> {
    let text = |r: &RunRecord| {
        std::fs::read_to_string(
            report
                .dir
                .join(&r.dir)
                .join(crate::rundir::growth::SERIES_FILE),
        )
        .ok()
    };
    write_population_with(head, report, &text)
}

/// [`write_population`] with each eye's series.csv text from `series` (None: it has none).
fn write_population_with(
    head: Head<'_>,
    report: &SweepReport,
    series: &dyn Fn(&RunRecord) -> Option<String>,
) -> Result<Option<population::Written>, OutputError> {
    let Some(sample) = head.sample else {
        return Ok(None);
    };
    if report.interrupted
        || report
            .records
            .iter()
            .any(|r| r.status == RunStatus::Pending)
    {
        return Ok(None);
    }
    let names = population::Names {
        sweep: head.name,
        age_unit: head.age_unit,
    };
    population::write(&report.dir, names, sample, &report.records, series).map(Some)
}

/// Run the runs of `shard` ([`shard::runs_of`]) into `out`, as [`run_sweep`] runs them,
/// beside any other shard of the same sweep writing into `out` at the same time: the
/// shard writes its runs and `out/shards/K.json` only ([`shard`]). The plan's runs are
/// validated one at a time and only the shard's own are built ([`SweepPlan`]); a shard may
/// hold at most [`crate::scene::sweep::MAX_RUNS`] runs. The report holds the shard's runs.
pub fn run_shard(
    plan: &SweepPlan,
    out: &Path,
    shard: Shard,
    options: &SweepOptions<'_>,
    done: &(dyn Fn(&RunRecord, usize, usize) + Sync),
) -> Result<SweepReport, Error> {
    let mine = shard::runs_of(plan, shard)?;
    let sweep = plan.sweep_of(&mine)?;
    // The shard's record, locked until the shard ends (the directory is shared).
    let (record, _lock) = target::prepare_shard(&|n| plan.has_name(n), out, shard)?;
    let write = |report: &SweepReport| ShardRecord::new(&sweep, shard, report).write(&record);
    let all: Vec<usize> = (0..sweep.runs.len()).collect();
    run_some(&sweep, &all, out, options, &write, done)
}

/// Run `indices` of `sweep.runs` into `out`, calling `write` with the report at the start,
/// after each run and at the end.
fn run_some(
    sweep: &Sweep,
    indices: &[usize],
    out: &Path,
    options: &SweepOptions<'_>,
    write: &(dyn Fn(&SweepReport) -> Result<(), OutputError> + Sync),
    done: &(dyn Fn(&RunRecord, usize, usize) + Sync),
) -> Result<SweepReport, Error> {
    let records: Vec<RunRecord> = indices
        .iter()
        .map(|&i| &sweep.runs[i])
        .map(|r| RunRecord {
            name: r.name.clone(),
            dir: format!("{RUNS_DIR}/{}", r.name),
            values: sweep.keys.iter().map(|k| r.shown(k)).collect(),
            status: RunStatus::Pending,
            result: None,
            rerun: None,
        })
        .collect();
    let report = Mutex::new(SweepReport {
        records,
        interrupted: false,
        dir: out.to_path_buf(),
    });
    write(&lock(&report))?;
    let total = indices.len();
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let table_error: Mutex<Option<OutputError>> = Mutex::new(None);
    let last_write = Mutex::new(std::time::Instant::now());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs)
        .build()
        .map_err(|e| io(out, std::io::Error::other(e.to_string())))?;
    pool.install(|| {
        indices.par_iter().enumerate().for_each(|(i, &index)| {
            let run = &sweep.runs[index];
            if options.cancel.load(Ordering::SeqCst) {
                lock(&report).interrupted = true;
                return;
            }
            let dir = out.join(RUNS_DIR).join(&run.name);
            let earlier = if options.resume {
                resume::reusable(run, &dir)
            } else {
                Reuse::No
            };
            let (status, result, rerun) = match earlier {
                Reuse::Yes(r) => (RunStatus::Reused, Some(r), None),
                Reuse::No => {
                    let (status, result) = options.runner.run(run, &dir);
                    (status, result, None)
                }
                Reuse::Stale(why) => {
                    let (status, result) = options.runner.run(run, &dir);
                    (status, result, Some(why))
                }
            };
            let mut rep = lock(&report);
            rep.records[i].status = status;
            rep.records[i].result = result;
            rep.records[i].rerun = rerun;
            let n = finished.fetch_add(1, Ordering::SeqCst) + 1;
            if table_due(total, &mut lock(&last_write)) {
                if let Err(e) = write(&rep) {
                    lock(&table_error).get_or_insert(e);
                }
            }
            done(&rep.records[i], n, total);
        });
    });
    let report = report.into_inner().unwrap_or_else(|e| e.into_inner());
    write(&report)?;
    match table_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
        Some(e) => Err(e.into()),
        None => Ok(report),
    }
}

/// Up to this many runs the table is rewritten after every run; a larger sweep's at most
/// once every [`TABLE_INTERVAL`]: each rewrite is the whole table, so rewriting it after
/// each of 10,000 runs would write 10,000 tables (gigabytes). It is always written at the
/// start and the end; the runs' own result.json files are what `--resume` and `merge` trust.
pub const TABLE_EVERY_RUN: usize = 1000;
/// See [`TABLE_EVERY_RUN`].
pub const TABLE_INTERVAL: std::time::Duration = std::time::Duration::from_secs(2);

/// Whether the table is to be rewritten after a run ends (`last`: when it last was).
fn table_due(runs: usize, last: &mut std::time::Instant) -> bool {
    if runs > TABLE_EVERY_RUN && last.elapsed() < TABLE_INTERVAL {
        return false;
    }
    *last = std::time::Instant::now();
    true
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn io(path: &Path, e: std::io::Error) -> OutputError {
    OutputError::Io {
        path: path.to_path_buf(),
        source: e,
    }
}

/// The columns of sweep.csv after `run`, `status` and the swept keys: `kind`, `t` (and
/// `age` with `ages`), the measures of the eye (the table of outputs,
/// [`crate::outputs::quantities`]), then the run's work and its error.
pub fn result_columns(ages: bool) -> Vec<&'static str> {
    let mut columns = vec!["kind", "t"];
    if ages {
        columns.push(crate::rundir::growth::AGE_COLUMN);
    }
    columns.extend(crate::outputs::quantities().iter().map(|q| q.name));
    columns.extend(WORK_COLUMNS);
    columns.push("error");
    columns
}

/// The columns of sweep.csv after the measures: what a run cost.
const WORK_COLUMNS: [&str; 5] = [
    "newton_iterations",
    "bvp_solves",
    "steps",
    "rhs_evaluations",
    "wall_seconds",
];

/// What sweep.csv and summary.json say of the sweep itself: a [`Sweep`]'s or a
/// [`SweepPlan`]'s name, scene and keys.
#[derive(Clone, Copy)]
pub struct Head<'a> {
    pub name: &'a str,
    pub origin: &'a str,
    pub keys: &'a [String],
    /// The cohort of a sampled sweep.
    pub sample: Option<&'a crate::scene::sample::Sample>,
    /// time.unit of the sweep's scene when it counts in ages: the unit of the population's
    /// ages.
    pub age_unit: Option<&'static str>,
}

impl<'a> From<&'a Sweep> for Head<'a> {
    fn from(s: &'a Sweep) -> Head<'a> {
        Head {
            name: &s.name,
            origin: &s.origin,
            keys: &s.keys,
            sample: s.sample.as_deref(),
            age_unit: s
                .runs
                .first()
                .and_then(|r| r.scene.growth.as_ref()?.age_unit()),
        }
    }
}

impl<'a> From<&'a SweepPlan> for Head<'a> {
    fn from(s: &'a SweepPlan) -> Head<'a> {
        Head {
            name: &s.name,
            origin: &s.origin,
            keys: &s.keys,
            sample: s.sample.as_deref(),
            age_unit: s.age_unit(),
        }
    }
}

/// sweep.csv and summary.json, written atomically.
fn write_tables(sweep: Head<'_>, report: &SweepReport) -> Result<(), OutputError> {
    let path = report.dir.join(TABLE_FILE);
    table_csv(sweep, report)
        .and_then(|csv| write_atomic(&path, &csv))
        .map_err(|e| io(&path, e))?;
    summary(sweep, report).write(&report.dir)
}

/// The text of sweep.csv: a cell is quoted when it holds a comma, a quote or a line break.
/// An `age` column follows `t` once a run that counts in ages has finished (a scene with
/// time.unit): empty for a run that has no result yet.
pub fn table_csv(sweep: Head<'_>, report: &SweepReport) -> std::io::Result<Vec<u8>> {
    let ages = report
        .records
        .iter()
        .any(|r| r.result.as_ref().is_some_and(|x| x.age.is_some()));
    let header = ["run", "status"]
        .iter()
        .map(|s| s.to_string())
        .chain(sweep.keys.iter().cloned())
        .chain(result_columns(ages).into_iter().map(str::to_string));
    let rows = report.records.iter().map(|r| {
        let mut fields = vec![r.name.clone(), r.status.as_str().to_string()];
        fields.extend(r.values.iter().cloned());
        fields.extend(result_fields(r, ages));
        fields
    });
    csv_bytes(header, rows, QuoteStyle::Necessary)
}

/// A run's cells in [`result_columns`]`(ages)` (its age empty when it has none).
fn result_fields(r: &RunRecord, ages: bool) -> Vec<String> {
    let error = match &r.status {
        RunStatus::Failed(m) => m.clone(),
        _ => String::new(),
    };
    match &r.result {
        Some(x) => {
            let mut v = vec![x.kind.clone(), format_value(x.t)];
            if ages {
                v.push(x.age.map(format_value).unwrap_or_default());
            }
            v.extend(x.eye.0.iter().map(|(_, value)| value.text()));
            v.extend([
                x.newton_iterations.to_string(),
                x.bvp_solves.to_string(),
                x.steps.to_string(),
                x.rhs_evaluations.to_string(),
                format_value(x.wall_seconds),
                error,
            ]);
            v
        }
        None => {
            let mut v = vec![String::new(); result_columns(ages).len() - 1];
            v.push(error);
            v
        }
    }
}

/// summary.json of the sweep.
pub fn summary(sweep: Head<'_>, report: &SweepReport) -> Summary {
    let runs = report
        .records
        .iter()
        .map(|r| SweepRunEntry {
            name: r.name.clone(),
            dir: r.dir.clone(),
            status: r.status.as_str().to_string(),
            values: sweep
                .keys
                .iter()
                .cloned()
                .zip(r.values.iter().cloned())
                .collect(),
            // The list of files is each run's (its result.json), not the sweep's.
            result: r.result.clone().map(|x| RunResult {
                files: Vec::new(),
                ..x
            }),
            error: match &r.status {
                RunStatus::Failed(m) => Some(m.clone()),
                _ => None,
            },
        })
        .collect();
    Summary::Sweep(SweepSummary {
        sweep: sweep.name.to_string(),
        scene: sweep.origin.to_string(),
        status: report.status().to_string(),
        keys: sweep.keys.to_vec(),
        table: TABLE_FILE.to_string(),
        runs_total: report.records.len(),
        runs_failed: report.failed().count(),
        sundials_version: rundir::sundials_version(),
        runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    #[test]
    fn a_large_sweeps_table_is_rewritten_at_most_every_interval() {
        let mut last = Instant::now();
        assert!(
            table_due(TABLE_EVERY_RUN, &mut last),
            "small: after every run"
        );
        assert!(table_due(TABLE_EVERY_RUN, &mut last));
        let mut last = Instant::now();
        assert!(!table_due(TABLE_EVERY_RUN + 1, &mut last));
        let Some(mut last) = Instant::now().checked_sub(TABLE_INTERVAL) else {
            return; // a clock younger than the interval
        };
        assert!(table_due(TABLE_EVERY_RUN + 1, &mut last));
        assert!(!table_due(TABLE_EVERY_RUN + 1, &mut last), "just written");
    }
}
