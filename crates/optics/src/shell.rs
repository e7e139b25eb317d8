//! Best-focus surfaces in the shell's frame (z from the anterior corneal apex along the axis,
//! r from the axis; docs/MODEL.md §6): the foci for field angles 0..max, a smooth interpolant
//! R(φ) in polar form about an axis point, and the paper's polar fit R(φ) = P1 φ⁴ + P2 φ² + P3.

use rayon::prelude::*;

use crate::error::OpticsError;
use crate::focus::{best_focus_with, Criterion, Focus, FocusSettings, Pupil, MAX_FIELD_DEG};
use crate::linalg;
use crate::system::OpticalSystem;

/// Which field angles are computed, and how each focus is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceSettings {
    /// The largest field angle (degrees).
    pub max_field_deg: f64,
    /// Field angles, evenly spaced from 0 to `max_field_deg`.
    pub fields: usize,
    pub focus: FocusSettings,
}

impl Default for SurfaceSettings {
    fn default() -> Self {
        Self {
            max_field_deg: 40.0,
            fields: 41,
            focus: FocusSettings::default(),
        }
    }
}

/// The best-focus surface of one wavelength: its foci in field order.
#[derive(Debug, Clone, PartialEq)]
pub struct FocusSurface {
    pub wavelength_nm: f64,
    pub criterion: Criterion,
    pub points: Vec<Focus>,
}

/// The best-focus surfaces of several wavelengths, computed together.
#[derive(Debug, Clone, PartialEq)]
pub struct Surfaces {
    pub surfaces: Vec<FocusSurface>,
    pub pupil: Pupil,
    pub criterion: Criterion,
    /// Rays traced through the whole system, over all wavelengths and fields.
    pub rays_traced: usize,
}

impl Surfaces {
    /// The surfaces of `system` for `wavelengths`, through `pupil`, by `criterion`: every
    /// (wavelength, field) pair in parallel. The first failure in (wavelength, field) order is
    /// the error, so it does not depend on the thread schedule.
    pub fn compute(
        system: &OpticalSystem,
        wavelengths: &[f64],
        pupil: &Pupil,
        criterion: Criterion,
        settings: &SurfaceSettings,
    ) -> Result<Self, OpticsError> {
        if wavelengths.is_empty() {
            return Err(OpticsError::input(
                "the wavelengths",
                0.0,
                "at least one is needed",
            ));
        }
        if !(settings.max_field_deg > 0.0 && settings.max_field_deg <= MAX_FIELD_DEG) {
            return Err(OpticsError::input(
                "the largest field angle (degrees)",
                settings.max_field_deg,
                format!("must be above 0 and at most {MAX_FIELD_DEG}"),
            ));
        }
        if !(4..=2001).contains(&settings.fields) {
            return Err(OpticsError::input(
                "the number of field angles",
                settings.fields as f64,
                "must be between 4 and 2001",
            ));
        }
        for &w in wavelengths {
            system.check_wavelength(w)?;
        }
        let fields: Vec<f64> = (0..settings.fields)
            .map(|i| settings.max_field_deg * i as f64 / (settings.fields - 1) as f64)
            .collect();
        let jobs: Vec<(f64, f64)> = wavelengths
            .iter()
            .flat_map(|&w| fields.iter().map(move |&f| (w, f)))
            .collect();
        let results: Vec<Result<Focus, OpticsError>> = jobs
            .par_iter()
            .map(|&(w, f)| best_focus_with(system, w, f, pupil, criterion, &settings.focus))
            .collect();
        let mut points = Vec::with_capacity(results.len());
        for r in results {
            points.push(r?);
        }
        let rays_traced = points.iter().map(|p| p.rays).sum();
        let surfaces = points
            .chunks(fields.len())
            .zip(wavelengths)
            .map(|(chunk, &w)| FocusSurface {
                wavelength_nm: w,
                criterion,
                points: chunk.to_vec(),
            })
            .collect();
        Ok(Self {
            surfaces,
            pupil: *pupil,
            criterion,
            rays_traced,
        })
    }

