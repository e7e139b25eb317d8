//! Elastic solve timings (issue: the shell at equilibrium). Run with
//!   cargo bench --bench elastic
//! Figures go in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use eyeshell::bvp::solve::{discretise, sphere_guess};
use eyeshell::bvp::{self};
use eyeshell::model::params::{Params, Scheme, SolverSettings, Thickness};
use eyeshell::sundials::MatrixSink;
use std::hint::black_box;

fn fibre_shell() -> Params {
    Params { thickness: Thickness::NonUniform, d: 200.0, ..Params::default() }
}

fn settings(nodes: usize) -> SolverSettings {
    SolverSettings { nodes, scheme: Scheme::HermiteSimpson, newton_tol: 1e-10, ..SolverSettings::default() }
}

/// One cold and one warm-started solve of the fibre shell at N = 501, order 4.
fn cold_and_warm(c: &mut Criterion) {
    let p = fibre_shell();
    let s = settings(501);
    let mut g = c.benchmark_group("fibre_shell_n501_hs");
    g.bench_function("cold", |b| b.iter(|| bvp::solve(black_box(&p), &s, None).unwrap()));
    // Warm: the previous solution at a 1 % higher pressure, as in a continuation or a growth step.
    let near = bvp::solve(&Params { dp: p.dp * 1.01, ..p }, &s, None).unwrap();
    g.bench_function("warm", |b| b.iter(|| bvp::solve(black_box(&p), &s, Some(&near)).unwrap()));
    g.finish();
}

/// Cost per node: cold and warm solves over N from 101 to 20001 (linear in N if the band
/// holds). Warm: from the solution at a 1 % higher pressure.
fn scaling(c: &mut Criterion) {
    let p = fibre_shell();
    for warm in [false, true] {
        let mut g = c.benchmark_group(if warm { "warm_solve_by_nodes" } else { "cold_solve_by_nodes" });
        g.sample_size(10);
        for n in [101usize, 501, 2001, 20001] {
            let s = settings(n);
            let near = warm.then(|| bvp::solve(&Params { dp: p.dp * 1.01, ..p }, &s, None).unwrap());
            g.throughput(Throughput::Elements(n as u64));
            g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| b.iter(|| bvp::solve(black_box(&p), &s, near.as_ref()).unwrap()));
        }
        g.finish();
    }
}

/// A sink that only touches the band entries, to time assembly without SUNDIALS.
struct NullSink(f64);
impl MatrixSink for NullSink {
    fn nrows(&self) -> usize {
        0
    }
    fn set(&mut self, _i: usize, _j: usize, v: f64) {
        self.0 += v;
    }
}

/// A closure doing one residual and one Jacobian assembly of `p` at N = 501, at the
/// inflated sphere nudged so that the evaluation cache is never reused.
fn assemble_once(p: &Params) -> impl FnMut() -> f64 {
    let mut disc = discretise(p, &settings(501)).unwrap();
    let u = sphere_guess(&disc, p.r0);
    let mut f = vec![0.0; disc.len()];
    move || {
        let mut v = u.clone();
        v[3] += 1e-9 * black_box(1.0);
        disc.residual(&v, &mut f).unwrap();
        let mut sink = NullSink(0.0);
        disc.jacobian(&v, &mut sink).unwrap();
        sink.0
    }
}

/// Residual and Jacobian assembly alone at N = 501.
fn assembly(c: &mut Criterion) {
    let mut once = assemble_once(&fibre_shell());
    c.bench_function("residual_and_jacobian_n501_hs", |b| b.iter(&mut once));
}

/// A scene pays only for the physics it declares: the same shell with and without fibres
/// (no ψ, no fibre terms in the residual or the Jacobian when D = 0).
fn components(c: &mut Criterion) {
    let mut g = c.benchmark_group("components_n501_hs");
    let s = settings(501);
    for (name, p) in [("nonuniform_no_fibres", Params { d: 0.0, ..fibre_shell() }), ("nonuniform_fibres_d200", fibre_shell())] {
        let mut once = assemble_once(&p);
        g.bench_function(format!("{name}/residual_and_jacobian"), |b| b.iter(&mut once));
        g.bench_function(format!("{name}/cold_solve"), |b| b.iter(|| bvp::solve(black_box(&p), &s, None).unwrap()));
    }
    g.finish();
}

criterion_group!(benches, cold_and_warm, scaling, assembly, components);
criterion_main!(benches);
