//! Growth in the user's time, and growth rates that vary with it (docs/MODEL.md §11).
//!
//! The clock (`time.unit`, `time.start`, `time.end`): with a unit, the model's time is the
//! age less time.start, t = a − a₀, and the run lasts time.end − time.start; every rate (η0
//! first) is then per unit of time.unit, so the same child grown over a longer window grows
//! the same amount each year. Without a unit, a = t, the paper's dimensionless time.
//!
//! The schedule (`growth.schedule`) multiplies η0 by a factor s(a) ≥ 0. Every growth rate of
//! the model is η0 times a function of the state (docs/MODEL.md §5: η = g_c g_v, g_c ∝ η0),
//! and nothing else in the model depends on time, so the scheduled growth
//! p' = s(a(t)) η0 f(p) is the constant-rate growth on the clock τ = S(t) = ∫₀ᵗ s(a(t')) dt':
//! p(t) = p̃(S(t)). The run integrates p̃ to S(t_end) and records it at S(tᵢ); the integrator
//! never sees s, so a table's points cost it nothing, and a factor of 1 leaves the run as it
//! was, bit for bit (the schedule is not applied at all).
//!
//! The sensitivity of anything measured at t to a parameter θ of the schedule follows from
//! the same identity: ∂L(t)/∂θ = L̃'(S(t)) ∂S(t)/∂θ, with L̃'(τ) = (η0/τ) ∂L̃/∂η0 (the
//! constant-rate growth depends on η0 and τ only through η0 τ), so it needs only the η0
//! sensitivity the run integrates anyway, and ∂S/∂θ in closed form.
//!
//! Optics that change with age read t itself: on τ the growth is p̃' = η0 f(p̃, S⁻¹(τ)), still
//! exact, with the surfaces read at the real time ([`super::real_time`]) and the outputs
//! recorded there. η0's sensitivity stays exact (S does not depend on η0), and so does
//! geometry.R0's difference of runs; the schedule's parameters now move S⁻¹ too and the
//! growth no longer depends on η0 and τ through η0 τ alone, so their identity fails and
//! they are refused ([`super::sensitivity_unavailable`]).

use crate::names::Quantity;
use crate::text::number;

/// time.unit: what the ages of the scene, its data and its outputs are in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimeUnit {
    /// The model's dimensionless t (the paper's).
    #[default]
    None,
    Years,
    Days,
}

impl TimeUnit {
    /// The names `time.unit` takes, in the order of the variants.
    pub const NAMES: [&'static str; 3] = ["none", "years", "days"];
    pub const ALL: [TimeUnit; 3] = [TimeUnit::None, TimeUnit::Years, TimeUnit::Days];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// One of the unit ("year"), for rates: "per year".
    pub fn one(self) -> &'static str {
        ["unit of t", "year", "day"][self as usize]
    }
}

/// The scene's clock: time.unit, time.start, time.end.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clock {
    pub unit: TimeUnit,
    pub start: Option<f64>,
    pub end: Option<f64>,
}

impl Clock {
    /// True when the scene counts in ages (a unit, with its start and end).
    pub fn has_ages(&self) -> bool {
        self.unit != TimeUnit::None
    }

    /// (time.start, time.end) when the scene counts in ages and gives both.
    pub fn window(&self) -> Option<(f64, f64)> {
        match (self.unit, self.start, self.end) {
            (TimeUnit::None, _, _) | (_, None, _) | (_, _, None) => None,
            (_, Some(a0), Some(a1)) => Some((a0, a1)),
        }
    }

    /// The age a₀ at t = 0: time.start with ages, else 0 (a = a₀ + t either way).
    pub fn origin(&self) -> f64 {
        self.window().map_or(0.0, |w| w.0)
    }

    /// The age of model time `t`.
    pub fn age(&self, t: f64) -> f64 {
        self.origin() + t
    }

    /// The model time of age `a`.
    pub fn t_of(&self, a: f64) -> f64 {
        a - self.origin()
    }

