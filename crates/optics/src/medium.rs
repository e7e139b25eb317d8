//! Optical media: homogeneous ones with a dispersion law, and gradient-index (GRIN) ones whose
//! index is a polynomial in r² and z, as the schematic eyes' sources write them.

use crate::error::OpticsError;
use crate::linalg;

/// A homogeneous medium's index as a function of wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength.
    Constant(f64),
    /// Cauchy's form n = a + b/λ² + c/λ⁴ + d/λ⁶, λ in µm (Atchison & Smith 2005 use this form).
    Cauchy { a: f64, b: f64, c: f64, d: f64 },
    /// Sellmeier's form n² = 1 + Σ bᵢ λ²/(λ² − cᵢ), λ in µm.
    Sellmeier { b: Vec<f64>, c: Vec<f64> },
    /// Liou & Brennan (1997): n(λ) = n₅₅₅ + 0.0512 − 0.1455 λ + 0.0961 λ², λ in µm, the same
    /// shift for every medium of their eye.
    LiouBrennan { n555: f64 },
    /// Indices tabulated at a few wavelengths `(nm, n)`, read through the three-term Cauchy
    /// law a + b/λ² + c/λ⁴ fitted to them by least squares (NaN, and so an error when the
    /// system is checked, if the table cannot fix one).
    Tabulated(Vec<(f64, f64)>),
}

impl Dispersion {
    /// The index at `wavelength_nm`.
    pub fn index(&self, wavelength_nm: f64) -> f64 {
        let l = wavelength_nm * 1e-3;
        match self {
            Self::Constant(n) => *n,
            Self::Cauchy { a, b, c, d } => {
                let l2 = l * l;
                a + b / l2 + c / (l2 * l2) + d / (l2 * l2 * l2)
            }
            Self::Sellmeier { b, c } => {
                let l2 = l * l;
                let s: f64 = b.iter().zip(c).map(|(b, c)| b * l2 / (l2 - c)).sum();
                (1.0 + s).sqrt()
            }
            Self::LiouBrennan { n555 } => n555 + 0.0512 - 0.1455 * l + 0.0961 * l * l,
            Self::Tabulated(points) => {
                Self::cauchy_fit(points).map_or(f64::NAN, |c| c.index(wavelength_nm))
            }
        }
    }

    /// Cauchy's law with the dispersion coefficients B, C, D of Atchison & Smith's form
    /// n = A + B/λ² + C/λ⁴ + D/λ⁶ (λ in nm) and A chosen so that the index at `reference_nm`
    /// is `n_reference` (the schematic eye's own index there).
    pub fn cauchy_through(
        n_reference: f64,
        reference_nm: f64,
        b_nm: f64,
        c_nm: f64,
        d_nm: f64,
    ) -> Self {
        let (b, c, d) = (b_nm * 1e-6, c_nm * 1e-12, d_nm * 1e-18);
        let l2 = (reference_nm * 1e-3).powi(2);
        let a = n_reference - b / l2 - c / (l2 * l2) - d / (l2 * l2 * l2);
        Self::Cauchy { a, b, c, d }
    }

    /// The three-term Cauchy law (a + b/λ² + c/λ⁴) through tabulated `(wavelength_nm, index)`
    /// pairs by least squares: how a source that tabulates indices at a few wavelengths
    /// (Escudero-Sanz & Navarro 1999) becomes a law for any wavelength.
    pub fn cauchy_fit(points: &[(f64, f64)]) -> Result<Self, OpticsError> {
        if points.len() < 3 {
            return Err(OpticsError::Fit(format!(
                "a Cauchy law needs at least 3 tabulated indices, not {}",
                points.len()
            )));
        }
        let rows: Vec<[f64; 3]> = points
            .iter()
            .map(|&(nm, _)| {
                let l2 = (nm * 1e-3).powi(2);
                [1.0, 1.0 / l2, 1.0 / (l2 * l2)]
            })
            .collect();
        let rhs: Vec<f64> = points.iter().map(|p| p.1).collect();
        let x = linalg::least_squares::<3>(&rows, &rhs).ok_or_else(|| {
            OpticsError::Fit("the tabulated wavelengths do not fix a Cauchy law".into())
        })?;
        Ok(Self::Cauchy {
            a: x[0],
            b: x[1],
            c: x[2],
            d: 0.0,
        })
    }
}

/// A gradient index n(r, z) = Σᵢⱼ cᵢⱼ r²ⁱ ζʲ with ζ = z − (medium's front vertex + `origin`),
/// at a reference wavelength, with an optional dispersion law.
#[derive(Debug, Clone, PartialEq)]
pub struct Grin {
    /// `coefficients[i][j]` multiplies r²ⁱ ζʲ (r and ζ in mm).
    pub coefficients: Vec<Vec<f64>>,
    /// Where ζ = 0, from the vertex of the surface in front of the medium (mm).
    pub origin: f64,
    pub dispersion: Option<GrinDispersion>,
}

