//! The scene layer's words for core's identifiers: each [`Quantity`] the numerics name in a
//! message (docs/MODEL.md §1–6 for the model's, §4–5 for the solvers') and each
//! [`SensParam`] mapped to the scene key that sets it. Core holds no key: it names a
//! parameter by its identifier and writes the words given here ([`speak_in_keys`], done by
//! the first [`Scene`](super::Scene) a process makes), so every message a user reads names
//! the key they would change.

use crate::growth::dae::SensParam;
pub use eyeshell_core::names::Quantity;

/// The scene key that sets `quantity`.
pub fn key_of(quantity: Quantity) -> &'static str {
    use Quantity as Q;
    match quantity {
        Q::Pressure => "pressure.dP",
        Q::Modulus => "material.C",
        Q::Bending => "material.bending",
        Q::Thickness => "material.H0",
        Q::FibreStiffness => "fibres.D",
        Q::CorneaModulus => "cornea.C",
        Q::CorneaThickness => "cornea.H",
        Q::CorneaRadius => "cornea.R0",
        Q::Radius => "geometry.R0",
        Q::Fraction => "geometry.fraction",
        Q::PoleTruncation => "solver.epsilon",
        Q::NewtonTolerance => "solver.newton_tol",
        Q::Nodes => "solver.nodes",
        Q::MaxSeconds => "solver.max_seconds",
        Q::Tolerance => "solver.tol",
        Q::Richardson => "solver.richardson",
        Q::GrowthRate => "growth.eta0",
        Q::CapacityFall => "growth.Gamma",
        Q::CapacityWidth => "growth.delta",
        Q::KinkWidth => "growth.kink_width",
        Q::EndTime => "growth.t_end",
        Q::RelativeTolerance => "solver.rtol",
        Q::AbsoluteTolerance => "solver.atol",
        Q::Steps => "solver.steps",
        Q::OutputTimes => "output.times",
        // A problem's refusal of the sensitivities is about the integrator they need.
        Q::Sensitivities | Q::Integrator => "solver.integrator",
        Q::Schedule => "growth.schedule",
        Q::Optics => "optics.eye",
        Q::Lenses => "optics.lenses",
        Q::MaxNodes => "solver.max_nodes",
        Q::StimulusSource => "stimulus.source",
        Q::BlueCentre => "stimulus.blue.z_B",
        Q::ScheduleTau => "growth.schedule_tau",
        Q::ScheduleCentre => "growth.schedule_centre",
        Q::ScheduleWidth => "growth.schedule_width",
        Q::ScheduleTimes => "growth.schedule_times",
        Q::ScheduleFactors => "growth.schedule_factors",
        Q::TimeUnit => "time.unit",
        Q::TimeStart => "time.start",
        Q::TimeEnd => "time.end",
        Q::Pupil => "optics.pupil",
        Q::PupilPosition => "optics.pupil_position",
        Q::Wavelengths => "optics.wavelengths",
        Q::MaxField => "optics.max_field",
        Q::Focus => "optics.focus",
        Q::Surfaces => "optics.surfaces",
        Q::RefractionWavelength => "optics.refraction_wavelength",
        // The core may name quantities this table does not know yet.
        _ => "(scene)",
    }
}

/// Give core the scene's words: from now on every message of the numerics names a
/// parameter by its key. Idempotent and cheap; the first scene of a process calls it.
pub fn speak_in_keys() {
    eyeshell_core::names::name_quantities_by(key_of);
}

/// The scene key of a sensitivity parameter.
pub fn sensitivity_key(param: SensParam) -> &'static str {
    key_of(param.quantity())
}

/// Every parameter sensitivities can be taken to, the DAE's then the others
/// ([`SensParam::ALL`], [`SensParam::OUTSIDE`]).
pub fn sensitivity_params() -> impl Iterator<Item = SensParam> {
    SensParam::ALL.into_iter().chain(SensParam::OUTSIDE)
}

/// The keys sensitivities can be taken to, for messages and help: "growth.eta0, …".
pub fn supported_sensitivities() -> String {
    sensitivity_params()
        .map(sensitivity_key)
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every quantity core can name, one of each.
    const QUANTITIES: [Quantity; 48] = {
        use Quantity as Q;
        [
            Q::Pressure,
            Q::Modulus,
            Q::Bending,
            Q::Thickness,
            Q::FibreStiffness,
            Q::CorneaModulus,
            Q::CorneaThickness,
            Q::CorneaRadius,
            Q::Radius,
            Q::Fraction,
            Q::PoleTruncation,
            Q::NewtonTolerance,
            Q::Nodes,
            Q::MaxSeconds,
            Q::Tolerance,
            Q::Richardson,
            Q::GrowthRate,
            Q::CapacityFall,
            Q::CapacityWidth,
            Q::KinkWidth,
            Q::EndTime,
            Q::RelativeTolerance,
            Q::AbsoluteTolerance,
            Q::Steps,
            Q::OutputTimes,
            Q::Sensitivities,
            Q::Schedule,
            Q::Optics,
            Q::Lenses,
            Q::MaxNodes,
            Q::Integrator,
            Q::StimulusSource,
            Q::BlueCentre,
            Q::ScheduleTau,
            Q::ScheduleCentre,
            Q::ScheduleWidth,
            Q::ScheduleTimes,
            Q::ScheduleFactors,
            Q::TimeUnit,
            Q::TimeStart,
            Q::TimeEnd,
            Q::Pupil,
            Q::PupilPosition,
            Q::Wavelengths,
            Q::MaxField,
            Q::Focus,
            Q::Surfaces,
            Q::RefractionWavelength,
        ]
    };

    #[test]
    fn every_quantity_names_a_key_of_the_table() {
        for q in QUANTITIES {
            let key = key_of(q);
            assert!(
                super::super::keys::find(key).is_some(),
                "{q:?} maps to {key:?}, which is not a scene key"
            );
        }
        // Two quantities share a key (the sensitivities' refusal names the integrator);
        // every other key is one quantity's.
        let mut keys: Vec<&str> = QUANTITIES.iter().map(|q| key_of(*q)).collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), QUANTITIES.len() - 1);
    }

    #[test]
    fn a_scene_gives_core_its_keys() {
        let _ = super::super::Scene::default();
        assert_eq!(Quantity::GrowthRate.to_string(), "growth.eta0");
        assert_eq!(SensParam::Radius.key(), "geometry.R0");
        assert_eq!(
            crate::bvp::BvpError::PrecisionLimit {
                newton_tol: 1e-12,
                residual: 3e-11,
                step: 1e-14,
                nodes: 801,
            }
            .to_string(),
            "Newton stalled at a scaled residual of 3.00e-11 on 801 nodes, its Newton correction only 1.0e-14 (scaled): the residual's round-off; solver.newton_tol = 1e-12 is below what double precision reaches on this mesh: ask for solver.newton_tol = 1e-10 or more"
        );
    }

    #[test]
    fn every_sensitivity_parameter_has_its_own_key() {
        let keys: Vec<&str> = sensitivity_params().map(sensitivity_key).collect();
        assert_eq!(
            supported_sensitivities(),
            "growth.eta0, growth.Gamma, growth.delta, fibres.D, material.C, material.bending, pressure.dP, stimulus.blue.z_B, growth.schedule_tau, growth.schedule_centre, growth.schedule_width, geometry.R0"
        );
        let mut unique = keys.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), keys.len());
    }
}
