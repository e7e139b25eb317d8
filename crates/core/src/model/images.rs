//! Simultaneous images through a lens whose power changes across its face (docs/optics.md,
//! "Simultaneous images"; docs/MODEL.md §6 for the surfaces): a zoned or lenslet lens forms
//! one image per power, each with its best-focus surface and the share of the light it
//! carries at each field.
//!
//! A zone is a ring of a perfect lens of its own power about the common axis
//! (crates/optics/src/lens.rs), so the light through the zones of power P is the light of
//! the same eye wearing a uniform lens of power P, restricted to those zones. Each image is
//! traced so, over the whole pupil: its surface is smooth in the field angle (no zone edge
//! inside it), and where no ray of a field goes through P the image is still defined, with
//! share 0. Its share is the fraction of the entrance pupil whose rays cross the lens in
//! P's zones (`eyeshell_optics::entrance_area`), at the first wavelength.

use eyeshell_optics as optics;
use eyeshell_optics::{PolarSpline, Surfaces};

use super::eyewear::LensSpec;
use super::optics::{OpticsKeyError, OpticsSpec, Traced};
use crate::names::Quantity;
use crate::text::number;

/// The images of `spec`'s eye at growth time `t` through lens `i`, which forms one per power
/// of `powers`: each traced through the same lens of that power everywhere, its share from
/// the entrance pupil's area. The first three items are the image that carries the most
/// light on the axis (the first such on a tie).
pub(crate) fn trace_images(
    spec: &OpticsSpec,
    t: f64,
    z_c: f64,
    i: usize,
    powers: &[f64],
) -> Result<Traced, OpticsKeyError> {
    let lens = &spec.lenses[i];
    let mut traced = Vec::new();
    for &power in powers {
        let mut one = spec.clone();
        one.lenses[i] = lens.with_power(power);
        let blame = |e: OpticsKeyError| image_error(lens, i, power, &e);
        let (surfaces, blue, red) = one.compute_single(t, z_c).map_err(blame)?;
        traced.push((power, surfaces, blue, red));
    }
    // The light through each zone reaches the pupil as through a uniform lens of the zone's
    // own power (its carrier): each image's area sums its parts over the carriers.
    let fields: Vec<f64> = (traced[0].1.surfaces[0].points.iter())
        .map(|f| f.field_deg)
        .collect();
    let edges = lens.zone_edges();
    let mut areas = vec![vec![0.0; fields.len()]; powers.len()];
    for carrier in lens.carrier_powers() {
        let mut one = spec.clone();
        one.lenses[i] = lens.with_power(carrier);
        let blame = |e: OpticsKeyError| image_error(lens, i, carrier, &e);
        let system = super::eyewear::worn_at(&one, t).map_err(blame)?;
        let naked = one.system_at(t).map_err(blame)?;
        let surface = lens_surface(&one.lenses, i, system.elements.len() - naked.elements.len());
        let pupil = one.pupil_stop(&system);
        let probes: Vec<optics::Probe> = (fields.iter())
            .map(|&field_deg| optics::Probe {
                system: &system,
                pupil,
                wavelength_nm: spec.wavelengths[0],
                field_deg,
            })
            .collect();
        for (k, &power) in powers.iter().enumerate() {
            let weight = |h: f64| lens.share_at(h, carrier, power);
            let region = optics::Region {
                surface,
                edges: &edges,
                weight: &weight,
            };
            let area = optics::entrance_areas(&probes, &region, super::optics::run_grin())
                .map_err(|e| blame(one.explain_worn(&e)))?;
            for (total, a) in areas[k].iter_mut().zip(area) {
                *total += a;
            }
        }
    }
    let shares = shares_from_areas(&areas).ok_or_else(|| OpticsKeyError {
        key: format!("{}[{i}]", Quantity::Lenses),
        value: lens.describe(),
        problem: "lets no ray of some field through the pupil".into(),
    })?;
    let main = (0..shares.len()).fold(0, |best, k| {
        if shares[k][0] > shares[best][0] {
            k
        } else {
            best
        }
    });
    let phi = focus_angles(&traced[main].1.surfaces[0], z_c);
    let curves = ShareCurve::curves(&phi, &shares);
    let images: Vec<ComputedImage> = traced
        .iter()
        .zip(curves)
        .map(|((power, surfaces, blue, red), share)| ComputedImage {
            blue: blue.clone(),
            red: red.clone(),
            share,
            power: Some(*power),
            surfaces: surfaces.clone(),
        })
        .collect();
    let mut surfaces = images[main].surfaces.clone();
    surfaces.rays_traced = images.iter().map(|im| im.surfaces.rays_traced).sum();
    let (blue, red) = (images[main].blue.clone(), images[main].red.clone());
    Ok((surfaces, blue, red, images))
}

