//! Exact (finite, skew) ray tracing: analytic intersection with each conicoid, refraction by
//! vector Snell's law, and in a gradient-index medium the ray equation integrated with error
//! control until the ray meets the medium's back surface.

use crate::error::{RayError, RayFailure};
use crate::medium::{GrinAt, Resolved};
use crate::surface::{refract, refract_phase, Surface};
use crate::system::{OpticalSystem, INDEX_RANGE};
use crate::vec3::Vec3;

/// A ray: where it is, its unit direction, and the optical path length it has travelled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub position: Vec3,
    pub direction: Vec3,
    pub opl: f64,
}

/// How gradient-index media are integrated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrinSettings {
    /// Local error bound per step on position (mm), on the optical direction n·dr/ds and on the
    /// optical path (mm).
    pub tolerance: f64,
    /// A ray that needs more steps than this in one medium is an error.
    pub max_steps: usize,
}

impl Default for GrinSettings {
    fn default() -> Self {
        // 1e-8 mm per step puts the best focus within 1e-7 mm of the converged one
        // (docs/optics.md's convergence table).
        Self {
            tolerance: 1e-8,
            max_steps: 20_000,
        }
    }
}

/// A system resolved at one wavelength: what rays are traced through.
#[derive(Debug, Clone)]
pub struct Tracer<'a> {
    pub(crate) system: &'a OpticalSystem,
    pub(crate) vertices: Vec<f64>,
    pub(crate) media: Vec<Resolved>,
    pub(crate) n_object: f64,
    object: Resolved,
    pub(crate) grin: GrinSettings,
}

impl<'a> Tracer<'a> {
    /// The system at `wavelength_nm` (checked by the caller with `check_wavelength`).
    pub fn new(system: &'a OpticalSystem, wavelength_nm: f64, grin: GrinSettings) -> Self {
        let vertices = system.vertices();
        let media = (0..system.elements.len())
            .map(|i| system.medium_at(i, wavelength_nm))
            .collect();
        let n_object = system.object.at(wavelength_nm, 0.0).index_at(0.0, 0.0);
        Self {
            system,
            vertices,
            media,
            n_object,
            object: Resolved::Constant(n_object),
            grin,
        }
    }

    /// The index of the image space.
    pub fn n_image(&self) -> f64 {
        self.media.last().map_or(1.0, |m| m.index_at(0.0, 0.0))
    }

    fn before(&self, i: usize) -> &Resolved {
        if i == 0 {
            &self.object
        } else {
            &self.media[i - 1]
        }
    }

    fn surface(&self, i: usize) -> &Surface {
        &self.system.elements[i].surface
    }

    /// Traces `ray` (in the object space) through surfaces `0..count`, ending on the last of
    /// them with the direction refracted into the medium behind it. `path`, when given,
    /// receives the points the ray passes (GRIN steps included), for figures.
    pub fn trace_surfaces(
        &self,
        ray: Ray,
        count: usize,
        mut path: Option<&mut Vec<Vec3>>,
    ) -> Result<Ray, RayError> {
        let Ray {
            position: mut p,
            direction: mut d,
            mut opl,
        } = ray;
        if let Some(path) = path.as_deref_mut() {
            path.push(p);
        }
        for i in 0..count {
            let surface = self.surface(i);
            let err = |failure| RayError {
                surface: surface.name.clone(),
                failure,
            };
            let before = self.before(i);
            // Leaving a GRIN medium, the ray's optical direction T = n dR/ds is what Snell's law
            // conserves across the surface: its length stands for n₁, so the integration error
            // in |T| does not leak into the refracted direction.
            let mut n_optical = None;
            match before {
                Resolved::Constant(n) => {
                    let (q, t) = surface.intersect(self.vertices[i], p, d).map_err(err)?;
                    opl += n * t;
                    p = q;
                }
                Resolved::Grin(g) => {
                    let medium = &self.system.elements[i - 1].medium.name;
                    let (q, dir, dl) = integrate_grin(
                        g,
                        p,
                        d,
                        surface,
                        self.vertices[i],
                        &self.grin,
                        path.as_deref_mut(),
                    )
                    .map_err(|(at_surface, failure)| RayError {
                        surface: if at_surface {
                            surface.name.clone()
                        } else {
                            medium.clone()
                        },
                        failure,
                    })?;
                    p = q;
                    d = dir.unit();
                    n_optical = Some(dir.norm());
                    opl += dl;
                }
            }
            if let Some(path) = path.as_deref_mut() {
                path.push(p);
            }
            let r2 = p.x * p.x + p.y * p.y;
            let n1 =
                physical(n_optical.unwrap_or_else(|| before.index_at(r2, p.z)), p).map_err(err)?;
            let n2 = physical(self.media[i].index_at(r2, p.z), p).map_err(err)?;
            let normal = surface.normal(p).ok_or(RayFailure::Miss).map_err(err)?;
            d = match &surface.phase {
                None => refract(d, normal, n1, n2).map_err(err)?,
                Some(profile) => {
                    let h = r2.sqrt();
                    let grad = if h > 0.0 {
                        let g = profile.deflection(h) / h;
                        Vec3::new(g * p.x, g * p.y, 0.0)
                    } else {
                        Vec3::new(0.0, 0.0, 0.0)
                    };
                    opl += profile.phase(h);
                    refract_phase(d, normal, n1, n2, grad).map_err(err)?
                }
            };
        }
        Ok(Ray {
            position: p,
            direction: d,
            opl,
        })
    }

