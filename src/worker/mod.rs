//! Each run of `eyeshell sweep` in a process of its own, so that a run that aborts (an
//! allocation that fails, a stack overflow: Rust aborts the process, no unwinding) fails
//! alone instead of taking the sweep down.
//!
//! [`Workers`] is the sweep's [`Runner`](eyeshell::sweep::Runner): a pool of long-lived
//! worker processes, `eyeshell sweep-worker OUT` (hidden), one per job at most, each
//! serving run after run, so that starting a process is paid once per worker, not per run.
//! A worker that dies fails its run with one line saying how (`killed by signal 6:
//! SIGABRT; ...`) and its last line on stderr; the files the run wrote stay; the next run
//! gets a fresh worker. A worker's stderr never reaches the terminal.
//!
//! # Protocol
//!
//! One line each way per run, over the worker's stdin and stdout:
//! - the parent sends a [`Request`] as JSON: the run directory relative to OUT, and the
//!   run's effective scene as TOML (`Scene::to_toml`) with the little the TOML does not
//!   hold (origin, overrides, whether the red surface follows the blue one); [`scene_of`]
//!   rebuilds the scene, and the parent checks that it is equal to the run's before
//!   sending;
//! - the worker runs it ([`eyeshell::sweep::run_scene`], exactly as in one process) and
//!   answers with [`REPLY_TAG`] and a [`Reply`] as JSON; other lines on its stdout are
//!   ignored.
//!
//! End of input tells a worker to exit, at once, even in the middle of a run: that is how a
//! parent that ends (the second Ctrl-C exits at once) takes its workers with it. Workers
//! ignore SIGINT: a Ctrl-C at the terminal reaches the whole process group, and the parent
//! alone decides (the first lets the running runs finish).
//!
//! # Fault injection
//!
//! [`ABORT_ENV`]: a worker given `EYESHELL_TEST_ABORT_RUN=<run name>` aborts
//! (`std::process::abort`) when asked for that run, before running it. Tests use it to kill
//! a run deterministically; nothing else reads it, and runs in one process ignore it.

mod pool;
mod serve;

use serde::{Deserialize, Serialize};

use eyeshell::scene::sweep::SweepRun;
use eyeshell::scene::{Scene, SceneError};
use eyeshell::sweep::RunResult;

pub(crate) use pool::Workers;
pub(crate) use serve::serve;

/// The hidden subcommand a worker runs.
pub(crate) const WORKER_COMMAND: &str = "sweep-worker";
/// Fault injection for tests: the run a worker aborts on (see the module doc).
pub const ABORT_ENV: &str = "EYESHELL_TEST_ABORT_RUN";
/// The start of a worker's reply line.
const REPLY_TAG: &str = "eyeshell-sweep-worker: ";

/// One run, from the parent to a worker.
#[derive(Debug, Serialize, Deserialize)]
struct Request {
    /// The run directory relative to the worker's OUT, `/` between plain components.
    dir: String,
    /// The run's effective scene, `Scene::to_toml`.
    scene: String,
    /// What the TOML does not hold: `Scene::origin`, `Scene::overrides`, and whether the
    /// red surface follows the blue one (`to_toml` writes the red keys either way).
    origin: String,
    overrides: Vec<String>,
    red_follows_blue: bool,
}

/// How a run ended, from a worker to the parent.
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum Reply {
    Ok(RunResult),
    Failed {
        message: String,
        partial: Option<RunResult>,
    },
}

impl Request {
    /// The request for `run` into `OUT/<dir>`; Err if the scene would not arrive whole.
    fn of(run: &SweepRun, dir: String) -> Result<Request, String> {
        let request = Request {
            dir,
            scene: run.scene.to_toml(),
            origin: run.scene.origin.clone(),
            overrides: run.scene.overrides.clone(),
            red_follows_blue: run.scene.stimulus.red_follows_blue,
        };
        match scene_of(&request) {
            Ok(back) if back == run.scene => Ok(request),
            _ => Err(
                "internal error (a bug; please report it): the run's scene does not read back from its TOML"
                    .into(),
            ),
        }
    }
}

/// The scene a request carries.
fn scene_of(request: &Request) -> Result<Scene, SceneError> {
    let mut scene = Scene::from_toml_str(&request.scene, &request.origin, &[])?;
    scene.overrides.clone_from(&request.overrides);
    scene.stimulus.red_follows_blue = request.red_follows_blue;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use eyeshell::scene::sweep::Sweep;

    /// Every run of every sweep in scenes/ (and a few odd values) reaches a worker whole.
    #[test]
    fn every_run_scene_reads_back_from_its_toml() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
        let mut checked = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let overrides = ["solver.nodes=21".to_string()];
            let Ok(sweep) = Sweep::from_file(&path, &overrides) else {
                continue;
            };
            // A cohort kept as a table runs in the sweep's own process, never in a worker.
            let table = eyeshell::scene::sample::PerRun::Table;
            if sweep.sample.as_ref().is_some_and(|s| s.per_run == table) {
                continue;
            }
            for run in &sweep.runs {
                let request = Request::of(run, format!("runs/{}", run.name))
                    .unwrap_or_else(|e| panic!("{}: {}: {e}", path.display(), run.name));
                assert_eq!(scene_of(&request).unwrap(), run.scene);
                checked += 1;
            }
        }
        assert!(checked > 10, "{checked} runs");
        let odd = "name = \"odd \\\"one\\\"\"\ndescription = \"two\\nlines\"\n[sweep.grid]\n\"fibres.D\" = [0.1, 123.456789012345, 1e-300]\n\"stimulus.blue.P3\" = [23.5]\n\"growth.eta0\" = [60]\n";
        let sweep = Sweep::from_toml_str(odd, "odd.toml", &["pressure.dP=2.5".into()]).unwrap();
        for run in &sweep.runs {
            // Blue set and red not: red follows blue, which the TOML cannot say.
            assert!(run.scene.stimulus.red_follows_blue);
            let request = Request::of(run, "runs/x".into()).unwrap();
            assert_eq!(scene_of(&request).unwrap(), run.scene);
        }
    }
}
