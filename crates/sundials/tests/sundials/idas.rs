//! Forward sensitivities through IDAS: exact solutions, the panic guard, bad input.

use eyeshell_sundials::*;

/// y' = −p y and z = y² (algebraic), p = 1: F = (y' + p y, z − y²). Sensitivities:
/// s_y = −t e^{−t}, s_z = 2 y s_y.
struct Decay {
    panic_in_sensitivities: bool,
}

impl DaeSystem for Decay {
    fn residual(&mut self, _t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        r[0] = yp[0] + y[0];
        r[1] = y[1] - y[0] * y[0];
        Ok(())
    }

    fn sensitivity_residual(
        &mut self,
        _t: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        ys: &[&[f64]],
        yps: &[&[f64]],
        rs: &mut [&mut [f64]],
    ) -> CallbackResult {
        if self.panic_in_sensitivities {
            panic!("sensitivity residual exploded");
        }
        rs[0][0] = yps[0][0] + ys[0][0] + y[0];
        rs[0][1] = ys[0][1] - 2.0 * y[0] * ys[0][0];
        Ok(())
    }
}

fn decay(panic_in_sensitivities: bool) -> Ida<Decay> {
    let options = IdaOptions {
        rtol: 1e-10,
        atol: 1e-12,
        id: Some(vec![1.0, 0.0]),
        ..IdaOptions::default()
    };
    let linear = IdaLinearSolver::Dense {
        user_jacobian: false,
    };
    let system = Decay {
        panic_in_sensitivities,
    };
    Ida::new(system, 0.0, &[1.0, 1.0], &[-1.0, 0.0], linear, &options).unwrap()
}

fn options(error_control: bool) -> SensitivityOptions {
    SensitivityOptions {
        error_control,
        scales: vec![1.0],
    }
}

#[test]
fn sensitivities_of_a_dae_match_the_exact_ones() {
    for error_control in [true, false] {
        let mut ida = decay(false);
        ida.init_sensitivities(
            &[vec![0.0, 0.0]],
            &[vec![-1.0, 0.0]],
            &options(error_control),
        )
        .unwrap();
        let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
        let mut s = vec![vec![0.0; 2]];
        for tout in [0.5, 1.0, 2.0] {
            let t = ida.advance_to(tout, &mut y, &mut yp).unwrap();
            ida.sensitivities_at(t, &mut s).unwrap();
            let sy = -t * (-t).exp();
            let sz = 2.0 * (-t).exp() * sy;
            let (ey, ez) = ((s[0][0] - sy).abs(), (s[0][1] - sz).abs());
            assert!(
                ey < 1e-8 && ez < 1e-8,
                "t = {t}: {:?} vs ({sy}, {sz})",
                s[0]
            );
        }
        let stats = ida.sensitivity_stats();
        assert!(stats.residual_evaluations > 0, "{stats:?}");
        assert_eq!(
            stats.state_residual_evaluations, 0,
            "our residual, not IDAS's quotients"
        );
        assert_eq!(ida.sensitivity_count(), 1);
    }
}

#[test]
fn a_panicking_sensitivity_residual_is_an_error_not_an_abort() {
    let mut ida = decay(true);
    ida.init_sensitivities(&[vec![0.0, 0.0]], &[vec![-1.0, 0.0]], &options(true))
        .unwrap();
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    let e = ida
        .advance_to(1.0, &mut y, &mut yp)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sensitivity_residual panicked: sensitivity residual exploded"),
        "{e}"
    );
}

#[test]
fn bad_sensitivity_input_is_refused() {
    let mut ida = decay(false);
    /// s(0), s'(0), the scales, and what the refusal says.
    type Case<'a> = (&'a [Vec<f64>], &'a [Vec<f64>], Vec<f64>, &'a str);
    let cases: [Case; 4] = [
        (&[], &[], vec![], "need the same number, ≥ 1"),
        (
            &[vec![0.0]],
            &[vec![0.0]],
            vec![1.0],
            "has length 1, expected 2",
        ),
        (
            &[vec![0.0; 2]],
            &[vec![0.0; 2]],
            vec![0.0],
            "must be positive and finite",
        ),
        (&[vec![0.0; 2]], &[vec![0.0; 2]], vec![1.0, 2.0], "2 scales"),
    ];
    for (ys, yps, scales, needle) in cases {
        let o = SensitivityOptions {
            error_control: false,
            scales,
        };
        let e = ida.init_sensitivities(ys, yps, &o).unwrap_err().to_string();
        assert!(e.contains(needle), "{needle:?} not in {e}");
    }
    let mut s = vec![vec![0.0; 2]];
    let e = ida.sensitivities_at(0.0, &mut s).unwrap_err().to_string();
    assert!(e.contains("no sensitivities"), "{e}");
}
