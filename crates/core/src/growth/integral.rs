//! The integrated stimulus (docs/MODEL.md §6, "Growth rules"): the rule's drive averaged
//! over the retina's area from the pole out to the polar angle Φ (`stimulus.max_field`),
//!     S = ∫ drive dA / ∫ dA,   dA = 2π r ds on the retina,
//! which then drives every point: the periphery acts on the pole.
//!
//! The retina is the curve through the growth points in Σ order; both integrals are
//! trapezoidal in its arclength, the last piece cut where the curve crosses Φ (the point
//! and its drive interpolated linearly in φ along the chord), so that S moves continuously
//! as points cross Φ: no jump when the mesh moves under the region's edge. Its exact
//! partials in every point's (z, r, φ, drive) make the border row of IDA's Newton matrix.

/// One point of the retina as the integral reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RetinaPoint {
    pub z: f64,
    pub r: f64,
    pub angle: f64,
    pub drive: f64,
}

/// ∂S/∂(z, r, φ, drive) of one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partials {
    pub z: f64,
    pub r: f64,
    pub angle: f64,
    pub drive: f64,
}

/// S and, on request, its partials (indexed by point).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Integral {
    pub value: f64,
    /// The area ∫ dA / 2π the average is over (mm²).
    pub area: f64,
    pub partials: Vec<Partials>,
}

/// The trapezoid of one chord from a to b: (∫ r·f ds, ∫ r ds) with r and f linear along it,
/// and their partials in (z_a, r_a, f_a, z_b, r_b, f_b).
fn chord(a: (f64, f64, f64), b: (f64, f64, f64)) -> ([f64; 2], [[f64; 6]; 2]) {
    let (dz, dr) = (b.0 - a.0, b.1 - a.1);
    let ds = dz.hypot(dr);
    // ∫ r f ds over a linear chord, exactly: ds (2 r_a f_a + r_a f_b + r_b f_a + 2 r_b f_b) / 6.
    let q = (2.0 * a.1 * a.2 + a.1 * b.2 + b.1 * a.2 + 2.0 * b.1 * b.2) / 6.0;
    let m = 0.5 * (a.1 + b.1);
    let (ds_za, ds_ra) = if ds > 0.0 {
        (-dz / ds, -dr / ds)
    } else {
        (0.0, 0.0)
    };
    let num = [
        ds_za * q,
        ds_ra * q + ds * (2.0 * a.2 + b.2) / 6.0,
        ds * (2.0 * a.1 + b.1) / 6.0,
        -ds_za * q,
        -ds_ra * q + ds * (a.2 + 2.0 * b.2) / 6.0,
        ds * (a.1 + 2.0 * b.1) / 6.0,
    ];
    let den = [
        ds_za * m,
        ds_ra * m + 0.5 * ds,
        0.0,
        -ds_za * m,
        -ds_ra * m + 0.5 * ds,
        0.0,
    ];
    ([ds * q, ds * m], [num, den])
}

