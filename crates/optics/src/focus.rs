//! Best focus of a distant point at one wavelength and field angle, through a pupil.
//!
//! Rays are aimed through a grid of points uniformly covering the aperture stop (the pupil)
//! and traced exactly into the image space. Each ray i leaves the last surface at qᵢ with unit
//! direction dᵢ and optical path Lᵢ; its contribution to the field at a point P is, in Debye's
//! approximation, the phase Φᵢ(P) = Lᵢ + n′ dᵢ·(P − qᵢ) (the plane wave it carries). Writing
//! P = Q + s d꜀ on the chief ray (Q where the chief ray leaves the last surface) and αᵢ for the
//! components of dᵢ across the chief ray (sagittal x, tangential y), the wave aberration at
//! distance s is Φᵢ(s) with piston and tilt removed.
//!
//! * `Strehl`: the Strehl ratio |⟨exp(i k W)⟩|² over the pupil, W the aberration at s with its
//!   weighted least-squares piston and tilt removed (the peak of the test plane perpendicular to
//!   the chief ray at s), summed on as many rays as W's waves need (`strehl.rs`) and maximised
//!   in s (a scan, then Newton's method on S′ = 0, or golden-section search).
//! * `MeanSphere`: Φᵢ(Q) and ψᵢ = dᵢ·d꜀ (the exact phase change per unit s) fitted by least
//!   squares with 1, αₓ, α_y, αₓ², α_y², αₓα_y (the span of the Zernike terms up to defocus and
//!   astigmatism); the sagittal and tangential foci are the s where the αₓ² and α_y²
//!   coefficients of Φ + s n′ψ vanish (≈ 2aₓₓ/n′, 2a_yy/n′), and the best focus is at the mean
//!   of their vergences, s = 2/(1/sₛ + 1/sₜ). For a small pupil these are Coddington's foci; a
//!   perfect spherical wave gives its centre at any aperture.

use crate::error::{OpticsError, RayError, RayFailure};
use crate::linalg;
use crate::medium::Resolved;
use crate::sampling::{pupil_samples, Sampling};
use crate::strehl::{PupilRay, StrehlModel};
use crate::system::OpticalSystem;
use crate::trace::{GrinSettings, Ray, Tracer};
use crate::vec3::Vec3;

/// The aperture stop: a circular opening centred on the axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pupil {
    /// Diameter (mm).
    pub diameter: f64,
    /// Axial position of the stop's plane (mm from the corneal apex).
    pub position: f64,
}

/// How the best focus is chosen along the chief ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Criterion {
    /// The point at the mean of the sagittal and tangential vergences of the wavefront's
    /// defocus and astigmatism (what peripheral refraction measures).
    MeanSphere,
    /// The maximum Strehl ratio along the chief ray (the paper's criterion).
    Strehl,
    /// The sagittal focus of the wavefront's fit (the sagittal focal line): the surface the
    /// paper's published blue surface follows (docs/optics.md).
    Sagittal,
    /// The tangential focus of the wavefront's fit (the tangential focal line).
    Tangential,
}

impl Criterion {
    pub fn name(self) -> &'static str {
        match self {
            Self::MeanSphere => "mean-sphere",
            Self::Strehl => "strehl",
            Self::Sagittal => "sagittal",
            Self::Tangential => "tangential",
        }
    }
}

/// Numerical settings of a best-focus computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocusSettings {
    /// Rays across the pupil's diameter: the pupil is sampled by rays_across/2 Gauss–Legendre
    /// rings times about 2 × rays_across spokes (rays_across² rays, half of them traced and
    /// the other half their mirror images).
    pub rays_across: usize,
    pub grin: GrinSettings,
}

impl Default for FocusSettings {
    fn default() -> Self {
        Self {
            rays_across: 16,
            grin: GrinSettings::default(),
        }
    }
}

/// The ray counts across the pupil [`rays_for`] tries, fewest first.
pub const RAYS_TRIED: [usize; 4] = [4, 6, 8, 12];

/// One best focus a ray count is checked at.
#[derive(Debug, Clone, Copy)]
pub struct Probe<'a> {
    pub system: &'a OpticalSystem,
    pub pupil: Pupil,
    pub wavelength_nm: f64,
    pub field_deg: f64,
}

