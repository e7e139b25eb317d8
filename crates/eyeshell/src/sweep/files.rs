//! The files of a finished run, recorded in its result.json ([`RunFile`]: path, size,
//! FNV-1a 64 checksum) and checked again before `--resume` reuses the run, so that a run
//! whose files were deleted, cut short or edited since is run again instead of trusted.
//!
//! Nothing here follows a symbolic link: a link inside a run directory is neither recorded
//! nor read through (it makes the run's files fail the check). FNV-1a is no defence against
//! someone forging a file on purpose; it catches accidents, which is what resuming needs.

use std::fs;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use crate::rundir::summary::RunFile;

/// Files named so are not recorded: result.json (which holds the record) and hidden
/// names (the temporary siblings of atomic writes).
fn recorded(name: &str) -> bool {
    name != super::RESULT_FILE && !name.starts_with('.')
}

/// Every regular file below `dir` (result.json and hidden names aside), sorted by path.
pub fn record(dir: &Path) -> std::io::Result<Vec<RunFile>> {
    list(dir)?
        .into_iter()
        .map(|rel| {
            let (bytes, hash) = checksum(&dir.join(&rel))?;
            Ok(RunFile {
                path: rel,
                bytes,
                fnv1a64: format!("{hash:016x}"),
            })
        })
        .collect()
}

/// The paths, relative to `dir`, of the files [`record`] records, sorted.
pub fn list(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut paths = Vec::new();
    walk(dir, "", &mut paths)?;
    paths.sort();
    Ok(paths)
}

fn walk(dir: &Path, prefix: &str, out: &mut Vec<String>) -> std::io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if !recorded(&name) {
            continue;
        }
        let rel = format!("{prefix}{name}");
        // file_type() does not follow links: a link is neither a file nor a directory here.
        let kind = entry.file_type()?;
        if kind.is_dir() {
            walk(&entry.path(), &format!("{rel}/"), out)?;
        } else if kind.is_file() {
            out.push(rel);
        }
    }
    Ok(())
}

/// Why the files of the run in `dir` are not those `files` records (None: they are).
pub fn verify(dir: &Path, files: &[RunFile]) -> Option<String> {
    if files.is_empty() {
        return Some(format!(
            "its {} lists no files (an earlier eyeshell wrote it)",
            super::RESULT_FILE
        ));
    }
    files.iter().find_map(|f| verify_one(dir, f))
}

/// Why the run in `dir` names a file that `files` does not record (None: it names none):
/// the run's own marker (every entry eyeshell wrote there) and its summary.json (series,
/// history and snapshot files) say what the run is made of, and each must be recorded,
/// so that [`verify`] has checked it. A result.json that dropped a file the run still
/// names (the file deleted, or its record edited) is not to be trusted; nor is a run
/// without its marker, which is no longer an eyeshell output.
pub fn unrecorded(dir: &Path, files: &[RunFile]) -> Option<String> {
    use crate::rundir::{owner::Marker, Summary, MARKER_FILE};
    let listed: std::collections::HashSet<&str> = files.iter().map(|f| f.path.as_str()).collect();
    // A file by its path, a directory (snapshots/) by a file inside it.
    let covers = |name: &str| {
        listed.contains(name)
            || files.iter().any(|f| {
                f.path
                    .strip_prefix(name)
                    .is_some_and(|rest| rest.starts_with('/'))
            })
    };
    let Some(marker) = Marker::read(dir) else {
        return Some(format!("its {MARKER_FILE} marker is missing"));
    };
    let mut named: Vec<String> = marker.entries.into_iter().filter(|e| recorded(e)).collect();
    match Summary::read(dir) {
        Ok(Summary::Growth(g)) => {
            named.push(g.series_file);
            named.extend(g.history_file);
            named.extend(g.snapshots.into_iter().map(|s| s.file));
        }
        Ok(_) => {}
        Err(e) => return Some(e.to_string()),
    }
    named.into_iter().find(|name| !covers(name)).map(|name| {
        format!(
            "{} is named by the run but not recorded in its {}",
            crate::text::one_line(&name),
            super::RESULT_FILE
        )
    })
}

fn verify_one(dir: &Path, f: &RunFile) -> Option<String> {
    let shown = crate::text::one_line(&f.path);
    let path = match locate(dir, &f.path) {
        Ok(path) => path,
        Err(why) => return Some(format!("{shown} {why}")),
    };
    match checksum(&path) {
        Err(e) => Some(format!("{shown}: {e}")),
        Ok((bytes, _)) if bytes != f.bytes => Some(format!(
            "{shown} has {bytes} bytes, not the {} the run wrote",
            f.bytes
        )),
        Ok((_, hash)) if format!("{hash:016x}") != f.fnv1a64 => {
            Some(format!("{shown} was changed after the run wrote it"))
        }
        Ok(_) => None,
    }
}

