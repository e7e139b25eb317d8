//! Forward sensitivities of the growth run through IDAS (docs/MODEL.md §10): against central
//! differences of tight runs.
//!
//! The reference needs a run that is differentiable in the parameters and tight enough
//! that its own error does not swamp the difference. Measured on the const scene (N = 101,
//! relative step 1e-4; BENCHMARKS.md "Forward sensitivities"): with the model's exact
//! [·]⁺ kinks, central differences of rtol-1e-10 runs move by up to 1e-2 relative between
//! steps of 1e-3, 1e-4 and 1e-5 after t ≈ 0.1 (growth switching off point by point makes
//! the run's error jump with p), while IDAS's sensitivities change by 1e-5 between rtol
//! 1e-10 and 1e-12. So the full check rounds the kinks (growth.kink_width = 0.01, the
//! model's own option) and takes the differences of rtol-1e-12 runs; the exact-kink model
//! is checked to t = 0.1, before growth stops anywhere.
//!
//! The differences are not exact either: the reference runs' outputs carry a noise that
//! does not vanish with the step (the t = 0 elastic solve to KINSOL's tolerance, so the
//! references solve it to 1e-12; points switching to the border depth d as they cross
//! φ_max, a discontinuity of the rates no integrator error control removes), so a
//! difference's error grows like noise/h as the step falls. Measured (const, E_b and z_B,
//! t = 0.4 and 1): steps of 1e-4 relative scatter by 1e-4..1e-3 relative (z_B is 0.5 mm:
//! its steps are the smallest), while those of 1e-3 agree with IDAS to 1e-7..1e-6 and IDAS
//! moves by 1e-9 between rtol 1e-10 and 1e-12. The reference is the mean of the differences
//! at relative steps 5e-4 and 2e-3 (truncation O(h²) ≲ 1e-6) ± their spread (its
//! uncertainty, as two samples tell it), and IDAS must lie within 1e-4 relative of that.
//! The spread is at most 3e-4 relative (D on the fibre scene at t = 0.4, where dL/dD
//! changes sign; retina − blue for z_B on the thick scene at t = 0.4, −0.024 as the
//! difference of two near-unit moves: 7e-5 absolute, as in the other columns).

use crate::common::grow;
use eyeshell_core::bvp::settings::SolverSettings;
use eyeshell_core::growth::dae::SensParam;
use eyeshell_core::growth::*;
use eyeshell_core::model::params::{Params, Thickness};

/// Keeps the snapshots' series rows and the sensitivity rows.
#[derive(Default)]
struct Keep {
    series: Vec<SeriesRow>,
    sens: Vec<SensitivityRow>,
}

impl Observer for Keep {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.series.push(s.series);
        Ok(())
    }

    fn sensitivities(&mut self, rows: &[SensitivityRow]) -> Result<(), ObserverError> {
        self.sens.extend_from_slice(rows);
        Ok(())
    }
}

const NODES: usize = 101;

/// The relative steps of the central differences; the reference is their mean ± spread.
const FD_STEPS: [f64; 2] = [5e-4, 2e-3];

fn run(
    p: &Params,
    g: &GrowthParams,
    times: &[f64],
    rtol: f64,
    sens: &[SensParam],
) -> (Keep, GrowthStats) {
    let settings = GrowthSettings {
        rtol,
        atol: rtol * 1e-3,
        output_times: times.to_vec(),
        sensitivities: sens.to_vec(),
        ..GrowthSettings::default()
    };
    let solver = SolverSettings {
        nodes: NODES,
        newton_tol: 1e-12,
        ..SolverSettings::default()
    };
    let mut keep = Keep::default();
    let stats = grow(p, &solver, g, &settings, &mut keep).expect("the run succeeds");
    (keep, stats)
}

/// The model (`p`, `g`) with `param` set to `v`.
fn with(p: &Params, g: &GrowthParams, param: SensParam, v: f64) -> (Params, GrowthParams) {
    let (mut p, mut g) = (*p, g.clone());
    param.set(&mut p, &mut g, v);
    (p, g)
}

