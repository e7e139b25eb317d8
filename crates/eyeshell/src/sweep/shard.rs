//! Shards: one sweep split over several processes or machines (`--shard K/N`), each
//! running its share of the runs into the same directory, and [`merge`] assembling the
//! sweep's table from what they left on disk.
//!
//! - **Partition.** Shard K of N runs the runs [`partition`] gives it: the runs sorted by
//!   an estimate of their cost ([`run_cost`]: nodes, times the growth's end time), the
//!   dearest first, each given to the shard with the least cost so far (ties: the lower
//!   shard, the earlier run). Runs of equal cost are dealt round-robin in sweep order. The
//!   rule depends only on the validated run list and N, so every shard computes the same
//!   partition without talking to the others. N may exceed the number of runs: the extra
//!   shards are empty (a job array need not match the sweep's size).
//! - **No shared writes.** A shard writes its runs (`DIR/runs/<name>/`, as a plain sweep
//!   does) and its own record, `DIR/shards/K.json` (the runs it ran and how they ended,
//!   which is where a failed run's message lives), and nothing else: not sweep.csv, not
//!   summary.json. Shards take no lock on `DIR`, only on their own record (`shards/.K.json.lock`:
//!   the same shard twice at once is refused). A shard never removes anything: it cannot
//!   know that another is not writing; a fresh start is another `--out`.
//! - **Large sweeps.** A shard plans the sweep ([`SweepPlan`]), and only the shard's own
//!   runs are built to run; a shard runs at most [`MAX_RUNS`] runs. A plan of at most
//!   [`MAX_RUNS`] runs has every run built and validated one at a time for its cost. A
//!   larger one (up to `MAX_PLANNED_RUNS`) is validated by one run per list entry and grid
//!   value ([`SweepPlan::representatives`]), each shard validating all its own runs before
//!   it runs any, and when no swept value changes a run's cost the partition is
//!   round-robin with nothing done per run ([`Costs::Equal`]): a grid of 10⁷ runs is
//!   planned in milliseconds. Merge and status read the runs one at a time, holding one
//!   row per run.
//! - **Merge.** [`merge`] rebuilds the run list from the scene the shards recorded, takes
//!   each run that finished from its own `result.json` (checked as `--resume` checks it),
//!   a failed run from its shard's record, and writes sweep.csv and summary.json exactly as
//!   a plain sweep would; runs that are missing are listed.

use std::collections::BinaryHeap;
use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::rundir::summary::SweepRunEntry;
use crate::rundir::{write_atomic, OutputError};
use crate::scene::sweep::{Sweep, SweepPlan, MAX_RUNS};
use crate::scene::Scene;
use crate::{Error, Origin, Subject};

use super::{resume, RunRecord, RunStatus, SweepReport, RUNS_DIR};

/// The shards' records, under the sweep's directory.
pub const SHARDS_DIR: &str = "shards";
/// The most shards a sweep may be split into (a typo such as `--shard 1/10000000` is
/// caught before a partition of that size is built).
pub const MAX_SHARDS: usize = 1_000_000;

/// Shard `k` of `n` (1 ≤ k ≤ n), as `--shard K/N` gives it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub k: usize,
    pub n: usize,
}

