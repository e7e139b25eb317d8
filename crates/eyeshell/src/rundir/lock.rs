//! One writer per output: an advisory lock on a hidden file beside the target,
//! `.NAME.lock` (NAME shortened as the temporary names are: [`super::atomic::hidden_base`]).
//!
//! The lock is `flock`-style (std's `File::try_lock`): the kernel releases it when the
//! holder dies, however it dies, so a killed run never blocks the next one. The holder
//! writes its pid into the file, for the message the next writer sees. On release the file
//! is unlinked, then unlocked; a process that opened the file before the unlink and locks
//! it after finds that the path no longer names the file it holds, and starts again.

use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use super::atomic::{hidden_base, parent_of};
use super::OutputError;

/// How often a lock is retried when its file was unlinked under us (a race with a holder
/// that was releasing it); more than a few means something else keeps removing it.
const ATTEMPTS: usize = 8;

/// The lock of one output target, held until dropped.
#[derive(Debug)]
pub struct DirLock {
    path: PathBuf,
    file: Option<File>,
}

impl DirLock {
    /// Lock `target` (which need not exist; its parent must). Another live holder is an
    /// error that names it: [`OutputError::Busy`].
    pub fn acquire(target: &Path) -> Result<DirLock, OutputError> {
        let path = lock_path(target);
        for _ in 0..ATTEMPTS {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(|e| OutputError::io(&path, e))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    return Err(OutputError::Busy {
                        path: target.to_path_buf(),
                        pid: holder(&mut file),
                    })
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(OutputError::io(&path, e)),
            }
            if !names_file(&path, &file) {
                continue; // unlinked by the previous holder after we opened it
            }
            let pid = std::process::id().to_string();
            let stamp = file
                .set_len(0)
                .and_then(|_| file.rewind())
                .and_then(|_| file.write_all(pid.as_bytes()));
            stamp.map_err(|e| OutputError::io(&path, e))?;
            return Ok(DirLock {
                path,
                file: Some(file),
            });
        }
        Err(OutputError::Busy {
            path: target.to_path_buf(),
            pid: None,
        })
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Unlink first, then unlock (by closing): see the module comment.
        let _ = fs::remove_file(&self.path);
        self.file.take();
    }
}

/// Does a live process hold the lock of `target`? Asked without taking it over: the lock
/// file is opened (never created) and locked shared for an instant, which fails only
/// while a holder has it. A holder that died, however it died, holds nothing, so a
/// record that says "running" with no holder is the record of a process that was killed.
/// When the lock cannot be probed, the answer is yes (nothing is said to be dead that
/// might not be).
pub fn is_held(target: &Path) -> bool {
    let file = match File::open(lock_path(target)) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return false,
        Err(_) => return true,
    };
    match file.try_lock_shared() {
        Ok(()) => false, // released when `file` closes, at once
        Err(std::fs::TryLockError::WouldBlock) => true,
        Err(std::fs::TryLockError::Error(_)) => true,
    }
}

/// `.NAME.lock` beside `target`.
pub fn lock_path(target: &Path) -> PathBuf {
    let base = hidden_base(target.file_name().unwrap_or_default());
    parent_of(target).join(format!(".{base}.lock"))
}

/// The pid written by the holder of a lock, if it wrote one.
fn holder(file: &mut File) -> Option<u32> {
    let mut text = String::new();
    file.rewind().ok()?;
    file.take(32).read_to_string(&mut text).ok()?;
    text.trim().parse().ok()
}

/// Does `path` still name the file we hold open?
#[cfg(unix)]
fn names_file(path: &Path, file: &File) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (fs::metadata(path), file.metadata()) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn names_file(path: &Path, _file: &File) -> bool {
    path.exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_until_the_first_releases() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        let first = DirLock::acquire(&target).unwrap();
        assert!(lock_path(&target).is_file());
        match DirLock::acquire(&target) {
            Err(OutputError::Busy { pid, .. }) => assert_eq!(pid, Some(std::process::id())),
            other => panic!("expected Busy, got {other:?}"),
        }
        drop(first);
        assert!(!lock_path(&target).exists(), "the lock file is removed");
        let again = DirLock::acquire(&target).unwrap();
        drop(again);
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_stale_lock_file_of_a_dead_holder_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        fs::write(lock_path(&target), "999999999").unwrap();
        let lock = DirLock::acquire(&target).unwrap();
        assert_eq!(
            fs::read_to_string(lock_path(&target)).unwrap(),
            std::process::id().to_string()
        );
        drop(lock);
    }

    #[test]
    fn a_holder_is_seen_alive_and_a_dead_one_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("3.json");
        assert!(!is_held(&target), "no lock file");
        let lock = DirLock::acquire(&target).unwrap();
        assert!(is_held(&target));
        // Probing takes nothing: the holder keeps it, and a second writer is still refused.
        assert!(matches!(
            DirLock::acquire(&target),
            Err(OutputError::Busy { .. })
        ));
        drop(lock);
        assert!(!is_held(&target));
        // The file of a holder that was killed (left behind, unlocked) holds nothing.
        fs::write(lock_path(&target), "999999999").unwrap();
        assert!(!is_held(&target));
        assert!(DirLock::acquire(&target).is_ok());
    }

    #[test]
    fn long_names_get_a_short_lock_name() {
        let name = "x".repeat(250);
        let p = lock_path(&Path::new("/tmp").join(&name));
        assert!(p.file_name().unwrap().len() < 100, "{}", p.display());
        assert_ne!(p, lock_path(&Path::new("/tmp").join("x".repeat(249))));
    }
}