/// The fewest rays across the pupil, of [`RAYS_TRIED`], whose best focus (z, r) lies within
/// `tolerance` mm of twice as many rays' at every probe, else the default count (16). The
/// pupil's Gauss–Legendre rings and even spokes integrate a smooth wavefront's fit exactly up
/// to an order that grows with the count, so the error falls steeply with it and the count
/// that agrees with its double is within about `tolerance` of the converged focus. A small
/// pupil's nearly spherical wavefront needs few rays (4 across a 1 mm pupil of the Atchison
/// eye: 3e-6 mm), a 3 mm pupil more (6: 3e-7 mm; 4 is off by 4e-4 mm). A probe where neither
/// count forms a focus says nothing; where one does and the other not, the counts disagree;
/// a count that no probe speaks for is not taken (nothing checked it).
/// A thin lens whose power changes across its face (zones, a table) keeps the default: a zone's
/// edge inside some field's pencil makes that focus converge slowly in the count, and the
/// probes need not be at that field.
pub fn rays_for(
    probes: &[Probe],
    criterion: Criterion,
    grin: GrinSettings,
    tolerance: f64,
) -> usize {
    use rayon::prelude::*;
    let default = FocusSettings::default().rays_across;
    let varying = probes.iter().any(|p| {
        p.system
            .elements
            .iter()
            .any(|e| e.surface.phase.as_ref().is_some_and(|f| f.edge().is_some()))
    });
    if varying {
        return default;
    }
    let focus = |p: &Probe, rays_across: usize| {
        let settings = FocusSettings { rays_across, grin };
        best_focus_with(
            p.system,
            p.wavelength_nm,
            p.field_deg,
            &p.pupil,
            criterion,
            &settings,
        )
        .ok()
        .map(|f| (f.z, f.r))
    };
    RAYS_TRIED
        .into_iter()
        .find(|&n| {
            // Some(agree), or None where neither count forms a focus.
            let verdicts: Vec<Option<bool>> = probes
                .par_iter()
                .map(|p| match (focus(p, n), focus(p, 2 * n)) {
                    (Some(a), Some(b)) => Some((a.0 - b.0).hypot(a.1 - b.1) <= tolerance),
                    (None, None) => None,
                    _ => Some(false),
                })
                .collect();
            verdicts.contains(&Some(true)) && !verdicts.contains(&Some(false))
        })
        .unwrap_or(default)
}

/// A best focus and what was found on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct Focus {
    pub wavelength_nm: f64,
    pub field_deg: f64,
    pub criterion: Criterion,
    /// The best focus in the shell's frame: z from the corneal apex along the axis, r from it.
    pub z: f64,
    pub r: f64,
    /// Its distance along the chief ray from where the chief ray leaves the last surface (mm).
    pub distance: f64,
    /// The sagittal and tangential foci (distances along the chief ray, mm).
    pub sagittal: f64,
    pub tangential: f64,
    /// The Strehl ratio at the best focus (with any criterion).
    pub strehl: f64,
    /// Rays across the pupil the Strehl ratio was summed on: the traced rays, or, where they
    /// are too few for the wavefront's aberration in waves, a finer sampling of its fit
    /// (docs/optics.md, "Best focus").
    pub strehl_rays: usize,
    /// Where the chief ray leaves the last surface (z, y) and its direction there (dz, dy).
    pub chief_exit: (f64, f64),
    pub chief_direction: (f64, f64),
    /// Rays traced through the whole system (pupil samples and the chief ray).
    pub rays: usize,
}

/// The best focus of `system` for light of `wavelength_nm` from a distant point at
/// `field_deg` from the axis, through `pupil`, by `criterion`, with default settings.
pub fn best_focus(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
    criterion: Criterion,
) -> Result<Focus, OpticsError> {
    best_focus_with(
        system,
        wavelength_nm,
        field_deg,
        pupil,
        criterion,
        &FocusSettings::default(),
    )
}

/// Largest field angle accepted (degrees).
pub const MAX_FIELD_DEG: f64 = 80.0;

