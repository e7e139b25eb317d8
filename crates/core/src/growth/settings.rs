//! The settings of a growth run, as the scene gives them: the growth model's parameters
//! ([`GrowthParams`]) and the time integration's ([`GrowthSettings`], [`Integrator`],
//! [`DaeLinear`]). The scene reads and writes these types (scene/keys.rs); nothing here
//! reads the scene.

use super::dae::SensParam;
use super::ThicknessLaw;
use crate::model::optics::{ComputedOptics, OpticsSpec, Source};
use crate::model::stimulus::{EyeMeasure, Focal, Refraction, Surface};

/// The shortest growth run (growth.t_end). SUNDIALS compares times by multiplying a
/// distance in time by a step, and below about 1e-160 that product underflows: IDA and CVODE
/// then refuse to step at all ("tstop is behind t") however small the step. 1e-100 leaves
/// steps 1e60 times shorter than the run room; a run that short does not grow anyway.
pub const MIN_T_END: f64 = 1e-100;

/// The growth model of one scene (docs/MODEL.md §4–6).
#[derive(Clone, Debug, PartialEq)]
pub struct GrowthParams {
    /// growth.eta0: η0, the largest growth rate.
    pub eta0: f64,
    /// growth.Gamma: Γ, where the growth capacity falls to half.
    pub gamma: f64,
    /// growth.delta: δ, the width of that fall.
    pub delta: f64,
    /// growth.t_end: the end of the run (dimensionless time).
    pub t_end: f64,
    /// growth.thickness_law.
    pub thickness_law: ThicknessLaw,
    /// The best-focus surface for blue light (growth stops where the retina reaches it).
    pub blue: Surface,
    /// The best-focus surface for red light (for the classification only).
    pub red: Surface,
    /// growth.kink_width: round the [·]⁺ kinks of the growth laws over this width (0, the
    /// default: the model's exact kinks; an option for measuring what they cost).
    pub kink_width: f64,
    /// stimulus.source: the polynomial surfaces above, or surfaces computed from `optics`.
    pub source: Source,
    /// The optics.* keys (used with `Source::Optics`).
    pub optics: OpticsSpec,
    /// The surfaces `optics` gives about `blue.z_b`, traced once ([`GrowthParams::resolved`])
    /// and shared by every copy of these parameters.
    pub computed: Option<std::sync::Arc<ComputedOptics>>,
    /// growth.schedule*: the factor on η0 over time ([`super::schedule`]).
    pub schedule: super::schedule::Schedule,
    /// time.*: the ages the growth window stands for.
    pub clock: super::schedule::Clock,
    /// stimulus.rule, stimulus.region: what drives growth (the paper's rule by default).
    pub stimulus: crate::model::rule::Stimulus,
}

impl GrowthParams {
    /// The age of growth time `t` in time.unit, None without a unit: every output that
    /// carries an `age` beside t asks here, so a scene without ages writes what it always
    /// wrote.
    pub fn age_of(&self, t: f64) -> Option<f64> {
        self.clock.has_ages().then(|| self.clock.age(t))
    }