    /// Why the clock cannot be used, as (key, problem): a unit without its start or end, an
    /// end not after the start, ages so far apart or so large that their differences are
    /// not resolved.
    pub fn check(&self) -> Result<(), (Quantity, String)> {
        match (self.unit, self.start, self.end) {
            (TimeUnit::None, None, None) => Ok(()),
            (TimeUnit::None, _, _) => Err((
                Quantity::TimeUnit,
                format!(
                    "is \"none\" (dimensionless t), but {} or {} is given: set {} = \"years\" or \"days\" to count in ages",
                    Quantity::TimeStart,
                    Quantity::TimeEnd,
                    Quantity::TimeUnit
                ),
            )),
            (u, None, _) | (u, _, None) => Err((
                Quantity::TimeUnit,
                format!(
                    "is \"{}\", but {} and {} must both be given: the ages mapped onto the growth window [0, {}]",
                    u.name(),
                    Quantity::TimeStart,
                    Quantity::TimeEnd,
                    Quantity::EndTime
                ),
            )),
            (_, Some(a0), Some(a1)) => {
                if a1 <= a0 {
                    return Err((
                        Quantity::TimeEnd,
                        format!(
                            "must come after {} = {} (the ages are out of order)",
                            Quantity::TimeStart,
                            number(a0)
                        ),
                    ));
                }
                if !(a1 - a0).is_finite() || a1 - a0 <= 1e-9 * a0.abs().max(a1.abs()) {
                    return Err((
                        Quantity::TimeEnd,
                        format!(
                            "is too close to {} = {} or too far from it: their difference must be finite and resolved in double precision",
                            Quantity::TimeStart,
                            number(a0)
                        ),
                    ));
                }
                Ok(())
            }
        }
    }
}

impl Clock {
    /// Why the clock cannot be used over a growth window of length `t_end`, as (key,
    /// problem): with ages, the window is time.end − time.start (one clock: t = age −
    /// time.start), so a t_end that is not that length names both.
    pub fn check_window(&self, t_end: f64) -> Result<(), (Quantity, String)> {
        let Some((a0, a1)) = self.window() else {
            return Ok(());
        };
        let length = a1 - a0;
        let min = super::settings::MIN_T_END;
        if length < min {
            return Err((
                Quantity::TimeEnd,
                format!(
                    "is only {} {unit} after {}: the run must last at least {} {unit} (the integrators multiply times by their steps, and for a shorter run that product underflows)",
                    number(length),
                    Quantity::TimeStart,
                    number(min),
                    unit = self.unit.name(),
                ),
            ));
        }
        if (t_end - length).abs() > 4.0 * f64::EPSILON * a0.abs().max(a1.abs()) {
            return Err((
                Quantity::EndTime,
                format!(
                    "is not the window of the ages: with {} = \"{unit}\" the run lasts {} − {} = {} {unit}; leave {} out and give {} per {one} (η per unit of t over t_end = T is η·T/({} − {}) per {one})",
                    Quantity::TimeUnit,
                    Quantity::TimeEnd,
                    Quantity::TimeStart,
                    number(length),
                    Quantity::EndTime,
                    Quantity::GrowthRate,
                    Quantity::TimeEnd,
                    Quantity::TimeStart,
                    one = self.unit.one(),
                    unit = self.unit.name(),
                ),
            ));
        }
        Ok(())
    }
}

/// growth.schedule: the form of the factor s on η0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Form {
    /// s = 1: the paper's constant rate.
    #[default]
    Constant,
    /// s = exp(−(a − a_start)/τ): a rate that declines with the time constant τ
    /// (growth.schedule_tau).
    Exponential,
    /// s = 1/(1 + exp((a − c)/w)): growth that ends around the centre c over the width w
    /// (growth.schedule_centre, growth.schedule_width).
    Logistic,
    /// A table of factors at ages (growth.schedule_times, growth.schedule_factors),
    /// interpolated monotonically and C¹ (Fritsch–Butland tangents; zero slopes at its ends,
    /// held constant beyond them).
    Table,
}

impl Form {
    pub const NAMES: [&'static str; 4] = ["constant", "exponential", "logistic", "table"];
    pub const ALL: [Form; 4] = [
        Form::Constant,
        Form::Exponential,
        Form::Logistic,
        Form::Table,
    ];
}

/// The factor on η0 over time. The parameters are in the scene's time (ages with time.unit,
/// else t); each is read only by its form.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    pub form: Form,
    pub tau: f64,
    pub centre: f64,
    pub width: f64,
    pub times: Vec<f64>,
    pub factors: Vec<f64>,
}

impl Default for Schedule {
    fn default() -> Self {
        Schedule {
            form: Form::Constant,
            tau: 1.0,
            centre: 0.5,
            width: 0.1,
            times: vec![],
            factors: vec![],
        }
    }
}

/// A parameter of a named schedule (forward sensitivities, `fit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScheduleParam {
    Tau,
    Centre,
    Width,
}

impl ScheduleParam {
    /// The quantity it is, for messages.
    pub fn quantity(self) -> Quantity {
        match self {
            ScheduleParam::Tau => Quantity::ScheduleTau,
            ScheduleParam::Centre => Quantity::ScheduleCentre,
            ScheduleParam::Width => Quantity::ScheduleWidth,
        }
    }

