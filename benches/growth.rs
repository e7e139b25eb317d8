//! Growth timings (growth in time). Run with
//!   cargo bench --bench growth
//! (`reduced_on_cpu` times by the thread's on-CPU time, for the shared machine).
//! Figures go in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, Criterion};
use eyeshell::bvp::settings::SolverSettings;
use eyeshell::growth::dae::{CoupledDae, SensParam};
use eyeshell::growth::system::GrowthSystem;
use eyeshell::growth::DaeLinear;
use eyeshell::growth::*;
use eyeshell::model::params::Params;
use eyeshell_linalg::{DirectSolver, Reduced, SchurSolver};
use std::hint::black_box;
use std::time::Duration;

/// The binary's allocator (src/main.rs), so that the figures are what `eyeshell` gets.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

struct Discard;
impl Observer for Discard {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), eyeshell::growth::ObserverError> {
        black_box(s.series.axial_length);
        Ok(())
    }
}

/// [`eyeshell::growth::grow`] of the problem these parts make (checked by its builder: a
/// few microseconds beside a run of a tenth of a second and more).
fn grow(
    params: &Params,
    solver: &SolverSettings,
    growth: &GrowthParams,
    settings: &GrowthSettings,
    observer: &mut dyn Observer,
) -> Result<GrowthStats, GrowthError> {
    let elastic = eyeshell::problem::ElasticProblem::builder()
        .params(*params)
        .solver(*solver)
        .build()
        .expect("the bench's shell is a valid problem");
    let problem = eyeshell::problem::GrowthProblem::builder(elastic)
        .growth(growth.clone())
        .settings(settings.clone())
        .build()
        .expect("the bench's growth is a valid problem");
    eyeshell::growth::grow(&problem, observer)
}

fn settings() -> SolverSettings {
    SolverSettings {
        nodes: 501,
        ..SolverSettings::default()
    }
}

/// The paper's const scene to t = 1, N = 501: CVODE at rtol 1e-6, and Euler's 200 steps.
fn const_scene(c: &mut Criterion) {
    let p = Params::default();
    let g = GrowthParams::default();
    let mut group = c.benchmark_group("const_scene_n501_to_t1");
    group.sample_size(10);
    let cv = GrowthSettings {
        integrator: Integrator::Cvode,
        rtol: 1e-6,
        atol: 1e-8,
        ..GrowthSettings::default()
    };
    group.bench_function("cvode_rtol_1e-6", |b| {
        b.iter(|| grow(&p, &settings(), &g, &cv, &mut Discard).unwrap())
    });
    // IDA on the coupled DAE at the same tolerances, with each linear solver of its Newton
    // matrix (the default first).
    for lin in DaeLinear::ALL {
        if matches!(lin, DaeLinear::Klu | DaeLinear::SchurKlu)
            && !eyeshell_sundials::klu_available()
        {
            continue;
        }
        let ida = GrowthSettings {
            integrator: Integrator::Ida,
            dae_linear: lin,
            rtol: 1e-6,
            atol: 1e-8,
            ..GrowthSettings::default()
        };
        group.bench_function(format!("ida_rtol_1e-6_{}", lin.name()), |b| {
            b.iter(|| grow(&p, &settings(), &g, &ida, &mut Discard).unwrap())
        });
    }
    // IDA at the rtol whose axial-length error matches CVODE's at 1e-6 (BENCHMARKS.md).
    let ida_equal = GrowthSettings {
        integrator: Integrator::Ida,
        rtol: IDA_RTOL_EQUAL_ERROR,
        atol: IDA_RTOL_EQUAL_ERROR * 1e-2,
        ..GrowthSettings::default()
    };
    group.bench_function("ida_equal_error", |b| {
        b.iter(|| grow(&p, &settings(), &g, &ida_equal, &mut Discard).unwrap())
    });
    let eu = GrowthSettings {
        integrator: Integrator::Euler,
        steps: 200,
        ..GrowthSettings::default()
    };
    group.bench_function("euler_200_steps", |b| {
        b.iter(|| grow(&p, &settings(), &g, &eu, &mut Discard).unwrap())
    });
    group.finish();
}

/// The pieces: one right side (a warm elastic re-solve), one Jacobian set-up (assemble and
/// factor F_u), one implicit-function Jacobian product.
fn pieces(c: &mut Criterion) {
    let mut sys =
        GrowthSystem::new(&Params::default(), &settings(), &GrowthParams::default()).unwrap();
    let p0 = sys.points.initial_state();
    let n = p0.len();
    let mut fy = vec![0.0; n];
    sys.rhs(&p0, &mut fy).unwrap();
    let v: Vec<f64> = (0..n).map(|k| p0[k] * (0.01 * k as f64).sin()).collect();
    let mut jv = vec![0.0; n];
    let mut group = c.benchmark_group("growth_pieces_n501");
    // A right side at a slightly grown state: the elastic re-solve from the last solution.
    let mut k = 0u32;
    group.bench_function("rhs_with_elastic_resolve", |b| {
        b.iter(|| {
            k += 1;
            let s = 1.0 + 1e-6 * (k % 7) as f64;
            let q: Vec<f64> = p0.iter().map(|x| x * s).collect();
            sys.rhs(&q, &mut fy).unwrap();
        })
    });
    sys.rhs(&p0, &mut fy).unwrap();
    group.bench_function("jacobian_setup", |b| {
        b.iter(|| sys.jac_setup(black_box(&p0)).unwrap())
    });
    group.bench_function("jacobian_product", |b| {
        b.iter(|| sys.jac_times(&p0, &fy, black_box(&v), &mut jv).unwrap())
    });
    group.finish();
}

