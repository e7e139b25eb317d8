//! The sweep's output directory, checked before anything is written into it.
//!
//! Without `--resume` it is made fresh like any in-place output ([`rundir::OwnedDir::fresh`]:
//! a previous eyeshell output is removed, links inside it with it, never followed; the
//! directory is locked while the sweep runs). With `--resume`
//! what is there is kept, so it is checked first, and refused (bad input, nothing
//! changed) when:
//! - `summary.json`, `sweep.csv`, `runs`, anything directly in `runs/`, or a run's
//!   `result.json` or `scene.toml` is a symbolic link: the sweep would read or write
//!   outside its directory through it;
//! - its summary.json is not a sweep's (a solve, grow, study or figures output);
//! - `runs/` holds runs that are not in this sweep: resuming would leave them beside the
//!   new runs, looking like part of a sweep they are not. `--resume` continues a sweep or
//!   adds runs to it; a sweep that dropped runs needs another directory or a fresh start.

use std::fs;
use std::path::Path;

use crate::rundir::{self, Summary, SUMMARY_FILE};
use crate::scene::sweep::Sweep;
use crate::Error;

use super::{RESULT_FILE, RUNS_DIR, SCENE_FILE, TABLE_FILE};

/// What to do instead, said after every refusal.
const INSTEAD: &str = "give another --out, or leave out --resume to replace it";

/// Make `out` ready for `sweep`: fresh, or (`resume`) checked as the module says; the
/// returned [`rundir::OwnedDir`] holds its lock until dropped.
pub fn prepare(sweep: &Sweep, out: &Path, resume: bool) -> Result<rundir::OwnedDir, Error> {
    let entries = [RUNS_DIR, TABLE_FILE, SUMMARY_FILE];
    if !resume {
        return Ok(rundir::OwnedDir::fresh(out, "sweep", &entries)?);
    }
    rundir::check_target(out)?;
    refuse_links(out)?;
    refuse_other_outputs(out)?;
    refuse_other_runs(sweep, out)?;
    Ok(rundir::OwnedDir::resume(out, "sweep", &entries)?)
}

/// Refuse `path` if it is a symbolic link (a missing path is fine).
fn no_link(path: &Path) -> Result<(), Error> {
    match fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => Err(Error::input(format!(
            "{}: is a symbolic link; a sweep never follows links inside its directory (remove it, or give another --out)",
            path.display()
        ))),
        _ => Ok(()),
    }
}

fn refuse_links(out: &Path) -> Result<(), Error> {
    for name in [SUMMARY_FILE, TABLE_FILE, RUNS_DIR] {
        no_link(&out.join(name))?;
    }
    for entry in run_entries(out)? {
        no_link(&entry)?;
        if entry.is_dir() {
            no_link(&entry.join(RESULT_FILE))?;
            no_link(&entry.join(SCENE_FILE))?;
        }
    }
    Ok(())
}

/// Everything directly in `out/runs` (nothing when it does not exist).
fn run_entries(out: &Path) -> Result<Vec<std::path::PathBuf>, Error> {
    let runs = out.join(RUNS_DIR);
    let listed = match fs::symlink_metadata(&runs) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Ok(m) if !m.is_dir() => {
            return Err(Error::input(format!(
                "{}: is not a directory, so this is not a sweep's output; {INSTEAD}",
                runs.display()
            )))
        }
        _ => fs::read_dir(&runs).and_then(|d| d.map(|e| e.map(|e| e.path())).collect()),
    };
    listed.map_err(|source| Error::Io { path: runs, source })
}

fn refuse_other_outputs(out: &Path) -> Result<(), Error> {
    if fs::symlink_metadata(out.join(SUMMARY_FILE)).is_err() {
        return Ok(());
    }
    let held = match Summary::read(out) {
        Ok(Summary::Sweep(_)) => return Ok(()),
        Ok(Summary::Elastic(_)) => "a solve output".to_string(),
        Ok(Summary::Growth(_)) => "a grow output".to_string(),
        Ok(Summary::Study(s)) => format!("the output of a study ({})", s.study),
        Ok(Summary::Figures(_)) => "figures".to_string(),
        Err(e) => {
            return Err(Error::input(format!(
                "{e} (--resume continues a sweep only: {INSTEAD})"
            )))
        }
    };
    Err(Error::input(format!(
        "{}: holds {held}, not a sweep; --resume continues a sweep only: {INSTEAD}",
        out.display()
    )))
}

fn refuse_other_runs(sweep: &Sweep, out: &Path) -> Result<(), Error> {
    let mut others: Vec<String> = run_entries(out)?
        .iter()
        .filter_map(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        // Hidden names are the temporary siblings of atomic writes; no run is named so.
        .filter(|n| !n.starts_with('.') && !sweep.runs.iter().any(|r| &r.name == n))
        .collect();
    if others.is_empty() {
        return Ok(());
    }
    others.sort();
    let count = others.len();
    let mut shown: Vec<String> = others
        .iter()
        .take(3)
        .map(|n| crate::text::one_line(n))
        .collect();
    if count > 3 {
        shown.push(format!("and {} more", count - 3));
    }
    Err(Error::input(format!(
        "{}: holds {count} run{} that {} not in this sweep ({}); --resume only continues the same sweep or adds runs to it: {INSTEAD}",
        out.join(RUNS_DIR).display(),
        if count == 1 { "" } else { "s" },
        if count == 1 { "is" } else { "are" },
        shown.join(", ")
    )))
}
