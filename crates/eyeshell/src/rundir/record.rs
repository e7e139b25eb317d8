//! How summary.json and fit.json record the numerics' types.
//!
//! The statistics, error estimates, accuracy choices and model components are
//! eyeshell-core's plain types, which know nothing of JSON; their form in the run
//! directory is decided here, once, by serde's remote derives (mirror definitions of the
//! core's structs, field for field, with the attributes of the file's format: `null` read
//! back as NaN, missing fields at their defaults, empty optional parts left out). The
//! compiler checks each mirror against its type: a field added in the core without its
//! line here does not build.
//!
//! A missing field takes the default of the core's type: the mirrors derive `Default` as
//! the core's types do (serde's `#[serde(default)]` reads the mirror's), field for field
//! the same values.
//!
//! Each type that a record names directly has a module ([`solve_stats`], [`growth_stats`],
//! ...) for `#[serde(with = "...")]`, and `option` and `vec` in it for an `Option` or a
//! `Vec` of it.

use eyeshell_core::bvp::ErrorEstimate;
use eyeshell_core::fit::lm::{Convergence, IterationRecord};
use eyeshell_core::growth::tolerance::{
    self, Lengths, Round, SensitivityEstimate, Split, TimedLengths,
};
use eyeshell_core::growth::SensitivityWork;
use eyeshell_core::model::components::{Membrane, ThicknessComponent};
use serde::{Deserialize, Serialize};

/// For a remote type: `serialize` and `deserialize` of it, and of an `Option` (`option`) and
/// a `Vec` (`vec`) of it, through its mirror.
macro_rules! record_of {
    ($m:ident, $t:ty, $def:ident) => {
        pub mod $m {
            use serde::{Deserialize, Deserializer, Serialize, Serializer};

            struct Ser<'a>(&'a $t);

            impl Serialize for Ser<'_> {
                fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                    super::$def::serialize(self.0, s)
                }
            }

            struct De($t);

            impl<'de> Deserialize<'de> for De {
                fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                    super::$def::deserialize(d).map(De)
                }
            }

            #[allow(dead_code)]
            pub fn serialize<S: Serializer>(v: &$t, s: S) -> Result<S::Ok, S::Error> {
                Ser(v).serialize(s)
            }

            #[allow(dead_code)]
            pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<$t, D::Error> {
                De::deserialize(d).map(|De(x)| x)
            }

            #[allow(dead_code)]
            pub mod option {
                use super::{De, Ser};
                use serde::{Deserialize, Deserializer, Serialize, Serializer};

                pub fn serialize<S: Serializer>(v: &Option<$t>, s: S) -> Result<S::Ok, S::Error> {
                    v.as_ref().map(Ser).serialize(s)
                }

                pub fn deserialize<'de, D: Deserializer<'de>>(
                    d: D,
                ) -> Result<Option<$t>, D::Error> {
                    Ok(Option::<De>::deserialize(d)?.map(|De(x)| x))
                }
            }

            #[allow(dead_code)]
            pub mod vec {
                use super::{De, Ser};
                use serde::{Deserialize, Deserializer, Serializer};

                pub fn serialize<S: Serializer>(v: &[$t], s: S) -> Result<S::Ok, S::Error> {
                    s.collect_seq(v.iter().map(Ser))
                }

                pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<$t>, D::Error> {
                    Ok(Vec::<De>::deserialize(d)?
                        .into_iter()
                        .map(|De(x)| x)
                        .collect())
                }
            }
        }
    };
}

