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
