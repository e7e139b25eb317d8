//! Parameters of the elastic shell and their defaults: the paper's table (docs/MODEL.md §8).
//!
//! Units: mm, kPa, kPa·mm³. Every field maps to one scene key (given beside it).

/// Thickness profile H(Σ) of the unloaded, ungrown shell (docs/MODEL.md §4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Thickness {
    /// H(Σ) = H0 everywhere.
    Uniform,
    /// The paper's two-piece tanh profile, thick at the back, with a jump at πR0/2.
    NonUniform,
}

/// The cornea: a neo-Hookean sphere inflated uniformly (Adkins; docs/MODEL.md §3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorneaParams {
    /// cornea.C: shear modulus C_c (kPa).
    pub c: f64,
    /// cornea.H: thickness H_c (mm).
    pub h: f64,
    /// cornea.R0: radius R_c (mm).
    pub r0: f64,
}

/// The physical parameters of one elastic problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// pressure.dP: pressure difference ΔP (kPa).
    pub dp: f64,
    /// material.C: neo-Hookean modulus C of the sclera (kPa).
    pub c: f64,
    /// material.bending: bending stiffness E_b (kPa·mm³).
    pub e_b: f64,
    /// material.thickness.
    pub thickness: Thickness,
    /// material.H0: uniform thickness H0 (mm).
    pub h0: f64,
    /// fibres.D: fibre stiffness D (kPa). Zero means no fibres: ψ is never evaluated.
    pub d: f64,
    /// cornea.*
    pub cornea: CorneaParams,
    /// geometry.R0: radius of the reference sphere (mm), the eye's size as a whole: it sets
    /// the shell's length π f R0 and, while [`Params::cornea_follows_radius`], the cornea's
    /// radius R_c too ([`Params::set_radius`]).
    pub r0: f64,
    /// geometry.fraction: f, with L = π f R0.
    pub fraction: f64,
    /// True until cornea.R0 is given: R_c is then R0, so that a larger eye has a larger
    /// cornea. The shell meets the cornea at Σ = L, where the cornea's edge (r*, z*) ∝ R_c
    /// (docs/MODEL.md §3); a larger shell on the same cornea is pulled into a longer, flatter
    /// front and an eye that is shorter, not longer.
    pub cornea_follows_radius: bool,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            dp: 2.0,
            c: 100.0,
            e_b: 18.0,
            thickness: Thickness::Uniform,
            h0: 0.65,
            d: 0.0,
            cornea: CorneaParams {
                c: 100.0,
                h: 0.65,
                r0: 10.0,
            },
            r0: 10.0,
            fraction: 0.8,
            cornea_follows_radius: true,
        }
    }
}

impl Params {
    /// Set R0 (geometry.R0), and with it the cornea's radius while it follows R0.
    pub fn set_radius(&mut self, r0: f64) {
        self.r0 = r0;
        if self.cornea_follows_radius {
            self.cornea.r0 = r0;
        }
    }

    /// These parameters with R0 = `r0` ([`Params::set_radius`]).
    pub fn with_radius(&self, r0: f64) -> Params {
        let mut p = *self;
        p.set_radius(r0);
        p
    }

    /// Material length of the shell, L = π f R0.
    pub fn length(&self) -> f64 {
        std::f64::consts::PI * self.fraction * self.r0
    }

    /// True when the scene has fibres (D > 0); otherwise ψ is not part of the model.
    pub fn has_fibres(&self) -> bool {
        self.d > 0.0
    }

    /// The parameters of docs/MODEL.md §7, whose solution is a uniformly inflated sphere:
    /// uniform H0, no fibres, and a cornea of the same material and radius as the sclera.
    pub fn exact_sphere(&self) -> Params {
        Params {
            thickness: Thickness::Uniform,
            d: 0.0,
            cornea: CorneaParams {
                c: self.c,
                h: self.h0,
                r0: self.r0,
            },
            ..*self
        }
    }
}