pub(crate) fn check_request(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
    settings: &FocusSettings,
) -> Result<(), OpticsError> {
    system.check_wavelength(wavelength_nm)?;
    if !(field_deg.abs() <= MAX_FIELD_DEG) {
        return Err(OpticsError::input(
            "the field angle (degrees)",
            field_deg,
            format!("must be between -{MAX_FIELD_DEG} and {MAX_FIELD_DEG}"),
        ));
    }
    if !(pupil.diameter > 0.0 && pupil.diameter <= 20.0) {
        return Err(OpticsError::input(
            "the pupil diameter (mm)",
            pupil.diameter,
            "must be positive and at most 20 mm",
        ));
    }
    system.check_pupil_position(pupil.position)?;
    if !(4..=1024).contains(&settings.rays_across) {
        return Err(OpticsError::input(
            "the rays across the pupil",
            settings.rays_across as f64,
            "must be between 4 and 1024",
        ));
    }
    let tol = settings.grin.tolerance;
    if !(1e-14..=1e-2).contains(&tol) {
        return Err(OpticsError::input(
            "the GRIN integration tolerance (mm)",
            tol,
            "must be between 1e-14 and 1e-2",
        ));
    }
    Ok(())
}

/// A collimated beam at a field angle, and how its rays are aimed at the stop.
pub(crate) struct Beam<'a> {
    pub(crate) tracer: Tracer<'a>,
    pub(crate) field_deg: f64,
    pub(crate) wavelength_nm: f64,
    direction: Vec3,
    e1: Vec3,
    e2: Vec3,
    back: f64,
    stop_z: f64,
}

const STOP: &str = "pupil";

/// A ray's launch coordinates, or why it cannot be aimed.
type Aimed = Result<(f64, f64), OpticsError>;

impl<'a> Beam<'a> {
    pub(crate) fn new(
        system: &'a OpticalSystem,
        wavelength_nm: f64,
        field_deg: f64,
        stop_z: f64,
        grin: GrinSettings,
    ) -> Self {
        let th = field_deg.to_radians();
        let direction = Vec3::new(0.0, th.sin(), th.cos());
        Self {
            tracer: Tracer::new(system, wavelength_nm, grin),
            field_deg,
            wavelength_nm,
            direction,
            e1: Vec3::new(1.0, 0.0, 0.0),
            e2: Vec3::new(0.0, th.cos(), -th.sin()),
            // Rays start on a plane normal to the beam, far enough in front of the cornea.
            back: (30.0 - system.origin) / th.cos(),
            stop_z,
        }
    }

    pub(crate) fn err(&self, e: RayError) -> OpticsError {
        OpticsError::ray(e, self.field_deg, self.wavelength_nm)
    }

    /// The ray of the beam through launch coordinates (u, v) on the plane normal to the beam.
    pub(crate) fn ray(&self, u: f64, v: f64) -> Ray {
        Ray {
            position: self.e1 * u + self.e2 * v - self.direction * self.back,
            direction: self.direction,
            opl: 0.0,
        }
    }

    pub(crate) fn at_stop(&self, u: f64, v: f64) -> Result<(f64, f64), OpticsError> {
        let r = self
            .tracer
            .trace_to_plane(self.ray(u, v), self.stop_z, STOP)
            .map_err(|e| self.err(e))?;
        Ok((r.position.x, r.position.y))
    }

    /// The chief ray's launch coordinate v (u = 0): it crosses the stop's centre.
    pub(crate) fn chief(&self) -> Result<f64, OpticsError> {
        let (mut v0, mut v1) = (0.0, 0.05);
        let mut f0 = self.at_stop(0.0, v0)?.1;
        let mut f1 = self.at_stop(0.0, v1)?.1;
        for _ in 0..60 {
            if f1.abs() < 1e-12 {
                return Ok(v1);
            }
            let v2 = v1 - f1 * (v1 - v0) / (f1 - f0);
            if !v2.is_finite() {
                break;
            }
            v0 = v1;
            f0 = f1;
            v1 = v2;
            f1 = self.at_stop(0.0, v1)?.1;
        }
        if self
            .tracer
            .system
            .elements
            .iter()
            .any(|e| e.surface.phase.is_some())
        {
            // A thin lens's zone edge can leave a sliver of the stop that no ray reaches: if
            // its centre lies there, the chief ray is the ray at the sliver's edge, found by
            // bisection on a bracket (the sliver is micrometres wide).
            if let Some(v) = self.chief_by_bisection()? {
                return Ok(v);
            }
        }
        Err(OpticsError::NoFocus {
            field_deg: self.field_deg,
            wavelength_nm: self.wavelength_nm,
            reason: "no chief ray through the centre of the pupil".into(),
        })
    }

