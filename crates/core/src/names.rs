//! How core's messages name a parameter: by its identifier, a [`Quantity`] (docs/MODEL.md
//! §1–6 for the model's, §4 and §5 for the solvers'), never by a scene key. The words a
//! user reads are the front end's: the `eyeshell` crate's scene layer gives its key table's
//! mapping once ([`name_quantities_by`]), and every message core forms from then on names
//! the parameter by its key. A program that uses core alone reads the mathematical names of
//! [`Quantity::symbol`] ("η0", "t_end", "tol").
//!
//! The words are a function from identifiers to names, set once: core's messages are
//! formed deep inside the integrators (in SUNDIALS callbacks and growth's reasons), where
//! no caller's value reaches, so the mapping is looked up where a message is written.

use std::sync::OnceLock;

/// A parameter of the model or of its solvers, named after the mathematics (docs/MODEL.md
/// §1–6): what a [`ProblemError`](crate::problem::ProblemError) or any other message of
/// core is about. The scene layer maps each to the key that sets it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Quantity {
    /// ΔP, the pressure difference.
    Pressure,
    /// C, the sclera's neo-Hookean modulus.
    Modulus,
    /// E_b, the bending stiffness.
    Bending,
    /// H0, the uniform thickness.
    Thickness,
    /// D, the fibre stiffness.
    FibreStiffness,
    /// C_c, H_c, R_c: the cornea's modulus, thickness and radius.
    CorneaModulus,
    CorneaThickness,
    CorneaRadius,
    /// R0, the reference sphere's radius.
    Radius,
    /// f, with L = π f R0.
    Fraction,
    /// ε, the pole's truncation.
    PoleTruncation,
    /// The Newton tolerance of the elastic solve.
    NewtonTolerance,
    /// The number of uniform nodes.
    Nodes,
    /// The wall-clock bound of a solve.
    MaxSeconds,
    /// The global error asked of the elastic solve.
    Tolerance,
    /// Richardson's extrapolation (elastic solves only).
    Richardson,
    /// η0, Γ, δ, the kink width: the growth law's numbers.
    GrowthRate,
    CapacityFall,
    CapacityWidth,
    KinkWidth,
    /// t_end, the end of the growth run.
    EndTime,
    /// The integrators' relative and absolute tolerances.
    RelativeTolerance,
    AbsoluteTolerance,
    /// Euler's number of steps.
    Steps,
    /// The snapshot times.
    OutputTimes,
    /// The forward sensitivities asked for.
    Sensitivities,
    /// The growth schedule and the clock of ages.
    Schedule,
    /// The optics the stimulus is computed from, and the lenses in front of the eye.
    Optics,
    Lenses,
    /// The most nodes the adaptive mesh may have, and the integrator of a growth run.
    MaxNodes,
    Integrator,
    /// Where the stimulus comes from, and z_B, the blue best-focus surface's polar centre.
    StimulusSource,
    BlueCentre,
    /// The named schedules' τ, centre and width, and a table schedule's times and factors.
    ScheduleTau,
    ScheduleCentre,
    ScheduleWidth,
    ScheduleTimes,
    ScheduleFactors,
    /// The clock of ages: its unit and the ages at t = 0 and t_end.
    TimeUnit,
    TimeStart,
    TimeEnd,
    /// The optics' pupil diameter and position, wavelengths, largest field angle, focus
    /// criterion, surfaces and the wavelength the refraction is taken at.
    Pupil,
    PupilPosition,
    Wavelengths,
    MaxField,
    Focus,
    Surfaces,
    RefractionWavelength,
}

/// A front end's words for the quantities: what a message calls each.
pub type Words = fn(Quantity) -> &'static str;

static WORDS: OnceLock<Words> = OnceLock::new();

/// Name the quantities in every later message by `words` (the scene layer's keys). The
/// first front end's words are kept for the life of the process: a second call changes
/// nothing, so a message never names one parameter in two ways.
pub fn name_quantities_by(words: Words) {
    let _ = WORDS.set(words);
}

impl Quantity {
    /// The quantity's name in the model's notation (docs/MODEL.md), or the solver
    /// setting's plain name: what a message says when no front end gave its words.
    pub fn symbol(self) -> &'static str {
        use Quantity as Q;
        match self {
            Q::Pressure => "ΔP",
            Q::Modulus => "C",
            Q::Bending => "E_b",
            Q::Thickness => "H0",
            Q::FibreStiffness => "D",
            Q::CorneaModulus => "C_c",
            Q::CorneaThickness => "H_c",
            Q::CorneaRadius => "R_c",
            Q::Radius => "R0",
            Q::Fraction => "f",
            Q::PoleTruncation => "ε",
            Q::NewtonTolerance => "newton_tol",
            Q::Nodes => "nodes",
            Q::MaxSeconds => "max_seconds",
            Q::Tolerance => "tol",
            Q::Richardson => "richardson",
            Q::GrowthRate => "η0",
            Q::CapacityFall => "Γ",
            Q::CapacityWidth => "δ",
            Q::KinkWidth => "kink_width",
            Q::EndTime => "t_end",
            Q::RelativeTolerance => "rtol",
            Q::AbsoluteTolerance => "atol",
            Q::Steps => "steps",
            Q::OutputTimes => "output times",
            Q::Sensitivities => "sensitivities",
            Q::Schedule => "schedule",
            Q::Optics => "eye",
            Q::Lenses => "lenses",
            Q::MaxNodes => "max_nodes",
            Q::Integrator => "integrator",
            Q::StimulusSource => "stimulus source",
            Q::BlueCentre => "z_B",
            Q::ScheduleTau => "τ",
            Q::ScheduleCentre => "schedule centre",
            Q::ScheduleWidth => "schedule width",
            Q::ScheduleTimes => "schedule times",
            Q::ScheduleFactors => "schedule factors",
            Q::TimeUnit => "time unit",
            Q::TimeStart => "start age",
            Q::TimeEnd => "end age",
            Q::Pupil => "pupil",
            Q::PupilPosition => "pupil position",
            Q::Wavelengths => "wavelengths",
            Q::MaxField => "max_field",
            Q::Focus => "focus",
            Q::Surfaces => "surfaces",
            Q::RefractionWavelength => "refraction wavelength",
        }
    }

    /// What messages call the quantity: the front end's word for it
    /// ([`name_quantities_by`]), else its [`symbol`](Quantity::symbol).
    pub fn name(self) -> &'static str {
        WORDS
            .get()
            .map_or_else(|| self.symbol(), |words| words(self))
    }
}

impl std::fmt::Display for Quantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_a_front_end_the_names_are_the_models() {
        // Core's own tests never install words: this binary links no front end.
        assert_eq!(Quantity::GrowthRate.to_string(), "η0");
        assert_eq!(Quantity::EndTime.name(), "t_end");
        assert_eq!(Quantity::Pressure.symbol(), "ΔP");
    }
}
