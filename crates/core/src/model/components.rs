//! Which physics a scene's model contains: its components (docs/MODEL.md §2, §4, §5).
//!
//! A scene declares what it needs, and the assembled model holds that and nothing more:
//!
//! - **Membrane** (docs/MODEL.md §2). [`Membrane::NeoHookean`] when the scene has no fibres
//!   (D = 0): ψ is never evaluated, the mesh gets no fibre breakpoints (a, b), and the
//!   residual and the Jacobian are built from `MembraneLaw<NoFibres>`, a zero-sized
//!   reinforcement that the compiler removes. The point evaluation and the assembly loop
//!   (`bvp::equations::Equations<R>`, `bvp::discretisation`) are monomorphised for it, so
//!   the fibre-free f and ∂f/∂y contain no fibre term, branch or `Option`, and invert the
//!   law by a cheaper iteration (t_s is concave in α_s there). [`Membrane::Reinforced`]
//!   brings ψ(Σ) and the fibre terms `[I4 − 1]⁺` in.
//! - **Thickness** (docs/MODEL.md §4). Uniform H0 or the paper's non-uniform profile H(Σ). In
//!   either case the thickness enters only as ζ at each material point: the discretisation
//!   carries t_s as an unknown and the constitutive law as an algebraic equation at each
//!   point, so no equation differentiates the material data. There are no dζ/dΣ (nor
//!   dψ/dΣ) terms anywhere, with or without a profile. What the profile adds is data: ζ
//!   varies from point to point, and its jump at πR0/2 puts a second evaluation (the limit
//!   from below) at that node, across which α_s jumps and t_s stays continuous.
//! - **Growth** (docs/MODEL.md §5, §6). Only a scene with a `[growth]` section has growth; only
//!   then do the visual stimulus (the retina, the blue and red focal surfaces: the optics)
//!   and the time integration (IDA, CVODE or Euler) exist (`scene::Scene::growth` is `None`
//!   otherwise, and `growth::grow` is never called). Without growth one elastic solve of
//!   the reference shell is the whole model.
//!
//! [`Components::of`] reads them off the parameters; its `Display` is one human line (summary.json's
//! form of them is the eyeshell crate's, `rundir::record`).

use super::constitutive::Law;
use super::params::{Params, Thickness};
use std::fmt;

/// The membrane law of the sclera (docs/MODEL.md §2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Membrane {
    /// Neo-Hookean of modulus C (kPa); no fibres, no ψ.
    NeoHookean { c: f64 },
    /// Neo-Hookean of modulus C reinforced by fibres of stiffness D (kPa) along ψ(Σ).
    Reinforced { c: f64, d: f64 },
}

/// The thickness of the unloaded, ungrown shell (docs/MODEL.md §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThicknessComponent {
    /// H(Σ) = H0 (mm) everywhere.
    Uniform { h0: f64 },
    /// The paper's two-piece tanh profile H(Σ), with its jump at πR0/2.
    Profile,
}

/// The physics a scene's model contains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Components {
    pub membrane: Membrane,
    pub thickness: ThicknessComponent,
    /// True when the scene grows: then, and only then, the optics and time integration.
    pub growth: bool,
}

impl Membrane {
    /// The scene's membrane: reinforced when D > 0 (the rule of `Params::has_fibres`).
    pub fn of(params: &Params) -> Membrane {
        if params.has_fibres() {
            Membrane::Reinforced {
                c: params.c,
                d: params.d,
            }
        } else {
            Membrane::NeoHookean { c: params.c }
        }
    }

    /// True for the reinforced membrane.
    pub fn has_fibres(&self) -> bool {
        matches!(self, Membrane::Reinforced { .. })
    }

    /// The constitutive constants of this membrane.
    pub fn law(&self) -> Law {
        Law::from(*self)
    }
}

/// A law with D, even D = 0 (the start of a continuation in D), is reinforced.
impl From<Law> for Membrane {
    fn from(law: Law) -> Membrane {
        match law.d {
            None => Membrane::NeoHookean { c: law.c },
            Some(d) => Membrane::Reinforced { c: law.c, d },
        }
    }
}