/// The parameters a scene of `p` takes sensitivities to: all eight, fibres.D only with fibres.
fn params_of(p: &Params) -> Vec<SensParam> {
    SensParam::ALL
        .into_iter()
        .filter(|s| s.check(p).is_ok())
        .collect()
}

/// The sensitivities of a rtol-1e-10 run of `g` at t = 0 and `times` against central
/// differences of rtol-`fd_rtol` runs at the relative steps [`FD_STEPS`]: every column
/// within `tol` relative of the differences' mean ± their spread (of the derivative's own
/// size, or 1e-3 of the row's largest where one is near zero, or a scaled sensitivity
/// (p/L) dL/dp of 1e-6, below which a parameter does not move the eye).
fn check(
    name: &str,
    p: &Params,
    g: &GrowthParams,
    params: &[SensParam],
    times: &[f64],
    fd_rtol: f64,
    tol: f64,
) {
    let np = params.len();
    let (keep, stats) = run(p, g, times, 1e-10, params);
    let work = stats
        .sensitivities
        .expect("the sensitivities' work is recorded");
    assert!(work.residual_evaluations > 0 && !work.error_control);
    assert_eq!(keep.sens.len(), np * (times.len() + 1));
    // At t = 0 nothing has grown: every sensitivity to η0, Γ, δ is zero (the others move
    // the t = 0 equilibrium and are checked there too).
    for (row, param) in keep.sens[..np].iter().zip(params) {
        assert_eq!(row.parameter, param.key());
        if param.is_growth() {
            assert_eq!(row.d_axial_length, 0.0, "{name} {}", param.key());
        }
    }
    let all_times: Vec<f64> = std::iter::once(0.0).chain(times.iter().copied()).collect();
    for (j, &param) in params.iter().enumerate() {
        let p0 = param.value(p, g);
        let diffs: Vec<Vec<[f64; 3]>> = FD_STEPS
            .iter()
            .map(|&step| {
                let h = step * p0.abs();
                let up = with(p, g, param, p0 + h);
                let down = with(p, g, param, p0 - h);
                let (plus, _) = run(&up.0, &up.1, times, fd_rtol, &[]);
                let (minus, _) = run(&down.0, &down.1, times, fd_rtol, &[]);
                (0..all_times.len())
                    .map(|k| {
                        let (a, b) = (&plus.series[k], &minus.series[k]);
                        assert_eq!(a.t, all_times[k]);
                        [
                            (a.axial_length - b.axial_length) / (2.0 * h),
                            (a.equatorial_radius - b.equatorial_radius) / (2.0 * h),
                            (a.retina_minus_blue - b.retina_minus_blue) / (2.0 * h),
                        ]
                    })
                    .collect()
            })
            .collect();
        for (k, &t) in all_times.iter().enumerate() {
            if t == 0.0 && param.is_growth() {
                continue;
            }
            let row = &keep.sens[np * k + j];
            assert_eq!((row.t, row.parameter), (t, param.key()));
            let ours = [
                row.d_axial_length,
                row.d_equatorial_radius,
                row.d_retina_minus_blue,
            ];
            let span = |c: usize| {
                diffs
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                        (lo.min(d[k][c]), hi.max(d[k][c]))
                    })
            };
            let scale = (0..3).fold(0.0_f64, |m, c| m.max(span(c).1.abs()));
            let unmoved = 1e-6 * row.axial_length / p0.abs();
            for (c, &v) in ours.iter().enumerate() {
                let (lo, hi) = span(c);
                let mid = 0.5 * (lo + hi);
                // The reference is uncertain by about the spread of its two differences.
                let outside = ((v - mid).abs() - (hi - lo)).max(0.0);
                let err = outside / mid.abs().max(1e-3 * scale).max(unmoved);
                println!(
                    "{name} {} t = {t} [{c}]: IDAS {v:.9e} FD {lo:.9e} .. {hi:.9e} rel {err:.1e}",
                    param.key(),
                );
                assert!(
                    err < tol,
                    "{name} {} t = {t} column {c}: IDAS {v} vs central differences {lo} .. {hi}",
                    param.key(),
                );
            }
        }
    }
}

