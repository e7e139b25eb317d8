//! The two problems eyeshell solves, as values that are valid by construction: the elastic
//! boundary value problem of docs/MODEL.md §3 ([`ElasticProblem`]: the shell's parameters and
//! how its equilibrium is discretised and solved) and the growth DAE of docs/MODEL.md §5–6
//! ([`GrowthProblem`]: that shell, the growth law and its stimulus, and how time is
//! integrated).
//!
//! Their fields are private and their only constructors are the builders' `build`, which
//! check what the numerics rely on: every number finite, the limits that tie parameters
//! together (ΔP below the cornea's limit, ε inside the shell, a mesh that can be laid), and
//! a growth run that can be integrated (tolerances, t_end, output times, schedule, optics).
//! The solvers then take a problem, so they never run on values nobody checked. A scene
//! (the `eyeshell` crate) checks each key's own range as well and builds its problems
//! through these builders; an error here names the quantity, and the scene layer names the
//! key that sets it.

use super::settings::MIN_T_END;
use super::{GrowthParams, GrowthSettings, Integrator};
use crate::bvp::settings::SolverSettings;
use crate::mesh::MeshError;
use crate::model::optics::Source;
use crate::model::params::Params;
use crate::text::{decimals6, number};

/// The quantity of a problem that a [`ProblemError`] is about (crate::names, where every
/// message of core finds it).
pub use crate::names::Quantity;

/// Why a problem cannot be built: the quantity and what is wrong with it, in the model's
/// terms (the scene layer adds the key and the origin).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProblemError {
    /// A number that must be finite (and, for most, positive) is not.
    #[error("{what} = {} {must}", number(*value))]
    OutOfRange {
        quantity: Quantity,
        /// The quantity in words, for the message.
        what: &'static str,
        value: f64,
        /// The end of a sentence "X = value ...".
        must: &'static str,
    },
    /// ΔP above the largest pressure the cornea admits (docs/MODEL.md §3).
    #[error("ΔP = {} kPa is above the cornea's limit {} kPa", number(*dp), decimals6(*limit))]
    AboveCorneaLimit { dp: f64, limit: f64 },
    /// ε at or beyond the shell's length L = π f R0.
    #[error("ε = {} mm is not below the shell's length L = {} mm", number(*epsilon), decimals6(*length))]
    TruncationBeyondShell { epsilon: f64, length: f64 },
    /// The mesh cannot be laid (docs/MODEL.md §3–4).
    #[error("the mesh cannot be laid: {0}")]
    Mesh(MeshError),
    /// Richardson's extrapolation asked of a growth run.
    #[error(
        "Richardson's extrapolation is for elastic solves only: a growth run is not extrapolated"
    )]
    RichardsonInGrowth,
    /// An output time after t_end, or a list not positive and strictly increasing.
    #[error("the output time {} {must}", number(*time))]
    OutputTime { time: f64, must: &'static str },
    /// The schedule, the clock of ages or the optics cannot run over [0, t_end].
    #[error("{problem}")]
    Inadmissible { quantity: Quantity, problem: String },
}

impl ProblemError {
    /// The quantity the error is about.
    pub fn quantity(&self) -> Quantity {
        match self {
            ProblemError::OutOfRange { quantity, .. } => *quantity,
            ProblemError::AboveCorneaLimit { .. } => Quantity::Pressure,
            ProblemError::TruncationBeyondShell { .. } => Quantity::PoleTruncation,
            ProblemError::Mesh(_) => Quantity::Nodes,
            ProblemError::RichardsonInGrowth => Quantity::Richardson,
            ProblemError::OutputTime { .. } => Quantity::OutputTimes,
            ProblemError::Inadmissible { quantity, .. } => *quantity,
        }
    }
}

/// What a number must be.
#[derive(Clone, Copy)]
enum Must {
    Finite,
    Positive,
    NonNegative,
}

fn check(
    quantity: Quantity,
    what: &'static str,
    value: f64,
    must: Must,
) -> Result<(), ProblemError> {
    let (ok, words) = match must {
        Must::Finite => (value.is_finite(), "must be finite"),
        Must::Positive => (
            value.is_finite() && value > 0.0,
            "must be positive and finite",
        ),
        Must::NonNegative => (
            value.is_finite() && value >= 0.0,
            "must be non-negative and finite",
        ),
    };
    match ok {
        true => Ok(()),
        false => Err(ProblemError::OutOfRange {
            quantity,
            what,
            value,
            must: words,
        }),
    }
}

/// The elastic boundary value problem of docs/MODEL.md §3: the loaded shell of `params`,
/// discretised and solved as `solver` says. Built by [`ElasticProblem::builder`].
#[derive(Clone, Debug, PartialEq)]
pub struct ElasticProblem {
    params: Params,
    solver: SolverSettings,
}

/// Builds an [`ElasticProblem`]: the paper's parameters and the default solver unless set.
#[derive(Clone, Debug, Default)]
pub struct ElasticProblemBuilder {
    params: Params,
    solver: SolverSettings,
}

