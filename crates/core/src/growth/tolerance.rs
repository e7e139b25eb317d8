//! `solver.tol` in a growth run (docs/MODEL.md §5, "Growth to a tolerance"): the global error
//! of the run's outputs — the lengths of series.csv and history.csv and the snapshots' r and
//! z, at every output time — is estimated, space and time apart, and the material mesh and
//! the integrator's tolerances are chosen together so that their sum is at most tol.
//!
//! A round runs the scene three times: on a mesh M (`solver.nodes`' uniform + graded mesh
//! of n nodes) at rtol, on M halved (M/2, every interval split in two) at rtol — the run
//! that is delivered — and on M again at 10·rtol. Then, at every output time and for every
//! length,
//!
//! - the space error of M/2 is |u(M/2) − u(M)| / (2^p − 1), p = [`SPACE_ORDER`]: the grown
//!   shell converges only at order 2–3 in the nodes (points stop growing at their own
//!   times, and the kinks this leaves in its data no fixed mesh resolves), so p = 2 errs on
//!   the safe side;
//! - the time error is |u(M, 10·rtol) − u(M, rtol)| / (10^q − 1), q = [`TIME_ORDER`]: the
//!   global error of IDA and CVODE falls as rtol^q, q ≈ 0.75 measured on the const scene
//!   over rtol 1e-5…1e-8. It is measured on M at the looser rtol, where it costs about a
//!   quarter of the delivered run, and it depends on the mesh only through the shell it
//!   integrates.
//!
//! The three runs are independent: with a second core the two on M go on a thread of their
//! own beside M/2's ([`three_runs`]), so that on two idle cores a round takes about the wall
//! time of its dearer side, and each round records both sides' CPU seconds.
//!
//! If the largest sum over the lengths and times is at most tol, M/2's run is delivered with
//! those estimates. If not, the next round's (n, rtol) is the cheapest that the measured
//! estimates, scaled as n^−[`MODEL_SPACE_ORDER`] and rtol^q, predict to meet [`AIM`]·tol
//! (the estimate takes the safe order 2, the prediction the observed 2.5): the cost of a run grows
//! as n·rtol^−β ([`COST_RTOL_EXPONENT`]), and the split of the error between space and
//! time is searched over with n and rtol held inside their bounds. Where nothing inside
//! them is predicted to meet AIM·tol, the next round aims at tol itself, and where nothing
//! meets tol either the run stops with the estimate it has. The first round reads
//! the same model with the const scene's measured constants ([`PRIOR`]), so that on the
//! scenes like it one round is enough.
//!
//! With forward sensitivities, the three runs carry them under IDAS's error test and each
//! one's error is estimated the same way ([`SensitivityEstimate`]), the space part at
//! [`SENSITIVITY_SPACE_ORDER`]; tol bounds each parameter p's |p|·(error of ∂y/∂p) too.
//!
//! The time estimate by a rerun at 10·rtol was chosen over two others: IDAS's quadrature
//! of the local errors does not bound the global error of a stiff DAE (the local errors are
//! damped, not summed), and an adjoint needs a backward run per output length and time
//! (each dearer than the rerun). Richardson in rtol with the rerun is what BDF's
//! tolerance proportionality allows; how far it holds is measured in BENCHMARKS.md.

use crate::bvp::settings::SolverSettings;
use crate::mesh::Mesh;
use crate::names::Quantity;

use super::system::GrowthSystem;
use super::{
    GrowthError, GrowthSettings, GrowthStats, Integrator, OutputFn, ProgressFn, SensitivityFn,
    SensitivityRow,
};

