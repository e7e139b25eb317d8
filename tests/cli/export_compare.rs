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

/// `--tol 1e-8` with the default `--rtol 1e-8` lets a 1e-7 error in r ≈ 10 through: the
/// report says so, naming the absolute tolerance it applied, and `--rtol 0` catches it.
#[test]
fn compare_prints_the_absolute_tolerance_it_applied() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, _) = small_runs(dir.path());
    let mat_file = dir.path().join("solve.mat");
    ok(&["export", s(&solve), "--mat", s(&mat_file), "--quiet"]);
    let r_last = *column(&solve.join("fields.csv"), "r")
        .iter()
        .fold(&0.0, |a, b| if b > a { b } else { a });
    let mut vars = mat::read(&mat_file).unwrap();
    let k = column(&solve.join("fields.csv"), "r")
        .iter()
        .position(|&v| v == r_last)
        .unwrap();
    if let MatValue::Struct(fields) = &mut vars[0].1 {
        let y = &mut fields.iter_mut().find(|(n, _)| n == "y").unwrap().1;
        perturb(y, 5 * k + 2, 1e-7);
    }
    let bad = dir.path().join("bad.mat");
    mat::write(&bad, &vars, false).unwrap();
    let r = ok(&["compare", s(&solve), s(&bad), "--tol", "1e-8"]);
    let allowed = 1e-8 + 1e-8 * r_last;
    let line = r
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("r "))
        .unwrap();
    let cells: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(
        cells[cells.len() - 2],
        format!("{allowed:.2e}"),
        "{}",
        r.stdout
    );
    assert_eq!(cells[cells.len() - 1], "ok", "{line}");
    assert!(r.stdout.contains("    allowed  status"), "{}", r.stdout);
    let r = eyeshell(&[
        "compare",
        s(&solve),
        s(&bad),
        "--tol",
        "1e-8",
        "--rtol",
        "0",
    ]);
    assert_fails(&r, 1, "r");
    let line = r
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("r "))
        .unwrap();
    assert!(line.contains("1.00e-8  FAIL (1 point)"), "{line}");
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

/// compare is as accurate as the solutions it compares: a Hermite–Simpson run at
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

/// A MAT v5 element: the 1×1 cell array `name` holding `inner` (eyeshell's writer writes
/// no cells; the layout is MATLAB's: array flags with class mxCELL_CLASS, dimensions, name,
/// then each cell as an element of its own).
fn cell_var(name: &str, inner: &MatValue) -> Vec<u8> {
    let word = |v: &mut Vec<u8>, x: u32| v.extend(x.to_le_bytes());
    // The inner value as an element: eyeshell's encoding of it, past the 128-byte header.
    let inner = mat::encode(&[("c".into(), inner.clone())], false).unwrap()[128..].to_vec();
    let mut body = Vec::new();
    for x in [6, 8, 1, 0, 5, 8, 1, 1, 1, name.len() as u32] {
        word(&mut body, x); // miUINT32 flags (cell), miINT32 dims 1×1, miINT8 name
    }
    body.extend(name.as_bytes());
    body.resize(body.len().div_ceil(8) * 8, 0);
    body.extend(inner);
    let mut element = Vec::new();
    word(&mut element, 14); // miMATRIX
    word(&mut element, body.len() as u32);
    element.extend(body);
    element
}

/// The solve's own export with one field of `sol` replaced (or removed when `value` is
/// None), written to `dir/NAME.mat`.
fn with_sol_field(
    dir: &std::path::Path,
    solve_mat: &std::path::Path,
    name: &str,
    field: &str,
    value: Option<MatValue>,
) -> std::path::PathBuf {
    let mut vars = mat::read(solve_mat).unwrap();
    let MatValue::Struct(fields) = &mut vars[0].1 else {
        panic!("sol is not a struct")
    };
    match value {
        Some(v) => fields.iter_mut().find(|(n, _)| n == field).unwrap().1 = v,
        None => fields.retain(|(n, _)| n != field),
    }
    let path = dir.join(format!("{name}.mat"));
    mat::write(&path, &vars, false).unwrap();
    path
}