/// Why a shard could not be had, one line each: from the command line's `--shard K/N`,
/// from the numbers, or from a Slurm job array's environment.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ShardError {
    /// Text that is not `K/N` with whole numbers.
    #[error("--shard {}: give K/N with 1 <= K <= N, e.g. --shard 2/8 (or --shard slurm in a Slurm job array)", crate::text::one_line(.text))]
    Syntax { text: String },
    /// N, the number of shards, out of range.
    #[error("N must be 1 to {MAX_SHARDS}, not {n}")]
    Count { n: usize },
    /// K, the shard, out of 1..=N.
    #[error("K must be 1 to N = {n}, not {k}")]
    Index { k: usize, n: usize },
    /// `--shard K/N` whose numbers are out of range.
    #[error("--shard {}: {source}", crate::text::one_line(.text))]
    Given {
        text: String,
        source: Box<ShardError>,
    },
    /// A variable of the job array's environment that is not set.
    #[error("--shard slurm: {name} is not set: run it as a task of a Slurm job array (sbatch --array=1-N), or give --shard K/N")]
    SlurmUnset { name: &'static str },
    /// A variable of the job array's environment that is not a whole number.
    #[error("--shard slurm: {name} = {} is not a whole number", crate::text::one_line(.value))]
    SlurmNotANumber { name: &'static str, value: String },
    /// The task's id outside the array's range.
    #[error("--shard slurm: SLURM_ARRAY_TASK_ID = {id} is outside SLURM_ARRAY_TASK_MIN..MAX = {min}..{max}")]
    SlurmOutside { id: usize, min: usize, max: usize },
    /// A job array that is not a plain range (a step, or a list).
    #[error("--shard slurm: the job array has {} tasks between {min} and {max}: it must be a plain range (--array={min}-{max}), one task per shard", crate::text::one_line(.count))]
    SlurmNotARange {
        count: String,
        min: usize,
        max: usize,
    },
    /// A job array of more tasks than shards may be.
    #[error("--shard slurm: {0}")]
    Slurm(Box<ShardError>),
}

impl Shard {
    /// `K/N`.
    ///
    /// # Errors
    /// [`ShardError::Syntax`] for text that is not two whole numbers, [`ShardError::Given`]
    /// for numbers out of range.
    pub fn parse(text: &str) -> Result<Shard, ShardError> {
        let syntax = || ShardError::Syntax { text: text.into() };
        let (k, n) = text.split_once('/').ok_or_else(syntax)?;
        let number = |s: &str| s.trim().parse::<usize>().ok();
        match (number(k), number(n)) {
            (Some(k), Some(n)) => Shard::new(k, n).map_err(|why| ShardError::Given {
                text: text.into(),
                source: Box::new(why),
            }),
            _ => Err(syntax()),
        }
    }

    /// Shard `k` of `n`, checked.
    ///
    /// # Errors
    /// [`ShardError::Count`] for n outside 1..=[`MAX_SHARDS`], [`ShardError::Index`] for k
    /// outside 1..=n.
    pub fn new(k: usize, n: usize) -> Result<Shard, ShardError> {
        if n == 0 || n > MAX_SHARDS {
            return Err(ShardError::Count { n });
        }
        if k == 0 || k > n {
            return Err(ShardError::Index { k, n });
        }
        Ok(Shard { k, n })
    }

    /// The shard of this task of a Slurm job array: K and N from `SLURM_ARRAY_TASK_ID`,
    /// `SLURM_ARRAY_TASK_MIN` and `SLURM_ARRAY_TASK_MAX` (K = ID − MIN + 1, N = MAX − MIN + 1;
    /// `SLURM_ARRAY_TASK_COUNT`, when set, must be N: the array must be a plain range
    /// such as `--array=1-8`). `var` reads the environment.
    ///
    /// # Errors
    /// The `Slurm…` variants of [`ShardError`], naming the variable.
    pub fn from_slurm(var: impl Fn(&str) -> Option<String>) -> Result<Shard, ShardError> {
        let get = |name: &'static str| -> Result<usize, ShardError> {
            let value = var(name).ok_or(ShardError::SlurmUnset { name })?;
            value
                .trim()
                .parse::<usize>()
                .map_err(|_| ShardError::SlurmNotANumber { name, value })
        };
        let (id, min, max) = (
            get("SLURM_ARRAY_TASK_ID")?,
            get("SLURM_ARRAY_TASK_MIN")?,
            get("SLURM_ARRAY_TASK_MAX")?,
        );
        if id < min || id > max {
            return Err(ShardError::SlurmOutside { id, min, max });
        }
        let n = max - min + 1;
        if let Some(count) = var("SLURM_ARRAY_TASK_COUNT") {
            if count.trim().parse::<usize>().ok() != Some(n) {
                return Err(ShardError::SlurmNotARange { count, min, max });
            }
        }
        Shard::new(id - min + 1, n).map_err(|why| ShardError::Slurm(Box::new(why)))
    }

    /// `K.json`.
    pub fn file_name(&self) -> String {
        format!("{}.json", self.k)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

/// An estimate of what a run costs, for balancing shards: its nodes, times (for a growth)
/// 1 + 100·t_end. Only the ratios between runs matter.
pub fn run_cost(scene: &Scene) -> u64 {
    let nodes = scene.solver.nodes.max(1) as u64;
    match &scene.growth {
        Some(g) if g.t_end.is_finite() && g.t_end > 0.0 => {
            nodes.saturating_mul(1 + (100.0 * g.t_end).ceil().min(1e12) as u64)
        }
        _ => nodes,
    }
}

/// The shard (0-based) of each run, given the runs' costs in sweep order: the dearest run
/// first to the least loaded shard (see the module doc). O(runs · log runs).
pub fn partition(costs: &[u64], n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..costs.len()).collect();
    // Stable: equal costs keep sweep order.
    order.sort_by(|&a, &b| costs[b].cmp(&costs[a]));
    // A min-heap of (load, shard): Reverse orders the smallest first, ties by lower shard.
    let mut heap: BinaryHeap<std::cmp::Reverse<(u64, usize)>> = (0..n.min(costs.len()).max(1))
        .map(|s| std::cmp::Reverse((0, s)))
        .collect();
    let mut shard_of = vec![0; costs.len()];
    for i in order {
        let std::cmp::Reverse((load, s)) = heap.pop().unwrap_or(std::cmp::Reverse((0, 0)));
        shard_of[i] = s;
        heap.push(std::cmp::Reverse((load.saturating_add(costs[i]), s)));
    }
    shard_of
}

/// What the partition needs of a plan's runs: their costs, or that all cost the same.
#[derive(Clone, Debug, PartialEq)]
pub enum Costs {
    /// This many runs, all of one cost: dealt round-robin ([`partition`] of equal costs).
    Equal(usize),
    /// Every run's cost, in sweep order.
    Each(Vec<u64>),
}

impl Costs {
    /// The number of runs.
    pub fn len(&self) -> usize {
        match self {
            Costs::Equal(n) => *n,
            Costs::Each(c) => c.len(),
        }
    }

    /// Whether there are no runs (never, for a plan).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The runs (indices, in sweep order) that shard `k` (1-based) of `n` holds. Equal
    /// costs need no list of the runs: shard k holds k − 1, k − 1 + m, … (m = min(n, runs)).
    pub fn runs_of(&self, shard: Shard) -> Vec<usize> {
        match self {
            Costs::Equal(runs) => {
                let m = shard.n.min(*runs).max(1);
                (shard.k - 1..*runs).step_by(m).collect()
            }
            Costs::Each(costs) => shard_runs(&partition(costs, shard.n), shard),
        }
    }

    /// The most runs any of `n` shards holds.
    pub fn largest_share(&self, n: usize) -> usize {
        match self {
            Costs::Equal(runs) => runs.div_ceil(n.min(*runs).max(1)),
            Costs::Each(costs) => {
                let mut count = vec![0usize; n.min(costs.len()).max(1)];
                for s in partition(costs, n) {
                    count[s] += 1;
                }
                count.into_iter().max().unwrap_or(0)
            }
        }
    }
}

/// The costs of a plan's runs, the plan validated on the way. A plan of at most
/// [`MAX_RUNS`] runs has each run built and validated in turn, one scene at a time (the
/// first invalid run is the error). A larger one is validated by its
/// [`SweepPlan::representatives`] (each shard then validates all its own runs before it
/// runs any), and when no list entry or grid value changes what [`run_cost`] reads (the
/// nodes, whether the scene grows, growth.t_end), its runs cost the same and nothing is
/// done per run: a plan of 10⁷ runs is partitioned in milliseconds.
pub fn costs_of(plan: &SweepPlan) -> Result<Costs, Error> {
    // A shard's runs are directories that `merge` reads; a cohort kept as a table is
    // computed and checkpointed by one process (super::compact).
    if plan.sample.as_ref().map(|s| s.per_run) == Some(crate::scene::sample::PerRun::Table) {
        return Err(Error::input(Subject::Key("sweep.sample.per_run".into()), format!(
            "{}: per_run = \"table\" in [sweep.sample] runs the cohort in one process, which shards cannot share: set per_run = \"directory\" to run it in shards",
            plan.origin
        ))
        .with_value("\"table\"")
        .with_origin(Origin::Scene(plan.origin.clone())));
    }
    let runs = plan.len();
    if runs > MAX_RUNS {
        let representatives: Vec<Scene> = plan
            .representatives()
            .into_iter()
            .map(|i| plan.run(i).map(|r| r.scene))
            .collect::<Result<_, _>>()?;
        crate::scene::sweep::refuse_keys_not_in_effect(plan, representatives.iter())?;
        let inputs = |s: &Scene| (s.solver.nodes, s.growth.as_ref().map(|g| g.t_end.to_bits()));
        if !plan.varies(inputs)? {
            return Ok(Costs::Equal(runs));
        }
    }
    let mut costs = Vec::with_capacity(runs);
    // Whether each swept key is read by some run, gathered as the runs are built (one
    // scene at a time), then refused as a plain sweep refuses it.
    let mut read = vec![false; plan.keys.len()];
    let mut unread: Option<Scene> = None;
    plan.each_run(|_, run| {
        costs.push(run_cost(&run.scene));
        for (k, key) in plan.keys.iter().enumerate() {
            read[k] |= run.scene.not_in_effect(key).is_none();
        }
        if unread.is_none() {
            unread = Some(run.scene.clone());
        }
    })?;
    if read.iter().any(|r| !r) {
        // Some key no run reads: the first run's reason names it.
        let keep: Vec<String> = plan
            .keys
            .iter()
            .zip(&read)
            .filter(|(_, r)| !**r)
            .map(|(k, _)| k.clone())
            .collect();
        let mut only = plan.clone();
        only.keys = keep;
        crate::scene::sweep::refuse_keys_not_in_effect(&only, unread.iter())?;
    }
    Ok(Costs::Each(costs))
}

/// The runs (indices into the plan, in sweep order) of `shard`; bad input when they are
/// more than one process holds ([`MAX_RUNS`]).
pub fn runs_of(plan: &SweepPlan, shard: Shard) -> Result<Vec<usize>, Error> {
    let mine = costs_of(plan)?.runs_of(shard);
    if mine.len() > MAX_RUNS {
        return Err(Error::input(Subject::Argument("--shard".into()), format!(
            "{}: shard {shard} would hold {} of the sweep's {} runs, more than the {MAX_RUNS} one process runs: split it into more shards (N of at least {})",
            plan.origin,
            mine.len(),
            plan.len(),
            plan.len().div_ceil(MAX_RUNS)
        ))
        .with_value(shard)
        .with_origin(Origin::Argument));
    }
    Ok(mine)
}

/// The indices the partition `shard_of` gives `shard`.
fn shard_runs(shard_of: &[usize], shard: Shard) -> Vec<usize> {
    shard_of
        .iter()
        .enumerate()
        .filter(|&(_, &s)| s + 1 == shard.k)
        .map(|(i, _)| i)
        .collect()
}

/// `DIR/shards/K.json`: what a shard ran, from which scene, and how each run ended.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ShardRecord {
    /// K.
    pub shard: usize,
    /// N.
    pub shards: usize,
    /// The scene as the command line named it (the sweep's `scene` in summary.json).
    pub scene: String,
    /// The same file, absolute, for a merge run from another directory.
    pub scene_path: String,
    /// The `--set` overrides.
    pub overrides: Vec<String>,
    /// "running", "ok", "partial" (some runs failed) or "interrupted".
    pub status: String,
    pub runs_total: usize,
    pub runs_failed: usize,
    pub runs: Vec<SweepRunEntry>,
}