/// The order in the nodes that the space estimate assumes (module docs).
pub const SPACE_ORDER: f64 = 2.0;
/// The order in the nodes that the next round's mesh is predicted with: the const scene's
/// axial length converges at 2.3 to 3.1 between N = 51 and 801 (module docs).
pub const MODEL_SPACE_ORDER: f64 = 2.5;
/// The order in the nodes that the sensitivities' space estimate assumes: ∂L/∂Γ on the
/// const scene with fibres (D = 100) converges at order 1.1, 1.6 and 2.1 between 26–50,
/// 50–100 and 100–150 nodes of M (the kinks of growth stopping point by point move with the
/// parameters, and their sensitivities resolve slower than the lengths); at order 2 the
/// estimate fell 1.8× short of the true error at tol 1e-3.
pub const SENSITIVITY_SPACE_ORDER: f64 = 1.0;
/// The order the next round's mesh is predicted with when the sensitivities bound it.
pub const SENSITIVITY_MODEL_ORDER: f64 = 1.5;
/// The power of rtol that the time error follows (module docs).
pub const TIME_ORDER: f64 = 0.75;
/// A run's cost grows as rtol^−β at a given mesh (IDA's steps on the const scene).
pub const COST_RTOL_EXPONENT: f64 = 0.25;
/// The fraction of tol a new round aims at, so that the estimate of the next is within tol.
pub const AIM: f64 = 0.5;
/// The most rounds before giving up.
pub const MAX_ROUNDS: usize = 4;
/// The bounds of the chosen rtol: looser (its companion at 10·rtol looser still), the
/// integrator's error stops following rtol;
/// tighter, IDA's error test fails at the start (const scene, rtol 1.2e-11).
pub const RTOL_RANGE: (f64, f64) = (1e-10, 1e-4);
/// The fewest nodes of M.
pub const MIN_NODES: usize = 11;
/// solver.atol as a fraction of the chosen rtol (the growth state is O(1) to O(10) mm).
pub const ATOL_PER_RTOL: f64 = 1e-2;
/// The first round's model: M of `nodes` nodes at `rtol` has the space error `space` and
/// the time error `time` (mm): the const scene's, measured against IDA at N = 3201, rtol 1e-10.
pub const PRIOR: Round = Round {
    nodes: 26,
    rtol: 1e-5,
    atol: 1e-7,
    space: 2e-4,
    time: 1.6e-4,
    seconds: 0.0,
    delivered_cpu_seconds: 0.0,
    companions_cpu_seconds: 0.0,
};

/// One length's estimated error (mm): space and time, and their sum.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Split {
    pub total: f64,
    pub space: f64,
    pub time: f64,
}

impl Split {
    fn new(space: f64, time: f64) -> Split {
        Split {
            total: space + time,
            space,
            time,
        }
    }

    fn max(self, o: Split) -> Split {
        Split {
            total: self.total.max(o.total),
            space: self.space.max(o.space),
            time: self.time.max(o.time),
        }
    }
}

/// The estimated error of each output length (mm).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lengths {
    pub axial_length: Split,
    pub equatorial_radius: Split,
    pub retina_minus_blue: Split,
    pub retina_minus_red: Split,
    /// The snapshots' r and z, the largest over the nodes (the snapshot times only).
    pub shell: Split,
}

impl Lengths {
    fn all(&self) -> [Split; 5] {
        [
            self.axial_length,
            self.equatorial_radius,
            self.retina_minus_blue,
            self.retina_minus_red,
            self.shell,
        ]
    }

    /// The largest total over the lengths, and the space and time parts of each (largest).
    fn worst(&self) -> Split {
        self.all().into_iter().fold(Split::default(), Split::max)
    }

    fn max(self, o: Lengths) -> Lengths {
        Lengths {
            axial_length: self.axial_length.max(o.axial_length),
            equatorial_radius: self.equatorial_radius.max(o.equatorial_radius),
            retina_minus_blue: self.retina_minus_blue.max(o.retina_minus_blue),
            retina_minus_red: self.retina_minus_red.max(o.retina_minus_red),
            shell: self.shell.max(o.shell),
        }
    }
}

/// The estimate at one output time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimedLengths {
    pub t: f64,
    pub lengths: Lengths,
}

/// summary.json's `error_estimate` of a growth run under `solver.tol`: each length's largest
/// over the output times, and each output time's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorEstimate {
    pub largest: Lengths,
    pub per_time: Vec<TimedLengths>,
    /// With sensitivities: each one's estimate, the largest over the recorded times.
    pub sensitivities: Vec<SensitivityEstimate>,
}