/// d(axial length)/dp, d(equatorial radius)/dp and d(retina − blue)/dp for every
/// parameter (η0, Γ, δ, C, E_b, ΔP, z_B, and D on the fibre scene) agree with central
/// differences to 1e-4 at t = 0.1, 0.4, 1 (and at t = 0 for those that move the t = 0
/// equilibrium) on the const, thick and fibre scenes (N = 101, rounded kinks: see the
/// module comment). The scenes run in threads of their own.
#[test]
fn sensitivities_match_central_differences() {
    let scenes = [
        ("const", Thickness::Uniform, 0.0),
        ("thick", Thickness::NonUniform, 0.0),
        ("fibre", Thickness::NonUniform, 200.0),
    ];
    std::thread::scope(|scope| {
        for (name, thickness, d) in scenes {
            scope.spawn(move || {
                let p = Params {
                    thickness,
                    d,
                    ..Params::default()
                };
                let g = GrowthParams {
                    kink_width: 0.01,
                    ..GrowthParams::default()
                };
                check(name, &p, &g, &params_of(&p), &[0.1, 0.4, 1.0], 1e-12, 1e-4);
            });
        }
    });
}

/// With the model's exact kinks, to t = 0.1 (before growth stops anywhere), against
/// rtol-1e-10 differences: 1e-4 too, for η0, Γ, δ.
#[test]
fn sensitivities_of_the_exact_kink_model_match_early() {
    let g = GrowthParams {
        t_end: 0.1,
        ..GrowthParams::default()
    };
    check(
        "const exact",
        &Params::default(),
        &g,
        &[SensParam::Eta0, SensParam::Gamma, SensParam::Delta],
        &[0.05, 0.1],
        1e-10,
        1e-4,
    );
}

/// A parameter whose value is 0 (Γ at the pole, the blue surface through z = 0) still has
/// its sensitivity under IDAS's control: the weights are 1/(rtol |s| + atol/|p̄|), and a
/// scale |p̄| = |p| = 0 made them vanish, so the sensitivity passed its Newton test
/// uncorrected (∂L/∂z_B was 0.21 instead of 0.96, ∂L/∂ΔP at ΔP = 0 −1e7). Against central
/// differences with an absolute step of 1e-3 at t = 1.
#[test]
fn a_parameter_at_zero_keeps_its_sensitivity_controlled() {
    let p = Params::default();
    let mut g = GrowthParams {
        gamma: 0.0,
        ..GrowthParams::default()
    };
    g.blue.z_b = 0.0;
    let params = [SensParam::Gamma, SensParam::BlueCentre];
    let length_at_end = |param: SensParam, v: f64| {
        let (p, g) = with(&p, &g, param, v);
        let (keep, _) = run(&p, &g, &[1.0], 1e-9, &[]);
        keep.series
            .last()
            .expect("a snapshot at t = 1")
            .axial_length
    };
    let (keep, _) = run(&p, &g, &[1.0], 1e-9, &params);
    for param in params {
        let row = keep
            .sens
            .iter()
            .find(|r| r.parameter == param.key() && r.t == 1.0)
            .expect("a row at t = 1");
        let h = 1e-3;
        let fd = (length_at_end(param, h) - length_at_end(param, -h)) / (2.0 * h);
        let rel = (row.d_axial_length - fd).abs() / fd.abs();
        assert!(
            rel < 1e-3,
            "{}: IDAS {} against the difference {fd} ({rel:.1e} relative)",
            param.key(),
            row.d_axial_length
        );
    }
}