    /// The surface of a wavelength.
    pub fn get(&self, wavelength_nm: f64) -> Option<&FocusSurface> {
        self.surfaces
            .iter()
            .find(|s| s.wavelength_nm == wavelength_nm)
    }
}

/// The paper's polar form: R(φ) = P1 φ⁴ + P2 φ² + P3 about the axis point z_B, for
/// 0 ≤ φ ≤ φ_max; with the fit's residuals when it was fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarFit {
    pub p1: f64,
    pub p2: f64,
    pub p3: f64,
    pub z_b: f64,
    pub phi_max: f64,
    /// Root-mean-square and largest |residual| in R over the fitted points (mm).
    pub rms_residual: f64,
    pub max_residual: f64,
}

impl PolarFit {
    /// The blue (400 nm) surface published with the paper's code (docs/MODEL.md §6).
    pub const PAPER_BLUE: Self = Self {
        p1: -4.464456500210127,
        p2: -8.019851138753314,
        p3: 23.6349728997666,
        z_b: -0.5064886748669879,
        phi_max: 0.5870000878571975,
        rms_residual: f64::NAN,
        max_residual: f64::NAN,
    };

    pub fn radius(&self, phi: f64) -> f64 {
        let p2 = phi * phi;
        self.p1 * p2 * p2 + self.p2 * p2 + self.p3
    }
}

/// Polar coordinates (φ, R) of the points about the axis point z_c.
fn polar(points: &[Focus], z_c: f64) -> Vec<(f64, f64)> {
    points
        .iter()
        .map(|p| (p.r.atan2(p.z - z_c), p.r.hypot(p.z - z_c)))
        .collect()
}

fn fit_about(points: &[Focus], z_b: f64) -> Option<PolarFit> {
    let pr = polar(points, z_b);
    let rows: Vec<[f64; 3]> = pr.iter().map(|&(f, _)| [f.powi(4), f * f, 1.0]).collect();
    let rhs: Vec<f64> = pr.iter().map(|p| p.1).collect();
    let c = linalg::least_squares::<3>(&rows, &rhs)?;
    let res: Vec<f64> = pr
        .iter()
        .map(|&(f, r)| r - (c[0] * f.powi(4) + c[1] * f * f + c[2]))
        .collect();
    let rms = (res.iter().map(|e| e * e).sum::<f64>() / res.len() as f64).sqrt();
    let max = res.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
    let phi_max = pr.iter().map(|p| p.0).fold(0.0_f64, f64::max);
    Some(PolarFit {
        p1: c[0],
        p2: c[1],
        p3: c[2],
        z_b,
        phi_max,
        rms_residual: rms,
        max_residual: max,
    })
}

impl FocusSurface {
    /// The polar fit about a given axis point z_B.
    pub fn polar_fit_about(&self, z_b: f64) -> Result<PolarFit, OpticsError> {
        if !z_b.is_finite() || self.points.iter().any(|p| !(p.z > z_b)) {
            return Err(OpticsError::Fit(format!(
                "the polar form's axis point z_B = {z_b} mm must lie in front of every focus of the {} nm surface",
                self.wavelength_nm
            )));
        }
        fit_about(&self.points, z_b).ok_or_else(|| {
            OpticsError::Fit(format!(
                "the {} nm surface has too few distinct points for a polar fit",
                self.wavelength_nm
            ))
        })
    }