impl ErrorEstimate {
    /// The largest estimated total error over every length and time (mm).
    pub fn overall(&self) -> f64 {
        self.largest.worst().total
    }

    /// What `solver.tol` bounds: the largest of [`Self::overall`] and every sensitivity's
    /// [`SensitivityEstimate::scaled`] (mm), with the largest space and time parts.
    pub fn bounded(&self) -> Split {
        self.sensitivities
            .iter()
            .map(SensitivityEstimate::scaled)
            .fold(self.largest.worst(), Split::max)
    }
}

/// The estimated error of one parameter's sensitivities (per unit of the parameter, as in
/// sensitivities.csv), the largest over the recorded times. `solver.tol` bounds them scaled
/// by the parameter's magnitude ([`Self::scaled`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensitivityEstimate {
    /// The scene key.
    pub parameter: String,
    /// Its value in the run.
    pub value: f64,
    pub d_axial_length: Split,
    pub d_equatorial_radius: Split,
    pub d_retina_minus_blue: Split,
}

impl SensitivityEstimate {
    /// The error of p·∂y/∂p (mm: the change of each length for a change of p by its own
    /// size, the scale a sensitivity is read at), the largest over the three lengths; a
    /// parameter at 0 is read per unit instead. Space and time are each the largest part.
    pub fn scaled(&self) -> Split {
        let scale = if self.value == 0.0 {
            1.0
        } else {
            self.value.abs()
        };
        let s = self
            .d_axial_length
            .max(self.d_equatorial_radius)
            .max(self.d_retina_minus_blue);
        Split {
            total: scale * s.total,
            space: scale * s.space,
            time: scale * s.time,
        }
    }
}

/// One round of the choice: M's nodes, the tolerances, and the estimated error of its
/// M/2 run (the largest over the lengths and times, mm), and the seconds of its three runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Round {
    pub nodes: usize,
    pub rtol: f64,
    pub atol: f64,
    pub space: f64,
    pub time: f64,
    pub seconds: f64,
    /// The CPU seconds of the delivered run (M/2), and of the two runs on M, each on its own
    /// thread (NaN in a summary.json that predates them): on two idle cores
    /// the round takes about the larger, under load the wall clock says little.
    pub delivered_cpu_seconds: f64,
    pub companions_cpu_seconds: f64,
}

/// The CPU time of the calling thread (s): the kernel's per-thread clock
/// (CLOCK_THREAD_CPUTIME_ID), through rustix's safe call.
fn thread_cpu_seconds() -> f64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// The CPU seconds the calling thread spends in `f`.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let before = thread_cpu_seconds();
    let value = f();
    (value, thread_cpu_seconds() - before)
}

/// summary.json's `accuracy`: what `solver.tol` chose for a growth run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Accuracy {
    pub tol: f64,
    /// Nodes of the delivered run's mesh (M/2 of the last round).
    pub nodes: usize,
    /// The delivered run's integrator tolerances.
    pub rtol: f64,
    pub atol: f64,
    pub rounds: Vec<Round>,
    /// Every run of every round, and the delivery.
    pub wall_seconds: f64,
    /// The threads each round ran its three runs on: 1 (one after another) or 2 (the test
    /// runs beside the delivered one): [`round_threads`].
    pub threads: usize,
}

/// The outputs of one run, recorded at every output time.
struct Recorded {
    t: Vec<f64>,
    /// The growth state and the elastic unknowns, to hand the caller's output afterwards.
    p: Vec<Vec<f64>>,
    u: Vec<Vec<f64>>,
    /// Axial length, equatorial radius, retina − blue, retina − red.
    series: Vec<[f64; 4]>,
    /// (r, z) at every node, at the snapshot times.
    shell: Vec<Option<Vec<(f64, f64)>>>,
    sens: Vec<Vec<SensitivityRow>>,
    stats: GrowthStats,
}