    /// The form that holds it.
    pub fn form(self) -> Form {
        match self {
            ScheduleParam::Tau => Form::Exponential,
            _ => Form::Logistic,
        }
    }
}

impl Schedule {
    /// True when the schedule is 1 everywhere (the run is the paper's, untouched).
    pub fn is_constant(&self) -> bool {
        self.form == Form::Constant
    }

    /// Why the schedule cannot be used, as (key, problem): a table whose times are out of
    /// order or whose factors are negative or not finite, lists of different lengths.
    pub fn check(&self) -> Result<(), (Quantity, String)> {
        if self.form != Form::Table {
            return Ok(());
        }
        let (xs, fs) = (&self.times, &self.factors);
        if xs.is_empty() || xs.len() != fs.len() {
            return Err((
                Quantity::ScheduleFactors,
                format!(
                    "holds {} factors for {} times in {}: {} = \"table\" needs one factor at each time (at least one)",
                    fs.len(),
                    xs.len(),
                    Quantity::ScheduleTimes,
                    Quantity::Schedule
                ),
            ));
        }
        for (i, w) in xs.windows(2).enumerate() {
            if w[1] <= w[0] {
                return Err((
                    Quantity::ScheduleTimes,
                    format!(
                        "must be strictly increasing (the ages are out of order): {} (item {}) follows {}",
                        number(w[1]),
                        i + 2,
                        number(w[0])
                    ),
                ));
            }
        }
        if let Some((i, f)) = fs
            .iter()
            .enumerate()
            .find(|(_, f)| !f.is_finite() || **f < 0.0 || **f > MAX_FACTOR)
        {
            return Err((
                Quantity::ScheduleFactors,
                format!(
                    "item {} is {}: a factor on {} must be finite, at least 0 and at most {} (the schedule multiplies the growth rate, which never goes negative)",
                    i + 1,
                    number(*f),
                    Quantity::GrowthRate,
                    number(MAX_FACTOR)
                ),
            ));
        }
        Ok(())
    }
}

impl Schedule {
    /// Why the schedule cannot run over a growth window of length `t_end` on `clock`, as
    /// (key, problem): its clock S(t_end) = ∫₀^t_end s dt must be finite and at least
    /// [`super::settings::MIN_T_END`], or the run would grow nothing it can integrate.
    pub fn check_window(&self, clock: &Clock, t_end: f64) -> Result<(), (Quantity, String)> {
        if self.is_constant() {
            return Ok(());
        }
        let tau_end = Warp::new(self, clock).clock(t_end);
        let min = super::settings::MIN_T_END;
        if !(tau_end.is_finite() && tau_end >= min) {
            let key = match self.form {
                Form::Exponential => Quantity::ScheduleTau,
                Form::Logistic => Quantity::ScheduleCentre,
                Form::Table => Quantity::ScheduleFactors,
                Form::Constant => Quantity::Schedule,
            };
            return Err((
                key,
                format!(
                    "makes the schedule grow nothing that can be integrated: ∫ s dt over the growth window is {} ({} = \"{}\"); it must be finite and at least {}",
                    number(tau_end),
                    Quantity::Schedule,
                    Form::NAMES[self.form as usize],
                    number(min)
                ),
            ));
        }
        Ok(())
    }
}

/// The largest factor a table may hold: larger factors are a rate η0 larger by that much,
/// better given as growth.eta0 itself (whose limits the run checks).
pub const MAX_FACTOR: f64 = 1e6;

/// The schedule of one run on its clock: S(t) and ∂S/∂θ.
#[derive(Clone, Debug)]
pub struct Warp {
    form: Form,
    tau: f64,
    centre: f64,
    width: f64,
    a0: f64,
    table: Option<Hermite>,
}

impl Warp {
    /// The warp of `schedule` on `clock`.
    pub fn new(schedule: &Schedule, clock: &Clock) -> Warp {
        Warp {
            form: schedule.form,
            tau: schedule.tau,
            centre: schedule.centre,
            width: schedule.width,
            a0: clock.origin(),
            table: (schedule.form == Form::Table)
                .then(|| Hermite::new(&schedule.times, &schedule.factors)),
        }
    }

    /// The factor s at model time t.
    pub fn factor(&self, t: f64) -> f64 {
        let a = self.a0 + t;
        match self.form {
            Form::Constant => 1.0,
            Form::Exponential => (-(a - self.a0) / self.tau).exp(),
            Form::Logistic => logistic(-(a - self.centre) / self.width),
            Form::Table => self.table.as_ref().map_or(1.0, |h| h.value(a)),
        }
    }

