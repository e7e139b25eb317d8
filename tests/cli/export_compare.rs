//! `eyeshell compare`: accepts a run against its own exports and against a copy of itself,
//! detects one value perturbed by 1e-6 (in a .mat file, a growth snapshot and a run's CSV),
//! interpolates to the reference's points, and refuses bad input with exit 2.

use crate::support::*;
use eyeshell::interop::mat::{self, MatValue};

fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.path().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

fn perturb(v: &mut MatValue, index: usize, by: f64) {
    match v {
        MatValue::Double { data, .. } => data[index] += by,
        _ => panic!("not an array"),
    }
}

#[test]
fn compare_accepts_the_same_and_detects_a_perturbed_field() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    let solve_mat = dir.path().join("solve.mat");
    let grow_mat = dir.path().join("grow-mat");
    ok(&[
        "export",
        s(&solve),
        "--mat",
        s(&solve_mat),
        "--compress",
        "--quiet",
    ]);
    ok(&[
        "export",
        s(&grow),
        "--mat",
        s(&grow_mat),
        "--npz",
        s(&dir.path().join("grow-npz")),
        "--quiet",
    ]);

    // Unperturbed: every reference kind passes, with zero differences.
    let r = ok(&["compare", s(&solve), s(&solve_mat)]);
    assert!(
        r.stdout.contains("kappa") && r.stdout.contains(" ok"),
        "{}",
        r.stdout
    );
    assert!(!r.stdout.contains("FAIL"), "{}", r.stdout);
    ok(&[
        "compare",
        s(&grow),
        s(&grow_mat),
        s(&dir.path().join("grow-npz")),
    ]);
    let copy = dir.path().join("copy");
    copy_dir(&solve, &copy);
    ok(&["compare", s(&solve), s(&copy), "--tol", "0", "--rtol", "0"]);

    // One value of κ (sol.y(1, 6)) moved by 1e-6: exit 1, κ fails, nothing else does.
    let mut vars = mat::read(&solve_mat).unwrap();
    if let MatValue::Struct(fields) = &mut vars[0].1 {
        let y = &mut fields.iter_mut().find(|(n, _)| n == "y").unwrap().1;
        perturb(y, 5 * 5, 1e-6);
    }
    let bad = dir.path().join("bad.mat");
    mat::write(&bad, &vars, true).unwrap();
    let r = eyeshell(&["compare", s(&solve), s(&bad)]);
    assert_fails(&r, 1, "kappa");
    let sigma = column(&solve.join("fields.csv"), "Sigma")[5];
    let kappa_line = r
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("kappa "))
        .unwrap();
    assert!(kappa_line.contains("FAIL (1 point)"), "{kappa_line}");
    assert!(kappa_line.contains("1.000e-6"), "{kappa_line}");
    assert!(kappa_line.contains(&format!("{sigma:.6}")), "{kappa_line}");
    assert_eq!(r.stdout.matches("FAIL").count(), 1, "{}", r.stdout);
    // ... and passes when the tolerance allows it.
    ok(&["compare", s(&solve), s(&bad), "--tol", "2e-6", "--quiet"]);

    // Growth: η of one snapshot perturbed at one node.
    let snaps = snapshots(&grow);
    let name = format!("{}.mat", snaps[2].0.file_stem().unwrap().to_str().unwrap());
    let mut vars = mat::read(&grow_mat.join(&name)).unwrap();
    perturb(
        &mut vars.iter_mut().find(|(n, _)| n == "rho").unwrap().1,
        10,
        1e-6,
    );
    let bad = dir.path().join("bad-growth.mat");
    mat::write(&bad, &vars, false).unwrap();
    let r = eyeshell(&["compare", s(&grow), s(&bad)]);
    assert_fails(&r, 1, "rho");
    assert!(
        r.stdout.contains(&format!("at t = {}", snaps[2].1)),
        "{}",
        r.stdout
    );

    // A run against a copy of itself with one CSV value changed.
    let fields = copy.join("fields.csv");
    let text = std::fs::read_to_string(&fields).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut row: Vec<f64> = lines[3].split(',').map(|v| v.parse().unwrap()).collect();
    row[4] += 1e-6; // r
    lines[3] = row
        .iter()
        .map(|x| format!("{x:e}"))
        .collect::<Vec<_>>()
        .join(",");
    std::fs::write(&fields, lines.join("\n") + "\n").unwrap();
    let r = eyeshell(&["compare", s(&solve), s(&copy)]);
    assert_fails(&r, 1, "field comparison");
    assert!(
        r.stdout
            .lines()
            .any(|l| l.trim_start().starts_with("r ") && l.contains("FAIL")),
        "{}",
        r.stdout
    );
}

#[test]
fn compare_interpolates_to_the_reference_points() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, _) = small_runs(dir.path());
    let fine = dir.path().join("fine");
    ok(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=41",
        "--out",
        s(&fine),
        "--quiet",
    ]);
    let fine_mat = dir.path().join("fine.mat");
    ok(&["export", s(&fine), "--mat", s(&fine_mat), "--quiet"]);
    // N = 21 interpolated to the N = 41 nodes: close, but the discretisations differ by more than 1e-8.
    let r = eyeshell(&["compare", s(&solve), s(&fine_mat)]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    let r = ok(&[
        "compare",
        s(&solve),
        s(&fine_mat),
        "--tol",
        "0.02",
        "--rtol",
        "0.02",
    ]);
    let n_fine = column(&fine.join("fields.csv"), "Sigma").len();
    assert!(
        r.stdout.contains(&format!("{n_fine} points in Sigma")),
        "{}",
        r.stdout
    );
}