/// An image's failure as a problem with the lens item that gives its power, in one line.
fn image_error(lens: &LensSpec, i: usize, power: f64, e: &OpticsKeyError) -> OpticsKeyError {
    let mut problem = match e.problem.strip_prefix("form ") {
        Some(rest) => format!("forms {rest}"),
        None => format!("gives an image that cannot be traced: {}", e.problem),
    };
    if problem.chars().count() > 200 {
        problem = problem.chars().take(199).collect::<String>() + "…";
    }
    OpticsKeyError {
        key: format!("{}[{i}].{}", Quantity::Lenses, lens.power_item(power)),
        value: number(power),
        problem,
    }
}

/// The index of the surface that carries lens `i`'s profile in the eye wearing `lenses`
/// (`in_front` elements in front of the cornea): the anterior cornea for a contact lens;
/// for a spectacle lens, behind the elements of the spectacle lenses further from the eye
/// (`lens::wear` puts the nearest first, then each further one in front, equal vertices in
/// the order given).
fn lens_surface(lenses: &[LensSpec], i: usize, in_front: usize) -> usize {
    if lenses[i].kind == 1 {
        return in_front;
    }
    let count = |l: &LensSpec| match l.profile {
        super::eyewear::ProfileSpec::Real { .. } => 2,
        _ => 1,
    };
    (lenses.iter().enumerate())
        .filter(|(j, l)| {
            l.kind == 0 && (l.vertex > lenses[i].vertex || (l.vertex == lenses[i].vertex && *j > i))
        })
        .map(|(_, l)| count(l))
        .sum()
}

/// One image of the eye through its lenses: its best-focus surfaces at the first two
/// wavelengths (about the same centre as [`super::optics::ComputedOptics`]'s) and the share
/// of the light it carries at each point of the retina.
#[derive(Clone, Debug)]
pub struct ComputedImage {
    pub blue: PolarSpline,
    pub red: PolarSpline,
    pub share: ShareCurve,
    /// The power (D) of the lens's part this image's light goes through; `None` for the one
    /// image of a lens of one smooth profile (or no lens).
    pub power: Option<f64>,
    /// Every wavelength's surface of this image, as traced.
    pub surfaces: Surfaces,
}

/// An image's share of the light against the polar angle φ of a retina point (about the
/// surfaces' centre): a C¹ cubic Hermite curve through the shares at the traced fields,
/// constant beyond them. The shares of a lens's images sum to 1 at every φ: the last image's
/// curve is 1 minus the others' (values and slopes), the others are monotone between the
/// fields (Fritsch–Carlson slopes, zero at both ends), so each stays within its neighbours'
/// values.
#[derive(Clone, Debug, PartialEq)]
pub struct ShareCurve {
    phi: Vec<f64>,
    value: Vec<f64>,
    slope: Vec<f64>,
}

impl ShareCurve {
    /// The same share everywhere (1 for the only image).
    pub fn constant(share: f64) -> Self {
        ShareCurve {
            phi: vec![0.0],
            value: vec![share],
            slope: vec![0.0],
        }
    }

