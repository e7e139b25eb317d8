//! A sampled sweep without a directory per eye (`per_run = "table"` in `[sweep.sample]`):
//! each eye is computed in memory and leaves a row of sweep.csv and its rows of the
//! sweep's one `series.csv` (a `run` column, then the columns of a run's series.csv, the
//! same text a run directory's series.csv holds). A cohort of 10,000 eyes is otherwise
//! 10,000 directories of scene.toml, summary.json, series.csv, snapshots and result.json,
//! each synced and checksummed: those files, not the numerics, take most of its time.
//!
//! Checkpoint: every finished eye is appended to `eyes.jsonl` (one JSON line: the run's
//! name, the FNV-1a 64 hash of its effective scene, its status, result and series rows),
//! in batches of [`batch_size`] eyes or every [`super::TABLE_INTERVAL`], each batch synced
//! to disk. `--resume` reuses an eye whose line is complete and whose scene hash is the
//! run's; the checkpoint is first rewritten with exactly those lines (a line cut short by a
//! kill, or an eye whose scene changed, is dropped and the eye runs again). Values travel
//! as JSON (exact f64 round trips) and series rows as their text, so a resumed sweep
//! writes the same population and series bytes as an uninterrupted one.
//!
//! Each eye runs on a thread of this process, whatever the [`super::Runner`]: an abort
//! (an allocation that fails) ends the sweep, and `--resume` continues from the last
//! checkpointed batch. Shards need run directories (`merge` reads them): a sharded sweep
//! keeps `per_run = "directory"`.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::growth::{Observer, ObserverError, SeriesRow, Snapshot};
use crate::number::format_value;
use crate::outputs::series_columns;
use crate::rundir::growth::{series_record, with_age_column};
use crate::rundir::{write_atomic, OutputError};
use crate::scene::sweep::Sweep;
use crate::scene::Scene;
use crate::Error;

use super::{io, lock, RunRecord, RunResult, RunStatus, SweepOptions, SweepReport};

/// The checkpoint: one JSON line per finished eye.
pub const CHECKPOINT_FILE: &str = "eyes.jsonl";
/// Every eye's series rows, a `run` column first.
pub const SERIES_TABLE: &str = "series.csv";

/// One eye as the checkpoint holds it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Entry {
    pub run: String,
    /// FNV-1a 64 of the eye's effective scene (`Scene::to_toml`), as 16 hex digits.
    pub scene: String,
    /// "ok" or "failed".
    pub status: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub result: Option<RunResult>,
    /// The eye's rows of series.csv (no header), as a run directory's series.csv has them.
    pub series: Vec<String>,
}

/// How often sweep.csv and summary.json are rewritten while the eyes run (they are also
/// written at the start and the end). The checkpoint is what a resumed sweep trusts; the
/// tables only show progress, and rewriting both whole (10 MB for 10,000 eyes) every few
/// seconds cost a quarter of a cohort's time.
pub const TABLE_INTERVAL: std::time::Duration = std::time::Duration::from_secs(30);

/// The hash a checkpoint line records of `scene`: its effective TOML and the columns its
/// series rows hold, so that a line whose rows have other columns is not reused.
pub fn scene_hash(scene: &Scene) -> String {
    let mut text = scene.to_toml();
    if counts_ages(scene) {
        text.push_str("\n# series.csv ends in an age column\n");
    }
    format!("{:016x}", crate::hash::fnv1a64(text.as_bytes()))
}

/// Whether `scene`'s series rows end in an age (a growth scene with time.unit).
pub fn counts_ages(scene: &Scene) -> bool {
    scene
        .growth
        .as_ref()
        .is_some_and(|g| g.age_unit().is_some())
}

/// Eyes per checkpointed batch: a hundredth of the cohort (at least 1), so that a cohort
/// of any size is synced about a hundred times, not once per eye.
pub fn batch_size(eyes: usize) -> usize {
    eyes.div_ceil(100).max(1)
}

