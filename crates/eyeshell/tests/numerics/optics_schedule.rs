//! Optics that change with age beside a growth schedule (docs/guide/optics.md, "Optics with
//! age"): scenes/optics-age.toml with s = exp(−t/0.5) on η0. The run integrates the
//! constant-rate growth on the clock τ = S(t), its surfaces read at t = S⁻¹(τ); the reference
//! here never sees that clock: it steps the growth p' = s(t) G(p, t) in real t with a plain
//! fixed-step RK4 (the growth system's right side at t, its surfaces blended at t, times the
//! factor computed here), which the model allows because every rate is η0 times a function of
//! the state and the optics (docs/MODEL.md §5).

use eyeshell::growth::dae::SensParam;
use eyeshell::growth::real_time::RealTime;
use eyeshell::growth::schedule::{Clock, Schedule, Warp};
use eyeshell::growth::system::GrowthSystem;
use eyeshell::growth::{self, GrowthProblem, SensitivityRow};
use eyeshell::scene::Scene;

/// The schedule's time constant (in t).
const TAU: f64 = 0.5;
/// The times compared.
const TIMES: [f64; 3] = [0.25, 0.5, 1.0];

fn scene(extra: &[&str]) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/optics-age.toml");
    let mut sets: Vec<String> = [
        "solver.nodes=51",
        "solver.rtol=1e-10",
        "solver.atol=1e-12",
        "output.history_points=0",
        "output.times=[0.25, 0.5, 1.0]",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    sets.extend(extra.iter().map(|s| s.to_string()));
    Scene::from_file(&path, &sets).unwrap()
}

fn scheduled(extra: &[&str]) -> Scene {
    let mut sets = vec!["growth.schedule=exponential", "growth.schedule_tau=0.5"];
    sets.extend_from_slice(extra);
    scene(&sets)
}

fn problem(s: &Scene) -> GrowthProblem {
    s.growth_problem().unwrap().unwrap()
}

/// Axial length at t = 0 and at every output time, from a growth run.
fn axial_lengths(p: &GrowthProblem) -> Vec<(f64, f64)> {
    let mut out = vec![];
    growth::run(
        p,
        &mut |sys, t, p| {
            out.push((t, sys.series(t, p)?.axial_length));
            Ok(())
        },
        &mut |_| Ok(()),
    )
    .unwrap();
    out
}

/// RK4 in real t on `steps` steps over [0, 1] with the factor exp(−t/[`TAU`]): the axial
/// length at each of [`TIMES`].
fn rk4(p: &GrowthProblem, steps: usize) -> Vec<f64> {
    rk4_with(p, steps, |t| (-t / TAU).exp())
}

/// RK4 of p' = s(t) G(p, t) in real t on `steps` steps over [0, 1]: the axial length at
/// each of [`TIMES`].
fn rk4_with(p: &GrowthProblem, steps: usize, factor: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut sys = GrowthSystem::new(p.params(), p.solver(), p.growth()).unwrap();
    let mut y = sys.points.initial_state();
    let n = y.len();
    let h = 1.0 / steps as f64;
    let f = |sys: &mut GrowthSystem, t: f64, y: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; n];
        sys.set_time(t).unwrap();
        sys.rhs(y, &mut out).unwrap();
        let s = factor(t);
        out.iter_mut().for_each(|v| *v *= s);
        out
    };
    let mut lengths = vec![];
    for k in 0..steps {
        let t = k as f64 * h;
        let k1 = f(&mut sys, t, &y);
        let y2: Vec<f64> = (0..n).map(|i| y[i] + 0.5 * h * k1[i]).collect();
        let k2 = f(&mut sys, t + 0.5 * h, &y2);
        let y3: Vec<f64> = (0..n).map(|i| y[i] + 0.5 * h * k2[i]).collect();
        let k3 = f(&mut sys, t + 0.5 * h, &y3);
        let y4: Vec<f64> = (0..n).map(|i| y[i] + h * k3[i]).collect();
        let k4 = f(&mut sys, t + h, &y4);
        for i in 0..n {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        let t1 = (k + 1) as f64 * h;
        if TIMES.iter().any(|&x| (x - t1).abs() < 1e-12) {
            lengths.push(sys.series(t1, &y).unwrap().axial_length);
        }
    }
    lengths
}

