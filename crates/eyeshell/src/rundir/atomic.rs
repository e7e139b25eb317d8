//! Files and directories that appear whole or not at all: the one atomic writer of eyeshell.
//!
//! - A file is written to a temporary sibling `.NAME.tmp-<pid>` and renamed into place
//!   ([`write_atomic`]): a reader sees the old file or the new one, never half of one.
//! - A directory is filled in a temporary sibling `.NAME.tmp-<pid>` ([`AtomicDir`]) and
//!   renamed into place by [`AtomicDir::commit`]. A directory already at the target is moved
//!   aside to `.NAME.old-<pid>` first and removed after the rename, so the target is never
//!   half-replaced. Dropping an [`AtomicDir`] uncommitted removes the temporary directory
//!   and the parents it created.
//! - An [`AtomicDir`] holds the target's advisory lock ([`super::lock::DirLock`]) from
//!   creation to commit, so two processes never write one target at once; holding it, any
//!   `.NAME.tmp-*` or `.NAME.old-*` beside the target is the litter of a process that was
//!   killed, and is removed (an `.old` one is first put back if the target is missing: it
//!   is the previous output, moved aside by a commit that was cut short).
//! - A long NAME is shortened in these hidden names (its first bytes and a hash), so a
//!   legal 255-byte target never gets an illegal temporary name.
//!
//! Whether a target may be replaced at all is the caller's policy, checked before
//! [`AtomicDir::create`] and again before [`AtomicDir::commit`]: see [`super::owner`]. The
//! figures crate (`eyeshell-plot`), which knows nothing of eyeshell, keeps its own two-file
//! write of a PNG and its SVG.

use std::ffi::OsStr;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::lock::DirLock;
use super::OutputError;

/// A name longer than this (bytes) is shortened in the hidden names beside it.
const MAX_BASE: usize = 100;

/// The part of a hidden sibling's name that stands for the file name `name`: the name
/// itself, or, when it is long, its first 60 bytes and a hash of the whole.
pub fn hidden_base(name: &OsStr) -> String {
    let name = name.to_string_lossy();
    if name.len() <= MAX_BASE {
        return name.into_owned();
    }
    let mut cut = 60;
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    let hash = crate::hash::fnv1a64(name.as_bytes());
    format!("{}~{hash:016x}", &name[..cut])
}

/// The hidden sibling `.BASE.<tag>-<pid>` of `path` (`tag`: `tmp` or `old`), BASE being
/// [`hidden_base`] of its name.
pub fn sibling(path: &Path, tag: &str) -> PathBuf {
    let base = hidden_base(path.file_name().unwrap_or_default());
    path.with_file_name(format!(".{base}.{tag}-{}", std::process::id()))
}

/// The hidden siblings `.BASE.<tag>-<pid>` of `path` that exist now, with their pids.
pub fn siblings(path: &Path, tag: &str) -> Vec<(PathBuf, u32)> {
    let prefix = format!(
        ".{}.{tag}-",
        hidden_base(path.file_name().unwrap_or_default())
    );
    let parent = parent_of(path);
    let Ok(entries) = fs::read_dir(&parent) else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let pid = name.strip_prefix(&prefix)?.parse::<u32>().ok()?;
            Some((e.path(), pid))
        })
        .collect()
}