    /// The share at polar angle `phi` (rad).
    pub fn share(&self, phi: f64) -> f64 {
        self.share_and_slope(phi).0
    }

    /// The share at `phi` and its derivative in φ (zero beyond the traced range).
    pub fn share_and_slope(&self, phi: f64) -> (f64, f64) {
        let (x, y, m) = (&self.phi, &self.value, &self.slope);
        let n = x.len();
        if n == 1 || phi <= x[0] {
            return (y[0], 0.0);
        }
        if phi >= x[n - 1] {
            return (y[n - 1], 0.0);
        }
        let k = x.partition_point(|&p| p <= phi).clamp(1, n - 1) - 1;
        let dx = x[k + 1] - x[k];
        let s = (phi - x[k]) / dx;
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s),
            s * (1.0 - s) * (1.0 - s),
            s * s * (3.0 - 2.0 * s),
            s * s * (s - 1.0),
        );
        let (d00, d10, d01, d11) = (
            6.0 * s * (s - 1.0) / dx,
            (1.0 - s) * (1.0 - 3.0 * s),
            -6.0 * s * (s - 1.0) / dx,
            s * (3.0 * s - 2.0),
        );
        (
            h00 * y[k] + h10 * dx * m[k] + h01 * y[k + 1] + h11 * dx * m[k + 1],
            d00 * y[k] + d10 * m[k] + d01 * y[k + 1] + d11 * m[k + 1],
        )
    }

    /// The share traced at the `j`-th field (the last one's beyond them; a constant share
    /// at every field).
    pub fn traced(&self, j: usize) -> f64 {
        self.value[j.min(self.value.len() - 1)]
    }

    /// The traced points (φ, share).
    pub fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.phi.iter().copied().zip(self.value.iter().copied())
    }

    /// The curves of several images' shares at the same angles `phi` (increasing), each
    /// `shares[k][j]` the share of image k at `phi[j]` (summing to 1 over k).
    pub fn curves(phi: &[f64], shares: &[Vec<f64>]) -> Vec<ShareCurve> {
        let mut curves: Vec<ShareCurve> = shares
            .iter()
            .map(|v| ShareCurve {
                phi: phi.to_vec(),
                value: v.clone(),
                slope: monotone_slopes(phi, v),
            })
            .collect();
        if let Some((last, others)) = curves.split_last_mut() {
            if !others.is_empty() {
                for j in 0..phi.len() {
                    last.value[j] = 1.0 - others.iter().map(|c| c.value[j]).sum::<f64>();
                    last.slope[j] = -others.iter().map(|c| c.slope[j]).sum::<f64>();
                }
            }
        }
        curves
    }
}

/// Fritsch–Carlson slopes (harmonic mean of the neighbouring secants, zero at an extremum and
/// at both ends): a monotone C¹ cubic through the points.
fn monotone_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut m = vec![0.0; n];
    for k in 1..n.saturating_sub(1) {
        let d0 = (y[k] - y[k - 1]) / (x[k] - x[k - 1]);
        let d1 = (y[k + 1] - y[k]) / (x[k + 1] - x[k]);
        if d0 * d1 > 0.0 {
            let (h0, h1) = (x[k] - x[k - 1], x[k + 1] - x[k]);
            let (w1, w2) = (2.0 * h1 + h0, h1 + 2.0 * h0);
            m[k] = (w1 + w2) / (w1 / d0 + w2 / d1);
        }
    }
    m
}

/// The shares of the images at each field of `fields_deg`: `areas[k][j]`, the entrance-pupil
/// area of image k at field j, normalised over k; `None` if a field's total area is not
/// positive (no ray passes the pupil).
pub fn shares_from_areas(areas: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let fields = areas.first().map_or(0, Vec::len);
    let mut shares = vec![vec![0.0; fields]; areas.len()];
    for j in 0..fields {
        let total: f64 = areas.iter().map(|a| a[j]).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        for (k, a) in areas.iter().enumerate() {
            shares[k][j] = a[j] / total;
        }
    }
    Some(shares)
}

