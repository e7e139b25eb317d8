//! Refraction in dioptres: the spectacle-plane power that brings an eye's best focus onto its
//! retina (docs/optics.md, "Refraction").
//!
//! The eye's optics are fixed while its retina moves, so the best focus on the axis is traced
//! once for thin spectacle lenses of [`POWERS`] (every dioptre) at the vertex distance, and a
//! retina's refraction is read from that table by inverting its cubic interpolant: growth
//! pays one lookup per output time. The interpolant's error is far below 0.01 D: the focus is
//! a smooth function of the lens's power (a Möbius map in Gaussian optics, plus the pupil's
//! slowly varying aberration), whose fourth derivative makes the 4-point cubic's error about
//! 1e-6 mm at 1 D spacing. The pole's table of a growth run ([`RefractionTable::compute_sampled`])
//! traces every fifth dioptre only and fills the rest by that Möbius map and a cubic through
//! what the aberrations add ([`fill_moebius`]).

use rayon::prelude::*;

use crate::error::OpticsError;
use crate::focus::{best_focus_with, Criterion, FocusSettings, Pupil};
use crate::lens::{wear, Lens};
use crate::system::OpticalSystem;

/// The spectacle powers traced (D): −25 to +25 in steps of 1.
pub const POWERS: (f64, f64, usize) = (-25.0, 25.0, 51);

/// The default vertex distance (mm) of a refraction.
pub const VERTEX_MM: f64 = 12.0;

/// The powers traced for a [`RefractionTable::compute_sampled`] (D): −25 to +25 in steps
/// of 5, the nodes of the fill.
pub const SAMPLED_POWERS: (f64, f64, usize) = (-25.0, 25.0, 11);

/// Values `y` at `x` (increasing) carried to the points `at` (inside [x₀, xₘ₋₁]), exactly for
/// a Möbius function y = (a x + b)/(1 + c x). A focus against the power of a thin spectacle
/// lens is one in Gaussian optics: the lens at vertex d sends the eye the vergence
/// F/(1 − dF), and the eye images a vergence at a Möbius function of it, so the composition
/// is one. The Möbius map through the first, middle and last samples carries that part
/// exactly, and what the pupil's aberrations add to it (small and smooth in the power) is
/// carried by the 4-point cubic through its samples. Where the samples give no Möbius map
/// (a NaN among those three, a singular fit, a pole inside the range) the cubic carries the
/// values themselves. A NaN sample makes NaN of the points whose cubic uses it.
pub fn fill_moebius(x: &[f64], y: &[f64], at: &[f64]) -> Vec<f64> {
    let m = x.len();
    if m < 4 || y.len() != m {
        return vec![f64::NAN; at.len()];
    }
    let moebius = moebius_through([0, m / 2, m - 1].map(|k| (x[k], y[k])))
        .filter(|&(_, _, c)| (1.0 + c * x[0]) * (1.0 + c * x[m - 1]) > 0.0);
    let shape = |f: f64| moebius.map_or(0.0, |(a, b, c)| (a * f + b) / (1.0 + c * f));
    let residual: Vec<f64> = x.iter().zip(y).map(|(&f, &v)| v - shape(f)).collect();
    at.iter()
        .map(|&f| {
            let k = x.partition_point(|&p| p <= f).clamp(1, m - 1) - 1;
            let j = k.saturating_sub(1).min(m - 4);
            let mut sum = 0.0;
            for a in j..j + 4 {
                let mut w = 1.0;
                for b in j..j + 4 {
                    if a != b {
                        w *= (f - x[b]) / (x[a] - x[b]);
                    }
                }
                // A sample on the point itself is taken as it is (its weight is 1, the
                // others' 0, and 0 × NaN would spoil it).
                if w != 0.0 {
                    sum += w * residual[a];
                }
            }
            shape(f) + sum
        })
        .collect()
}

