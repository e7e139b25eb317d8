//! Sampled sweeps: `[sweep.sample]`, a virtual cohort of eyes whose parameters are drawn
//! from distributions.
//!
//! ```toml
//! [sweep.sample]
//! eyes = 200
//! design = "latin-hypercube"   # "random", "latin-hypercube", "sobol", "saltelli"
//! seed = 11
//! [sweep.sample.keys]
//! "growth.eta0" = { dist = "normal", mean = 70.0, sd = 5.0 }
//! "growth.Gamma" = { dist = "uniform", low = 6.0, high = 10.0 }
//! [sweep.sample.correlation]     # optional: a Gaussian copula
//! keys = ["growth.eta0", "growth.Gamma"]
//! matrix = [[1.0, 0.5], [0.5, 1.0]]
//! ```
//!
//! The draws become the sweep's list of runs (`eye-001`, `eye-002`, ...; each run sets the
//! sampled keys to its eye's values), so that a sampled sweep runs, resumes, shards, merges
//! and goes to Slurm or Dask exactly as a listed sweep does. Every draw is a function of the
//! scene alone (seed, design, eyes, distributions): each shard computes the same cohort.
//!
//! Points in the unit cube come from the design; each is mapped through the Gaussian copula
//! when a correlation is given (`u → Φ⁻¹(u) → L z → Φ`), then through each key's inverse
//! CDF. A Gaussian copula rather than Iman–Conover: it acts on one point at a time, so it
//! works the same for every design (and for any subset of eyes, as a shard sees them), and
//! its parameter is a plain correlation of normal scores; Iman–Conover reorders the whole
//! sample and would tie each eye to all the others.
//!
//! A draw outside a key's range (the key table's rule: a normal η0 below 0) is not clipped:
//! the sweep is refused, naming the key, the count and the first eyes, so that the cohort
//! run is the cohort described.
//!
//! `design = "saltelli"` draws `eyes` base points A and B (2k dimensions of the scrambled
//! Sobol sequence) and runs A, B and each AB_i (A with column i from B): eyes · (k + 2)
//! runs, from which [`crate::sweep::population`] estimates first-order and total Sobol
//! indices (Saltelli 2010; Jansen).

mod maths;
mod parse;
#[cfg(test)]
mod tests;

use super::{keys, SceneError};
use crate::text::number;
use maths::{copula, SplitMix64};
pub use maths::{normal_cdf, normal_quantile, Resampler};
pub use parse::parse;

/// The largest cohort: the draws are held in memory (8 bytes per key and eye).
pub const MAX_EYES: usize = 1_000_000;
/// The Sobol sequence (sobol_burley) gives at most 2^16 points, in at most 256 dimensions.
pub const MAX_SOBOL_POINTS: usize = 1 << 16;
const MAX_SOBOL_DIMENSIONS: usize = sobol_burley::NUM_DIMENSIONS as usize;
/// The fewest base points of a `saltelli` design. Each index is a mean over the N base
/// points whose Monte Carlo error is about 1/√N of the output's variance: at N = 4 that is
/// half the variance, and estimates such as 1.41 (interval [1.25, 1.77]) for an index that
/// lies in [0, 1] come out as if they meant something; the bootstrap of 4 points has 35
/// distinct resamples, too few for a 95 % interval. From 32 the error is below a fifth and
/// the bootstrap has 9·10¹⁷ resamples; an index still outside [0, 1] is noted in
/// population.json (`notes`).
pub const MIN_SALTELLI_EYES: usize = 32;
/// Bootstrap resamples for the Sobol indices' confidence intervals.
pub const BOOTSTRAP: usize = 1000;

/// How the points in the unit cube are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Design {
    /// Independent uniform points from the seeded generator.
    Random,
    /// One point in each of `eyes` equal strata of every key, paired at random.
    LatinHypercube,
    /// The Owen-scrambled Sobol sequence (sobol_burley), scrambled by the seed.
    Sobol,
    /// A, B and AB_i matrices for Sobol indices (see the module's documentation).
    Saltelli,
}

impl Design {
    pub const NAMES: [&'static str; 4] = ["random", "latin-hypercube", "sobol", "saltelli"];

    pub fn name(self) -> &'static str {
        match self {
            Design::Random => "random",
            Design::LatinHypercube => "latin-hypercube",
            Design::Sobol => "sobol",
            Design::Saltelli => "saltelli",
        }
    }
}