/// The series rows of a growth, collected as its snapshots come.
struct Rows(Vec<SeriesRow>);

impl Observer for Rows {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.0.push(s.series);
        Ok(())
    }
}

/// Compute `scene` (grow it, or solve it when it has no growth) without writing anything:
/// how it ended, its result (also that reached by a failed growth) and its series rows.
/// A panic inside is a failed eye, as [`super::run_scene`] makes it a failed run.
pub fn compute(scene: &Scene) -> (RunStatus, Option<RunResult>, Vec<String>) {
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| compute_eye(scene)));
    let age = |t: f64| scene.growth.as_ref().and_then(|g| g.age_of(t));
    match outcome {
        Ok((status, result, rows)) => (
            status,
            result,
            rows.iter()
                .map(|r| {
                    let cells = series_record(r).into_iter();
                    let cells: Vec<String> = cells.chain(age(r.t).map(format_value)).collect();
                    cells.join(",")
                })
                .collect(),
        ),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown".into());
            (
                RunStatus::Failed(format!("internal error (a bug; please report it): {what}")),
                None,
                Vec::new(),
            )
        }
    }
}

fn compute_eye(scene: &Scene) -> (RunStatus, Option<RunResult>, Vec<SeriesRow>) {
    let problem = match scene.growth_problem() {
        Ok(problem) => problem,
        Err(e) => return (RunStatus::Failed(e.to_string()), None, Vec::new()),
    };
    let Some(problem) = problem else {
        let solved = scene.elastic_problem().map_err(Error::from);
        return match solved.and_then(|p| p.solve().map_err(Error::from)) {
            Ok(solution) => (
                RunStatus::Ok,
                Some(super::run::elastic_result(scene, &solution)),
                Vec::new(),
            ),
            Err(e) => (RunStatus::Failed(e.to_string()), None, Vec::new()),
        };
    };
    let mut rows = Rows(Vec::new());
    let outcome = crate::growth::grow(&problem, &mut rows);
    let last = rows.0.last().copied();
    match (outcome, last) {
        (Ok(stats), Some(last)) => (
            RunStatus::Ok,
            Some(super::run::growth_result(scene, &last, &stats)),
            rows.0,
        ),
        (Ok(_), None) => (
            RunStatus::Failed("no snapshot was written".into()),
            None,
            rows.0,
        ),
        (Err(e), last) => (
            RunStatus::Failed(e.to_string()),
            last.map(|r| super::run::growth_result(scene, &r, &e.stats)),
            rows.0,
        ),
    }
}

/// The complete, readable lines of the checkpoint at `path`, up to the first that is not
/// (a line cut short by a kill ends the list); none if there is no checkpoint.
pub fn read_checkpoint(path: &Path) -> Result<Vec<Entry>, OutputError> {
    let text = match std::fs::read(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(io(path, e)),
    };
    let mut entries = Vec::new();
    let mut rest = text.as_slice();
    while let Some(end) = rest.iter().position(|&b| b == b'\n') {
        match serde_json::from_slice::<Entry>(&rest[..end]) {
            Ok(e) => entries.push(e),
            Err(_) => break,
        }
        rest = &rest[end + 1..];
    }
    Ok(entries)
}

fn line(entry: &Entry) -> Vec<u8> {
    let mut text = serde_json::to_vec(entry).unwrap_or_default();
    text.push(b'\n');
    text
}

/// The series columns of a run directory's series.csv, with the age when `ages`.
fn header(ages: bool) -> String {
    with_age_column(&series_columns(), ages).join(",")
}

/// The sweep's series.csv: `run`, then the series columns (the age last when `ages`);
/// every eye's rows in run order.
pub fn series_table(
    report: &SweepReport,
    series: &HashMap<String, Vec<String>>,
    ages: bool,
) -> Vec<u8> {
    let mut text = format!("run,{}\n", header(ages));
    for r in &report.records {
        for row in series.get(&r.name).into_iter().flatten() {
            text.push_str(&r.name);
            text.push(',');
            text.push_str(row);
            text.push('\n');
        }
    }
    text.into_bytes()
}