/// The Möbius map y = (a x + b)/(1 + c x) through three points: the linear equations
/// a x + b − c x y = y. None when they are singular or give no finite map.
fn moebius_through(p: [(f64, f64); 3]) -> Option<(f64, f64, f64)> {
    let rows: Vec<[f64; 4]> = p.iter().map(|&(x, y)| [x, 1.0, -x * y, y]).collect();
    let det3 = |c: [usize; 3]| {
        let e = |r: usize, k: usize| rows[r][c[k]];
        e(0, 0) * (e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1))
            - e(0, 1) * (e(1, 0) * e(2, 2) - e(1, 2) * e(2, 0))
            + e(0, 2) * (e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0))
    };
    let d = det3([0, 1, 2]);
    if !(d.is_finite() && d != 0.0) {
        return None;
    }
    // Cramer's rule: the right side (column 3) in place of each unknown's column.
    let (a, b, c) = (
        det3([3, 1, 2]) / d,
        det3([0, 3, 2]) / d,
        det3([0, 1, 3]) / d,
    );
    (a.is_finite() && b.is_finite() && c.is_finite()).then_some((a, b, c))
}

/// The system a refraction table traces for a trial lens of power `f` (D): the eye with a
/// thin spectacle lens of that power at the table's vertex distance, and whatever else it
/// wears.
pub type Trial<'a> = dyn Fn(f64) -> Result<OpticalSystem, OpticsError> + Sync + 'a;

/// The spectacle powers (D) of a table's grid `(lowest, highest, count)`, evenly spaced.
pub fn power_grid((lo, hi, n): (f64, f64, usize)) -> Vec<f64> {
    (0..n)
        .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
        .collect()
}

/// An eye's on-axis best focus against the power of a thin spectacle lens in front of it.
#[derive(Debug, Clone, PartialEq)]
pub struct RefractionTable {
    pub wavelength_nm: f64,
    pub vertex: f64,
    /// Spectacle powers (D), increasing.
    pub powers: Vec<f64>,
    /// The best focus's z (mm from the corneal apex) with each, decreasing.
    pub foci: Vec<f64>,
}

impl RefractionTable {
    /// Trace the table for `eye` (as worn: no other lens) at `wavelength_nm`: every power
    /// of [`POWERS`] traced.
    pub fn compute(
        eye: &OpticalSystem,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        vertex: f64,
    ) -> Result<Self, OpticsError> {
        Self::compute_from(
            eye,
            wavelength_nm,
            pupil,
            criterion,
            settings,
            vertex,
            POWERS,
        )
    }

    /// [`RefractionTable::compute`] with the focus traced at the powers of [`SAMPLED_POWERS`]
    /// only (11 of 51) and the table's other powers filled by [`fill_moebius`]: within
    /// 1e-3 D of the full trace (crates/optics/tests/lenses.rs), at a fifth of the rays.
    pub fn compute_sampled(
        eye: &OpticalSystem,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        vertex: f64,
    ) -> Result<Self, OpticsError> {
        Self::compute_from(
            eye,
            wavelength_nm,
            pupil,
            criterion,
            settings,
            vertex,
            SAMPLED_POWERS,
        )
    }

    /// [`RefractionTable::compute_sampled`] through the systems `trial` gives: the eye as
    /// worn with a thin trial lens of each power at `vertex` (with lenses on, the eye
    /// through them: the over-refraction).
    pub fn compute_sampled_through(
        trial: &Trial<'_>,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        vertex: f64,
    ) -> Result<Self, OpticsError> {
        Self::compute_through(
            trial,
            wavelength_nm,
            pupil,
            criterion,
            settings,
            vertex,
            SAMPLED_POWERS,
        )
    }

    fn compute_from(
        eye: &OpticalSystem,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        vertex: f64,
        traced: (f64, f64, usize),
    ) -> Result<Self, OpticsError> {
        let trial = |f: f64| wear(eye, &[Lens::spectacle(f, vertex)]);
        Self::compute_through(
            &trial,
            wavelength_nm,
            pupil,
            criterion,
            settings,
            vertex,
            traced,
        )
    }

    fn compute_through(
        trial: &Trial<'_>,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        vertex: f64,
        traced: (f64, f64, usize),
    ) -> Result<Self, OpticsError> {
        let powers = power_grid(POWERS);
        let sampled = power_grid(traced);
        let at_samples = sampled
            .par_iter()
            .map(|&f| {
                let system = trial(f)?;
                best_focus_with(&system, wavelength_nm, 0.0, pupil, criterion, settings)
                    .map(|focus| focus.z)
            })
            .collect::<Result<Vec<f64>, OpticsError>>()?;
        let foci = if traced == POWERS {
            at_samples
        } else {
            fill_moebius(&sampled, &at_samples, &powers)
        };
        if foci.windows(2).any(|w| !(w[1] < w[0])) {
            return Err(OpticsError::NoFocus {
                field_deg: 0.0,
                wavelength_nm,
                reason: "the on-axis focus does not move forward steadily as plus power is added"
                    .into(),
            });
        }
        Ok(RefractionTable {
            wavelength_nm,
            vertex,
            powers,
            foci,
        })
    }

