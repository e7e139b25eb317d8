//! The optics' errors. Each names what failed in the user's terms: the surface or medium by
//! its name, the field angle and the wavelength, so that a caller can print one clear line.

use thiserror::Error;

/// A number in a message: six significant digits in its shortest form, in scientific
/// notation outside [1e-4, 1e15), so that 1e280 is not 281 digits long and a ray's position
/// not 18 (where a ray fails is told, not measured).
pub fn num(x: f64) -> String {
    let x: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Why one ray could not be traced (without the field and wavelength, which the caller adds).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RayFailure {
    #[error("the ray misses the surface")]
    Miss,
    #[error("the ray is totally internally reflected")]
    TotalInternalReflection,
    #[error("the ray meets the surface {} mm from the axis, outside its semi-diameter {} mm", num(*r), num(*semi_diameter))]
    OutsideAperture { r: f64, semi_diameter: f64 },
    #[error("the gradient-index integration did not converge ({reason})")]
    GrinNotConverged { reason: String },
    #[error("the refractive index {} at z = {} mm, r = {} mm is not physical", num(*n), num(*z), num(*r))]
    NonPhysicalIndex { n: f64, z: f64, r: f64 },
}

/// A ray's failure at a named surface (or in the medium before it).
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{surface}: {failure}")]
pub struct RayError {
    pub surface: String,
    pub failure: RayFailure,
}

#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum OpticsError {
    /// A ray of a field failed: the surface, the field angle and the wavelength are named.
    #[error("the ray at {}° and {} nm fails at '{surface}': {failure}", num(*field_deg), num(*wavelength_nm))]
    Ray {
        surface: String,
        field_deg: f64,
        wavelength_nm: f64,
        failure: RayFailure,
    },
    /// The system itself is not an optical system (a radius of zero, a negative thickness,
    /// a non-physical index, ...): `what` names the surface or medium and its key.
    #[error("{what} is {}: {reason}", num(*value))]
    InvalidSystem {
        what: String,
        value: f64,
        reason: String,
    },
    /// A request's own number is unusable (a pupil of zero, a wavelength of 5 nm, ...).
    #[error("{what} is {}: {reason}", num(*value))]
    InvalidInput {
        what: String,
        value: f64,
        reason: String,
    },
    /// The wavefront of a field has no focus the criterion can find.
    #[error("no best focus at {}° and {} nm: {reason}", num(*field_deg), num(*wavelength_nm))]
    NoFocus {
        field_deg: f64,
        wavelength_nm: f64,
        reason: String,
    },
    /// A fit (polar form, interpolant) cannot be made from the points given.
    #[error("{0}")]
    Fit(String),
    /// Lens `lens` (counted from 0, in the order given) cannot be worn with the others or
    /// where it sits: the reason in words (no number of the lens is wrong by itself).
    #[error("lens {lens}: {reason}")]
    Eyewear { lens: usize, reason: String },
}

impl OpticsError {
    pub(crate) fn ray(err: RayError, field_deg: f64, wavelength_nm: f64) -> Self {
        Self::Ray {
            surface: err.surface,
            field_deg,
            wavelength_nm,
            failure: err.failure,
        }
    }

    pub(crate) fn input(what: impl Into<String>, value: f64, reason: impl Into<String>) -> Self {
        Self::InvalidInput {
            what: what.into(),
            value,
            reason: reason.into(),
        }
    }

    pub(crate) fn system(what: impl Into<String>, value: f64, reason: impl Into<String>) -> Self {
        Self::InvalidSystem {
            what: what.into(),
            value,
            reason: reason.into(),
        }
    }
}