/// Run the scene `parts` on `mesh`, recording its outputs, and with `keep_states` the
/// states [`replay`] hands the caller (the delivered run's only).
fn record(
    parts: super::Parts<'_>,
    mesh: Mesh,
    keep_states: bool,
    progress: &mut ProgressFn<'_>,
) -> Result<Recorded, GrowthError> {
    let snapshots = super::snapshot_times(parts.settings, parts.growth.t_end);
    let mut rec = Recorded {
        t: vec![],
        p: vec![],
        u: vec![],
        series: vec![],
        shell: vec![],
        sens: vec![],
        stats: GrowthStats::default(),
    };
    let mut sens_rows = vec![];
    let mut output = |sys: &mut GrowthSystem, t: f64, p: &[f64]| {
        let (row, shell) = if t == 0.0 || snapshots.contains(&t) {
            let (row, shell) = sys.outline(t, p)?;
            (row, Some(shell))
        } else {
            (sys.series(t, p)?, None)
        };
        rec.t.push(t);
        if keep_states {
            rec.p.push(p.to_vec());
            rec.u.push(sys.elastic.u.clone());
        }
        rec.series.push([
            row.axial_length,
            row.equatorial_radius,
            row.retina_minus_blue,
            row.retina_minus_red,
        ]);
        rec.shell.push(shell);
        Ok(())
    };
    let stats = super::run_on(
        parts,
        Some(mesh),
        super::Hooks {
            sens: &mut |rows| {
                sens_rows.push(rows.to_vec());
                Ok(())
            },
            output: &mut output,
            progress,
        },
    )?;
    rec.stats = stats;
    rec.sens = sens_rows;
    Ok(rec)
}

/// The threads a round's three runs use: `solver.threads` (a round has work for two),
/// else two when the machine has a second core.
pub fn round_threads(solver: &SolverSettings) -> usize {
    let cores = || std::thread::available_parallelism().map_or(1, |n| n.get());
    solver.threads.unwrap_or_else(cores).clamp(1, 2)
}

/// A round's three runs: `fine_mesh` at `at[0]` (the delivered one, which reports
/// `progress`), and `mesh` at `at[0]` and at `at[1]`, in that order. They are independent,
/// so with a second core (and `solver.threads` not 1) the two on M run on a thread of their own beside the delivered
/// run, which costs about as much as those two together (M/2 has twice M's nodes, and the
/// looser run is cheaper): the round then takes about the wall time of the delivered run
/// alone. Each run makes and drops its own SUNDIALS context on its own thread. Once one run
/// fails the others stop at their next step (a flag their progress reads), and the error
/// is that of the run that failed first: a failure or an interruption costs no more than
/// it would one run after another.
fn three_runs(
    parts: super::Parts<'_>,
    at: [GrowthSettings; 2],
    mesh: Mesh,
    fine_mesh: Mesh,
    progress: &mut ProgressFn<'_>,
) -> Result<([Recorded; 3], [f64; 2]), GrowthError> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let [tight, loose] = at;
    // One run of the round: the delivered one keeps its states for the replay.
    let run = |at: &GrowthSettings, mesh: Mesh, delivered: bool, progress: &mut ProgressFn<'_>| {
        record(
            super::Parts {
                settings: at,
                ..parts
            },
            mesh,
            delivered,
            progress,
        )
    };
    if round_threads(parts.solver) < 2 {
        let (fine, f) = timed(|| run(&tight, fine_mesh, true, progress));
        let fine = fine?;
        let (others, o) = timed(|| {
            let coarse = run(&tight, mesh.clone(), false, &mut |_| Ok(()))?;
            let loose = run(&loose, mesh, false, &mut |_| Ok(()))?;
            Ok::<_, GrowthError>((coarse, loose))
        });
        let (coarse, loose) = others?;
        return Ok(([fine, coarse, loose], [f, o]));
    }
    // 0 while every run goes on, else 1 + the index of the run that failed first.
    let failed = AtomicUsize::new(0);
    let fail = |k: usize| {
        let _ = failed.compare_exchange(0, k + 1, Ordering::Relaxed, Ordering::Relaxed);
    };
    let halt = || -> Result<(), super::ObserverError> {
        match failed.load(Ordering::Relaxed) {
            0 => Ok(()),
            _ => Err("stopped: another run of the round failed".into()),
        }
    };
    let (fine, coarse, loose, cpu) = std::thread::scope(|scope| {
        let helper = scope.spawn(|| {
            timed(|| {
                let coarse = run(&tight, mesh.clone(), false, &mut |_| halt());
                if coarse.is_err() {
                    fail(1);
                    let skipped = GrowthError {
                        t: 0.0,
                        reason: "not run: another run of the round failed".into(),
                        stats: Box::default(),
                    };
                    return (coarse, Err(skipped));
                }
                let loose = run(&loose, mesh, false, &mut |_| halt());
                if loose.is_err() {
                    fail(2);
                }
                (coarse, loose)
            })
        });
        let (fine, f) = timed(|| {
            run(&tight, fine_mesh, true, &mut |t| {
                halt()?;
                progress(t)
            })
        });
        if fine.is_err() {
            fail(0);
        }
        let ((coarse, loose), o) = helper
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (fine, coarse, loose, [f, o])
    });
    let first = failed.into_inner();
    match (fine, coarse, loose) {
        (Ok(f), Ok(c), Ok(l)) => Ok(([f, c, l], cpu)),
        (_, Err(e), _) if first == 2 => Err(e),
        (_, _, Err(e)) if first == 3 => Err(e),
        (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => Err(e),
    }
}