    /// The cubic through the four table points around interval k, at power f.
    fn focus_in(&self, k: usize, f: f64) -> f64 {
        let n = self.powers.len();
        let j = k.saturating_sub(1).min(n - 4);
        let mut sum = 0.0;
        for a in j..j + 4 {
            let mut w = 1.0;
            for b in j..j + 4 {
                if a != b {
                    w *= (f - self.powers[b]) / (self.powers[a] - self.powers[b]);
                }
            }
            sum += w * self.foci[a];
        }
        sum
    }

    /// The best focus's z with a thin spectacle lens of power `f` (D), interpolated.
    pub fn focus(&self, f: f64) -> Option<f64> {
        let (lo, hi) = (self.powers[0], *self.powers.last()?);
        if !(f >= lo && f <= hi) {
            return None;
        }
        let k = self
            .powers
            .partition_point(|&p| p <= f)
            .clamp(1, self.powers.len() - 1)
            - 1;
        Some(self.focus_in(k, f))
    }

    /// The refraction (D) of a retina at `retina_z`: the spectacle power that puts the best
    /// focus there; `None` beyond the table (more than 25 D either way).
    pub fn refraction(&self, retina_z: f64) -> Option<f64> {
        let n = self.foci.len();
        if !(retina_z <= self.foci[0] && retina_z >= self.foci[n - 1]) {
            return None;
        }
        // foci decrease: interval k holds foci[k] ≥ z ≥ foci[k+1].
        let k = self.foci.partition_point(|&z| z > retina_z).clamp(1, n - 1) - 1;
        let (mut a, mut b) = (self.powers[k], self.powers[k + 1]);
        let g = |f: f64| self.focus_in(k, f) - retina_z;
        let (mut ga, gb) = (g(a), g(b));
        if ga * gb > 0.0 {
            return None;
        }
        // Bisection to 1e-12 D: the interpolant is monotone on the interval.
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            let gm = g(m);
            if gm == 0.0 {
                return Some(m);
            }
            if (gm > 0.0) == (ga > 0.0) {
                a = m;
                ga = gm;
            } else {
                b = m;
            }
        }
        Some(0.5 * (a + b))
    }
}

/// The spectacle powers of a [`PeripheralTable`] (D): −10 to +20 in steps of 2.5. Coarser
/// and narrower than [`POWERS`] because each field pays the whole column: at 5 D steps the
/// cubic misses a wide field's focus by 0.005 mm (more than 0.01 D), at 2.5 D the tests hold
/// the pole to 1e-3 D of its 1 D table and every field's focus to 0.004 mm (0.01 D) of the
/// retina. The range holds the model's eyes (+10.5 D at the const scene's start, a few
/// dioptres either way later); beyond it the refraction is NaN.
pub const PERIPHERAL_POWERS: (f64, f64, usize) = (-10.0, 20.0, 13);

/// Where a [`PeripheralTable`] is traced: the spectacle lens's vertex distance (mm in front
/// of the corneal apex) and the field angles (degrees, in air, increasing).
#[derive(Clone, Copy, Debug)]
pub struct FieldsAt<'a> {
    pub vertex: f64,
    pub fields: &'a [f64],
}

/// An eye's best focus at each of a few field angles against the power of a thin spectacle
/// lens in front of it: the peripheral refraction of a retina is read from it as the pole's
/// is from a [`RefractionTable`], by finding the power that puts the field's focus on it.
#[derive(Debug, Clone, PartialEq)]
pub struct PeripheralTable {
    pub wavelength_nm: f64,
    pub vertex: f64,
    /// Field angles (degrees, in air), increasing.
    pub fields: Vec<f64>,
    /// Spectacle powers (D), increasing.
    pub powers: Vec<f64>,
    /// The best focus (z, r) for each field, then each power.
    pub foci: Vec<Vec<(f64, f64)>>,
    /// For each field, the powers traced between those of `powers` where the cubic through
    /// them missed the traced focus ([`REFINE_MM`]), each with its focus, increasing (empty:
    /// none; a field list shorter than `fields` leaves the rest without).
    pub between: Vec<Vec<(f64, (f64, f64))>>,
}

