//! Eyewear: spectacle and contact lenses in front of an eye (docs/optics.md, "Lenses").
//!
//! A thin lens is a phase φ(h) added on a surface (a plane at the spectacle's vertex, or the
//! anterior cornea for a contact lens), h the distance from the lens's axis. A ray crossing it
//! at height h gains the optical path φ(h), and its optical direction across the surface
//! changes by the phase's gradient (the law of a diffractive or metasurface lens, which is
//! Snell's law when φ comes from a thickness of glass): n′d′ₜ = n dₜ + ∇φ. Tying the deflection
//! to the path this way keeps Malus–Dupin's theorem: the wavefront the focus criteria fit is
//! the one the rays are normal to.
//!
//! "Power P at radial position h" means: the ray parallel to the axis at height h leaves aimed
//! at the axial point at 1/P (mm, for P in mm⁻¹) behind the lens, as it would through a
//! perfect lens of power P centred on the lens's axis. Its radial deflection is
//! δ(h) = −hP/√(1 + h²P²) (paraxially Δu = −h·P), and φ(h) = ∫₀ʰ δ. A zone is so a ring of an
//! aberration-free lens of its own power about the common axis (as concentric bifocal contact
//! lenses are made): a pencil crossing it focuses where that power puts it, and φ is
//! continuous at a zone's edge while the deflection jumps. For a smooth table P(h), a thin
//! pencil at height h sees the sagittal power P(h) and the tangential power d(hP)/dh =
//! P + hP′: the definition fixes the rays, not both powers at once.

use crate::error::OpticsError;

/// The largest power (D) a lens or a zone may have: beyond any ophthalmic lens (spectacles
/// reach about ±30 D).
pub const MAX_POWER_D: f64 = 100.0;

/// One ring of a zoned lens: from the previous zone's radius (0 for the first) to `radius`
/// (mm from the lens's axis), of power `power` (D).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Zone {
    pub radius: f64,
    pub power: f64,
}

/// A thin lens's power over its radial position.
#[derive(Debug, Clone, PartialEq)]
pub enum PowerProfile {
    /// One power (D) everywhere.
    Uniform(f64),
    /// Rings of constant power, radii strictly increasing; the last radius is the lens's edge.
    Zones(Vec<Zone>),
    /// P(h) through (radius, power) points, interpolated by a monotone cubic (C¹, no
    /// overshoot between points); the last radius is the lens's edge.
    Table(PowerTable),
}

/// A tabulated power profile and its phase, precomputed.
#[derive(Debug, Clone, PartialEq)]
pub struct PowerTable {
    radius: Vec<f64>,
    power: Vec<f64>,
    slope: Vec<f64>,
    /// φ at `step`-spaced heights from 0 to the last radius.
    phase: Vec<f64>,
    step: f64,
}

/// A problem with a profile: the item (`zones[1].radius`, `power`) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileError {
    pub item: String,
    pub value: f64,
    pub problem: String,
}

fn bad(item: impl Into<String>, value: f64, problem: impl Into<String>) -> ProfileError {
    ProfileError {
        item: item.into(),
        value,
        problem: problem.into(),
    }
}

fn check_power(item: String, p: f64) -> Result<(), ProfileError> {
    if !(p.is_finite() && p.abs() <= MAX_POWER_D) {
        return Err(bad(
            item,
            p,
            format!("must lie in [-{MAX_POWER_D}, {MAX_POWER_D}] D"),
        ));
    }
    Ok(())
}

/// δ(h) for a lens of power p (mm⁻¹).
fn deflection(h: f64, p: f64) -> f64 {
    let x = h * p;
    -x / (1.0 + x * x).sqrt()
}

/// φ(h) = ∫₀ʰ δ for a lens of power p (mm⁻¹): −(√(1 + h²p²) − 1)/p, written without
/// cancellation.
fn phase(h: f64, p: f64) -> f64 {
    let x = h * p;
    -p * h * h / ((1.0 + x * x).sqrt() + 1.0)
}