    /// Traces through every surface: the ray leaves the last surface into the image space.
    pub fn trace(&self, ray: Ray) -> Result<Ray, RayError> {
        self.trace_surfaces(ray, self.vertices.len(), None)
    }

    /// Traces to the plane z = `z_plane` (a stop in a homogeneous medium): through the
    /// surfaces in front of it, then straight to the plane.
    pub fn trace_to_plane(&self, ray: Ray, z_plane: f64, name: &str) -> Result<Ray, RayError> {
        let i = self.system.medium_index_at(z_plane);
        let count = if z_plane > self.vertices[0] { i + 1 } else { 0 };
        let r = self.trace_surfaces(ray, count, None)?;
        let n = if count == 0 {
            self.n_object
        } else {
            self.media[count - 1].index_at(0.0, z_plane)
        };
        let t = (z_plane - r.position.z) / r.direction.z;
        if !(t.is_finite() && t >= -1e-9) {
            return Err(RayError {
                surface: name.to_string(),
                failure: RayFailure::Miss,
            });
        }
        Ok(Ray {
            position: r.position + r.direction * t,
            direction: r.direction,
            opl: r.opl + n * t,
        })
    }
}

fn physical(n: f64, p: Vec3) -> Result<f64, RayFailure> {
    if n >= INDEX_RANGE.0 && n <= INDEX_RANGE.1 {
        Ok(n)
    } else {
        Err(RayFailure::NonPhysicalIndex {
            n,
            z: p.z,
            r: p.rho(),
        })
    }
}

/// The ray equation with Sharma's parameter t (dt = ds/n): R' = T, T' = n∇n, L' = n², where
/// T = n dR/ds is the optical direction and L the optical path.
type State = [f64; 7];

fn derivative(g: &GrinAt, y: &State) -> Result<State, RayFailure> {
    let r2 = y[0] * y[0] + y[1] * y[1];
    let (n, dn_dr2, dn_dz) = g.eval(r2, y[2]);
    if !(n >= INDEX_RANGE.0 && n <= INDEX_RANGE.1) {
        return Err(RayFailure::NonPhysicalIndex {
            n,
            z: y[2],
            r: r2.sqrt(),
        });
    }
    Ok([
        y[3],
        y[4],
        y[5],
        n * 2.0 * y[0] * dn_dr2,
        n * 2.0 * y[1] * dn_dr2,
        n * dn_dz,
        n * n,
    ])
}

// Dormand & Prince's 5(4) pair (the system is autonomous, so the nodes cᵢ are not needed).
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// One Dormand–Prince step of size h from y (whose derivative is k1): the 5th-order solution
/// and the norm of the embedded error estimate.
fn step(g: &GrinAt, y: &State, k1: &State, h: f64) -> Result<(State, f64), RayFailure> {
    let stage = |k: &[State; 7], s: usize| {
        let mut ys = *y;
        for (j, kj) in k.iter().enumerate().take(s) {
            let a = A[s][j];
            if a != 0.0 {
                for m in 0..7 {
                    ys[m] += h * a * kj[m];
                }
            }
        }
        ys
    };
    let mut k = [[0.0; 7]; 7];
    k[0] = *k1;
    for s in 1..6 {
        k[s] = derivative(g, &stage(&k, s))?;
    }
    // The 7th stage is evaluated at the 5th-order solution itself.
    let y5 = stage(&k, 6);
    k[6] = derivative(g, &y5)?;
    let mut err = 0.0_f64;
    for m in 0..7 {
        let e: f64 = (0..7).map(|j| E[j] * k[j][m]).sum::<f64>() * h;
        err = err.max(e.abs());
    }
    Ok((y5, err))
}

