//! `--resume`: which runs of an earlier sweep into the same directory may be reused.
//!
//! A run is reused when its directory holds a result.json, a scene.toml identical to the
//! run's effective scene, and every file result.json lists with the size and checksum it
//! had when the run ended ([`super::files`]), and result.json lists every file the run
//! itself names (its marker's entries, its summary.json's series, history and snapshots:
//! [`files::unrecorded`]). A run that never finished simply runs; one
//! that finished but fails a check runs again, and [`Reuse::Stale`] says why (the command
//! line prints it with the run's line).

use std::fs;
use std::path::Path;

use crate::scene::sweep::SweepRun;

use super::{files, RunResult, RESULT_FILE, SCENE_FILE};

/// What an earlier sweep left of one run.
#[derive(Debug)]
pub enum Reuse {
    /// Finished, with the same scene and its files intact.
    Yes(RunResult),
    /// Nothing finished there (no result.json): the run runs.
    No,
    /// Finished, but not to be trusted: why it runs again.
    Stale(String),
}

/// What the earlier sweep left of `run` in `dir`. The caller has refused symbolic links
/// at `dir`, its scene.toml and its result.json ([`super::target`]); the files checked
/// are reached without following any.
pub fn reusable(run: &SweepRun, dir: &Path) -> Reuse {
    let result = match fs::read_to_string(dir.join(RESULT_FILE)) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Reuse::No,
        Err(e) => return Reuse::Stale(format!("its {RESULT_FILE} could not be read: {e}")),
    };
    let result: RunResult = match serde_json::from_str(&result) {
        Ok(r) => r,
        Err(e) => return Reuse::Stale(format!("its {RESULT_FILE} is not valid: {e}")),
    };
    match fs::read_to_string(dir.join(SCENE_FILE)) {
        Ok(scene) if scene == run.scene.to_toml() => {}
        Ok(_) => return Reuse::Stale("its scene changed".into()),
        Err(e) => return Reuse::Stale(format!("its {SCENE_FILE}: {e}")),
    }
    match files::verify(dir, &result.files).or_else(|| files::unrecorded(dir, &result.files)) {
        None => Reuse::Yes(result),
        Some(why) => Reuse::Stale(why),
    }
}
