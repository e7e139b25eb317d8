//! Elastic solve timings (the shell at equilibrium). Run with
//!   cargo bench --bench elastic
//! and the interleaved fibres-or-not comparison with
//!   EYESHELL_INTERLEAVED=1 cargo bench --bench elastic -- components
//! The linear solvers side by side (band, klu, block):
//!   cargo bench --bench elastic -- "factor_and_solve|solve_by_nodes"
//! Figures go in BENCHMARKS.md.

use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};
use eyeshell::bvp::discretisation::{LOWER, NY, POLE_ROWS, UPPER};
use eyeshell::bvp::settings::{LinearSolverKind, Scheme, SolverSettings};
use eyeshell::bvp::solve::{discretise, linear_spec, sphere_guess};
use eyeshell::bvp::{self};
use eyeshell::model::params::{Params, Thickness};
use eyeshell_linalg::{AbdLu, BandLu};
use eyeshell_sundials::{Context, LinearSolver, MatrixSink, NVector};
use std::hint::black_box;
use std::time::Duration;

/// The binary's allocator (src/main.rs), so that the figures are what `eyeshell` gets.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn fibre_shell() -> Params {
    Params {
        thickness: Thickness::NonUniform,
        d: 200.0,
        ..Params::default()
    }
}

fn settings(nodes: usize) -> SolverSettings {
    SolverSettings {
        nodes,
        scheme: Scheme::HermiteSimpson,
        newton_tol: 1e-10,
        ..SolverSettings::default()
    }
}

/// One cold and one warm-started solve of the fibre shell at N = 501, order 4.
fn cold_and_warm(c: &mut Criterion) {
    let p = fibre_shell();
    let s = settings(501);
    let mut g = c.benchmark_group("fibre_shell_n501_hs");
    g.bench_function("cold", |b| {
        b.iter(|| bvp::solve(black_box(&p), &s, None).unwrap())
    });
    // Warm: the previous solution at a 1 % higher pressure, as in a continuation or a growth step.
    let near = bvp::solve(
        &Params {
            dp: p.dp * 1.01,
            ..p
        },
        &s,
        None,
    )
    .unwrap();
    g.bench_function("warm", |b| {
        b.iter(|| bvp::solve(black_box(&p), &s, Some(&near)).unwrap())
    });
    g.finish();
}

const LINEAR: [(&str, LinearSolverKind); 3] = [
    ("band", LinearSolverKind::Band),
    ("klu", LinearSolverKind::Klu),
    ("block", LinearSolverKind::Block),
];

/// Cost per node: cold and warm solves over N from 51 to 20001 with each linear solver
/// (linear in N if the band holds). Warm: from the solution at a 1 % higher pressure.
fn scaling(c: &mut Criterion) {
    let p = fibre_shell();
    for warm in [false, true] {
        let mut g = c.benchmark_group(if warm {
            "warm_solve_by_nodes"
        } else {
            "cold_solve_by_nodes"
        });
        g.sample_size(10);
        g.warm_up_time(Duration::from_secs(1));
        g.measurement_time(Duration::from_secs(3));
        for n in [51usize, 101, 501, 2001, 20001] {
            for (name, linear) in LINEAR {
                let s = SolverSettings {
                    linear,
                    ..settings(n)
                };
                let near = warm.then(|| {
                    bvp::solve(
                        &Params {
                            dp: p.dp * 1.01,
                            ..p
                        },
                        &s,
                        None,
                    )
                    .unwrap()
                });
                g.throughput(Throughput::Elements(n as u64));
                g.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                    b.iter(|| bvp::solve(black_box(&p), &s, near.as_ref()).unwrap())
                });
            }
        }
        g.finish();
    }
}

