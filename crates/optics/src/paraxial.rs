//! Paraxial optics by a y-nu trace: equivalent power, cardinal points, back focal distance.
//! A GRIN medium n(r, z) = N₀(z) + N₂(z) r² + … is crossed by integrating the paraxial ray
//! equation d/dz(N₀ dy/dz) = 2 N₂ y (classical RK4 on a fine fixed grid, checked by halving).

use crate::error::OpticsError;
use crate::medium::Resolved;
use crate::system::OpticalSystem;

/// First-order properties at one wavelength. Positions are z from the first vertex (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paraxial {
    pub wavelength_nm: f64,
    /// Equivalent power (dioptres).
    pub power: f64,
    /// From the last surface's vertex to the back focal point (mm).
    pub back_focal_distance: f64,
    /// The back (image-side) focal point: where a distant object's paraxial image lies.
    pub focus: f64,
    pub front_focus: f64,
    pub principal: (f64, f64),
    pub nodal: (f64, f64),
    pub n_object: f64,
    pub n_image: f64,
    /// The system matrix from the first vertex (object side) to the last (image side), acting
    /// on (y, n u).
    pub matrix: [[f64; 2]; 2],
}

/// RK4 steps per mm of GRIN medium.
const STEPS_PER_MM: f64 = 400.0;

/// Traces (y, nu) through surfaces and media; returns it just behind the last surface.
fn trace(
    system: &OpticalSystem,
    wavelength_nm: f64,
    mut y: f64,
    mut nu: f64,
    steps_per_mm: f64,
) -> (f64, f64) {
    let vertices = system.vertices();
    let m = system.elements.len();
    let mut n_before = system.object.at(wavelength_nm, 0.0).index_at(0.0, 0.0);
    for i in 0..m {
        let e = &system.elements[i];
        let medium = system.medium_at(i, wavelength_nm);
        let z0 = vertices[i];
        let n_after = medium.index_at(0.0, z0);
        let lens = e
            .surface
            .phase
            .as_ref()
            .map_or(0.0, |p| p.power(0.0) / 1000.0);
        nu -= y * ((n_after - n_before) * e.surface.curvature() + lens);
        if i + 1 == m {
            break;
        }
        let t = e.thickness;
        match &medium {
            Resolved::Constant(n) => {
                y += t * nu / n;
                n_before = *n;
            }
            Resolved::Grin(g) => {
                let steps = (t * steps_per_mm).ceil().max(8.0) as usize;
                let h = t / steps as f64;
                let f = |z: f64, y: f64, nu: f64| {
                    let (n0, n2) = g.axial(z);
                    (nu / n0, 2.0 * n2 * y)
                };
                for k in 0..steps {
                    let z = z0 + k as f64 * h;
                    let (a1, b1) = f(z, y, nu);
                    let (a2, b2) = f(z + h / 2.0, y + h / 2.0 * a1, nu + h / 2.0 * b1);
                    let (a3, b3) = f(z + h / 2.0, y + h / 2.0 * a2, nu + h / 2.0 * b2);
                    let (a4, b4) = f(z + h, y + h * a3, nu + h * b3);
                    y += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
                    nu += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
                }
                n_before = g.axial(z0 + t).0;
            }
        }
    }
    (y, nu)
}

/// The paraxial properties of `system` at `wavelength_nm`.
pub fn paraxial(system: &OpticalSystem, wavelength_nm: f64) -> Result<Paraxial, OpticsError> {
    system.check_wavelength(wavelength_nm)?;
    let (a, c) = trace(system, wavelength_nm, 1.0, 0.0, STEPS_PER_MM);
    let (b, d) = trace(system, wavelength_nm, 0.0, 1.0, STEPS_PER_MM);
    if !(c.abs() > 1e-12) {
        return Err(OpticsError::system(
            format!("the system '{}' power (D)", system.name),
            -c * 1000.0,
            "an afocal system has no focus",
        ));
    }
    let n = system.object.at(wavelength_nm, 0.0).index_at(0.0, 0.0);
    let n_image = system.image_index(wavelength_nm);
    let power = -c; // mm⁻¹
    let last = system.last_vertex();
    let bfd = -a * n_image / c;
    let front_focus = system.origin + n * d / c;
    let focus = last + bfd;
    let principal = (front_focus + n / power, focus - n_image / power);
    let shift = (n_image - n) / power;
    Ok(Paraxial {
        wavelength_nm,
        power: power * 1000.0,
        back_focal_distance: bfd,
        focus,
        front_focus,
        principal,
        nodal: (principal.0 + shift, principal.1 + shift),
        n_object: n,
        n_image,
        matrix: [[a, b], [c, d]],
    })
}

impl Paraxial {
    /// The ocular refraction (D): the vergence, at the first vertex, of the light from an
    /// object whose paraxial image lies at `image_z` (the retina's vertex); negative for a
    /// myopic eye. The difference between two wavelengths is the chromatic difference of
    /// refraction that the Indiana eye's formula gives.
    pub fn ocular_refraction(&self, image_z: f64) -> f64 {
        let [[a, b], [c, d]] = self.matrix;
        let last = self.focus - self.back_focal_distance;
        let t = (image_z - last) / self.n_image;
        // A ray from an object of vergence V enters with n·u = −V·y; it must reach y = 0 at
        // the image: A − B V + t (C − D V) = 0.
        (a + t * c) / (b + t * d) * 1000.0
    }
}

/// The paraxial focus found with half the GRIN step count: how far the fixed-step paraxial
/// GRIN transfer is from converged (mm), for the convergence table.
pub fn paraxial_grin_error(system: &OpticalSystem, wavelength_nm: f64) -> f64 {
    let bfd = |spm: f64| {
        let (a, c) = trace(system, wavelength_nm, 1.0, 0.0, spm);
        -a * system.image_index(wavelength_nm) / c
    };
    (bfd(STEPS_PER_MM) - bfd(STEPS_PER_MM / 2.0)).abs()
}