/// A peripheral table's interval is halved where the focus traced at its middle power lies
/// farther than this (mm) from the cubic through the traced powers around it: 1e-3 mm is
/// about 0.0025 D, a quarter of the refraction's 0.01 D. Where a wide field's focus runs
/// steeply forward with plus power (towards the power at which it forms none) the cubic
/// through powers 2.5 D apart misses by a tenth of a dioptre; halving there, and again
/// ([`REFINE_ROUNDS`]), brings it within this.
pub const REFINE_MM: f64 = 1e-3;

/// The most times an interval of a peripheral table is halved: its powers are then
/// 2.5/2⁶ ≈ 0.04 D apart.
pub const REFINE_ROUNDS: usize = 6;

/// A field's traced powers and their foci, increasing in power.
type Nodes = Vec<(f64, (f64, f64))>;

/// The focus of a field whose traced powers and foci are `nodes` with a lens of power `f`
/// in interval k: the cubic through four nodes that hold the interval, in z and r apart.
/// The centred four come first; where one of them is NaN (a strong lens at a wide field that
/// forms no focus) the four on the other side are taken, then three points, then the
/// interval's own two, so an interval whose ends were both traced always gives a focus.
fn focus_on(nodes: &[(f64, (f64, f64))], k: usize, f: f64) -> (f64, f64) {
    let n = nodes.len();
    let finite = |j: usize, m: usize| {
        j + m <= n
            && nodes[j..j + m]
                .iter()
                .all(|(_, p)| p.0.is_finite() && p.1.is_finite())
    };
    let centred = k.saturating_sub(1).min(n.saturating_sub(4));
    let stencil = [
        (centred, 4),
        (k, 4),
        (k.saturating_sub(2), 4),
        (k.saturating_sub(1), 3),
        (k, 3),
        (k, 2),
    ]
    .into_iter()
    .find(|&(j, m)| j <= k && j + m > k + 1 && finite(j, m));
    let Some((j, m)) = stencil else {
        return (f64::NAN, f64::NAN);
    };
    let (mut z, mut r) = (0.0, 0.0);
    for a in j..j + m {
        let mut w = 1.0;
        for b in j..j + m {
            if a != b {
                w *= (f - nodes[b].0) / (nodes[a].0 - nodes[b].0);
            }
        }
        z += w * nodes[a].1 .0;
        r += w * nodes[a].1 .1;
    }
    (z, r)
}

/// `nodes` with the intervals whose middle the cubic misses halved ([`REFINE_MM`]), as
/// often as [`REFINE_ROUNDS`] allows: the powers traced between them, increasing. `trace`
/// gives the focus at a power (NaN where it forms none). An interval whose middle forms no
/// focus, or that the cubic already meets, is left as it is; so is one whose miss did not
/// fall to half its parent's: a smooth focus's cubic misses 16 times less at half the step,
/// and one that does not is the focus's own scatter where the pencil is about to form none,
/// which halving would chase to no end.
fn refine(nodes: &[(f64, (f64, f64))], trace: &dyn Fn(f64) -> (f64, f64)) -> Nodes {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let mut nodes: Nodes = nodes.to_vec();
    // Each interval's parent's miss (infinite for the grid's), None once it is left as it is.
    let mut open: Vec<Option<f64>> = (nodes.windows(2))
        .map(|w| (finite(&w[0].1) && finite(&w[1].1)).then_some(f64::INFINITY))
        .collect();
    let mut added: Nodes = Vec::new();
    for _ in 0..REFINE_ROUNDS {
        let mut next: Nodes = Vec::with_capacity(nodes.len());
        let mut next_open: Vec<Option<f64>> = Vec::new();
        for k in 0..nodes.len() - 1 {
            next.push(nodes[k]);
            let Some(parent) = open[k] else {
                next_open.push(None);
                continue;
            };
            let m = 0.5 * (nodes[k].0 + nodes[k + 1].0);
            let (z, r) = trace(m);
            let (pz, pr) = focus_on(&nodes, k, m);
            let miss = (z - pz).hypot(r - pr);
            if finite(&(z, r)) && miss > REFINE_MM {
                next.push((m, (z, r)));
                added.push((m, (z, r)));
                let again = (miss < 0.5 * parent).then_some(miss);
                next_open.extend([again, again]);
            } else {
                next_open.push(None);
            }
        }
        next.push(nodes[nodes.len() - 1]);
        nodes = next;
        open = next_open;
        if open.iter().all(Option::is_none) {
            break;
        }
    }
    added.sort_by(|a, b| a.0.total_cmp(&b.0));
    added
}