/// |a − b| of each length at each output time; `stride` reads a's nodes every `stride`
/// nodes of b's (2: a on M/2, b on M).
fn differences(a: &Recorded, b: &Recorded, stride: usize) -> Vec<[f64; 5]> {
    a.series
        .iter()
        .zip(&b.series)
        .zip(a.shell.iter().zip(&b.shell))
        .map(|((x, y), (sa, sb))| {
            let shell = match (sa, sb) {
                (Some(sa), Some(sb)) => sb
                    .iter()
                    .enumerate()
                    .map(|(i, q)| {
                        let p = sa[stride * i];
                        (p.0 - q.0).abs().max((p.1 - q.1).abs())
                    })
                    .fold(0.0, f64::max),
                _ => 0.0,
            };
            [
                (x[0] - y[0]).abs(),
                (x[1] - y[1]).abs(),
                (x[2] - y[2]).abs(),
                (x[3] - y[3]).abs(),
                shell,
            ]
        })
        .collect()
}

/// The error estimate of `fine` (M/2 at rtol) from `coarse` (M at rtol) and `loose`
/// (M at 10·rtol): module docs.
fn estimate(fine: &Recorded, coarse: &Recorded, loose: &Recorded) -> ErrorEstimate {
    let space = differences(fine, coarse, 2);
    let time = differences(coarse, loose, 1);
    let ks = 1.0 / (2f64.powf(SPACE_ORDER) - 1.0);
    let kt = 1.0 / (10f64.powf(TIME_ORDER) - 1.0);
    let per_time: Vec<TimedLengths> = fine
        .t
        .iter()
        .zip(space.iter().zip(&time))
        .map(|(&t, (s, d))| {
            let split = |k: usize| Split::new(ks * s[k], kt * d[k]);
            TimedLengths {
                t,
                lengths: Lengths {
                    axial_length: split(0),
                    equatorial_radius: split(1),
                    retina_minus_blue: split(2),
                    retina_minus_red: split(3),
                    shell: split(4),
                },
            }
        })
        .collect();
    let largest = per_time
        .iter()
        .fold(Lengths::default(), |m, t| m.max(t.lengths));
    // The sensitivity rows of the three runs come at the same recorded times, one per
    // parameter in the same order.
    let mut sensitivities: Vec<SensitivityEstimate> = fine
        .sens
        .first()
        .map(|rows| {
            rows.iter()
                .map(|r| SensitivityEstimate {
                    parameter: r.parameter.to_string(),
                    value: r.value,
                    ..SensitivityEstimate::default()
                })
                .collect()
        })
        .unwrap_or_default();
    let ks = 1.0 / (2f64.powf(SENSITIVITY_SPACE_ORDER) - 1.0);
    for ((f, c), l) in fine.sens.iter().zip(&coarse.sens).zip(&loose.sens) {
        for (((e, f), c), l) in sensitivities.iter_mut().zip(f).zip(c).zip(l) {
            let split = |f: f64, c: f64, l: f64| Split::new(ks * (f - c).abs(), kt * (c - l).abs());
            e.d_axial_length =
                e.d_axial_length
                    .max(split(f.d_axial_length, c.d_axial_length, l.d_axial_length));
            e.d_equatorial_radius = e.d_equatorial_radius.max(split(
                f.d_equatorial_radius,
                c.d_equatorial_radius,
                l.d_equatorial_radius,
            ));
            e.d_retina_minus_blue = e.d_retina_minus_blue.max(split(
                f.d_retina_minus_blue,
                c.d_retina_minus_blue,
                l.d_retina_minus_blue,
            ));
        }
    }
    ErrorEstimate {
        largest,
        per_time,
        sensitivities,
    }
}

