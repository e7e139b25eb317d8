//! What eyeshell wrote it can always rerun, resume, merge and read back: every kind of
//! output written, then written again into its own `--out` (and, for sweeps, resumed,
//! merged again and read by `sweep status`), and after each step every eyeshell directory
//! in it lists each of its entries in its marker (`rundir::owner::inspect`).

use std::path::Path;

use eyeshell::rundir::owner::{inspect, Marker, Target};

use crate::support::*;

/// The exact sphere of docs/MODEL.md §7 on 21 nodes: milliseconds a run.
const SPHERE: &str = "name = \"sphere\"\n[pressure]\ndP = 2.0\n[material]\nC = 100.0\nbending = 18.0\nthickness = \"uniform\"\nH0 = 0.65\n[fibres]\nD = 0.0\n[cornea]\nC = 100.0\nH = 0.65\nR0 = 10.0\n[geometry]\nR0 = 10.0\nfraction = 0.8\n[solver]\nnodes = 21\n";

/// A small growth scene (N = 21, CVODE rtol 1e-3, to t = 0.1).
const GROWING: &str = "name = \"small\"\n[fibres]\nD = 0.0\n[growth]\neta0 = 70.0\nt_end = 0.1\n[solver]\nnodes = 21\nrtol = 1e-3\n[output]\ntimes = [0.05, 0.1]\nhistory_points = 5\n";

/// Every directory under `dir` (itself included) that carries a marker lists each of its
/// entries: `inspect` finds nothing that eyeshell did not write.
fn all_listed(dir: &Path, what: &str) {
    assert!(
        Marker::read(dir).is_some(),
        "{what}: {} has no marker",
        dir.display()
    );
    match inspect(dir) {
        Ok(Target::Ours(_)) => {}
        other => panic!("{what}: {}: {other:?}", dir.display()),
    }
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() && Marker::read(&path).is_some() {
            all_listed(&path, what);
        }
    }
}

/// `eyeshell ARGS` in `dir` succeeds and leaves `out` whole.
fn again(dir: &Path, args: &[&str], out: &str, what: &str) -> Run {
    let run = eyeshell_in(dir, args);
    succeeded(&run, what);
    all_listed(&dir.join(out), what);
    run
}

#[test]
fn every_output_can_be_written_again_resumed_merged_and_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cohort = |design: &str, eyes: usize, per_run: &str| {
        format!("{SPHERE}[sweep.sample]\neyes = {eyes}\ndesign = \"{design}\"\nseed = 4\nper_run = \"{per_run}\"\n[sweep.sample.keys]\n\"pressure.dP\" = {{ dist = \"uniform\", low = 1.5, high = 2.5 }}\n")
    };
    std::fs::write(d.join("sphere.toml"), SPHERE).unwrap();
    std::fs::write(d.join("grow.toml"), GROWING).unwrap();
    std::fs::write(
        d.join("grid.toml"),
        format!("{SPHERE}[sweep.grid]\n\"pressure.dP\" = [1.5, 2.0]\n"),
    )
    .unwrap();
    std::fs::write(d.join("dirs.toml"), cohort("random", 6, "directory")).unwrap();
    std::fs::write(d.join("table.toml"), cohort("random", 6, "table")).unwrap();
    std::fs::write(d.join("sobol.toml"), cohort("saltelli", 32, "directory")).unwrap();
    std::fs::write(d.join("grow_cohort.toml"), {
        let mut t = GROWING.to_string();
        t.push_str("[sweep.sample]\neyes = 3\nseed = 2\nper_run = \"table\"\n[sweep.sample.keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 60.0, high = 80.0 }\n");
        t
    })
    .unwrap();

    // Single runs, and what is drawn or exported from them.
    for _ in 0..2 {
        again(
            d,
            &["solve", "sphere.toml", "--out", "solve", "-q"],
            "solve",
            "solve",
        );
        again(
            d,
            &["grow", "grow.toml", "--out", "grow", "-q"],
            "grow",
            "grow",
        );
        again(d, &["plot", "grow", "--out", "plot", "-q"], "plot", "plot");
        again(
            d,
            &["export", "grow", "--npz", "grow.npz", "-q"],
            "grow",
            "export",
        );
    }

    // Sweeps: written twice, resumed, read by status.
    for (scene, out) in [
        ("grid.toml", "grid"),
        ("dirs.toml", "dirs"),
        ("table.toml", "table"),
        ("sobol.toml", "sobol"),
        ("grow_cohort.toml", "grow_cohort"),
    ] {
        let what = format!("sweep {scene}");
        for _ in 0..2 {
            again(d, &["sweep", scene, "--out", out, "--quiet"], out, &what);
        }
        let resumed = again(d, &["sweep", scene, "--out", out, "--resume"], out, &what);
        assert!(
            resumed.stdout.contains("reused"),
            "{what}: {}",
            resumed.stdout
        );
        if scene != "grid.toml" {
            for f in ["population.json", "population.csv", "population.png"] {
                assert!(d.join(out).join(f).is_file(), "{what}: {f}");
            }
        }
    }
    assert!(d.join("sobol/sobol.csv").is_file());

    // A sharded cohort: merged, merged again, read by status, resumed, written again.
    for shard in ["1/2", "2/2"] {
        again(
            d,
            &[
                "sweep",
                "dirs.toml",
                "--out",
                "sharded",
                "--shard",
                shard,
                "--quiet",
            ],
            "sharded",
            shard,
        );
    }
    for what in ["merge", "merge again"] {
        again(d, &["sweep", "merge", "sharded"], "sharded", what);
        succeeded(&eyeshell_in(d, &["sweep", "status", "sharded"]), what);
    }
    again(
        d,
        &[
            "sweep",
            "dirs.toml",
            "--out",
            "sharded",
            "--resume",
            "--quiet",
        ],
        "sharded",
        "resume after merge",
    );
    again(
        d,
        &["sweep", "dirs.toml", "--out", "sharded", "--quiet"],
        "sharded",
        "rerun after merge",
    );
}