/// A key's distribution.
#[derive(Clone, Debug, PartialEq)]
pub enum Dist {
    Normal {
        mean: f64,
        sd: f64,
    },
    /// Given by the mean and sd of the value itself (not of its logarithm).
    LogNormal {
        mean: f64,
        sd: f64,
    },
    Uniform {
        low: f64,
        high: f64,
    },
    /// The normal of `mean` and `sd` restricted to [low, high].
    TruncatedNormal {
        mean: f64,
        sd: f64,
        low: f64,
        high: f64,
    },
    Triangular {
        low: f64,
        mode: f64,
        high: f64,
    },
    /// Measured values, drawn with equal probability (resampling).
    Empirical {
        values: Vec<f64>,
    },
}

impl Dist {
    pub const NAMES: [&'static str; 6] = [
        "normal",
        "lognormal",
        "uniform",
        "truncated-normal",
        "triangular",
        "empirical",
    ];

    /// The value at probability `u` ∈ (0, 1): the inverse of the distribution function.
    pub fn quantile(&self, u: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => mean + sd * normal_quantile(u),
            Dist::LogNormal { mean, sd } => {
                let s2 = (1.0 + (sd / mean).powi(2)).ln();
                let mu = mean.ln() - 0.5 * s2;
                (mu + s2.sqrt() * normal_quantile(u)).exp()
            }
            Dist::Uniform { low, high } => low + (high - low) * u,
            Dist::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => {
                // In the upper tail work with the mirror image, where Φ keeps its digits.
                let (a, b) = ((low - mean) / sd, (high - mean) / sd);
                let z = if a > 0.0 {
                    let (pa, pb) = (normal_cdf(-b), normal_cdf(-a));
                    -normal_quantile(pa + (1.0 - u) * (pb - pa))
                } else {
                    let (pa, pb) = (normal_cdf(a), normal_cdf(b));
                    normal_quantile(pa + u * (pb - pa))
                };
                (mean + sd * z).clamp(low, high)
            }
            Dist::Triangular { low, mode, high } => {
                let f = (mode - low) / (high - low);
                if u < f {
                    low + (u * (high - low) * (mode - low)).sqrt()
                } else {
                    high - ((1.0 - u) * (high - low) * (high - mode)).sqrt()
                }
            }
            Dist::Empirical { ref values } => {
                let i = ((u * values.len() as f64) as usize).min(values.len() - 1);
                values[i]
            }
        }
    }
}

/// A parsed `[sweep.sample]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// The cohort's size (for `saltelli`, the number of base points N).
    pub eyes: usize,
    pub design: Design,
    pub seed: u64,
    /// The sampled keys, in the table's order, each with its distribution.
    pub keys: Vec<(String, Dist)>,
    /// The Cholesky factor of the correlation of normal scores, over `keys`' order.
    pub cholesky: Option<Vec<Vec<f64>>>,
    /// What each eye leaves: a run directory, or a row of the sweep's tables.
    pub per_run: PerRun,
}

/// What a sampled sweep keeps of each eye (`per_run` in `[sweep.sample]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PerRun {
    /// `runs/<eye>/`, an ordinary run directory per eye (the default).
    #[default]
    Directory,
    /// No directory: a row per eye in sweep.csv, its series in the sweep's one series.csv,
    /// checkpointed in batches ([`crate::sweep::compact`]). A cohort of 10,000 eyes is
    /// otherwise 10,000 directories of files, each synced: the files, not the numerics,
    /// take most of the time.
    Table,
}

impl PerRun {
    pub const NAMES: [&'static str; 2] = ["directory", "table"];
}

/// The role of a run in a Saltelli design: base matrix A, B, or AB_i (0-based i).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    A,
    B,
    AB(usize),
}

impl Sample {
    /// The number of runs: eyes, or eyes · (k + 2) for `saltelli`.
    pub fn runs(&self) -> usize {
        match self.design {
            Design::Saltelli => self.eyes * (self.keys.len() + 2),
            _ => self.eyes,
        }
    }

    /// Run `index`'s name: `eye-007`, or `A-007`, `B-007`, `AB2-007` for `saltelli` (runs
    /// eye by eye: A, B, AB1, ..., ABk of the first base point, then the next).
    pub fn run_name(&self, index: usize) -> String {
        let width = self.eyes.to_string().len().max(3);
        match self.role(index) {
            (None, eye) => format!("eye-{:0width$}", eye + 1),
            (Some(Role::A), eye) => format!("A-{:0width$}", eye + 1),
            (Some(Role::B), eye) => format!("B-{:0width$}", eye + 1),
            (Some(Role::AB(i)), eye) => format!("AB{}-{:0width$}", i + 1, eye + 1),
        }
    }

    /// Run `index`'s Saltelli role (None for other designs) and its base point.
    pub fn role(&self, index: usize) -> (Option<Role>, usize) {
        match self.design {
            Design::Saltelli => {
                let per = self.keys.len() + 2;
                let role = match index % per {
                    0 => Role::A,
                    1 => Role::B,
                    r => Role::AB(r - 2),
                };
                (Some(role), index / per)
            }
            _ => (None, index),
        }
    }

