//! The Strehl ratio through focus (docs/optics.md, "Best focus"; the paper's criterion of
//! docs/MODEL.md §6), summed on a sampling of the pupil fine enough for the wavefront's
//! aberration.
//!
//! Along the chief ray the aberration is W(s) = r₀ + s n′ r₁, with r₀ and r₁ the residuals of
//! each ray's phase Φ(Q) and of ψ = d·d꜀ after their piston and tilt, fitted by least squares
//! weighted by the pupil's area (the weights of the Strehl sum itself: the tilt removed is the
//! one that maximises the sum for a small aberration), and S(s) = |Σ wᵢ exp(i k Wᵢ(s))|².
//!
//! The sum is a quadrature of exp(i k W) over the pupil, and it aliases once the phase turns
//! by more than about π between neighbouring samples: an astigmatic W = (P/2) cos 2θ at the
//! rim (P the peak-to-valley in waves) holds the angular modes of exp(i π P cos 2θ) up to
//! about 2πP, so the pupil's 2 × rays_across spokes need rays_across > πP (the Bessel
//! coefficients J_m(πP) die out beyond m ≈ πP), and its Gauss–Legendre rings in r² need
//! fewer. Where the traced rays are too few for the peak-to-valley over the distances
//! scanned, the residuals are fitted by Zernike polynomials (even in the sagittal x, as the
//! beam is) from the traced rays and the sum is taken on a finer sampling of the same kind:
//! the rings and spokes integrate the products of the fitted terms exactly, so the fit is
//! the wavefront's projection onto them, and the wavefront of a smooth eye is far smoother
//! than its phasor. A lens whose power changes across its face makes W jump at its zone
//! edges, which no polynomial follows: it is summed on the traced rays alone.

use crate::linalg;
use crate::sampling::Sampling;

/// Rays across the pupil per wave of peak-to-valley aberration, and a floor added: πP with a
/// quarter's margin, and 8 for the Bessel tail's m^(1/3) width at small P.
const RAYS_PER_WAVE: f64 = 4.0;
const RAYS_MARGIN: f64 = 8.0;
/// The finest sampling the Strehl sum is taken on (rays across).
const MAX_SUM_RAYS: usize = 1024;
/// The highest Zernike degree fitted to the traced rays: the rings of 16 rays across
/// integrate the products of terms to degree 15 exactly, and a degree of 10 leaves the
/// wavefront's content up to degree 20 out of the fitted coefficients (no aliasing).
const MAX_DEGREE: usize = 10;

/// The lowest Zernike degree a resampling is fitted with: a fit of degree 3 (4 rays across)
/// leaves out the eye's spherical aberration (the Atchison eye's Strehl ratio on the axis
/// with a 3 mm pupil reads 1.0000 for 0.9556), one of degree 5 (6 rays across) puts the
/// Strehl focus within 7e-4 mm of the converged one at 0–40° with 3 and 4 mm pupils. Fewer
/// rays are summed as traced.
const MIN_DEGREE: usize = 5;

/// One traced ray of a field's pencil.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PupilRay {
    /// Where it crosses the stop (x sagittal, y tangential, mm).
    pub(crate) stop: (f64, f64),
    /// Its direction's components across the chief ray (sagittal, tangential).
    pub(crate) alpha: (f64, f64),
    /// Φ(Q): its phase at the chief ray's exit point (mm of optical path).
    pub(crate) phase: f64,
    /// ψ = d·d꜀: the change of its phase per unit distance along the chief ray, over n′.
    pub(crate) psi: f64,
    /// Its share of the pupil's area.
    pub(crate) weight: f64,
}

/// The highest Zernike degree whose terms' products the rings and spokes of `sampling`
/// integrate exactly (Gauss–Legendre in r² to degree 2·rings − 1, spokes to mode
/// spokes − 1), at most [`MAX_DEGREE`].
fn degree(sampling: &Sampling) -> usize {
    (2 * sampling.ring_count() - 1)
        .min(sampling.spoke_count() / 2 - 1)
        .min(MAX_DEGREE)
}