/// The rtol at which IDA's axial-length error at t = 1 (against CVODE at rtol 1e-10) is no
/// larger than CVODE's at rtol 1e-6 (measured: BENCHMARKS.md).
const IDA_RTOL_EQUAL_ERROR: f64 = 5e-7;

/// The coupled system's pieces at the consistent start: one residual, one Newton-matrix
/// set-up (assembly, then factorisation), one solve with it.
fn dae_pieces(c: &mut Criterion) {
    let mut group = c.benchmark_group("dae_pieces_n501");
    for lin in DaeLinear::ALL {
        if matches!(lin, DaeLinear::Klu | DaeLinear::SchurKlu)
            && !eyeshell_sundials::klu_available()
        {
            continue;
        }
        let sys =
            GrowthSystem::new(&Params::default(), &settings(), &GrowthParams::default()).unwrap();
        let mut dae = CoupledDae::new(sys);
        dae.set_linear(lin).unwrap();
        let y = dae.initial_state().unwrap();
        let yp = dae.derivative(&y).unwrap();
        let n = y.len();
        let mut r = vec![0.0; n];
        if lin == DaeLinear::ALL[0] {
            let mut k = 0u32;
            group.bench_function("residual", |b| {
                b.iter(|| {
                    // A new iterate each time, as in Newton (no evaluation cache hit).
                    k += 1;
                    let s = 1.0 + 1e-9 * (k % 7) as f64;
                    let q: Vec<f64> = y.iter().map(|v| v * s).collect();
                    dae.residual(&q, &yp, &mut r).unwrap();
                })
            });
            group.bench_function("assembly", |b| {
                b.iter(|| dae.assemble(black_box(500.0), &y).unwrap())
            });
        }
        group.bench_function(format!("setup_{}", lin.name()), |b| {
            b.iter(|| dae.setup(black_box(500.0), &y).unwrap())
        });
        let rhs: Vec<f64> = (0..n).map(|k| (0.01 * k as f64).sin()).collect();
        let mut x = vec![0.0; n];
        // Factored here too, so that a filter that skips the set-up bench still solves.
        dae.setup(500.0, &y).unwrap();
        group.bench_function(format!("solve_{}", lin.name()), |b| {
            b.iter(|| dae.solve(black_box(&rhs), &mut x).unwrap())
        });
    }
    group.finish();
}