/// Error control on the sensitivities (IDASetSensErrCon) on the exact-kink model: the runs
/// finish at every rtol, and the sensitivities converge with it. The error test leaves out
/// the border d (its sensitivity jumps whenever the pair of points bracketing the crossing
/// of φ_max changes; with d in the test the step collapsed to 1e-314 at t = 0.053 at rtol
/// 1e-8). Measured (const, N = 101, η0, Γ, δ, C; the largest over the parameters of
/// max_t |∂L/∂p − ref| / max_t |ref|, ref at rtol 1e-10 with error control): 1.2e-4 at
/// rtol 1e-6, 1.3e-6 at 1e-8; without error control 3.7e-3, 4.5e-4 and 1.9e-4 at rtol 1e-6,
/// 1e-8 and 1e-10 (BENCHMARKS.md, "Error control and accuracy"); for this test's η0 and Γ,
/// 1.5e-4 and 2.0e-6.
#[test]
fn sensitivity_error_control_converges_with_rtol() {
    let params = [SensParam::Eta0, SensParam::Gamma];
    let times = [0.1, 0.2, 0.4, 1.0];
    let run_controlled = |rtol: f64| {
        let settings = GrowthSettings {
            rtol,
            atol: rtol * 1e-2,
            output_times: times.to_vec(),
            sensitivities: params.to_vec(),
            sensitivity_error_control: true,
            ..GrowthSettings::default()
        };
        let solver = SolverSettings {
            nodes: NODES,
            ..SolverSettings::default()
        };
        let mut keep = Keep::default();
        let stats = grow(
            &Params::default(),
            &solver,
            &GrowthParams::default(),
            &settings,
            &mut keep,
        )
        .unwrap_or_else(|e| panic!("rtol {rtol:e}: {e}"));
        assert!(stats.sensitivities.expect("recorded").error_control);
        keep.sens
    };
    let reference = run_controlled(1e-10);
    let error = |rows: &[SensitivityRow]| {
        params
            .iter()
            .map(|param| {
                let of = |rs: &[SensitivityRow]| -> Vec<f64> {
                    rs.iter()
                        .filter(|r| r.parameter == param.key())
                        .map(|r| r.d_axial_length)
                        .collect()
                };
                let (got, want) = (of(rows), of(&reference));
                assert_eq!(got.len(), times.len() + 1);
                let scale = want.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                got.iter()
                    .zip(&want)
                    .map(|(a, b)| (a - b).abs() / scale)
                    .fold(0.0_f64, f64::max)
            })
            .fold(0.0_f64, f64::max)
    };
    let (e6, e8) = (error(&run_controlled(1e-6)), error(&run_controlled(1e-8)));
    assert!(e6 < 5e-4, "rtol 1e-6: {e6:.1e}");
    assert!(e8 < 1e-5, "rtol 1e-8: {e8:.1e}");
    assert!(
        e8 < e6 / 20.0,
        "no convergence: {e6:.1e} at rtol 1e-6, {e8:.1e} at 1e-8"
    );
}

/// Error control on the sensitivities to the model's parameters with rounded kinks, at
/// tight tolerances (material.C, growth.kink_width 0.05 and 0.2, rtol 1e-9 … 1e-11): the
/// algebraic s'(0) that seeds IDAS's first predictor must hold the second-order terms, or
/// the first step fails its error test down to h = 1e-13. Runs to t = 0.05 (the
/// failure was at t = 0) start, and agree across rtol.
#[test]
fn error_control_starts_at_tight_rtol_for_the_models_parameters() {
    let params = [SensParam::Modulus, SensParam::Bending, SensParam::Pressure];
    for kink_width in [0.05, 0.2] {
        let g = GrowthParams {
            kink_width,
            t_end: 0.05,
            ..GrowthParams::default()
        };
        let run_controlled = |rtol: f64| {
            let settings = GrowthSettings {
                rtol,
                atol: 1e-8,
                output_times: vec![0.05],
                sensitivities: params.to_vec(),
                sensitivity_error_control: true,
                ..GrowthSettings::default()
            };
            let solver = SolverSettings {
                nodes: NODES,
                ..SolverSettings::default()
            };
            let mut keep = Keep::default();
            let stats = grow(&Params::default(), &solver, &g, &settings, &mut keep)
                .unwrap_or_else(|e| panic!("kink {kink_width}, rtol {rtol:e}: {e}"));
            assert!(stats.sensitivities.expect("recorded").error_control);
            keep.sens
        };
        let (loose, tight) = (run_controlled(1e-9), run_controlled(1e-11));
        assert_eq!(loose.len(), 2 * params.len());
        for (a, b) in loose.iter().zip(&tight).skip(params.len()) {
            let rel = (a.d_axial_length - b.d_axial_length).abs() / b.d_axial_length.abs();
            println!(
                "kink {kink_width}, {}: dL/dp {:.9e} (rtol 1e-9) vs {:.9e} (1e-11): {rel:.1e}",
                a.parameter, a.d_axial_length, b.d_axial_length
            );
            assert!(rel < 1e-6, "{}: {rel:.1e}", a.parameter);
        }
    }
}