impl PeripheralTable {
    /// Trace the table for `eye` (as worn: no other lens) at `wavelength_nm`, at `fields`.
    /// An error only when a lens cannot be worn: a focus that fails is NaN. Every power is
    /// traced: off the axis the focus against the power is no Möbius map (the lens also
    /// turns the chief ray), and filled from every fifth dioptre it misses a 30° focus by
    /// 0.2 D.
    pub fn compute(
        eye: &OpticalSystem,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        at: FieldsAt<'_>,
    ) -> Result<Self, OpticsError> {
        let trial = |f: f64| wear(eye, &[Lens::spectacle(f, at.vertex)]);
        Self::compute_through(&trial, wavelength_nm, pupil, criterion, settings, at)
    }

    /// [`PeripheralTable::compute`] through the systems `trial` gives: the eye as worn with
    /// a thin trial lens of each power at `at.vertex` (with lenses on, the eye through them).
    pub fn compute_through(
        trial: &Trial<'_>,
        wavelength_nm: f64,
        pupil: &Pupil,
        criterion: Criterion,
        settings: &FocusSettings,
        at: FieldsAt<'_>,
    ) -> Result<Self, OpticsError> {
        let FieldsAt { vertex, fields } = at;
        let powers = power_grid(PERIPHERAL_POWERS);
        let n = powers.len();
        let systems = powers
            .iter()
            .map(|&f| trial(f))
            .collect::<Result<Vec<_>, _>>()?;
        let jobs: Vec<(usize, usize)> = (0..fields.len())
            .flat_map(|i| (0..n).map(move |k| (i, k)))
            .collect();
        let points = jobs
            .par_iter()
            .map(|&(i, k)| {
                best_focus_with(
                    &systems[k],
                    wavelength_nm,
                    fields[i],
                    pupil,
                    criterion,
                    settings,
                )
                .map(|focus| (focus.z, focus.r))
                // A strong lens at a wide field may form no focus; its entry is NaN, the
                // intervals that need it are skipped, and a retina beyond them has none.
                .unwrap_or((f64::NAN, f64::NAN))
            })
            .collect::<Vec<_>>();
        let foci: Vec<Vec<(f64, f64)>> = points.chunks(n).map(<[_]>::to_vec).collect();
        let between = (0..fields.len())
            .into_par_iter()
            .map(|i| {
                let trace = |f: f64| {
                    (trial(f).ok())
                        .and_then(|system| {
                            best_focus_with(
                                &system,
                                wavelength_nm,
                                fields[i],
                                pupil,
                                criterion,
                                settings,
                            )
                            .ok()
                        })
                        .map_or((f64::NAN, f64::NAN), |focus| (focus.z, focus.r))
                };
                let nodes: Nodes = powers
                    .iter()
                    .copied()
                    .zip(foci[i].iter().copied())
                    .collect();
                refine(&nodes, &trace)
            })
            .collect();
        Ok(PeripheralTable {
            wavelength_nm,
            vertex,
            fields: fields.to_vec(),
            powers,
            foci,
            between,
        })
    }