record_of!(solve_stats, eyeshell_core::bvp::SolveStats, SolveStatsDef);
record_of!(
    bvp_error_estimate,
    eyeshell_core::bvp::ErrorEstimate,
    BvpErrorEstimateDef
);
record_of!(
    growth_stats,
    eyeshell_core::growth::GrowthStats,
    GrowthStatsDef
);
record_of!(
    sensitivity_work,
    eyeshell_core::growth::SensitivityWork,
    SensitivityWorkDef
);
record_of!(
    accuracy,
    eyeshell_core::growth::tolerance::Accuracy,
    AccuracyDef
);
record_of!(round, eyeshell_core::growth::tolerance::Round, RoundDef);
record_of!(
    growth_error_estimate,
    eyeshell_core::growth::tolerance::ErrorEstimate,
    GrowthErrorEstimateDef
);
record_of!(
    timed_lengths,
    eyeshell_core::growth::tolerance::TimedLengths,
    TimedLengthsDef
);
record_of!(
    sensitivity_estimate,
    eyeshell_core::growth::tolerance::SensitivityEstimate,
    SensitivityEstimateDef
);
record_of!(
    components,
    eyeshell_core::model::components::Components,
    ComponentsDef
);

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::bvp::SolveStats")]
#[serde(default)]
struct SolveStatsDef {
    pub newton_iterations: usize,
    pub residual_evaluations: usize,
    pub jacobian_evaluations: usize,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub residual_norm: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub first_integral_max: f64,
    pub nodes: usize,
    pub uniform_nodes: usize,
    pub breakpoint_nodes: usize,
    pub pole_nodes: usize,
    pub cornea_nodes: usize,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub cornea_alpha: f64,
    pub continuation_stages: usize,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub wall_seconds: f64,
    #[serde(
        skip_serializing_if = "Option::is_none",
        with = "bvp_error_estimate::option"
    )]
    pub error_estimate: Option<ErrorEstimate>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh_refinements: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pass_nodes: Option<Vec<usize>>,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::bvp::ErrorEstimate")]
#[serde(default)]
struct BvpErrorEstimateDef {
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub kappa: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub alpha_s: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub r: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub theta: f64,
    #[serde(rename = "Q", deserialize_with = "crate::json::f64_or_nan")]
    pub q: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub overall: f64,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::GrowthStats")]
#[serde(default)]
struct GrowthStatsDef {
    pub steps: usize,
    pub rhs_evaluations: usize,
    pub bvp_solves: usize,
    pub newton_iterations: usize,
    pub jacobian_products: usize,
    pub error_test_failures: usize,
    pub nonlinear_iterations: usize,
    pub nonlinear_failures: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub jacobian_evaluations: usize,
    pub linear_fallbacks: usize,
    #[serde(
        skip_serializing_if = "Option::is_none",
        with = "sensitivity_work::option"
    )]
    pub sensitivities: Option<SensitivityWork>,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub t_reached: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub wall_seconds: f64,
    #[serde(skip_serializing_if = "Option::is_none", with = "accuracy::option")]
    pub accuracy: Option<tolerance::Accuracy>,
    #[serde(
        skip_serializing_if = "Option::is_none",
        with = "growth_error_estimate::option"
    )]
    pub error_estimate: Option<tolerance::ErrorEstimate>,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::SensitivityWork")]
#[serde(default)]
struct SensitivityWorkDef {
    pub parameters: Vec<String>,
    pub error_control: bool,
    pub residual_evaluations: usize,
    pub nonlinear_iterations: usize,
    pub nonlinear_failures: usize,
    pub error_test_failures: usize,
    pub linear_setups: usize,
    pub jacobian_assemblies: usize,
    pub jacobian_seconds: f64,
    pub parameter_seconds: f64,
    pub product_seconds: f64,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::Split")]
#[serde(default)]
struct SplitDef {
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub total: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub space: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub time: f64,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::Lengths")]
#[serde(default)]
struct LengthsDef {
    #[serde(with = "SplitDef")]
    pub axial_length: Split,
    #[serde(with = "SplitDef")]
    pub equatorial_radius: Split,
    #[serde(with = "SplitDef")]
    pub retina_minus_blue: Split,
    #[serde(with = "SplitDef")]
    pub retina_minus_red: Split,
    #[serde(with = "SplitDef")]
    pub shell: Split,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::TimedLengths")]
#[serde(default)]
struct TimedLengthsDef {
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub t: f64,
    #[serde(flatten, with = "LengthsDef")]
    pub lengths: Lengths,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::ErrorEstimate")]
#[serde(default)]
struct GrowthErrorEstimateDef {
    #[serde(flatten, with = "LengthsDef")]
    pub largest: Lengths,
    #[serde(with = "timed_lengths::vec")]
    pub per_time: Vec<TimedLengths>,
    #[serde(
        skip_serializing_if = "Vec::is_empty",
        with = "sensitivity_estimate::vec"
    )]
    pub sensitivities: Vec<SensitivityEstimate>,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::SensitivityEstimate")]
#[serde(default)]
struct SensitivityEstimateDef {
    pub parameter: String,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub value: f64,
    #[serde(with = "SplitDef")]
    pub d_axial_length: Split,
    #[serde(with = "SplitDef")]
    pub d_equatorial_radius: Split,
    #[serde(with = "SplitDef")]
    pub d_retina_minus_blue: Split,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::Round")]
#[serde(default)]
struct RoundDef {
    pub nodes: usize,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub rtol: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub atol: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub space: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub time: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub seconds: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub delivered_cpu_seconds: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub companions_cpu_seconds: f64,
}

#[derive(Default, Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::growth::tolerance::Accuracy")]
#[serde(default)]
struct AccuracyDef {
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub tol: f64,
    pub nodes: usize,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub rtol: f64,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub atol: f64,
    #[serde(with = "round::vec")]
    pub rounds: Vec<Round>,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub wall_seconds: f64,
    pub threads: usize,
}

#[derive(Serialize, Deserialize)]
#[serde(remote = "eyeshell_core::model::components::Components")]
struct ComponentsDef {
    #[serde(with = "MembraneDef")]
    pub membrane: Membrane,
    #[serde(with = "ThicknessComponentDef")]
    pub thickness: ThicknessComponent,
    pub growth: bool,
}

#[derive(Serialize, Deserialize)]
#[serde(
    remote = "eyeshell_core::model::components::Membrane",
    tag = "kind",
    rename_all = "snake_case"
)]
enum MembraneDef {
    NeoHookean { c: f64 },
    Reinforced { c: f64, d: f64 },
}

#[derive(Serialize, Deserialize)]
#[serde(
    remote = "eyeshell_core::model::components::ThicknessComponent",
    tag = "kind",
    rename_all = "snake_case"
)]
enum ThicknessComponentDef {
    Uniform { h0: f64 },
    Profile,
}