/// The Strehl ratio along the chief ray: S(s) = |Σ wᵢ exp(i k (r₀ᵢ + s n′ r₁ᵢ))|², the
/// weights summing to 1.
pub(crate) struct StrehlModel {
    k: f64,
    n: f64,
    r0: Vec<f64>,
    r1: Vec<f64>,
    w: Vec<f64>,
    /// Rays across the pupil the sum is taken on.
    pub(crate) rays_across: usize,
}

impl StrehlModel {
    /// The model of the pencil `rays` (sampled as `sampling`) for distances in [lo, hi]:
    /// summed on the traced rays where they resolve the phase there, else on a resampling of
    /// the Zernike fit when `resample` (a smooth wavefront). `None` when the tilt cannot be
    /// fitted.
    pub(crate) fn new(
        rays: &[PupilRay],
        sampling: Sampling,
        resample: bool,
        wavelength_nm: f64,
        n: f64,
        (lo, hi): (f64, f64),
    ) -> Option<Self> {
        let lambda = wavelength_nm * 1e-6;
        let k = 2.0 * std::f64::consts::PI / lambda;
        let (r0, r1) = tilt_residuals(rays)?;
        let total: f64 = rays.iter().map(|r| r.weight).sum();
        if !(total > 0.0) {
            return None;
        }
        let waves = peak_to_valley(&r0, &r1, n, lo).max(peak_to_valley(&r0, &r1, n, hi)) / lambda;
        let needed = rays_for_waves(waves);
        if needed <= sampling.rays_across || !resample || degree(&sampling) < MIN_DEGREE {
            return Some(Self {
                k,
                n,
                r0,
                r1,
                w: rays.iter().map(|r| r.weight / total).collect(),
                rays_across: sampling.rays_across,
            });
        }
        let fine = Sampling {
            radius: sampling.radius,
            rays_across: needed,
        };
        let basis = Zernike::new(degree(&sampling));
        let (c0, c1) = basis.fit(rays, (&r0, &r1), sampling.radius)?;
        let (r0, r1, w) = basis.resample(&c0, &c1, fine);
        Some(Self {
            k,
            n,
            r0,
            r1,
            w,
            rays_across: needed,
        })
    }

    pub(crate) fn at(&self, s: f64) -> f64 {
        let (mut re, mut im) = (0.0, 0.0);
        for ((a, b), w) in self.r0.iter().zip(&self.r1).zip(&self.w) {
            let (sn, cs) = (self.k * (a + s * self.n * b)).sin_cos();
            re += w * cs;
            im += w * sn;
        }
        re * re + im * im
    }

    /// S at `count` evenly spaced distances from `lo` to `hi`: each ray's phasor is advanced by
    /// a fixed rotation per step, so the scan costs one complex product per ray and point
    /// instead of a sine and cosine.
    pub(crate) fn scan(&self, lo: f64, hi: f64, count: usize) -> Vec<f64> {
        let h = (hi - lo) / (count - 1) as f64;
        let (k, n) = (self.k, self.n);
        let mut z: Vec<(f64, f64)> = self
            .r0
            .iter()
            .zip(&self.r1)
            .map(|(a, b)| {
                let (s, c) = (k * (a + lo * n * b)).sin_cos();
                (c, s)
            })
            .collect();
        let rot: Vec<(f64, f64)> = self
            .r1
            .iter()
            .map(|b| {
                let (s, c) = (k * h * n * b).sin_cos();
                (c, s)
            })
            .collect();
        (0..count)
            .map(|_| {
                let (mut re, mut im) = (0.0, 0.0);
                for ((zi, ri), a) in z.iter_mut().zip(&rot).zip(&self.w) {
                    re += a * zi.0;
                    im += a * zi.1;
                    *zi = (zi.0 * ri.0 - zi.1 * ri.1, zi.0 * ri.1 + zi.1 * ri.0);
                }
                re * re + im * im
            })
            .collect()
    }
    /// The largest S on [lo, hi]: the best of `count` evenly spaced distances, refined by
    /// Newton's method on S′ = 0 within a scan step of it (S, S′ and S″ from one pass over
    /// the rays, a few passes where golden-section search takes some 35), or by golden-section
    /// search where S is not concave there.
    pub(crate) fn maximum(&self, lo: f64, hi: f64, count: usize) -> (f64, f64) {
        let scan = self.scan(lo, hi, count);
        let h = (hi - lo) / (count - 1) as f64;
        let (mut best, mut fbest) = (lo, f64::NEG_INFINITY);
        for (i, &v) in scan.iter().enumerate() {
            if v > fbest {
                best = lo + i as f64 * h;
                fbest = v;
            }
        }
        let mut s = best;
        for _ in 0..30 {
            let (_, d1, d2) = self.derivatives(s);
            if !(d2 < 0.0) {
                break;
            }
            let step = -d1 / d2;
            s += step;
            if !((s - best).abs() <= h) {
                break;
            }
            if step.abs() < 1e-10 {
                let v = self.at(s);
                return if v >= fbest { (s, v) } else { (best, fbest) };
            }
        }
        golden_section(|s| self.at(s), lo, hi, &scan)
    }