/// A reference that cannot be compared whole is refused (exit 2) with what is wrong in it,
/// never passed on the fields that are left: `sol.y` transposed, short, with 4 or 6 rows,
/// a cell or text; an empty, 0-d or one-point x (never replaced by the other coordinate);
/// a NaN in x; a field the run has with the wrong length; a `sol` that is not a struct; a
/// `time` that is not one number. y with wrong values fails (exit 1). Variables the run
/// has no field for are listed as not compared.
#[test]
fn compare_refuses_a_reference_it_cannot_compare_whole() {
    use eyeshell::interop::npz::{self, NpyArray};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (solve, grow) = small_runs(d);
    let solve_mat = d.join("solve.mat");
    ok(&["export", s(&solve), "--mat", s(&solve_mat), "--quiet"]);
    let vars = mat::read(&solve_mat).unwrap();
    let sol = &vars[0].1;
    let y = sol.field("y").unwrap().clone();
    let n = y.dims().unwrap()[1];
    let rows: Vec<Vec<f64>> = (0..5).map(|i| y.row_of(i).unwrap()).collect();
    let x = sol.field("x").unwrap().data().unwrap().to_vec();

    // The export itself: everything compared or said not to be.
    let r = ok(&["compare", s(&solve), s(&solve_mat)]);
    let line = r
        .stdout
        .lines()
        .find(|l| l.contains("not compared:"))
        .unwrap_or_else(|| panic!("{}", r.stdout));
    for name in [
        "solver (text",
        "stats (a struct)",
        &format!("yp (a 5×{n} array, not a vector over the points)"),
    ] {
        assert!(line.contains(name), "{line}");
    }
    assert!(
        r.stdout.contains("13 of 13 field comparisons"),
        "{}",
        r.stdout
    );

    let transposed = MatValue::Double {
        dims: vec![n, 5],
        data: rows.iter().flatten().copied().collect(),
    };
    let short = MatValue::from_rows(&rows.iter().map(|r| r[..n - 3].to_vec()).collect::<Vec<_>>());
    let four = MatValue::from_rows(&rows[..4]);
    let mut six_rows = rows.clone();
    six_rows.push(rows[0].clone());
    let six = MatValue::from_rows(&six_rows);
    let one = MatValue::row(&x[..1]);
    let mut nan_x = x.clone();
    nan_x[3] = f64::NAN;
    let cases: Vec<(&str, &str, Option<MatValue>, String)> = vec![
        (
            "transposed",
            "y",
            Some(transposed),
            format!("sol.y is a {n}×5 array (it looks transposed)"),
        ),
        (
            "short",
            "y",
            Some(short),
            format!("sol.y has {} columns but sol.x has {n} points", n - 3),
        ),
        ("four", "y", Some(four), format!("sol.y is a 4×{n} array")),
        ("six", "y", Some(six), format!("sol.y is a 6×{n} array")),
        (
            "text",
            "y",
            Some(MatValue::Char("kappa".into())),
            "sol.y is text".into(),
        ),
        (
            "empty-x",
            "x",
            Some(MatValue::row(&[])),
            "sol.x is empty".into(),
        ),
        ("one-x", "x", Some(one), "sol.x has a single point".into()),
        (
            "nan-x",
            "x",
            Some(MatValue::row(&nan_x)),
            format!("sol.x has nan at point 4 of {n}"),
        ),
        ("no-x", "x", None, "sigma".into()),
        (
            "short-sigma",
            "sigma",
            Some(MatValue::row(&x[..n - 1])),
            format!(
                "sigma is {} values, but sol.x has {n} points, so it cannot be compared",
                n - 1
            ),
        ),
    ];
    for (name, field, value, needle) in cases {
        let bad = with_sol_field(d, &solve_mat, name, field, value);
        let r = eyeshell(&["compare", s(&solve), s(&bad)]);
        if name == "no-x" {
            // Without x the reference's own coordinate sigma is used, and said.
            assert!(
                r.stdout.contains(&format!("{n} points in sigma")),
                "{name}: {}",
                r.stdout
            );
            continue;
        }
        one_clean_line(&r, name);
        assert_fails(&r, 2, &needle);
        assert!(r.stdout.is_empty(), "{name}: {}", r.stdout);
    }

    // Well-formed y with wrong values fails the comparison: every row, all 123, and a NaN.
    let all = MatValue::from_rows(&vec![vec![123.0; n]; 5]);
    let bad = with_sol_field(d, &solve_mat, "all-123", "y", Some(all));
    let r = eyeshell(&["compare", s(&solve), s(&bad)]);
    assert_fails(&r, 1, "5 field comparisons beyond");
    assert_eq!(r.stdout.matches("FAIL").count(), 5, "{}", r.stdout);
    let mut nan_rows = rows.clone();
    nan_rows[2][7] = f64::NAN;
    let bad = with_sol_field(
        d,
        &solve_mat,
        "nan-y",
        "y",
        Some(MatValue::from_rows(&nan_rows)),
    );
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&bad)]),
        1,
        "worst: r in",
    );

    // Cell arrays (eyeshell writes none: encoded here): a y in a cell, and a `sol` in a
    // cell, which is not read as the top level instead.
    let mut cells = mat::encode(&[("x".into(), MatValue::row(&x))], false).unwrap();
    cells.extend(cell_var("y", &y));
    let cell_y = d.join("cell-y.mat");
    std::fs::write(&cell_y, cells).unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&cell_y)]),
        2,
        "y is a 1×1 cell array: expected a 5×N numeric array",
    );
    let mut cells = mat::header();
    cells.extend(cell_var("sol", sol));
    let cell_sol = d.join("cell-sol.mat");
    std::fs::write(&cell_sol, cells).unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&cell_sol)]),
        2,
        "sol is a 1×1 cell array, not bvp4c's solution struct",
    );

    // The same in .npz: (N, 5) y, 0-d x, one-point x.
    let npz_of = |name: &str, x: NpyArray, y: NpyArray| {
        let p = d.join(format!("{name}.npz"));
        npz::write(&p, &[("x".into(), x), ("y".into(), y)]).unwrap();
        p
    };
    let good_y = NpyArray::from_rows(&rows);
    let p = npz_of("ok", NpyArray::vector(&x), good_y.clone());
    ok(&["compare", s(&solve), s(&p), "--quiet"]);
    let t = NpyArray {
        shape: vec![n, 5],
        data: (0..n)
            .flat_map(|j| rows.iter().map(move |r| r[j]))
            .collect(),
    };
    let p = npz_of("t", NpyArray::vector(&x), t);
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&p)]),
        2,
        &format!("y is a {n}×5 array (it looks transposed)"),
    );
    let p = npz_of("zero-d", NpyArray::scalar(x[0]), good_y.clone());
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&p)]),
        2,
        "x is a 0-d array (one number)",
    );
    let p = npz_of("one", NpyArray::vector(&x[..1]), good_y);
    assert_fails(
        &eyeshell(&["compare", s(&solve), s(&p)]),
        2,
        "x has a single point",
    );

    // A growth snapshot whose time is text.
    let odd = d.join("odd-time.mat");
    mat::write(
        &odd,
        &[
            ("Sigma".into(), MatValue::row(&[0.5, 1.0])),
            ("rho".into(), MatValue::row(&[1.0, 2.0])),
            ("time".into(), MatValue::Char("0.1".into())),
        ],
        false,
    )
    .unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&grow), s(&odd)]),
        2,
        "time is text (a char array): expected one finite number",
    );
}
