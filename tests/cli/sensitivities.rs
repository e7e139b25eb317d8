//! `eyeshell grow --sensitivities`: sensitivities.csv, its work in summary.json,
//! its figure from `eyeshell plot`, and the keys it refuses (exit 2, one line, nothing
//! written).

use crate::support::*;

#[test]
fn bad_sensitivity_keys_are_refused_and_nothing_is_written() {
    for (keys, sets, needle) in [
        ("stimulus.red.offset", "", "only affects the classification"),
        (
            "growth.eta0,fibres.D",
            "",
            "fibres.D = 0: the scene has no fibres",
        ),
        (
            "material.H0",
            "",
            "sensitivities to material.H0 are not available",
        ),
        ("growth.Gama", "", "\"growth.Gama\" is not a scene key"),
        ("growth.eta0,growth.eta0", "", "growth.eta0 is listed twice"),
        (
            "growth.eta0",
            "solver.integrator=cvode",
            "--sensitivities need solver.integrator = \"ida\"",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let mut args = vec![
            "grow",
            "scenes/const.toml",
            "--sensitivities",
            keys,
            "--out",
            s(&out),
        ];
        if !sets.is_empty() {
            args.extend(["--set", sets]);
        }
        let run = eyeshell(&args);
        assert_bad(&run, needle, keys);
        assert!(!out.exists(), "{keys}: nothing may be written");
    }
}

/// One row per recorded time and parameter; zero at t = 0 for the growth parameters, and
/// for ΔP the inflation of the t = 0 equilibrium (the eye lengthens: dL/dΔP > 0); the
/// scaled column is
/// (p/L) dL/dp with L from series.csv (to 1e-6: series.csv measures the snapshot's shell,
/// re-solved, the sensitivities the integrator's state); dL/dη0 at t = 0.1 is the value of a rtol-1e-12 run
/// (N = 101, 1.847218610e-2, tests/numerics/sensitivities.rs's scene) to 1e-4.
#[test]
fn grow_writes_sensitivities_csv_and_their_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    ok(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=101",
        "--set",
        "solver.rtol=1e-8",
        "--set",
        "solver.atol=1e-11",
        "--set",
        "output.history_points=0",
        "--sensitivities",
        "growth.eta0,growth.Gamma,pressure.dP",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let (header, cells) = csv_cells(&out.join("sensitivities.csv"));
    assert_eq!(
        header,
        [
            "t",
            "parameter",
            "d_axial_length",
            "d_equatorial_radius",
            "d_retina_minus_blue",
            "scaled_axial_length"
        ]
    );
    // series.csv: t, axial_length, ... (its class column is text).
    let (series_header, series) = csv_cells(&out.join("series.csv"));
    assert_eq!(&series_header[..2], ["t", "axial_length"]);
    let times: Vec<f64> = series.iter().map(|r| r[0].parse().unwrap()).collect();
    let lengths: Vec<f64> = series.iter().map(|r| r[1].parse().unwrap()).collect();
    assert_eq!(cells.len(), 3 * times.len());
    for (k, (&t, &l)) in times.iter().zip(&lengths).enumerate() {
        for (j, (key, p)) in [
            ("growth.eta0", 70.0),
            ("growth.Gamma", 8.0),
            ("pressure.dP", 2.0),
        ]
        .into_iter()
        .enumerate()
        {
            let row = &cells[3 * k + j];
            let v = |c: usize| -> f64 { row[c].parse().unwrap() };
            assert_eq!((v(0), row[1].as_str()), (t, key));
            let scaled = p / l * v(2);
            assert!((v(5) - scaled).abs() <= 1e-6 * scaled.abs(), "{row:?}");
            match (t, key) {
                (0.0, "pressure.dP") => assert!(v(2) > 0.0 && v(3) > 0.0, "{row:?}"),
                (0.0, _) => assert_eq!([v(2), v(3), v(4)], [0.0; 3]),
                _ => {}
            }
            if t == 0.1 && key == "growth.eta0" {
                let rel = (v(2) / 1.847218610e-2 - 1.0).abs();
                assert!(rel < 1e-4, "dL/dη0 at t = 0.1: {} (rel {rel:.1e})", v(2));
            }
        }
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let work = summary
        .pointer("/stats/sensitivities")
        .or_else(|| summary.pointer("/sensitivities"))
        .unwrap_or_else(|| panic!("no sensitivities in summary.json: {summary}"));
    assert_eq!(
        work["parameters"],
        serde_json::json!(["growth.eta0", "growth.Gamma", "pressure.dP"])
    );
    assert_eq!(work["error_control"], serde_json::json!(false));
    assert!(work["residual_evaluations"].as_u64().unwrap() > 0);
    // `eyeshell plot` draws them against t.
    let plots = dir.path().join("plots");
    ok(&["plot", s(&out), "--out", s(&plots), "--quiet"]);
    for ext in ["png", "svg"] {
        let f = plots.join(format!("sensitivities.{ext}"));
        assert!(
            std::fs::metadata(&f).unwrap().len() > 1000,
            "{}",
            f.display()
        );
    }
}

/// `--sensitivity-error-control` at rtol 1e-8 runs to the end (with the border d in the
/// error test the step collapses to 1e-314 at t = 0.053: d's sensitivity jumps; the test
/// leaves d out), summary.json says so, and its dL/dη0 at t = 0.1 is the converged value (the
/// uncontrolled rtol-1e-8 run of the test above agrees with it to 1e-4).
#[test]
fn error_control_on_the_sensitivities_runs_at_tight_tolerances() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    ok(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=101",
        "--set",
        "solver.rtol=1e-8",
        "--set",
        "solver.atol=1e-10",
        "--set",
        "output.history_points=0",
        "--sensitivities",
        "growth.eta0",
        "--sensitivity-error-control",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let (_, cells) = csv_cells(&out.join("sensitivities.csv"));
    let last: f64 = cells.last().unwrap()[0].parse().unwrap();
    assert_eq!(last, 1.0, "the run reached t_end");
    let at = |t: f64| -> f64 {
        let row = cells
            .iter()
            .find(|r| r[0].parse::<f64>().unwrap() == t)
            .unwrap_or_else(|| panic!("no row at t = {t}"));
        row[2].parse().unwrap()
    };
    let rel = (at(0.1) / 1.847218610e-2 - 1.0).abs();
    assert!(rel < 1e-4, "dL/dη0 at t = 0.1: {} (rel {rel:.1e})", at(0.1));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "ok");
    let work = summary
        .pointer("/stats/sensitivities")
        .or_else(|| summary.pointer("/sensitivities"))
        .unwrap_or_else(|| panic!("no sensitivities in summary.json: {summary}"));
    assert_eq!(work["error_control"], serde_json::json!(true));
}

/// `--sensitivities material.C --sensitivity-error-control` with rounded kinks at rtol
/// 1e-10 starts (it failed at t = 0 with IDA_ERR_FAIL, h = 2.5e-12: the algebraic s'(0)
/// seeding IDAS's first predictor left out second-order terms), short runs to t = 0.05.
#[test]
fn error_control_starts_for_the_modulus_with_rounded_kinks() {
    let dir = tempfile::tempdir().unwrap();
    for kink in ["0.05", "0.2"] {
        let out = dir.path().join(format!("out-{kink}"));
        ok(&[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.nodes=101",
            "--set",
            "solver.rtol=1e-10",
            "--set",
            &format!("growth.kink_width={kink}"),
            "--set",
            "growth.t_end=0.05",
            "--set",
            "output.times=[0.05]",
            "--set",
            "output.history_points=0",
            "--sensitivities",
            "material.C",
            "--sensitivity-error-control",
            "--out",
            s(&out),
            "--quiet",
        ]);
        let (_, cells) = csv_cells(&out.join("sensitivities.csv"));
        assert_eq!(cells.last().unwrap()[0].parse::<f64>().unwrap(), 0.05);
    }
}
