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

    /// Every key of the key table, swept over two or more values on an elastic scene, a
    /// growing one of the published surfaces and a growing one of everything (optics,
    /// dioptres, an exponential schedule, ages): each sweep is refused up front naming the
    /// key, or every run reaches a worker whole. A key no run reads is refused naming why
    /// (every run would otherwise fail to read back from its TOML), and a key some runs read (optics.pupil crossed with stimulus.source)
    /// is swept, the runs that do not read it carrying it as given.
    #[test]
    fn every_key_of_the_key_table_is_swept_or_refused_naming_why() {
        use eyeshell::scene::{Access, KeyValue, KEYS};
        let bases = [
            ("elastic", "[solver]\nnodes = 21\n"),
            ("growing", "[solver]\nnodes = 21\n[growth]\neta0 = 70.0\n"),
            ("everything", "[solver]\nnodes = 21\n[growth]\neta0 = 70.0\nschedule = \"exponential\"\nschedule_tau = 2.0\n[stimulus]\nsource = \"optics\"\nclassify = \"dioptres\"\n[time]\nunit = \"years\"\nstart = 2.0\nend = 12.0\n"),
        ];
        let (mut swept, mut refused, mut not_in_effect) = (0, 0, 0);
        for (base, text) in bases {
            let scene = Scene::from_toml_str(text, "b.toml", &[]).unwrap();
            for spec in KEYS {
                let values: Vec<String> = match (spec.access, spec.get(&scene)) {
                    (Access::Float { .. }, KeyValue::Float(d)) if d.is_finite() => {
                        let other = if d == 0.0 { 0.5 } else { d * 1.05 };
                        vec![
                            eyeshell::text::toml_float(d),
                            eyeshell::text::toml_float(other),
                        ]
                    }
                    (Access::OptionalFloat { .. }, _) => vec!["0.5".into(), "2.0".into()],
                    (Access::Count { .. }, KeyValue::Count(n)) => {
                        vec![n.to_string(), (n + 1).to_string()]
                    }
                    (Access::Bool { .. }, _) => vec!["true".into(), "false".into()],
                    (Access::Choice { names, .. }, _) => {
                        names.iter().map(|n| format!("{n:?}")).collect()
                    }
                    // Metadata and array-valued keys (lists of times, lenses, surface
                    // tables) are not swept here: their grids are lists of lists.
                    _ => continue,
                };
                let sweep = format!(
                    "{text}[sweep.grid]\n\"{}\" = [{}]\n",
                    spec.key,
                    values.join(", ")
                );
                let what = format!("{base}: {} = [{}]", spec.key, values.join(", "));
                match Sweep::from_toml_str(&sweep, "s.toml", &[]) {
                    Err(e) => {
                        let e = e.to_string();
                        assert!(!e.contains("internal error"), "{what}: {e}");
                        assert!(e.contains(spec.key), "{what}: {e}");
                        refused += 1;
                        if e.contains("which no run reads") {
                            not_in_effect += 1;
                        }
                    }
                    Ok(sweep) => {
                        for run in &sweep.runs {
                            let request = Request::of(run, "runs/x".into())
                                .unwrap_or_else(|e| panic!("{what}: {}: {e}", run.name));
                            assert_eq!(scene_of(&request).unwrap(), run.scene, "{what}");
                        }
                        swept += 1;
                    }
                }
            }
        }
        assert!(
            swept > 100 && not_in_effect > 10,
            "{swept} swept, {refused} refused ({not_in_effect} not in effect)"
        );
        // The three, refused naming why; as samples too.
        let growing = bases[1].1;
        for (key, values, why) in [
            ("optics.pupil", "[2.0, 4.0]", "stimulus.source = \"optics\""),
            (
                "stimulus.myopia_D",
                "[-1.0, -2.0]",
                "stimulus.classify = \"dioptres\"",
            ),
            (
                "growth.schedule_tau",
                "[1.0, 2.0]",
                "growth.schedule = \"exponential\"",
            ),
        ] {
            let text = format!("{growing}[sweep.grid]\n\"{key}\" = {values}\n");
            let e = Sweep::from_toml_str(&text, "s.toml", &[])
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(&format!(
                    "sweeps {key}, which no run reads ({key} is not in effect: "
                )) && e.contains(why),
                "{e}"
            );
        }
        let sampled = format!("{growing}[sweep.sample]\neyes = 4\nseed = 1\n[sweep.sample.keys]\n\"optics.pupil\" = {{ dist = \"uniform\", low = 2.0, high = 4.0 }}\n");
        let e = Sweep::from_toml_str(&sampled, "s.toml", &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("samples optics.pupil, which no run reads"),
            "{e}"
        );
        // Read by some runs: swept, and every run whole.
        let mixed = format!("{growing}[sweep.grid]\n\"stimulus.source\" = [\"polynomial\", \"optics\"]\n\"optics.pupil\" = [2.0, 4.0]\n");
        let sweep = Sweep::from_toml_str(&mixed, "s.toml", &[]).unwrap();
        assert_eq!(sweep.runs.len(), 4);
        for run in &sweep.runs {
            let request = Request::of(run, "runs/x".into()).unwrap();
            assert_eq!(scene_of(&request).unwrap(), run.scene, "{}", run.name);
        }
    }
}