impl ElasticProblemBuilder {
    /// The shell's physical parameters.
    pub fn params(mut self, params: Params) -> Self {
        self.params = params;
        self
    }

    /// How the equilibrium is discretised and solved.
    pub fn solver(mut self, solver: SolverSettings) -> Self {
        self.solver = solver;
        self
    }

    /// The problem, checked.
    ///
    /// # Errors
    /// A [`ProblemError`] for a parameter that is not finite or not positive where the
    /// model needs it, ΔP above the cornea's limit, ε not inside the shell, or a mesh that
    /// cannot be laid.
    pub fn build(self) -> Result<ElasticProblem, ProblemError> {
        let (p, s) = (&self.params, &self.solver);
        use Must::*;
        use Quantity as Q;
        check(Q::Pressure, "ΔP", p.dp, Finite)?;
        check(Q::Modulus, "C", p.c, Positive)?;
        check(Q::Bending, "E_b", p.e_b, NonNegative)?;
        check(Q::Thickness, "H0", p.h0, Positive)?;
        check(Q::FibreStiffness, "D", p.d, NonNegative)?;
        check(Q::CorneaModulus, "C_c", p.cornea.c, Positive)?;
        check(Q::CorneaThickness, "H_c", p.cornea.h, Positive)?;
        check(Q::CorneaRadius, "R_c", p.cornea.r0, Positive)?;
        check(Q::Radius, "R0", p.r0, Positive)?;
        check(Q::Fraction, "f", p.fraction, Positive)?;
        check(Q::PoleTruncation, "ε", s.epsilon, Positive)?;
        check(
            Q::NewtonTolerance,
            "the Newton tolerance",
            s.newton_tol,
            Positive,
        )?;
        if let Some(seconds) = s.max_seconds {
            check(
                Q::MaxSeconds,
                "the solve's wall-clock bound",
                seconds,
                Positive,
            )?;
        }
        if let Some(tol) = s.tol {
            check(Q::Tolerance, "the global error asked for", tol, Positive)?;
        }
        let limit = crate::model::cornea::max_pressure(&p.cornea);
        if p.dp > limit {
            return Err(ProblemError::AboveCorneaLimit { dp: p.dp, limit });
        }
        if s.epsilon >= p.length() {
            return Err(ProblemError::TruncationBeyondShell {
                epsilon: s.epsilon,
                length: p.length(),
            });
        }
        crate::bvp::solve::mesh_plan(p, s).map_err(ProblemError::Mesh)?;
        Ok(ElasticProblem {
            params: self.params,
            solver: self.solver,
        })
    }
}

impl ElasticProblem {
    /// A builder starting from the paper's parameters and the default solver.
    pub fn builder() -> ElasticProblemBuilder {
        ElasticProblemBuilder::default()
    }

    /// A builder starting from this problem (to change a part and check again).
    pub fn to_builder(&self) -> ElasticProblemBuilder {
        ElasticProblemBuilder {
            params: self.params,
            solver: self.solver,
        }
    }

    /// The shell's physical parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// How the equilibrium is discretised and solved.
    pub fn solver(&self) -> &SolverSettings {
        &self.solver
    }

    /// Solve the loaded shell on the mesh `solver.nodes` lays (or, with `solver.tol`, the
    /// adapted one): [`crate::bvp::solve`].
    ///
    /// # Errors
    /// A [`crate::bvp::BvpError`] when the solve fails (no convergence, out of time).
    pub fn solve(&self) -> Result<crate::bvp::Solution, crate::bvp::BvpError> {
        crate::bvp::solve(&self.params, &self.solver, None)
    }
}

/// The growth DAE of docs/MODEL.md §5–6: the shell of an [`ElasticProblem`] grown from
/// t = 0 to t_end by the growth law and stimulus of `growth`, integrated as `settings` say.
/// Built by [`GrowthProblem::builder`].
#[derive(Clone, Debug, PartialEq)]
pub struct GrowthProblem {
    elastic: ElasticProblem,
    growth: GrowthParams,
    settings: GrowthSettings,
}

/// Builds a [`GrowthProblem`] on a checked [`ElasticProblem`]: the default growth model
/// and integration unless set.
#[derive(Clone, Debug)]
pub struct GrowthProblemBuilder {
    elastic: ElasticProblem,
    growth: GrowthParams,
    settings: GrowthSettings,
}

impl GrowthProblemBuilder {
    /// The growth law, its stimulus, schedule and clock, and t_end.
    pub fn growth(mut self, growth: GrowthParams) -> Self {
        self.growth = growth;
        self
    }

    /// The time integration and the output times.
    pub fn settings(mut self, settings: GrowthSettings) -> Self {
        self.settings = settings;
        self
    }