/// The linear algebra of one Newton iteration alone: factorisation and one solve of the
/// fibre shell's Jacobian at its solution, N = 101 … 20001, by SUNDIALS' band LU, KLU, the
/// almost-block-diagonal LU (through the same SUNDIALS ops KINSOL calls) and the crate's
/// safe-Rust band LU. SUNDIALS' band LU factors in place, so each iteration first copies
/// the assembled matrix back (`band_copy` times that copy alone); KLU and the crate's LUs
/// keep the matrix and factor from it (into the last factors' storage).
fn factor_and_solve(c: &mut Criterion) {
    let p = fibre_shell();
    let mut g = c.benchmark_group("factor_and_solve");
    g.warm_up_time(Duration::from_secs(1));
    g.measurement_time(Duration::from_secs(3));
    for n in [101usize, 501, 2001, 20001] {
        let s = settings(n);
        let sol = bvp::solve(&p, &s, None).unwrap();
        let mut disc = discretise(&p, &s).unwrap();
        let m = disc.len();
        let b: Vec<f64> = (0..m).map(|i| (0.3 * i as f64).sin()).collect();
        let ctx = Context::new().unwrap();
        g.throughput(Throughput::Elements(n as u64));
        for (name, linear) in LINEAR {
            let spec = linear_spec(&disc, linear);
            let (mut a, mut ls) = LinearSolver::for_spec(&ctx, m, &spec).unwrap();
            disc.jacobian(&sol.u, &mut a.view_mut()).unwrap();
            let (mut saved, _) = LinearSolver::for_spec(&ctx, m, &spec).unwrap();
            saved.copy_from(&a).unwrap();
            let rhs = NVector::from_slice(&ctx, &b).unwrap();
            let mut x = NVector::new(&ctx, m).unwrap();
            let in_place = linear == LinearSolverKind::Band;
            g.bench_with_input(BenchmarkId::new(name, n), &n, |bch, _| {
                bch.iter(|| {
                    if in_place {
                        a.copy_from(&saved).unwrap();
                    }
                    ls.setup(&mut a).unwrap();
                    ls.solve(&mut a, &mut x, &rhs).unwrap();
                    black_box(x.as_slice()[0])
                })
            });
            if in_place {
                g.bench_with_input(BenchmarkId::new("band_copy", n), &n, |bch, _| {
                    bch.iter(|| a.copy_from(black_box(&saved)).unwrap())
                });
            }
        }
        let mut own = BandLu::new(m, LOWER, UPPER).unwrap();
        disc.jacobian(&sol.u, &mut own).unwrap();
        let mut own_factors = own.factor().ok();
        let mut x = b.clone();
        g.bench_with_input(BenchmarkId::new("band_rust", n), &n, |bch, _| {
            bch.iter(|| {
                let f = own.factor_reusing(own_factors.take()).unwrap();
                x.copy_from_slice(&b);
                f.solve_in_place(&mut x).unwrap();
                own_factors = Some(f);
                black_box(x[0])
            })
        });
        // The block LU's two halves, for the flop table.
        let mut abd = AbdLu::new(m / NY, POLE_ROWS).unwrap();
        disc.jacobian(&sol.u, &mut abd).unwrap();
        let mut abd_factors = abd.factor().ok();
        g.bench_with_input(BenchmarkId::new("block_factor_only", n), &n, |bch, _| {
            bch.iter(|| abd_factors = Some(abd.factor_reusing(abd_factors.take()).unwrap()))
        });
        let abd_factors = abd_factors.unwrap();
        g.bench_with_input(BenchmarkId::new("block_solve_only", n), &n, |bch, _| {
            bch.iter(|| {
                x.copy_from_slice(&b);
                abd_factors.solve_in_place(&mut x).unwrap();
                black_box(x[0])
            })
        });
    }
    g.finish();
}

/// A band matrix stored as SUNDIALS stores one (column-major, entry (i, j) at offset
/// smu + i − j of column j, smu = lower + upper for the LU fill), to time assembly without
/// SUNDIALS' calls.
struct BandSink {
    n: usize,
    data: Vec<f64>,
}
const SMU: usize = LOWER + UPPER;
const LDIM: usize = SMU + LOWER + 1;
impl BandSink {
    fn new(n: usize) -> Self {
        BandSink {
            n,
            data: vec![0.0; n * LDIM],
        }
    }
}
impl MatrixSink for BandSink {
    fn nrows(&self) -> usize {
        self.n
    }
    fn set(&mut self, i: usize, j: usize, v: f64) {
        self.data[j * LDIM + SMU + i - j] = v;
    }
}