/// Integrates a ray through a GRIN medium from `p` (on the medium's front surface, unit
/// direction `d` already refracted into it) until it meets `exit` (vertex at `exit_z`).
/// Returns the exit point, the optical direction T = n dR/ds there and the optical path; on
/// failure, whether it is the exit surface's fault (a miss) and why.
fn integrate_grin(
    g: &GrinAt,
    p: Vec3,
    d: Vec3,
    exit: &Surface,
    exit_z: f64,
    settings: &GrinSettings,
    mut path: Option<&mut Vec<Vec3>>,
) -> Result<(Vec3, Vec3, f64), (bool, RayFailure)> {
    let medium_err = |f| (false, f);
    let side = |y: &State| exit.side(exit_z, Vec3::new(y[0], y[1], y[2]));
    let r2 = p.x * p.x + p.y * p.y;
    let n0 = physical(g.eval(r2, p.z).0, p).map_err(medium_err)?;
    let mut y: State = [p.x, p.y, p.z, n0 * d.x, n0 * d.y, n0 * d.z, 0.0];
    let mut g0 = side(&y).ok_or((true, RayFailure::Miss))?;
    if g0 >= 0.0 {
        // The back surface is not behind the ray's entry: the surfaces cross at this height.
        return Err((true, RayFailure::Miss));
    }
    let tol = settings.tolerance;
    let mut h = 0.25_f64;
    let mut steps = 0usize;
    loop {
        steps += 1;
        if steps > settings.max_steps {
            return Err(medium_err(RayFailure::GrinNotConverged {
                reason: format!("more than {} steps", settings.max_steps),
            }));
        }
        if y[5] <= 0.0 {
            return Err(medium_err(RayFailure::GrinNotConverged {
                reason: "the ray turns back inside the medium".into(),
            }));
        }
        let k1 = derivative(g, &y).map_err(medium_err)?;
        let (y1, err) = step(g, &y, &k1, h).map_err(medium_err)?;
        if !err.is_finite() {
            return Err(medium_err(RayFailure::GrinNotConverged {
                reason: "the error estimate is not finite".into(),
            }));
        }
        if err > tol {
            h *= (0.9 * (tol / err).powf(0.2)).clamp(0.1, 0.9);
            if h < 1e-12 {
                return Err(medium_err(RayFailure::GrinNotConverged {
                    reason: "the step size underflows".into(),
                }));
            }
            continue;
        }
        let g1 = side(&y1).ok_or((true, RayFailure::Miss))?;
        if g1 >= 0.0 {
            // The ray crosses the back surface within this step: find the sub-step τ with
            // side(step(y, τ)) = 0 by the Illinois variant of regula falsi, re-stepping from y so
            // that the exit point has the integrator's own accuracy.
            let (mut ta, mut fa) = (0.0_f64, g0);
            let (mut tb, mut fb) = (h, g1);
            let mut yb = y1;
            let mut last = 0;
            for _ in 0..100 {
                let tc = (ta * fb - tb * fa) / (fb - fa);
                let (yc, _) = step(g, &y, &k1, tc).map_err(medium_err)?;
                let fc = side(&yc).ok_or((true, RayFailure::Miss))?;
                if fc >= 0.0 {
                    tb = tc;
                    fb = fc;
                    yb = yc;
                    if last == 1 {
                        fa *= 0.5;
                    }
                    last = 1;
                } else {
                    ta = tc;
                    fa = fc;
                    if last == -1 {
                        fb *= 0.5;
                    }
                    last = -1;
                }
                if fc.abs() < 1e-13 || (tb - ta).abs() < 1e-15 * h.max(1.0) {
                    yb = yc;
                    break;
                }
            }
            let q = Vec3::new(yb[0], yb[1], yb[2]);
            let dir = Vec3::new(yb[3], yb[4], yb[5]);
            return Ok((q, dir, yb[6]));
        }
        y = y1;
        g0 = g1;
        if let Some(path) = path.as_deref_mut() {
            path.push(Vec3::new(y[0], y[1], y[2]));
        }
        let grow = if err == 0.0 {
            5.0
        } else {
            (0.9 * (tol / err).powf(0.2)).clamp(0.2, 5.0)
        };
        h *= grow;
    }
}