    /// time.unit's name when the scene counts in ages ("years", "days"), else None.
    pub fn age_unit(&self) -> Option<&'static str> {
        self.clock.has_ages().then(|| self.clock.unit.name())
    }

    /// The blue surface the stimulus reads: the computed one with `Source::Optics` (once
    /// [`GrowthParams::resolved`]), else the polynomial.
    pub fn blue_focal(&self) -> Focal<'_> {
        match (&self.source, &self.computed) {
            (Source::Optics, Some(c)) => Focal::Computed(&c.blue),
            _ => Focal::Polynomial(&self.blue),
        }
    }

    /// The red surface of the classification, as [`GrowthParams::blue_focal`].
    pub fn red_focal(&self) -> Focal<'_> {
        match (&self.source, &self.computed) {
            (Source::Optics, Some(c)) => Focal::Computed(&c.red),
            _ => Focal::Polynomial(&self.red),
        }
    }

    /// True when the stimulus reads optics that change with time (tables over t in
    /// `optics.surfaces`, `stimulus.source = "optics"`): the growth's rates then depend on t
    /// itself, not only through η0's schedule.
    pub fn optics_change(&self) -> bool {
        self.source == Source::Optics && !self.optics.times().is_empty()
    }

    /// True when the stimulus can be read as it is: polynomial surfaces, or computed ones
    /// that are those of the current optics keys and centre.
    pub fn is_resolved(&self) -> bool {
        self.source == Source::Polynomial
            || self
                .computed
                .as_ref()
                .is_some_and(|c| c.is_for(&self.optics, self.blue.z_b))
    }

    /// The optics whose refraction this scene reports: its own with `stimulus.source =
    /// "optics"`, else the defaults (the Atchison 2006 eye, 3 mm pupil, mean sphere,
    /// 555 nm): the eye's optics, not the published polynomial.
    pub fn refraction_optics(&self) -> OpticsSpec {
        crate::model::eyewear::refraction_optics(&self.optics, self.source == Source::Optics)
    }

    /// The refraction (D) at growth time `t` of a retina at `retina_z` on the axis (NaN
    /// beyond ±25 D or when the optics give none): computed at output times only, from a
    /// table traced once; for optics that change with age, once per table time, and the
    /// refractions there blended in t as the surfaces are ([`blend_over_ages`]).
    pub fn refraction(&self, t: f64, retina_z: f64) -> f64 {
        super::refraction::pole(&self.refraction_optics(), t, retina_z)
    }

    /// The peripheral refraction at growth time `t` of the retina through `retina` (its
    /// points (z, r) from the pole outwards): one row per field angle of
    /// [`crate::model::eyewear::peripheral_fields`], with the same optics and conversion as
    /// [`GrowthParams::refraction`] (NaN where the optics give none). Computed at output
    /// times only, from a table traced once (once per table time for optics that change
    /// with age, blended as [`blend_over_ages`] says).
    pub fn peripheral(&self, t: f64, retina: &[(f64, f64)]) -> Vec<super::PeripheralRow> {
        super::refraction::peripheral(&self.refraction_optics(), self.blue.z_b, t, retina)
    }

    /// The refraction through the lenses at growth time `t` of the retina through `retina`
    /// (pole first), one entry per image with its share of the light at each field: the
    /// same tables and conversion as `eyeshell optics` ([`super::refraction::through_lenses`]),
    /// traced once per run (once per table time for optics that change with age); NaN
    /// where they cannot be traced, as [`GrowthParams::peripheral`]'s. None without lenses.
    pub fn through_lenses(
        &self,
        t: f64,
        retina: &[(f64, f64)],
    ) -> Vec<super::refraction::ThroughLenses> {
        let spec = self.refraction_optics();
        let mut through = super::refraction::through_lenses_or_nan(&spec, self.blue.z_b, t, retina);
        if let (Source::Optics, Some(c)) = (&self.source, &self.computed) {
            super::refraction::with_shares(&mut through, c);
        }
        through
    }

    /// `eye` at growth time `t` with its refraction, classified as `stimulus.classify` says.
    /// By dioptres, an eye whose refraction_D is NaN (beyond the ±25 D it is traced over)
    /// is [`Refraction::Unknown`]: the surfaces' rule answers another question (a 35 mm
    /// eye between the two surfaces is not emmetropic in dioptres).
    pub fn measure(&self, t: f64, eye: EyeMeasure) -> EyeMeasure {
        let refraction_d = self.refraction(t, eye.axial_length);
        let class = match self.optics.classify {
            1 if !refraction_d.is_finite() => Refraction::Unknown,
            1 => {
                if refraction_d > self.optics.hyperopia_d {
                    Refraction::Hyperopic
                } else if refraction_d < self.optics.myopia_d {
                    Refraction::Myopic
                } else {
                    Refraction::Emmetropic
                }
            }
            _ => eye.class,
        };
        EyeMeasure {
            refraction_d,
            class,
            ..eye
        }
    }

    /// The dioptre conversion of the stimulus's defocus (docs/MODEL.md §6, "Growth rules"),
    /// when the rule reads defocus: the paraxial eye of `optics.*` at the stimulus's
    /// wavelength (`optics.wavelengths[0]`) with `stimulus.source = "optics"`, else the
    /// default optics' (the Atchison 2006 eye at 400 nm: the published surface is blue).
    ///
    /// # Errors
    /// [`OpticsKeyError`](crate::model::optics::OpticsKeyError) when that eye has no
    /// paraxial image.
    pub fn vergence(
        &self,
    ) -> Result<Option<crate::model::rule::Vergence>, crate::model::optics::OpticsKeyError> {
        if !self.stimulus.rule().reads().defocus {
            return Ok(None);
        }
        let spec = match self.source {
            Source::Optics => self.optics.clone(),
            Source::Polynomial => OpticsSpec::default(),
        };
        let system = spec.system()?;
        let wavelength = spec.wavelengths.first().copied().unwrap_or(400.0);
        let p = eyeshell_optics::paraxial(&system, wavelength).map_err(|e| spec.explain(&e))?;
        Ok(Some(crate::model::rule::Vergence::new(&p)))
    }

    /// These parameters with their surfaces computed if they must be (once: a resolved copy
    /// is returned as it is).
    ///
    /// # Errors
    /// [`OpticsKeyError`](crate::model::optics::OpticsKeyError), naming the optics key to
    /// change, if the surfaces cannot be traced.
    pub fn resolved(
        &self,
    ) -> Result<std::borrow::Cow<'_, GrowthParams>, crate::model::optics::OpticsKeyError> {
        if self.is_resolved() {
            return Ok(std::borrow::Cow::Borrowed(self));
        }
        let computed = self.optics.compute_over(self.blue.z_b, self.t_end)?;
        Ok(std::borrow::Cow::Owned(GrowthParams {
            computed: Some(std::sync::Arc::new(computed)),
            ..self.clone()
        }))
    }
}