    /// S(s), S′(s) and S″(s): with φᵢ = k Wᵢ(s), gᵢ = k n′ r₁ᵢ and F = Σ wᵢ exp(i φᵢ),
    /// F′ = Σ wᵢ i gᵢ exp(i φᵢ), F″ = −Σ wᵢ gᵢ² exp(i φᵢ): S = |F|², S′ = 2 Re(F̄ F′),
    /// S″ = 2 (|F′|² + Re(F̄ F″)).
    fn derivatives(&self, s: f64) -> (f64, f64, f64) {
        let (mut f, mut f1, mut f2) = ((0.0, 0.0), (0.0, 0.0), (0.0, 0.0));
        for ((a, b), w) in self.r0.iter().zip(&self.r1).zip(&self.w) {
            let (sn, cs) = (self.k * (a + s * self.n * b)).sin_cos();
            let g = self.k * self.n * b;
            f.0 += w * cs;
            f.1 += w * sn;
            f1.0 -= w * g * sn;
            f1.1 += w * g * cs;
            f2.0 -= w * g * g * cs;
            f2.1 -= w * g * g * sn;
        }
        let value = f.0 * f.0 + f.1 * f.1;
        let d1 = 2.0 * (f.0 * f1.0 + f.1 * f1.1);
        let d2 = 2.0 * (f1.0 * f1.0 + f1.1 * f1.1 + f.0 * f2.0 + f.1 * f2.1);
        (value, d1, d2)
    }
}

/// Maximises `f` on [lo, hi] given its values `scan` at evenly spaced points: golden-section
/// search around the best of them.
fn golden_section(f: impl Fn(f64) -> f64, lo: f64, hi: f64, scan: &[f64]) -> (f64, f64) {
    let h = (hi - lo) / (scan.len() - 1) as f64;
    let (mut best, mut fbest) = (lo, f64::NEG_INFINITY);
    for (i, &v) in scan.iter().enumerate() {
        if v > fbest {
            best = lo + i as f64 * h;
            fbest = v;
        }
    }
    let (mut a, mut b) = (best - h, best + h);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    while (b - a).abs() > 1e-8 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    let x = (a + b) / 2.0;
    let fx = f(x);
    if fx >= fbest {
        (x, fx)
    } else {
        (best, fbest)
    }
}

/// Rays across the pupil that resolve a phase of `waves` peak-to-valley (module comment),
/// a multiple of 4, at most [`MAX_SUM_RAYS`].
pub(crate) fn rays_for_waves(waves: f64) -> usize {
    let n = (RAYS_PER_WAVE * waves + RAYS_MARGIN).ceil();
    if !(n < MAX_SUM_RAYS as f64) {
        return MAX_SUM_RAYS;
    }
    (n as usize).div_ceil(4) * 4
}

/// The peak-to-valley of W(s) = r₀ + s n′ r₁ over the rays (mm of optical path).
fn peak_to_valley(r0: &[f64], r1: &[f64], n: f64, s: f64) -> f64 {
    let (lo, hi) = r0
        .iter()
        .zip(r1)
        .map(|(a, b)| a + s * n * b)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), w| {
            (lo.min(w), hi.max(w))
        });
    hi - lo
}

