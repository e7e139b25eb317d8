//! An output never deletes what it was made from: every spelling of a run, a sweep or a
//! fit's output as the destination of `export`, `plot`, `fit`, `solve`, `grow` or `sweep`
//! (relative, absolute, `.`, `..`, `RUN/../RUN`, through a symlinked parent, a run inside a
//! sweep, the sweep holding the input, a folder inside the run) is refused with one line and
//! exit 2, and every file under the test's directory is left as it was. An output replaces
//! only an earlier output of its own kind (`plot --help`'s promise), never another run, a
//! sweep or a fit's output.

use std::path::Path;

use crate::support::*;

/// A run, a growth run, a sweep of two growth runs and a fit's output under `root`:
/// `solve`, `grow`, `sweep` (runs `a` and `b`) and `fit`.
fn outputs(root: &Path) {
    small_runs(root);
    std::fs::write(
        root.join("s.toml"),
        format!(
            "{}[[sweep.runs]]\nname = \"a\"\n\"growth.Gamma\" = 4\n[[sweep.runs]]\nname = \"b\"\n\"growth.Gamma\" = 8\n",
            crate::shards::SMALL
        ),
    )
    .unwrap();
    succeeded(
        &eyeshell_in(root, &["sweep", "s.toml", "--out", "sweep", "-q"]),
        "the sweep",
    );
    let fit = eyeshell(&[
        "fit",
        "scenes/const.toml",
        "--set",
        "solver.nodes=21",
        "--set",
        "solver.rtol=1e-3",
        "--data",
        "examples/fit/const_synthetic.csv",
        "--fit",
        "growth.Gamma",
        "--out",
        s(&root.join("fit")),
        "-q",
    ]);
    succeeded(&fit, "the fit");
    std::os::unix::fs::symlink(root, root.join("here")).unwrap();
    for name in ["grow", "sweep"] {
        std::os::unix::fs::symlink(root.join(name), root.join(format!("{name}-link"))).unwrap();
    }
}

/// `eyeshell ARGS` in `cwd` is refused naming `needle`, and nothing under `root` changed.
fn intact(root: &Path, cwd: &Path, args: &[&str], needle: &str) {
    let before = World::of(root);
    let r = eyeshell_in(cwd, args);
    refused(&r, needle, &format!("{args:?} in {}", cwd.display()));
    assert!(r.stdout.is_empty(), "{args:?}: {}", r.stdout);
    assert!(World::of(root) == before, "{args:?} changed the files");
}

/// The spellings of `name` (a directory under `root`) seen from `root`, and from inside it.
fn spellings(root: &Path, name: &str) -> Vec<(std::path::PathBuf, String)> {
    let abs = root.join(name);
    vec![
        (root.to_path_buf(), name.to_string()),
        (root.to_path_buf(), format!("./{name}")),
        (root.to_path_buf(), format!("{name}/.")),
        (root.to_path_buf(), format!("{name}/../{name}")),
        (root.to_path_buf(), format!("{name}/snapshots/../../{name}")),
        (root.to_path_buf(), format!("here/{name}")),
        (root.to_path_buf(), format!("{name}-link")),
        (root.to_path_buf(), format!("here/{name}-link/.")),
        (root.to_path_buf(), format!("here/./{name}/")),
        (root.to_path_buf(), s(&abs).to_string()),
        (root.join("sweep/runs"), format!("../../{name}")),
        (abs.clone(), format!("../{name}")),
        (abs.clone(), format!("{}/{name}/../{name}", s(root))),
    ]
}

#[test]
fn an_export_never_replaces_the_run_it_reads_nor_what_holds_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    outputs(root);
    for flag in ["--mat", "--npz"] {
        // The run itself, however it is spelled.
        for (cwd, dest) in spellings(root, "grow") {
            let run = s(&root.join("grow")).to_string();
            intact(root, &cwd, &["export", &run, flag, &dest], "grow");
        }
        // `.` and `..` from inside the run: no name to write to, nothing touched.
        for dest in [".", "..", "snapshots/..", "./"] {
            intact(
                root,
                &root.join("grow"),
                &["export", ".", flag, dest],
                "no file name",
            );
        }
        // A folder inside the run, and a run inside the sweep exported into the sweep.
        intact(
            root,
            root,
            &["export", "grow", flag, "grow/snapshots/out"],
            "is inside grow, which this export is made from",
        );
        intact(
            root,
            root,
            &["export", "grow", flag, "grow/snapshots"],
            "not an eyeshell output",
        );
        for dest in ["sweep", "sweep/.", "here/sweep", "sweep/runs/../../sweep"] {
            intact(
                root,
                root,
                &["export", "sweep/runs/a", flag, dest],
                "holds a sweep output",
            );
        }
        intact(
            root,
            &root.join("sweep/runs/a"),
            &["export", ".", flag, "../b"],
            "holds a grow output",
        );
        intact(
            root,
            root,
            &["export", "sweep/runs/a", flag, "sweep/runs"],
            "not an eyeshell output",
        );
        // Another run, the fit's output: not an export's to replace.
        for other in ["solve", "fit", "sweep/runs/b"] {
            intact(
                root,
                root,
                &["export", "grow", flag, other],
                "refusing to replace it with an export output",
            );
        }
    }
    // A one-file export (an elastic solve) onto a file of another output, even forced.
    for dest in [
        "grow/series.csv",
        "sweep/summary.json",
        "here/sweep/runs/a/result.json",
        "fit/.eyeshell",
        "solve/fields.csv",
    ] {
        for flag in ["--mat", "--npz"] {
            intact(
                root,
                root,
                &["export", "solve", flag, dest, "--force"],
                "refusing to overwrite it, even with --force",
            );
        }
    }
    // What may be written: a new directory, then the same again, and a nested one at the
    // top of the run (as plots/ is).
    for dest in ["exported", "exported", "grow/npz", "sweep/runs/a/npz"] {
        let from = if dest.starts_with("sweep") {
            "sweep/runs/a"
        } else {
            "grow"
        };
        succeeded(
            &eyeshell_in(root, &["export", from, "--npz", dest, "-q"]),
            dest,
        );
    }
    assert!(root.join("grow/summary.json").is_file());
    assert!(root.join("grow/npz/.eyeshell").is_file());
}