/// fit.json's `convergence`.
#[derive(Serialize)]
#[serde(remote = "Convergence", rename_all = "lowercase")]
enum ConvergenceDef {
    Step,
    Cost,
    Gradient,
    #[serde(rename = "standard-error")]
    StandardError,
    Stalled,
    Refused,
    Iterations,
}

/// fit.json's `history`: one record per iteration.
#[derive(Serialize)]
#[serde(remote = "IterationRecord")]
struct IterationRecordDef {
    iteration: usize,
    values: Vec<f64>,
    chi2: f64,
    lambda: f64,
    accepted: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    rejected: Option<String>,
}

/// `#[serde(serialize_with)]` of fit.json's `convergence`.
pub fn convergence<S: serde::Serializer>(c: &Convergence, s: S) -> Result<S::Ok, S::Error> {
    ConvergenceDef::serialize(c, s)
}

/// `#[serde(serialize_with)]` of fit.json's `history`.
pub fn iteration_records<S: serde::Serializer>(
    records: &[IterationRecord],
    s: S,
) -> Result<S::Ok, S::Error> {
    struct Ser<'a>(&'a IterationRecord);
    impl Serialize for Ser<'_> {
        fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            IterationRecordDef::serialize(self.0, s)
        }
    }
    s.collect_seq(records.iter().map(Ser))
}

#[cfg(test)]
mod tests {
    use super::*;
    use eyeshell_core::bvp::SolveStats;
    use eyeshell_core::growth::GrowthStats;
    use eyeshell_core::model::components::Components;
    use eyeshell_core::model::params::{Params, Thickness};