/// The cheapest (nodes of M, rtol) that `last`'s errors, scaled as n^−`order` and rtol^q,
/// predict to meet `target`, the split between space and time searched over in steps of 1/40;
/// None if nothing inside the bounds of n and rtol is predicted to.
fn next(last: &Round, target: f64, max_nodes: usize, order: f64) -> Option<(usize, f64)> {
    let space = last.space.max(1e-300);
    let time = last.time.max(1e-300);
    let mut best: Option<(f64, usize, f64)> = None;
    for k in 1..40 {
        let f = k as f64 / 40.0;
        let n = (last.nodes as f64 * (space / (f * target)).powf(1.0 / order)).ceil();
        let n = (n as usize).max(MIN_NODES);
        let rtol = (last.rtol * ((1.0 - f) * target / time).powf(1.0 / TIME_ORDER))
            .clamp(RTOL_RANGE.0, RTOL_RANGE.1);
        // Held at a bound, the model's error may exceed the target: such a split is out.
        let predicted = space * (last.nodes as f64 / n as f64).powf(order)
            + time * (rtol / last.rtol).powf(TIME_ORDER);
        if predicted > target * (1.0 + 1e-9) || n > max_nodes {
            continue;
        }
        let cost = n as f64 * rtol.powf(-COST_RTOL_EXPONENT);
        if best.is_none_or(|b| cost < b.0) {
            best = Some((cost, n, rtol));
        }
    }
    best.map(|(_, n, rtol)| (n, rtol))
}

/// The elastic settings of each run of a round: its solves as tight as the adaptive elastic
/// solve's, and like it to precision (a soft shell's residual stalls at round-off above
/// 1e-2·tol).
fn run_settings(solver: &SolverSettings, tol: f64) -> SolverSettings {
    SolverSettings {
        tol: None,
        richardson: false,
        newton_tol: crate::bvp::adapt::newton_tol_for(solver),
        newton_budget: Some(crate::bvp::solve::NEWTON_SHARE * tol),
        ..*solver
    }
}