    /// τ = S(t) = ∫₀ᵗ s dt' = A(a₀ + t) with A(a) = ∫_{a₀}^a s da'.
    pub fn clock(&self, t: f64) -> f64 {
        if self.form == Form::Constant {
            return t;
        }
        let (a, x) = (self.a0 + t, t);
        match self.form {
            Form::Constant => x,
            Form::Exponential => -self.tau * (-x / self.tau).exp_m1(),
            Form::Logistic => {
                let (u, v) = (
                    (a - self.centre) / self.width,
                    (self.a0 - self.centre) / self.width,
                );
                // ∫ 1/(1 + e^{(a−c)/w}) da = a − w softplus((a − c)/w).
                x - self.width * (softplus(u) - softplus(v))
            }
            Form::Table => {
                let h = self.table.as_ref().expect("a table form has its table");
                h.integral(a) - h.integral(self.a0)
            }
        }
    }

    /// ∂S(t)/∂θ for a parameter of the named forms (in the scene's time units of θ).
    pub fn clock_partial(&self, t: f64, p: ScheduleParam) -> f64 {
        let (a, x) = (self.a0 + t, t);
        match (self.form, p) {
            (Form::Exponential, ScheduleParam::Tau) => {
                let e = (-x / self.tau).exp();
                -(-x / self.tau).exp_m1() - (x / self.tau) * e
            }
            (Form::Logistic, ScheduleParam::Centre) => {
                let (u, v) = (
                    (a - self.centre) / self.width,
                    (self.a0 - self.centre) / self.width,
                );
                logistic(u) - logistic(v)
            }
            (Form::Logistic, ScheduleParam::Width) => {
                let (u, v) = (
                    (a - self.centre) / self.width,
                    (self.a0 - self.centre) / self.width,
                );
                -(softplus(u) - u * logistic(u)) + (softplus(v) - v * logistic(v))
            }
            _ => 0.0,
        }
    }

    /// The model time t at which the clock reads τ (the first, where s vanishes over an
    /// interval), by bisection on the monotone S; for progress reports only.
    pub fn time_at(&self, tau: f64, t_end: f64) -> f64 {
        if self.form == Form::Constant {
            return tau;
        }
        let (mut lo, mut hi) = (0.0, t_end);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if self.clock(mid) < tau {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }
}

/// 1/(1 + e^{−x}).
fn logistic(x: f64) -> f64 {
    if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}

/// ln(1 + eˣ), without overflow.
fn softplus(x: f64) -> f64 {
    if x > 0.0 {
        x + (-x).exp().ln_1p()
    } else {
        x.exp().ln_1p()
    }
}

/// A monotone C¹ cubic Hermite interpolant (Fritsch–Butland tangents: the weighted
/// harmonic mean of the neighbouring secants, 0 where they differ in sign), with zero
/// slopes at its ends and held constant beyond them, so that it is C¹ everywhere and keeps
/// to the range of its data on every interval (never below the smallest factor, so never
/// negative).
#[derive(Clone, Debug)]
struct Hermite {
    x: Vec<f64>,
    f: Vec<f64>,
    m: Vec<f64>,
    /// ∫_{x₀}^{x_i} of the interpolant.
    cum: Vec<f64>,
}

impl Hermite {
    fn new(x: &[f64], f: &[f64]) -> Hermite {
        let n = x.len();
        let mut m = vec![0.0; n];
        for i in 1..n.saturating_sub(1) {
            let (h0, h1) = (x[i] - x[i - 1], x[i + 1] - x[i]);
            let (d0, d1) = ((f[i] - f[i - 1]) / h0, (f[i + 1] - f[i]) / h1);
            if d0 * d1 > 0.0 {
                let (w1, w2) = (2.0 * h1 + h0, h1 + 2.0 * h0);
                m[i] = (w1 + w2) / (w1 / d0 + w2 / d1);
            }
        }
        let mut h = Hermite {
            x: x.to_vec(),
            f: f.to_vec(),
            m,
            cum: vec![0.0; n],
        };
        for i in 1..n {
            h.cum[i] = h.cum[i - 1] + h.piece_integral(i - 1, x[i]);
        }
        h
    }

    /// The interval of `a` (clamped to the table).
    fn interval(&self, a: f64) -> usize {
        let n = self.x.len();
        self.x.partition_point(|&xi| xi <= a).clamp(1, n - 1) - 1
    }

    fn piece(&self, i: usize, a: f64) -> f64 {
        let h = self.x[i + 1] - self.x[i];
        let s = (a - self.x[i]) / h;
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * self.f[i]
            + (s3 - 2.0 * s2 + s) * h * self.m[i]
            + (-2.0 * s3 + 3.0 * s2) * self.f[i + 1]
            + (s3 - s2) * h * self.m[i + 1]
    }