    fn components_json(c: Components) -> serde_json::Value {
        #[derive(Serialize)]
        struct W(#[serde(with = "components")] Components);
        serde_json::to_value(W(c)).unwrap()
    }

    #[test]
    fn components_are_recorded_by_kind() {
        let plain = components_json(Components::of(&Params::default(), false));
        assert_eq!(
            plain,
            serde_json::json!({
                "membrane": { "kind": "neo_hookean", "c": 100.0 },
                "thickness": { "kind": "uniform", "h0": 0.65 },
                "growth": false,
            })
        );
        let fibres = Params {
            thickness: Thickness::NonUniform,
            d: 200.0,
            ..Params::default()
        };
        assert_eq!(
            components_json(Components::of(&fibres, true)),
            serde_json::json!({
                "membrane": { "kind": "reinforced", "c": 100.0, "d": 200.0 },
                "thickness": { "kind": "profile" },
                "growth": true,
            })
        );
    }

    /// Statistics read back are the statistics written: every field, NaN as null and back,
    /// the optional parts absent when None.
    #[test]
    fn statistics_survive_a_round_trip() {
        #[derive(Serialize, Deserialize)]
        struct S(#[serde(with = "solve_stats")] SolveStats);
        #[derive(Serialize, Deserialize)]
        struct G(#[serde(with = "growth_stats")] GrowthStats);
        let stats = SolveStats {
            newton_iterations: 7,
            residual_norm: f64::NAN,
            cornea_alpha: 1.25,
            error_estimate: Some(ErrorEstimate {
                q: 3e-9,
                ..ErrorEstimate::default()
            }),
            ..SolveStats::default()
        };
        let text = serde_json::to_string(&S(stats.clone())).unwrap();
        assert!(
            text.contains("\"residual_norm\":null") && text.contains("\"Q\":3e-9"),
            "{text}"
        );
        assert!(!text.contains("mesh_refinements"), "{text}");
        let back: S = serde_json::from_str(&text).unwrap();
        assert!(back.0.residual_norm.is_nan());
        assert_eq!(
            SolveStats {
                residual_norm: 0.0,
                ..back.0
            },
            SolveStats {
                residual_norm: 0.0,
                ..stats
            }
        );
        let growth = GrowthStats {
            steps: 12,
            t_reached: 1.0,
            accuracy: Some(tolerance::Accuracy {
                tol: 1e-4,
                rounds: vec![Round {
                    nodes: 41,
                    ..Round::default()
                }],
                ..tolerance::Accuracy::default()
            }),
            error_estimate: Some(tolerance::ErrorEstimate {
                per_time: vec![TimedLengths {
                    t: 0.5,
                    lengths: Lengths {
                        shell: Split {
                            total: 2.0,
                            space: 1.5,
                            time: 0.5,
                        },
                        ..Lengths::default()
                    },
                }],
                sensitivities: vec![SensitivityEstimate {
                    parameter: "growth.eta0".into(),
                    value: 0.3,
                    ..SensitivityEstimate::default()
                }],
                ..tolerance::ErrorEstimate::default()
            }),
            sensitivities: Some(SensitivityWork {
                parameters: vec!["growth.eta0".into()],
                ..SensitivityWork::default()
            }),
            ..GrowthStats::default()
        };
        let text = serde_json::to_string(&G(growth.clone())).unwrap();
        let back: G = serde_json::from_str(&text).unwrap();
        assert_eq!(back.0, growth);
        // A missing field takes its default.
        let sparse: G = serde_json::from_str("{\"steps\": 3}").unwrap();
        assert_eq!(
            sparse.0,
            GrowthStats {
                steps: 3,
                ..GrowthStats::default()
            }
        );
    }

    /// fit.json's `convergence` is the reason's name, and its `history` one record per
    /// iteration, `rejected` only on a rejected step.
    #[test]
    fn the_fit_records_its_convergence_and_history_by_name() {
        #[derive(Serialize)]
        struct Fit {
            #[serde(serialize_with = "convergence")]
            convergence: Convergence,
            #[serde(serialize_with = "iteration_records")]
            history: Vec<IterationRecord>,
        }
        let step = |iteration, accepted, rejected: Option<&str>| IterationRecord {
            iteration,
            values: vec![0.5, 2.0],
            chi2: 1.5,
            lambda: 1e-5,
            accepted,
            rejected: rejected.map(str::to_string),
        };
        let fit = Fit {
            convergence: Convergence::StandardError,
            history: vec![step(1, true, None), step(2, false, Some("χ² 2 ≥ 1.5"))],
        };
        assert_eq!(
            serde_json::to_value(fit).unwrap(),
            serde_json::json!({
                "convergence": "standard-error",
                "history": [
                    { "iteration": 1, "values": [0.5, 2.0], "chi2": 1.5, "lambda": 1e-5, "accepted": true },
                    { "iteration": 2, "values": [0.5, 2.0], "chi2": 1.5, "lambda": 1e-5, "accepted": false, "rejected": "χ² 2 ≥ 1.5" },
                ],
            })
        );
        for (c, name) in [
            (Convergence::Step, "step"),
            (Convergence::Cost, "cost"),
            (Convergence::Gradient, "gradient"),
            (Convergence::Stalled, "stalled"),
            (Convergence::Refused, "refused"),
            (Convergence::Iterations, "iterations"),
        ] {
            #[derive(Serialize)]
            struct C(#[serde(serialize_with = "convergence")] Convergence);
            assert_eq!(serde_json::to_value(C(c)).unwrap(), name);
        }
    }
}
