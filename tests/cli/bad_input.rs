//! Bad input to the binary: every case fails before any solve, with exit code 2, one line
//! `eyeshell: error: ...` naming the key, no panic, and no output directory left behind.
//! None of these need the solver.

use crate::support::*;

fn file_fails(scene: &str, needle: &str) {
    fails("solve", scene, &[], needle, "scene.toml: ");
}

fn set_fails(set: &str, needle: &str) {
    fails("solve", "", &[set], needle, &format!("--set {set}: "));
}

#[test]
fn unknown_key_and_section() {
    file_fails("[material]\nc = 100", "material.c");
    file_fails("[material]\nc = 100", "did you mean 'material.C'");
    file_fails("[materail]\nC = 100", "materail");
    file_fails("nodes = 11", "did you mean 'solver.nodes'");
    set_fails("pressure.dp=2", "'pressure.dP'");
    set_fails("bogus=2", "bogus");
}

#[test]
fn wrong_type() {
    file_fails("[material]\nC = \"stiff\"", "material.C");
    file_fails("[solver]\nnodes = 10.5", "solver.nodes");
    file_fails("[solver]\nscheme = \"rk4\"", "solver.scheme");
    file_fails("[solver]\npole_grading = \"yes\"", "solver.pole_grading");
    file_fails("material = 1", "material");
    set_fails("material.C=stiff", "material.C");
    set_fails("solver.linear=lapack", "solver.linear");
}

#[test]
fn non_positive_moduli_thickness_bending_radius() {
    for key in [
        "material.C",
        "material.H0",
        "material.bending",
        "geometry.R0",
        "cornea.C",
        "cornea.H",
        "cornea.R0",
    ] {
        for v in ["0", "-1"] {
            file_fails(&format!("{key} = {v}"), key);
            set_fails(&format!("{key}={v}"), key);
        }
    }
    file_fails("[material]\nC = -1", "material.C = -1 must be positive");
}

#[test]
fn negative_fibres_and_pressure() {
    file_fails("[fibres]\nD = -5", "fibres.D");
    file_fails("[pressure]\ndP = -1", "pressure.dP");
}

#[test]
fn pressure_beyond_the_corneal_limit() {
    file_fails("[pressure]\ndP = 17", "pressure.dP");
    file_fails("[pressure]\ndP = 17", "the largest admissible ΔP is 16.113");
    set_fails("pressure.dP=1e6", "cornea's limit");
    // The limit follows the cornea: a weak cornea cannot hold the default ΔP = 2.
    set_fails("cornea.C=5", "pressure.dP");
}

#[test]
fn too_few_nodes() {
    file_fails("[solver]\nnodes = 4", "solver.nodes");
    file_fails("[solver]\nnodes = -1", "solver.nodes");
    set_fails("solver.nodes=0", "between 5 and 1000000");
}

#[test]
fn epsilon_out_of_range() {
    file_fails("[solver]\nepsilon = 0", "solver.epsilon");
    file_fails("[solver]\nepsilon = -1e-3", "solver.epsilon");
    file_fails("[solver]\nepsilon = 25.2", "solver.epsilon");
    file_fails("[solver]\nepsilon = 25.2", "L = π·fraction·R0 = 25.132741");
    set_fails("solver.epsilon=100", "solver.epsilon");
}

#[test]
fn fraction_outside_the_unit_interval() {
    for v in ["0", "1", "1.2", "-0.5"] {
        file_fails(&format!("[geometry]\nfraction = {v}"), "geometry.fraction");
        set_fails(&format!("geometry.fraction={v}"), "geometry.fraction");
    }
}

#[test]
fn nan_and_inf_via_file_and_set() {
    for v in ["nan", "inf", "-inf"] {
        for key in [
            "pressure.dP",
            "material.C",
            "material.H0",
            "fibres.D",
            "solver.epsilon",
            "geometry.R0",
        ] {
            file_fails(&format!("{key} = {v}"), key);
            set_fails(
                &format!("{key}={v}"),
                &format!("{key} = {v} must be a finite number"),
            );
        }
    }
}

#[test]
fn newton_settings() {
    file_fails("[solver]\nnewton_tol = 0", "solver.newton_tol");
    file_fails("[solver]\nmax_newton = 0", "solver.max_newton");
}

#[test]
fn malformed_toml_and_overrides() {
    file_fails("[material\nC = 1", "invalid TOML at line 1");
    set_fails("pressure.dP", "key=value");
}

#[test]
fn missing_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let run = eyeshell_in(dir.path(), &["solve", "nope.toml", "--out", "out"]);
    assert_bad(&run, "nope.toml: cannot read the scene", "missing file");
    assert!(!dir.path().join("out").exists());
}

#[test]
fn at_points_are_checked_before_solving() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), "").unwrap();
    for (at, needle) in [
        ("1,abc", "\"abc\" is not a number"),
        ("0.0001", "Σ = 0.0001 is outside the shell [ε, L]"),
        ("1,26", "Σ = 26 is outside"),
        ("nan", "Σ = nan must be a finite number"),
        ("inf", "Σ = inf must be a finite number"),
        ("1,,2", "is not a number"),
    ] {
        let run = eyeshell_in(dir.path(), &["solve", "s.toml", "--out", "out", "--at", at]);
        assert_bad(&run, needle, at);
        assert!(run.stderr.contains("--at"), "{}", run.stderr);
        assert!(!dir.path().join("out").exists());
    }
    // ε and L follow the scene: Σ = 20 is beyond L for R0 = 5.
    let run = eyeshell_in(
        dir.path(),
        &[
            "solve",
            "s.toml",
            "--set",
            "geometry.R0=5",
            "--out",
            "out",
            "--at",
            "20",
        ],
    );
    assert_bad(&run, "Σ = 20 is outside", "at beyond L(R0 = 5)");
}

#[test]
fn a_foreign_output_directory_is_refused_and_untouched() {
    let dir = foreign_dir_is_refused("solve", "");
    std::fs::write(dir.path().join("file"), "x").unwrap();
    let run = eyeshell_in(dir.path(), &["solve", "s.toml", "--out", "file/inside/out"]);
    assert_bad(
        &run,
        "file/inside/out: a parent of the output path is not a directory",
        "parent is a file",
    );
    let run = eyeshell_in(dir.path(), &["solve", "s.toml", "--out", "file"]);
    assert_bad(&run, "refusing", "file as out");
}

#[test]
fn usage_errors_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needle) in [
        (&[][..], "missing subcommand"),
        (&["solve", "s.toml"][..], "--out"),
        (&["frobnicate"][..], "frobnicate"),
        (&["solve", "s.toml", "--out", "o", "--bogus"][..], "--bogus"),
        (&["check"][..], "SCENE.toml"),
    ] {
        let run = eyeshell_in(dir.path(), args);
        assert_bad(&run, needle, &format!("{args:?}"));
    }
}

#[test]
fn check_fails_like_solve() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), "[material]\nC = -1\n").unwrap();
    let run = eyeshell_in(dir.path(), &["check", "s.toml"]);
    assert_bad(&run, "s.toml: material.C = -1 must be positive", "check");
    let run = eyeshell_in(
        dir.path(),
        &[
            "check",
            "s.toml",
            "--set",
            "material.C=5",
            "--set",
            "solver.nodes=3",
        ],
    );
    assert_bad(
        &run,
        "--set solver.nodes=3: solver.nodes = 3 must lie between 5 and 1000000",
        "check --set",
    );
}