impl ShardRecord {
    /// The record of `report` (the shard's runs so far).
    pub fn new(sweep: &Sweep, shard: Shard, report: &SweepReport) -> ShardRecord {
        let crate::rundir::Summary::Sweep(summary) = super::summary(sweep.into(), report) else {
            unreachable!("a sweep's summary is a sweep summary")
        };
        ShardRecord {
            shard: shard.k,
            shards: shard.n,
            scene: sweep.origin.clone(),
            // The file itself (its name may hold a line break that origin shows escaped).
            scene_path: fs::canonicalize(sweep.path.as_deref().unwrap_or(Path::new(&sweep.origin)))
                .map(|p| p.display().to_string())
                .unwrap_or_else(|_| sweep.origin.clone()),
            overrides: overrides_of(sweep),
            status: report.status().to_string(),
            runs_total: report.records.len(),
            runs_failed: summary.runs_failed,
            runs: summary.runs,
        }
    }

    /// Write it, atomically, to `path`.
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let text = serde_json::to_string_pretty(self).unwrap_or_default() + "\n";
        write_atomic(path, text.as_bytes()).map_err(|e| OutputError::io(path, e))
    }
}

/// The `--set` overrides of a sweep (every run has the same).
pub fn overrides_of(sweep: &Sweep) -> Vec<String> {
    sweep
        .runs
        .first()
        .map(|r| r.scene.overrides.clone())
        .unwrap_or_default()
}