/// How a GRIN profile changes with wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum GrinDispersion {
    /// Every point shifted alike by law(λ) − law(reference), or by law(λ) itself when there is
    /// no reference (Liou & Brennan's additive form).
    Uniform {
        law: Dispersion,
        reference_nm: Option<f64>,
    },
    /// The shift interpolated, by the point's index at the reference wavelength, between the
    /// lens surface's law (index `n_surface` there) and the centre's (`n_centre`): the
    /// dispersion of the lens varies with its index, as Atchison & Smith (2005) model it.
    Interpolated {
        surface: Dispersion,
        centre: Dispersion,
        n_surface: f64,
        n_centre: f64,
        reference_nm: f64,
    },
}

impl GrinDispersion {
    /// (scale, shift): the index at λ is scale · n_ref + shift.
    fn affine(&self, wavelength_nm: f64) -> (f64, f64) {
        match self {
            Self::Uniform { law, reference_nm } => {
                let base = reference_nm.map_or(0.0, |r| law.index(r));
                (1.0, law.index(wavelength_nm) - base)
            }
            Self::Interpolated {
                surface,
                centre,
                n_surface,
                n_centre,
                reference_nm,
            } => {
                let ds = surface.index(wavelength_nm) - surface.index(*reference_nm);
                let dc = centre.index(wavelength_nm) - centre.index(*reference_nm);
                let kappa = (dc - ds) / (n_centre - n_surface);
                (1.0 + kappa, ds - kappa * n_surface)
            }
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum MediumKind {
    Homogeneous(Dispersion),
    Grin(Grin),
}

/// A named medium (the name is what errors show: "aqueous", "lens (anterior half)").
#[derive(Debug, Clone, PartialEq)]
pub struct Medium {
    pub name: String,
    pub kind: MediumKind,
}

impl Medium {
    pub fn homogeneous(name: impl Into<String>, dispersion: Dispersion) -> Self {
        Self {
            name: name.into(),
            kind: MediumKind::Homogeneous(dispersion),
        }
    }

    pub fn constant(name: impl Into<String>, n: f64) -> Self {
        Self::homogeneous(name, Dispersion::Constant(n))
    }

    pub fn grin(name: impl Into<String>, grin: Grin) -> Self {
        Self {
            name: name.into(),
            kind: MediumKind::Grin(grin),
        }
    }

    pub fn is_grin(&self) -> bool {
        matches!(self.kind, MediumKind::Grin(_))
    }

    /// The medium at one wavelength, its front surface's vertex at `front_vertex`.
    pub(crate) fn at(&self, wavelength_nm: f64, front_vertex: f64) -> Resolved {
        match &self.kind {
            MediumKind::Homogeneous(d) => Resolved::Constant(d.index(wavelength_nm)),
            MediumKind::Grin(g) => {
                let (scale, shift) = g
                    .dispersion
                    .as_ref()
                    .map_or((1.0, 0.0), |d| d.affine(wavelength_nm));
                Resolved::Grin(GrinAt {
                    c: g.coefficients.clone(),
                    z0: front_vertex + g.origin,
                    scale,
                    shift,
                })
            }
        }
    }
}

/// A medium at one wavelength and place: what the tracer evaluates.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Resolved {
    Constant(f64),
    Grin(GrinAt),
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GrinAt {
    c: Vec<Vec<f64>>,
    z0: f64,
    scale: f64,
    shift: f64,
}

impl GrinAt {
    /// n, ∂n/∂(r²) and ∂n/∂z at (r², z).
    pub(crate) fn eval(&self, r2: f64, z: f64) -> (f64, f64, f64) {
        let zeta = z - self.z0;
        let (mut n, mut dn_dr2, mut dn_dz) = (0.0, 0.0, 0.0);
        let mut r2i = 1.0; // r²ⁱ
        let mut r2im1 = 0.0; // i r²⁽ⁱ⁻¹⁾
        for (i, row) in self.c.iter().enumerate() {
            // Horner in ζ for the row's polynomial and its derivative.
            let (mut p, mut dp) = (0.0, 0.0);
            for &a in row.iter().rev() {
                dp = dp * zeta + p;
                p = p * zeta + a;
            }
            n += r2i * p;
            dn_dz += r2i * dp;
            dn_dr2 += r2im1 * p;
            r2im1 = (i + 1) as f64 * r2i;
            r2i *= r2;
        }
        (
            self.scale * n + self.shift,
            self.scale * dn_dr2,
            self.scale * dn_dz,
        )
    }

    /// The index on the axis at z, and its r² coefficient there: the paraxial GRIN.
    pub(crate) fn axial(&self, z: f64) -> (f64, f64) {
        let (n, dn_dr2, _) = self.eval(0.0, z);
        (n, dn_dr2)
    }
}

impl Resolved {
    pub(crate) fn index_at(&self, r2: f64, z: f64) -> f64 {
        match self {
            Self::Constant(n) => *n,
            Self::Grin(g) => g.eval(r2, z).0,
        }
    }
}