    /// ∫_{x_i}^{a} of piece i, a in its interval: two-point Gauss–Legendre, exact for cubics.
    fn piece_integral(&self, i: usize, a: f64) -> f64 {
        let (lo, half) = (self.x[i], 0.5 * (a - self.x[i]));
        let g = half / 3f64.sqrt();
        half * (self.piece(i, lo + half - g) + self.piece(i, lo + half + g))
    }

    fn value(&self, a: f64) -> f64 {
        let n = self.x.len();
        if n == 1 || a <= self.x[0] {
            return self.f[0];
        }
        if a >= self.x[n - 1] {
            return self.f[n - 1];
        }
        self.piece(self.interval(a), a)
    }

    /// ∫_{x₀}^{a} (negative below x₀).
    fn integral(&self, a: f64) -> f64 {
        let n = self.x.len();
        if n == 1 || a <= self.x[0] {
            return self.f[0] * (a - self.x[0]);
        }
        if a >= self.x[n - 1] {
            return self.cum[n - 1] + self.f[n - 1] * (a - self.x[n - 1]);
        }
        let i = self.interval(a);
        self.cum[i] + self.piece_integral(i, a)
    }
}

/// The relative step of geometry.R0's directional difference: small enough that its
/// truncation error (∝ step²) is far below the runs' own error, large enough that their
/// error (≈ solver.rtol·L) divided by the step stays near 1e-3 of ∂L/∂R0 at rtol 1e-6.
pub const RADIUS_STEP: f64 = 1e-3;

/// [`super::run_with`] with a schedule or with sensitivities the DAE does not integrate
/// (the schedule's parameters, geometry.R0): the constant-rate run on the clock τ = S(t),
/// its records relabelled with t, the schedule's sensitivities from η0's and R0's from two
/// more runs at R0(1 ± [`RADIUS_STEP`]).
pub(crate) fn run(
    parts: super::Parts<'_>,
    hooks: super::Hooks<'_, '_>,
) -> Result<super::GrowthStats, super::GrowthError> {
    use super::dae::SensParam;
    let super::Parts {
        growth, settings, ..
    } = parts;
    let fail = |reason: String| super::GrowthError {
        t: 0.0,
        reason,
        stats: Box::default(),
    };
    check_schedule_sensitivities(growth, settings).map_err(fail)?;
    // Optics that change with age are traced over the real window [0, t_end], which the
    // run on the clock reads through S⁻¹ (its own t_end is S(t_end)).
    let growth = &*growth.resolved().map_err(|e| fail(e.to_string()))?;
    let parts = super::Parts { growth, ..parts };
    let clocked = OnClock::new(growth, settings).map_err(fail)?;
    let wanted = settings.sensitivities.clone();
    // geometry.R0: the eye measured at every τ in runs at R0(1 ± step).
    let radius = match wanted.contains(&SensParam::Radius) {
        true => Some(radius_runs(parts, &clocked)?),
        false => None,
    };
    let super::Hooks {
        sens,
        output,
        progress,
    } = hooks;
    let (warp, t_end, pairs) = (&clocked.warp, clocked.t_end, &clocked.pairs);
    let near = |a: f64, b: f64| clocked.near(a, b);
    let mut sens_done = vec![false; pairs.len()];
    let mut out_done = vec![false; pairs.len()];
    let relabel_rows = |rows: &[super::SensitivityRow], t: f64| {
        let at = RowsAt {
            rows,
            t,
            tau: rows[0].t,
        };
        at.in_time(&wanted, parts, &clocked, radius.as_ref())
    };
    let result = super::run_plain(
        super::Parts {
            growth: &clocked.growth,
            settings: &clocked.settings,
            real_time: clocked.real_time.as_ref(),
            ..parts
        },
        super::Hooks {
            sens: &mut |rows| {
                let Some(first) = rows.first() else {
                    return Ok(());
                };
                for (i, &(tau_i, t)) in pairs.iter().enumerate() {
                    if !sens_done[i] && near(tau_i, first.t) {
                        sens_done[i] = true;
                        sens(&relabel_rows(rows, t)?)?;
                    }
                }
                Ok(())
            },
            output: &mut |sys, tau, p| {
                for (i, &(tau_i, t)) in pairs.iter().enumerate() {
                    if !out_done[i] && near(tau_i, tau) {
                        out_done[i] = true;
                        // The record of t reads the eye of t (its surfaces, refraction).
                        sys.on_real_clock(|sys| output(sys, t, p))?;
                    }
                }
                Ok(())
            },
            progress: &mut |tau| progress(warp.time_at(tau, t_end)),
        },
    );
    let relabel = |stats: &mut super::GrowthStats| {
        stats.t_reached = warp.time_at(stats.t_reached, t_end);
    };
    match result {
        Ok(mut stats) => {
            relabel(&mut stats);
            Ok(stats)
        }
        Err(mut e) => {
            e.t = warp.time_at(e.t, t_end);
            relabel(&mut e.stats);
            Err(e)
        }
    }
}

/// A schedule parameter's sensitivity needs the schedule of its form, and optics that do
/// not change with age.
fn check_schedule_sensitivities(
    growth: &super::GrowthParams,
    settings: &super::GrowthSettings,
) -> Result<(), String> {
    for p in &settings.sensitivities {
        if let Some(why) = super::sensitivity_unavailable(*p, growth) {
            return Err(why);
        }
        if let Some(sp) = p.schedule_param() {
            if growth.schedule.form != sp.form() {
                let want = Form::NAMES[sp.form() as usize];
                return Err(format!(
                    "the sensitivity to {} needs {} = \"{want}\" (the scene has \"{}\")",
                    sp.quantity(),
                    Quantity::Schedule,
                    Form::NAMES[growth.schedule.form as usize]
                ));
            }
        }
    }
    Ok(())
}

/// The constant-rate run on the clock τ = S(t): its growth parameters (t_end = S(t_end)),
/// its settings (output times in τ, the DAE's sensitivities with η0's, no history), and
/// every recorded time t after 0 paired with its τ.
struct OnClock {
    warp: Warp,
    /// The run's t_end and S(t_end).
    t_end: f64,
    tau_end: f64,
    /// (τ, t) of every recorded time, (0, 0) first.
    pairs: Vec<(f64, f64)>,
    /// The real time of each τ, when the optics change with age (else the rates read no t).
    real_time: Option<super::real_time::RealTime>,
    growth: super::GrowthParams,
    settings: super::GrowthSettings,
}

impl OnClock {
    fn new(
        growth: &super::GrowthParams,
        settings: &super::GrowthSettings,
    ) -> Result<OnClock, String> {
        use super::dae::SensParam;
        let t_end = growth.t_end;
        let warp = Warp::new(&growth.schedule, &growth.clock);
        let tau_end = warp.clock(t_end);
        let min = super::settings::MIN_T_END;
        if !(tau_end.is_finite() && tau_end >= min) {
            return Err(format!(
                "the schedule grows nothing that can be integrated: ∫ s dt over the growth window is {} ({} = \"{}\"); it must be finite and at least {}",
                number(tau_end),
                Quantity::Schedule,
                Form::NAMES[growth.schedule.form as usize],
                number(min)
            ));
        }
        // Every recorded time after 0 in t, with its τ.
        let times = super::recorded_times(settings, t_end);
        let mut pairs: Vec<(f64, f64)> = vec![(0.0, 0.0)];
        pairs.extend(
            times
                .iter()
                .map(|&t| (if t == t_end { tau_end } else { warp.clock(t) }, t)),
        );
        let mut warped = settings.clone();
        warped.history_points = 0;
        warped.output_times = pairs[1..]
            .iter()
            .map(|p| p.0)
            .filter(|&tau| tau > 0.0 && tau < tau_end)
            .collect();
        warped.output_times.dedup();
        let wanted = &settings.sensitivities;
        warped.sensitivities = wanted.iter().copied().filter(|p| p.in_dae()).collect();
        let outside = wanted.iter().any(|p| !p.in_dae());
        if outside && !warped.sensitivities.contains(&SensParam::Eta0) {
            warped.sensitivities.push(SensParam::Eta0);
        }
        let clocked = super::GrowthParams {
            t_end: tau_end,
            ..growth.clone()
        };
        let changing = growth.optics_change() && !growth.schedule.is_constant();
        if changing {
            super::real_time::check_zeros(&growth.schedule, &growth.clock, t_end)
                .map_err(|(key, problem)| format!("{key} {problem}"))?;
        }
        let real_time = changing.then(|| super::real_time::RealTime::new(warp.clone(), t_end));
        Ok(OnClock {
            warp,
            t_end,
            tau_end,
            pairs,
            real_time,
            growth: clocked,
            settings: warped,
        })
    }