/// The residuals of Φ(Q) and of ψ after their piston and tilt (1, αₓ, α_y), fitted by least
/// squares weighted by the rays' shares of the pupil.
fn tilt_residuals(rays: &[PupilRay]) -> Option<(Vec<f64>, Vec<f64>)> {
    let a = rays
        .iter()
        .map(|r| r.alpha.0.hypot(r.alpha.1))
        .fold(0.0, f64::max)
        .max(1e-300);
    let rows: Vec<[f64; 3]> = rays
        .iter()
        .map(|r| {
            let w = r.weight.sqrt();
            [w, w * r.alpha.0 / a, w * r.alpha.1 / a]
        })
        .collect();
    let resid = |value: &dyn Fn(&PupilRay) -> f64| -> Option<Vec<f64>> {
        let rhs: Vec<f64> = rays.iter().map(|r| r.weight.sqrt() * value(r)).collect();
        let c = linalg::least_squares::<3>(&rows, &rhs)?;
        Some(
            rays.iter()
                .map(|r| value(r) - (c[0] + (c[1] * r.alpha.0 + c[2] * r.alpha.1) / a))
                .collect(),
        )
    };
    Some((resid(&|r| r.phase)?, resid(&|r| r.psi)?))
}

/// Zernike polynomials R_n^m(ρ) cos(m θ) to degree `degree`, θ measured from the tangential
/// (y) axis: the terms even in the sagittal x, the span of a pencil of a centred system.
struct Zernike {
    degree: usize,
    /// (n, m) of each term.
    terms: Vec<(usize, usize)>,
    /// Each term's R_n^m as (power of ρ, coefficient) pairs.
    radial: Vec<Vec<(usize, f64)>>,
}

impl Zernike {
    fn new(degree: usize) -> Self {
        let terms: Vec<(usize, usize)> = (0..=degree)
            .flat_map(|n| (n % 2..=n).step_by(2).map(move |m| (n, m)))
            .collect();
        let radial = terms
            .iter()
            .map(|&(n, m)| Self::coefficients(n, m))
            .collect();
        Self {
            degree,
            terms,
            radial,
        }
    }

    /// R_n^m(ρ) = Σₖ (−1)ᵏ (n − k)! / (k! ((n + m)/2 − k)! ((n − m)/2 − k)!) ρ^(n − 2k).
    fn coefficients(n: usize, m: usize) -> Vec<(usize, f64)> {
        let fact = |j: usize| (1..=j).map(|i| i as f64).product::<f64>();
        (0..=(n - m) / 2)
            .map(|k| {
                let c = fact(n - k) / (fact(k) * fact((n + m) / 2 - k) * fact((n - m) / 2 - k));
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                (n - 2 * k, sign * c)
            })
            .collect()
    }

    /// Every term's R_n^m(ρ).
    fn radial_at(&self, rho: f64) -> Vec<f64> {
        let mut powers = vec![1.0; self.degree + 1];
        for p in 1..=self.degree {
            powers[p] = powers[p - 1] * rho;
        }
        self.radial
            .iter()
            .map(|c| c.iter().map(|&(p, a)| a * powers[p]).sum())
            .collect()
    }

    /// Every term's cos(m θ) at the angle θ from the y axis with cos θ = `c`: Chebyshev's
    /// T_m(c) by its recurrence.
    fn angular_at(&self, c: f64) -> Vec<f64> {
        let mut t = vec![1.0; self.degree + 1];
        if self.degree > 0 {
            t[1] = c;
        }
        for m in 2..=self.degree {
            t[m] = 2.0 * c * t[m - 1] - t[m - 2];
        }
        self.terms.iter().map(|&(_, m)| t[m]).collect()
    }

    fn values(&self, x: f64, y: f64, radius: f64) -> Vec<f64> {
        let r = x.hypot(y);
        let cos = if r > 0.0 { y / r } else { 1.0 };
        self.radial_at(r / radius)
            .into_iter()
            .zip(self.angular_at(cos))
            .map(|(a, b)| a * b)
            .collect()
    }