/// The growth run under `solver.tol` (module docs): rounds until the estimate is within tol,
/// then the delivered run's outputs and sensitivities are handed to the callbacks, in the
/// order of the run. `solver` has its clock started: every run shares `solver.max_seconds`.
pub(super) fn run(
    parts: super::Parts<'_>,
    hooks: super::Hooks<'_, '_>,
) -> Result<GrowthStats, GrowthError> {
    let super::Parts {
        params,
        solver,
        settings,
        ..
    } = parts;
    let super::Hooks {
        sens,
        output,
        progress,
    } = hooks;
    let start = std::time::Instant::now();
    let tol = solver
        .tol
        .expect("growth to a tolerance is for a global error tolerance");
    let refuse = |reason: String| GrowthError {
        t: 0.0,
        reason,
        stats: Box::default(),
    };
    if settings.integrator == Integrator::Euler {
        return Err(refuse(
            format!(
                "{} in a growth scene needs {} = \"ida\" or \"cvode\" (Euler's fixed steps have no tolerance to choose)",
                Quantity::Tolerance,
                Quantity::Integrator
            ),
        ));
    }
    let base = run_settings(solver, tol);
    let mut accuracy = Accuracy {
        tol,
        threads: round_threads(solver),
        ..Accuracy::default()
    };
    // M's nodes from the model, at most half of solver.max_nodes (M/2 has 2n − 1).
    let max_nodes = solver.max_nodes.div_ceil(2);
    // The prior is another scene's: where it sees no way to tol, the finest the bounds allow
    // is tried, and the measured estimate decides.
    let (mut nodes, mut rtol) = next(&PRIOR, AIM * tol, max_nodes, MODEL_SPACE_ORDER)
        .unwrap_or((max_nodes.max(MIN_NODES), RTOL_RANGE.0));
    loop {
        let round_start = std::time::Instant::now();
        let atol = ATOL_PER_RTOL * rtol;
        // Every run carries the sensitivities (their error is estimated from the three, as
        // the lengths'), in the local error test: outside it their time error does not
        // follow rtol (∂L/∂Γ, const scene with fibres, tol 1e-4: the error was 5.8× its
        // estimate; with the test, 0.53×).
        let at = |rtol: f64| GrowthSettings {
            rtol,
            atol: ATOL_PER_RTOL * rtol,
            sensitivity_error_control: !settings.sensitivities.is_empty(),
            ..settings.clone()
        };
        let with_rounds = |mut e: GrowthError, accuracy: &Accuracy| {
            e.stats.accuracy = Some(Accuracy {
                wall_seconds: start.elapsed().as_secs_f64(),
                ..accuracy.clone()
            });
            e
        };
        let s = SolverSettings { nodes, ..base };
        let mesh = crate::bvp::solve::mesh_of(params, &s).map_err(|e| refuse(e.to_string()))?;
        let fine_mesh = mesh.halved();
        let ([fine, coarse, loose], cpu) = three_runs(
            super::Parts {
                solver: &s,
                ..parts
            },
            [at(rtol), at(10.0 * rtol)],
            mesh,
            fine_mesh.clone(),
            progress,
        )
        .map_err(|e| with_rounds(e, &accuracy))?;
        let est = estimate(&fine, &coarse, &loose);
        let worst = est.bounded();
        let round = Round {
            nodes,
            rtol,
            atol,
            space: worst.space,
            time: worst.time,
            seconds: round_start.elapsed().as_secs_f64(),
            delivered_cpu_seconds: cpu[0],
            companions_cpu_seconds: cpu[1],
        };
        accuracy.rounds.push(round);
        if worst.total <= tol {
            accuracy.nodes = fine_mesh.len();
            accuracy.rtol = rtol;
            accuracy.atol = atol;
            let mut stats = fine.stats.clone();
            stats.error_estimate = Some(est);
            stats.accuracy = Some(accuracy);
            let parts = super::Parts {
                solver: &s,
                ..parts
            };
            replay(parts, fine_mesh, &fine, &mut stats, sens, output)?;
            stats.wall_seconds = start.elapsed().as_secs_f64();
            if let Some(a) = stats.accuracy.as_mut() {
                a.wall_seconds = stats.wall_seconds;
            }
            return Ok(stats);
        }
        // The sensitivities converge slower in the nodes: where they bound the error, the
        // mesh is predicted at their order.
        let order = if est.largest.worst().total < worst.total {
            SENSITIVITY_MODEL_ORDER
        } else {
            MODEL_SPACE_ORDER
        };
        // Without the margin if the measured errors leave no room for it; if they say tol
        // itself is out of reach (the time error at the tightest rtol, or the nodes past
        // solver.max_nodes), the run stops here rather than run the finest mesh to learn it.
        let choice = next(&round, AIM * tol, max_nodes, order)
            .or_else(|| next(&round, tol, max_nodes, order));
        if accuracy.rounds.len() >= MAX_ROUNDS || choice.is_none_or(|c| c == (nodes, rtol)) {
            let in_sensitivities = order == SENSITIVITY_MODEL_ORDER;
            let out_of_rounds = accuracy.rounds.len() >= MAX_ROUNDS;
            let why = out_of_reach(
                tol,
                &worst,
                in_sensitivities,
                fine_mesh.len(),
                rtol,
                out_of_rounds,
                solver.max_nodes,
            );
            let mut e = refuse(why);
            e.stats = Box::new(fine.stats);
            return Err(with_rounds(e, &accuracy));
        }
        if let Some(c) = choice {
            (nodes, rtol) = c;
        }
    }
}