    /// The records at τ: those of every time t whose τ lies within the run's merging of
    /// close times (1e-12 of its end), each once.
    fn near(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * self.tau_end
    }
}

/// The eye measured at every τ in the runs at R0 + h and R0 − h (the step h, then those
/// two records of (τ, [axial length, equatorial radius, retina − blue])).
type RadiusRuns = (f64, Vec<Vec<(f64, [f64; 3])>>);

/// The two runs at R0(1 ± [`RADIUS_STEP`]) for the sensitivity to geometry.R0.
fn radius_runs(
    parts: super::Parts<'_>,
    clocked: &OnClock,
) -> Result<RadiusRuns, super::GrowthError> {
    let params = parts.params;
    let h = RADIUS_STEP * params.r0;
    let mut sides = vec![];
    for r0 in [params.r0 + h, params.r0 - h] {
        let shifted = params.with_radius(r0);
        let plain = super::GrowthSettings {
            sensitivities: vec![],
            ..clocked.settings.clone()
        };
        let mut rows: Vec<(f64, [f64; 3])> = vec![];
        super::run_plain(
            super::Parts {
                params: &shifted,
                growth: &clocked.growth,
                settings: &plain,
                real_time: clocked.real_time.as_ref(),
                ..parts
            },
            super::Hooks {
                sens: &mut |_| Ok(()),
                output: &mut |sys, tau, p| {
                    let r = sys.series(tau, p)?;
                    rows.push((
                        tau,
                        [r.axial_length, r.equatorial_radius, r.retina_minus_blue],
                    ));
                    Ok(())
                },
                progress: &mut |_| Ok(()),
            },
        )
        .map_err(|e| super::GrowthError {
            t: clocked.warp.time_at(e.t, clocked.t_end),
            reason: format!(
                "the run at {radius} = {} for the sensitivity to {radius}: {}",
                number(r0),
                e.reason,
                radius = Quantity::Radius
            ),
            stats: e.stats,
        })?;
        sides.push(rows);
    }
    Ok((h, sides))
}

/// The sensitivity rows the run on the clock recorded at `tau`, to be handed on at `t`.
struct RowsAt<'a> {
    rows: &'a [super::SensitivityRow],
    t: f64,
    tau: f64,
}