    fn chief_by_bisection(&self) -> Result<Option<f64>, OpticsError> {
        let f = |v: f64| self.at_stop(0.0, v).map(|p| p.1);
        let (mut a, mut b) = (-1.0, 1.0);
        let (mut fa, fb) = (f(a)?, f(b)?);
        let mut grow = 0;
        while fa * fb > 0.0 && grow < 6 {
            a *= 3.0;
            b *= 3.0;
            fa = f(a)?;
            if fa * f(b)? <= 0.0 {
                break;
            }
            grow += 1;
        }
        if fa * f(b)? > 0.0 {
            return Ok(None);
        }
        for _ in 0..80 {
            let m = 0.5 * (a + b);
            let fm = f(m)?;
            if fm * fa > 0.0 {
                a = m;
                fa = fm;
            } else {
                b = m;
            }
        }
        let v = if fa.abs() < f(b)?.abs() { a } else { b };
        Ok((f(v)?.abs() < 0.02).then_some(v))
    }

    /// Launch coordinates of rays that cross the stop at `targets` (x, y): Newton's method with
    /// the Jacobian at the chief ray, iterated until each ray lands within 1e-10 mm.
    pub(crate) fn aim(
        &self,
        v_chief: f64,
        targets: &[(f64, f64)],
    ) -> Result<Vec<(f64, f64)>, OpticsError> {
        self.aim_each(v_chief, targets)?.into_iter().collect()
    }

