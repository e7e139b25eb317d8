//! One run of a sweep: how it is executed ([`Runner`]: in this process by default) and
//! what executing it is ([`execute`]: solve or grow into the run directory, then its
//! scene.toml and result.json).

use std::path::Path;

use crate::bvp::FieldRow;
use crate::growth::{GrowthStats, SeriesRow};
use crate::model::stimulus::{self, EyeMeasure};
use crate::rundir::{self, write_atomic, GrowthWriter};
use crate::scene::sweep::SweepRun;
use crate::scene::Scene;

use super::{files, io, RunResult, RunStatus, RESULT_FILE, SCENE_FILE};

/// How one run of a sweep is executed into its directory `dir` (`out/runs/<name>`).
/// [`run_sweep`](super::run_sweep) calls it from as many threads as it runs jobs.
pub trait Runner: Sync {
    fn run(&self, run: &SweepRun, dir: &Path) -> (RunStatus, Option<RunResult>);
}

/// The default [`Runner`]: each run on a thread of this process ([`run_scene`]). A panic
/// is a failed run, but an abort (an allocation that fails, a stack overflow) takes the
/// whole process, and so the sweep, down with it: the command line runs each run in a
/// worker process instead.
#[derive(Clone, Copy, Debug, Default)]
pub struct InProcess;

impl Runner for InProcess {
    fn run(&self, run: &SweepRun, dir: &Path) -> (RunStatus, Option<RunResult>) {
        run_scene(&run.scene, dir)
    }
}

/// Run `scene` into `dir` ([`execute`]); a panic inside is a failed run, not a failed
/// sweep.
pub fn run_scene(scene: &Scene, dir: &Path) -> (RunStatus, Option<RunResult>) {
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| execute(scene, dir)));
    match outcome {
        Ok(Ok(result)) => (RunStatus::Ok, Some(result)),
        Ok(Err((message, partial))) => (RunStatus::Failed(message), partial.map(|r| *r)),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown".into());
            (
                RunStatus::Failed(format!("internal error (a bug; please report it): {what}")),
                None,
            )
        }
    }
}

/// A failed run: the message and what it had reached.
pub type RunFailure = (String, Option<Box<RunResult>>);

/// Solve or grow `scene` into `dir`, then write its scene.toml and, last, result.json with
/// the list of the files written ([`files::record`]).
pub fn execute(scene: &Scene, dir: &Path) -> Result<RunResult, RunFailure> {
    let mut result = match &scene.growth {
        Some(_) => execute_growth(scene, dir)?,
        None => execute_elastic(scene, dir)?,
    };
    let unwritten = |path: &Path, e: std::io::Error, result: &RunResult| {
        (io(path, e).to_string(), Some(Box::new(result.clone())))
    };
    rundir::owner::claim(dir, &[SCENE_FILE, RESULT_FILE])
        .map_err(|e| (e.to_string(), Some(Box::new(result.clone()))))?;
    let path = dir.join(SCENE_FILE);
    write_atomic(&path, scene.to_toml().as_bytes()).map_err(|e| unwritten(&path, e, &result))?;
    result.files = files::record(dir).map_err(|e| unwritten(dir, e, &result))?;
    let path = dir.join(RESULT_FILE);
    let text = serde_json::to_string_pretty(&result).unwrap_or_default();
    write_atomic(&path, text.as_bytes()).map_err(|e| unwritten(&path, e, &result))?;
    Ok(result)
}

fn execute_growth(scene: &Scene, dir: &Path) -> Result<RunResult, RunFailure> {
    let writer = GrowthWriter::create(dir, scene, &[]).map_err(|e| (e.to_string(), None))?;
    // scene.toml first, so a failed run can still be reproduced.
    rundir::owner::claim(dir, &[SCENE_FILE, RESULT_FILE]).map_err(|e| (e.to_string(), None))?;
    let path = dir.join(SCENE_FILE);
    write_atomic(&path, scene.to_toml().as_bytes())
        .map_err(|e| (io(&path, e).to_string(), None))?;
    let run = rundir::run::grow_with(scene, writer, &mut ());
    match run.outcome {
        Ok((stats, _)) => {
            let last = run
                .last
                .ok_or_else(|| ("no snapshot was written".to_string(), None))?;
            Ok(growth_result(scene, &last, &stats))
        }
        Err(failure) => {
            let partial = run
                .last
                .map(|r| Box::new(growth_result(scene, &r, failure.stats())));
            Err((failure.to_string(), partial))
        }
    }
}

/// What a sweep's table says of a growth run of `scene` that reached `row`.
pub(super) fn growth_result(scene: &Scene, row: &SeriesRow, stats: &GrowthStats) -> RunResult {
    RunResult {
        kind: "grow".into(),
        t: row.t,
        age: scene.growth.as_ref().and_then(|g| g.age_of(row.t)),
        eye: crate::outputs::Measures::of(row),
        newton_iterations: stats.newton_iterations,
        bvp_solves: stats.bvp_solves,
        steps: stats.steps,
        rhs_evaluations: stats.rhs_evaluations,
        wall_seconds: stats.wall_seconds,
        files: Vec::new(),
    }
}

fn execute_elastic(scene: &Scene, dir: &Path) -> Result<RunResult, RunFailure> {
    let run = rundir::run::solve_into(scene, dir, &[], &[]).map_err(|e| (e.to_string(), None))?;
    Ok(elastic_result(scene, &run.solution))
}

/// What a sweep's table says of the elastic solve of `scene`.
pub(super) fn elastic_result(scene: &Scene, solution: &crate::bvp::Solution) -> RunResult {
    let s = &solution.stats;
    let eye = unloaded_eye(scene, &solution.rows);
    RunResult {
        kind: "solve".into(),
        t: 0.0,
        age: None,
        eye: crate::outputs::Measures::of(&SeriesRow::new(0.0, eye)),
        newton_iterations: s.newton_iterations,
        bvp_solves: 1,
        steps: 0,
        rhs_evaluations: 0,
        wall_seconds: s.wall_seconds,
        files: Vec::new(),
    }
}

/// The retina of a loaded, ungrown shell, measured as a growth run measures it
/// (docs/MODEL.md §6; [`EyeMeasure`]): what a sweep's table says of an elastic run.
pub fn unloaded_eye(scene: &Scene, rows: &[FieldRow]) -> EyeMeasure {
    let retina = |f: &FieldRow| stimulus::retina(f.z, f.r, f.h, f.theta);
    let pole = rows.first().map(retina).unwrap_or((f64::NAN, f64::NAN));
    let radii = rows.iter().map(retina);
    let (blue, red) = (scene.blue(), scene.red());
    match &scene.growth {
        // A growing scene's surfaces, computed ones included (traced when it was read).
        Some(g) if g.is_resolved() => g.measure(
            0.0,
            EyeMeasure::new(pole, radii, g.blue_focal(), g.red_focal()),
        ),
        _ => EyeMeasure::new(
            pole,
            radii,
            stimulus::Focal::Polynomial(&blue),
            stimulus::Focal::Polynomial(&red),
        ),
    }
}
