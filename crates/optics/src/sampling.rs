//! How a pupil is sampled: Gauss–Legendre rings in r² (the area measure) times evenly spaced
//! spokes, for the traced pencils of the best focus (docs/optics.md, "Best focus") and the
//! finer sums of the Strehl ratio.

/// How the pupil is sampled: rings × spokes, the layout of [`pupil_samples`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sampling {
    pub(crate) radius: f64,
    pub(crate) rays_across: usize,
}

impl Sampling {
    /// The rings: the radius and weight of each, Gauss–Legendre nodes and weights in r² (the
    /// area measure) on [−1, 1], so the weights sum to 2.
    pub(crate) fn rings(&self) -> Vec<(f64, f64)> {
        gauss_legendre(self.ring_count())
            .into_iter()
            .map(|(x, w)| (self.radius * ((x + 1.0) / 2.0).sqrt(), w))
            .collect()
    }

    /// The spokes' angles from the sagittal x axis, evenly spaced and offset by half a spoke,
    /// so that the set is symmetric under x → −x with no point on x = 0.
    pub(crate) fn spokes(&self) -> Vec<f64> {
        let count = self.spoke_count();
        (0..count)
            .map(|j| 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / count as f64)
            .collect()
    }

    /// rays_across / 2 rings.
    pub(crate) fn ring_count(&self) -> usize {
        (self.rays_across / 2).max(1)
    }

    /// About 2 × rays_across spokes, a multiple of 4 (symmetric about both axes).
    pub(crate) fn spoke_count(&self) -> usize {
        (2 * self.rays_across).div_ceil(4).max(1) * 4
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton's method on Pₙ from Chebyshev
/// guesses).
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_n(x) and its derivative by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                let pn = if n == 0 { 1.0 } else { p1 };
                let pm = if n == 0 { 0.0 } else { p0 };
                dp = n as f64 * (x * pn - pm) / (x * x - 1.0);
                let dx = pn / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Sample points of the pupil disc of radius `a` with their area weights: Gauss–Legendre rings
/// in r² (the area measure) times evenly spaced spokes, offset by half a spoke so that the set
/// is symmetric under x → −x with no point on x = 0. Integrals of smooth functions over the
/// disc converge far faster than on a square grid, whose staircase rim costs O(1/n).
pub(crate) fn pupil_samples(a: f64, rays_across: usize) -> Vec<(f64, f64, f64)> {
    let sampling = Sampling {
        radius: a,
        rays_across,
    };
    let (rings, spokes) = (sampling.rings(), sampling.spokes());
    let mut pts = Vec::with_capacity(rings.len() * spokes.len());
    for (r, w) in rings {
        for &th in &spokes {
            pts.push((r * th.cos(), r * th.sin(), w / spokes.len() as f64));
        }
    }
    pts
}