#[test]
fn a_plot_replaces_only_an_earlier_plot_or_an_empty_directory() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    outputs(root);
    for (cwd, dest) in spellings(root, "grow") {
        let run = s(&root.join("grow")).to_string();
        intact(root, &cwd, &["plot", &run, "--out", &dest], "grow");
    }
    for (cwd, dest) in spellings(root, "sweep") {
        let run = s(&root.join("sweep/runs/a")).to_string();
        intact(root, &cwd, &["plot", &run, "--out", &dest], "sweep");
    }
    // A sweep plotted into one of its runs, or into runs/.
    intact(
        root,
        root,
        &["plot", "sweep", "--out", "sweep/runs/a"],
        "holds a grow output",
    );
    intact(
        root,
        root,
        &["plot", "sweep", "--out", "sweep/runs"],
        "not an eyeshell output",
    );
    intact(
        root,
        root,
        &["plot", "sweep", "--out", "sweep/runs/z"],
        "is inside sweep, which this plot is made from",
    );
    // Another growth run, a solve, a sweep, a fit's output: eyeshell's, but not plots.
    for (other, kind) in [
        ("solve", "a solve"),
        ("sweep/runs/b", "a grow"),
        ("sweep", "a sweep"),
        ("fit", "a fit"),
    ] {
        intact(
            root,
            root,
            &["plot", "grow", "--out", other],
            &format!("holds {kind} output; refusing to replace it with a plot output"),
        );
    }
    // An earlier plot, an empty directory and the default DIR/plots are replaced.
    std::fs::create_dir(root.join("empty")).unwrap();
    for dest in ["pictures", "pictures", "empty", "grow/plots", "sweep/plots"] {
        let from = if dest.starts_with("sweep") {
            "sweep"
        } else {
            "grow"
        };
        succeeded(
            &eyeshell_in(root, &["plot", from, "--out", dest, "-q"]),
            dest,
        );
    }
    succeeded(&eyeshell_in(root, &["plot", "grow", "-q"]), "default");
    succeeded(
        &eyeshell_in(root, &["plot", "sweep/runs/a", "-q"]),
        "default in a run of a sweep",
    );
    assert!(root.join("empty/.eyeshell").is_file());
    assert!(root.join("grow/series.csv").is_file());
    // ... but not one plot made from another's: a plot output holding the run drawn.
    let outer = root.join("pictures");
    std::fs::rename(root.join("solve"), outer.join("solve")).unwrap();
    intact(
        root,
        root,
        &["plot", "pictures/solve", "--out", "pictures"],
        "holds pictures/solve, which this plot is made from",
    );
}

#[test]
fn runs_sweeps_and_fits_never_replace_the_directory_of_their_scene_or_data() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    outputs(root);
    // The scene of a sweep's run, run again into the run, or into the sweep.
    intact(
        root,
        root,
        &["grow", "sweep/runs/a/scene.toml", "--out", "sweep/runs/a"],
        "holds sweep/runs/a/scene.toml, which this grow is made from",
    );
    intact(
        root,
        root,
        &["grow", "sweep/runs/a/scene.toml", "--out", "sweep/runs/a/."],
        "holds sweep/runs/a/scene.toml",
    );
    intact(
        root,
        root,
        &["sweep", "sweep/runs/a/scene.toml", "--out", "here/sweep"],
        "holds sweep/runs/a/scene.toml, which this sweep is made from",
    );
    intact(
        root,
        root,
        &["solve", "sweep/runs/a/scene.toml", "--out", "sweep/runs/b"],
        "holds a grow output; refusing to replace it with a solve output",
    );
    // The fitted scene, fitted again into its own directory.
    intact(
        root,
        root,
        &[
            "fit",
            "fit/scene.toml",
            "--data",
            s(&repo().join("examples/fit/const_synthetic.csv")),
            "--fit",
            "growth.Gamma",
            "--out",
            "here/fit",
        ],
        "here/fit: holds fit/scene.toml, which this fit is made from",
    );
    // A growth run into another kind of output.
    intact(
        root,
        root,
        &["grow", "sweep/runs/b/scene.toml", "--out", "fit"],
        "holds a fit output; refusing to replace it with a grow output",
    );
}