impl PowerProfile {
    /// Zones checked: at least one, radii positive, finite and strictly increasing, powers
    /// within ±[`MAX_POWER_D`].
    pub fn zones(zones: Vec<Zone>) -> Result<Self, ProfileError> {
        if zones.is_empty() {
            return Err(bad("zones", f64::NAN, "must list at least one zone"));
        }
        let mut inner = 0.0;
        for (i, z) in zones.iter().enumerate() {
            if !(z.radius.is_finite() && z.radius > inner) {
                let problem = if i == 0 {
                    "must be positive and finite (mm from the lens's axis)".to_string()
                } else {
                    format!(
                        "must be larger than the previous zone's radius ({} mm): zones go outwards in order",
                        crate::error::num(inner)
                    )
                };
                return Err(bad(format!("zones[{i}].radius"), z.radius, problem));
            }
            check_power(format!("zones[{i}].power"), z.power)?;
            inner = z.radius;
        }
        Ok(PowerProfile::Zones(zones))
    }

    /// A table checked and prepared: at least two points, radii from ≥ 0 strictly
    /// increasing, powers within ±[`MAX_POWER_D`].
    pub fn table(radius: Vec<f64>, power: Vec<f64>) -> Result<Self, ProfileError> {
        if radius.len() < 2 || radius.len() != power.len() {
            return Err(bad(
                "table",
                radius.len() as f64,
                "must hold at least two (radius, power) points",
            ));
        }
        let mut prev = -1.0;
        for (i, (&r, &p)) in radius.iter().zip(&power).enumerate() {
            if !(r.is_finite() && r >= 0.0 && r > prev) {
                return Err(bad(
                    format!("table[{i}].radius"),
                    r,
                    "must be finite, at least 0 and larger than the previous radius",
                ));
            }
            check_power(format!("table[{i}].power"), p)?;
            prev = r;
        }
        let slope = pchip_slopes(&radius, &power);
        let edge = *radius.last().unwrap_or(&1.0);
        let n = 4096;
        let step = edge / n as f64;
        let mut t = PowerTable {
            radius,
            power,
            slope,
            phase: vec![0.0; n + 1],
            step,
        };
        // φ by Gauss–Legendre (3 points) on each step: the table's own accuracy (1e-12 mm)
        // is far below any focus criterion's.
        let g = [
            (-0.774_596_669_241_483_4, 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            (0.774_596_669_241_483_4, 5.0 / 9.0),
        ];
        for k in 0..n {
            let (a, b) = (k as f64 * step, (k + 1) as f64 * step);
            let sum: f64 = g
                .iter()
                .map(|&(x, w)| {
                    let h = 0.5 * (a + b) + 0.5 * (b - a) * x;
                    w * deflection(h, t.power_at(h) / 1000.0)
                })
                .sum();
            t.phase[k + 1] = t.phase[k] + 0.5 * (b - a) * sum;
        }
        Ok(PowerProfile::Table(t))
    }

    /// A uniform profile checked.
    pub fn uniform(power: f64) -> Result<Self, ProfileError> {
        check_power("power".into(), power)?;
        Ok(PowerProfile::Uniform(power))
    }

    /// The power (D) at distance `h` (mm) from the lens's axis.
    pub fn power(&self, h: f64) -> f64 {
        match self {
            PowerProfile::Uniform(p) => *p,
            PowerProfile::Zones(z) => z
                .iter()
                .find(|z| h <= z.radius)
                .or(z.last())
                .map_or(0.0, |z| z.power),
            PowerProfile::Table(t) => t.power_at(h),
        }
    }

    /// The lens's edge (mm from its axis): rays beyond it miss the lens.
    pub fn edge(&self) -> Option<f64> {
        match self {
            PowerProfile::Uniform(_) => None,
            PowerProfile::Zones(z) => z.last().map(|z| z.radius),
            PowerProfile::Table(t) => t.radius.last().copied(),
        }
    }

    /// The radial change δ(h) of the optical direction across the lens (dimensionless).
    pub fn deflection(&self, h: f64) -> f64 {
        deflection(h, self.power(h) / 1000.0)
    }

    /// The optical path φ(h) the lens adds at height h (mm), φ(0) = 0.
    pub fn phase(&self, h: f64) -> f64 {
        match self {
            PowerProfile::Uniform(p) => phase(h, p / 1000.0),
            PowerProfile::Zones(zones) => {
                let mut inner = 0.0;
                let mut total = 0.0;
                for z in zones {
                    let p = z.power / 1000.0;
                    if h <= z.radius {
                        return total + phase(h, p) - phase(inner, p);
                    }
                    total += phase(z.radius, p) - phase(inner, p);
                    inner = z.radius;
                }
                total
            }
            PowerProfile::Table(t) => t.phase_at(h),
        }
    }
}

impl PowerTable {
    fn power_at(&self, h: f64) -> f64 {
        let (r, p, m) = (&self.radius, &self.power, &self.slope);
        let n = r.len();
        if h <= r[0] {
            return p[0];
        }
        if h >= r[n - 1] {
            return p[n - 1];
        }
        let k = r.partition_point(|&x| x <= h).clamp(1, n - 1) - 1;
        let dx = r[k + 1] - r[k];
        let s = (h - r[k]) / dx;
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s),
            s * (1.0 - s) * (1.0 - s),
            s * s * (3.0 - 2.0 * s),
            s * s * (s - 1.0),
        );
        h00 * p[k] + h10 * dx * m[k] + h01 * p[k + 1] + h11 * dx * m[k + 1]
    }

    /// φ by cubic Hermite interpolation of the tabulated phase with its exact derivative δ.
    fn phase_at(&self, h: f64) -> f64 {
        let n = self.phase.len() - 1;
        let edge = self.step * n as f64;
        if !(self.step > 0.0) {
            return 0.0;
        }
        let h = h.clamp(0.0, edge);
        let k = ((h / self.step) as usize).min(n - 1);
        let (a, b) = (k as f64 * self.step, (k + 1) as f64 * self.step);
        let s = (h - a) / self.step;
        let da = deflection(a, self.power_at(a) / 1000.0);
        let db = deflection(b, self.power_at(b) / 1000.0);
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s),
            s * (1.0 - s) * (1.0 - s),
            s * s * (3.0 - 2.0 * s),
            s * s * (s - 1.0),
        );
        h00 * self.phase[k] + h10 * self.step * da + h01 * self.phase[k + 1] + h11 * self.step * db
    }
}