/// What a record that says "running" is called when no process holds its lock.
pub const INTERRUPTED: &str = "interrupted";

/// The largest shard record read (a record lists one shard's runs; this bounds a corrupt
/// or foreign file).
const MAX_RECORD_BYTES: u64 = 1 << 30;

/// Every `DIR/shards/K.json`, sorted by K; Err (bad input) when there is none or one is
/// not a shard's record.
pub fn read_records(out: &Path) -> Result<Vec<(PathBuf, ShardRecord)>, Error> {
    let dir = out.join(SHARDS_DIR);
    // Not through a link: it would read (and merge) another sweep's shards.
    super::target::no_link(&dir)?;
    let listed = match fs::read_dir(&dir) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(Error::input(Subject::File(out.to_path_buf()), format!(
                "{}: no shard has run here (no {SHARDS_DIR}/ directory): merge assembles the runs of `eyeshell sweep SCENE --out {} --shard K/N`",
                out.display(),
                out.display()
            )))
        }
        Err(source) => return Err(Error::Io { path: dir, source }),
    };
    let mut records = Vec::new();
    for entry in listed {
        let entry = entry.map_err(|source| Error::Io {
            path: dir.clone(),
            source,
        })?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(k) = name
            .strip_suffix(".json")
            .and_then(|k| k.parse::<usize>().ok())
        else {
            continue; // locks, temporaries, Slurm's logs
        };
        let path = entry.path();
        let bad = |why: String| {
            Error::input(
                Subject::File(path.to_path_buf()),
                format!("{}: {why}", path.display()),
            )
        };
        let meta = fs::symlink_metadata(&path).map_err(|e| bad(e.to_string()))?;
        if !meta.is_file() || meta.len() > MAX_RECORD_BYTES {
            return Err(bad(
                "is not a shard's record (not a regular file of sensible size)".into(),
            ));
        }
        let text = fs::read_to_string(&path).map_err(|e| bad(e.to_string()))?;
        let record: ShardRecord = serde_json::from_str(&text)
            .map_err(|e| bad(format!("is not a shard's record: {e}")))?;
        if record.shard != k || record.shards == 0 || record.shard > record.shards {
            return Err(bad(format!(
                "is not a shard's record (it says shard {} of {})",
                record.shard, record.shards
            )));
        }
        let mut record = record;
        if record.status == "running" && !crate::rundir::lock::is_held(&path) {
            // Its process holds no lock: it was killed (or its machine went down) before it
            // could say so.
            record.status = INTERRUPTED.into();
        }
        records.push((path, record));
    }
    if records.is_empty() {
        return Err(Error::input(Subject::File(dir.to_path_buf()), format!(
            "{}: no shard has run here (no K.json): merge assembles the runs of `eyeshell sweep SCENE --out {} --shard K/N`",
            dir.display(),
            out.display()
        )));
    }
    records.sort_by_key(|(_, r)| r.shard);
    Ok(records)
}