    /// Every run's values, in run order, one value per key: the design's points through the
    /// copula and the inverse CDFs.
    pub fn draws(&self) -> Vec<Vec<f64>> {
        let k = self.keys.len();
        let points = self.points();
        let to_values = |u: &[f64]| -> Vec<f64> {
            let u = match &self.cholesky {
                Some(l) => copula(l, u),
                None => u.to_vec(),
            };
            self.keys
                .iter()
                .zip(&u)
                .map(|((_, d), &u)| d.quantile(u))
                .collect()
        };
        match self.design {
            Design::Saltelli => {
                let mut out = Vec::with_capacity(self.runs());
                for p in &points {
                    let (a, b) = p.split_at(k);
                    out.push(to_values(a));
                    out.push(to_values(b));
                    for i in 0..k {
                        let mut ab = a.to_vec();
                        ab[i] = b[i];
                        out.push(to_values(&ab));
                    }
                }
                out
            }
            _ => points.iter().map(|p| to_values(p)).collect(),
        }
    }

    /// The design's points in (0, 1)^d: d = k, or 2k for `saltelli`.
    fn points(&self) -> Vec<Vec<f64>> {
        let k = self.keys.len();
        let n = self.eyes;
        match self.design {
            Design::Random => (0..n)
                .map(|i| {
                    let mut rng = SplitMix64::new(self.seed, i as u64, 0);
                    (0..k).map(|_| rng.unit()).collect()
                })
                .collect(),
            Design::LatinHypercube => {
                let mut points = vec![vec![0.0; k]; n];
                for d in 0..k {
                    // The strata in a random order, a point at random within each.
                    let mut order: Vec<usize> = (0..n).collect();
                    let mut rng = SplitMix64::new(self.seed, d as u64, 1);
                    for i in (1..n).rev() {
                        let j = rng.below(i + 1);
                        order.swap(i, j);
                    }
                    for (i, p) in points.iter_mut().enumerate() {
                        p[d] = (order[i] as f64 + rng.unit()) / n as f64;
                    }
                }
                points
            }
            Design::Sobol | Design::Saltelli => {
                let dims = if self.design == Design::Saltelli {
                    2 * k
                } else {
                    k
                };
                let seed = (self.seed ^ (self.seed >> 32)) as u32;
                (0..n)
                    .map(|i| {
                        (0..dims)
                            .map(|d| {
                                // f32 in [0, 1) on a grid of 2^-24: the cell's centre, never 0.
                                let x = sobol_burley::sample(i as u32, d as u32, seed);
                                (f64::from(x) * 16_777_216.0).floor() / 16_777_216.0
                                    + 0.5 / 16_777_216.0
                            })
                            .collect()
                    })
                    .collect()
            }
        }
    }
}

/// The draws of `sample` outside their key's range, refused with their count, the key and
/// the first eyes: never clipped.
pub fn check_draws(sample: &Sample, draws: &[Vec<f64>], origin: &str) -> Result<(), SceneError> {
    const SHOWN: usize = 2;
    let mut problems = Vec::new();
    let mut total = 0;
    for (d, (key, _)) in sample.keys.iter().enumerate() {
        let Some(spec) = keys::find(key) else {
            continue;
        };
        let mut bad = Vec::new();
        let mut why = String::new();
        for (i, row) in draws.iter().enumerate() {
            if let Err(e) = spec.rule.check_float(row[d]) {
                if bad.len() < SHOWN {
                    // Six significant digits: the message stays one short line.
                    let x: f64 = format!("{:.5e}", row[d]).parse().unwrap_or(row[d]);
                    bad.push(format!("{} = {}", sample.run_name(i), number(x)));
                }
                if why.is_empty() {
                    // The rule without its reason (the key's documentation has it).
                    let e = e.to_string();
                    why = e.split(':').next().unwrap_or(&e).to_string();
                }
                total += 1;
            }
        }
        if !bad.is_empty() {
            let count = draws
                .iter()
                .filter(|r| spec.rule.check_float(r[d]).is_err())
                .count();
            // The first key with its eyes, the others by their count: one short line.
            problems.push(if problems.is_empty() {
                format!(
                    "{count} of {key} ({why}: {}{})",
                    bad.join(", "),
                    if count > SHOWN { ", ..." } else { "" }
                )
            } else {
                format!("{count} of {key}")
            });
        }
    }
    if problems.is_empty() {
        return Ok(());
    }
    Err(SceneError::BadSweep {
        origin: origin.to_string(),
        problem: format!(
            "sample: {total} of {} drawn values lie outside their key's range and are not clipped: {}; narrow the distribution or bound it (truncated-normal)",
            draws.len() * sample.keys.len(),
            problems.join("; ")
        ),
    })
}
