//! The material nodes Σ_i on [ε, L] (docs/MODEL.md §3–4).
//!
//! `uniform` nodes are spread evenly, so ladders N = 101, 201, 401, … are nested. On top:
//! - the material breakpoints (πR0/2, and a, b with fibres) become nodes, so that data
//!   jump or kink only at nodes and never inside an interval;
//! - next to the pole, graded nodes ε + h q^k (k = 1..K, q = 0.3) shrink the spacing until
//!   it is no larger than ε. The equations carry 1/r and 1/r² coefficients, stiff where
//!   r ~ Σ is small; on a uniform mesh κ and α_s at the first nodes converge only at
//!   order 1. With spacing ≲ distance from the pole the scheme keeps its order.

use crate::text::{decimals6, number};

/// Ratio q of the geometric grading next to the pole.
pub const POLE_RATIO: f64 = 0.3;

/// The most nodes a mesh may have, of every kind together. A node costs about 2 kB in the
/// elastic solve (the band Jacobian and its LU, the unknowns, the point evaluations), so
/// the limit is about 2 GB; it stops a typo (solver.nodes = 1e9) before any allocation.
pub const MAX_NODES: usize = 1_000_000;
/// The memory one node of a scene's largest mesh costs its solve, at most: what a mesh is
/// counted in when it is refused. Measured: solver.richardson on 249 997 nodes (its
/// largest mesh 999 997 nodes, the smaller two held beside it) peaks at 2.38 GB resident.
pub const BYTES_PER_NODE: u64 = 2400;

/// Why a mesh cannot be laid; found by [`plan`] before anything is allocated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    #[error("the shell [ε, L] = [{}, {}] mm is not an interval of finite, positive numbers with ε < L", number(*epsilon), number(*length))]
    Interval { epsilon: f64, length: f64 },
    #[error("{uniform} uniform nodes: a mesh needs at least 2")]
    TooFewNodes { uniform: usize },
    #[error("the mesh would have {nodes} nodes or more ({uniform} uniform, {pole} graded at the pole, {cornea} at the cornea), more than the {MAX_NODES} allowed")]
    TooManyNodes {
        nodes: usize,
        uniform: usize,
        pole: usize,
        cornea: usize,
    },
    #[error("the cornea's bending layer √(E_b / t_s) = {layer:.3e} mm is thinner than double precision resolves at Σ = L = {} mm (spacings below {resolution:.1e} mm)", decimals6(*length))]
    LayerUnresolvable {
        layer: f64,
        length: f64,
        resolution: f64,
    },
}

/// The node counts of a mesh, computed without laying it: every loop of [`Mesh::new`] and
/// [`Mesh::grade_cornea`] run with counting only, each bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    pub uniform: usize,
    pub pole: usize,
    pub cornea: usize,
}

impl Plan {
    /// An upper bound on the nodes (breakpoints may add a few more, at most `breakpoints`).
    pub fn nodes(&self, breakpoints: usize) -> usize {
        self.uniform + self.pole + self.cornea + breakpoints
    }
}

/// Check that a mesh of `uniform` nodes on [ε, L] (graded at the pole when `grade_pole`,
/// and at the cornea for a bending layer `cornea_layer` when given) can be laid, and count
/// its nodes.
pub fn plan(
    epsilon: f64,
    length: f64,
    uniform: usize,
    grade_pole: bool,
    cornea_layer: Option<f64>,
) -> Result<Plan, MeshError> {
    if !(epsilon > 0.0 && epsilon < length && length.is_finite()) {
        return Err(MeshError::Interval { epsilon, length });
    }
    if uniform < 2 {
        return Err(MeshError::TooFewNodes { uniform });
    }
    let too_many = |pole, cornea| MeshError::TooManyNodes {
        nodes: uniform.saturating_add(pole).saturating_add(cornea),
        uniform,
        pole,
        cornea,
    };
    if uniform > MAX_NODES {
        return Err(too_many(0, 0));
    }
    let h = (length - epsilon) / (uniform - 1) as f64;
    // h/ε ≤ L/ε is finite, so the pole's geometric grading ends within ~1300 steps.
    let pole = if grade_pole {
        pole_spacings(h, epsilon).count()
    } else {
        0
    };
    let cornea = match cornea_layer {
        Some(layer) => {
            let resolution = 16.0 * f64::EPSILON * length;
            if !(0.25 * layer > resolution) {
                return Err(MeshError::LayerUnresolvable {
                    layer,
                    length,
                    resolution,
                });
            }
            cornea_nodes(layer, length, length - h).count()
        }
        None => 0,
    };
    let plan = Plan {
        uniform,
        pole,
        cornea,
    };
    if plan.nodes(0) > MAX_NODES {
        return Err(too_many(pole, cornea));
    }
    Ok(plan)
}

/// The spacings of the pole's grading, h q, h q², …, the last the first no larger than ε.
fn pole_spacings(h: f64, epsilon: f64) -> impl Iterator<Item = f64> {
    std::iter::successors(Some(h * POLE_RATIO), |s| Some(s * POLE_RATIO)).scan(h, move |prev, s| {
        (*prev > epsilon).then(|| {
            *prev = s;
            s
        })
    })
}