/// S over `points` taken in the order `order` (pole first) out to `max_angle`. None when no
/// area lies inside (the first point already beyond Φ, or a degenerate curve).
pub fn integrate(
    order: &[usize],
    points: &[RetinaPoint],
    max_angle: f64,
    partials: bool,
) -> Option<Integral> {
    let n = points.len();
    let (mut num, mut den) = (0.0, 0.0);
    // ∂num, ∂den per point in (z, r, φ, f).
    let mut d_num = vec![[0.0; 4]; if partials { n } else { 0 }];
    let mut d_den = vec![[0.0; 4]; if partials { n } else { 0 }];
    let first = *order.first()?;
    if !(points[first].angle < max_angle) {
        return None;
    }
    for w in order.windows(2) {
        let (ka, kb) = (w[0], w[1]);
        let (pa, pb) = (points[ka], points[kb]);
        let inside = pb.angle < max_angle;
        let (b, lam) = if inside {
            ((pb.z, pb.r, pb.drive), 1.0)
        } else {
            // Cut at Φ: λ = (Φ − φ_a)/(φ_b − φ_a) along the chord.
            let span = pb.angle - pa.angle;
            if !(span > 0.0) {
                break;
            }
            let lam = (max_angle - pa.angle) / span;
            (
                (
                    pa.z + lam * (pb.z - pa.z),
                    pa.r + lam * (pb.r - pa.r),
                    pa.drive + lam * (pb.drive - pa.drive),
                ),
                lam,
            )
        };
        let ([cn, cd], [gn, gd]) = chord((pa.z, pa.r, pa.drive), b);
        num += cn;
        den += cd;
        if partials {
            for (acc, g) in [(&mut d_num, gn), (&mut d_den, gd)] {
                // a's own (z, r, f); b's through the cut point, which moves with both ends
                // and, through λ, with both angles.
                acc[ka][0] += g[0];
                acc[ka][1] += g[1];
                acc[ka][3] += g[2];
                if inside {
                    acc[kb][0] += g[3];
                    acc[kb][1] += g[4];
                    acc[kb][3] += g[5];
                } else {
                    let span = pb.angle - pa.angle;
                    let d_lam_a = (lam - 1.0) / span;
                    let d_lam_b = -lam / span;
                    let (vz, vr, vf) = (pb.z - pa.z, pb.r - pa.r, pb.drive - pa.drive);
                    let along = g[3] * vz + g[4] * vr + g[5] * vf;
                    acc[ka][0] += (1.0 - lam) * g[3];
                    acc[ka][1] += (1.0 - lam) * g[4];
                    acc[ka][3] += (1.0 - lam) * g[5];
                    acc[kb][0] += lam * g[3];
                    acc[kb][1] += lam * g[4];
                    acc[kb][3] += lam * g[5];
                    acc[ka][2] += along * d_lam_a;
                    acc[kb][2] += along * d_lam_b;
                }
            }
        }
        if !inside {
            break;
        }
    }
    if !(den > 0.0) {
        return None;
    }
    let value = num / den;
    let partials = if partials {
        (0..n)
            .map(|k| {
                let g = |c: usize| (d_num[k][c] - value * d_den[k][c]) / den;
                Partials {
                    z: g(0),
                    r: g(1),
                    angle: g(2),
                    drive: g(3),
                }
            })
            .collect()
    } else {
        Vec::new()
    };
    Some(Integral {
        value,
        area: den,
        partials,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hemisphere of radius 11 about (0, 0) sampled at angles from the pole, with a drive
    /// of the angle.
    fn sphere(n: usize, drive: impl Fn(f64) -> f64) -> Vec<RetinaPoint> {
        (0..n)
            .map(|k| {
                let a = 0.04 * k as f64 + 0.013 * (k as f64).sin();
                RetinaPoint {
                    z: 11.0 * a.cos(),
                    r: 11.0 * a.sin(),
                    angle: a,
                    drive: drive(a),
                }
            })
            .collect()
    }

    /// On a sphere the area element is 2π R² sin φ dφ: a constant drive averages to itself,
    /// and a drive cos φ to the exact mean, at second order in the spacing.
    #[test]
    fn the_average_is_the_area_mean() {
        let order: Vec<usize> = (0..40).collect();
        let c = integrate(&order, &sphere(40, |_| 0.7), 0.5, false).unwrap();
        assert!((c.value - 0.7).abs() < 1e-14, "{}", c.value);
        // ∫₀^Φ cos φ sin φ dφ / ∫₀^Φ sin φ dφ = sin²Φ / (2 (1 − cos Φ)).
        let phi = 0.5f64;
        let exact = phi.sin().powi(2) / (2.0 * (1.0 - phi.cos()));
        let errs: Vec<f64> = [40, 80, 160]
            .iter()
            .map(|&n| {
                let pts: Vec<RetinaPoint> = (0..n)
                    .map(|k| {
                        let a = 0.8 * k as f64 / n as f64;
                        RetinaPoint {
                            z: 11.0 * a.cos(),
                            r: 11.0 * a.sin(),
                            angle: a,
                            drive: a.cos(),
                        }
                    })
                    .collect();
                let order: Vec<usize> = (0..n).collect();
                (integrate(&order, &pts, phi, false).unwrap().value - exact).abs()
            })
            .collect();
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!(order > 1.8, "{errs:?}");
        }
    }

    /// Every partial against central differences, with the region's edge inside a chord.
    #[test]
    fn the_partials_match_differences() {
        let pts = sphere(20, |a| 0.3 - a * a);
        let order: Vec<usize> = (0..20).collect();
        let phi = 0.37;
        let exact = integrate(&order, &pts, phi, true).unwrap();
        let h = 1e-7;
        for k in 0..12 {
            for c in 0..4 {
                let moved = |x: f64| {
                    let mut p = pts.clone();
                    match c {
                        0 => p[k].z += x,
                        1 => p[k].r += x,
                        2 => p[k].angle += x,
                        _ => p[k].drive += x,
                    }
                    integrate(&order, &p, phi, false).unwrap().value
                };
                let fd = (moved(h) - moved(-h)) / (2.0 * h);
                let an = [
                    exact.partials[k].z,
                    exact.partials[k].r,
                    exact.partials[k].angle,
                    exact.partials[k].drive,
                ][c];
                assert!(
                    (an - fd).abs() < 1e-7,
                    "point {k} coordinate {c}: {an} vs {fd}"
                );
            }
        }
        // Points beyond the cut do not enter.
        assert_eq!(exact.partials[15], Partials::default());
        // The first point beyond Φ: no area.
        assert!(integrate(&order, &pts, -1.0, false).is_none());
    }
}