/// `rel` (a recorded path) inside `dir`, if it names a regular file reached without
/// leaving `dir` and without a symbolic link on the way; otherwise why not.
fn locate(dir: &Path, rel: &str) -> Result<PathBuf, String> {
    let rel = Path::new(rel);
    let plain =
        rel.components().count() > 0 && rel.components().all(|c| matches!(c, Component::Normal(_)));
    if !plain {
        return Err("is not a path inside the run's directory".into());
    }
    let mut path = dir.to_path_buf();
    let mut parts = rel.components().peekable();
    while let Some(part) = parts.next() {
        path.push(part);
        let meta = match fs::symlink_metadata(&path) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err("is missing".into()),
            Err(e) => return Err(format!("cannot be read: {e}")),
        };
        if meta.file_type().is_symlink() {
            return Err("is reached through a symbolic link".into());
        }
        let wanted = match parts.peek() {
            None => meta.is_file(),
            Some(_) => meta.is_dir(),
        };
        if !wanted {
            return Err("is not a regular file".into());
        }
    }
    Ok(path)
}

/// The size of the file at `path` and its FNV-1a 64 hash, read in blocks.
fn checksum(path: &Path) -> std::io::Result<(u64, u64)> {
    let mut file = fs::File::open(path)?;
    let mut hash = crate::hash::Fnv1a64::default();
    let mut bytes = 0u64;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buf)?;
        if n == 0 {
            return Ok((bytes, hash.0));
        }
        hash.update(&buf[..n]);
        bytes += n as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_verifies_until_a_file_is_missing_resized_or_edited() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        fs::create_dir(dir.join("snapshots")).unwrap();
        fs::write(dir.join("fields.csv"), "a,b\n1,2\n").unwrap();
        fs::write(dir.join("snapshots/s0.csv"), "x\n").unwrap();
        fs::write(dir.join("result.json"), "{}").unwrap();
        fs::write(dir.join(".fields.csv.tmp-1"), "half").unwrap();
        let files = record(dir).unwrap();
        let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
        assert_eq!(paths, ["fields.csv", "snapshots/s0.csv"]);
        assert_eq!(files[0].bytes, 8);
        assert_eq!(files[0].fnv1a64.len(), 16);
        assert_eq!(verify(dir, &files), None);
        // The same size, one byte changed.
        fs::write(dir.join("fields.csv"), "a,b\n1,3\n").unwrap();
        let why = verify(dir, &files).unwrap();
        assert!(why.contains("fields.csv was changed"), "{why}");
        fs::write(dir.join("fields.csv"), "a,b\n1,2\n\n").unwrap();
        let why = verify(dir, &files).unwrap();
        assert!(why.contains("has 9 bytes, not the 8"), "{why}");
        fs::write(dir.join("fields.csv"), "a,b\n1,2\n").unwrap();
        fs::remove_file(dir.join("snapshots/s0.csv")).unwrap();
        assert_eq!(verify(dir, &files).unwrap(), "snapshots/s0.csv is missing");
        // No list at all: an older result.json.
        assert!(verify(dir, &[]).unwrap().contains("lists no files"));
    }

    #[test]
    fn paths_out_of_the_run_and_links_are_not_read() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        fs::create_dir(&dir).unwrap();
        fs::write(tmp.path().join("outside"), "x").unwrap();
        let bad = |path: &str| RunFile {
            path: path.into(),
            bytes: 1,
            fnv1a64: format!("{:016x}", crate::hash::fnv1a64(b"x")),
        };
        for path in ["../outside", "/etc/hostname", "", ".", "a/../../outside"] {
            let why = verify(&dir, &[bad(path)]).unwrap();
            assert!(
                why.ends_with("is not a path inside the run's directory"),
                "{why}"
            );
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(tmp.path().join("outside"), dir.join("link")).unwrap();
            std::os::unix::fs::symlink(tmp.path(), dir.join("up")).unwrap();
            let why = verify(&dir, &[bad("link")]).unwrap();
            assert_eq!(why, "link is reached through a symbolic link");
            let why = verify(&dir, &[bad("up/outside")]).unwrap();
            assert_eq!(why, "up/outside is reached through a symbolic link");
            // Links are not recorded either.
            assert!(record(&dir).unwrap().is_empty());
        }
    }
}