#[test]
fn compare_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    let r = eyeshell(&["compare", s(&solve), s(&dir.path().join("missing.mat"))]);
    assert_fails(&r, 2, "missing.mat");
    let junk = dir.path().join("junk.mat");
    std::fs::write(&junk, "not a mat file at all").unwrap();
    assert_fails(&eyeshell(&["compare", s(&solve), s(&junk)]), 2, "junk.mat");
    let nocoord = dir.path().join("nocoord.mat");
    mat::write(
        &nocoord,
        &[("kappa".into(), MatValue::row(&[1.0, 2.0]))],
        false,
    )
    .unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&nocoord)]),
        2,
        "material coordinate",
    );
    let nocommon = dir.path().join("nocommon.mat");
    mat::write(
        &nocommon,
        &[
            ("x".into(), MatValue::row(&[0.5, 1.0])),
            ("foo".into(), MatValue::row(&[1.0, 2.0])),
        ],
        false,
    )
    .unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&nocommon)]),
        2,
        "no variable in common",
    );
    // A reference at a time the run never output.
    let odd = dir.path().join("odd.mat");
    mat::write(
        &odd,
        &[
            ("Sigma".into(), MatValue::row(&[0.5, 1.0])),
            ("rho".into(), MatValue::row(&[1.0, 2.0])),
            ("time".into(), MatValue::scalar(0.123)),
        ],
        false,
    )
    .unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&grow), s(&odd)]),
        2,
        "time = 0.123",
    );
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&solve), "--tol", "-1"]),
        2,
        "--tol",
    );
}

/// compare is as accurate as the solutions it compares (issue 14): a Hermite–Simpson run at
/// N = 801 against a reference at N = 8001 on its own graded, non-uniform mesh (both
/// accurate to about 1e-10 in κ, r, θ, Q) passes at 1e-7, and a perturbation of 1e-6 at
/// any single reference point fails, near the pole, the breakpoint and the cornea too.
#[test]
fn compare_is_as_accurate_as_the_solutions() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("n801");
    let reference = dir.path().join("n8001");
    for (n, out) in [("801", &run), ("8001", &reference)] {
        ok(&[
            "solve",
            "scenes/fibres-nonuniform.toml",
            "--set",
            &format!("solver.nodes={n}"),
            "--out",
            s(out),
            "-q",
        ]);
    }
    let npz = dir.path().join("ref.npz");
    ok(&["export", s(&reference), "--npz", s(&npz), "-q"]);
    for r in [&reference, &npz] {
        let out = ok(&["compare", s(&run), s(r), "--tol", "1e-7", "--rtol", "1e-7"]);
        assert!(
            out.stdout.contains("13 of 13 field comparisons"),
            "{}",
            out.stdout
        );
    }
    // One point perturbed by 1e-6, anywhere: a failure that names the field.
    let (header, rows) = csv_cells(&reference.join("fields.csv"));
    let col = |c: &str| header.iter().position(|h| h == c).unwrap();
    let (kappa, sigma_col) = (col("kappa"), col("Sigma"));
    let n = rows.len();
    let sigmas: Vec<f64> = rows.iter().map(|r| r[sigma_col].parse().unwrap()).collect();
    let near = |x: f64| {
        (0..n)
            .min_by(|&a, &b| (sigmas[a] - x).abs().total_cmp(&(sigmas[b] - x).abs()))
            .unwrap()
    };
    let breakpoint = std::f64::consts::PI * 10.0 / 2.0; // πR0/2 at R0 = 10
    for k in [1, near(breakpoint) + 1, n / 3, n - 3] {
        let mut rows = rows.clone();
        let v: f64 = rows[k][kappa].parse().unwrap();
        rows[k][kappa] = format!("{:e}", v + 1e-6);
        let text = std::iter::once(header.join(","))
            .chain(rows.iter().map(|r| r.join(",")))
            .collect::<Vec<_>>()
            .join("\n")
            + "\n";
        let bent = dir.path().join("bent");
        let _ = std::fs::remove_dir_all(&bent);
        std::fs::create_dir(&bent).unwrap();
        for f in ["summary.json", ".eyeshell"] {
            std::fs::copy(reference.join(f), bent.join(f)).unwrap();
        }
        std::fs::write(bent.join("fields.csv"), text).unwrap();
        let r = eyeshell(&[
            "compare",
            s(&run),
            s(&bent),
            "--tol",
            "1e-7",
            "--rtol",
            "1e-7",
        ]);
        assert_eq!(
            r.code,
            Some(1),
            "point {k} (Σ = {}): {}",
            sigmas[k],
            r.stdout
        );
        assert!(r.stderr.contains("kappa"), "{}", r.stderr);
    }
}