    /// Field `i`'s traced powers and foci: the grid's and those traced between them.
    fn nodes(&self, i: usize) -> Nodes {
        let mut nodes: Nodes = (self.powers.iter().copied())
            .zip(self.foci[i].iter().copied())
            .collect();
        if let Some(between) = self.between.get(i) {
            nodes.extend(between.iter().copied());
            nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        nodes
    }

    /// The refraction (D) at field `i` of a retina: the spectacle power that puts the
    /// field's best focus on it. `behind(z, r)` is how far the point (z, r) lies behind the
    /// retina (negative in front; `None` where the retina does not reach), which decreases
    /// as plus power pulls the focus forward. `None` when no power of the table does it.
    pub fn refraction(&self, i: usize, behind: impl Fn(f64, f64) -> Option<f64>) -> Option<f64> {
        let nodes = self.nodes(i);
        let n = nodes.len();
        let g = |k: usize, f: f64| {
            let (z, r) = focus_on(&nodes, k, f);
            if z.is_finite() && r.is_finite() {
                behind(z, r)
            } else {
                None
            }
        };
        // The first interval where the focus crosses the retina.
        let k = (0..n - 1).find(|&k| {
            matches!(
                (g(k, nodes[k].0), g(k, nodes[k + 1].0)),
                (Some(a), Some(b)) if a >= 0.0 && b <= 0.0
            )
        })?;
        let (mut a, mut b) = (nodes[k].0, nodes[k + 1].0);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if g(k, m)? > 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        Some(0.5 * (a + b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the focus runs steeply forward with plus power towards the power at which it
    /// forms none (here z(F) = 17 + 1336/(60 + F) − 3/(9.5 − F), none from 9.5 D), the cubic
    /// through the grid's powers misses a retina's refraction by more than 0.01 D; with the
    /// intervals halved where it missed their middle ([`refine`]), every retina from 0 to 7.5 D
    /// (the last traced power before none) is found to 1e-3 D of the exact inverse.
    #[test]
    fn halving_the_intervals_the_cubic_misses_finds_a_steep_focus() {
        let powers = power_grid(PERIPHERAL_POWERS);
        let z_of = |f: f64| match f < 9.5 {
            true => (17.0 + 1336.0 / (60.0 + f) - 3.0 / (9.5 - f), 0.0),
            false => (f64::NAN, f64::NAN),
        };
        let column: Vec<(f64, f64)> = powers.iter().map(|&f| z_of(f)).collect();
        let mut table = PeripheralTable {
            wavelength_nm: 555.0,
            vertex: VERTEX_MM,
            fields: vec![40.0],
            powers: powers.clone(),
            foci: vec![column.clone()],
            between: vec![],
        };
        let worst = |t: &PeripheralTable| {
            (0..=30)
                .map(|k| {
                    let exact = 0.25 * k as f64;
                    let retina = z_of(exact).0;
                    let d = t.refraction(0, |z, _| Some(z - retina));
                    d.map_or(f64::INFINITY, |d| (d - exact).abs())
                })
                .fold(0.0, f64::max)
        };
        let grid_alone = worst(&table);
        let nodes: Nodes = powers.iter().copied().zip(column).collect();
        table.between = vec![refine(&nodes, &z_of)];
        let halved = worst(&table);
        eprintln!(
            "grid alone: {grid_alone} D; halved: {halved} D, {} powers",
            table.between[0].len()
        );
        assert!(grid_alone > 0.01, "{grid_alone}");
        assert!(halved < 1e-3, "{halved}");
        assert!(table.between[0].len() < 40, "{:?}", table.between);
    }

    /// A field whose strongest lens forms no focus (its entry NaN) still gives the
    /// refraction of a retina in the interval next to it, from the four points on the other
    /// side: against the exact inverse of a Gaussian-optics focus z(F) = 17 + 1336/(60 + F),
    /// to 0.01 D; the centred four alone would include the NaN.
    #[test]
    fn a_nan_neighbour_leaves_the_refraction_to_the_other_side() {
        let powers = power_grid(PERIPHERAL_POWERS);
        let z_of = |f: f64| 17.0 + 1336.0 / (60.0 + f);
        let mut column: Vec<(f64, f64)> = powers.iter().map(|&f| (z_of(f), 0.0)).collect();
        let last = column.len() - 1;
        column[last] = (f64::NAN, f64::NAN);
        let table = PeripheralTable {
            wavelength_nm: 555.0,
            vertex: VERTEX_MM,
            fields: vec![40.0],
            powers,
            foci: vec![column],
            between: vec![],
        };
        for exact in [15.4, 16.6, 17.4, 3.3, -8.8] {
            let retina = z_of(exact);
            let d = table.refraction(0, |z, _| Some(z - retina)).unwrap();
            assert!((d - exact).abs() < 0.01, "{d} against {exact}");
        }
        // Beyond the last traced power there is none.
        let retina = z_of(19.0);
        assert_eq!(table.refraction(0, |z, _| Some(z - retina)), None);
    }
}