    /// [`Beam::aim`], each target's launch or why it cannot be reached.
    pub(crate) fn aim_each(
        &self,
        v_chief: f64,
        targets: &[(f64, f64)],
    ) -> Result<Vec<Aimed>, OpticsError> {
        // Through a zoned thin lens the ray map jumps at the zone edges: a wider difference
        // gives the Jacobian of the map's smooth part even where the chief ray sits on an
        // edge, and Newton's method (then linear) gets more iterations.
        let zoned = self
            .tracer
            .system
            .elements
            .iter()
            .any(|e| e.surface.phase.is_some());
        let (h, iterations) = if zoned { (0.02, 200) } else { (1e-4, 50) };
        let (xu, yu) = self.at_stop(h, v_chief)?;
        let (xu2, yu2) = self.at_stop(-h, v_chief)?;
        let (xv, yv) = self.at_stop(0.0, v_chief + h)?;
        let (xv2, yv2) = self.at_stop(0.0, v_chief - h)?;
        let j = [
            [(xu - xu2) / (2.0 * h), (xv - xv2) / (2.0 * h)],
            [(yu - yu2) / (2.0 * h), (yv - yv2) / (2.0 * h)],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if !(det.abs() > 1e-12) {
            return Err(OpticsError::NoFocus {
                field_deg: self.field_deg,
                wavelength_nm: self.wavelength_nm,
                reason: "the pupil cannot be aimed at (singular ray map)".into(),
            });
        }
        let inv = [
            [j[1][1] / det, -j[0][1] / det],
            [-j[1][0] / det, j[0][0] / det],
        ];
        Ok(targets
            .iter()
            .map(|&(tx, ty)| {
                let (mut u, mut v) = (
                    inv[0][0] * tx + inv[0][1] * ty,
                    v_chief + inv[1][0] * tx + inv[1][1] * ty,
                );
                for _ in 0..iterations {
                    let (x, y) = self.at_stop(u, v)?;
                    let (ex, ey) = (tx - x, ty - y);
                    if ex.hypot(ey) < 1e-10 {
                        return Ok((u, v));
                    }
                    u += inv[0][0] * ex + inv[0][1] * ey;
                    v += inv[1][0] * ex + inv[1][1] * ey;
                }
                Err(OpticsError::NoFocus {
                    field_deg: self.field_deg,
                    wavelength_nm: self.wavelength_nm,
                    reason: format!("the ray to the pupil point ({tx}, {ty}) mm cannot be aimed"),
                })
            })
            .collect())
    }
}

/// The traced beam of one field: chief ray and pupil rays in the image space.
pub(crate) struct Wavefront {
    pub(crate) n_image: f64,
    pub(crate) chief: Ray,
    /// The pupil rays, both halves (the half x < 0 mirrored from the traced half).
    pub(crate) samples: Vec<PupilRay>,
    /// How the pupil was sampled.
    pub(crate) sampling: Sampling,
    /// No thin lens whose power changes across its face: the wavefront is smooth.
    pub(crate) smooth: bool,
    pub(crate) rays: usize,
}

pub(crate) fn wavefront(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
    settings: &FocusSettings,
) -> Result<Wavefront, OpticsError> {
    check_request(system, wavelength_nm, field_deg, pupil, settings)?;
    let beam = Beam::new(
        system,
        wavelength_nm,
        field_deg,
        pupil.position,
        settings.grin,
    );
    let v_chief = beam.chief()?;
    let chief = beam
        .tracer
        .trace(beam.ray(0.0, v_chief))
        .map_err(|e| beam.err(e))?;
    // The beam lies in the y–z plane of a rotationally symmetric system, so it is symmetric
    // under x → −x: the rays of the half pupil x ≥ 0 are traced and mirrored.
    let pupil_points: Vec<(f64, f64, f64)> =
        pupil_samples(pupil.diameter / 2.0, settings.rays_across)
            .into_iter()
            .filter(|p| p.0 > 0.0)
            .collect();
    let targets: Vec<(f64, f64)> = pupil_points.iter().map(|p| (p.0, p.1)).collect();
    // A thin lens's zone edge deflects the rays on either side of it differently, so the
    // pupil has a sliver (micrometres wide) that no ray reaches, or that two reach: a
    // sample point there is left out (its weight with it) rather than failing the focus.
    let zoned = system.elements.iter().any(|e| e.surface.phase.is_some());
    let mut kept = Vec::with_capacity(targets.len());
    let mut launches = Vec::with_capacity(targets.len());
    for (launch, point) in beam
        .aim_each(v_chief, &targets)?
        .into_iter()
        .zip(&pupil_points)
    {
        match launch {
            Ok(l) => {
                launches.push(l);
                kept.push(*point);
            }
            Err(_) if zoned => {}
            Err(e) => return Err(e),
        }
    }
    if 2 * launches.len() < targets.len() {
        return Err(OpticsError::NoFocus {
            field_deg,
            wavelength_nm,
            reason: "most rays cannot be aimed at the pupil through the lens".into(),
        });
    }
    let pupil_points = kept;
    let n_image = beam.tracer.n_image();
    let dc = chief.direction;
    let es = Vec3::new(1.0, 0.0, 0.0);
    let et = dc.cross(es);
    let q = chief.position;
    let mut samples = Vec::with_capacity(2 * launches.len());
    for (&(u, v), &(x, y, w)) in launches.iter().zip(&pupil_points) {
        let r = beam.tracer.trace(beam.ray(u, v)).map_err(|e| beam.err(e))?;
        let d = r.direction;
        let ray = PupilRay {
            stop: (x, y),
            alpha: (d.dot(es), d.dot(et)),
            phase: r.opl + n_image * d.dot(q - r.position) - chief.opl,
            psi: d.dot(dc),
            weight: w,
        };
        samples.push(ray);
        samples.push(PupilRay {
            stop: (-x, y),
            alpha: (-ray.alpha.0, ray.alpha.1),
            ..ray
        });
    }
    let smooth = !system
        .elements
        .iter()
        .any(|e| e.surface.phase.as_ref().is_some_and(|f| f.edge().is_some()));
    Ok(Wavefront {
        n_image,
        chief,
        samples,
        sampling: Sampling {
            radius: pupil.diameter / 2.0,
            rays_across: settings.rays_across,
        },
        smooth,
        rays: launches.len() + 1,
    })
}

impl Wavefront {
    fn alpha_scale(&self) -> f64 {
        self.samples
            .iter()
            .map(|s| s.alpha.0.hypot(s.alpha.1))
            .fold(0.0, f64::max)
            .max(1e-300)
    }