/// Why `tol` cannot be reached: the estimate of the last round (on `nodes` at `rtol`), in the
/// sensitivities or the lengths, and whether the rounds ran out or no mesh and rtol within
/// the bounds is predicted to reach it.
fn out_of_reach(
    tol: f64,
    worst: &Split,
    in_sensitivities: bool,
    nodes: usize,
    rtol: f64,
    out_of_rounds: bool,
    max_nodes: usize,
) -> String {
    format!(
        "{} = {} cannot be reached in growth: the estimated error was {} mm{} (space {}, time {}) on {} nodes at {} = {}{}",
        Quantity::Tolerance,
        crate::text::number(tol),
        crate::text::number(worst.total),
        if in_sensitivities {
            " in the sensitivities (p·∂y/∂p)"
        } else {
            ""
        },
        crate::text::number(worst.space),
        crate::text::number(worst.time),
        nodes,
        Quantity::RelativeTolerance,
        crate::text::number(rtol),
        if out_of_rounds {
            format!(" after {MAX_ROUNDS} rounds")
        } else {
            format!(
                " and neither more nodes ({} = {}) nor a tighter rtol (down to {}) is predicted to reach it",
                Quantity::MaxNodes,
                max_nodes,
                crate::text::number(RTOL_RANGE.0)
            )
        }
    )
}

/// Hand the delivered run's outputs and sensitivity rows to the caller, in the order of the
/// run: at each output time the growth system on its mesh takes the recorded state (the
/// snapshots re-polish the elastic state, as in the run).
fn replay(
    parts: super::Parts<'_>,
    mesh: Mesh,
    fine: &Recorded,
    stats: &mut GrowthStats,
    sens: &mut SensitivityFn<'_>,
    output: &mut OutputFn<'_>,
) -> Result<(), GrowthError> {
    let fail = |t: f64, reason: String, stats: &GrowthStats| GrowthError {
        t,
        reason,
        stats: Box::new(stats.clone()),
    };
    let super::Parts {
        params,
        solver,
        growth,
        ..
    } = parts;
    let mut sys = GrowthSystem::on_mesh(params, solver, growth, mesh)
        .and_then(|mut sys| sys.set_real_time(parts.real_time.cloned()).map(|_| sys))
        .map_err(|e| fail(0.0, e.to_string(), stats))?;
    // The sensitivity rows of a recorded time come after t = 0's output and before each
    // later one's ([`super::Observer::sensitivities`]).
    let mut rows = fine.sens.iter();
    for ((&t, p), u) in fine.t.iter().zip(&fine.p).zip(&fine.u) {
        if t > 0.0 {
            if let Some(r) = rows.next() {
                sens(r).map_err(|e| fail(t, e.to_string(), stats))?;
            }
        }
        sys.adopt(p, u);
        output(&mut sys, t, p).map_err(|e| fail(t, e.to_string(), stats))?;
        if t == 0.0 {
            if let Some(r) = rows.next() {
                sens(r).map_err(|e| fail(t, e.to_string(), stats))?;
            }
        }
    }
    stats.bvp_solves += sys.work.bvp_solves;
    Ok(())
}