/// An eye's series as the text of a run directory's series.csv (header first; the age
/// last when `ages`).
pub fn series_text(rows: &[String], ages: bool) -> String {
    let mut text = header(ages);
    for r in rows {
        text.push('\n');
        text.push_str(r);
    }
    text.push('\n');
    text
}

/// The checkpoint's file, appended batch by batch.
struct Checkpoint {
    file: std::fs::File,
    pending: Vec<u8>,
    eyes: usize,
    batch: usize,
    last: std::time::Instant,
}

impl Checkpoint {
    /// Append the pending lines and sync them, when a batch is full or the interval has
    /// passed (`force`: now).
    fn flush(&mut self, force: bool) -> std::io::Result<()> {
        let due = force || self.eyes >= self.batch || self.last.elapsed() >= super::TABLE_INTERVAL;
        if !due || self.pending.is_empty() {
            return Ok(());
        }
        self.file.write_all(&self.pending)?;
        self.file.sync_data()?;
        self.pending.clear();
        self.eyes = 0;
        self.last = std::time::Instant::now();
        Ok(())
    }
}

/// Run every eye of `sweep` into `out` (prepared and owned by the caller) as the module
/// says: the checkpoint, the tables ([`super::write_tables`]) and, at the end, series.csv.
pub(super) fn run(
    sweep: &Sweep,
    out: &Path,
    owned: &mut crate::rundir::OwnedDir,
    options: &SweepOptions<'_>,
    done: &(dyn Fn(&RunRecord, usize, usize) + Sync),
) -> Result<(SweepReport, HashMap<String, Vec<String>>), Error> {
    // One table holds every eye's rows, so one set of columns: the eyes of a sample share
    // their scene's time.unit (a sample draws numbers, never a unit).
    let ages = sweep.runs.first().is_some_and(|r| counts_ages(&r.scene));
    let checkpoint_path = owned.claim(CHECKPOINT_FILE)?;
    owned.claim(SERIES_TABLE)?;
    // What an earlier sweep finished with the same scene; the checkpoint is rewritten
    // with exactly that, so that what follows is appended to whole lines.
    let mut earlier: HashMap<String, Entry> = HashMap::new();
    if options.resume {
        let wanted: HashMap<&str, &Scene> = sweep
            .runs
            .iter()
            .map(|r| (r.name.as_str(), &r.scene))
            .collect();
        for e in read_checkpoint(&checkpoint_path)? {
            let same = wanted
                .get(e.run.as_str())
                .is_some_and(|s| e.status == "ok" && scene_hash(s) == e.scene);
            if same {
                earlier.insert(e.run.clone(), e);
            }
        }
    }
    let mut kept: Vec<&Entry> = earlier.values().collect();
    kept.sort_by(|a, b| a.run.cmp(&b.run));
    let kept: Vec<u8> = kept.into_iter().flat_map(line).collect();
    write_atomic(&checkpoint_path, &kept).map_err(|e| io(&checkpoint_path, e))?;
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(&checkpoint_path)
        .map_err(|e| io(&checkpoint_path, e))?;
    let total = sweep.runs.len();
    let checkpoint = Mutex::new(Checkpoint {
        file,
        pending: Vec::new(),
        eyes: 0,
        batch: batch_size(total),
        last: std::time::Instant::now(),
    });
    let records: Vec<RunRecord> = sweep
        .runs
        .iter()
        .map(|r| RunRecord {
            name: r.name.clone(),
            dir: String::new(),
            values: sweep.keys.iter().map(|k| r.shown(k)).collect(),
            status: RunStatus::Pending,
            result: None,
            rerun: None,
        })
        .collect();
    let head: super::Head = sweep.into();
    let report = Mutex::new(SweepReport {
        records,
        interrupted: false,
        dir: out.to_path_buf(),
    });
    let series: Mutex<HashMap<String, Vec<String>>> = Mutex::new(HashMap::new());
    super::write_tables(head, &lock(&report))?;
    let finished = AtomicUsize::new(0);
    let failure: Mutex<Option<OutputError>> = Mutex::new(None);
    let last_write = Mutex::new(std::time::Instant::now());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs)
        .build()
        .map_err(|e| io(out, std::io::Error::other(e.to_string())))?;
    pool.install(|| {
        sweep.runs.par_iter().enumerate().for_each(|(i, run)| {
            if options.cancel.load(Ordering::SeqCst) || lock(&failure).is_some() {
                lock(&report).interrupted = true;
                return;
            }
            let (status, result, rows, reused) = match earlier.get(&run.name) {
                Some(e) => (RunStatus::Reused, e.result.clone(), e.series.clone(), true),
                None => {
                    let (status, result, rows) = compute(&run.scene);
                    (status, result, rows, false)
                }
            };
            let mut rep = lock(&report);
            if !reused {
                let entry = Entry {
                    run: run.name.clone(),
                    scene: scene_hash(&run.scene),
                    status: match status {
                        RunStatus::Failed(_) => "failed".into(),
                        _ => "ok".into(),
                    },
                    error: match &status {
                        RunStatus::Failed(m) => Some(m.clone()),
                        _ => None,
                    },
                    result: result.clone(),
                    series: rows.clone(),
                };
                let mut c = lock(&checkpoint);
                c.pending.extend(line(&entry));
                c.eyes += 1;
                if let Err(e) = c.flush(false) {
                    lock(&failure).get_or_insert(io(&checkpoint_path, e));
                }
            }
            lock(&series).insert(run.name.clone(), rows);
            rep.records[i].status = status;
            rep.records[i].result = result;
            let n = finished.fetch_add(1, Ordering::SeqCst) + 1;
            let due = {
                let mut last = lock(&last_write);
                let due = last.elapsed() >= TABLE_INTERVAL;
                if due {
                    *last = std::time::Instant::now();
                }
                due
            };
            if due {
                if let Err(e) = super::write_tables(head, &rep) {
                    lock(&failure).get_or_insert(e);
                }
            }
            done(&rep.records[i], n, total);
        });
    });
    let report = report.into_inner().unwrap_or_else(|e| e.into_inner());
    let series = series.into_inner().unwrap_or_else(|e| e.into_inner());
    lock(&checkpoint)
        .flush(true)
        .map_err(|e| io(&checkpoint_path, e))?;
    if let Some(e) = failure.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(e.into());
    }
    let path = out.join(SERIES_TABLE);
    write_atomic(&path, &series_table(&report, &series, ages)).map_err(|e| io(&path, e))?;
    super::write_tables(head, &report)?;
    Ok((report, series))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checkpoint_cut_short_keeps_its_whole_lines() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join(CHECKPOINT_FILE);
        let entry = |run: &str| Entry {
            run: run.into(),
            scene: "0123456789abcdef".into(),
            status: "ok".into(),
            error: None,
            result: None,
            series: vec!["0e0,1.5e0,2e0,3e0,4e0,emmetropic,NaN".into()],
        };
        let mut text: Vec<u8> = ["eye-1", "eye-2"]
            .iter()
            .flat_map(|r| line(&entry(r)))
            .collect();
        let third = line(&entry("eye-3"));
        text.extend(&third[..third.len() / 2]);
        std::fs::write(&path, &text).unwrap();
        let read = read_checkpoint(&path).unwrap();
        let runs: Vec<&str> = read.iter().map(|e| e.run.as_str()).collect();
        assert_eq!(runs, ["eye-1", "eye-2"]);
        assert_eq!(read[1].series, entry("eye-2").series);
        assert!(read_checkpoint(&tmp.path().join("none"))
            .unwrap()
            .is_empty());
        assert_eq!(batch_size(10_000), 100);
        assert_eq!(batch_size(40), 1);
        assert_eq!(batch_size(1), 1);
    }
}
