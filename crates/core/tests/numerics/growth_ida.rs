//! Growth by IDA on the coupled DAE: it agrees with CVODE on the paper's scenes,
//! survives the growth extremes of TESTING.md, and every linear solver gives the same run.

use crate::common::grow;
use eyeshell_core::bvp::settings::SolverSettings;
use eyeshell_core::growth::DaeLinear;
use eyeshell_core::growth::*;
use eyeshell_core::model::params::{Params, Thickness};

/// Keeps every snapshot's series row.
#[derive(Default)]
struct Keep(Vec<SeriesRow>);

impl Observer for Keep {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), eyeshell_core::growth::ObserverError> {
        self.0.push(s.series);
        Ok(())
    }
}

fn run(
    p: &Params,
    nodes: usize,
    g: &GrowthParams,
    s: &GrowthSettings,
) -> (Vec<SeriesRow>, Result<GrowthStats, GrowthError>) {
    let mut keep = Keep::default();
    let solver = SolverSettings {
        nodes,
        ..SolverSettings::default()
    };
    let r = grow(p, &solver, g, s, &mut keep);
    (keep.0, r)
}

fn settings(integrator: Integrator, rtol: f64) -> GrowthSettings {
    GrowthSettings {
        integrator,
        rtol,
        atol: rtol * 1e-3,
        ..GrowthSettings::default()
    }
}

/// IDA at rtol 1e-8 matches CVODE at rtol 1e-8 in axial length at t = 0.1, 0.2, 0.4, 1 to
/// 1e-5 mm on the const, thick and fibre (D = 200) scenes, N = 501, both thickness laws.
#[test]
fn ida_agrees_with_cvode_on_the_paper_scenes() {
    let scenes = [
        ("const", Thickness::Uniform, 0.0),
        ("thick", Thickness::NonUniform, 0.0),
        ("fibre", Thickness::NonUniform, 200.0),
    ];
    for (name, thickness, d) in scenes {
        for law in [ThicknessLaw::None, ThicknessLaw::Mass] {
            let p = Params {
                thickness,
                d,
                ..Params::default()
            };
            let g = GrowthParams {
                thickness_law: law,
                ..GrowthParams::default()
            };
            let (cv, rc) = run(&p, 501, &g, &settings(Integrator::Cvode, 1e-8));
            let (ida, ri) = run(&p, 501, &g, &settings(Integrator::Ida, 1e-8));
            rc.unwrap();
            let stats = ri.unwrap();
            assert_eq!((cv.len(), ida.len()), (5, 5));
            for (a, b) in cv.iter().zip(&ida).skip(1) {
                assert_eq!(a.t, b.t);
                let diff = (a.axial_length - b.axial_length).abs();
                println!(
                    "{name} {law:?} t = {}: CVODE {:.9} IDA {:.9} (|Δ| {diff:.1e}); IDA steps {}",
                    a.t, a.axial_length, b.axial_length, stats.steps
                );
                assert!(
                    diff < 1e-5,
                    "{name} {law:?} t = {}: CVODE {} vs IDA {}",
                    a.t,
                    a.axial_length,
                    b.axial_length
                );
            }
        }
    }
}

/// The growth cases of TESTING.md (const scene, N = 101, rtol 1e-5) all run with IDA, and
/// end within 1e-3 mm of CVODE's axial length.
#[test]
fn ida_survives_the_growth_extremes() {
    let base = GrowthParams::default();
    let cases: Vec<(&str, GrowthParams)> = vec![
        (
            "eta0 = 0",
            GrowthParams {
                eta0: 0.0,
                ..base.clone()
            },
        ),
        (
            "eta0 = 1e2",
            GrowthParams {
                eta0: 1e2,
                ..base.clone()
            },
        ),
        (
            "eta0 = 1e3",
            GrowthParams {
                eta0: 1e3,
                ..base.clone()
            },
        ),
        (
            "eta0 = 1e4",
            GrowthParams {
                eta0: 1e4,
                ..base.clone()
            },
        ),
        (
            "delta = 0.05",
            GrowthParams {
                delta: 0.05,
                ..base.clone()
            },
        ),
        (
            "delta = 50",
            GrowthParams {
                delta: 50.0,
                ..base.clone()
            },
        ),
        (
            "Gamma = -10",
            GrowthParams {
                gamma: -10.0,
                ..base.clone()
            },
        ),
        (
            "Gamma = 40",
            GrowthParams {
                gamma: 40.0,
                ..base.clone()
            },
        ),
        (
            "t_end = 10",
            GrowthParams {
                t_end: 10.0,
                ..base.clone()
            },
        ),
        (
            "mass law",
            GrowthParams {
                thickness_law: ThicknessLaw::Mass,
                ..base.clone()
            },
        ),
    ];
    let p = Params::default();
    for (name, g) in cases {
        let (ida, ri) = run(&p, 101, &g, &settings(Integrator::Ida, 1e-5));
        let (cv, rc) = run(&p, 101, &g, &settings(Integrator::Cvode, 1e-5));
        let stats = ri.unwrap_or_else(|e| panic!("{name}: IDA failed: {e}"));
        rc.unwrap();
        let (a, b) = (cv.last().unwrap(), ida.last().unwrap());
        assert_eq!(a.t, g.t_end);
        assert_eq!(b.t, g.t_end);
        assert!(b.axial_length.is_finite());
        assert!(
            (a.axial_length - b.axial_length).abs() < 1e-3,
            "{name}: CVODE {} vs IDA {}",
            a.axial_length,
            b.axial_length
        );
        // The growth never shrinks the eye.
        assert!(
            ida.windows(2)
                .all(|w| w[1].axial_length >= w[0].axial_length - 1e-9),
            "{name}: axial length fell"
        );
        assert!(
            stats.steps > 0
                && stats.residual_evaluations >= stats.steps
                && stats.jacobian_evaluations >= 1,
            "{name}: {stats:?}"
        );
    }
}

