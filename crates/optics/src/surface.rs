//! Centred, rotationally symmetric refracting surfaces: conicoids with optional even aspheric
//! terms, their sag, slope and principal curvatures, and exact ray intersection.

use crate::error::RayFailure;
use crate::lens::PowerProfile;
use crate::vec3::Vec3;

/// A surface of revolution about the z axis. Its sag from the vertex plane is
/// z(r) = c r² / (1 + √(1 − (1 + k) c² r²)) + Σⱼ aⱼ r²ʲ⁺⁴ with c = 1/radius and k the conic
/// constant (k = Q, the asphericity, in the eye literature: −1 paraboloid, 0 sphere).
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// The name errors show ("anterior cornea").
    pub name: String,
    /// Vertex radius of curvature (mm), positive when the centre of curvature lies behind the
    /// vertex (+z, the direction light travels); `f64::INFINITY` for a plane.
    pub radius: f64,
    pub conic: f64,
    /// Coefficients of r⁴, r⁶, r⁸, ... (mm⁻³, mm⁻⁵, ...).
    pub aspheric: Vec<f64>,
    /// The surface ends this far from the axis (mm); rays beyond it are an error.
    pub semi_diameter: Option<f64>,
    /// A thin lens on this surface (crate::lens): the optical path it adds and the deflection
    /// that goes with it.
    pub phase: Option<PowerProfile>,
}

impl Surface {
    pub fn new(name: impl Into<String>, radius: f64, conic: f64) -> Self {
        Self {
            name: name.into(),
            radius,
            conic,
            aspheric: Vec::new(),
            semi_diameter: None,
            phase: None,
        }
    }

    pub fn plane(name: impl Into<String>) -> Self {
        Self::new(name, f64::INFINITY, 0.0)
    }

    pub fn with_aspheric(mut self, coefficients: Vec<f64>) -> Self {
        self.aspheric = coefficients;
        self
    }

    pub fn with_semi_diameter(mut self, semi_diameter: f64) -> Self {
        self.semi_diameter = Some(semi_diameter);
        self
    }

    /// The vertex curvature 1/radius (0 for a plane).
    pub fn curvature(&self) -> f64 {
        if self.radius.is_infinite() {
            0.0
        } else {
            1.0 / self.radius
        }
    }

    /// Sag and its first two derivatives in r at distance `r` from the axis; `None` where the
    /// conicoid does not reach (an ellipsoid's rim).
    pub fn sag_derivatives(&self, r: f64) -> Option<(f64, f64, f64)> {
        let c = self.curvature();
        let q = 1.0 - (1.0 + self.conic) * c * c * r * r;
        if q < 0.0 {
            return None;
        }
        let sq = q.sqrt();
        let mut z = c * r * r / (1.0 + sq);
        let (mut dz, mut d2z) = if c == 0.0 {
            (0.0, 0.0)
        } else {
            (c * r / sq, c / (q * sq))
        };
        if !self.aspheric.is_empty() {
            let r2 = r * r;
            let mut pow = r2 * r2; // r^(2j+4)
            for (j, a) in self.aspheric.iter().enumerate() {
                let e = (2 * j + 4) as f64;
                z += a * pow;
                dz += e * a * pow / r.max(f64::MIN_POSITIVE);
                d2z += e * (e - 1.0) * a * pow / r2.max(f64::MIN_POSITIVE);
                pow *= r2;
            }
        }
        (z.is_finite() && dz.is_finite() && d2z.is_finite()).then_some((z, dz, d2z))
    }

    pub fn sag(&self, r: f64) -> Option<f64> {
        self.sag_derivatives(r).map(|s| s.0)
    }

    /// The principal curvatures (sagittal, tangential) at distance `r` from the axis (mm⁻¹,
    /// positive like the vertex curvature): what Coddington's equations use.
    pub fn principal_curvatures(&self, r: f64) -> Option<(f64, f64)> {
        let (_, dz, d2z) = self.sag_derivatives(r)?;
        let g = 1.0 + dz * dz;
        let tangential = d2z / (g * g.sqrt());
        let sagittal = if r < 1e-12 { d2z } else { dz / (r * g.sqrt()) };
        Some((sagittal, tangential))
    }

    /// The unit normal at a point of the surface, pointing along +z.
    pub fn normal(&self, p: Vec3) -> Option<Vec3> {
        let r = p.rho();
        let (_, dz, _) = self.sag_derivatives(r)?;
        if r < 1e-300 {
            return Some(Vec3::new(0.0, 0.0, 1.0));
        }
        Some(Vec3::new(-dz * p.x / r, -dz * p.y / r, 1.0).unit())
    }

