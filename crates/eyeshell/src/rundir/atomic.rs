//! Files and directories that appear whole or not at all: the one atomic writer of eyeshell.
//!
//! - A file is written to a temporary sibling `.NAME.tmp-<pid>-<nonce>` and renamed into
//!   place ([`write_atomic`]): a reader sees the old file or the new one, never half of one.
//! - A directory is filled in a temporary sibling `.NAME.tmp-<pid>-<nonce>` ([`AtomicDir`])
//!   and renamed into place by [`AtomicDir::commit`]. A directory already at the target is
//!   moved aside to `.NAME.old-<pid>-<nonce>` first and removed after the rename, so the
//!   target is never half-replaced. Dropping an [`AtomicDir`] uncommitted removes the
//!   temporary directory and the parents it created.
//! - Durable, not only atomic: what is renamed into place is on disk first (the file, or
//!   every file and directory of the tree, `fsync`ed), and the directory that holds the new
//!   name is `fsync`ed after the rename. After a power cut a target is the old one or the
//!   new one whole, never a new name over empty or missing contents.
//! - The pid tells a dead writer's litter from a live one's (`/proc/<pid>`); the nonce (a
//!   per-process count and a hash of the host name and the clock) keeps two writers apart
//!   that share a pid: two threads of one process, or processes of one pid on two hosts of
//!   a cluster writing one shared file system.
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

/// The hidden sibling `.BASE.<tag>-<pid>-<nonce>` of `path` (`tag`: `tmp` or `old`), BASE
/// being [`hidden_base`] of its name: a new name at every call.
pub fn sibling(path: &Path, tag: &str) -> PathBuf {
    let base = hidden_base(path.file_name().unwrap_or_default());
    path.with_file_name(format!(".{base}.{tag}-{}-{}", std::process::id(), nonce()))
}

/// Eight hex digits that differ between calls in this process (a counter) and, with high
/// probability, between processes of one pid on different hosts or at different times.
fn nonce() -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNT: AtomicU64 = AtomicU64::new(0);
    let count = COUNT.fetch_add(1, Ordering::Relaxed);
    let host = fs::read("/proc/sys/kernel/hostname").unwrap_or_default();
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let mut bytes = host;
    bytes.extend_from_slice(&nanos.to_le_bytes());
    bytes.extend_from_slice(&count.to_le_bytes());
    let h = crate::hash::fnv1a64(&bytes);
    format!("{:08x}", (h ^ (h >> 32)) as u32)
}

/// The pid in a hidden sibling's suffix `<pid>` or `<pid>-<nonce>` (the form without a
/// nonce is an older eyeshell's litter, still recognised and cleaned).
fn suffix_pid(suffix: &str) -> Option<u32> {
    let (pid, nonce) = suffix.split_once('-').unwrap_or((suffix, "0"));
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let hex = !nonce.is_empty() && nonce.bytes().all(|b| b.is_ascii_hexdigit());
    (digits(pid) && hex).then(|| pid.parse().ok()).flatten()
}

/// The hidden siblings `.BASE.<tag>-<pid>[-<nonce>]` of `path` that exist now, with their
/// pids.
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
            let pid = suffix_pid(name.strip_prefix(&prefix)?)?;
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
            .is_some_and(|(_, suffix)| suffix_pid(suffix).is_some())
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

/// Write `bytes` to `path` through a temporary sibling and a rename: never half-written,
/// and on disk (the file, then its directory) when this returns.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), std::io::Error> {
    write_renamed(path, bytes, true)
}

/// [`write_atomic`] without the `fsync`s, for a file inside a directory that is synced
/// whole ([`sync_tree`]) before the record that says it is complete is written (a growth
/// run's snapshots before its summary.json): a reader never sees half a file, and after
/// a power cut the completion record is not there to vouch for a lost one.
pub fn write_atomic_unsynced(path: &Path, bytes: &[u8]) -> Result<(), std::io::Error> {
    write_renamed(path, bytes, false)
}