/// Fritsch–Carlson slopes: a monotone piecewise cubic through the points.
fn pchip_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let d: Vec<f64> = (0..n - 1)
        .map(|k| (y[k + 1] - y[k]) / (x[k + 1] - x[k]))
        .collect();
    let mut m = vec![0.0; n];
    if n == 2 {
        return vec![d[0]; 2];
    }
    for k in 1..n - 1 {
        if d[k - 1] * d[k] > 0.0 {
            let (h0, h1) = (x[k] - x[k - 1], x[k + 1] - x[k]);
            let (w1, w2) = (2.0 * h1 + h0, h1 + 2.0 * h0);
            m[k] = (w1 + w2) / (w1 / d[k - 1] + w2 / d[k]);
        }
    }
    // One-sided three-point ends, limited to keep the shape.
    let end = |h0: f64, h1: f64, d0: f64, d1: f64| {
        let s = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
        if s * d0 <= 0.0 {
            0.0
        } else if d0 * d1 <= 0.0 && s.abs() > 3.0 * d0.abs() {
            3.0 * d0
        } else {
            s
        }
    };
    m[0] = end(x[1] - x[0], x[2] - x[1], d[0], d[1]);
    m[n - 1] = end(x[n - 1] - x[n - 2], x[n - 2] - x[n - 3], d[n - 2], d[n - 3]);
    m
}

/// Where a lens sits.
#[derive(Debug, Clone, PartialEq)]
pub enum Mount {
    /// A spectacle lens whose back vertex is `vertex` mm in front of the corneal apex.
    Spectacle { vertex: f64 },
    /// A contact lens on the cornea.
    Contact,
}

/// What a lens is made of.
#[derive(Debug, Clone, PartialEq)]
pub enum LensBody {
    /// A thin lens of this profile.
    Thin(PowerProfile),
    /// A real lens: front and back vertex radii (mm, ∞ for a plane), centre thickness (mm)
    /// and index.
    Real {
        front_radius: f64,
        back_radius: f64,
        thickness: f64,
        index: f64,
    },
}