/// Is a hidden name one of eyeshell's temporaries (`.X.tmp-<pid>`, `.X.old-<pid>`,
/// `.X.lock`)? Such litter may be removed with the directory that holds it.
pub fn is_litter(name: &str) -> bool {
    if !name.starts_with('.') {
        return false;
    }
    if name.ends_with(".lock") {
        return true;
    }
    ["tmp-", "old-"].iter().any(|tag| {
        name.rsplit_once(&format!(".{tag}"))
            .is_some_and(|(_, pid)| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
    })
}

/// Is process `pid` alive? On a system without /proc, every process is taken to be alive
/// (its litter is then never removed, which is safe).
pub fn pid_alive(pid: u32) -> bool {
    let proc = Path::new("/proc");
    !proc.is_dir() || proc.join(pid.to_string()).exists()
}

/// The directory that holds `path` (`.` for a bare name).
pub fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Remove the temporary files `.NAME.tmp-<pid>` beside `path` left by killed processes
/// (a file has no lock, so only those of dead pids are touched).
pub fn remove_dead_temporaries(path: &Path) {
    for (tmp, pid) in siblings(path, "tmp") {
        if !pid_alive(pid) && fs::symlink_metadata(&tmp).is_ok_and(|m| m.is_file()) {
            let _ = fs::remove_file(&tmp);
        }
    }
}

/// Write `bytes` to `path` through a temporary sibling and a rename: never half-written.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), std::io::Error> {
    let tmp = sibling(path, "tmp");
    let write = || -> std::io::Result<()> {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.flush()
    };
    if let Err(e) = write() {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    fs::rename(&tmp, path).inspect_err(|_| {
        let _ = fs::remove_file(&tmp);
    })
}

/// A directory being written: files go into a temporary sibling of the target, which
/// [`AtomicDir::commit`] renames into place. Dropping it uncommitted removes it.
#[derive(Debug)]
pub struct AtomicDir {
    target: PathBuf,
    tmp: PathBuf,
    committed: bool,
    /// Parent directories this writer created (outermost first), removed again if it fails.
    created: Vec<PathBuf>,
    /// The target's lock, held until the commit (released before the parents are removed).
    lock: Option<DirLock>,
}

impl AtomicDir {
    /// Lock `target`, clean the litter of killed writers beside it, and create the
    /// temporary directory next to it (and the target's missing parents).
    pub fn create(target: &Path) -> Result<AtomicDir, OutputError> {
        if target.file_name().is_none() {
            return Err(OutputError::NoName {
                path: target.to_path_buf(),
            });
        }
        let parent = parent_of(target);
        let mut created: Vec<PathBuf> = parent
            .ancestors()
            .filter(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        created.reverse();
        fs::create_dir_all(&parent).map_err(|e| OutputError::io(&parent, e))?;
        let mut dir = AtomicDir {
            target: target.to_path_buf(),
            tmp: sibling(&parent.join(target.file_name().unwrap_or_default()), "tmp"),
            committed: false,
            created,
            lock: None,
        };
        // On any error below, dropping `dir` removes the parents it created.
        dir.lock = Some(DirLock::acquire(target)?);
        remove_litter(target)?;
        fs::create_dir(&dir.tmp).map_err(|e| OutputError::io(&dir.tmp, e))?;
        Ok(dir)
    }

    /// The final path of the directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The temporary directory, where everything must be written until the commit.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// The path of `name` inside the temporary directory.
    pub fn file(&self, name: &str) -> PathBuf {
        self.tmp.join(name)
    }

    /// Move the finished directory into place. Whatever is at the target (the caller has
    /// checked that it may be replaced) is moved aside first and removed after.
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        if fs::symlink_metadata(&self.target).is_err() {
            fs::rename(&self.tmp, &self.target).map_err(|e| OutputError::io(&self.target, e))?;
            self.committed = true;
            return Ok(self.target.clone());
        }
        let old = sibling(&self.tmp.with_file_name(self.target_name()), "old");
        // Not `remove_dir_all` on a symlink's target: a symlink here is removed as a file.
        if old.exists() {
            fs::remove_dir_all(&old).map_err(|e| OutputError::io(&old, e))?;
        }
        fs::rename(&self.target, &old).map_err(|e| OutputError::io(&self.target, e))?;
        if let Err(e) = fs::rename(&self.tmp, &self.target) {
            let _ = fs::rename(&old, &self.target);
            return Err(OutputError::io(&self.target, e));
        }
        self.committed = true;
        fs::remove_dir_all(&old).map_err(|e| OutputError::io(&old, e))?;
        Ok(self.target.clone())
    }

    fn target_name(&self) -> std::ffi::OsString {
        self.target.file_name().unwrap_or_default().to_os_string()
    }
}

/// With the target's lock held: put back a previous output that a killed commit had moved
/// aside (when the target is missing), and remove every other `.NAME.tmp-*` / `.NAME.old-*`
/// beside the target. Only directories and files are removed; a symlink is left alone.
pub(crate) fn remove_litter(target: &Path) -> Result<(), OutputError> {
    let mut old = siblings(target, "old");
    if fs::symlink_metadata(target).is_err() {
        if let Some((aside, _)) = old.pop() {
            fs::rename(&aside, target).map_err(|e| OutputError::io(target, e))?;
        }
    }
    for (path, _) in old.into_iter().chain(siblings(target, "tmp")) {
        let removed = match fs::symlink_metadata(&path) {
            Ok(m) if m.is_dir() => fs::remove_dir_all(&path),
            Ok(m) if m.is_file() => fs::remove_file(&path),
            _ => Ok(()),
        };
        removed.map_err(|e| OutputError::io(&path, e))?;
    }
    Ok(())
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        self.lock.take();
        if !self.committed {
            let _ = fs::remove_dir_all(&self.tmp);
            for dir in self.created.iter().rev() {
                let _ = fs::remove_dir(dir); // only if still empty
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_file_is_replaced_whole_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two");
        assert_eq!(names(dir.path()), vec!["a.txt"]);
        // A directory in the way: an error, and no temporary left.
        let blocked = dir.path().join("d");
        fs::create_dir(&blocked).unwrap();
        fs::write(blocked.join("x"), "x").unwrap();
        assert!(write_atomic(&blocked, b"no").is_err());
        assert_eq!(names(dir.path()), vec!["a.txt", "d"]);
    }

    #[test]
    fn the_temporary_names_follow_the_pattern() {
        let pid = std::process::id();
        assert_eq!(
            sibling(Path::new("out/run"), "tmp"),
            PathBuf::from(format!("out/.run.tmp-{pid}"))
        );
        let dir = tempfile::tempdir().unwrap();
        let w = AtomicDir::create(&dir.path().join("run")).unwrap();
        assert_eq!(
            w.path(),
            dir.path().join(format!(".run.tmp-{pid}")).as_path()
        );
    }

    #[test]
    fn a_directory_replaces_the_old_one_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("old-only"), "x").unwrap();
        let w = AtomicDir::create(&target).unwrap();
        fs::write(w.file("new"), "y").unwrap();
        assert_eq!(names(&target), vec!["old-only"]);
        assert_eq!(w.commit().unwrap(), target);
        assert_eq!(names(&target), vec!["new"]);
        assert_eq!(names(dir.path()), vec!["out"]);
        // Dropped uncommitted: nothing changes, nothing is left, created parents go too.
        let w = AtomicDir::create(&dir.path().join("a/b/out")).unwrap();
        fs::write(w.file("partial"), "z").unwrap();
        drop(w);
        assert_eq!(names(dir.path()), vec!["out"]);
        assert!(AtomicDir::create(Path::new("/")).is_err());
    }
}