/// What [`merge`] found.
#[derive(Debug)]
pub struct Merged {
    /// The sweep's plan, rebuilt from the scene the shards recorded.
    pub plan: SweepPlan,
    /// Each run's cost, in sweep order (the partition's input).
    pub costs: Vec<u64>,
    /// One row per run of the sweep: ok, failed, or not run (missing).
    pub report: SweepReport,
    /// The shards' records, by K.
    pub records: Vec<ShardRecord>,
    /// Runs that had finished but cannot be trusted any more, and why.
    pub stale: Vec<(String, String)>,
}

impl Merged {
    /// The runs with no result: never run, interrupted, or stale.
    pub fn missing(&self) -> impl Iterator<Item = &RunRecord> {
        self.report
            .records
            .iter()
            .filter(|r| r.status == RunStatus::Pending)
    }

    /// The shards (of the N all records agree on) that own a missing or failed run, or
    /// None when the records disagree on N.
    pub fn shards_to_resume(&self) -> Option<(usize, Vec<usize>)> {
        let n = self.records.first()?.shards;
        if self.records.iter().any(|r| r.shards != n) {
            return None;
        }
        let shard_of = partition(&self.costs, n);
        let mut ks: Vec<usize> = self
            .report
            .records
            .iter()
            .zip(&shard_of)
            .filter(|(r, _)| !matches!(r.status, RunStatus::Ok))
            .map(|(_, s)| s + 1)
            .collect();
        ks.sort_unstable();
        ks.dedup();
        Some((n, ks))
    }
}

