//! The coupled growth DAE's analytic Newton matrix ∂F/∂y + c ∂F/∂y' against central
//! differences of its residual, at grown, off-equilibrium states: both schemes,
//! with and without fibres, both thickness laws.

use eyeshell_core::bvp::settings::{Scheme, SolverSettings};
use eyeshell_core::growth::dae::CoupledDae;
use eyeshell_core::growth::system::GrowthSystem;
use eyeshell_core::growth::{GrowthParams, ThicknessLaw};
use eyeshell_core::model::params::{Params, Thickness};

/// A state of the coupled system away from equilibrium and from the kinks: the consistent
/// start, grown a little (ρ, γ_s up by a smooth profile) and its elastic unknowns shifted.
fn grown_state(dae: &mut CoupledDae, seed: u64) -> Vec<f64> {
    let mut y = dae.initial_state().unwrap();
    let n_p = dae.differential_len();
    let mut s = seed;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    for k in 0..n_p {
        y[k] *= 1.0 + 0.002 * (1.0 + rnd());
    }
    for v in y[n_p..].iter_mut() {
        *v *= 1.0 + 1e-4 * rnd();
    }
    y
}

fn check(p: Params, solver: SolverSettings, g: GrowthParams, seed: u64) {
    let sys = GrowthSystem::new(&p, &solver, &g).unwrap();
    let mut dae = CoupledDae::new(sys);
    let y = grown_state(&mut dae, seed);
    let n = dae.len();
    let n_p = dae.differential_len();
    let c = 37.5;
    dae.assemble(c, &y).unwrap();
    let jac = dae.matrix().clone();
    let yp = vec![0.0; n];
    // Steps relative to each unknown's typical size (θ and q_s vanish at the pole).
    let typical: Vec<f64> = dae
        .abs_tolerances(1.0, 0.0, p.r0)
        .into_iter()
        .enumerate()
        .map(|(k, t)| if k < n_p { y[k].abs().max(1.0) } else { t })
        .collect();
    let mut differences = |j: usize, h: f64| {
        let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
        let (mut yu, mut yd) = (y.clone(), y.clone());
        yu[j] += h;
        yd[j] -= h;
        dae.residual(&yu, &yp, &mut rp).unwrap();
        dae.residual(&yd, &yp, &mut rm).unwrap();
        (0..n)
            .map(|i| (rp[i] - rm[i]) / (2.0 * h) + if i == j && j < n_p { c } else { 0.0 })
            .collect::<Vec<f64>>()
    };
    // The size of the terms of row i, Σ_j |J_ij| |y_j|: the scale of its round-off.
    let terms: Vec<f64> = (0..n)
        .map(|i| {
            let (cols, vals) = (
                jac.row_ptr()[i]..jac.row_ptr()[i + 1],
                &jac.values()[jac.row_ptr()[i]..jac.row_ptr()[i + 1]],
            );
            cols.zip(vals)
                .map(|(k, v)| v.abs() * y[jac.col_idx()[k]].abs().max(typical[jac.col_idx()[k]]))
                .sum()
        })
        .collect();
    let mut worst = (0.0f64, 0, 0, 0.0, 0.0);
    for j in 0..n {
        let h = 1e-6 * y[j].abs().max(typical[j]);
        let (fd, fd2) = (differences(j, h), differences(j, 2.0 * h));
        for i in 0..n {
            let an = jac.get(i, j);
            // A wrong entry shows as differences that agree with each other (steps h, 2h),
            // not with it; their spread bounds their own error (round-off, inversions).
            let spread = 4.0 * (fd[i] - fd2[i]).abs();
            let noise = 64.0 * f64::EPSILON * terms[i] / h;
            let err = (an - fd[i]).abs() / (1e-5 * an.abs().max(fd[i].abs()) + noise + spread);
            if err > worst.0 {
                worst = (err, i, j, an, fd[i]);
            }
        }
    }
    let (err, i, j, an, fd) = worst;
    assert!(err < 1.0, "{:?} {:?} D={} law {:?}: row {i} col {j} (n_p {n_p}, n {n}): analytic {an} vs differences {fd}", solver.scheme, p.thickness, p.d, g.thickness_law);
}

#[test]
fn newton_matrix_matches_differences() {
    let mut seed = 1;
    for scheme in [Scheme::HermiteSimpson, Scheme::Trapezoid] {
        for (thickness, d) in [
            (Thickness::Uniform, 0.0),
            (Thickness::NonUniform, 200.0),
            (Thickness::NonUniform, 0.0),
        ] {
            for law in [ThicknessLaw::None, ThicknessLaw::Mass] {
                let p = Params {
                    thickness,
                    d,
                    ..Params::default()
                };
                let s = SolverSettings {
                    nodes: 21,
                    scheme,
                    ..SolverSettings::default()
                };
                let g = GrowthParams {
                    thickness_law: law,
                    ..GrowthParams::default()
                };
                check(p, s, g, seed);
                seed += 1;
            }
        }
    }
    // The rounded kinks (growth.kink_width), whose slopes are no longer 0 or 1.
    let p = Params {
        thickness: Thickness::NonUniform,
        d: 100.0,
        ..Params::default()
    };
    let s = SolverSettings {
        nodes: 21,
        ..SolverSettings::default()
    };
    check(
        p,
        s,
        GrowthParams {
            kink_width: 0.05,
            ..GrowthParams::default()
        },
        seed,
    );
}