impl Default for GrowthParams {
    fn default() -> Self {
        GrowthParams {
            eta0: 70.0,
            gamma: 8.0,
            delta: 4.0,
            t_end: 1.0,
            thickness_law: ThicknessLaw::None,
            blue: Surface::blue(),
            red: Surface::default_red(),
            kink_width: 0.0,
            source: Source::Polynomial,
            optics: OpticsSpec::default(),
            computed: None,
            schedule: super::schedule::Schedule::default(),
            clock: super::schedule::Clock::default(),
            stimulus: crate::model::rule::Stimulus::default(),
        }
    }
}

/// Which time integrator runs the growth. IDA is the default: it wins the const scene's
/// work-precision diagram at every axial-length accuracy from 1e-2 to 1e-7 (BENCHMARKS.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// CVODE: BDF, variable order and step, error-controlled.
    Cvode,
    /// Explicit Euler with a fixed number of steps (docs/MODEL.md §8), for comparison.
    Euler,
    /// IDA: BDF on the coupled DAE of growth and elastic equilibrium (one Newton per step).
    Ida,
}

impl Integrator {
    /// The names `solver.integrator` takes, in the order of the variants.
    pub const NAMES: [&'static str; 3] = ["cvode", "euler", "ida"];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// Numerical settings of the time integration.
#[derive(Clone, Debug, PartialEq)]
pub struct GrowthSettings {
    /// solver.integrator.
    pub integrator: Integrator,
    /// solver.rtol, solver.atol: CVODE's tolerances.
    pub rtol: f64,
    pub atol: f64,
    /// solver.steps: Euler's number of steps to t_end.
    pub steps: usize,
    /// solver.dae_linear: the linear solver of IDA's Newton matrix.
    pub dae_linear: DaeLinear,
    /// output.times: when to write snapshots (sorted, in (0, t_end]); t = 0 is always written.
    pub output_times: Vec<f64>,
    /// output.history_points: record the series row (axial length, class, ...) at this many
    /// evenly spaced times t_end·k/n as well (history.csv), without snapshots; 0: none.
    pub history_points: usize,
    /// Forward sensitivities of the run with respect to these parameters (IDA only;
    /// `eyeshell grow --sensitivities`): [`super::Observer::sensitivities`] at every recorded time.
    pub sensitivities: Vec<SensParam>,
    /// Whether the sensitivities take part in IDAS's local error test (IDASetSensErrCon).
    pub sensitivity_error_control: bool,
}

impl Default for GrowthSettings {
    fn default() -> Self {
        GrowthSettings {
            integrator: Integrator::Ida,
            rtol: 1e-6,
            atol: 1e-8,
            steps: 200,
            dae_linear: super::ida::default_linear(),
            output_times: vec![0.1, 0.2, 0.4, 1.0],
            history_points: 0,
            sensitivities: vec![],
            sensitivity_error_control: false,
        }
    }
}

/// Which linear solver factors the Newton matrix of the coupled system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DaeLinear {
    /// Eliminate the growth unknowns point by point; almost-block-diagonal LU (6×6 node
    /// blocks) of what is left.
    SchurBlock,
    /// Eliminate the growth unknowns point by point; band LU of what is left.
    Schur,
    /// The same elimination; KLU of what is left.
    SchurKlu,
    /// Band LU of the whole system, unknowns interleaved node by node.
    Band,
    /// KLU on the whole sparse system.
    Klu,
}

impl DaeLinear {
    pub const NAMES: [&'static str; 5] = ["schur-block", "schur", "schur-klu", "band", "klu"];
    pub const ALL: [DaeLinear; 5] = [
        DaeLinear::SchurBlock,
        DaeLinear::Schur,
        DaeLinear::SchurKlu,
        DaeLinear::Band,
        DaeLinear::Klu,
    ];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// `values(t_k)` at growth time `t`: for an eye that does not change, at 0; for one whose
/// optics are tables over t, at each table time t_k of `spec` and blended with the weights
/// the best-focus surfaces are blended with (the natural cubic spline through them,
/// [`crate::model::eye::spline_weights`]), so that the optics are traced at the table times
/// only, not at every output and history time. NaN in any is NaN in the blend.
pub fn blend_over_ages(spec: &OpticsSpec, t: f64, values: impl Fn(f64) -> Vec<f64>) -> Vec<f64> {
    let times = spec.times();
    if times.is_empty() {
        return values(0.0);
    }
    let weights = crate::model::eye::spline_weights(&times, t);
    let mut sum: Vec<f64> = vec![];
    for (&at, w) in times.iter().zip(weights) {
        let v = values(at);
        if sum.is_empty() {
            sum = vec![0.0; v.len()];
        }
        for (s, x) in sum.iter_mut().zip(v) {
            *s += w * x;
        }
    }
    sum
}