    /// The problem, checked.
    ///
    /// # Errors
    /// A [`ProblemError`] for a growth number that is not finite, a t_end below
    /// [`MIN_T_END`], tolerances that are not positive, output times not positive, not
    /// increasing or after t_end, Richardson's extrapolation asked of a growth run,
    /// sensitivities without IDA, or a schedule, clock or optics that cannot run over
    /// [0, t_end].
    pub fn build(self) -> Result<GrowthProblem, ProblemError> {
        let (g, s) = (&self.growth, &self.settings);
        use Must::*;
        use Quantity as Q;
        check(Q::GrowthRate, "η0", g.eta0, NonNegative)?;
        check(Q::CapacityFall, "Γ", g.gamma, Finite)?;
        check(Q::CapacityWidth, "δ", g.delta, Positive)?;
        check(Q::KinkWidth, "the kink width", g.kink_width, NonNegative)?;
        check(Q::EndTime, "t_end", g.t_end, Positive)?;
        if g.t_end < MIN_T_END {
            return Err(ProblemError::OutOfRange {
                quantity: Q::EndTime,
                what: "t_end",
                value: g.t_end,
                must: "is shorter than the shortest run the integrators can step",
            });
        }
        check(
            Q::RelativeTolerance,
            "the relative tolerance",
            s.rtol,
            Positive,
        )?;
        check(
            Q::AbsoluteTolerance,
            "the absolute tolerance",
            s.atol,
            Positive,
        )?;
        if s.integrator == Integrator::Euler && s.steps == 0 {
            return Err(ProblemError::OutOfRange {
                quantity: Q::Steps,
                what: "Euler's number of steps",
                value: 0.0,
                must: "must be at least 1",
            });
        }
        let mut before = 0.0;
        for &t in &s.output_times {
            if !(t.is_finite() && t > before) {
                return Err(ProblemError::OutputTime {
                    time: t,
                    must: "must be finite, positive and after the one before it",
                });
            }
            if t > g.t_end {
                return Err(ProblemError::OutputTime {
                    time: t,
                    must: "is after t_end",
                });
            }
            before = t;
        }
        if self.elastic.solver.richardson {
            return Err(ProblemError::RichardsonInGrowth);
        }
        if !s.sensitivities.is_empty() && s.integrator != Integrator::Ida {
            return Err(ProblemError::Inadmissible {
                quantity: Q::Sensitivities,
                problem: format!(
                    "sensitivities need the IDA integrator, not {}",
                    s.integrator.name()
                ),
            });
        }
        let inadmissible = |quantity: Quantity| {
            move |problem: String| ProblemError::Inadmissible { quantity, problem }
        };
        (g.clock.check())
            .and_then(|()| g.clock.check_window(g.t_end))
            .and_then(|()| g.schedule.check())
            .and_then(|()| g.schedule.check_window(&g.clock, g.t_end))
            .map_err(|(_, problem)| problem)
            .map_err(inadmissible(Q::Schedule))?;
        if g.source == Source::Optics {
            g.optics
                .check_over(g.t_end)
                .and_then(|()| g.optics.check_growth_wavelengths())
                .map_err(|e| e.to_string())
                .map_err(inadmissible(Q::Optics))?;
        } else if !g.optics.lenses.is_empty() {
            return Err(ProblemError::Inadmissible {
                quantity: Q::Lenses,
                problem: "lenses need the stimulus computed from the optics: the published surfaces are of the naked eye".into(),
            });
        }
        Ok(GrowthProblem {
            elastic: self.elastic,
            growth: self.growth,
            settings: self.settings,
        })
    }
}

impl GrowthProblem {
    /// A builder on the checked shell `elastic`, with the default growth model and
    /// integration.
    pub fn builder(elastic: ElasticProblem) -> GrowthProblemBuilder {
        GrowthProblemBuilder {
            elastic,
            growth: GrowthParams::default(),
            settings: GrowthSettings::default(),
        }
    }

    /// A builder starting from this problem (to change a part and check again).
    pub fn to_builder(&self) -> GrowthProblemBuilder {
        GrowthProblemBuilder {
            elastic: self.elastic.clone(),
            growth: self.growth.clone(),
            settings: self.settings.clone(),
        }
    }

    /// The shell that grows.
    pub fn elastic(&self) -> &ElasticProblem {
        &self.elastic
    }

    /// The shell's physical parameters.
    pub fn params(&self) -> &Params {
        &self.elastic.params
    }

    /// How each elastic equilibrium is discretised and solved.
    pub fn solver(&self) -> &SolverSettings {
        &self.elastic.solver
    }

    /// The growth law, its stimulus, schedule and clock, and t_end.
    pub fn growth(&self) -> &GrowthParams {
        &self.growth
    }

    /// The time integration and the output times.
    pub fn settings(&self) -> &GrowthSettings {
        &self.settings
    }

    /// This problem recording what `settings` ask (the fit's observation times, the
    /// sensitivities to its parameters, no history), integrated as before: `settings`
    /// differ from the checked ones in the outputs only, which the caller chose from them.
    pub(crate) fn recording(&self, settings: GrowthSettings) -> GrowthProblem {
        GrowthProblem {
            elastic: self.elastic.clone(),
            growth: self.growth.clone(),
            settings,
        }
    }
}