    /// Sagittal and tangential foci (distances along the chief ray from Q): where the
    /// αₓ² and α_y² coefficients of the aberration W(s) = Φ(Q) + s n′ψ vanish, ψᵢ = dᵢ·d꜀ being
    /// the exact change of phase as the reference point moves along the chief ray. Both are
    /// fitted with the same basis, so a perfect spherical wave gives its centre exactly at any
    /// aperture (ψ's own α⁴ content, which a fit of Φ alone would read as defocus, cancels).
    pub(crate) fn astigmatic_foci(&self) -> Option<(f64, f64)> {
        let a = self.alpha_scale();
        let rows: Vec<[f64; 6]> = self
            .samples
            .iter()
            .map(|s| {
                let (x, y, w) = (s.alpha.0 / a, s.alpha.1 / a, s.weight.sqrt());
                [w, w * x, w * y, w * x * x, w * y * y, w * x * y]
            })
            .collect();
        let fit = |value: &dyn Fn(&PupilRay) -> f64| {
            let rhs: Vec<f64> = self
                .samples
                .iter()
                .map(|s| s.weight.sqrt() * value(s))
                .collect();
            linalg::least_squares::<6>(&rows, &rhs)
        };
        let (phi, psi) = (fit(&|s| s.phase)?, fit(&|s| s.psi)?);
        let n = self.n_image;
        Some((-phi[3] / (n * psi[3]), -phi[4] / (n * psi[4])))
    }
}

/// [`best_focus`] with explicit numerical settings.
pub fn best_focus_with(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
    criterion: Criterion,
    settings: &FocusSettings,
) -> Result<Focus, OpticsError> {
    let w = wavefront(system, wavelength_nm, field_deg, pupil, settings)?;
    let no_focus = |reason: &str| OpticsError::NoFocus {
        field_deg,
        wavelength_nm,
        reason: reason.to_string(),
    };
    if w.samples.len() < 6 {
        return Err(no_focus(
            "too few rays across the pupil to fit its wavefront",
        ));
    }
    let (ss, st) = w
        .astigmatic_foci()
        .ok_or_else(|| no_focus("the wavefront's defocus and astigmatism cannot be fitted"))?;
    if !(ss > 0.0 && st > 0.0 && ss.is_finite() && st.is_finite()) {
        return Err(no_focus(
            "the light does not converge behind the last surface",
        ));
    }
    let mean = 2.0 / (1.0 / ss + 1.0 / st);
    let n = w.n_image;
    let model = |range: (f64, f64)| {
        StrehlModel::new(&w.samples, w.sampling, w.smooth, wavelength_nm, n, range)
            .ok_or_else(|| no_focus("the wavefront's tilt cannot be fitted"))
    };
    let at_one = |s: f64| model((s, s)).map(|m| (s, m.at(s), m.rays_across));
    let (distance, strehl_best, strehl_rays) = match criterion {
        Criterion::MeanSphere => at_one(mean)?,
        Criterion::Sagittal => at_one(ss)?,
        Criterion::Tangential => at_one(st)?,
        Criterion::Strehl => {
            // The scan spans both astigmatic foci, two depths of focus λ/(n′ α²) and 1 % of the
            // distance around them.
            let a2 = w
                .samples
                .iter()
                .map(|s| s.alpha.0 * s.alpha.0 + s.alpha.1 * s.alpha.1)
                .fold(0.0, f64::max);
            let dof = (wavelength_nm * 1e-6 / (n * a2.max(1e-12))).min(5.0);
            let margin = 2.0 * dof + 0.5 * (ss - st).abs() + 0.01 * mean;
            let lo = (ss.min(st) - margin).max(1e-3);
            let hi = ss.max(st) + margin;
            let model = model((lo, hi))?;
            let (s, v) = model.maximum(lo, hi, 161);
            (s, v, model.rays_across)
        }
    };
    let p = w.chief.position + w.chief.direction * distance;
    if !(p.is_finite() && strehl_best.is_finite()) {
        return Err(no_focus("the focus is not a finite point"));
    }
    Ok(Focus {
        wavelength_nm,
        field_deg,
        criterion,
        z: p.z,
        r: p.y.abs(),
        distance,
        sagittal: ss,
        tangential: st,
        strehl: strehl_best,
        strehl_rays,
        chief_exit: (w.chief.position.z, w.chief.position.y),
        chief_direction: (w.chief.direction.z, w.chief.direction.y),
        rays: w.rays,
    })
}

/// The Strehl ratio at `count` evenly spaced distances from `lo` to `hi` along the chief ray
/// (mm from where it leaves the last surface), summed on the traced rays themselves, with
/// the tilt fitted as for the best focus: the through-focus Strehl of `settings.rays_across`
/// rays across the pupil, with no resampling, that a best focus's finer sum is checked
/// against.
///
/// # Errors
/// As [`best_focus_with`]; also a range that is not finite and increasing, or fewer than 2
/// or more than 100 000 distances.
pub fn traced_strehl(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
    settings: &FocusSettings,
    (lo, hi, count): (f64, f64, usize),
) -> Result<Vec<f64>, OpticsError> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(OpticsError::input(
            "the through-focus range's end (mm)",
            hi,
            format!("must be finite and beyond its start {lo}"),
        ));
    }
    if !(2..=100_000).contains(&count) {
        return Err(OpticsError::input(
            "the through-focus distances",
            count as f64,
            "must be between 2 and 100000",
        ));
    }
    let w = wavefront(system, wavelength_nm, field_deg, pupil, settings)?;
    let model = StrehlModel::new(
        &w.samples,
        w.sampling,
        false,
        wavelength_nm,
        w.n_image,
        (lo, hi),
    )
    .ok_or_else(|| OpticsError::NoFocus {
        field_deg,
        wavelength_nm,
        reason: "the wavefront's tilt cannot be fitted".into(),
    })?;
    Ok(model.scan(lo, hi, count))
}

