//! Hostile files and values (issue 13): each case asserts the exit code, one line of
//! stderr with no panic text, and that nothing was written or lost. The families this
//! module covers so far: broken run files (6) and sweeps that point outside themselves
//! (5, 6). Finite but absurd values (1) are in `crates/eyeshell/src/scene/tests.rs`, the
//! mesh and solver tests; names with control characters (7) in `keys_check.rs`; foreign
//! .mat/.npz files in `readers.rs` and `fuzz_readers.rs`.

use crate::support::*;

/// stderr is one line, an eyeshell error, with no panic text.
fn one_clean_line(r: &Run, what: &str) {
    assert_eq!(r.stderr.lines().count(), 1, "{what}: {:?}", r.stderr);
    assert!(
        r.stderr.starts_with("eyeshell: error: "),
        "{what}: {}",
        r.stderr
    );
    assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
}

/// A fields.csv that lost a column is refused by export (it used to write a .mat with a
/// short `y` and an .npz with a missing row, as if nothing were wrong).
#[test]
fn a_run_missing_a_column_is_not_exported() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, _) = small_runs(dir.path());
    let fields = solve.join("fields.csv");
    let text = std::fs::read_to_string(&fields).unwrap();
    let cut: String = text
        .lines()
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(j, _)| *j != 2)
                .map(|(_, c)| c)
                .collect::<Vec<_>>()
                .join(",")
        })
        .map(|l| l + "\n")
        .collect();
    std::fs::write(&fields, cut).unwrap();
    for format in ["--mat", "--npz"] {
        let target = dir.path().join(format!("x{format}"));
        let r = eyeshell(&["export", s(&solve), format, s(&target)]);
        assert_eq!(r.code, Some(2), "{format}: {}", r.stderr);
        one_clean_line(&r, format);
        assert!(r.stderr.contains("no column \"kappa\""), "{}", r.stderr);
        assert!(!target.exists(), "{format}: nothing written");
    }
}

/// A sweep's summary.json whose run names the sweep itself (or a path out of it) is
/// refused by plot, which used to recurse until the stack overflowed.
#[test]
fn a_sweep_run_pointing_outside_the_sweep_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        "[solver]\nnodes = 21\n[sweep.grid]\n\"fibres.D\" = [0, 100]\n",
    )
    .unwrap();
    let sweep = dir.path().join("sweep");
    let r = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "sweep", "-q"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let summary = sweep.join("summary.json");
    let original = std::fs::read_to_string(&summary).unwrap();
    for bad in [".", "..", "../sweep", "/tmp", ""] {
        let planted = original.replacen("\"runs/D=0\"", &format!("{:?}", bad), 1);
        assert_ne!(planted, original, "the run's dir is in summary.json");
        std::fs::write(&summary, planted).unwrap();
        let plots = dir.path().join("plots");
        let r = eyeshell(&["plot", s(&sweep), "--out", s(&plots)]);
        assert_eq!(r.code, Some(2), "{bad:?}: {}", r.stderr);
        one_clean_line(&r, bad);
        assert!(
            r.stderr.contains("points outside the sweep"),
            "{}",
            r.stderr
        );
    }
    std::fs::write(&summary, original).unwrap();
    let plots = dir.path().join("plots");
    assert_eq!(
        eyeshell(&["plot", s(&sweep), "--out", s(&plots), "-q"]).code,
        Some(0)
    );
}