/// With the stimulus computed from a schematic eye (`stimulus.source = "optics"`), the
/// Newton matrix reads the spline's exact derivative R′(φ): it matches differences too, on
/// both sides of the computed surface's φ_max (the crossing rule beyond it).
#[test]
fn newton_matrix_matches_differences_with_computed_surfaces() {
    use eyeshell_core::model::optics::{OpticsSpec, Source};
    let g = GrowthParams {
        source: Source::Optics,
        optics: OpticsSpec {
            // sagittal: the published surface's criterion; 20 fields keep the test quick.
            focus: 2,
            max_field: 20.0,
            ..OpticsSpec::default()
        },
        ..GrowthParams::default()
    };
    let g = g.resolved().unwrap().into_owned();
    let phi_max = g.blue_focal().phi_max();
    assert!(phi_max > 0.2 && phi_max < 0.3, "{phi_max}");
    for scheme in [Scheme::HermiteSimpson, Scheme::Trapezoid] {
        let s = SolverSettings {
            nodes: 21,
            scheme,
            ..SolverSettings::default()
        };
        check(Params::default(), s, g.clone(), 40);
    }
}

/// Every built-in growth rule's drive enters the Newton matrix through its exact partials
/// (docs/MODEL.md §6, "Growth rules"): the defocus rule through the dioptre conversion and
/// both of its gains, the chromatic one through both surfaces. The blue surface is moved
/// forward so that the retina lies between blue and red (the chromatic rule's proportional
/// band) and sees defocus of both signs across the meridian. Over an integrated region the
/// border row is the average's partials in every point inside it.
#[test]
fn newton_matrix_matches_differences_for_every_rule() {
    use eyeshell_core::model::rule::{Region, CATALOGUE};
    use eyeshell_core::model::stimulus::{Surface, RED_OFFSET};
    let blue = Surface {
        z_b: Surface::blue().z_b - 3.5,
        ..Surface::blue()
    };
    let red = Surface {
        offset: RED_OFFSET,
        ..blue
    };
    for (rule, name) in CATALOGUE.iter().enumerate() {
        let mut g = GrowthParams {
            blue,
            red,
            ..GrowthParams::default()
        };
        g.stimulus.set_keys(|k| {
            k.rule = rule;
            k.baseline = 0.1;
            k.hyperopic_gain = 0.3;
            k.myopic_gain = 0.6;
            k.chromatic_gain = 0.8;
        });
        assert_eq!(g.stimulus.rule().name(), *name);
        for region in [Region::Local, Region::Integrated] {
            g.stimulus.region = region;
            for scheme in [Scheme::HermiteSimpson, Scheme::Trapezoid] {
                let s = SolverSettings {
                    nodes: 21,
                    scheme,
                    ..SolverSettings::default()
                };
                check(Params::default(), s, g.clone(), 60 + rule as u64);
            }
        }
    }
}

/// Through a dual-focus contact lens the defocus rule reads both images, each with its
/// share of the light: the Newton matrix carries the shares' slopes in φ too.
#[test]
fn newton_matrix_matches_differences_through_two_images() {
    use eyeshell_core::model::eyewear::{LensSpec, ProfileSpec};
    use eyeshell_core::model::optics::{OpticsSpec, Source};
    let mut g = GrowthParams {
        source: Source::Optics,
        optics: OpticsSpec {
            focus: 2,
            max_field: 20.0,
            lenses: vec![LensSpec {
                kind: 1,
                vertex: 0.0,
                profile: ProfileSpec::Zones(vec![(1.0, -2.0), (1.6, 0.0), (2.3, -2.0), (7.0, 0.0)]),
                lenslets: vec![],
                prescribe: None,
            }],
            ..OpticsSpec::default()
        },
        ..GrowthParams::default()
    };
    g.stimulus.set_keys(|k| {
        k.rule = 1;
        k.baseline = 0.1;
        k.myopic_gain = 0.6;
    });
    let g = g.resolved().unwrap().into_owned();
    let images = &g.computed.as_ref().unwrap().images;
    assert_eq!(images.len(), 2);
    let s = SolverSettings {
        nodes: 21,
        ..SolverSettings::default()
    };
    check(Params::default(), s, g.clone(), 70);
}