/// Assemble the sweep in `out` from its shards' runs: every run with a trustworthy
/// result.json is `ok`, a run a shard recorded as failed is `failed` with its message,
/// anything else is `not run`. The directory is checked as `--resume` checks it, with or
/// without `write`; with it, sweep.csv and summary.json are written (under the sweep's
/// lock). A record that says "running" but whose shard holds no lock is `interrupted`.
pub fn merge(out: &Path, write: bool) -> Result<Merged, Error> {
    let found = read_records(out)?;
    let (first_path, first) = &found[0];
    for (path, r) in &found[1..] {
        if r.scene_path != first.scene_path || r.overrides != first.overrides {
            return Err(Error::input(Subject::File(path.to_path_buf()), format!(
                "{}: was run from another scene ({}{}) than {} ({}{}): the shards of one --out must run the same sweep",
                path.display(),
                r.scene,
                shown_sets(&r.overrides),
                first_path.display(),
                first.scene,
                shown_sets(&first.overrides)
            )));
        }
    }
    let (_, text) = crate::scene::read_scene_file(Path::new(&first.scene_path)).map_err(|e| {
        Error::input(
            Subject::File(first_path.to_path_buf()),
            format!(
                "{}: the scene the shards ran cannot be read: {e}",
                first_path.display()
            ),
        )
    })?;
    let plan = SweepPlan::from_toml_str(&text, &first.scene, &first.overrides)?;
    // The same checks of the directory for both: status says done only where merge
    // accepts it; merge also locks it.
    let is_run = |n: &str| plan.has_name(n);
    let _owned = if write {
        Some(super::target::prepare(&is_run, out, true, &[])?)
    } else {
        super::target::check_kept(&is_run, out)?;
        None
    };
    // The failed runs the shards recorded, by name (a later shard's record wins).
    let failures: std::collections::HashMap<&str, &SweepRunEntry> = found
        .iter()
        .flat_map(|(_, r)| r.runs.iter())
        .filter(|e| e.status == "failed")
        .map(|e| (e.name.as_str(), e))
        .collect();
    let mut stale = Vec::new();
    let mut costs = Vec::with_capacity(plan.len());
    let mut records = Vec::with_capacity(plan.len());
    // One run's scene at a time: a plan of 10⁶ runs is never held as scenes.
    plan.each_run(|_, run| {
        costs.push(run_cost(&run.scene));
        let dir = out.join(RUNS_DIR).join(&run.name);
        let (status, result) = match resume::reusable(run, &dir) {
            resume::Reuse::Yes(result) => (RunStatus::Ok, Some(result)),
            other => {
                if let resume::Reuse::Stale(why) = other {
                    stale.push((run.name.clone(), why));
                }
                match failures.get(run.name.as_str()) {
                    Some(e) => (
                        RunStatus::Failed(e.error.clone().unwrap_or_default()),
                        e.result.clone(),
                    ),
                    None => (RunStatus::Pending, None),
                }
            }
        };
        records.push(RunRecord {
            name: run.name.clone(),
            dir: format!("{RUNS_DIR}/{}", run.name),
            values: plan.keys.iter().map(|k| run.shown(k)).collect(),
            status,
            result,
            rerun: None,
        });
    })?;
    let interrupted = records.iter().any(|r| r.status == RunStatus::Pending);
    let report = SweepReport {
        records,
        interrupted,
        dir: out.to_path_buf(),
    };
    if write {
        super::write_tables((&plan).into(), &report)?;
        super::write_population((&plan).into(), &report)?;
    }
    Ok(Merged {
        plan,
        costs,
        report,
        records: found.into_iter().map(|(_, r)| r).collect(),
        stale,
    })
}

