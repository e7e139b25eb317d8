//! Which files and directories eyeshell may replace: only those it wrote.
//!
//! - **Directories.** Every output directory holds a marker, `.eyeshell`, that eyeshell
//!   alone writes: a small JSON naming what wrote it (`"written_by": "eyeshell 0.1.0"`), the
//!   kind of output (`solve`, `grow`, `sweep`, `study`, `figures`, `plot`, `export`) and the
//!   entries it put there. A target may be replaced only when it is absent, an empty
//!   directory, or a directory with that marker whose every entry eyeshell wrote (a listed
//!   entry, its own temporary litter, or a directory with a marker of its own, such as
//!   `plots/`). A file called summary.json proves nothing. Anything else is refused, and
//!   named: a user's file in an output directory is never deleted with it.
//! - **Kinds.** An output replaces only an earlier output of its own kind (a plot an
//!   earlier plot, an export an earlier export): never another run, a sweep or a fit's
//!   output, whatever eyeshell wrote.
//! - **Inputs.** Every writer names what its output is made from (the run an export or a
//!   plot reads, the scene, the fit's data), and the target may not be one of them, hold
//!   one, or lie inside one except as a nested output at the top of an eyeshell output
//!   (`RUN/plots`). Paths are compared by what they are, device and inode along their
//!   canonical ancestors, never by how they are spelled: `RUN/.`, `RUN/../RUN`, an absolute
//!   path, a symlinked parent or a bind mount all name the same directory.
//! - **Files** (`export --mat FILE`, `extremes --out FILE`): an existing file is replaced
//!   only when eyeshell wrote it (recognised by its own header) or with `--force`.
//!
//! Writers: [`OutputDir`] (solve, studies, exports: the directory appears whole, through
//! [`AtomicDir`]) and [`OwnedDir`] (grow, sweep, figures, plot: written in place, as the
//! results come). Both hold the target's lock ([`DirLock`]) while they write.

use std::fs;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::atomic::{is_litter, parent_of, remove_dead_temporaries, remove_litter, write_atomic};
use super::lock::DirLock;
use super::{AtomicDir, OutputError};

/// The marker of an eyeshell output directory.
pub const MARKER_FILE: &str = ".eyeshell";
/// What every marker's `written_by` starts with.
const SIGNATURE: &str = "eyeshell ";
/// A marker larger than this is not one of ours.
const MAX_MARKER_BYTES: u64 = 1 << 20;

/// The content of `.eyeshell`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// "eyeshell <version>".
    pub written_by: String,
    /// solve, grow, sweep, study, figures, plot or export.
    pub kind: String,
    /// The entries eyeshell wrote at the top of the directory.
    #[serde(default)]
    pub entries: Vec<String>,
}

impl Marker {
    /// A marker of this version of eyeshell for an output of `kind`.
    pub fn new(kind: &str) -> Marker {
        Marker {
            written_by: format!("{SIGNATURE}{}", env!("CARGO_PKG_VERSION")),
            kind: kind.to_string(),
            entries: Vec::new(),
        }
    }

    /// The marker of `dir`, if it has one eyeshell wrote (a regular file, not a symlink,
    /// of bounded size, that parses and carries the signature).
    pub fn read(dir: &Path) -> Option<Marker> {
        let path = dir.join(MARKER_FILE);
        let meta = fs::symlink_metadata(&path).ok()?;
        if !meta.is_file() || meta.len() > MAX_MARKER_BYTES {
            return None;
        }
        let marker: Marker = serde_json::from_slice(&fs::read(&path).ok()?).ok()?;
        marker.written_by.starts_with(SIGNATURE).then_some(marker)
    }

    /// Write the marker into `dir` (atomically).
    pub fn write(&self, dir: &Path) -> Result<(), OutputError> {
        let path = dir.join(MARKER_FILE);
        let text = serde_json::to_string_pretty(self).unwrap_or_default() + "\n";
        write_atomic(&path, text.as_bytes()).map_err(|e| OutputError::io(&path, e))
    }

    fn lists(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e == name)
    }
}

/// What is at an output path now.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    Absent,
    EmptyDir,
    /// An eyeshell output, all of whose entries eyeshell wrote.
    Ours(Marker),
}

/// The path as written, without `.` components (`prev/.` is `prev`), so that its file name
/// and parent are the directory's own.
pub fn normalise(target: &Path) -> PathBuf {
    target.components().collect()
}