/// This thread's CPU time (CLOCK_THREAD_CPUTIME_ID).
fn on_cpu_now() -> Duration {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// `iters` calls of f, timed by the thread's time on a CPU instead of the wall clock: on
/// the shared 2-core machine the other builds held the core for 50–80 % of the wall time
/// at times, which made wall-clock comparisons of a 10 % difference meaningless.
fn on_cpu(iters: u64, mut f: impl FnMut()) -> Duration {
    let start = on_cpu_now();
    for _ in 0..iters {
        f();
    }
    on_cpu_now() - start
}

/// The block and band reduced solvers side by side, in on-CPU time (see [`on_cpu`]): the
/// Schur solver alone on the assembled matrix at the consistent start (factor: growth
/// blocks eliminated, S filled and factored; solve: one right side), the whole set-up and
/// solve of the Newton matrix as IDA calls them, and the const scene's IDA run.
fn reduced_on_cpu(c: &mut Criterion) {
    let mut group = c.benchmark_group("reduced_on_cpu_n501");
    let sys = GrowthSystem::new(&Params::default(), &settings(), &GrowthParams::default()).unwrap();
    let mut dae = CoupledDae::new(sys);
    let y = dae.initial_state().unwrap();
    dae.assemble(500.0, &y).unwrap();
    let a = dae.matrix().clone();
    let n = a.n();
    let rhs: Vec<f64> = (0..n).map(|k| (0.01 * k as f64).sin()).collect();
    let mut x = vec![0.0; n];
    for (name, how, lin) in [
        ("block", Reduced::Block, DaeLinear::SchurBlock),
        ("band", Reduced::Band, DaeLinear::Schur),
    ] {
        let mut schur = SchurSolver::new(&a, dae.differential_len(), true, how).unwrap();
        group.bench_function(format!("schur_factor_only_{name}"), |b| {
            b.iter_custom(|k| on_cpu(k, || schur.factor(black_box(&a)).unwrap()))
        });
        schur.factor(&a).unwrap();
        group.bench_function(format!("schur_solve_only_{name}"), |b| {
            b.iter_custom(|k| on_cpu(k, || schur.solve(black_box(&rhs), &mut x).unwrap()))
        });
        dae.set_linear(lin).unwrap();
        group.bench_function(format!("setup_{name}"), |b| {
            b.iter_custom(|k| on_cpu(k, || dae.setup(black_box(500.0), &y).unwrap()))
        });
        dae.setup(500.0, &y).unwrap();
        group.bench_function(format!("solve_{name}"), |b| {
            b.iter_custom(|k| on_cpu(k, || dae.solve(black_box(&rhs), &mut x).unwrap()))
        });
    }
    group.sample_size(10);
    let (p, g) = (Params::default(), GrowthParams::default());
    for lin in [DaeLinear::SchurBlock, DaeLinear::Schur] {
        let ida = GrowthSettings {
            integrator: Integrator::Ida,
            dae_linear: lin,
            rtol: 1e-6,
            atol: 1e-8,
            ..GrowthSettings::default()
        };
        group.bench_function(format!("const_scene_ida_rtol_1e-6_{}", lin.name()), |b| {
            b.iter_custom(|k| {
                on_cpu(k, || {
                    grow(&p, &settings(), &g, &ida, &mut Discard).unwrap();
                })
            })
        });
    }
    group.finish();
}

/// One analytic assembly of the coupled DAE's F_y (c = 0, as the forward sensitivities
/// assemble it once per step) at the consistent start, in on-CPU time (see [`on_cpu`]):
/// BENCHMARKS.md "Forward sensitivities", "What changed".
fn assembly_on_cpu(c: &mut Criterion) {
    let mut group = c.benchmark_group("assembly_on_cpu_n501");
    let sys = GrowthSystem::new(&Params::default(), &settings(), &GrowthParams::default()).unwrap();
    let mut dae = CoupledDae::new(sys);
    let y = dae.initial_state().unwrap();
    group.bench_function("fy", |b| {
        b.iter_custom(|k| on_cpu(k, || dae.assemble(black_box(0.0), &y).unwrap()))
    });
    group.finish();
}

/// The parameter lists [`sensitivities_on_cpu`] times when EYESHELL_BENCH_SENSITIVITIES
/// is not set: k = 1, 2, 3.
const DEFAULT_SENSITIVITIES: &str =
    "growth.eta0;growth.eta0,growth.Gamma;growth.eta0,growth.Gamma,growth.delta";

/// The const scene's IDA run (rtol 1e-6, N = 501, to t = 1) without and with forward
/// sensitivities, in on-CPU time (see [`on_cpu`]); BENCHMARKS.md "Forward sensitivities"
/// divides each by the plain run. The parameter lists come from the environment variable
/// EYESHELL_BENCH_SENSITIVITIES (lists separated by `;`, scene keys by `,`), by default
/// [`DEFAULT_SENSITIVITIES`]:
///   EYESHELL_BENCH_SENSITIVITIES="growth.eta0;KEY,KEY,KEY,KEY" \
///     cargo bench --bench growth -- sensitivities
fn sensitivities_on_cpu(c: &mut Criterion) {
    let lists = std::env::var("EYESHELL_BENCH_SENSITIVITIES")
        .unwrap_or_else(|_| DEFAULT_SENSITIVITIES.to_string());
    let mut group = c.benchmark_group("sensitivities_on_cpu_n501");
    group.sample_size(10);
    let (p, g) = (Params::default(), GrowthParams::default());
    let plain = GrowthSettings {
        integrator: Integrator::Ida,
        rtol: 1e-6,
        atol: 1e-8,
        ..GrowthSettings::default()
    };
    let mut time = |name: String, s: GrowthSettings| {
        group.bench_function(name, |b| {
            b.iter_custom(|k| {
                on_cpu(k, || {
                    grow(&p, &settings(), &g, &s, &mut Discard).unwrap();
                })
            })
        });
    };
    time("plain".into(), plain.clone());
    for list in lists.split(';').filter(|l| !l.trim().is_empty()) {
        let params: Vec<SensParam> = list
            .split(',')
            .map(|key| {
                eyeshell::scene::sensitivity::sensitivity_param(key.trim())
                    .unwrap_or_else(|why| panic!("{why}"))
            })
            .collect();
        let name = format!("k{}_{}", params.len(), list.trim());
        time(
            name,
            GrowthSettings {
                sensitivities: params,
                ..plain.clone()
            },
        );
    }
    group.finish();
}

criterion_group!(
    benches,
    const_scene,
    pieces,
    dae_pieces,
    reduced_on_cpu,
    assembly_on_cpu,
    sensitivities_on_cpu
);
criterion_main!(benches);