    /// g(p) = (z − vertex) − sag(r): negative in front of the surface, positive behind.
    pub(crate) fn side(&self, vertex_z: f64, p: Vec3) -> Option<f64> {
        Some(p.z - vertex_z - self.sag(p.rho())?)
    }

    /// Where the ray p + t d (d a unit vector, travelling towards +z) meets the surface whose
    /// vertex is at `vertex_z`: the point and the distance t.
    pub(crate) fn intersect(
        &self,
        vertex_z: f64,
        p: Vec3,
        d: Vec3,
    ) -> Result<(Vec3, f64), RayFailure> {
        let c = self.curvature();
        let k1 = 1.0 + self.conic;
        let w0 = p.z - vertex_z;
        // The conicoid c(x² + y²) + c(1 + k)w² − 2w = 0 (the plane when c = 0), exactly.
        let a = c * (d.x * d.x + d.y * d.y + k1 * d.z * d.z);
        let b = c * (p.x * d.x + p.y * d.y + k1 * w0 * d.z) - d.z;
        let cc = c * (p.x * p.x + p.y * p.y + k1 * w0 * w0) - 2.0 * w0;
        let disc = b * b - a * cc;
        if !(disc >= 0.0) {
            return Err(RayFailure::Miss);
        }
        let den = -b + (-b).signum() * disc.sqrt();
        let mut best: Option<f64> = None;
        for t in [cc / den, den / a] {
            if !t.is_finite() || t < -1e-9 {
                continue;
            }
            // Keep the sheet that holds the vertex: there 1 − c(1 + k)w = √(1 − (1+k)c²r²) ≥ 0.
            let w = w0 + t * d.z;
            if 1.0 - c * k1 * w < -1e-12 {
                continue;
            }
            if best.is_none_or(|b| t < b) {
                best = Some(t);
            }
        }
        let mut t = best.ok_or(RayFailure::Miss)?;
        if !self.aspheric.is_empty() {
            // Newton on g(t) = w(t) − sag(r(t)) from the conicoid's point.
            let mut converged = false;
            for _ in 0..60 {
                let q = p + d * t;
                let r = q.rho();
                let (s, ds, _) = self.sag_derivatives(r).ok_or(RayFailure::Miss)?;
                let g = q.z - vertex_z - s;
                let dr_dt = if r > 1e-300 {
                    (q.x * d.x + q.y * d.y) / r
                } else {
                    0.0
                };
                let dg = d.z - ds * dr_dt;
                if !(dg.abs() > 1e-14) {
                    return Err(RayFailure::Miss);
                }
                let step = g / dg;
                t -= step;
                if step.abs() < 1e-13 * (1.0 + t.abs()) {
                    converged = true;
                    break;
                }
            }
            if !converged || !(t >= -1e-9) {
                return Err(RayFailure::Miss);
            }
        }
        let q = p + d * t;
        let r = q.rho();
        if self.sag(r).is_none() {
            return Err(RayFailure::Miss);
        }
        if let Some(semi) = self.semi_diameter {
            if r > semi {
                return Err(RayFailure::OutsideAperture {
                    r,
                    semi_diameter: semi,
                });
            }
        }
        Ok((q, t))
    }
}

/// Vector Snell's law: the unit direction after refraction from index `n1` into `n2` at a
/// surface of unit normal `normal` (either orientation).
pub(crate) fn refract(d: Vec3, normal: Vec3, n1: f64, n2: f64) -> Result<Vec3, RayFailure> {
    let n = if normal.dot(d) < 0.0 { -normal } else { normal };
    let mu = n1 / n2;
    let cos_i = n.dot(d);
    let k = 1.0 - mu * mu * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        return Err(RayFailure::TotalInternalReflection);
    }
    Ok((d * mu + n * (k.sqrt() - mu * cos_i)).unit())
}

/// Refraction at a surface carrying a phase φ (a thin lens): the optical direction's
/// component along the surface gains φ's gradient `grad` (n′d′ₜ = n dₜ + ∇φ), the normal
/// component follows from |d′| = 1. No real direction (the tangential part longer than n′)
/// is total internal reflection.
pub(crate) fn refract_phase(
    d: Vec3,
    normal: Vec3,
    n1: f64,
    n2: f64,
    grad: Vec3,
) -> Result<Vec3, RayFailure> {
    let n = if normal.dot(d) < 0.0 { -normal } else { normal };
    let v = d * n1 + grad;
    let t = v - n * v.dot(n);
    let k = n2 * n2 - t.dot(t);
    if !(k > 0.0) {
        return Err(RayFailure::TotalInternalReflection);
    }
    Ok(((t + n * k.sqrt()) * (1.0 / n2)).unit())
}