/// May `target` be written as an output of `kind` made from `inputs`? Refuses files,
/// symlinks, directories that are not eyeshell outputs, outputs that hold somebody else's
/// files, outputs of another kind, and any target that is, holds or lies inside one of the
/// inputs ([`admit`]). Call it before a long computation, so that a refusal comes first;
/// the writers check again under the lock.
pub fn check_target(target: &Path, kind: &str, inputs: &[&Path]) -> Result<(), OutputError> {
    admit(&normalise(target), kind, inputs).map(|_| ())
}

/// What is at `target`, or why an output of `kind` made from `inputs` may not replace it:
/// [`inspect`], then the two rules every writer shares (see the module doc): only an
/// earlier output of the same kind is replaced, and never where an input is.
pub fn admit(target: &Path, kind: &str, inputs: &[&Path]) -> Result<Target, OutputError> {
    let found = inspect(target)?;
    if let Target::Ours(marker) = &found {
        if marker.kind != kind {
            return Err(OutputError::NotItsKind {
                path: target.to_path_buf(),
                found: marker.kind.clone(),
                wanted: kind.to_string(),
            });
        }
    }
    for input in inputs {
        clear_of(target, kind, input)?;
    }
    Ok(found)
}

/// A directory's identity: device and inode (following links), which no spelling of its
/// path changes.
type Identity = (u64, u64);

fn identity(path: &Path) -> Option<Identity> {
    fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// The identities of `path` and of every directory above it, from its canonical path (no
/// `.`, `..` or links left, so its lexical ancestors are its real ones).
fn lineage(path: &Path) -> Vec<Identity> {
    fs::canonicalize(path)
        .map(|c| c.ancestors().filter_map(identity).collect())
        .unwrap_or_default()
}

/// The nearest of `path` and its ancestors that exists (where a missing output's parents
/// will be created from).
fn existing_ancestor(path: &Path) -> PathBuf {
    path.ancestors()
        .find(|a| !a.as_os_str().is_empty() && fs::symlink_metadata(a).is_ok())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Refuse `target` if it is `input`, holds it, or lies inside it (an eyeshell output)
/// other than as a nested output directly in an eyeshell output (`RUN/plots`, `SWEEP/runs/a/plots`), which the
/// input's readers and its owner's checks pass over.
fn clear_of(target: &Path, kind: &str, input: &Path) -> Result<(), OutputError> {
    let Some(input_id) = identity(input) else {
        return Ok(()); // a missing input is its reader's error, said in its terms
    };
    let refuse = |how: &'static str| OutputError::Input {
        path: target.to_path_buf(),
        how,
        input: input.to_path_buf(),
        kind: kind.to_string(),
    };
    if let Some(target_id) = identity(target) {
        let above = lineage(input);
        if above.first() == Some(&target_id) {
            return Err(refuse("is"));
        }
        if above.contains(&target_id) {
            return Err(refuse("holds"));
        }
    }
    // Only an eyeshell output has insides to keep clear of; any other directory given as
    // an input is its reader's to refuse, in its terms ("not a run directory").
    if !fs::metadata(input).is_ok_and(|m| m.is_dir()) || Marker::read(input).is_none() {
        return Ok(());
    }
    let parent = parent_of(target);
    let inside = lineage(&existing_ancestor(&parent)).contains(&input_id);
    let nested = fs::metadata(&parent).is_ok_and(|m| m.is_dir()) && Marker::read(&parent).is_some();
    if inside && !nested {
        return Err(refuse("is inside"));
    }
    Ok(())
}

/// What is at `target`, or why it may not be written.
pub fn inspect(target: &Path) -> Result<Target, OutputError> {
    if target.file_name().is_none() {
        return Err(OutputError::NoName {
            path: target.to_path_buf(),
        });
    }
    let meta = match fs::symlink_metadata(target) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return absent(target),
        Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => {
            return Err(OutputError::NoParent {
                path: target.to_path_buf(),
            })
        }
        Err(e) => return Err(OutputError::io(target, e)),
    };
    if !meta.is_dir() {
        return Err(OutputError::Refused {
            path: target.to_path_buf(),
        });
    }
    let names = entry_names(target)?;
    match Marker::read(target) {
        None if names.is_empty() => Ok(Target::EmptyDir),
        None => Err(OutputError::Refused {
            path: target.to_path_buf(),
        }),
        Some(marker) => {
            if let Some(foreign) = names.iter().find(|n| !is_ours(target, &marker, n)) {
                return Err(OutputError::Foreign {
                    path: target.to_path_buf(),
                    entry: foreign.clone(),
                });
            }
            Ok(Target::Ours(marker))
        }
    }
}