/// Coddington's sagittal and tangential foci by differential ray tracing along the chief ray
/// (distances from where it leaves the last surface, mm): an independent check of the
/// wavefront's foci. Needs homogeneous media.
pub fn coddington(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
) -> Result<(f64, f64), OpticsError> {
    let settings = FocusSettings::default();
    check_request(system, wavelength_nm, field_deg, pupil, &settings)?;
    let no_grin = || {
        OpticsError::input(
            "Coddington's equations",
            f64::NAN,
            "need homogeneous media (this system has a gradient-index medium)",
        )
    };
    if system.elements.iter().any(|e| e.medium.is_grin()) {
        return Err(no_grin());
    }
    if system.elements.iter().any(|e| e.surface.phase.is_some()) {
        return Err(OpticsError::input(
            "Coddington's equations",
            f64::NAN,
            "need refracting surfaces (this system wears a thin lens)",
        ));
    }
    let beam = Beam::new(
        system,
        wavelength_nm,
        field_deg,
        pupil.position,
        settings.grin,
    );
    let v = beam.chief()?;
    let tr = &beam.tracer;
    let mut ray = beam.ray(0.0, v);
    let fail = |surface: &str, failure: RayFailure| {
        beam.err(RayError {
            surface: surface.to_string(),
            failure,
        })
    };
    // Distances (along the chief ray) of the sagittal and tangential images behind the latest
    // surface; a distant object's are infinite.
    let (mut s_out, mut t_out) = (f64::INFINITY, f64::INFINITY);
    let mut prev: Option<Vec3> = None;
    let mut n1 = tr.n_object;
    for (i, element) in system.elements.iter().enumerate() {
        let surface = &element.surface;
        let (q, _) = surface
            .intersect(tr.vertices[i], ray.position, ray.direction)
            .map_err(|f| fail(&surface.name, f))?;
        let n2 = match &tr.media[i] {
            Resolved::Constant(n) => *n,
            Resolved::Grin(_) => return Err(no_grin()),
        };
        let normal = surface
            .normal(q)
            .ok_or_else(|| fail(&surface.name, RayFailure::Miss))?;
        let d_in = ray.direction;
        let d_out =
            crate::surface::refract(d_in, normal, n1, n2).map_err(|f| fail(&surface.name, f))?;
        let (s_in, t_in) = match prev {
            Some(p) => {
                let dist = (q - p).norm();
                (s_out - dist, t_out - dist)
            }
            None => (f64::INFINITY, f64::INFINITY),
        };
        let cos_i = normal.dot(d_in).abs();
        let cos_r = normal.dot(d_out).abs();
        let (ks, kt) = surface
            .principal_curvatures(q.rho())
            .ok_or_else(|| fail(&surface.name, RayFailure::Miss))?;
        let oblique = n2 * cos_r - n1 * cos_i;
        // n′/s′ = n/s + (n′cos I′ − n cos I) κₛ;  n′cos²I′/t′ = n cos²I/t + (n′cos I′ − n cos I) κₜ.
        let vs = if s_in.is_infinite() { 0.0 } else { n1 / s_in } + oblique * ks;
        let ut = if t_in.is_infinite() {
            0.0
        } else {
            n1 * cos_i * cos_i / t_in
        } + oblique * kt;
        s_out = n2 / vs;
        t_out = n2 * cos_r * cos_r / ut;
        prev = Some(q);
        n1 = n2;
        ray = Ray {
            position: q,
            direction: d_out,
            opl: 0.0,
        };
    }
    Ok((s_out, t_out))
}