/// The scheduled run with optics that change with age agrees with RK4 in real t: RK4 on 200
/// and 400 steps differ by less than the agreement asked, and the run (IDA at rtol 1e-10 on
/// the clock, the surfaces at S⁻¹(τ)) is within 1e-6 mm of RK4 on 400 steps at every time,
/// while the schedule shortens the eye at t = 1 by tenths of a millimetre.
#[test]
fn the_scheduled_optics_age_growth_is_rk4_in_real_time() {
    let scheduled = problem(&scheduled(&[]));
    let run = axial_lengths(&scheduled);
    let coarse = rk4(&scheduled, 200);
    let fine = rk4(&scheduled, 400);
    for (k, &t) in TIMES.iter().enumerate() {
        let (tr, l) = run[k + 1];
        assert_eq!(tr, t);
        println!(
            "t = {t}: run {l:.9}, RK4 400 {:.9} (run − RK4 {:.2e}), RK4 200 − 400 {:.2e}",
            fine[k],
            l - fine[k],
            coarse[k] - fine[k]
        );
        agrees_with_rk4(t, l, coarse[k], fine[k]);
    }
    let unscheduled = axial_lengths(&problem(&scene(&[])));
    let (last, plain) = (run.last().unwrap().1, unscheduled.last().unwrap().1);
    println!("t = 1: scheduled {last:.6} mm, unscheduled {plain:.6} mm");
    assert!(
        plain - last > 0.1,
        "the schedule grows less: {last} vs {plain}"
    );
}

/// The run's `l` at `t` within 1e-6 mm of RK4's finer run, which has converged (its coarser
/// run within 2e-7 of it).
fn agrees_with_rk4(t: f64, l: f64, coarse: f64, fine: f64) {
    assert!(
        (coarse - fine).abs() < 2e-7,
        "RK4 has not converged at t = {t}"
    );
    assert!((l - fine).abs() < 1e-6, "t = {t}: run {l} vs RK4 {fine}");
}

/// On an age clock (time.unit = "years", time.start = 0.25, time.end = 1.25: t = age − 0.25)
/// with a logistic schedule in ages (half at age 0.75, width 0.1), the optics' tables over t
/// and the schedule's ages each keep their own origin: the run agrees with RK4 in real t of
/// s = 1/(1 + e^((0.25 + t − 0.75)/0.1)), and not with the schedule's origin forgotten.
#[test]
fn on_an_age_clock_the_schedule_reads_ages_and_the_optics_t() {
    use eyeshell::growth::schedule::{Form, TimeUnit};
    let base = problem(&scene(&[]));
    let mut g = base.growth().clone();
    g.clock = Clock {
        unit: TimeUnit::Years,
        start: Some(0.25),
        end: Some(1.25),
    };
    g.schedule = Schedule {
        form: Form::Logistic,
        centre: 0.75,
        width: 0.1,
        ..Schedule::default()
    };
    let p = base.to_builder().growth(g).build().unwrap();
    let run = axial_lengths(&p);
    let logistic = |a: f64| 1.0 / (1.0 + ((a - 0.75) / 0.1).exp());
    // The logistic's fall over 0.1 asks for finer steps than the exponential's.
    let fine = rk4_with(&p, 800, |t| logistic(0.25 + t));
    let coarse = rk4_with(&p, 400, |t| logistic(0.25 + t));
    let forgotten = rk4_with(&p, 200, logistic);
    for (k, &t) in TIMES.iter().enumerate() {
        let l = run[k + 1].1;
        println!(
            "t = {t}: run − RK4 {:.2e}, RK4 400 − 800 {:.2e}, origin forgotten {:.2e}",
            l - fine[k],
            coarse[k] - fine[k],
            forgotten[k] - fine[k]
        );
        agrees_with_rk4(t, l, coarse[k], fine[k]);
    }
    assert!((forgotten[2] - fine[2]).abs() > 1e-2);
}

/// The wrong clock for the optics is visible: the growth system reading the surfaces at τ
/// instead of S⁻¹(τ) gives rates that differ, at a state and clock time inside the run.
#[test]
fn the_surfaces_are_read_at_the_real_time() {
    let p = problem(&scheduled(&[]));
    let warp = Warp::new(&p.growth().schedule, &p.growth().clock);
    let mut real = GrowthSystem::new(p.params(), p.solver(), p.growth()).unwrap();
    real.set_real_time(Some(RealTime::new(warp.clone(), 1.0)))
        .unwrap();
    let mut direct = GrowthSystem::new(p.params(), p.solver(), p.growth()).unwrap();
    let y = real.points.initial_state();
    let (mut a, mut b) = (vec![0.0; y.len()], vec![0.0; y.len()]);
    let t = 0.3;
    let tau = warp.clock(t);
    real.set_time(tau).unwrap();
    real.rhs(&y, &mut a).unwrap();
    // The eye of real time t, read directly: the same rates, bit for bit.
    direct.set_time(t).unwrap();
    direct.rhs(&y, &mut b).unwrap();
    let largest_difference = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let diff = largest_difference(&a, &b);
    assert!(
        diff < 1e-12 * a.iter().map(|x| x.abs()).fold(0.0, f64::max),
        "{diff}"
    );
    // The eye of t = τ: other rates.
    direct.set_time(tau).unwrap();
    direct.rhs(&y, &mut b).unwrap();
    let diff = largest_difference(&a, &b);
    assert!(
        diff > 1e-4 * a.iter().map(|x| x.abs()).fold(0.0, f64::max),
        "{diff}"
    );
}