impl RowsAt<'_> {
    /// The rows of the parameters `wanted` at t: the DAE's own relabelled, the schedule's
    /// from η0's, geometry.R0's from the runs at R0 ± h, zero for one the run has none of.
    fn in_time(
        &self,
        wanted: &[super::dae::SensParam],
        parts: super::Parts<'_>,
        clocked: &OnClock,
        radius: Option<&RadiusRuns>,
    ) -> Result<Vec<super::SensitivityRow>, super::ObserverError> {
        use super::dae::SensParam;
        let (rows, t, tau) = (self.rows, self.t, self.tau);
        let first = &rows[0];
        let eta_row = rows.iter().find(|r| r.parameter == SensParam::Eta0.key());
        let eta0 = parts.growth.eta0;
        let mut out = Vec::with_capacity(wanted.len());
        for &p in wanted {
            let mut row = match rows.iter().find(|r| r.parameter == p.key()) {
                Some(r) => *r,
                None => super::SensitivityRow {
                    parameter: p.key(),
                    value: p.value(parts.params, parts.growth),
                    d_axial_length: 0.0,
                    d_equatorial_radius: 0.0,
                    d_retina_minus_blue: 0.0,
                    ..*first
                },
            };
            row.t = t;
            if let Some(sp) = p.schedule_param() {
                // ∂x(t)/∂θ = x̃'(τ) ∂S/∂θ, x̃'(τ) = (η0/τ) ∂x̃/∂η0.
                let e = eta_row.expect("η0's sensitivity is integrated with the schedule's");
                let rate = if tau > 0.0 { eta0 / tau } else { 0.0 };
                let ds = clocked.warp.clock_partial(t, sp);
                row.d_axial_length = rate * e.d_axial_length * ds;
                row.d_equatorial_radius = rate * e.d_equatorial_radius * ds;
                row.d_retina_minus_blue = rate * e.d_retina_minus_blue * ds;
            }
            if let (SensParam::Radius, Some((h, sides))) = (p, radius) {
                let at = |side: &Vec<(f64, [f64; 3])>| {
                    side.iter()
                        .find(|(x, _)| clocked.near(*x, tau))
                        .map(|(_, v)| *v)
                };
                let (Some(up), Some(down)) = (at(&sides[0]), at(&sides[1])) else {
                    return Err(format!(
                        "the runs at {} ± {} recorded nothing at t = {}",
                        Quantity::Radius,
                        number(*h),
                        number(t)
                    )
                    .into());
                };
                row.d_axial_length = (up[0] - down[0]) / (2.0 * h);
                row.d_equatorial_radius = (up[1] - down[1]) / (2.0 * h);
                row.d_retina_minus_blue = (up[2] - down[2]) / (2.0 * h);
            }
            out.push(row);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(w: &Warp, t: f64) -> f64 {
        // Composite Simpson of s over [0, t].
        let n = 20_000;
        let h = t / n as f64;
        (0..=n)
            .map(|i| {
                let c = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                c * w.factor(i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    }

    fn ages() -> Clock {
        Clock {
            unit: TimeUnit::Years,
            start: Some(0.25),
            end: Some(20.0),
        }
    }

    /// S(t) is the integral of the factor, for every form, on an age clock.
    #[test]
    fn clock_is_the_integral_of_the_factor() {
        let table = Schedule {
            form: Form::Table,
            times: vec![0.0, 1.0, 3.0, 8.0, 15.0],
            factors: vec![3.0, 2.0, 0.5, 0.5, 0.0],
            ..Schedule::default()
        };
        for s in [
            Schedule {
                form: Form::Exponential,
                tau: 2.5,
                ..Schedule::default()
            },
            Schedule {
                form: Form::Logistic,
                centre: 6.0,
                width: 1.5,
                ..Schedule::default()
            },
            table,
        ] {
            let w = Warp::new(&s, &ages());
            for t in [0.2, 4.0, 10.0, 19.75] {
                let (exact, q) = (w.clock(t), quad(&w, t));
                assert!(
                    (exact - q).abs() < 1e-10,
                    "{:?} t = {t}: {exact} vs {q}",
                    s.form
                );
            }
        }
    }

    /// ∂S/∂θ in closed form against central differences.
    #[test]
    fn clock_partials_match_differences() {
        let cases = [
            (Form::Exponential, ScheduleParam::Tau),
            (Form::Logistic, ScheduleParam::Centre),
            (Form::Logistic, ScheduleParam::Width),
        ];
        for (form, p) in cases {
            let base = Schedule {
                form,
                tau: 2.5,
                centre: 6.0,
                width: 1.5,
                ..Schedule::default()
            };
            let at = |d: f64| {
                let mut s = base.clone();
                match p {
                    ScheduleParam::Tau => s.tau += d,
                    ScheduleParam::Centre => s.centre += d,
                    ScheduleParam::Width => s.width += d,
                }
                Warp::new(&s, &ages())
            };
            for t in [2.0, 8.0, 19.75] {
                let h = 1e-5;
                let fd = (at(h).clock(t) - at(-h).clock(t)) / (2.0 * h);
                let exact = at(0.0).clock_partial(t, p);
                assert!((fd - exact).abs() < 1e-8, "{p:?} t = {t}: {exact} vs {fd}");
                assert!(exact.abs() > 1e-4, "{p:?} t = {t}: {exact}");
            }
        }
    }

    /// The table's interpolant passes its points, stays in the range of its neighbours
    /// (monotone, so never negative), and is C¹ at the points.
    #[test]
    fn table_is_monotone_and_c1() {
        let (x, f) = (vec![0.0, 1.0, 3.0, 8.0], vec![3.0, 2.0, 0.0, 0.0]);
        let h = Hermite::new(&x, &f);
        for (xi, fi) in x.iter().zip(&f) {
            assert_eq!(h.value(*xi), *fi);
        }
        let mut prev = h.value(-1.0);
        for i in 0..=900 {
            let v = h.value(-1.0 + i as f64 * 0.01);
            assert!(v <= prev + 1e-15 && v >= 0.0, "at {}: {v} after {prev}", i);
            prev = v;
        }
        for &xi in &x {
            let e = 1e-7;
            let left = (h.value(xi) - h.value(xi - e)) / e;
            let right = (h.value(xi + e) - h.value(xi)) / e;
            assert!(
                (left - right).abs() < 1e-5,
                "kink at {xi}: {left} vs {right}"
            );
        }
    }

    #[test]
    fn bad_clocks_and_tables_are_refused() {
        let c = Clock {
            unit: TimeUnit::Years,
            start: Some(0.0),
            end: None,
        };
        assert_eq!(c.check().unwrap_err().0, Quantity::TimeUnit);
        let c = Clock {
            start: Some(0.0),
            end: Some(0.0),
            ..ages()
        };
        assert!(c.check().unwrap_err().1.contains("out of order"));
        let mut s = Schedule {
            form: Form::Table,
            times: vec![0.0, 2.0, 1.0],
            factors: vec![1.0, 1.0, 1.0],
            ..Schedule::default()
        };
        assert!(s.check().unwrap_err().1.contains("out of order"));
        s.times = vec![0.0, 1.0, 2.0];
        s.factors = vec![1.0, -0.5, 1.0];
        assert!(s.check().unwrap_err().1.contains("item 2 is -0.5"));
        s.factors = vec![1.0, f64::NAN, 1.0];
        assert!(s.check().unwrap_err().1.contains("finite"));
    }
}
