//! `eyeshell solve` end to end: the files it writes and what they hold.

use crate::support::*;

#[test]
fn solve_writes_fields_summary_and_at() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let out_s = out.to_str().unwrap();
    let Run {
        code,
        stdout,
        stderr,
    } = eyeshell(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=101",
        "--at",
        "0.001,1,12.5,25.132741228718345",
        "--out",
        out_s,
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout.contains("Newton") && stdout.contains(out_s),
        "{stdout}"
    );

    let header = eyeshell::bvp::COLUMNS.join(",");
    let (h, fields) = csv(&out.join("fields.csv"));
    assert_eq!(h.join(","), header);
    assert!(fields
        .iter()
        .all(|r| r.len() == eyeshell::bvp::COLUMNS.len() && r.iter().all(|x| x.is_finite())));
    // Σ increases from ε to L.
    assert!((fields[0][0] - 1e-3).abs() < 1e-15);
    assert!((fields.last().unwrap()[0] - std::f64::consts::PI * 8.0).abs() < 1e-12);
    assert!(fields.windows(2).all(|w| w[1][0] > w[0][0]));

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["nodes"].as_u64().unwrap() as usize, fields.len());
    assert_eq!(summary["uniform_nodes"], 101);
    assert_eq!(summary["parameters"]["solver.nodes"], 101);
    assert_eq!(summary["scheme"], "hermite-simpson");
    assert!(
        summary["first_integral_max"].as_f64().unwrap() < 1e-6,
        "{summary}"
    );
    assert!((summary["cornea_alpha"].as_f64().unwrap() - 1.0136216901111).abs() < 1e-12);

    let (h, at) = csv(&out.join("at.csv"));
    assert_eq!(h.join(","), header);
    assert_eq!(at.len(), 4);
    for (row, s) in at.iter().zip([0.001, 1.0, 12.5, 25.132741228718345]) {
        assert!((row[0] - s).abs() < 1e-12, "{row:?}");
    }
    // At a node, the interpolant agrees with the nodal values.
    for (a, f) in at[0].iter().zip(&fields[0]) {
        assert!(
            (a - f).abs() <= 1e-9 * (1.0 + f.abs()),
            "{:?} vs {:?}",
            at[0],
            fields[0]
        );
    }

    // Solving again into the same directory replaces the previous output (no at.csv now).
    let Run {
        code,
        stdout,
        stderr,
    } = eyeshell(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=51",
        "--out",
        out_s,
        "--quiet",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.is_empty());
    assert!(!out.join("at.csv").exists());
    assert_only_entry(dir.path(), "run", "next to the output");
}