/// A constant warp, or optics without tables under any warp, leave the growth system's rates
/// bit for bit as without one.
#[test]
fn a_constant_schedule_or_fixed_optics_change_nothing() {
    let fixed = problem(&scheduled(&["optics.surfaces=[{}, {}]"]));
    let changing = problem(&scheduled(&[]));
    let exponential = Warp::new(&changing.growth().schedule, &Clock::default());
    let constant = Warp::new(&Schedule::default(), &Clock::default());
    for (p, warp) in [(&changing, constant), (&fixed, exponential)] {
        let mut with = GrowthSystem::new(p.params(), p.solver(), p.growth()).unwrap();
        with.set_real_time(Some(RealTime::new(warp, 1.0))).unwrap();
        let mut without = GrowthSystem::new(p.params(), p.solver(), p.growth()).unwrap();
        let y = with.points.initial_state();
        for t in [0.0, 0.1, 0.37, 1.0] {
            let (mut a, mut b) = (vec![0.0; y.len()], vec![0.0; y.len()]);
            with.set_time(t).unwrap();
            with.rhs(&y, &mut a).unwrap();
            without.set_time(t).unwrap();
            without.rhs(&y, &mut b).unwrap();
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "t = {t}"
            );
        }
    }
}

/// A schedule that is 1 everywhere, given as a table (so run on the clock S(t) = t, its
/// surfaces through S⁻¹), is the unscheduled run to rounding.
#[test]
fn a_table_of_ones_is_no_schedule() {
    let ones = axial_lengths(&problem(&scene(&[
        "growth.schedule=table",
        "growth.schedule_times=[0, 0.5, 1]",
        "growth.schedule_factors=[1, 1, 1]",
    ])));
    let plain = axial_lengths(&problem(&scene(&[])));
    assert_eq!(ones.len(), plain.len());
    for (a, b) in ones.iter().zip(&plain) {
        assert_eq!(a.0, b.0);
        println!("t = {}: {:.3e}", a.0, a.1 - b.1);
        assert!(
            (a.1 - b.1).abs() < 1e-14 * b.1,
            "t = {}: {} vs {}",
            a.0,
            a.1,
            b.1
        );
    }
}

/// The sensitivity rows of the scheduled run at each output time. The outputs are measured
/// as a caller's would be: with an output that leaves the elastic state of t = 0 unpolished,
/// IDA at rtol 1e-10 fails its first step with or without a schedule.
fn sensitivities(p: &GrowthProblem) -> Vec<SensitivityRow> {
    let mut rows = vec![];
    growth::run_with(
        p,
        &mut |r| {
            rows.extend_from_slice(r);
            Ok(())
        },
        &mut |sys, t, p| sys.series(t, p).map(|_| ()).map_err(Into::into),
        &mut |_| Ok(()),
    )
    .unwrap();
    rows
}

/// η0's (integrated by IDAS on the clock) and geometry.R0's (runs at R0(1 ± 1e-3)) beside the
/// schedule and the changing optics against central differences of whole scheduled runs.
#[test]
fn eta0_and_r0_sensitivities_beside_the_schedule_match_central_differences() {
    let mut s = scheduled(&[]);
    s.growth_settings.sensitivities = vec![SensParam::Eta0, SensParam::Radius];
    let rows = sensitivities(&problem(&s));
    let cases = [
        (SensParam::Eta0, "growth.eta0", 70.0, 0.7),
        (SensParam::Radius, "geometry.R0", 10.0, 0.02),
    ];
    for (param, key, value, h) in cases {
        let at = |v: f64| axial_lengths(&problem(&scheduled(&[&format!("{key}={v}")])));
        let (up, down) = (at(value + h), at(value - h));
        let fd: Vec<f64> = (0..TIMES.len())
            .map(|k| (up[k + 1].1 - down[k + 1].1) / (2.0 * h))
            .collect();
        let top = fd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(top > 1e-2, "{key}: largest ∂L/∂p {top}");
        for (k, &t) in TIMES.iter().enumerate() {
            let row = rows
                .iter()
                .find(|r| r.parameter == param.key() && r.t == t)
                .unwrap();
            let err = (row.d_axial_length - fd[k]).abs();
            println!(
                "{key} t = {t}: {:.6e} vs central {:.6e} ({:.1e} of the largest)",
                row.d_axial_length,
                fd[k],
                err / top
            );
            assert!(
                err < 2e-3 * top,
                "{key} at t = {t}: {} vs {}",
                row.d_axial_length,
                fd[k]
            );
        }
    }
}