/// A missing target: fine if every parent that exists is a directory, and the path does
/// not climb (`..`) out of a directory that does not exist yet (`RUN/new/../x`: where that
/// lands is decided only once `new` is created, after every check).
fn absent(target: &Path) -> Result<Target, OutputError> {
    let blocked = target
        .ancestors()
        .skip(1)
        .any(|a| !a.as_os_str().is_empty() && a.exists() && !a.is_dir());
    if blocked {
        return Err(OutputError::NoParent {
            path: target.to_path_buf(),
        });
    }
    let existing = existing_ancestor(target);
    let missing = target.strip_prefix(&existing).unwrap_or(target);
    if missing
        .components()
        .any(|c| c == std::path::Component::ParentDir)
    {
        return Err(OutputError::Unresolved {
            path: target.to_path_buf(),
        });
    }
    Ok(Target::Absent)
}

/// The entry names of a directory, sorted.
fn entry_names(dir: &Path) -> Result<Vec<String>, OutputError> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .map_err(|e| OutputError::io(dir, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    Ok(names)
}

/// Did eyeshell write `name` in `dir`? Listed, the marker, litter, or an output of its own.
fn is_ours(dir: &Path, marker: &Marker, name: &str) -> bool {
    name == MARKER_FILE
        || marker.lists(name)
        || is_litter(name)
        || fs::symlink_metadata(dir.join(name)).is_ok_and(|m| m.is_dir())
            && Marker::read(&dir.join(name)).is_some()
}

/// An output directory being written: files go into a temporary sibling of the target,
/// which [`OutputDir::commit`] renames into place with its marker. Dropping it uncommitted
/// removes it. The mechanism is [`AtomicDir`]'s; the policy (only an empty directory or
/// an eyeshell output is replaced) is this type's.
#[derive(Debug)]
pub struct OutputDir {
    dir: AtomicDir,
    kind: String,
    inputs: Vec<PathBuf>,
}

impl OutputDir {
    /// Check the target for an output of `kind` made from `inputs` ([`admit`]), lock it and
    /// create the temporary directory next to it.
    pub fn create(target: &Path, kind: &str, inputs: &[&Path]) -> Result<OutputDir, OutputError> {
        let target = normalise(target);
        admit(&target, kind, inputs)?;
        let dir = AtomicDir::create(&target)?;
        admit(&target, kind, inputs)?; // again, under the lock
        Ok(OutputDir {
            dir,
            kind: kind.to_string(),
            inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
        })
    }

    fn admit(&self) -> Result<Target, OutputError> {
        let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
        admit(self.dir.target(), &self.kind, &inputs)
    }

    /// The final path of the directory.
    pub fn target(&self) -> &Path {
        self.dir.target()
    }

    /// The path of `name` inside the temporary directory (where it must be written).
    pub fn file(&self, name: &str) -> PathBuf {
        self.dir.file(name)
    }

    /// Write `bytes` as the file `name` of the output (atomically; the whole directory is
    /// synced when it is committed).
    pub fn write_file(&self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        let path = self.file(name);
        super::atomic::write_atomic_unsynced(&path, bytes).map_err(|e| OutputError::io(&path, e))
    }

    /// Write the marker (listing what was written) and move the finished directory into
    /// place, replacing an empty directory or an eyeshell output (checked again).
    pub fn commit(self) -> Result<PathBuf, OutputError> {
        self.admit()?;
        let mut marker = Marker::new(&self.kind);
        marker.entries = entry_names(self.dir.path())?;
        marker.write(self.dir.path())?;
        self.dir.commit()
    }
}

/// An output directory written in place, as results come (grow, sweep, figures, plot),
/// locked while this value lives. New top-level entries are [`OwnedDir::claim`]ed in the
/// marker before they are written, so a run killed at any moment leaves a directory the
/// next run may replace.
#[derive(Debug)]
pub struct OwnedDir {
    path: PathBuf,
    marker: Marker,
    _lock: DirLock,
}

impl OwnedDir {
    /// Lock `target`, remove a previous eyeshell output of the same `kind` there (refusing
    /// anything else, and any target where one of `inputs` is: [`admit`]), and create it
    /// afresh with a marker listing `entries`.
    pub fn fresh(
        target: &Path,
        kind: &str,
        entries: &[&str],
        inputs: &[&Path],
    ) -> Result<OwnedDir, OutputError> {
        let (path, lock, found) = Self::lock(target, &|p| admit(p, kind, inputs))?;
        if let Target::Ours(_) = found {
            fs::remove_dir_all(&path).map_err(|e| OutputError::io(&path, e))?;
        }
        Self::start(path, lock, Marker::new(kind), entries)
    }

    /// Lock `target` and keep what is there if it is an eyeshell output of the same `kind`
    /// (a resumed sweep); an empty or missing target starts fresh. Another kind of output
    /// is refused.
    pub fn resume(target: &Path, kind: &str, entries: &[&str]) -> Result<OwnedDir, OutputError> {
        let (path, lock, found) = Self::lock(target, &inspect)?;
        match found {
            Target::Ours(marker) if marker.kind == kind => Self::start(path, lock, marker, entries),
            Target::Ours(marker) => Err(OutputError::OtherKind {
                path,
                found: marker.kind,
                wanted: kind.to_string(),
            }),
            _ => Self::start(path, lock, Marker::new(kind), entries),
        }
    }

    /// Check (`check`: [`admit`] or [`inspect`]), create the parents, lock, clean litter,
    /// check again under the lock.
    fn lock(
        target: &Path,
        check: &dyn Fn(&Path) -> Result<Target, OutputError>,
    ) -> Result<(PathBuf, DirLock, Target), OutputError> {
        let path = normalise(target);
        check(&path)?;
        let parent = parent_of(&path);
        fs::create_dir_all(&parent).map_err(|e| OutputError::io(&parent, e))?;
        let lock = DirLock::acquire(&path)?;
        remove_litter(&path)?;
        let found = check(&path)?;
        Ok((path, lock, found))
    }

    fn start(
        path: PathBuf,
        lock: DirLock,
        marker: Marker,
        entries: &[&str],
    ) -> Result<OwnedDir, OutputError> {
        let mut dir = OwnedDir {
            path,
            marker,
            _lock: lock,
        };
        dir.claim_all(entries)?;
        if fs::symlink_metadata(&dir.path).is_ok() {
            dir.marker.write(&dir.path)?;
            return Ok(dir);
        }
        // A new directory appears with its marker or not at all: made and marked under a
        // temporary name, then renamed into place. A process killed in between leaves only
        // litter that the next writer removes under the lock, never an unmarked directory
        // that every later run would have to refuse as somebody else's.
        let tmp = super::atomic::sibling(&dir.path, "tmp");
        let made = fs::create_dir(&tmp)
            .map_err(|e| OutputError::io(&tmp, e))
            .and_then(|()| dir.marker.write(&tmp))
            .and_then(|()| fs::rename(&tmp, &dir.path).map_err(|e| OutputError::io(&dir.path, e)));
        if let Err(e) = made {
            let _ = fs::remove_dir_all(&tmp);
            return Err(e);
        }
        let parent = parent_of(&dir.path);
        super::atomic::sync_dir(&parent).map_err(|e| OutputError::io(&parent, e))?;
        Ok(dir)
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Record `name` in the marker (if it is new) and return its path, to be written next.
    pub fn claim(&mut self, name: &str) -> Result<PathBuf, OutputError> {
        if self.claim_all(&[name])? {
            self.marker.write(&self.path)?;
        }
        Ok(self.path.join(name))
    }

    /// Add `names` to the marker's entries; true if any was new.
    fn claim_all(&mut self, names: &[&str]) -> Result<bool, OutputError> {
        let mut new = false;
        for &name in names {
            if name.is_empty() || name.contains('/') || name == MARKER_FILE {
                return Err(OutputError::io(
                    &self.path.join(name),
                    std::io::Error::other("not a plain entry name"),
                ));
            }
            if !self.marker.lists(name) {
                self.marker.entries.push(name.to_string());
                new = true;
            }
        }
        Ok(new)
    }
}

/// Add `names` to the marker of the eyeshell output `dir`, before they are written into it
/// (a sweep's run directory gains scene.toml and result.json after the run). The caller
/// must be the directory's only writer (a sweep holds its own directory's lock).
pub fn claim(dir: &Path, names: &[&str]) -> Result<(), OutputError> {
    let mut marker = Marker::read(dir).ok_or_else(|| OutputError::Refused {
        path: dir.to_path_buf(),
    })?;
    let before = marker.entries.len();
    for &name in names {
        if !marker.lists(name) {
            marker.entries.push(name.to_string());
        }
    }
    if marker.entries.len() > before {
        marker.write(dir)?;
    }
    Ok(())
}

/// May the file `path` be written? Absent: yes. A regular file: if `ours` recognises it as
/// eyeshell's, or with `force`, but never one that an eyeshell output's marker lists (a
/// run's fields.csv, a sweep's summary.json), even with `force`. Anything else (a directory, a symlink, a device) is
/// refused. Litter of killed writers beside it is removed.
pub fn check_file(
    path: &Path,
    force: bool,
    ours: impl Fn(&Path) -> bool,
) -> Result<(), OutputError> {
    let path = normalise(path);
    if path.file_name().is_none() {
        return Err(OutputError::NoName { path });
    }
    match fs::symlink_metadata(&path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => absent(&path).map(|_| ())?,
        Err(e) => return Err(OutputError::io(&path, e)),
        Ok(m) if m.is_file() => {
            // A file of an eyeshell output (its marker lists it) belongs to that output, a
            // run or a sweep, which it would leave broken: --force is for other files.
            let dir = parent_of(&path);
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            let listed = Marker::read(&dir).is_some_and(|m| m.lists(&name));
            if listed || name == MARKER_FILE {
                return Err(OutputError::PartOfOutput { path, dir });
            }
            if !force && !ours(&path) {
                return Err(OutputError::NotOurFile { path });
            }
        }
        Ok(_) => return Err(OutputError::NotAFile { path }),
    }
    remove_dead_temporaries(&path);
    Ok(())
}

/// The first `n` bytes of a file (fewer if it is shorter), for recognising a header.
pub fn head(path: &Path, n: usize) -> Vec<u8> {
    use std::io::Read;
    let mut bytes = Vec::new();
    if let Ok(f) = fs::File::open(path) {
        let _ = f.take(n as u64).read_to_end(&mut bytes);
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rundir::atomic::sibling;

    fn names(dir: &Path) -> Vec<String> {
        entry_names(dir).unwrap()
    }

    fn committed(target: &Path, files: &[&str]) {
        let out = OutputDir::create(target, "solve", &[]).unwrap();
        for f in files {
            fs::write(out.file(f), "x").unwrap();
        }
        out.commit().unwrap();
    }

    #[test]
    fn a_summary_json_alone_proves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("data");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("summary.json"), "{}").unwrap();
        fs::write(target.join("thesis.tex"), "keep").unwrap();
        let e = OutputDir::create(&target, "solve", &[]).unwrap_err();
        assert!(e.is_refusal() && e.to_string().contains(".eyeshell"), "{e}");
        let e = OwnedDir::fresh(&target, "grow", &[], &[]).unwrap_err();
        assert!(e.is_refusal(), "{e}");
        assert_eq!(names(&target), vec!["summary.json", "thesis.tex"]);
        // A forged marker that does not carry the signature, or is a symlink, is not ours.
        fs::write(
            target.join(MARKER_FILE),
            r#"{"written_by":"me","kind":"solve"}"#,
        )
        .unwrap();
        assert!(OutputDir::create(&target, "solve", &[]).is_err());
    }

    #[test]
    fn an_output_holding_a_users_file_is_not_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        committed(&target, &["fields.csv", "summary.json"]);
        let marker = Marker::read(&target).unwrap();
        assert_eq!(marker.kind, "solve");
        assert_eq!(marker.entries, vec!["fields.csv", "summary.json"]);
        assert!(marker.written_by.starts_with("eyeshell "));
        fs::write(target.join("notes.txt"), "mine").unwrap();
        let e = OutputDir::create(&target, "solve", &[]).unwrap_err();
        assert!(e.to_string().contains("\"notes.txt\""), "{e}");
        fs::remove_file(target.join("notes.txt")).unwrap();
        // A nested eyeshell output (plots/) and eyeshell litter are ours.
        committed(&target.join("plots"), &["a.png"]);
        fs::write(target.join(".summary.json.tmp-12345"), "").unwrap();
        committed(&target, &["fields.csv"]);
        assert_eq!(names(&target), vec![".eyeshell", "fields.csv"]);
    }

    #[test]
    fn in_place_outputs_claim_entries_before_writing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("grow");
        let mut owned = OwnedDir::fresh(&target, "grow", &["series.csv"], &[]).unwrap();
        let p = owned.claim("snapshots").unwrap();
        fs::create_dir(&p).unwrap();
        assert_eq!(
            Marker::read(&target).unwrap().entries,
            vec!["series.csv", "snapshots"]
        );
        assert!(owned.claim("../escape").is_err());
        // Locked while it lives: a second writer is refused, and told who holds it.
        let e = OwnedDir::fresh(&target, "grow", &[], &[]).unwrap_err();
        assert!(matches!(e, OutputError::Busy { .. }), "{e}");
        assert!(e.to_string().contains("another eyeshell process"), "{e}");
        drop(owned);
        // Killed at any moment, it is ours to replace; a resume of another kind is refused.
        let e = OwnedDir::resume(&target, "sweep", &[]).unwrap_err();
        assert!(
            e.to_string().contains("holds a grow output, not a sweep"),
            "{e}"
        );
        let again = OwnedDir::resume(&target, "grow", &["history.csv"]).unwrap();
        assert!(
            target.join("snapshots").is_dir(),
            "resume keeps what is there"
        );
        drop(again);
        OwnedDir::fresh(&target, "grow", &[], &[]).unwrap();
        assert_eq!(names(&target), vec![".eyeshell"]);
    }

    #[test]
    fn litter_of_killed_writers_is_cleaned_and_an_interrupted_commit_undone() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        committed(&target, &["fields.csv"]);
        // A killed commit: the previous output moved aside, the new one not yet in place.
        let aside = dir.path().join(".out.old-999999999");
        fs::rename(&target, &aside).unwrap();
        let tmp = dir.path().join(".out.tmp-999999998");
        fs::create_dir(&tmp).unwrap();
        fs::write(tmp.join("fields.csv"), "half").unwrap();
        let out = OutputDir::create(&target, "solve", &[]).unwrap();
        assert!(
            target.join("fields.csv").is_file(),
            "the old output is back"
        );
        assert!(!aside.exists() && !tmp.exists());
        fs::write(out.file("fields.csv"), "new").unwrap();
        out.commit().unwrap();
        assert_eq!(names(dir.path()), vec!["out"]);
    }

    #[test]
    fn awkward_paths() {
        let dir = tempfile::tempdir().unwrap();
        // `prev/.` is prev.
        let prev = dir.path().join("prev");
        committed(&prev, &["a"]);
        committed(&prev.join("."), &["b"]);
        assert_eq!(names(&prev), vec![".eyeshell", "b"]);
        assert!(OutputDir::create(&prev.join(".."), "solve", &[]).is_err());
        // A legal 250-byte name gets short hidden names beside it.
        let long = dir.path().join("n".repeat(250));
        committed(&long, &["a"]);
        assert!(long.join("a").is_file());
        assert!(sibling(&long, "tmp").file_name().unwrap().len() < 120);
        // A symlink to a directory is not followed.
        let elsewhere = dir.path().join("elsewhere");
        fs::create_dir(&elsewhere).unwrap();
        fs::write(elsewhere.join("keep"), "k").unwrap();
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&elsewhere, &link).unwrap();
        assert!(OutputDir::create(&link, "solve", &[])
            .unwrap_err()
            .is_refusal());
        assert!(OwnedDir::fresh(&link, "grow", &[], &[]).is_err());
        assert_eq!(names(&elsewhere), vec!["keep"]);
    }

    #[test]
    fn files_are_replaced_only_if_ours_or_forced() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.mat");
        let ours = |p: &Path| head(p, 4) == b"OURS";
        check_file(&path, false, ours).unwrap();
        fs::write(&path, "OURS and more").unwrap();
        check_file(&path, false, ours).unwrap();
        fs::write(&path, "theirs").unwrap();
        let e = check_file(&path, false, ours).unwrap_err();
        assert!(e.is_refusal() && e.to_string().contains("--force"), "{e}");
        check_file(&path, true, ours).unwrap();
        assert!(check_file(dir.path(), true, ours).is_err(), "a directory");
        // A file of an eyeshell output, and its marker: not even with force.
        let out = dir.path().join("out");
        committed(&out, &["fields.csv"]);
        for name in ["fields.csv", MARKER_FILE] {
            let e = check_file(&out.join(name), true, |_| true).unwrap_err();
            assert!(
                e.to_string().contains("is a file of the eyeshell output"),
                "{e}"
            );
        }
        // Temporary files of dead writers go.
        let dead = dir.path().join(".x.mat.tmp-999999999");
        fs::write(&dead, "").unwrap();
        let live = dir
            .path()
            .join(format!(".x.mat.tmp-{}", std::process::id()));
        fs::write(&live, "").unwrap();
        check_file(&path, true, ours).unwrap();
        assert!(!dead.exists() && live.exists());
    }
}