/// Every linear solver of the Newton matrix gives the same run: the same steps, and the
/// same axial length up to what the Newton iterations leave unconverged (each solver's
/// rounding leads to slightly different iterates; measured 1.4e-9 mm apart at most, against
/// the run's error of 1e-5), far below the tolerance.
#[test]
fn every_linear_solver_gives_the_same_run() {
    let p = Params {
        thickness: Thickness::NonUniform,
        d: 100.0,
        ..Params::default()
    };
    let g = GrowthParams::default();
    let mut results = vec![];
    for lin in DaeLinear::ALL {
        if matches!(lin, DaeLinear::Klu | DaeLinear::SchurKlu)
            && !eyeshell_sundials::klu_available()
        {
            continue;
        }
        let s = GrowthSettings {
            dae_linear: lin,
            ..settings(Integrator::Ida, 1e-6)
        };
        let (rows, r) = run(&p, 101, &g, &s);
        let stats = r.unwrap();
        results.push((lin, stats.steps, rows.last().unwrap().axial_length));
    }
    let (_, steps0, axial0) = results[0];
    for (lin, steps, axial) in &results {
        assert!(
            (axial - axial0).abs() < 5e-9,
            "{lin:?}: {axial} vs {axial0}"
        );
        assert!(
            steps.abs_diff(steps0) <= 2,
            "{lin:?}: {steps} steps vs {steps0}"
        );
    }
}

/// The default reduced solver (block LU of S) gives the band path's run on the const scene
/// at N = 501 (the benches' run) and on the fibre scene, Hermite–Simpson, at N = 101: the
/// same steps, residuals and Newton matrices, and the axial-length series at every output
/// time within 1e-10 mm (the two LUs pivot alike, so only rounding differs).
#[test]
fn the_block_reduced_solver_gives_the_band_paths_run() {
    let fibre = Params {
        thickness: Thickness::NonUniform,
        d: 200.0,
        ..Params::default()
    };
    for (p, nodes) in [(Params::default(), 501), (fibre, 101)] {
        let s = |lin| GrowthSettings {
            dae_linear: lin,
            ..settings(Integrator::Ida, 1e-6)
        };
        assert_eq!(
            s(DaeLinear::SchurBlock).dae_linear,
            GrowthSettings::default().dae_linear
        );
        let g = GrowthParams::default();
        let (block_rows, block) = run(&p, nodes, &g, &s(DaeLinear::SchurBlock));
        let (band_rows, band) = run(&p, nodes, &g, &s(DaeLinear::Schur));
        let (block, band) = (block.unwrap(), band.unwrap());
        assert_eq!(
            (
                block.steps,
                block.residual_evaluations,
                block.jacobian_evaluations
            ),
            (
                band.steps,
                band.residual_evaluations,
                band.jacobian_evaluations
            ),
            "{block:?} vs {band:?}"
        );
        assert_eq!(block_rows.len(), band_rows.len());
        assert!(block_rows.len() >= 4);
        for (a, b) in block_rows.iter().zip(&band_rows) {
            assert_eq!(a.t, b.t);
            assert!(
                (a.axial_length - b.axial_length).abs() <= 1e-10,
                "N = {nodes}, t = {}: {} vs {}",
                a.t,
                a.axial_length,
                b.axial_length
            );
        }
    }
}

/// The default Schur path hands the Newton matrices it cannot eliminate unpivoted to a
/// pivoting solver: with Γ = −10 nothing grows, growth rates barely depend on the growth
/// state, and IDA's long steps leave c I − ∂rates/∂P tiny (measured: 4 of 4 matrices at
/// N = 101). The run is the pivoting solvers' run; on the const scene no matrix falls back.
#[test]
fn the_schur_path_falls_back_to_pivoting_where_it_must() {
    let p = Params::default();
    let s = |lin| GrowthSettings {
        dae_linear: lin,
        ..settings(Integrator::Ida, 1e-6)
    };
    assert_eq!(
        s(DaeLinear::SchurBlock).dae_linear,
        GrowthSettings::default().dae_linear
    );
    let idle = GrowthParams {
        gamma: -10.0,
        ..GrowthParams::default()
    };
    let (rows, r) = run(&p, 101, &idle, &s(DaeLinear::SchurBlock));
    let stats = r.unwrap();
    assert!(stats.linear_fallbacks > 0, "{stats:?}");
    let (band_rows, band) = run(&p, 101, &idle, &s(DaeLinear::Band));
    assert_eq!(band.unwrap().linear_fallbacks, 0);
    let (a, b) = (rows.last().unwrap(), band_rows.last().unwrap());
    assert!(
        (a.axial_length - b.axial_length).abs() < 1e-9,
        "{a:?} vs {b:?}"
    );
    let (_, r) = run(&p, 101, &GrowthParams::default(), &s(DaeLinear::SchurBlock));
    assert_eq!(r.unwrap().linear_fallbacks, 0);
}