    /// The coefficients of r₀ and of r₁ at the rays by least squares weighted by their
    /// shares, on the half x > 0: the other half mirrors it, with the same values of these
    /// terms and of W, so it adds the same normal equations again.
    fn fit(
        &self,
        rays: &[PupilRay],
        (r0, r1): (&[f64], &[f64]),
        radius: f64,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let half: Vec<usize> = (0..rays.len()).filter(|&i| rays[i].stop.0 > 0.0).collect();
        let rows: Vec<Vec<f64>> = half
            .iter()
            .map(|&i| {
                let (r, w) = (&rays[i], rays[i].weight.sqrt());
                self.values(r.stop.0, r.stop.1, radius)
                    .into_iter()
                    .map(|z| w * z)
                    .collect()
            })
            .collect();
        let rhs = |v: &[f64]| -> Vec<f64> {
            half.iter().map(|&i| rays[i].weight.sqrt() * v[i]).collect()
        };
        let [c0, c1] = linalg::least_squares_dyn(&rows, [&rhs(r0), &rhs(r1)])?;
        Some((c0, c1))
    }

    /// The fitted r₀ and r₁ on the half pupil x > 0 of `sampling`, with the weights of both
    /// halves (the mirror image of a point has the same W): each term is its radial factor
    /// on a ring times its angular factor on a spoke.
    fn resample(
        &self,
        c0: &[f64],
        c1: &[f64],
        sampling: Sampling,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let rings = sampling.rings();
        let spokes: Vec<f64> = sampling
            .spokes()
            .into_iter()
            .filter(|th| th.cos() > 0.0)
            .collect();
        // cos of the angle from the tangential y axis of the spoke's point (cos θ, sin θ).
        let angular: Vec<Vec<f64>> = spokes.iter().map(|th| self.angular_at(th.sin())).collect();
        let total: f64 = rings.iter().map(|r| r.1).sum::<f64>() * spokes.len() as f64;
        let count = rings.len() * spokes.len();
        let (mut r0, mut r1, mut w) = (
            Vec::with_capacity(count),
            Vec::with_capacity(count),
            Vec::with_capacity(count),
        );
        for &(r, weight) in &rings {
            let rho = r / sampling.radius;
            let radial: Vec<(f64, f64)> = self
                .radial_at(rho)
                .into_iter()
                .zip(c0.iter().zip(c1))
                .map(|(z, (a, b))| (a * z, b * z))
                .collect();
            for ang in &angular {
                let (mut v0, mut v1) = (0.0, 0.0);
                for ((a, b), t) in radial.iter().zip(ang) {
                    v0 += a * t;
                    v1 += b * t;
                }
                r0.push(v0);
                r1.push(v1);
                w.push(weight / total);
            }
        }
        (r0, r1, w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAMBDA_NM: f64 = 400.0;

    /// A pencil sampled as `sampling`, each ray's α proportional to its stop point, its phase
    /// and ψ given functions of the stop point.
    fn pencil(
        sampling: Sampling,
        phase: impl Fn(f64, f64) -> f64,
        psi: impl Fn(f64, f64) -> f64,
    ) -> Vec<PupilRay> {
        crate::sampling::pupil_samples(sampling.radius, sampling.rays_across)
            .into_iter()
            .map(|(x, y, weight)| PupilRay {
                stop: (x, y),
                alpha: (0.05 * x, 0.05 * y),
                phase: phase(x, y),
                psi: psi(x, y),
                weight,
            })
            .collect()
    }

    #[test]
    fn the_tilt_is_fitted_with_the_pupils_area_weights() {
        let sampling = Sampling {
            radius: 1.5,
            rays_across: 16,
        };
        // Coma, whose tilt-free part depends on how the rays are weighted.
        let rays = pencil(sampling, |x, y| 1e-3 * y * (x * x + y * y), |_, _| 0.0);
        let (r0, _) = tilt_residuals(&rays).unwrap();
        let moment = |f: &dyn Fn(&PupilRay) -> f64, weighted: bool| -> f64 {
            rays.iter()
                .zip(&r0)
                .map(|(r, v)| if weighted { r.weight } else { 1.0 } * f(r) * v)
                .sum()
        };
        let scale: f64 = rays.iter().map(|r| r.weight * r.phase.abs()).sum();
        for f in [&|_: &PupilRay| 1.0, &|r: &PupilRay| r.alpha.1] as [&dyn Fn(&PupilRay) -> f64; 2]
        {
            assert!(moment(f, true).abs() < 1e-12 * scale);
        }
        // Unweighted, the residual is not orthogonal to the tilt: the weights matter here.
        let unweighted = moment(&|r| r.alpha.1, false) / rays.len() as f64;
        assert!(unweighted.abs() > 1e-3 * scale, "{unweighted} {scale}");
    }

    /// A pencil of 16 rays across with 30 waves of astigmatism, 2 of coma and ±10 of defocus
    /// over the distances: the Zernike resampling gives the Strehl ratio of the exact
    /// wavefront summed on 512 rays across, where the 16 traced rays' own sum aliases.
    #[test]
    fn the_resampled_sum_is_the_exact_wavefronts() {
        let lambda = LAMBDA_NM * 1e-6;
        let a: f64 = 1.5;
        let astig = 30.0 * lambda / (2.0 * a * a);
        let coma = 2.0 * lambda / (2.0 * a.powi(3));
        let n = 1.336;
        let (lo, hi) = (-0.2, 0.2);
        let defocus = 10.0 * lambda / (n * hi * 0.5 * a * a);
        let phase = |x: f64, y: f64| astig * (y * y - x * x) + coma * y * (x * x + y * y);
        let psi = |x: f64, y: f64| -0.5 * defocus * (x * x + y * y);
        let coarse = Sampling {
            radius: a,
            rays_across: 16,
        };
        let fine = Sampling {
            radius: a,
            rays_across: 512,
        };
        let resampled = StrehlModel::new(
            &pencil(coarse, phase, psi),
            coarse,
            true,
            LAMBDA_NM,
            n,
            (lo, hi),
        )
        .unwrap();
        let traced = StrehlModel::new(
            &pencil(coarse, phase, psi),
            coarse,
            false,
            LAMBDA_NM,
            n,
            (lo, hi),
        )
        .unwrap();
        let exact = StrehlModel::new(
            &pencil(fine, phase, psi),
            fine,
            false,
            LAMBDA_NM,
            n,
            (lo, hi),
        )
        .unwrap();
        assert!(
            (100..512).contains(&resampled.rays_across),
            "{}",
            resampled.rays_across
        );
        assert_eq!(traced.rays_across, 16);
        let mut worst_traced: f64 = 0.0;
        for i in 0..=20 {
            let s = lo + (hi - lo) * i as f64 / 20.0;
            let e = exact.at(s);
            assert!(
                (resampled.at(s) - e).abs() < 1e-6,
                "{s}: {} {e}",
                resampled.at(s)
            );
            worst_traced = worst_traced.max((traced.at(s) - e).abs());
        }
        assert!(worst_traced > 0.01, "{worst_traced}");
    }

    #[test]
    fn zernike_radial_polynomials_are_the_tabulated_ones() {
        let rho: f64 = 0.7;
        let basis = Zernike::new(6);
        let r = |n: usize, m: usize| {
            let i = basis.terms.iter().position(|&t| t == (n, m)).unwrap();
            basis.radial_at(rho)[i]
        };
        assert!((r(2, 0) - (2.0 * rho * rho - 1.0)).abs() < 1e-15);
        assert!((r(3, 1) - (3.0 * rho.powi(3) - 2.0 * rho)).abs() < 1e-15);
        let r40 = 6.0 * rho.powi(4) - 6.0 * rho * rho + 1.0;
        assert!((r(4, 0) - r40).abs() < 1e-15);
        let r62 = 15.0 * rho.powi(6) - 20.0 * rho.powi(4) + 6.0 * rho * rho;
        assert!((r(6, 2) - r62).abs() < 1e-14);
        // R_n^m(1) = 1 for every term; cos(m θ) by the recurrence.
        let basis = Zernike::new(10);
        assert!(basis.radial_at(1.0).iter().all(|r| (r - 1.0).abs() < 1e-9));
        let th: f64 = 0.3;
        for (&(_, m), t) in basis.terms.iter().zip(basis.angular_at(th.cos())) {
            assert!((t - (m as f64 * th).cos()).abs() < 1e-13, "{m}");
        }
    }
}
