//! The light each image of a multifocal lens carries (docs/optics.md, "Simultaneous images").
//!
//! A lens whose power changes across its face (concentric zones, a ring of lenslets) sends
//! each ray of a field's pencil through one power, so the pencil forms one image per power.
//! The share of the light an image carries is the fraction of the entrance pupil (the
//! incoming beam's cross-section whose rays pass the stop) whose rays cross the lens where it
//! has that power. The rays through a zone of power P are the rays of a uniform lens of power
//! P (a zone is a ring of such a lens), so the share of P is measured on the eye wearing the
//! uniform lens: the part of its entrance pupil whose rays cross the lens in P's zones.
//!
//! The area is integrated in polar form about the chief ray's launch point: along each of
//! [`SPOKES`] evenly spaced spokes the pupil's edge is found by bisection and the zone edges
//! (where the lens height crosses a zone radius) by bisection between samples, so the area
//! is exact along each spoke and the spokes' midpoint rule converges fast in angle.

use crate::error::OpticsError;
use crate::focus::{check_request, Beam, FocusSettings, Probe};
use crate::trace::GrinSettings;

/// Spokes of the polar integration over the entrance pupil (half of them traced: the beam
/// is symmetric under x → −x).
pub const SPOKES: usize = 64;
/// Lens heights sampled along a spoke to find the zone edges it crosses.
const SAMPLES: usize = 48;
/// Bisection steps for an edge (the pupil's, a zone's): 2⁻⁴⁰ of the bracket.
const BISECTIONS: usize = 40;

/// Where on a lens an image's light goes through: `weight(h)` is the fraction of the light
/// crossing surface `surface` at height h (mm from the axis) that forms the image (1 or 0 for
/// zones, a lenslet ring's fill), piecewise constant between the radii `edges`.
pub struct Region<'a> {
    /// The index of the surface that carries the lens's profile in the probe's system.
    pub surface: usize,
    pub edges: &'a [f64],
    pub weight: &'a (dyn Fn(f64) -> f64 + Sync),
}

/// The entrance pupil's area (mm², in the plane normal to the beam) of the probe's system at
/// its field and wavelength, each part weighted by the region's weight at the height where its
/// ray crosses the lens. With weight 1 everywhere it is the whole entrance pupil's area.
///
/// # Errors
/// The probe's request is invalid, or its chief ray or the pupil's edge cannot be traced.
pub fn entrance_area(
    probe: &Probe,
    region: &Region,
    grin: GrinSettings,
) -> Result<f64, OpticsError> {
    let settings = FocusSettings {
        rays_across: 16,
        grin,
    };
    check_request(
        probe.system,
        probe.wavelength_nm,
        probe.field_deg,
        &probe.pupil,
        &settings,
    )?;
    if region.surface >= probe.system.elements.len() {
        return Err(OpticsError::input(
            "the lens's surface index",
            region.surface as f64,
            "must name a surface of the system",
        ));
    }
    let beam = Beam::new(
        probe.system,
        probe.wavelength_nm,
        probe.field_deg,
        probe.pupil.position,
        grin,
    );
    let v_chief = beam.chief()?;
    let a = probe.pupil.diameter / 2.0;
    // Beyond the stop's rim, or a ray that does not reach it: outside the pupil.
    let outside = |u: f64, v: f64| beam.at_stop(u, v).map_or(true, |(x, y)| x.hypot(y) > a);
    let height = |u: f64, v: f64| {
        beam.tracer
            .trace_surfaces(beam.ray(u, v), region.surface + 1, None)
            .map_or(f64::INFINITY, |r| r.position.rho())
    };
    let mut total = 0.0;
    for j in 0..SPOKES / 2 {
        // Spokes at ψ = 2π(j + ½)/SPOKES with cos ψ > 0; their mirror images ψ → π − ψ give
        // the same area.
        let psi = std::f64::consts::PI * ((j as f64 + 0.5) * 2.0 / SPOKES as f64 - 0.5);
        let (s, c) = psi.sin_cos();
        let at = |rho: f64| (rho * c, v_chief + rho * s);
        let edge = pupil_edge(
            &|rho| {
                let (u, v) = at(rho);
                outside(u, v)
            },
            a,
        )
        .ok_or_else(|| OpticsError::NoFocus {
            field_deg: probe.field_deg,
            wavelength_nm: probe.wavelength_nm,
            reason: "the pupil's edge cannot be found in the incoming beam".into(),
        })?;
        let h = |rho: f64| {
            let (u, v) = at(rho);
            height(u, v)
        };
        total += spoke_area(&h, edge, region);
    }
    Ok(total * 2.0 * std::f64::consts::TAU / SPOKES as f64)
}

/// The distance along a spoke at which the beam leaves the pupil (`outside` turns true),
/// bracketed by doubling from the stop's radius `a`.
fn pupil_edge(outside: &dyn Fn(f64) -> bool, a: f64) -> Option<f64> {
    let (mut lo, mut hi) = (0.0, a);
    while !outside(hi) {
        lo = hi;
        hi *= 2.0;
        if hi > 1e3 * a {
            return None;
        }
    }
    for _ in 0..BISECTIONS {
        let m = 0.5 * (lo + hi);
        if outside(m) {
            hi = m;
        } else {
            lo = m;
        }
    }
    Some(0.5 * (lo + hi))
}

/// ∫₀^edge weight(h(ρ)) ρ dρ along one spoke: exact between the zone edges it crosses.
fn spoke_area(h: &dyn Fn(f64) -> f64, edge: f64, region: &Region) -> f64 {
    let rho: Vec<f64> = (0..=SAMPLES)
        .map(|i| edge * i as f64 / SAMPLES as f64)
        .collect();
    let hs: Vec<f64> = rho.iter().map(|&r| h(r)).collect();
    let mut cuts = vec![0.0, edge];
    for i in 0..SAMPLES {
        for &r_edge in region.edges {
            let (fa, fb) = (hs[i] - r_edge, hs[i + 1] - r_edge);
            if fa * fb < 0.0 {
                let (mut lo, mut hi) = (rho[i], rho[i + 1]);
                for _ in 0..BISECTIONS {
                    let m = 0.5 * (lo + hi);
                    if (h(m) - r_edge) * fa > 0.0 {
                        lo = m;
                    } else {
                        hi = m;
                    }
                }
                cuts.push(0.5 * (lo + hi));
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2)
        .map(|w| (region.weight)(h(0.5 * (w[0] + w[1]))) * 0.5 * (w[1] * w[1] - w[0] * w[0]))
        .sum()
}

/// [`entrance_area`] of each probe, in parallel; the first failure in the probes' order is
/// the error, so it does not depend on the thread schedule.
///
/// # Errors
/// As [`entrance_area`], for the first probe that fails.
pub fn entrance_areas(
    probes: &[Probe],
    region: &Region,
    grin: GrinSettings,
) -> Result<Vec<f64>, OpticsError> {
    use rayon::prelude::*;
    probes
        .par_iter()
        .map(|p| entrance_area(p, region, grin))
        .collect::<Vec<_>>()
        .into_iter()
        .collect()
}