/// The polar angle about `z_c` of each focus of a surface, in field order.
pub fn focus_angles(surface: &optics::FocusSurface, z_c: f64) -> Vec<f64> {
    surface
        .points
        .iter()
        .map(|f| f.r.atan2(f.z - z_c))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::eyewear::ProfileSpec;
    use super::*;
    use optics::{OpticalSystem, Ray, Tracer, Vec3};

    /// The paper's polar centre z_B (docs/MODEL.md §6).
    const Z_C: f64 = -0.5065;

    fn contact(zones: &[(f64, f64)]) -> OpticsSpec {
        OpticsSpec {
            lenses: vec![LensSpec {
                kind: 1,
                vertex: 12.0,
                profile: ProfileSpec::Zones(zones.to_vec()),
                lenslets: vec![],
                prescribe: None,
            }],
            ..OpticsSpec::default()
        }
    }

    /// The share of the light through `power` by brute force: a 600 × 300 grid over the half
    /// of the incoming beam x > 0 (normal to it), each ray traced to the stop through the
    /// lens of that power, its height on the cornea read where it meets it.
    fn counted_area(spec: &OpticsSpec, power: f64, field_deg: f64) -> f64 {
        let mut one = spec.clone();
        one.lenses[0] = spec.lenses[0].with_power(power);
        let system: OpticalSystem = super::super::eyewear::worn(&one).unwrap();
        let pupil = one.pupil_stop(&system);
        let tracer = Tracer::new(
            &system,
            spec.wavelengths[0],
            optics::GrinSettings::default(),
        );
        let th = field_deg.to_radians();
        let d = Vec3::new(0.0, th.sin(), th.cos());
        let e2 = Vec3::new(0.0, th.cos(), -th.sin());
        let back = 30.0 / th.cos();
        let ray = |u: f64, v: f64| Ray {
            position: Vec3::new(u, 0.0, 0.0) + e2 * v - d * back,
            direction: d,
            opl: 0.0,
        };
        let passes = |u: f64, v: f64| {
            tracer
                .trace_to_plane(ray(u, v), pupil.position, "pupil")
                .is_ok_and(|r| r.position.x.hypot(r.position.y) <= pupil.diameter / 2.0)
        };
        // The beam's centre: the middle of the passing stretch of u = 0.
        let vs: Vec<f64> = (0..4000)
            .map(|i| -20.0 + 40.0 * i as f64 / 4000.0)
            .filter(|&v| passes(0.0, v))
            .collect();
        let centre = 0.5 * (vs[0] + vs[vs.len() - 1]);
        let (n, half) = (600, 2.5);
        let cell = 2.0 * half / n as f64;
        let mut area = 0.0;
        for i in 0..n / 2 {
            for j in 0..n {
                let u = (i as f64 + 0.5) * cell;
                let v = centre - half + (j as f64 + 0.5) * cell;
                if passes(u, v) {
                    let h = tracer
                        .trace_surfaces(ray(u, v), 1, None)
                        .unwrap()
                        .position
                        .rho();
                    area += spec.lenses[0].share_at(h, power, power) * cell * cell;
                }
            }
        }
        2.0 * area
    }

    #[test]
    fn a_dual_focus_contact_gives_two_images_with_the_zones_shares_and_the_single_lenses_foci() {
        let spec = contact(&[(1.0, -2.0), (1.6, 0.0), (2.3, -2.0), (7.0, 0.0)]);
        let c = spec.compute(Z_C).unwrap();
        assert_eq!(c.images.len(), 2);
        assert_eq!(
            c.images.iter().map(|i| i.power).collect::<Vec<_>>(),
            [Some(-2.0), Some(0.0)]
        );
        for field in [0.0, 10.0, 20.0] {
            let j = field as usize;
            let counted: Vec<f64> = [-2.0, 0.0]
                .iter()
                .map(|&p| counted_area(&spec, p, field))
                .collect();
            let total: f64 = counted.iter().sum();
            let shares: Vec<f64> = c.images.iter().map(|i| i.share.traced(j)).collect();
            assert!((shares.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for (k, share) in shares.iter().enumerate() {
                let expected = counted[k] / total;
                eprintln!("image {k} at {field}°: share {share:.5}, counted {expected:.5}");
                assert!(
                    (share - expected).abs() < 0.01 && *share > 0.1,
                    "image {k} at {field}°: share {share}, counted {expected}"
                );
            }
            // Summing to 1 between the traced fields too.
            let phi = focus_angles(&c.surfaces.surfaces[0], Z_C)[j] + 0.003;
            let sum: f64 = c.images.iter().map(|i| i.share.share(phi)).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{sum}");
        }
        // On the axis the 0 D rings (1 to 1.6 mm) hold more of the ~1.69 mm beam than the
        // -2 D centre and ring: the 0 D image is the paper's rule's.
        assert!(c.images[1].share.traced(0) > 0.5);
        assert_eq!(c.blue.radius(0.0), c.images[1].blue.radius(0.0));
        for (k, power) in [-2.0, 0.0].into_iter().enumerate() {
            let mut single = spec.clone();
            single.lenses[0].profile = ProfileSpec::Power(power);
            let s = single.compute(Z_C).unwrap();
            assert_eq!(s.images.len(), 1);
            assert_eq!(s.images[0].blue.radius(0.0), s.blue.radius(0.0));
            for w in 0..2 {
                let (a, b) = (
                    c.images[k].surfaces.surfaces[w].points[0].z,
                    s.surfaces.surfaces[w].points[0].z,
                );
                assert!(
                    (a - b).abs() < 0.01,
                    "image {k}, wavelength {w}: {a} against {b}"
                );
            }
        }
        // The two images' axial foci differ as the two powers do (about 0.68 mm for 2 D).
        let dz = c.images[0].surfaces.surfaces[0].points[0].z
            - c.images[1].surfaces.surfaces[0].points[0].z;
        assert!((0.5..0.9).contains(&dz), "{dz}");
    }

    #[test]
    fn shares_sum_to_one_are_c1_and_constant_beyond_the_fields() {
        let phi = [0.0, 0.1, 0.2, 0.3, 0.4];
        let a = vec![0.2, 0.25, 0.6, 1.0, 1.0];
        let b: Vec<f64> = a.iter().map(|x| 1.0 - x).collect();
        let c = ShareCurve::curves(&phi, &[a, b]);
        for i in 0..=500 {
            let p = -0.1 + 0.6 * i as f64 / 500.0;
            let (s0, d0) = c[0].share_and_slope(p);
            let (s1, d1) = c[1].share_and_slope(p);
            assert!((s0 + s1 - 1.0).abs() < 1e-14, "sum {} at {p}", s0 + s1);
            assert!((d0 + d1).abs() < 1e-12);
            assert!((-1e-12..=1.0 + 1e-12).contains(&s0), "{s0} at {p}");
            // The slope against a central difference of the share.
            let h = 1e-6;
            let fd = (c[0].share(p + h) - c[0].share(p - h)) / (2.0 * h);
            assert!((fd - d0).abs() < 1e-4, "slope {d0} against {fd} at {p}");
        }
        assert_eq!(c[0].share_and_slope(0.7), (1.0, 0.0));
        assert_eq!(c[0].share(-0.3), 0.2);
        // C¹ at a node: the slopes from both sides agree.
        let (l, r) = (
            c[0].share_and_slope(0.2 - 1e-9).1,
            c[0].share_and_slope(0.2 + 1e-9).1,
        );
        assert!((l - r).abs() < 1e-6, "{l} {r}");
    }
}
