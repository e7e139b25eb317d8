//! A centred optical system: the object medium, then surfaces each followed by a medium and the
//! thickness to the next surface (the last thickness reaches the retina's vertex).

use crate::error::OpticsError;
use crate::medium::{Medium, MediumKind, Resolved};
use crate::surface::Surface;

/// One refracting surface and what follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    pub surface: Surface,
    /// Axial distance from this surface's vertex to the next one's (mm); for the last surface,
    /// to the retina's vertex.
    pub thickness: f64,
    /// The medium behind the surface.
    pub medium: Medium,
}

impl Element {
    pub fn new(surface: Surface, thickness: f64, medium: Medium) -> Self {
        Self {
            surface,
            thickness,
            medium,
        }
    }
}

/// An eye (or any centred system) in the shell's frame: z along the axis from the first
/// surface's vertex (the anterior corneal apex), light travelling towards +z.
#[derive(Debug, Clone, PartialEq)]
pub struct OpticalSystem {
    pub name: String,
    /// The medium in front of the first surface (air).
    pub object: Medium,
    pub elements: Vec<Element>,
    /// The aperture stop's default position (mm from the apex): the source's pupil.
    pub pupil_position: Option<f64>,
    /// The retina (image surface) at the end of the last thickness, for figures; the optics do
    /// not need it.
    pub retina: Option<Surface>,
    /// The z of the first surface's vertex: 0 for an eye (z from the corneal apex), negative
    /// when eyewear sits in front of it (`lens::wear`), so that z keeps its meaning.
    pub origin: f64,
}

/// The accepted range of refractive indices: below 1 is not a transparent dielectric, above 3
/// nothing in an eye or an ophthalmic lens comes near.
pub const INDEX_RANGE: (f64, f64) = (1.0, 3.0);

impl OpticalSystem {
    /// A system from its elements, checked: every number finite, radii non-zero, thicknesses
    /// positive, the last medium homogeneous (the image space), indices physical at 555 nm.
    pub fn new(
        name: impl Into<String>,
        object: Medium,
        elements: Vec<Element>,
    ) -> Result<Self, OpticsError> {
        let system = Self {
            name: name.into(),
            object,
            elements,
            pupil_position: None,
            retina: None,
            origin: 0.0,
        };
        system.validate()?;
        Ok(system)
    }

    pub fn with_pupil_position(mut self, z: f64) -> Self {
        self.pupil_position = Some(z);
        self
    }

    pub fn with_retina(mut self, retina: Surface) -> Self {
        self.retina = Some(retina);
        self
    }

    pub(crate) fn validate(&self) -> Result<(), OpticsError> {
        if self.elements.is_empty() {
            return Err(OpticsError::system("the system", 0.0, "it has no surfaces"));
        }
        if self.object.is_grin() {
            return Err(OpticsError::system(
                format!("the object medium '{}'", self.object.name),
                f64::NAN,
                "the object space must be homogeneous",
            ));
        }
        for e in &self.elements {
            let s = &e.surface;
            let what = |key: &str| format!("surface '{}' {key}", s.name);
            if s.radius == 0.0 || s.radius.is_nan() {
                return Err(OpticsError::system(
                    what("radius"),
                    s.radius,
                    "a radius must be non-zero (infinite for a plane)",
                ));
            }
            if !s.conic.is_finite() {
                return Err(OpticsError::system(
                    what("conic"),
                    s.conic,
                    "must be finite",
                ));
            }
            if let Some(a) = s.aspheric.iter().find(|a| !a.is_finite()) {
                return Err(OpticsError::system(
                    what("aspheric coefficient"),
                    *a,
                    "must be finite",
                ));
            }
            if let Some(sd) = s.semi_diameter {
                if !(sd > 0.0 && sd.is_finite()) {
                    return Err(OpticsError::system(
                        what("semi-diameter"),
                        sd,
                        "must be positive and finite",
                    ));
                }
            }
            if !(e.thickness > 0.0 && e.thickness.is_finite()) {
                return Err(OpticsError::system(
                    what("thickness"),
                    e.thickness,
                    "must be positive and finite",
                ));
            }
            if let MediumKind::Grin(g) = &e.medium.kind {
                let bad = g.coefficients.iter().flatten().find(|c| !c.is_finite());
                if g.coefficients.is_empty() || g.coefficients[0].is_empty() {
                    return Err(OpticsError::system(
                        format!("medium '{}' gradient index", e.medium.name),
                        f64::NAN,
                        "needs at least the index on the axis",
                    ));
                }
                if let Some(c) = bad {
                    return Err(OpticsError::system(
                        format!("medium '{}' gradient coefficient", e.medium.name),
                        *c,
                        "must be finite",
                    ));
                }
                if !g.origin.is_finite() {
                    return Err(OpticsError::system(
                        format!("medium '{}' origin", e.medium.name),
                        g.origin,
                        "must be finite",
                    ));
                }
            }
        }
        if self.elements.last().is_some_and(|e| e.medium.is_grin()) {
            return Err(OpticsError::system(
                "the last medium",
                f64::NAN,
                "the image space must be homogeneous",
            ));
        }
        if let Some(z) = self.pupil_position {
            self.check_pupil_position(z)?;
        }
        self.check_wavelength(555.0)
    }

