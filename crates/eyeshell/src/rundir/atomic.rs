//! Files and directories that appear whole or not at all: the one atomic writer of eyeshell.
//!
//! - A file is written to a temporary sibling `.NAME.tmp-<pid>` and renamed into place
//!   ([`write_atomic`]): a reader sees the old file or the new one, never half of one.
//! - A directory is filled in a temporary sibling `.NAME.tmp-<pid>` ([`AtomicDir`]) and
//!   renamed into place by [`AtomicDir::commit`]. A directory already at the target is moved
//!   aside to `.NAME.old-<pid>` first and removed after the rename, so the target is never
//!   half-replaced. Dropping an [`AtomicDir`] uncommitted removes the temporary directory
//!   and the parents it created.
//!
//! Whether a target may be replaced at all is the caller's policy, checked before
//! [`AtomicDir::create`] and again before [`AtomicDir::commit`]: run directories replace
//! only previous eyeshell outputs ([`super::OutputDir`]), `eyeshell export` only previous
//! exports. Both use this module; the figures crate (`eyeshell-plot`), which knows nothing
//! of eyeshell, keeps its own two-file write of a PNG and its SVG.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::OutputError;

/// The hidden sibling `.NAME.<tag>-<pid>` of `path` (`tag`: `tmp` or `old`).
pub fn sibling(path: &Path, tag: &str) -> PathBuf {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!(".{name}.{tag}-{}", std::process::id()))
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
}

impl AtomicDir {
    /// Create the temporary directory next to `target`, and the target's missing parents.
    /// A leftover temporary directory of a killed run with our pid is removed first.
    pub fn create(target: &Path) -> Result<AtomicDir, OutputError> {
        if target.file_name().is_none() {
            return Err(OutputError::NoName {
                path: target.to_path_buf(),
            });
        }
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let mut created: Vec<PathBuf> = parent
            .ancestors()
            .filter(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        created.reverse();
        fs::create_dir_all(&parent).map_err(|e| OutputError::io(&parent, e))?;
        let tmp = sibling(&parent.join(target.file_name().unwrap_or_default()), "tmp");
        if tmp.exists() {
            // A leftover of a killed run with our pid: ours to remove.
            fs::remove_dir_all(&tmp).map_err(|e| OutputError::io(&tmp, e))?;
        }
        fs::create_dir(&tmp).map_err(|e| OutputError::io(&tmp, e))?;
        Ok(AtomicDir {
            target: target.to_path_buf(),
            tmp,
            committed: false,
            created,
        })
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

impl Drop for AtomicDir {
    fn drop(&mut self) {
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
