//! The sweep's output directory, checked before anything is written into it.
//!
//! Without `--resume` it is made fresh like any in-place output ([`rundir::OwnedDir::fresh`]:
//! a previous eyeshell output is removed, links inside it with it, never followed; the
//! directory is locked while the sweep runs). With `--resume`
//! what is there is kept, so it is checked first, and refused (bad input, nothing
//! changed) when:
//! - `summary.json`, `sweep.csv`, `runs`, `shards`, anything directly in `runs/`, or a
//!   run's `result.json` or `scene.toml` is a symbolic link: the sweep would read or write
//!   outside its directory through it;
//! - its summary.json is not a sweep's (a solve, grow, study or figures output);
//! - `runs/` holds runs that are not in this sweep: resuming would leave them beside the
//!   new runs, looking like part of a sweep they are not. `--resume` continues a sweep or
//!   adds runs to it; a sweep that dropped runs needs another directory or a fresh start.
//!
//! A shard (`--shard K/N`, [`prepare_shard`]) checks the directory the same way, resuming or
//! not (it shares the directory and so may remove nothing), and locks only its own record.

use std::fs;
use std::path::{Path, PathBuf};

use crate::rundir::lock::DirLock;
use crate::rundir::owner::Marker;
use crate::rundir::{self, OutputError, Summary, SUMMARY_FILE};
use crate::{Error, Subject};

use super::shard::{Shard, SHARDS_DIR};
use super::{RESULT_FILE, RUNS_DIR, SCENE_FILE, TABLE_FILE};

/// What to do instead, said after every refusal.
const INSTEAD: &str = "give another --out, or leave out --resume to replace it";
/// The same for a shard, which never replaces anything (another shard may be writing).
const SHARD_INSTEAD: &str =
    "give another --out (a shard never removes anything: other shards may be writing there)";
/// What a sweep's directory holds at the top; shards add `shards/`.
const ENTRIES: [&str; 4] = [RUNS_DIR, TABLE_FILE, SUMMARY_FILE, SHARDS_DIR];

/// Make `out` ready for a sweep whose run names `is_run` accepts: fresh, or (`resume`)
/// checked as the module says; the returned [`rundir::OwnedDir`] holds its lock until
/// dropped.
pub fn prepare(
    is_run: &dyn Fn(&str) -> bool,
    out: &Path,
    resume: bool,
    inputs: &[&Path],
) -> Result<rundir::OwnedDir, Error> {
    let entries = [RUNS_DIR, TABLE_FILE, SUMMARY_FILE];
    if !resume {
        return Ok(rundir::OwnedDir::fresh(out, "sweep", &entries, inputs)?);
    }
    check_kept(is_run, out)?;
    Ok(rundir::OwnedDir::resume(out, "sweep", &entries)?)
}

/// The checks of a sweep directory that is kept (`--resume`, `sweep merge`) as the module
/// says, without locking or writing anything: `sweep status` runs exactly these, so that
/// it says "done" only where `merge` would accept the directory.
pub fn check_kept(is_run: &dyn Fn(&str) -> bool, out: &Path) -> Result<(), Error> {
    // Kept, not replaced: what is there is checked by the rules below, not by kind.
    rundir::owner::inspect(&rundir::owner::normalise(out))?;
    refuse_links(out)?;
    no_link(&out.join(SHARDS_DIR))?;
    refuse_other_outputs(out, INSTEAD)?;
    refuse_other_runs(is_run, out, INSTEAD)
}

/// Make `out` ready for one shard of a sweep whose run names `is_run` accepts
/// ([`super::shard`]): checked as for `--resume` (whether or not the shard resumes: it may
/// not remove anything), given the sweep's marker
/// if it has none yet, with `runs/` and `shards/`. No lock is taken on `out`, which the
/// shards share; the shard's record, `shards/K.json`, is locked instead. Returns its path
/// and the lock.
pub fn prepare_shard(
    is_run: &dyn Fn(&str) -> bool,
    out: &Path,
    shard: Shard,
) -> Result<(PathBuf, DirLock), Error> {
    let out = &rundir::owner::normalise(out);
    // A shard started beside others may look at `out` while another is writing the
    // marker (its temporary file present, the marker not yet renamed into place): such a
    // refusal is retried once the marker is there, for up to a second.
    let mut tries = 0;
    loop {
        wait_for_marker(out);
        match check_and_mark(is_run, out) {
            Err(_) if tries < 50 && (sweep_marked(out) || marker_pending(out)) => {
                tries += 1;
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            done => break done?,
        }
    }
    let io = |path: &Path, source: std::io::Error| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    for name in [RUNS_DIR, SHARDS_DIR] {
        let path = out.join(name);
        match fs::create_dir(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => return Err(io(&path, e)),
            _ if !path.is_dir() => {
                return Err(Error::input(
                    Subject::File(path.to_path_buf()),
                    format!(
                        "{}: is not a directory, so this is not a sweep's output; {SHARD_INSTEAD}",
                        path.display()
                    ),
                ))
            }
            _ => {}
        }
    }
    let record = out.join(SHARDS_DIR).join(shard.file_name());
    no_link(&record)?;
    if record.exists() && !record.is_file() {
        return Err(Error::input(
            Subject::File(record.to_path_buf()),
            format!(
                "{}: is not a shard's record (not a file); {SHARD_INSTEAD}",
                record.display()
            ),
        ));
    }
    let lock = DirLock::acquire(&record)?;
    Ok((record, lock))
}

/// Refuse a plain sweep into `out` while a shard runs there (its record `shards/K.json` is
/// locked): replacing the directory would delete the shard's runs under it, and resuming
/// would run the same runs twice at once. (A shard started after this check is not seen:
/// shards take no lock on `out`, so that a merge may run beside them.)
pub fn refuse_running_shards(out: &Path) -> Result<(), Error> {
    let Ok(listed) = fs::read_dir(out.join(SHARDS_DIR)) else {
        return Ok(());
    };
    for entry in listed.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || !name.ends_with(".json") {
            continue;
        }
        if let Err(OutputError::Busy { pid, .. }) = DirLock::acquire(&path) {
            let by = pid.map(|p| format!(" (pid {p})")).unwrap_or_default();
            return Err(Error::input(Subject::File(out.to_path_buf()), format!(
                "{}: shard {} is running here{by}: a plain sweep would replace or rerun its runs; wait for the shards and run `eyeshell sweep merge {}`, or give another --out",
                out.display(),
                name.trim_end_matches(".json"),
                out.display()
            )));
        }
    }
    Ok(())
}