    /// The z of each surface's vertex.
    pub fn vertices(&self) -> Vec<f64> {
        let mut z = self.origin;
        self.elements
            .iter()
            .map(|e| {
                let v = z;
                z += e.thickness;
                v
            })
            .collect()
    }

    /// The vertex of the last refracting surface.
    pub fn last_vertex(&self) -> f64 {
        self.vertices().last().copied().unwrap_or(0.0)
    }

    /// From the apex to the retina's vertex.
    pub fn axial_length(&self) -> f64 {
        self.origin + self.elements.iter().map(|e| e.thickness).sum::<f64>()
    }

    /// The index of the image space (behind the last surface) at a wavelength.
    pub fn image_index(&self, wavelength_nm: f64) -> f64 {
        let last = self.elements.len() - 1;
        self.medium_at(last, wavelength_nm)
            .index_at(0.0, self.last_vertex())
    }

    /// Every medium's index is physical at this wavelength (on the axis for a GRIN medium, at
    /// both its ends); the wavelength itself is in the range the dispersion laws cover.
    pub fn check_wavelength(&self, wavelength_nm: f64) -> Result<(), OpticsError> {
        if !(300.0..=1200.0).contains(&wavelength_nm) {
            return Err(OpticsError::input(
                "the wavelength (nm)",
                wavelength_nm,
                "must be between 300 and 1200 nm, where the eye's dispersion laws hold",
            ));
        }
        let vertices = self.vertices();
        let check = |name: &str, n: f64| {
            if !(n >= INDEX_RANGE.0 && n <= INDEX_RANGE.1) {
                Err(OpticsError::system(
                    format!(
                        "the refractive index of '{name}' at {} nm",
                        crate::error::num(wavelength_nm)
                    ),
                    n,
                    format!(
                        "is not physical (must be between {} and {})",
                        INDEX_RANGE.0, INDEX_RANGE.1
                    ),
                ))
            } else {
                Ok(())
            }
        };
        check(
            &self.object.name,
            self.object.at(wavelength_nm, 0.0).index_at(0.0, 0.0),
        )?;
        for (i, e) in self.elements.iter().enumerate() {
            let m = e.medium.at(wavelength_nm, vertices[i]);
            check(&e.medium.name, m.index_at(0.0, vertices[i]))?;
            check(&e.medium.name, m.index_at(0.0, vertices[i] + e.thickness))?;
        }
        Ok(())
    }

    /// A stop must lie inside the system, in a homogeneous medium, not on a surface's vertex
    /// plane in a way that makes it ambiguous.
    pub fn check_pupil_position(&self, z: f64) -> Result<(), OpticsError> {
        let last = self.last_vertex();
        if !(z > self.origin.max(0.0) && z <= last) {
            return Err(OpticsError::input(
                "the pupil position (mm from the corneal apex)",
                z,
                format!(
                    "must lie behind the first surface and not behind the last one (at {} mm)",
                    crate::error::num(last)
                ),
            ));
        }
        let i = self.medium_index_at(z);
        if self.elements[i].medium.is_grin() {
            return Err(OpticsError::input(
                "the pupil position (mm from the corneal apex)",
                z,
                format!(
                    "lies inside the gradient-index medium '{}'",
                    self.elements[i].medium.name
                ),
            ));
        }
        Ok(())
    }

    /// Which element's medium holds the axial point z: that of the last surface whose vertex
    /// lies in front of z. A stop on a vertex plane (to within rounding of the summed
    /// thicknesses) is in front of that surface, where the sources put the iris.
    pub(crate) fn medium_index_at(&self, z: f64) -> usize {
        let v = self.vertices();
        let mut i = 0;
        for (k, &vz) in v.iter().enumerate() {
            if vz < z - 1e-9 {
                i = k;
            }
        }
        i
    }

    pub(crate) fn medium_at(&self, i: usize, wavelength_nm: f64) -> Resolved {
        self.elements[i]
            .medium
            .at(wavelength_nm, self.vertices()[i])
    }
}