/// One lens in front of (or on) the eye.
#[derive(Debug, Clone, PartialEq)]
pub struct Lens {
    pub mount: Mount,
    pub body: LensBody,
}

impl Lens {
    /// A thin spectacle lens of one power (D) at `vertex` mm.
    pub fn spectacle(power: f64, vertex: f64) -> Self {
        Lens {
            mount: Mount::Spectacle { vertex },
            body: LensBody::Thin(PowerProfile::Uniform(power)),
        }
    }
}

/// The eye with `lenses` worn: spectacle lenses become elements in front of the cornea (the
/// system's origin moves forward, so z keeps its meaning, from the corneal apex); a thin
/// contact lens becomes a phase on the anterior cornea: its back surface is taken to fit the
/// cornea with a tear layer of no thickness, so the tear lens has no power and only the
/// lens's own profile acts. Lenses are applied from the eye outwards, in the order given;
/// spectacle lenses must not overlap each other or the cornea.
pub fn wear(
    eye: &crate::OpticalSystem,
    lenses: &[Lens],
) -> Result<crate::OpticalSystem, OpticsError> {
    use crate::{Element, Medium, Surface};
    let mut system = eye.clone();
    let mut specs: Vec<(f64, &Lens)> = Vec::new();
    for (i, lens) in lenses.iter().enumerate() {
        match (&lens.mount, &lens.body) {
            (Mount::Contact, LensBody::Thin(profile)) => {
                let first = &mut system.elements[0];
                if first.surface.phase.is_some() {
                    return Err(OpticsError::Eyewear {
                        lens: i,
                        reason: "is a second contact lens: two contact lenses cannot be worn at once (the cornea holds one)".into(),
                    });
                }
                first.surface.phase = Some(profile.clone());
                if let Some(edge) = profile.edge() {
                    first.surface.semi_diameter = Some(edge);
                }
            }
            (Mount::Contact, LensBody::Real { .. }) => {
                return Err(OpticsError::Eyewear {
                    lens: i,
                    reason: "is a contact lens with a real lens's surfaces: a contact lens is thin here (its power profile on the cornea)".into(),
                })
            }
            (Mount::Spectacle { vertex }, _) => {
                if !(vertex.is_finite() && *vertex > 0.0) {
                    return Err(OpticsError::system(
                        format!("lens {i} vertex distance (mm)"),
                        *vertex,
                        "must be positive: the lens lies in front of the cornea",
                    ));
                }
                specs.push((*vertex, lens));
            }
        }
    }
    // Nearest the eye first: each is prepended in turn.
    specs.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (k, (vertex, lens)) in specs.iter().enumerate() {
        let front = system.origin;
        let name = format!("spectacle lens {}", k + 1);
        let mut new = match &lens.body {
            LensBody::Thin(profile) => {
                let mut s = Surface::plane(name);
                s.phase = Some(profile.clone());
                s.semi_diameter = profile.edge();
                vec![(s, vertex + front, Medium::constant("air", 1.0), *vertex)]
            }
            LensBody::Real {
                front_radius,
                back_radius,
                thickness,
                index,
            } => vec![
                (
                    Surface::new(format!("{name} front"), *front_radius, 0.0),
                    *thickness,
                    Medium::constant(format!("{name} material"), *index),
                    vertex + thickness,
                ),
                (
                    Surface::new(format!("{name} back"), *back_radius, 0.0),
                    vertex + front,
                    Medium::constant("air", 1.0),
                    *vertex,
                ),
            ],
        };
        let gap = new.last().map_or(0.0, |x| x.1);
        if !(gap > 0.0) {
            return Err(OpticsError::system(
                format!("{} vertex distance (mm)", new[0].0.name),
                *vertex,
                format!(
                    "puts the lens at or behind the surface in front of which it must sit (at {} mm)",
                    crate::error::num(-front)
                ),
            ));
        }
        let origin = -new[0].3;
        let mut elements: Vec<Element> = new
            .drain(..)
            .map(|(s, t, m, _)| Element::new(s, t, m))
            .collect();
        elements.append(&mut system.elements);
        system.elements = elements;
        system.origin = origin;
    }
    system.validate()?;
    Ok(system)
}