/// The cornea's graded nodes L − d for a layer of width `layer` in the last interval
/// (start, L): d = layer/4 apart over the last 6 widths, then doubling from 12 widths out
/// to the interval's start. Finite only for layer/4 well above L's round-off ([`plan`]).
fn cornea_nodes(layer: f64, l: f64, start: f64) -> impl Iterator<Item = f64> {
    let fine = 0.25 * layer;
    let even = std::iter::successors(Some(fine), move |d| Some(d + fine))
        .take_while(move |&d| d < 6.0 * layer && l - d > start);
    let doubling = std::iter::successors(Some(12.0 * layer), |d| Some(2.0 * d))
        .take_while(move |&d| l - d > start + 0.5 * fine);
    even.chain(doubling).map(move |d| l - d)
}

#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Σ_0 = ε < Σ_1 < … < Σ_{M−1} = L.
    pub nodes: Vec<f64>,
    /// The uniform nodes asked for (solver.nodes).
    pub uniform: usize,
    /// Indices of nodes that are material breakpoints.
    pub breakpoint_nodes: Vec<usize>,
    /// Breakpoints that were added as new nodes (not already uniform nodes).
    pub inserted_breakpoints: usize,
    /// Graded nodes added next to the pole.
    pub pole_nodes: usize,
    /// Graded nodes added next to the cornea.
    pub cornea_nodes: usize,
}

impl Mesh {
    /// Lay the nodes: `uniform` ≥ 2 even nodes on [ε, L], the `breakpoints` inside (ε, L),
    /// and the pole grading when `grade_pole`; refused by [`plan`] before any allocation
    /// when that cannot be done.
    pub fn new(
        epsilon: f64,
        length: f64,
        uniform: usize,
        breakpoints: &[f64],
        grade_pole: bool,
    ) -> Result<Mesh, MeshError> {
        let plan = plan(epsilon, length, uniform, grade_pole, None)?;
        let h = (length - epsilon) / (uniform - 1) as f64;
        let mut nodes = Vec::with_capacity(plan.nodes(breakpoints.len()));
        nodes.extend((0..uniform).map(|i| epsilon + i as f64 * h));
        nodes[uniform - 1] = length;
        let mut pole_nodes = 0;
        if grade_pole {
            nodes.extend(pole_spacings(h, epsilon).map(|s| epsilon + s));
            pole_nodes = plan.pole;
        }
        // A breakpoint within round-off of an existing node replaces it; otherwise it is added.
        let snap = 1e-10 * length;
        let mut inserted = 0;
        let mut exact = Vec::new();
        for &b in breakpoints.iter().filter(|&&b| b > epsilon && b < length) {
            match nodes.iter().position(|&x| (x - b).abs() <= snap) {
                Some(i) => nodes[i] = b,
                None => {
                    nodes.push(b);
                    inserted += 1;
                }
            }
            exact.push(b);
        }
        nodes.sort_by(f64::total_cmp);
        nodes.dedup();
        let breakpoint_nodes = exact
            .iter()
            .map(|b| nodes.iter().position(|x| x == b).unwrap())
            .collect();
        Ok(Mesh {
            nodes,
            uniform,
            breakpoint_nodes,
            inserted_breakpoints: inserted,
            pole_nodes,
            cornea_nodes: 0,
        })
    }

