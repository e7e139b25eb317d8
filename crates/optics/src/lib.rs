//! The eye's optics for eyeshell: exact ray tracing through centred schematic eyes (conicoid
//! and aspheric surfaces, dispersive media, gradient-index lenses), paraxial properties, and
//! the best-focus surfaces that drive the growth (docs/optics.md).
//!
//! Frame: z along the optical axis from the first surface's vertex (the anterior corneal apex),
//! light travelling towards +z; r (or x, y) from the axis; lengths in mm, wavelengths in nm.
//! Pure computation: no file I/O. No function here panics on any input; every failure is an
//! [`OpticsError`] naming the surface or medium, the field angle and the wavelength.

mod error;
pub mod eyes;
mod focus;
mod images;
pub mod lens;
mod linalg;
mod medium;
mod paraxial;
pub mod refraction;
mod sampling;
mod shell;
mod strehl;
mod surface;
mod system;
mod trace;
mod vec3;

pub use error::{OpticsError, RayError, RayFailure};
pub use focus::{
    best_focus, best_focus_with, coddington, ray_fan, rays_for, traced_strehl, Criterion, Focus,
    FocusSettings, Probe, Pupil, MAX_FIELD_DEG, RAYS_TRIED,
};
pub use images::{entrance_area, entrance_areas, Region, SPOKES};
pub use medium::{Dispersion, Grin, GrinDispersion, Medium, MediumKind};
pub use paraxial::{paraxial, paraxial_grin_error, Paraxial};
pub use shell::{FocusSurface, PolarFit, PolarSpline, SurfaceSettings, Surfaces};
pub use surface::Surface;
pub use system::{Element, OpticalSystem, INDEX_RANGE};
pub use trace::{GrinSettings, Ray, Tracer};
pub use vec3::Vec3;

/// The name the brief and the library use for a schematic eye.
pub type Eye = OpticalSystem;
