//! Runs that are the same run: solved once, each twin given its own complete directory.
//!
//! Two runs are the same ([`same_run`]) when everything that determines their outputs is
//! equal: the resolved scenes with their name, description, source path and overrides left
//! out (the overrides are already in the parameters). The first of them to claim its place
//! ([`Twins::claim`]) solves; the others wait for it ([`Waiter::wait`]) and then copy its
//! directory ([`copy_run`]): every data file byte for byte, and their own scene.toml,
//! summary.json and result.json, written by the writers a run uses, so that a twin's
//! directory is the one its own run would have written (its statistics being those of the
//! solve it shares).

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};

use crate::rundir::summary::RunInfo;
use crate::rundir::{self, write_atomic, Marker, OwnedDir, Summary, SUMMARY_FILE};
use crate::scene::Scene;

use super::{files, io, RunFailure, RunResult, RunStatus, RESULT_FILE, SCENE_FILE};

/// Whether runs of `a` and `b` write the same outputs: the scenes are equal in every part
/// but their name, description, source path and overrides, both as values and as the
/// effective TOML a run writes (so that two values that compare equal but print apart,
/// 0 and -0, are not taken for one).
pub fn same_run(a: &Scene, b: &Scene) -> bool {
    let (a, b) = (bare(a), bare(b));
    a == b && a.to_toml() == b.to_toml()
}

fn bare(scene: &Scene) -> Scene {
    Scene {
        name: None,
        description: None,
        origin: String::new(),
        overrides: Vec::new(),
        ..scene.clone()
    }
}

/// How a solved run ended, for its twins: its directory, status and result.
#[derive(Clone, Debug)]
pub struct Solved {
    pub dir: PathBuf,
    pub status: RunStatus,
    pub result: Option<RunResult>,
}

/// The runs claimed so far, each with its outcome once it has one.
#[derive(Default)]
pub struct Twins {
    runs: Mutex<Vec<(Scene, Arc<Slot>)>>,
}

#[derive(Default)]
struct Slot {
    outcome: Mutex<Option<Solved>>,
    ended: Condvar,
}

/// What a run is to do: solve (and tell its twins), or wait for the run it is a twin of.
pub enum Claim {
    First(Publisher),
    Twin(Waiter),
}

impl Twins {
    /// Claim the run of `scene` into `dir`: the first run of its kind solves, the later
    /// ones are its twins.
    pub fn claim(&self, scene: &Scene, dir: &Path) -> Claim {
        let mut runs = self.runs.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, slot)) = runs.iter().find(|(s, _)| same_run(s, scene)) {
            return Claim::Twin(Waiter(slot.clone()));
        }
        let slot = Arc::new(Slot::default());
        runs.push((scene.clone(), slot.clone()));
        Claim::First(Publisher {
            slot,
            dir: dir.to_path_buf(),
            published: false,
        })
    }
}

/// The solving run's side: its outcome goes to its twins. Dropped without
/// [`Publisher::publish`] (the run stopped by a panic), the twins are told it failed, so
/// none waits forever.
pub struct Publisher {
    slot: Arc<Slot>,
    dir: PathBuf,
    published: bool,
}

impl Publisher {
    /// The run ended with `status` and `result`.
    pub fn publish(mut self, status: &RunStatus, result: Option<&RunResult>) {
        self.set(status.clone(), result.cloned());
    }

    fn set(&mut self, status: RunStatus, result: Option<RunResult>) {
        let mut outcome = self.slot.outcome.lock().unwrap_or_else(|e| e.into_inner());
        *outcome = Some(Solved {
            dir: self.dir.clone(),
            status,
            result,
        });
        self.published = true;
        self.slot.ended.notify_all();
    }
}

impl Drop for Publisher {
    fn drop(&mut self) {
        if !self.published {
            let why = "the run it shares stopped before it ended (a bug; please report it)";
            self.set(RunStatus::Failed(why.into()), None);
        }
    }
}

/// A twin's side: the outcome of the run it shares.
pub struct Waiter(Arc<Slot>);

impl Waiter {
    /// Wait until the run it shares has ended.
    pub fn wait(self) -> Solved {
        let mut outcome = self.0.outcome.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            if let Some(solved) = outcome.as_ref() {
                return solved.clone();
            }
            outcome = self
                .0
                .ended
                .wait(outcome)
                .unwrap_or_else(|e| e.into_inner());
        }
    }
}

