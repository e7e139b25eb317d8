//! Shared test systems and independent reference computations.
#![allow(dead_code)]

use eyeshell_optics::{
    Element, GrinSettings, Medium, OpticalSystem, Pupil, Ray, Surface, Tracer, Vec3,
};

/// A four-surface eye with constant indices and conic surfaces (Navarro-like numbers at
/// 589 nm, different conics so that nothing is shared with a built-in eye).
pub fn four_surface_eye() -> OpticalSystem {
    OpticalSystem::new(
        "custom",
        Medium::constant("air", 1.0),
        vec![
            Element::new(
                Surface::new("anterior cornea", 7.8, -0.25),
                0.55,
                Medium::constant("cornea", 1.376),
            ),
            Element::new(
                Surface::new("posterior cornea", 6.5, -0.3),
                3.05,
                Medium::constant("aqueous", 1.336),
            ),
            Element::new(
                Surface::new("anterior lens", 10.2, -3.0),
                4.0,
                Medium::constant("lens", 1.42),
            ),
            Element::new(
                Surface::new("posterior lens", -6.0, -1.0),
                16.4,
                Medium::constant("vitreous", 1.336),
            ),
        ],
    )
    .expect("a valid eye")
}

pub const SMALL_PUPIL: Pupil = Pupil {
    diameter: 0.5,
    position: 3.6,
};

/// An independent paraxial trace (y, u: height and angle) for homogeneous systems: returns
/// the equivalent power (D) and the back focal distance (mm).
pub fn ynu_reference(system: &OpticalSystem, n: &[f64]) -> (f64, f64) {
    // n[0] object index, n[i+1] index behind surface i.
    let (mut y, mut u) = (1.0_f64, 0.0_f64);
    let m = system.elements.len();
    for (i, e) in system.elements.iter().enumerate() {
        let c = 1.0 / e.surface.radius;
        // n'u' = nu − y (n' − n) c
        u = (n[i] * u - y * (n[i + 1] - n[i]) * c) / n[i + 1];
        if i + 1 < m {
            y += e.thickness * u;
        }
    }
    let power = -n[m] * u / 1.0 * 1000.0;
    (power, -y / u)
}

/// The chief ray's launch offset (along the beam's tangential axis) for a field angle: by
/// bisection, the ray that crosses the stop plane on the axis.
pub fn chief_launch(tracer: &Tracer, field_deg: f64, stop_z: f64) -> f64 {
    let ray = |v: f64| launch(field_deg, 0.0, v);
    let f = |v: f64| {
        tracer
            .trace_to_plane(ray(v), stop_z, "stop")
            .unwrap()
            .position
            .y
    };
    let (mut a, mut b) = (-3.0, 3.0);
    assert!(f(a) * f(b) < 0.0);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(a) * f(m) <= 0.0 {
            b = m;
        } else {
            a = m;
        }
    }
    0.5 * (a + b)
}

/// A ray of a collimated beam at `field_deg` (in the y–z plane), launched 30 mm in front.
pub fn launch(field_deg: f64, u: f64, v: f64) -> Ray {
    let th = field_deg.to_radians();
    let d = Vec3::new(0.0, th.sin(), th.cos());
    let e2 = Vec3::new(0.0, th.cos(), -th.sin());
    Ray {
        position: Vec3::new(u, 0.0, 0.0) + e2 * v - d * 30.0,
        direction: d,
        opl: 0.0,
    }
}

/// Sagittal and tangential foci by differential ray tracing: neighbours of the chief ray,
/// offset by ±δ across the beam, traced exactly; where each crosses the chief ray (sagittal:
/// the meridional plane; tangential: the chief ray's line), measured along the chief ray from
/// where it leaves the last surface.
pub fn differential_foci(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    stop_z: f64,
) -> (f64, f64) {
    let tracer = Tracer::new(system, wavelength_nm, GrinSettings::default());
    let v0 = chief_launch(&tracer, field_deg, stop_z);
    let chief = tracer.trace(launch(field_deg, 0.0, v0)).unwrap();
    let (q, dc) = (chief.position, chief.direction);
    let delta = 1e-4;
    let mut s = 0.0;
    let mut t = 0.0;
    for sign in [-1.0, 1.0] {
        let rs = tracer.trace(launch(field_deg, sign * delta, v0)).unwrap();
        let k = -rs.position.x / rs.direction.x;
        let p = rs.position + rs.direction * k;
        s += 0.5 * (p - q).dot(dc);
        let rt = tracer
            .trace(launch(field_deg, 0.0, v0 + sign * delta))
            .unwrap();
        // Intersection of the two lines in the y–z plane.
        let (p1, d1) = (
            (rt.position.y, rt.position.z),
            (rt.direction.y, rt.direction.z),
        );
        let (p2, d2) = ((q.y, q.z), (dc.y, dc.z));
        let den = d1.0 * d2.1 - d1.1 * d2.0;
        let w = ((p2.0 - p1.0) * d1.1 - (p2.1 - p1.1) * d1.0) / den;
        t += 0.5 * w; // distance along the chief ray (unit direction) from q
    }
    (s, t)
}