    /// Resolve a boundary layer of width `layer` at the cornea (Σ = L) inside the last
    /// interval: uniform spacing layer/4 over the last 6 widths, then spacings doubling
    /// back out to the interval's start. As E_b → 0 the bending stiffness matters only
    /// within √(E_b / t_s) of the clamped edge, where κ changes by O(1) (the membrane limit).
    /// The layer must be resolvable ([`plan`] checks it); a thinner one is refused.
    pub fn grade_cornea(mut self, layer: f64) -> Result<Mesh, MeshError> {
        let m = self.len();
        let (l, start) = (self.nodes[m - 1], self.nodes[m - 2]);
        let resolution = 16.0 * f64::EPSILON * l;
        if !(0.25 * layer > resolution) {
            return Err(MeshError::LayerUnresolvable {
                layer,
                length: l,
                resolution,
            });
        }
        let added: Vec<f64> = cornea_nodes(layer, l, start).collect();
        self.cornea_nodes = added.len();
        self.nodes.extend(added);
        // The new nodes all lie in the last interval, after every breakpoint, so the
        // breakpoints' indices do not move.
        self.nodes.sort_by(f64::total_cmp);
        self.nodes.dedup();
        Ok(self)
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub fn intervals(&self) -> usize {
        self.nodes.len() - 1
    }

    /// Length of interval i, [Σ_i, Σ_{i+1}].
    pub fn step(&self, i: usize) -> f64 {
        self.nodes[i + 1] - self.nodes[i]
    }

    /// The interval holding Σ (the last one for Σ = L), or None outside [ε, L].
    pub fn locate(&self, sigma_ref: f64) -> Option<usize> {
        let (first, last) = (self.nodes[0], *self.nodes.last().unwrap());
        if !(sigma_ref >= first && sigma_ref <= last) {
            return None;
        }
        let i = self.nodes.partition_point(|&x| x <= sigma_ref);
        Some(i.saturating_sub(1).min(self.intervals() - 1))
    }

    /// Every interval halved: the self-similar refinement, under which the error expansion
    /// h⁴ C + h⁶ D + … keeps its coefficients, so Richardson extrapolation cancels h⁴ exactly
    /// (refining by `solver.nodes` re-grades the pole and moves the breakpoints within
    /// their intervals, which changes C).
    pub fn halved(&self) -> Mesh {
        let mut nodes = Vec::with_capacity(2 * self.len() - 1);
        for w in self.nodes.windows(2) {
            nodes.extend_from_slice(&[w[0], 0.5 * (w[0] + w[1])]);
        }
        nodes.push(*self.nodes.last().unwrap());
        let breakpoint_nodes = self.breakpoint_nodes.iter().map(|&i| 2 * i).collect();
        Mesh {
            nodes,
            uniform: 2 * self.uniform - 1,
            breakpoint_nodes,
            inserted_breakpoints: self.inserted_breakpoints,
            pole_nodes: 2 * self.pole_nodes,
            cornea_nodes: 2 * self.cornea_nodes,
        }
    }

    /// A mesh laid node by node (by `bvp::adapt`): `nodes` increasing, `breakpoint_nodes`
    /// the indices of the breakpoints. It has no uniform part: all its nodes count as
    /// `uniform`, none as graded or inserted breakpoints.
    pub fn adapted(nodes: Vec<f64>, breakpoint_nodes: Vec<usize>) -> Mesh {
        debug_assert!(nodes.windows(2).all(|w| w[0] < w[1]));
        Mesh {
            uniform: nodes.len(),
            nodes,
            breakpoint_nodes,
            inserted_breakpoints: 0,
            pole_nodes: 0,
            cornea_nodes: 0,
        }
    }

    /// Index of the node at exactly Σ, if any (none for a NaN: the nodes are finite, and
    /// the total order puts NaN past them all).
    pub fn node_at(&self, sigma_ref: f64) -> Option<usize> {
        self.nodes
            .binary_search_by(|x| x.total_cmp(&sigma_ref))
            .ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_ladders_are_nested() {
        let coarse = Mesh::new(1e-3, 25.0, 101, &[], false).unwrap();
        let fine = Mesh::new(1e-3, 25.0, 201, &[], false).unwrap();
        for (i, x) in coarse.nodes.iter().enumerate() {
            assert!((fine.nodes[2 * i] - x).abs() < 1e-13);
        }
    }

    #[test]
    fn pole_grading_reaches_epsilon() {
        let m = Mesh::new(1e-3, 25.0, 501, &[], true).unwrap();
        let h: f64 = (25.0 - 1e-3) / 500.0;
        assert_eq!(
            m.pole_nodes,
            ((h / 1e-3).ln() / (1.0 / POLE_RATIO).ln()).ceil() as usize
        );
        assert!(m.step(0) <= 1e-3 && m.step(0) > 1e-3 * POLE_RATIO);
        // Each graded spacing is a bounded multiple, (1 − q)/q, of the distance from the pole.
        for i in 0..m.pole_nodes {
            assert!(
                m.step(i) <= (1.0 - POLE_RATIO) / POLE_RATIO * m.nodes[i] + 1e-15,
                "spacing too large at node {i}"
            );
        }
        assert_eq!(m.len(), 501 + m.pole_nodes);
    }

    #[test]
    fn halving_keeps_every_node_and_breakpoint() {
        let bps = [std::f64::consts::FRAC_PI_2, 5.0 * std::f64::consts::PI];
        let m = Mesh::new(1e-3, 25.0, 51, &bps, true).unwrap();
        let h = m.halved();
        assert_eq!(h.len(), 2 * m.len() - 1);
        for (i, x) in m.nodes.iter().enumerate() {
            assert_eq!(h.nodes[2 * i], *x);
        }
        for (k, &b) in bps.iter().enumerate() {
            assert_eq!(h.nodes[h.breakpoint_nodes[k]], b);
        }
        assert!((h.step(0) - 0.5 * m.step(0)).abs() < 1e-18);
    }

    #[test]
    fn breakpoints_become_nodes() {
        let bps = [
            std::f64::consts::FRAC_PI_2,
            1.25 * std::f64::consts::PI,
            5.0 * std::f64::consts::PI,
        ];
        let m = Mesh::new(1e-3, 8.0 * std::f64::consts::PI, 101, &bps, true).unwrap();
        for (k, &b) in bps.iter().enumerate() {
            assert_eq!(m.nodes[m.breakpoint_nodes[k]], b);
        }
        assert!(m.nodes.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(m.locate(bps[2]), Some(m.breakpoint_nodes[2]));
        assert_eq!(m.locate(*m.nodes.last().unwrap()), Some(m.intervals() - 1));
        assert_eq!(m.locate(0.0), None);
    }
}
