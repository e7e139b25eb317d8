//! `eyeshell keys` and `eyeshell check` (no solver needed).

use crate::support::*;

use eyeshell::scene::{Scene, KEYS};

#[test]
fn keys_lists_every_key_with_type_default_and_doc() {
    let Run {
        code,
        stdout: out,
        stderr: err,
    } = eyeshell_in(repo(), &["keys"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.is_empty());
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines[0].starts_with("KEY") && lines[0].contains("DEFAULT"));
    assert_eq!(lines.len(), KEYS.len() + 1);
    for (line, key) in lines[1..].iter().zip(KEYS) {
        let fields: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(fields[0], key.key);
        assert!(line.contains(&key.type_name()), "{line}");
        assert!(line.contains(&key.default_value().to_string()), "{line}");
        assert!(line.contains(key.doc), "{line}");
    }
    for key in [
        "pressure.dP",
        "material.C",
        "material.bending",
        "material.thickness",
        "material.H0",
        "fibres.D",
        "cornea.C",
        "cornea.H",
        "cornea.R0",
        "geometry.R0",
        "geometry.fraction",
        "solver.nodes",
        "solver.epsilon",
        "solver.scheme",
        "solver.linear",
        "solver.newton_tol",
        "solver.max_newton",
        "solver.pole_grading",
    ] {
        assert!(
            lines
                .iter()
                .any(|l| l.split_whitespace().next() == Some(key)),
            "{key} missing"
        );
    }
}