/// A closure doing one residual and one Jacobian assembly of `p` at N = 501 near the
/// inflated sphere. Successive calls alternate between two states 2e-9 apart, so every
/// call evaluates every point again (the evaluation cache never hits), from α_s guesses
/// as close as in the last iteration of a Newton solve.
fn assemble_once(p: &Params) -> impl FnMut() -> f64 {
    let mut disc = discretise(p, &settings(501)).unwrap();
    let u = sphere_guess(&disc, p.r0);
    let mut f = vec![0.0; disc.len()];
    let mut sink = BandSink::new(disc.len());
    let mut flip = 1.0;
    move || {
        flip = -flip;
        let mut v = u.clone();
        v[3] += 1e-9 * black_box(flip);
        disc.residual(&v, &mut f).unwrap();
        disc.jacobian(&v, &mut sink).unwrap();
        sink.data[SMU] + f[3]
    }
}

/// Residual and Jacobian assembly alone at N = 501.
fn assembly(c: &mut Criterion) {
    let mut once = assemble_once(&fibre_shell());
    c.bench_function("residual_and_jacobian_n501_hs", |b| b.iter(&mut once));
}

/// The converged state of `p` and of the same shell at ΔP 1 % higher, on the same mesh: a
/// pass that alternates between them moves every α_s as much as a Newton step of a warm
/// solve does, so the α_s inversions start from realistic guesses (not from the answer).
fn two_states(p: &Params) -> (Vec<f64>, Vec<f64>) {
    let s = settings(501);
    let a = bvp::solve(p, &s, None).unwrap();
    let b = bvp::solve(
        &Params {
            dp: p.dp * 1.01,
            ..*p
        },
        &s,
        None,
    )
    .unwrap();
    assert_eq!(a.mesh.nodes, b.mesh.nodes);
    (a.u, b.u)
}

/// A closure doing one pass of point evaluations (α_s inversion, f and ∂f/∂y at every
/// node and midpoint), alternating between the two states of [`two_states`].
fn evaluate_alternating(p: &Params) -> impl FnMut() -> f64 {
    let mut disc = discretise(p, &settings(501)).unwrap();
    let (ua, ub) = two_states(p);
    let mut flip = false;
    move || {
        flip = !flip;
        let u = if flip { &ua } else { &ub };
        disc.evaluate_at(black_box(u)).unwrap();
        disc.evaluations().left(0).alpha_s
    }
}

/// The α_s inversions alone, through the public constitutive law: at every node and
/// midpoint of the converged state, seeded with α_s of the state at ΔP 1 % higher.
fn inversions(p: &Params) -> impl FnMut() -> f64 {
    let mut disc = discretise(p, &settings(501)).unwrap();
    let (ua, ub) = two_states(p);
    let m = disc.mesh.len();
    disc.evaluate_at(&ub).unwrap();
    let guesses: Vec<f64> = (0..m - 1)
        .flat_map(|i| {
            [
                disc.evaluations().left(i).alpha_s,
                disc.evaluations().mid(i).alpha_s,
            ]
        })
        .collect();
    disc.evaluate_at(&ua).unwrap();
    let ev = disc.evaluations();
    // (material point, t_s, α_φ, guess) at node i from above and at midpoint i.
    let points: Vec<_> = (0..m - 1)
        .flat_map(|i| {
            let (mp, mm) = (disc.data.above[i], disc.data.mid[i]);
            let (y, ym) = (&ua[5 * i..5 * i + 5], ev.y_mid(i));
            [
                (mp, y[4], y[1] / mp.rho, guesses[2 * i]),
                (mm, ym[4], ym[1] / mm.rho, guesses[2 * i + 1]),
            ]
        })
        .collect();
    let law = disc.shell.law;
    move || {
        let mut acc = 0.0;
        for (mp, ts, phi, guess) in black_box(&points) {
            acc += law
                .alpha_s_from_ts(mp.zeta, mp.fibre, *ts, *phi, *guess)
                .unwrap()
                .0;
        }
        acc
    }
}