fn shown_sets(overrides: &[String]) -> String {
    overrides.iter().map(|s| format!(" --set {s}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_k_of_n_is_checked() {
        assert_eq!(Shard::parse("2/3"), Ok(Shard { k: 2, n: 3 }));
        assert_eq!(Shard::parse(" 1 / 1 "), Ok(Shard { k: 1, n: 1 }));
        for bad in ["0/3", "4/3", "1/0", "3", "a/b", "-1/3", "1/2/3", ""] {
            let why = Shard::parse(bad).unwrap_err().to_string();
            assert!(why.starts_with("--shard "), "{why}");
            assert!(!why.contains('\n'), "{why}");
        }
        assert!(Shard::parse("1/2000000")
            .unwrap_err()
            .to_string()
            .contains("N must be 1 to"));
        assert_eq!(
            Shard::parse("4/3"),
            Err(ShardError::Given {
                text: "4/3".into(),
                source: Box::new(ShardError::Index { k: 4, n: 3 })
            })
        );
    }

    #[test]
    fn slurm_gives_k_and_n_from_the_array() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |name: &str| {
                pairs
                    .iter()
                    .find(|(k, _)| *k == name)
                    .map(|(_, v)| v.to_string())
            }
        };
        let ok = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "4"),
            ("SLURM_ARRAY_TASK_MAX", "7"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(Shard::from_slurm(ok), Ok(Shard { k: 2, n: 4 }));
        let zero_based = env(&[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", "2"),
        ]);
        assert_eq!(Shard::from_slurm(zero_based), Ok(Shard { k: 1, n: 3 }));
        let unset = Shard::from_slurm(env(&[])).unwrap_err();
        assert_eq!(
            unset,
            ShardError::SlurmUnset {
                name: "SLURM_ARRAY_TASK_ID"
            }
        );
        assert!(
            unset.to_string().contains("SLURM_ARRAY_TASK_ID is not set"),
            "{unset}"
        );
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        assert!(Shard::from_slurm(stepped)
            .unwrap_err()
            .to_string()
            .contains("plain range"));
    }

    #[test]
    fn the_partition_covers_every_run_once_and_balances_the_cost() {
        // Equal costs: round-robin in sweep order.
        assert_eq!(partition(&[1; 7], 3), [0, 1, 2, 0, 1, 2, 0]);
        // More shards than runs: the extra ones are empty.
        assert_eq!(partition(&[5, 5], 4), [0, 1]);
        // One dear run alone, the cheap ones together.
        let costs = [1, 1, 10, 1, 1, 1];
        let shard_of = partition(&costs, 2);
        assert_eq!(shard_of[2], 0);
        assert!(shard_of.iter().enumerate().all(|(i, &s)| i == 2 || s == 1));
        // Loads within the dearest run of each other.
        let costs: Vec<u64> = (0..1000).map(|i| 1 + (i * 7919 % 97)).collect();
        let shard_of = partition(&costs, 7);
        let mut load = [0u64; 7];
        for (c, s) in costs.iter().zip(&shard_of) {
            load[*s] += c;
        }
        assert!(
            load.iter().max().unwrap() - load.iter().min().unwrap() <= 97,
            "{load:?}"
        );
    }
}