#[test]
fn check_prints_the_effective_scene_as_toml() {
    let Run {
        code,
        stdout: out,
        stderr: err,
    } = eyeshell_in(
        repo(),
        &[
            "check",
            "scenes/fibres-nonuniform.toml",
            "--set",
            "pressure.dP=3",
            "--set",
            "solver.scheme=trapezoid",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(err.is_empty(), "{err}");
    assert!(
        out.starts_with("# scenes/fibres-nonuniform.toml: valid scene 'fibres-nonuniform'"),
        "{out}"
    );
    assert!(out.contains("pressure.dP = 3.0\n"), "{out}");
    assert!(out.contains("fibres.D = 200.0\n"), "{out}");
    assert!(
        out.contains("material.thickness = \"nonuniform\"\n"),
        "{out}"
    );
    assert!(out.contains("solver.scheme = \"trapezoid\"\n"), "{out}");
    // Every parameter is printed, and the listing reads back to the same scene.
    let back = Scene::from_toml_str(&out, "check output", &[]).unwrap();
    let direct = Scene::from_file(
        &repo().join("scenes/fibres-nonuniform.toml"),
        &[
            "pressure.dP=3".to_string(),
            "solver.scheme=trapezoid".to_string(),
        ],
    )
    .unwrap();
    assert_eq!(back.params, direct.params);
    assert_eq!(back.solver, direct.solver);
}

#[test]
fn shipped_scenes_check() {
    for s in [
        "scenes/default.toml",
        "scenes/fibres-nonuniform.toml",
        "scenes/exact-sphere.toml",
    ] {
        let Run {
            code,
            stdout: out,
            stderr: err,
        } = eyeshell_in(repo(), &["check", s]);
        assert_eq!(code, Some(0), "{s}: {err}");
        assert!(out.contains("valid scene"), "{out}");
    }
}

#[test]
fn help_and_version_succeed() {
    let Run {
        code, stdout: out, ..
    } = eyeshell_in(repo(), &["--help"]);
    assert_eq!(code, Some(0));
    for sub in ["solve", "check", "keys"] {
        assert!(out.contains(sub), "{out}");
    }
    let Run {
        code, stdout: out, ..
    } = eyeshell_in(repo(), &["solve", "--help"]);
    assert_eq!(code, Some(0));
    assert!(
        out.contains("--set")
            && out.contains("--at")
            && out.contains("--out")
            && out.contains("--quiet")
    );
    let Run {
        code, stdout: out, ..
    } = eyeshell_in(repo(), &["--version"]);
    assert_eq!(code, Some(0));
    assert!(out.starts_with("eyeshell "));
}

/// A scene name carrying a line break and terminal escape sequences is shown escaped by
/// `check`, `solve` and in error lines: nothing reaches the terminal raw, `check`'s output
/// still reads back as the same scene, and an error stays one line (TESTING.md, family 7).
#[test]
fn hostile_names_are_printed_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("hostile.toml");
    let name = "eye\n# injected = 1\u{1b}[31m\u{7}";
    let text = format!(
        "name = {}\n[solver]\nnodes = 21\n",
        toml::Value::String(name.into())
    );
    std::fs::write(&scene, &text).unwrap();
    let check = ok(&["check", s(&scene)]);
    for stream in [&check.stdout, &check.stderr] {
        assert!(
            !stream.contains('\u{1b}') && !stream.contains('\u{7}'),
            "{stream:?}"
        );
    }
    assert!(
        check.stdout.contains(r"eye\n# injected = 1\u{1b}[31m\u{7}"),
        "{}",
        check.stdout
    );
    let back = Scene::from_toml_str(&check.stdout, "check output", &[]).unwrap();
    assert_eq!(back.name.as_deref(), Some(name));

    let out = dir.path().join("run");
    let solve = ok(&["solve", s(&scene), "--out", s(&out)]);
    assert!(!solve.stdout.contains('\u{1b}'), "{:?}", solve.stdout);
    let first = solve.stdout.lines().next().unwrap();
    assert!(
        first.contains(r"(eye\n# injected = 1\u{1b}[31m\u{7})"),
        "{first}"
    );

    // An error quoting the text keeps to one line and shows the escape.
    let bad = eyeshell(&[
        "solve",
        s(&scene),
        "--set",
        "solver.scheme=\u{1b}[2Jx",
        "--out",
        s(&out),
    ]);
    assert_eq!(bad.code, Some(2));
    assert_eq!(bad.stderr.lines().count(), 1, "{:?}", bad.stderr);
    assert!(!bad.stderr.contains('\u{1b}'), "{:?}", bad.stderr);
}

/// An `--out` holding a line break is printed escaped in every summary that names it
/// (solve, grow, a sweep, a shard and its merge), so that a path cannot forge a line of
/// the report.
#[test]
fn an_out_path_with_a_line_break_cannot_forge_a_report_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = "[solver]\nnodes = 21\n[growth]\nt_end = 0.05\n[output]\ntimes = [0.05]\n";
    std::fs::write(d.join("g.toml"), scene).unwrap();
    std::fs::write(d.join("e.toml"), "[solver]\nnodes = 21\n").unwrap();
    std::fs::write(
        d.join("s.toml"),
        "[solver]\nnodes = 21\n[sweep.grid]\n\"pressure.dP\" = [1.5, 2.0]\n",
    )
    .unwrap();
    let forged = "  output          /etc/passwd";
    let outs: Vec<String> = ["a", "b", "c", "d"]
        .iter()
        .map(|k| format!("{k}\n{forged}"))
        .collect();
    let cases: Vec<Vec<&str>> = vec![
        vec!["solve", "e.toml", "--out", &outs[0]],
        vec!["grow", "g.toml", "--out", &outs[1], "-q"],
        vec!["grow", "g.toml", "--out", &outs[1]],
        vec!["sweep", "s.toml", "--out", &outs[2]],
        vec!["sweep", "s.toml", "--out", &outs[3], "--shard", "1/1"],
        vec!["sweep", "merge", &outs[3]],
    ];
    for args in cases {
        let run = eyeshell_in(d, &args);
        succeeded(&run, &args.join(" "));
        assert!(
            !run.stdout.lines().any(|l| l == forged) && !run.stderr.lines().any(|l| l == forged),
            "{args:?}: {}",
            run.stdout
        );
        if !args.contains(&"-q") {
            assert!(
                run.stdout.contains("\\n  output"),
                "{args:?}: {}",
                run.stdout
            );
        }
    }
}