/// Fails at its `fail_at`-th snapshot (t = 0 is the first), keeping those before.
struct FailAt {
    kept: Vec<f64>,
    fail_at: usize,
}

impl Observer for FailAt {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), eyeshell_core::growth::ObserverError> {
        if self.kept.len() == self.fail_at {
            // An output's error as the files crate words one (its path, then the cause).
            return Err(Box::new(std::io::Error::other(
                "snapshots: the disk is full",
            )));
        }
        self.kept.push(s.t);
        Ok(())
    }
}

/// A run whose output fails at t = 0.4 stops there with t and the reason, keeps the
/// snapshots at t = 0, 0.1 and 0.2, and reports the work done until then.
#[test]
fn a_failing_ida_run_says_where_and_keeps_what_it_had() {
    let mut obs = FailAt {
        kept: vec![],
        fail_at: 3,
    };
    let solver = SolverSettings {
        nodes: 51,
        ..SolverSettings::default()
    };
    let s = settings(Integrator::Ida, 1e-5);
    let err = grow(
        &Params::default(),
        &solver,
        &GrowthParams::default(),
        &s,
        &mut obs,
    )
    .unwrap_err();
    assert_eq!(obs.kept, vec![0.0, 0.1, 0.2]);
    assert_eq!(err.t, 0.4);
    assert!(err.reason.contains("the disk is full"), "{}", err.reason);
    assert!(
        err.to_string().starts_with("growth failed at t = 0.400000"),
        "{err}"
    );
    assert!(
        err.stats.steps > 0 && err.stats.residual_evaluations > 0 && err.stats.t_reached >= 0.4,
        "{:?}",
        err.stats
    );
}

/// Absurd but finite growth data: rates that overflow fail the evaluation at their point
/// (no NaN reaches the Newton matrix), and the run says so at t = 0 instead of hanging.
#[test]
fn overflowing_rates_fail_cleanly() {
    let solver = SolverSettings {
        nodes: 51,
        ..SolverSettings::default()
    };
    let g = GrowthParams {
        eta0: 1.7e308,
        ..GrowthParams::default()
    };
    let err = grow(
        &Params::default(),
        &solver,
        &g,
        &settings(Integrator::Ida, 1e-5),
        &mut Keep::default(),
    )
    .unwrap_err();
    assert_eq!(err.t, 0.0);
    assert!(
        err.reason
            .contains("the growth rates cannot be evaluated at node"),
        "{}",
        err.reason
    );
}

/// With the stimulus computed from the Atchison 2006 eye (`stimulus.source = "optics"`,
/// traced once before t = 0), the const scene on 51 nodes grows to t = 1 with IDA, CVODE and
/// Euler: IDA and CVODE agree, and the surfaces are the computed ones, not the polynomial.
#[test]
fn the_optics_source_grows_with_every_integrator() {
    use eyeshell_core::model::optics::{OpticsSpec, Source};
    let p = Params::default();
    let optics = GrowthParams {
        source: Source::Optics,
        optics: OpticsSpec {
            focus: 2,
            ..OpticsSpec::default()
        },
        ..GrowthParams::default()
    };
    // Traced once here; every run below shares the traced surfaces.
    let optics = optics.resolved().unwrap().into_owned();
    let last = |integrator, g: &GrowthParams| {
        let s = GrowthSettings {
            steps: 100,
            ..settings(integrator, 1e-7)
        };
        let (rows, r) = run(&p, 51, g, &s);
        r.unwrap();
        *rows.last().unwrap()
    };
    let ida = last(Integrator::Ida, &optics);
    let cvode = last(Integrator::Cvode, &optics);
    let euler = last(Integrator::Euler, &optics);
    let polynomial = last(Integrator::Ida, &GrowthParams::default());
    assert_eq!(ida.t, 1.0);
    assert!(
        (ida.axial_length - cvode.axial_length).abs() < 1e-5,
        "IDA {} vs CVODE {}",
        ida.axial_length,
        cvode.axial_length
    );
    assert!(
        (ida.axial_length - euler.axial_length).abs() < 2e-2,
        "Euler {}",
        euler.axial_length
    );
    // The computed blue surface lies about 0.1 mm in front of the published one on the axis
    // and bends further forward off it: the eye stops growing earlier.
    assert!(
        ida.axial_length < polynomial.axial_length - 0.05,
        "optics {} vs polynomial {}",
        ida.axial_length,
        polynomial.axial_length
    );
}