impl From<Membrane> for Law {
    fn from(m: Membrane) -> Law {
        match m {
            Membrane::NeoHookean { c } => Law { c, d: None },
            Membrane::Reinforced { c, d } => Law { c, d: Some(d) },
        }
    }
}

impl ThicknessComponent {
    pub fn of(params: &Params) -> ThicknessComponent {
        match params.thickness {
            Thickness::Uniform => ThicknessComponent::Uniform { h0: params.h0 },
            Thickness::NonUniform => ThicknessComponent::Profile,
        }
    }
}

impl Components {
    /// The components of the elastic problem `params`, with growth when `growth` (the scene
    /// has a `[growth]` section).
    pub fn of(params: &Params, growth: bool) -> Components {
        Components {
            membrane: Membrane::of(params),
            thickness: ThicknessComponent::of(params),
            growth,
        }
    }
}

impl fmt::Display for Membrane {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Membrane::NeoHookean { c } => {
                write!(f, "neo-Hookean membrane (C = {c} kPa), no fibres")
            }
            Membrane::Reinforced { c, d } => {
                write!(f, "fibre-reinforced neo-Hookean membrane (C = {c} kPa, D = {d} kPa, fibre angle ψ(Σ))")
            }
        }
    }
}

impl fmt::Display for ThicknessComponent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ThicknessComponent::Uniform { h0 } => write!(
                f,
                "uniform thickness H0 = {h0} mm (no thickness derivatives)"
            ),
            ThicknessComponent::Profile => {
                write!(f, "non-uniform thickness profile H(Σ) (pointwise, no thickness derivatives: t_s is an unknown)")
            }
        }
    }
}

impl fmt::Display for Components {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let growth = if self.growth {
            "growth (optics, time integration)"
        } else {
            "no growth (no optics, no time integration)"
        };
        write!(f, "{}; {}; {}", self.membrane, self.thickness, growth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fibre_shell() -> Params {
        Params {
            thickness: Thickness::NonUniform,
            d: 200.0,
            ..Params::default()
        }
    }

    #[test]
    fn the_default_scene_is_the_plainest_model() {
        let c = Components::of(&Params::default(), false);
        assert_eq!(c.membrane, Membrane::NeoHookean { c: 100.0 });
        assert_eq!(c.thickness, ThicknessComponent::Uniform { h0: 0.65 });
        assert!(!c.growth && !c.membrane.has_fibres());
        assert_eq!(
            c.to_string(),
            "neo-Hookean membrane (C = 100 kPa), no fibres; uniform thickness H0 = 0.65 mm \
             (no thickness derivatives); no growth (no optics, no time integration)"
        );
    }

    #[test]
    fn fibres_profile_and_growth_are_named() {
        let c = Components::of(&fibre_shell(), true);
        assert_eq!(c.membrane, Membrane::Reinforced { c: 100.0, d: 200.0 });
        assert_eq!(c.thickness, ThicknessComponent::Profile);
        let line = c.to_string();
        assert!(!line.contains('\n'));
        for part in [
            "D = 200 kPa",
            "ψ(Σ)",
            "non-uniform thickness",
            "no thickness derivatives",
            "growth (optics, time integration)",
        ] {
            assert!(line.contains(part), "{part:?} missing from {line:?}");
        }
    }

    #[test]
    fn zero_fibre_stiffness_means_no_fibres() {
        let c = Components::of(
            &Params {
                d: 0.0,
                ..fibre_shell()
            },
            false,
        );
        assert_eq!(c.membrane, Membrane::NeoHookean { c: 100.0 });
    }

    #[test]
    fn membrane_and_law_convert_both_ways() {
        for m in [
            Membrane::NeoHookean { c: 80.0 },
            Membrane::Reinforced { c: 80.0, d: 0.0 },
            Membrane::Reinforced { c: 80.0, d: 400.0 },
        ] {
            assert_eq!(Membrane::from(m.law()), m);
        }
        assert_eq!(
            Membrane::of(&fibre_shell()).law(),
            Law {
                c: 100.0,
                d: Some(200.0)
            }
        );
        assert_eq!(
            Membrane::of(&Params::default()).law(),
            Law { c: 100.0, d: None }
        );
    }
}