/// The twin of `solved` (which had not [`RunStatus::Pending`]) for `scene` into `dir`: the
/// status and result of the run it shares, its directory copied (see [`copy_run`]). A
/// failed run's twin fails with the same message, keeping a copy of what it had written.
pub fn twin_of(solved: &Solved, scene: &Scene, dir: &Path) -> (RunStatus, Option<RunResult>) {
    let finished = solved.status == RunStatus::Ok;
    match copy_run(&solved.dir, scene, dir, solved.result.as_ref(), finished) {
        Ok(result) => (solved.status.clone(), result.or(solved.result.clone())),
        Err((_, partial)) if !finished => (solved.status.clone(), partial.map(|r| *r)),
        Err((message, partial)) => (RunStatus::Failed(message), partial.map(|r| *r)),
    }
}

/// Copy the run directory `from` into `to` as the run of `scene`, a scene that is the same
/// run ([`same_run`]): `to` is owned fresh with the marker entries of `from`, every file is
/// copied byte for byte but scene.toml, summary.json and result.json, which are written as
/// the run of `scene` writes them: its scene.toml, the summary of `from` with `scene` as
/// its scene (after the copies are on disk, as a growth run syncs its files before its
/// summary), and, for a `finished` run, `result` with the files of `to` recorded last.
/// Returns that result (None: the run had not finished).
pub fn copy_run(
    from: &Path,
    scene: &Scene,
    to: &Path,
    result: Option<&RunResult>,
    finished: bool,
) -> Result<Option<RunResult>, RunFailure> {
    let partial = || result.map(|r| Box::new(r.clone()));
    let fail = |message: String| (message, partial());
    let marker = Marker::read(from).ok_or_else(|| {
        fail(format!(
            "{}: the run it shares has no {} marker",
            from.display(),
            rundir::MARKER_FILE
        ))
    })?;
    let entries: Vec<&str> = marker.entries.iter().map(String::as_str).collect();
    let owned =
        OwnedDir::fresh(to, &marker.kind, &entries, &[]).map_err(|e| fail(e.to_string()))?;
    let to = owned.path();
    let own = [SCENE_FILE, SUMMARY_FILE];
    for rel in files::list(from).map_err(|e| fail(io(from, e).to_string()))? {
        if own.contains(&rel.as_str()) {
            continue;
        }
        let target = to.join(&rel);
        if let Some(parent) = target.parent() {
            fs::create_dir_all(parent).map_err(|e| fail(io(parent, e).to_string()))?;
        }
        fs::copy(from.join(&rel), &target).map_err(|e| fail(io(&target, e).to_string()))?;
    }
    let path = to.join(SCENE_FILE);
    write_atomic(&path, scene.to_toml().as_bytes()).map_err(|e| fail(io(&path, e).to_string()))?;
    if from.join(SUMMARY_FILE).is_file() {
        let mut summary = Summary::read(from).map_err(|e| fail(e.to_string()))?;
        match &mut summary {
            Summary::Growth(s) => s.run = RunInfo::of(scene),
            Summary::Elastic(s) => s.run = RunInfo::of(scene),
            other => {
                return Err(fail(format!(
                    "{}: the run it shares holds a {}, not a run's summary",
                    from.display(),
                    other.kind()
                )))
            }
        }
        rundir::atomic::sync_tree(to).map_err(|e| fail(io(to, e).to_string()))?;
        summary.write(to).map_err(|e| fail(e.to_string()))?;
    }
    let Some(result) = result.filter(|_| finished) else {
        return Ok(None);
    };
    let mut result = result.clone();
    result.files = files::record(to).map_err(|e| fail(io(to, e).to_string()))?;
    let path = to.join(RESULT_FILE);
    let text = serde_json::to_string_pretty(&result).unwrap_or_default();
    write_atomic(&path, text.as_bytes()).map_err(|e| fail(io(&path, e).to_string()))?;
    Ok(Some(result))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "[fibres]\nD = 0.0\n[growth]\neta0 = 70.0\nt_end = 0.2\n[solver]\nnodes = 21\nrtol = 1e-3\n[output]\ntimes = [0.1]\nhistory_points = 10\n";

    /// The small scene named `name`, with the overrides `sets`.
    fn scene(name: &str, sets: &[&str]) -> Scene {
        let text = format!("name = \"{name}\"\ndescription = \"{name}'s\"\n{SMALL}");
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        Scene::from_toml_str(&text, &format!("{name}.toml"), &sets).unwrap()
    }

    fn summary(dir: &Path) -> serde_json::Value {
        serde_json::from_str(&fs::read_to_string(dir.join(SUMMARY_FILE)).unwrap()).unwrap()
    }

    /// Solve `a` into `dir/a` as the first of its kind, then make `b` its twin in `dir/b`.
    fn solve_and_share(dir: &Path, a: &Scene, b: &Scene) -> (RunStatus, Option<RunResult>) {
        let twins = Twins::default();
        let Claim::First(publisher) = twins.claim(a, &dir.join("a")) else {
            panic!("the first run is not first");
        };
        let Claim::Twin(waiter) = twins.claim(b, &dir.join("b")) else {
            panic!("the same run is not a twin");
        };
        let (status, result) = super::super::run_scene(a, &dir.join("a"));
        publisher.publish(&status, result.as_ref());
        let solved = waiter.wait();
        assert_eq!(solved.status, status);
        twin_of(&solved, b, &dir.join("b"))
    }

    /// A twin's directory: every data file the solved run's, byte for byte; its own
    /// scene.toml and summary.json (the solved run's but for the scene); a result.json
    /// whose record of the files verifies.
    #[test]
    fn a_twin_gets_the_solved_runs_files_under_its_own_scene() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = (scene("first", &[]), scene("second", &[]));
        assert!(same_run(&a, &b));
        let (status, result) = solve_and_share(tmp.path(), &a, &b);
        assert_eq!(status, RunStatus::Ok);
        let (from, to) = (tmp.path().join("a"), tmp.path().join("b"));
        let paths = files::list(&from).unwrap();
        assert_eq!(paths, files::list(&to).unwrap());
        assert!(
            paths.iter().any(|p| p.starts_with("snapshots/")),
            "{paths:?}"
        );
        for rel in &paths {
            let (x, y) = (
                fs::read(from.join(rel)).unwrap(),
                fs::read(to.join(rel)).unwrap(),
            );
            match rel.as_str() {
                SCENE_FILE => assert_eq!(String::from_utf8(y).unwrap(), b.to_toml()),
                SUMMARY_FILE => {}
                _ => assert_eq!(x, y, "{rel}"),
            }
        }
        assert_eq!(Marker::read(&from), Marker::read(&to));
        let (mut x, mut y) = (summary(&from), summary(&to));
        assert_eq!(y["scene"]["name"], "second");
        assert_eq!(y["scene"]["description"], "second's");
        assert_eq!(y["scene"]["path"], "second.toml");
        assert_eq!(x["scene"]["name"], "first");
        x["scene"] = serde_json::Value::Null;
        y["scene"] = serde_json::Value::Null;
        assert_eq!(x, y);
        let result = result.unwrap();
        let written: RunResult =
            serde_json::from_str(&fs::read_to_string(to.join(RESULT_FILE)).unwrap()).unwrap();
        // Field for field, NaN included (defocus_D where no rule reads defocus).
        assert_eq!(format!("{written:?}"), format!("{result:?}"));
        assert_eq!(files::verify(&to, &result.files), None);
        assert_eq!(files::unrecorded(&to, &result.files), None);
    }

    /// The twin of a run that failed fails with its message and keeps a copy of what it
    /// wrote, under its own scene; no result.json.
    #[test]
    fn the_twin_of_a_failed_run_fails_with_its_message() {
        let tmp = tempfile::tempdir().unwrap();
        // η0 = 1e4 with two Euler steps turns the shell inside out at the first step.
        let sets = [
            "solver.integrator=\"euler\"",
            "solver.steps=2",
            "growth.eta0=1e4",
        ];
        let (a, b) = (scene("first", &sets), scene("second", &sets));
        let (status, _) = solve_and_share(tmp.path(), &a, &b);
        let RunStatus::Failed(message) = &status else {
            panic!("{status:?}");
        };
        assert!(message.contains("growth failed at t = 0.02"), "{message}");
        let (from, to) = (tmp.path().join("a"), tmp.path().join("b"));
        let (first, _) = super::super::run_scene(&a, &tmp.path().join("again"));
        assert_eq!(first, status);
        assert_eq!(summary(&to)["status"], "failed");
        assert_eq!(summary(&to)["scene"]["name"], "second");
        assert_eq!(
            fs::read(from.join(crate::rundir::growth::SERIES_FILE)).unwrap(),
            fs::read(to.join(crate::rundir::growth::SERIES_FILE)).unwrap()
        );
        assert!(!to.join(RESULT_FILE).exists());
    }

    /// A solving run that ends without saying how (a panic past its runner) leaves its
    /// twins a failure, not a wait forever.
    #[test]
    fn a_publisher_dropped_unpublished_fails_its_twins() {
        let twins = Twins::default();
        let first = twins.claim(&scene("first", &[]), Path::new("a"));
        let Claim::Twin(waiter) = twins.claim(&scene("second", &[]), Path::new("b")) else {
            panic!("not a twin");
        };
        drop(first);
        let solved = waiter.wait();
        assert!(matches!(solved.status, RunStatus::Failed(m) if m.contains("stopped before")));
        // Another run is a run of its own.
        let other = scene("third", &["fibres.D=100"]);
        assert!(matches!(
            twins.claim(&other, Path::new("c")),
            Claim::First(_)
        ));
    }
}