    /// The polar fit with its axis point z_B chosen too (least squares over z_B by a scan and
    /// golden-section search between 40 mm and 2 mm in front of the axial focus).
    pub fn polar_fit(&self) -> Result<PolarFit, OpticsError> {
        let z0 = self.points.first().map_or(0.0, |p| p.z);
        let zmin = self
            .points
            .iter()
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        let (lo, hi) = (z0 - 40.0, zmin - 2.0);
        let rms = |z: f64| fit_about(&self.points, z).map_or(f64::INFINITY, |f| f.rms_residual);
        let n = 80;
        let h = (hi - lo) / n as f64;
        let best = (0..=n)
            .map(|i| lo + i as f64 * h)
            .min_by(|a, b| rms(*a).total_cmp(&rms(*b)))
            .unwrap_or(lo);
        let (mut a, mut b) = ((best - h).max(lo), (best + h).min(hi));
        let g = (5f64.sqrt() - 1.0) / 2.0;
        while b - a > 1e-9 {
            let c = b - g * (b - a);
            let d = a + g * (b - a);
            if rms(c) < rms(d) {
                b = d;
            } else {
                a = c;
            }
        }
        self.polar_fit_about((a + b) / 2.0)
    }

    /// The smooth interpolant R(φ) about the axis point `z_c`.
    pub fn interpolant(&self, z_c: f64) -> Result<PolarSpline, OpticsError> {
        if !z_c.is_finite() || self.points.iter().any(|p| !(p.z > z_c)) {
            return Err(OpticsError::Fit(format!(
                "the axis point {z_c} mm must lie in front of every focus of the {} nm surface",
                self.wavelength_nm
            )));
        }
        let pr = polar(&self.points, z_c);
        for (w, p) in pr.windows(2).zip(self.points.windows(2)) {
            if !(w[1].0 > w[0].0) {
                return Err(OpticsError::Fit(format!(
                    "the {} nm surface folds back between {}° and {}°: its polar angle about z = {z_c} mm does not increase",
                    self.wavelength_nm, p[0].field_deg, p[1].field_deg
                )));
            }
        }
        PolarSpline::new(
            z_c,
            pr.iter().map(|p| p.0).collect(),
            pr.iter().map(|p| p.1).collect(),
        )
    }
}

/// A cubic spline R(φ) through the surface's points in polar form about `z_c`, with
/// R′(0) = 0 (the surface is symmetric about the axis) and a natural end at φ_max: twice
/// continuously differentiable, so a growth law that reads it has no kinks.
#[derive(Debug, Clone, PartialEq)]
pub struct PolarSpline {
    pub z_c: f64,
    phi: Vec<f64>,
    radius: Vec<f64>,
    second: Vec<f64>,
}

impl PolarSpline {
    /// The spline through the points (φᵢ, Rᵢ) about `z_c`, φ increasing from the axis (φ₀ = 0
    /// makes the slope zero there): how a surface resampled or blended from others is held.
    pub fn from_points(z_c: f64, phi: Vec<f64>, radius: Vec<f64>) -> Result<Self, OpticsError> {
        if phi.len() != radius.len() || phi.windows(2).any(|w| !(w[1] > w[0])) {
            return Err(OpticsError::Fit(
                "a spline's angles must increase and match its radii".into(),
            ));
        }
        Self::new(z_c, phi, radius)
    }

    fn new(z_c: f64, phi: Vec<f64>, radius: Vec<f64>) -> Result<Self, OpticsError> {
        let n = phi.len();
        if n < 3 || phi.iter().chain(&radius).any(|v| !v.is_finite()) {
            return Err(OpticsError::Fit(
                "a spline needs at least 3 finite points".into(),
            ));
        }
        let h: Vec<f64> = phi.windows(2).map(|w| w[1] - w[0]).collect();
        // Tridiagonal system for the second derivatives M: clamped (slope 0) at φ₀ when φ₀ is
        // the axis, natural at the end.
        let mut a = vec![0.0; n];
        let mut b = vec![0.0; n];
        let mut c = vec![0.0; n];
        let mut d = vec![0.0; n];
        let slope = |i: usize| (radius[i + 1] - radius[i]) / h[i];
        if phi[0].abs() < 1e-9 {
            b[0] = 2.0 * h[0];
            c[0] = h[0];
            d[0] = 6.0 * slope(0);
        } else {
            b[0] = 1.0;
        }
        for i in 1..n - 1 {
            a[i] = h[i - 1];
            b[i] = 2.0 * (h[i - 1] + h[i]);
            c[i] = h[i];
            d[i] = 6.0 * (slope(i) - slope(i - 1));
        }
        b[n - 1] = 1.0;
        // Thomas algorithm.
        for i in 1..n {
            let m = a[i] / b[i - 1];
            b[i] -= m * c[i - 1];
            d[i] -= m * d[i - 1];
        }
        let mut second = vec![0.0; n];
        second[n - 1] = d[n - 1] / b[n - 1];
        for i in (0..n - 1).rev() {
            second[i] = (d[i] - c[i] * second[i + 1]) / b[i];
        }
        if second.iter().any(|v| !v.is_finite()) {
            return Err(OpticsError::Fit("the spline's system is singular".into()));
        }
        Ok(Self {
            z_c,
            phi,
            radius,
            second,
        })
    }