/// A meridional fan of `rays` rays of the beam at `field_deg`, spread evenly across the pupil's
/// diameter (the chief ray in the middle when `rays` is odd), for figures: each ray's path in
/// the meridional plane as (z, y) points, from 1 mm in front of the corneal apex through every
/// surface (and the GRIN steps), continued straight in the image space to the plane
/// z = `end_z`.
pub fn ray_fan(
    system: &OpticalSystem,
    wavelength_nm: f64,
    field_deg: f64,
    pupil: &Pupil,
    rays: usize,
    end_z: f64,
) -> Result<Vec<Vec<(f64, f64)>>, OpticsError> {
    let settings = FocusSettings::default();
    check_request(system, wavelength_nm, field_deg, pupil, &settings)?;
    if !(1..=1000).contains(&rays) {
        return Err(OpticsError::input(
            "the rays of a fan",
            rays as f64,
            "must be between 1 and 1000",
        ));
    }
    if !(end_z > system.last_vertex() && end_z.is_finite()) {
        return Err(OpticsError::input(
            "the end of the fan (mm from the corneal apex)",
            end_z,
            "must lie behind the last surface",
        ));
    }
    let beam = Beam::new(
        system,
        wavelength_nm,
        field_deg,
        pupil.position,
        settings.grin,
    );
    let v_chief = beam.chief()?;
    let a = pupil.diameter / 2.0;
    let targets: Vec<(f64, f64)> = (0..rays)
        .map(|i| {
            let t = if rays == 1 {
                0.0
            } else {
                i as f64 / (rays - 1) as f64 * 2.0 - 1.0
            };
            (0.0, t * a)
        })
        .collect();
    let launches = beam.aim(v_chief, &targets)?;
    launches
        .iter()
        .map(|&(u, v)| {
            let mut ray = beam.ray(u, v);
            // Start the drawn path 1 mm in front of the apex.
            let t0 = (system.origin - 1.0 - ray.position.z) / ray.direction.z;
            ray.position += ray.direction * t0;
            let mut path = Vec::new();
            let end = beam
                .tracer
                .trace_surfaces(ray, system.elements.len(), Some(&mut path))
                .map_err(|e| beam.err(e))?;
            let t = (end_z - end.position.z) / end.direction.z;
            if t.is_finite() && t > 0.0 {
                path.push(end.position + end.direction * t);
            }
            Ok(path.iter().map(|p| (p.z, p.y)).collect())
        })
        .collect()
}