/// Wait (a second at most) while `out` has no marker and holds nothing but temporaries, as
/// while another shard, started at the same moment, writes the marker: a check now would
/// take it for a directory that is not eyeshell's.
fn wait_for_marker(out: &Path) {
    for _ in 0..50 {
        if !marker_pending(out) {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Whether `out` has a sweep's marker (written by a shard racing this one).
fn sweep_marked(out: &Path) -> bool {
    Marker::read(out).is_some_and(|m| m.kind == "sweep")
}

/// Whether `out` holds nothing but the temporary files of atomic writes and no marker yet:
/// another shard is writing the marker.
fn marker_pending(out: &Path) -> bool {
    Marker::read(out).is_none()
        && fs::read_dir(out).is_ok_and(|entries| {
            let names: Vec<String> = entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            !names.is_empty() && names.iter().all(|n| rundir::atomic::is_litter(n))
        })
}

/// The checks of [`prepare_shard`] on `out`, then its marker: an existing sweep's claimed,
/// or a new one written into an empty (or new) directory.
fn check_and_mark(is_run: &dyn Fn(&str) -> bool, out: &PathBuf) -> Result<(), Error> {
    rundir::owner::inspect(out)?;
    refuse_links(out)?;
    no_link(&out.join(SHARDS_DIR))?;
    refuse_other_outputs(out, SHARD_INSTEAD)?;
    refuse_other_runs(is_run, out, SHARD_INSTEAD)?;
    fs::create_dir_all(out).map_err(|source| Error::Io {
        path: out.clone(),
        source,
    })?;
    // The marker first, before any entry it must list: another shard checking `out` in
    // between sees an empty directory or a marked one, never unlisted entries. Shards that
    // race here write the same marker.
    match Marker::read(out) {
        Some(marker) if marker.kind == "sweep" => rundir::owner::claim(out, &ENTRIES)?,
        Some(marker) => {
            return Err(OutputError::OtherKind {
                path: out.clone(),
                found: marker.kind,
                wanted: "sweep".into(),
            }
            .into())
        }
        None => {
            rundir::owner::inspect(out)?;
            let mut marker = Marker::new("sweep");
            marker.entries = ENTRIES.iter().map(|e| e.to_string()).collect();
            marker.write(out)?;
        }
    }
    Ok(())
}

/// Refuse `path` if it is a symbolic link (a missing path is fine).
pub(crate) fn no_link(path: &Path) -> Result<(), Error> {
    match fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => Err(Error::input(Subject::File(path.to_path_buf()), format!(
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
            return Err(Error::input(
                Subject::File(runs.to_path_buf()),
                format!(
                    "{}: is not a directory, so this is not a sweep's output; {INSTEAD}",
                    runs.display()
                ),
            ))
        }
        _ => fs::read_dir(&runs).and_then(|d| d.map(|e| e.map(|e| e.path())).collect()),
    };
    listed.map_err(|source| Error::Io { path: runs, source })
}

fn refuse_other_outputs(out: &Path, instead: &str) -> Result<(), Error> {
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
            return Err(Error::input(
                Subject::File(out.to_path_buf()),
                format!("{e} (--resume continues a sweep only: {instead})"),
            ))
        }
    };
    Err(Error::input(
        Subject::File(out.to_path_buf()),
        format!(
            "{}: holds {held}, not a sweep; --resume continues a sweep only: {instead}",
            out.display()
        ),
    ))
}

fn refuse_other_runs(
    is_run: &dyn Fn(&str) -> bool,
    out: &Path,
    instead: &str,
) -> Result<(), Error> {
    let mut others: Vec<String> = run_entries(out)?
        .iter()
        .filter_map(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        // Hidden names are the temporary siblings of atomic writes; no run is named so.
        .filter(|n| !n.starts_with('.') && !is_run(n))
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
    Err(Error::input(Subject::File(out.join(RUNS_DIR).to_path_buf()), format!(
        "{}: holds {count} run{} that {} not in this sweep ({}); --resume only continues the same sweep or adds runs to it: {instead}",
        out.join(RUNS_DIR).display(),
        if count == 1 { "" } else { "s" },
        if count == 1 { "is" } else { "are" },
        shown.join(", ")
    )))
}