/// A scene pays only for the physics it declares: the same non-uniform shell with and
/// without fibres (D = 0: no ψ, no fibre terms in the residual or the Jacobian).
fn components(c: &mut Criterion) {
    let mut g = c.benchmark_group("components_n501_hs");
    let s = settings(501);
    for (name, p) in [
        (
            "nonuniform_no_fibres",
            Params {
                d: 0.0,
                ..fibre_shell()
            },
        ),
        ("nonuniform_fibres_d200", fibre_shell()),
    ] {
        let mut once = assemble_once(&p);
        g.bench_function(format!("{name}/residual_and_jacobian"), |b| {
            b.iter(&mut once)
        });
        let mut pass = evaluate_alternating(&p);
        g.bench_function(format!("{name}/point_evaluations"), |b| b.iter(&mut pass));
        let mut inv = inversions(&p);
        g.bench_function(format!("{name}/alpha_s_inversions"), |b| b.iter(&mut inv));
        g.bench_function(format!("{name}/cold_solve"), |b| {
            b.iter(|| bvp::solve(black_box(&p), &s, None).unwrap())
        });
        let near = bvp::solve(
            &Params {
                dp: p.dp * 1.01,
                ..p
            },
            &s,
            None,
        )
        .unwrap();
        g.bench_function(format!("{name}/warm_solve"), |b| {
            b.iter(|| bvp::solve(black_box(&p), &s, Some(&near)).unwrap())
        });
    }
    g.finish();
}

/// The same comparison as [`components`] for the solves, but interleaved: criterion times
/// one benchmark after another, so on a shared machine a drift of the load between them
/// (±5 % here) can hide or fake a difference of a few per cent. Here the four solves take
/// turns, `rounds` times `per` solves each, and the table gives each one's minimum and
/// median time per solve. Run with
///   EYESHELL_INTERLEAVED=1 cargo bench --bench elastic -- components
fn interleaved_components(rounds: usize, per: usize) {
    let s = settings(501);
    let fibres = fibre_shell();
    let plain = Params { d: 0.0, ..fibres };
    let near = |p: &Params| {
        Some(
            bvp::solve(
                &Params {
                    dp: p.dp * 1.01,
                    ..*p
                },
                &s,
                None,
            )
            .unwrap(),
        )
    };
    let cases = [
        ("nonuniform_no_fibres/cold_solve", plain, None),
        ("nonuniform_fibres_d200/cold_solve", fibres, None),
        ("nonuniform_no_fibres/warm_solve", plain, near(&plain)),
        ("nonuniform_fibres_d200/warm_solve", fibres, near(&fibres)),
    ];
    let mut ms = vec![Vec::with_capacity(rounds); cases.len()];
    for _ in 0..rounds {
        for (k, (_, p, warm)) in cases.iter().enumerate() {
            let start = std::time::Instant::now();
            for _ in 0..per {
                black_box(bvp::solve(black_box(p), &s, warm.as_ref()).unwrap());
            }
            ms[k].push(start.elapsed().as_secs_f64() * 1e3 / per as f64);
        }
    }
    println!("interleaved, {rounds} rounds of {per} solves (ms per solve):");
    for ((name, _, _), t) in cases.iter().zip(&mut ms) {
        t.sort_by(f64::total_cmp);
        println!("  {name:36} min {:.3}  median {:.3}", t[0], t[t.len() / 2]);
    }
}

criterion_group!(
    benches,
    cold_and_warm,
    scaling,
    factor_and_solve,
    assembly,
    components
);

fn main() {
    if std::env::var_os("EYESHELL_INTERLEAVED").is_some() {
        interleaved_components(60, 10);
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