    /// The largest polar angle the surface reaches.
    pub fn phi_max(&self) -> f64 {
        self.phi[self.phi.len() - 1]
    }

    /// R(φ) for 0 ≤ φ ≤ φ_max (below the first point, by the axis's symmetry, the spline's own
    /// even continuation); `None` outside.
    pub fn radius(&self, phi: f64) -> Option<f64> {
        let phi = if phi < self.phi[0] && self.phi[0].abs() < 1e-9 {
            -phi
        } else {
            phi
        };
        if !(phi >= self.phi[0] - 1e-12 && phi <= self.phi_max() + 1e-12) {
            return None;
        }
        let i = match self.phi.partition_point(|&p| p <= phi) {
            0 => 0,
            k => (k - 1).min(self.phi.len() - 2),
        };
        let (x0, x1) = (self.phi[i], self.phi[i + 1]);
        let h = x1 - x0;
        let (t, u) = ((x1 - phi) / h, (phi - x0) / h);
        let (m0, m1) = (self.second[i], self.second[i + 1]);
        Some(
            t * self.radius[i]
                + u * self.radius[i + 1]
                + h * h / 6.0 * ((t * t * t - t) * m0 + (u * u * u - u) * m1),
        )
    }

    /// R′(φ), the spline's own derivative (exact: the derivative of the cubic pieces), for
    /// 0 ≤ φ ≤ φ_max (below the first point, that of the even continuation); `None` outside.
    pub fn slope(&self, phi: f64) -> Option<f64> {
        let mirrored = phi < self.phi[0] && self.phi[0].abs() < 1e-9;
        let at = if mirrored { -phi } else { phi };
        if !(at >= self.phi[0] - 1e-12 && at <= self.phi_max() + 1e-12) {
            return None;
        }
        let i = match self.phi.partition_point(|&p| p <= at) {
            0 => 0,
            k => (k - 1).min(self.phi.len() - 2),
        };
        let (x0, x1) = (self.phi[i], self.phi[i + 1]);
        let h = x1 - x0;
        let (t, u) = ((x1 - at) / h, (at - x0) / h);
        let (m0, m1) = (self.second[i], self.second[i + 1]);
        let s = (self.radius[i + 1] - self.radius[i]) / h
            + h / 6.0 * (-(3.0 * t * t - 1.0) * m0 + (3.0 * u * u - 1.0) * m1);
        Some(if mirrored { -s } else { s })
    }

    /// The signed distance from the point (z, r) out to the surface along its polar ray,
    /// R(φ) − |(z, r) − (z_c, 0)|: positive when the point lies in front of the surface (the
    /// d of docs/MODEL.md §6). `None` beyond φ_max.
    pub fn depth(&self, z: f64, r: f64) -> Option<f64> {
        let phi = r.atan2(z - self.z_c);
        Some(self.radius(phi)? - r.hypot(z - self.z_c))
    }

    /// The knots (φ, R).
    pub fn knots(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.phi.iter().copied().zip(self.radius.iter().copied())
    }
}