/// ∂L/∂Γ at t = 1 on the const scene with fibres (D = 100): the central difference of
/// `eyeshell grow scenes/const.toml --set fibres.D=100 --set growth.Gamma=8±0.2` on N = 801
/// at rtol 1e-8 (atol 1e-10): 4.31428e-3. On N = 1601 at rtol 1e-9, 4.31380e-3; with the
/// step 0.1, 4.31659e-3 (its run noise over a smaller step): the spread is the larger gap.
const GAMMA_FD: f64 = 4.3143e-3;
const GAMMA_FD_SPREAD: f64 = 3e-6;

/// `solver.tol` with sensitivities (docs/guide/accuracy.md, "Growth"): the sensitivities
/// are estimated from the same round's runs and bounded as p·∂y/∂p ≤ tol (mm). On the
/// const scene with fibres at tol 3e-3, the sensitivities choose the mesh (217 nodes against
/// the 63 that the lengths alone need), ∂L/∂Γ at t = 1 lies within tol/Γ of the central
/// difference (0.0042734 against 0.0043143), the estimate is within tol and not below a
/// third of that error. At tol 1e-3 (505 nodes) the same checks took 22 s of CPU; at 3e-3,
/// about 3 s.
#[test]
fn solver_tol_bounds_the_sensitivities() {
    let tol = 3e-3;
    let params = Params {
        d: 100.0,
        ..Params::default()
    };
    let growth = GrowthParams::default();
    let settings = GrowthSettings {
        sensitivities: vec![SensParam::Gamma],
        ..GrowthSettings::default()
    };
    let solver = SolverSettings {
        tol: Some(tol),
        ..SolverSettings::default()
    };
    let mut keep = Keep::default();
    let stats = grow(&params, &solver, &growth, &settings, &mut keep).unwrap();
    // The mesh the lengths alone need at this tol: the sensitivities must ask for more.
    let lengths_only = grow(
        &params,
        &solver,
        &growth,
        &GrowthSettings::default(),
        &mut Keep::default(),
    )
    .unwrap();
    let nodes = |s: &eyeshell_core::growth::GrowthStats| s.accuracy.as_ref().map(|a| a.nodes);
    assert!(
        nodes(&stats) > nodes(&lengths_only),
        "{:?} nodes for the sensitivities, {:?} for the lengths",
        nodes(&stats),
        nodes(&lengths_only)
    );
    let estimate = stats
        .error_estimate
        .expect("solver.tol estimates the error");
    let [s] = estimate.sensitivities.as_slice() else {
        panic!("one sensitivity estimate: {:?}", estimate.sensitivities)
    };
    // Core names the parameter by its symbol (the scene layer maps it to growth.Gamma).
    assert_eq!(s.parameter, "Γ");
    assert_eq!(s.value, growth.gamma);
    assert!(s.scaled().total <= tol, "{s:?}");
    assert!(estimate.bounded().total <= tol, "{estimate:?}");
    let last = keep.sens.last().expect("sensitivity rows");
    assert_eq!((last.t, last.parameter), (1.0, "Γ"));
    let error = (last.d_axial_length - GAMMA_FD).abs();
    println!(
        "∂L/∂Γ {} against {GAMMA_FD}: error {error:e}, estimate {:?}, {:?}",
        last.d_axial_length, s.d_axial_length, stats.accuracy
    );
    assert!(
        growth.gamma * error <= tol - growth.gamma * GAMMA_FD_SPREAD,
        "∂L/∂Γ {} against {GAMMA_FD}",
        last.d_axial_length
    );
    assert!(
        s.d_axial_length.total >= (error - GAMMA_FD_SPREAD) / 3.0,
        "estimate {:?} against the error {error:e}",
        s.d_axial_length
    );
}