fn write_renamed(path: &Path, bytes: &[u8], durable: bool) -> std::io::Result<()> {
    let tmp = sibling(path, "tmp");
    let write = || -> std::io::Result<()> {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        if durable {
            f.sync_all()
        } else {
            f.flush()
        }
    };
    if let Err(e) = write() {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    fs::rename(&tmp, path).inspect_err(|_| {
        let _ = fs::remove_file(&tmp);
    })?;
    if durable {
        sync_dir(&parent_of(path))?;
    }
    Ok(())
}

/// `fsync` a directory: its entries (names created, renamed or removed in it) reach the
/// disk.
pub fn sync_dir(dir: &Path) -> std::io::Result<()> {
    fs::File::open(dir)?.sync_all()
}

/// `fsync` every file and directory under `dir`, the files first, then each directory
/// after its contents (symbolic links are not followed).
pub fn sync_tree(dir: &Path) -> std::io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        let kind = entry.file_type()?;
        if kind.is_dir() {
            sync_tree(&entry.path())?;
        } else if kind.is_file() {
            fs::File::open(entry.path())?.sync_all()?;
        }
    }
    sync_dir(dir)
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
        sync_tree(&self.tmp).map_err(|e| OutputError::io(&self.tmp, e))?;
        let parent = parent_of(&self.target);
        let synced = |target: PathBuf| {
            sync_dir(&parent)
                .map(|()| target)
                .map_err(|e| OutputError::io(&parent, e))
        };
        if fs::symlink_metadata(&self.target).is_err() {
            fs::rename(&self.tmp, &self.target).map_err(|e| OutputError::io(&self.target, e))?;
            self.committed = true;
            return synced(self.target.clone());
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
        synced(self.target.clone())
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
    fn the_temporary_names_follow_the_pattern_and_never_repeat() {
        let pid = std::process::id();
        let prefix = format!(".run.tmp-{pid}-");
        let name = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
        let a = sibling(Path::new("out/run"), "tmp");
        assert_eq!(a.parent(), Some(Path::new("out")));
        let nonce = name(&a).strip_prefix(&prefix).unwrap().to_string();
        assert!(
            nonce.len() == 8 && nonce.bytes().all(|b| b.is_ascii_hexdigit()),
            "{a:?}"
        );
        assert!(is_litter(&name(&a)));
        assert_eq!(suffix_pid(&format!("{pid}-{nonce}")), Some(pid));
        // An older eyeshell's `<pid>` alone is still litter; other suffixes are not.
        assert!(is_litter(".run.tmp-42") && is_litter(".run.old-42-00ff00ff"));
        for keep in [
            ".run.tmp-",
            ".run.tmp-x1",
            ".run.tmp-1-",
            ".run.tmp-1-zz",
            ".run.tmp--1",
        ] {
            assert!(!is_litter(keep), "{keep}");
        }
        // Many names from many threads of one process: all distinct.
        let names: std::collections::BTreeSet<PathBuf> = std::thread::scope(|s| {
            let hs: Vec<_> = (0..8)
                .map(|_| {
                    s.spawn(|| {
                        (0..500)
                            .map(|_| sibling(Path::new("run"), "tmp"))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            hs.into_iter().flat_map(|h| h.join().unwrap()).collect()
        });
        assert_eq!(names.len(), 4000);
        let dir = tempfile::tempdir().unwrap();
        let w = AtomicDir::create(&dir.path().join("run")).unwrap();
        assert!(name(w.path()).starts_with(&prefix), "{:?}", w.path());
    }

    #[test]
    fn a_killed_writers_litter_of_either_form_is_found_with_its_pid() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        for n in [
            ".out.tmp-999999998",
            ".out.tmp-999999997-0123abcd",
            ".out.tmp-x",
            ".other.tmp-5",
        ] {
            fs::create_dir(dir.path().join(n)).unwrap();
        }
        let mut found: Vec<u32> = siblings(&target, "tmp")
            .into_iter()
            .map(|(_, p)| p)
            .collect();
        found.sort();
        assert_eq!(found, [999999997, 999999998]);
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