#[test]
fn exact_sphere_is_reproduced() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sphere");
    let Run { code, stderr, .. } = eyeshell(&[
        "solve",
        "scenes/exact-sphere.toml",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let (_, fields) = csv(&out.join("fields.csv"));
    let alpha = 1.0136216901111_f64;
    for row in &fields {
        let (sigma, kappa, r, theta) = (row[1], row[2], row[4], row[5]);
        assert!(
            (r - alpha * 10.0 * (sigma / 10.0).sin()).abs() < 1e-6,
            "{row:?}"
        );
        assert!((theta - sigma / 10.0).abs() < 1e-6, "{row:?}");
        assert!((kappa - 1.0 / (alpha * 10.0)).abs() < 1e-5, "{row:?}");
    }
}

/// `solver.tol`: the mesh is adapted, summary.json gives the estimate per field and overall,
/// the refinements and each pass's nodes, fields.csv is on the final mesh and `--at` works.
#[test]
fn solve_to_a_tolerance_reports_its_error_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let out_s = out.to_str().unwrap();
    let Run {
        code,
        stdout,
        stderr,
    } = eyeshell(&[
        "solve",
        "scenes/exact-sphere.toml",
        "--set",
        "solver.tol=1e-8",
        "--at",
        "1,12.5",
        "--out",
        out_s,
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("adapted to solver.tol = 1e-8"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let est = &summary["error_estimate"];
    for f in ["kappa", "alpha_s", "r", "theta", "Q"] {
        let e = est[f].as_f64().unwrap();
        assert!(
            e > 0.0 && e <= est["overall"].as_f64().unwrap(),
            "{summary}"
        );
    }
    let overall = est["overall"].as_f64().unwrap();
    assert!(overall <= 1e-8 && overall > 1e-11, "{summary}");
    let passes: Vec<u64> = summary["pass_nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_u64().unwrap())
        .collect();
    assert_eq!(
        summary["mesh_refinements"].as_u64().unwrap() as usize,
        passes.len() - 1
    );
    let (_, fields) = csv(&out.join("fields.csv"));
    assert_eq!(*passes.last().unwrap() as usize, fields.len());
    assert_eq!(summary["nodes"].as_u64().unwrap() as usize, fields.len());
    assert_eq!(summary["parameters"]["solver.tol"], 1e-8);
    // The exact sphere's r = α R0 sin(Σ/R0), to the tolerance, at the points asked for.
    let alpha = summary["cornea_alpha"].as_f64().unwrap();
    let (_, at) = csv(&out.join("at.csv"));
    for row in &at {
        let exact = alpha * 10.0 * (row[0] / 10.0).sin();
        assert!((row[4] - exact).abs() < 1e-8, "{row:?}");
    }
}

/// A tolerance below round-off: exit 1, one line with the best error and its nodes, and no
/// output directory.
#[test]
fn a_tolerance_below_round_off_fails_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let Run { code, stderr, .. } = eyeshell(&[
        "solve",
        "scenes/fibres-nonuniform.toml",
        "--set",
        "solver.tol=1e-15",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with(
            "eyeshell: error: solver.tol = 1e-15 cannot be reached: the best estimated error was "
        ) && stderr.contains(" nodes; ")
            && stderr.contains("round-off"),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// Soft shells under solver.tol: E_b = 1e-4 and 1e-6 on the fibre shell solve to
/// tol 1e-6. (KINSOL's line search fails at a root whose residual is already below
/// newton_tol; that iterate is converged, not a failure. The true error of these solves is checked against a reference in
/// `numerics::adapt::tolerance_holds_over_the_parameter_space`.)
#[test]
fn soft_shells_solve_to_a_tolerance() {
    for e_b in ["1e-4", "1e-6"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        let Run {
            code,
            stdout,
            stderr,
        } = eyeshell(&[
            "solve",
            "scenes/fibres-nonuniform.toml",
            "--set",
            &format!("material.bending={e_b}"),
            "--set",
            "solver.tol=1e-6",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, Some(0), "E_b = {e_b}: {stderr}");
        assert!(stdout.contains("adapted to solver.tol = 1e-6"), "{stdout}");
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let overall = summary["error_estimate"]["overall"].as_f64().unwrap();
        assert!(overall > 0.0 && overall <= 1e-6, "E_b = {e_b}: {summary}");
        let (_, fields) = csv(&out.join("fields.csv"));
        assert_eq!(summary["nodes"].as_u64().unwrap() as usize, fields.len());
        assert!(fields.iter().flatten().all(|v| v.is_finite()));
    }
}

/// A Newton tolerance below what double precision reaches on the mesh: one line naming it
/// as that, with the residual reached and the newton_tol that can be, exit 1 and nothing
/// written; never a failed evaluation at a trial point of the line search ("r ≤ 0: the
/// shell has passed through its axis") nor a plain "did not converge".
#[test]
fn a_newton_tolerance_below_round_off_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let Run { code, stderr, .. } = eyeshell(&[
        "solve",
        "scenes/fibres-nonuniform.toml",
        "--set",
        "material.bending=1e-6",
        "--set",
        "solver.nodes=12801",
        "--set",
        "solver.newton_tol=1e-14",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("eyeshell: error: Newton stalled at a scaled residual of ")
            && stderr.contains(
                "solver.newton_tol = 1e-14 is below what double precision reaches on this mesh"
            )
            && stderr.contains("ask for solver.newton_tol = ")
            && !stderr.contains("axis"),
        "{stderr}"
    );
    assert!(
        stderr.chars().count() <= 300 + "eyeshell: error: ".len(),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// A node cap below what the tolerance needs; solver.richardson in a growth scene.
#[test]
fn solver_tol_refusals_are_clear() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let Run { code, stderr, .. } = eyeshell(&[
        "solve",
        "scenes/fibres-nonuniform.toml",
        "--set",
        "solver.tol=1e-10",
        "--set",
        "solver.max_nodes=500",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("more than solver.max_nodes = 500 nodes") && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(!out.exists());
    // In a growth scene solver.tol chooses the mesh; solver.richardson is refused.
    let Run { code, stderr, .. } =
        eyeshell(&["check", "scenes/const.toml", "--set", "solver.tol=1e-6"]);
    assert_eq!(code, Some(0), "{stderr}");
    let Run { code, stderr, .. } = eyeshell(&[
        "check",
        "scenes/const.toml",
        "--set",
        "solver.richardson=true",
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("solver.richardson") && stderr.contains("growth"),
        "{stderr}"
    );
}

/// `solver.richardson` alone: one extrapolation on the mesh of solver.nodes (reported on
/// it halved), with its estimate; against the exact sphere it is order 6 accurate.
#[test]
fn richardson_alone_extrapolates_on_the_mesh_of_solver_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let Run { code, stderr, .. } = eyeshell(&[
        "solve",
        "scenes/exact-sphere.toml",
        "--set",
        "solver.nodes=51",
        "--set",
        "solver.richardson=true",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let (_, fields) = csv(&out.join("fields.csv"));
    let mesh51 = 51 + summary["pole_nodes"].as_u64().unwrap() as usize / 2 + 1;
    assert_eq!(fields.len(), 2 * mesh51 - 1, "{summary}");
    assert_eq!(summary["mesh_refinements"], 0);
    let est = summary["error_estimate"]["overall"].as_f64().unwrap();
    // Hermite–Simpson alone on this mesh halved is 1e-5 off in Q; extrapolated, 1e-8.
    let alpha = summary["cornea_alpha"].as_f64().unwrap();
    let worst = fields
        .iter()
        .map(|row| {
            (row[4] - alpha * 10.0 * (row[0] / 10.0).sin())
                .abs()
                .max(row[6].abs())
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "{worst:e}");
    assert!(
        est > worst / 3.0 && est < 30.0 * worst,
        "{est:e} vs {worst:e}"
    );
}

/// `solver.max_seconds` bounds a tolerance-driven solve as a whole, not each of its solves.
#[test]
fn max_seconds_bounds_the_whole_adaptive_solve() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let Run { code, stderr, .. } = eyeshell(&[
        "solve",
        "scenes/fibres-nonuniform.toml",
        "--set",
        "solver.tol=1e-12",
        "--set",
        "solver.max_seconds=0.002",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr
            .starts_with("eyeshell: error: solver.max_seconds = 0.002 s reached in the solve on ")
            && stderr.contains("solver.tol's adaptation")
            && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(!out.exists());
}
