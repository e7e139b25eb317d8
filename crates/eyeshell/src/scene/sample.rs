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

use super::{closest, describe, keys, one_line, Access, SceneError};
use crate::text::number;

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

/// `u` through the Gaussian copula of Cholesky factor `l`.
fn copula(l: &[Vec<f64>], u: &[f64]) -> Vec<f64> {
    let z: Vec<f64> = u.iter().map(|&u| normal_quantile(u)).collect();
    (0..z.len())
        .map(|i| {
            let zi: f64 = (0..=i).map(|j| l[i][j] * z[j]).sum();
            normal_cdf(zi).clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON / 2.0)
        })
        .collect()
}

/// SplitMix64 (Steele, Lea and Flood 2014): eyeshell's own few lines rather than a crate's
/// generator, so that the same seed gives the same cohort whatever crate versions build it.
/// Each (seed, stream, tag) starts its own sequence: an eye's draws do not depend on how
/// many eyes there are.
struct SplitMix64(u64);

impl SplitMix64 {
    fn new(seed: u64, stream: u64, tag: u64) -> SplitMix64 {
        let mut g = SplitMix64(seed);
        let a = g.next();
        let mut g = SplitMix64(a ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let b = g.next();
        SplitMix64(b ^ tag.wrapping_mul(0x8CB9_2BA7_2F3D_8DD7))
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1): the centre of one of 2^53 cells.
    fn unit(&mut self) -> f64 {
        ((self.next() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Uniform in 0..n (n ≥ 1), by rejection: no modulo bias.
    fn below(&mut self, n: usize) -> usize {
        let n = n as u64;
        let zone = u64::MAX - u64::MAX % n;
        loop {
            let x = self.next();
            if x < zone {
                return (x % n) as usize;
            }
        }
    }
}

/// A seeded generator for the bootstrap of [`crate::sweep::population`].
pub struct Resampler(SplitMix64);

impl Resampler {
    pub fn new(seed: u64) -> Resampler {
        Resampler(SplitMix64::new(seed, 0, 2))
    }

    /// Uniform in 0..n (n ≥ 1).
    pub fn below(&mut self, n: usize) -> usize {
        self.0.below(n)
    }
}

/// Φ⁻¹(p) for p ∈ (0, 1): Wichura's algorithm AS 241 (PPND16), about 1e-16 relative.
// The coefficients as Wichura published them, digits beyond f64's included, to be checked
// against the paper.
#[allow(clippy::excessive_precision)]
pub fn normal_quantile(p: f64) -> f64 {
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180625 - q * q;
        return q
            * (((((((2509.0809287301226727 * r + 33430.575583588128105) * r
                + 67265.770927008700853)
                * r
                + 45921.953931549871457)
                * r
                + 13731.693765509461125)
                * r
                + 1971.5909503065514427)
                * r
                + 133.14166789178437745)
                * r
                + 3.387132872796366608)
            / (((((((5226.495278852545925 * r + 28729.085735721942674) * r
                + 39307.89580009271061)
                * r
                + 21213.794301586595867)
                * r
                + 5394.1960214247511077)
                * r
                + 687.1870074920579083)
                * r
                + 42.313330701600911252)
                * r
                + 1.0);
    }
    let r = if q < 0.0 { p } else { 1.0 - p };
    let r = (-r.ln()).sqrt();
    let x = if r <= 5.0 {
        let r = r - 1.6;
        (((((((7.7454501427834140764e-4 * r + 0.0227238449892691845833) * r
            + 0.24178072517745061177)
            * r
            + 1.27045825245236838258)
            * r
            + 3.64784832476320460504)
            * r
            + 5.7694972214606914055)
            * r
            + 4.6303378461565452959)
            * r
            + 1.42343711074968357734)
            / (((((((1.05075007164441684324e-9 * r + 5.475938084995344946e-4) * r
                + 0.0151986665636164571966)
                * r
                + 0.14810397642748007459)
                * r
                + 0.68976733498510000455)
                * r
                + 1.6763848301838038494)
                * r
                + 2.05319162663775882187)
                * r
                + 1.0)
    } else {
        let r = r - 5.0;
        (((((((2.01033439929228813265e-7 * r + 2.71155556874348757815e-5) * r
            + 0.0012426609473880784386)
            * r
            + 0.026532189526576123093)
            * r
            + 0.29656057182850489123)
            * r
            + 1.7848265399172913358)
            * r
            + 5.4637849111641143699)
            * r
            + 6.6579046435011037772)
            / (((((((2.04426310338993978564e-15 * r + 1.4215117583164458887e-7) * r
                + 1.8463183175100546818e-5)
                * r
                + 7.868691311456132591e-4)
                * r
                + 0.0148753612908506148525)
                * r
                + 0.13692988092273580531)
                * r
                + 0.59983220655588793769)
                * r
                + 1.0)
    };
    if q < 0.0 {
        -x
    } else {
        x
    }
}

/// Φ(x), the standard normal distribution function: Marsaglia's Taylor series (2004) for
/// |x| ≤ 3, about 1e-15 absolute; beyond, the tail from the continued fraction of the Mills
/// ratio, Φ(−a) = φ(a) / (a + 1/(a + 2/(a + 3/(a + ...)))), to full relative precision
/// (the series would lose the tail's digits to cancellation against 1/2).
pub fn normal_cdf(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x.abs() > 3.0 {
        let a = x.abs();
        let phi = (-0.5 * a * a).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let mut d = a;
        for n in (1..=300).rev() {
            d = a + n as f64 / d;
        }
        let tail = phi / d;
        return if x < 0.0 { tail } else { 1.0 - tail };
    }
    let (mut s, mut t, x2) = (x, x, x * x);
    let mut i = 1.0;
    loop {
        i += 2.0;
        t *= x2 / i;
        let next = s + t;
        if next == s {
            break;
        }
        s = next;
    }
    0.5 + s * (-0.5 * x2 - 0.918_938_533_204_672_8).exp()
}

/// Parse `[sweep.sample]`.
pub fn parse(t: &toml::Table, origin: &str) -> Result<Sample, SceneError> {
    let bad = |problem: String| SceneError::BadSweep {
        origin: origin.to_string(),
        problem: format!("sample: {problem}"),
    };
    let mut eyes = None;
    let mut design = Design::Random;
    let mut seed = None;
    let mut keys = Vec::new();
    let mut correlation = None;
    let mut per_run = PerRun::Directory;
    for (name, value) in t {
        match name.as_str() {
            "eyes" => match value {
                toml::Value::Integer(n) if *n >= 2 && *n as u64 <= MAX_EYES as u64 => {
                    eyes = Some(*n as usize)
                }
                v => {
                    return Err(bad(format!(
                        "eyes must be a whole number from 2 to {MAX_EYES}, found {}",
                        describe(v)
                    )))
                }
            },
            "seed" => match value {
                toml::Value::Integer(n) if *n >= 0 => seed = Some(*n as u64),
                v => {
                    return Err(bad(format!(
                        "seed must be a whole number >= 0, found {}",
                        describe(v)
                    )))
                }
            },
            "design" => {
                let s = match value {
                    toml::Value::String(s) => s.as_str(),
                    v => {
                        return Err(bad(format!(
                            "design must be one of {}, found {}",
                            Design::NAMES.join(", "),
                            describe(v)
                        )))
                    }
                };
                design = match s {
                    "random" => Design::Random,
                    "latin-hypercube" => Design::LatinHypercube,
                    "sobol" => Design::Sobol,
                    "saltelli" => Design::Saltelli,
                    other => {
                        let hint = closest(other, Design::NAMES.into_iter())
                            .map(|s| format!(" (did you mean '{s}'?)"))
                            .unwrap_or_default();
                        return Err(bad(format!(
                            "design '{}' is not one of {}{hint}",
                            one_line(other),
                            Design::NAMES.join(", ")
                        )));
                    }
                };
            }
            "keys" => match value {
                toml::Value::Table(k) => key_dists(k, "", origin, &mut keys)?,
                v => return Err(bad(format!("keys must be a table, found {}", describe(v)))),
            },
            "correlation" => match value {
                toml::Value::Table(c) => correlation = Some(c.clone()),
                v => {
                    return Err(bad(format!(
                        "correlation must be a table of keys and matrix, found {}",
                        describe(v)
                    )))
                }
            },
            "per_run" => {
                per_run = match value {
                    toml::Value::String(s) if s == "directory" => PerRun::Directory,
                    toml::Value::String(s) if s == "table" => PerRun::Table,
                    v => {
                        return Err(bad(format!(
                            "per_run must be \"directory\" (a run directory per eye) or \"table\" (a row per eye, no directories), found {}",
                            describe(v)
                        )))
                    }
                }
            }
            other => {
                let known = ["eyes", "design", "seed", "keys", "correlation", "per_run"];
                let hint = closest(other, known.into_iter())
                    .map(|s| format!(" (did you mean '{s}'?)"))
                    .unwrap_or_default();
                return Err(bad(format!(
                    "unknown entry '{}'{hint}: a sample has eyes, design, seed, keys, correlation and per_run",
                    one_line(other)
                )));
            }
        }
    }
    let Some(eyes) = eyes else {
        return Err(bad("give eyes, the number of eyes to draw".into()));
    };
    // Without a seed the cohort would differ from one run (or shard) to the next.
    let Some(seed) = seed else {
        return Err(bad(
            "give seed (a whole number): the same seed draws the same cohort".into(),
        ));
    };
    if keys.is_empty() {
        return Err(bad(
            "keys is missing or empty: give [sweep.sample.keys] with a distribution for each key"
                .into(),
        ));
    }
    let dims = match design {
        Design::Saltelli => 2 * keys.len(),
        _ => keys.len(),
    };
    if design == Design::Saltelli && eyes < MIN_SALTELLI_EYES {
        return Err(bad(format!(
            "eyes = {eyes}: the saltelli design needs at least {MIN_SALTELLI_EYES} base points for its Sobol indices to mean anything (with fewer, an index's Monte Carlo error is as large as the index); give eyes = {MIN_SALTELLI_EYES} or more"
        )));
    }
    if matches!(design, Design::Sobol | Design::Saltelli) {
        if eyes > MAX_SOBOL_POINTS {
            return Err(bad(format!(
                "eyes = {eyes}: the {} design draws at most {MAX_SOBOL_POINTS} points of the Sobol sequence",
                design.name()
            )));
        }
        if dims > MAX_SOBOL_DIMENSIONS {
            return Err(bad(format!(
                "{} keys need {dims} dimensions of the Sobol sequence, which has {MAX_SOBOL_DIMENSIONS}",
                keys.len()
            )));
        }
    }
    let cholesky = match correlation {
        None => None,
        Some(c) => {
            if design == Design::Saltelli {
                return Err(bad("correlation: Sobol indices (design = \"saltelli\") assume independent keys; leave out the correlation or use another design".into()));
            }
            Some(correlation_factor(&c, &keys).map_err(bad)?)
        }
    };
    let sample = Sample {
        eyes,
        design,
        seed,
        keys,
        cholesky,
        per_run,
    };
    if sample.runs() > super::sweep::MAX_PLANNED_RUNS {
        return Err(bad(format!(
            "declares {} runs, more than the {} allowed",
            sample.runs(),
            super::sweep::MAX_PLANNED_RUNS
        )));
    }
    Ok(sample)
}

/// Each key's distribution (quoted dotted keys, or nested tables of them).
fn key_dists(
    t: &toml::Table,
    prefix: &str,
    origin: &str,
    out: &mut Vec<(String, Dist)>,
) -> Result<(), SceneError> {
    for (name, value) in t {
        let key = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        match (keys::find(&key), value) {
            (Some(spec), toml::Value::Table(d)) => {
                if !matches!(
                    spec.access,
                    Access::Float { .. } | Access::OptionalFloat { .. }
                ) {
                    return Err(SceneError::BadSweep {
                        origin: origin.to_string(),
                        problem: format!(
                            "sample: {key} is not a real-valued key ({}): only real numbers are drawn",
                            spec.type_name()
                        ),
                    });
                }
                let dist = dist(d).map_err(|p| SceneError::BadSweep {
                    origin: origin.to_string(),
                    problem: format!("sample: keys.{key}: {p}"),
                })?;
                out.push((key, dist));
            }
            (Some(_), v) => {
                return Err(SceneError::BadSweep {
                    origin: origin.to_string(),
                    problem: format!(
                        "sample: keys.{key} must be a table such as {{ dist = \"normal\", mean = 70.0, sd = 5.0 }}, found {}",
                        describe(v)
                    ),
                })
            }
            (None, toml::Value::Table(sub)) => key_dists(sub, &key, origin, out)?,
            (None, _) => {
                return Err(super::unknown_key(
                    &format!("{origin}: [sweep.sample.keys]"),
                    &key,
                ))
            }
        }
    }
    Ok(())
}

/// One key's `{ dist = ..., ... }`.
fn dist(t: &toml::Table) -> Result<Dist, String> {
    let name = match t.get("dist") {
        Some(toml::Value::String(s)) => s.clone(),
        Some(v) => return Err(format!("dist must be a string, found {}", describe(v))),
        None => return Err(format!("give dist, one of {}", Dist::NAMES.join(", "))),
    };
    let expected: &[&str] = match name.as_str() {
        "normal" | "lognormal" => &["mean", "sd"],
        "uniform" => &["low", "high"],
        "truncated-normal" => &["mean", "sd", "low", "high"],
        "triangular" => &["low", "mode", "high"],
        "empirical" => &["values"],
        other => {
            let hint = closest(other, Dist::NAMES.into_iter())
                .map(|s| format!(" (did you mean '{s}'?)"))
                .unwrap_or_default();
            return Err(format!(
                "dist '{}' is not one of {}{hint}",
                one_line(other),
                Dist::NAMES.join(", ")
            ));
        }
    };
    for k in t.keys() {
        if k != "dist" && !expected.contains(&k.as_str()) {
            return Err(format!(
                "'{}' is not a parameter of a {name} distribution (give {})",
                one_line(k),
                expected.join(", ")
            ));
        }
    }
    let real = |k: &str| -> Result<f64, String> {
        let x = match t.get(k) {
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(n)) => *n as f64,
            Some(v) => return Err(format!("{k} must be a number, found {}", describe(v))),
            None => {
                return Err(format!(
                    "give {} for a {name} distribution",
                    expected.join(", ")
                ))
            }
        };
        if !x.is_finite() || x.abs() > 1e300 {
            return Err(format!("{k} = {} is not a usable number", number(x)));
        }
        Ok(x)
    };
    let positive_sd = |sd: f64| -> Result<(), String> {
        if sd > 0.0 {
            Ok(())
        } else {
            Err(format!("sd = {} must be positive", number(sd)))
        }
    };
    let ordered = |low: f64, high: f64| -> Result<(), String> {
        if low < high {
            Ok(())
        } else {
            Err(format!(
                "low = {} must be below high = {}",
                number(low),
                number(high)
            ))
        }
    };
    Ok(match name.as_str() {
        "normal" => {
            let (mean, sd) = (real("mean")?, real("sd")?);
            positive_sd(sd)?;
            Dist::Normal { mean, sd }
        }
        "lognormal" => {
            let (mean, sd) = (real("mean")?, real("sd")?);
            positive_sd(sd)?;
            if mean <= 0.0 {
                return Err(format!(
                    "mean = {} must be positive: a lognormal value is",
                    number(mean)
                ));
            }
            Dist::LogNormal { mean, sd }
        }
        "uniform" => {
            let (low, high) = (real("low")?, real("high")?);
            ordered(low, high)?;
            Dist::Uniform { low, high }
        }
        "truncated-normal" => {
            let (mean, sd, low, high) = (real("mean")?, real("sd")?, real("low")?, real("high")?);
            positive_sd(sd)?;
            ordered(low, high)?;
            // Φ has no digits left 37 sd into a tail: no value could be drawn there.
            let (a, b) = ((low - mean) / sd, (high - mean) / sd);
            if a > 30.0 || b < -30.0 {
                return Err(format!(
                    "[low, high] = [{}, {}] lies more than 30 sd from the mean {}",
                    number(low),
                    number(high),
                    number(mean)
                ));
            }
            Dist::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            }
        }
        "triangular" => {
            let (low, mode, high) = (real("low")?, real("mode")?, real("high")?);
            ordered(low, high)?;
            if !(low..=high).contains(&mode) {
                return Err(format!(
                    "mode = {} must lie in [low, high] = [{}, {}]",
                    number(mode),
                    number(low),
                    number(high)
                ));
            }
            Dist::Triangular { low, mode, high }
        }
        _ => {
            let values = match t.get("values") {
                Some(toml::Value::Array(a)) => a
                    .iter()
                    .map(|v| match v {
                        toml::Value::Float(x) if x.is_finite() => Ok(*x),
                        toml::Value::Integer(n) => Ok(*n as f64),
                        v => Err(format!(
                            "values must be finite numbers, found {}",
                            describe(v)
                        )),
                    })
                    .collect::<Result<Vec<f64>, String>>()?,
                Some(v) => return Err(format!("values must be a list, found {}", describe(v))),
                None => return Err("give values, the measured values".into()),
            };
            if values.is_empty() || values.len() > MAX_EYES {
                return Err(format!(
                    "values must hold 1 to {MAX_EYES} numbers, found {}",
                    values.len()
                ));
            }
            Dist::Empirical { values }
        }
    })
}

/// The Cholesky factor of `[sweep.sample.correlation]` (keys, matrix) over the sample's
/// keys' order; keys it leaves out are independent.
fn correlation_factor(c: &toml::Table, keys: &[(String, Dist)]) -> Result<Vec<Vec<f64>>, String> {
    for k in c.keys() {
        if k != "keys" && k != "matrix" {
            return Err(format!(
                "correlation: unknown entry '{}' (give keys and matrix)",
                one_line(k)
            ));
        }
    }
    let names: Vec<String> = match c.get("keys") {
        Some(toml::Value::Array(a)) => a
            .iter()
            .map(|v| match v {
                toml::Value::String(s) => Ok(s.clone()),
                v => Err(format!(
                    "correlation.keys must be key names, found {}",
                    describe(v)
                )),
            })
            .collect::<Result<_, _>>()?,
        _ => {
            return Err(
                "correlation: give keys, the list of sampled keys the matrix is over".into(),
            )
        }
    };
    let mut at = Vec::with_capacity(names.len());
    for n in &names {
        let Some(i) = keys.iter().position(|(k, _)| k == n) else {
            return Err(format!(
                "correlation.keys: {} is not a sampled key",
                one_line(n)
            ));
        };
        if at.contains(&i) {
            return Err(format!("correlation.keys: {} is given twice", one_line(n)));
        }
        at.push(i);
    }
    let m = names.len();
    let rows: Vec<Vec<f64>> = match c.get("matrix") {
        Some(toml::Value::Array(rows)) => rows
            .iter()
            .map(|r| match r {
                toml::Value::Array(xs) => xs
                    .iter()
                    .map(|x| match x {
                        toml::Value::Float(x) => Ok(*x),
                        toml::Value::Integer(n) => Ok(*n as f64),
                        v => Err(format!(
                            "correlation.matrix must hold numbers, found {}",
                            describe(v)
                        )),
                    })
                    .collect::<Result<Vec<f64>, String>>(),
                v => Err(format!(
                    "correlation.matrix must be a list of rows, found {}",
                    describe(v)
                )),
            })
            .collect::<Result<_, _>>()?,
        _ => return Err("correlation: give matrix, a list of rows".into()),
    };
    if rows.len() != m || rows.iter().any(|r| r.len() != m) {
        return Err(format!(
            "correlation.matrix must be {m} × {m}, one row and column per key in correlation.keys"
        ));
    }
    let k = keys.len();
    let mut full = vec![vec![0.0; k]; k];
    for (i, row) in full.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for a in 0..m {
        for b in 0..m {
            let x = rows[a][b];
            if a == b && x != 1.0 {
                return Err(format!(
                    "correlation.matrix[{}][{}] = {} must be 1 (a key's correlation with itself)",
                    a + 1,
                    b + 1,
                    number(x)
                ));
            }
            if x != rows[b][a] {
                return Err(format!(
                    "correlation.matrix is not symmetric: [{}][{}] = {} but [{}][{}] = {}",
                    a + 1,
                    b + 1,
                    number(x),
                    b + 1,
                    a + 1,
                    number(rows[b][a])
                ));
            }
            if !(-1.0..=1.0).contains(&x) || !x.is_finite() {
                return Err(format!(
                    "correlation.matrix[{}][{}] = {} must lie in [-1, 1]",
                    a + 1,
                    b + 1,
                    number(x)
                ));
            }
            full[at[a]][at[b]] = x;
        }
    }
    // Cholesky; a matrix that is not positive definite is no correlation of any keys.
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let s: f64 = full[i][j] - (0..j).map(|p| l[i][p] * l[j][p]).sum::<f64>();
            if i == j {
                if s <= 1e-12 {
                    return Err("correlation.matrix is not positive definite (no keys can be correlated so; a correlation of ±1 is not allowed either)".into());
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Ok(l)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_quantile_inverts_the_normal_cdf() {
        for &p in &[1e-300, 1e-12, 0.001, 0.025, 0.3, 0.5, 0.8, 0.975, 0.999999] {
            let x = normal_quantile(p);
            let back = normal_cdf(x);
            assert!(((back - p) / p).abs() < 1e-9, "{p}: {x} {back}");
        }
        assert!((normal_quantile(0.975) - 1.959_963_984_540_054).abs() < 1e-14);
        assert!((normal_cdf(1.0) - 0.841_344_746_068_542_9).abs() < 1e-15);
        assert!((normal_cdf(-9.0) - 1.128_588_405_953_840_5e-19).abs() < 1e-22);
    }

    #[test]
    fn each_distribution_has_its_quantiles() {
        let tn = Dist::TruncatedNormal {
            mean: 0.0,
            sd: 1.0,
            low: 0.0,
            high: 1.0,
        };
        // The median of N(0,1) on [0, 1]: Φ(m) = (Φ(0) + Φ(1)) / 2.
        let m = normal_quantile((0.5 + normal_cdf(1.0)) / 2.0);
        assert!((tn.quantile(0.5) - m).abs() < 1e-12);
        let tri = Dist::Triangular {
            low: 0.0,
            mode: 1.0,
            high: 2.0,
        };
        assert!((tri.quantile(0.125) - 0.5).abs() < 1e-15);
        let ln = Dist::LogNormal { mean: 2.0, sd: 0.5 };
        // The median of a lognormal is exp(μ) = mean / sqrt(1 + (sd/mean)²).
        assert!((ln.quantile(0.5) - 2.0 / (1.0f64 + 0.0625).sqrt()).abs() < 1e-14);
        let e = Dist::Empirical {
            values: vec![3.0, 1.0, 2.0],
        };
        assert_eq!(
            [0.1, 0.4, 0.9].map(|u| e.quantile(u)),
            [3.0, 1.0, 2.0],
            "each value a third of the time"
        );
    }

    fn sample(text: &str) -> Result<Sample, SceneError> {
        let t: toml::Table = toml::from_str(text).unwrap();
        parse(&t, "s.toml")
    }

    #[test]
    fn a_latin_hypercube_has_one_point_per_stratum() {
        let s = sample(
            "eyes = 50\ndesign = \"latin-hypercube\"\nseed = 3\n[keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 0, high = 50 }\n\"growth.Gamma\" = { dist = \"uniform\", low = 0, high = 1 }\n",
        )
        .unwrap();
        let draws = s.draws();
        for d in 0..2 {
            let scale = if s.keys[d].0 == "growth.eta0" {
                50.0
            } else {
                1.0
            };
            let mut strata: Vec<usize> = draws
                .iter()
                .map(|r| (r[d] / scale * 50.0) as usize)
                .collect();
            strata.sort();
            assert_eq!(strata, (0..50).collect::<Vec<_>>());
        }
        assert_eq!(draws, s.draws(), "the same seed, the same cohort");
    }

    #[test]
    fn a_gaussian_copula_correlates_normal_scores() {
        let s = sample(
            "eyes = 4000\ndesign = \"sobol\"\nseed = 1\n[keys]\n\"growth.eta0\" = { dist = \"normal\", mean = 70, sd = 5 }\n\"growth.Gamma\" = { dist = \"normal\", mean = 8, sd = 1 }\n[correlation]\nkeys = [\"growth.eta0\", \"growth.Gamma\"]\nmatrix = [[1, 0.6], [0.6, 1]]\n",
        )
        .unwrap();
        let d = s.draws();
        let n = d.len() as f64;
        let mean = |c: usize| d.iter().map(|r| r[c]).sum::<f64>() / n;
        let (m0, m1) = (mean(0), mean(1));
        let cov = d.iter().map(|r| (r[0] - m0) * (r[1] - m1)).sum::<f64>() / n;
        let var = |c: usize, m: f64| d.iter().map(|r| (r[c] - m).powi(2)).sum::<f64>() / n;
        let rho = cov / (var(0, m0) * var(1, m1)).sqrt();
        assert!((rho - 0.6).abs() < 0.03, "{rho}");
    }

    #[test]
    fn bad_samples_are_one_line_errors() {
        let k = "[keys]\n\"growth.eta0\" = { dist = \"normal\", mean = 70, sd = 5 }\n";
        let cases = [
            (format!("eyes = 1\nseed = 1\n{k}"), "eyes must be a whole number from 2"),
            (format!("eyes = 10\n{k}"), "give seed"),
            (format!("eyes = 10\nseed = 1\ndesign = \"lhs\"\n{k}"), "design 'lhs' is not one of"),
            ("eyes = 10\nseed = 1\n".into(), "keys is missing"),
            ("eyes = 10\nseed = 1\n[keys]\n\"growth.eta0\" = { dist = \"normol\", mean = 1, sd = 1 }\n".into(), "did you mean 'normal'"),
            ("eyes = 10\nseed = 1\n[keys]\n\"growth.eta0\" = { dist = \"normal\", mean = 1, sd = -1 }\n".into(), "sd = -1 must be positive"),
            ("eyes = 10\nseed = 1\n[keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 2, high = 1 }\n".into(), "low = 2 must be below high = 1"),
            ("eyes = 10\nseed = 1\n[keys]\n\"solver.nodes\" = { dist = \"uniform\", low = 2, high = 1 }\n".into(), "not a real-valued key"),
            ("eyes = 10\nseed = 1\n[keys]\n\"growth.eta00\" = { dist = \"uniform\", low = 1, high = 2 }\n".into(), "unknown key"),
            (format!("eyes = 10\nseed = 1\n{k}\"growth.Gamma\" = {{ dist = \"uniform\", low = 1, high = 2 }}\n[correlation]\nkeys = [\"growth.eta0\", \"growth.Gamma\"]\nmatrix = [[1, 1], [1, 1]]\n"), "not positive definite"),
            (format!("eyes = 10\nseed = 1\n{k}[correlation]\nkeys = [\"growth.Gamma\"]\nmatrix = [[1]]\n"), "not a sampled key"),
            (format!("eyes = 100000\nseed = 1\ndesign = \"sobol\"\n{k}"), "at most 65536 points"),
        ];
        for (text, expect) in cases {
            let e = sample(&text).expect_err(&text).to_string();
            assert!(e.contains(expect), "{text:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn draws_outside_a_keys_range_are_named_and_counted() {
        let s = sample(
            "eyes = 1000\nseed = 5\n[keys]\n\"growth.eta0\" = { dist = \"normal\", mean = 1, sd = 1 }\n",
        )
        .unwrap();
        let d = s.draws();
        let below = d.iter().filter(|r| r[0] <= 0.0).count();
        assert!(below > 100 && below < 220, "{below}");
        let e = check_draws(&s, &d, "s.toml").unwrap_err().to_string();
        assert!(
            e.contains(&format!("{below} of 1000 drawn values lie outside")),
            "{e}"
        );
        assert!(
            e.contains(&format!(
                "{below} of growth.eta0 (must be non-negative: eye-"
            )),
            "{e}"
        );
        assert!(e.contains("not clipped"), "{e}");
    }

    #[test]
    fn a_saltelli_design_swaps_one_column_per_run() {
        let s = sample(
            "eyes = 32\ndesign = \"saltelli\"\nseed = 2\n[keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 0, high = 1 }\n\"growth.Gamma\" = { dist = \"uniform\", low = 0, high = 1 }\n",
        )
        .unwrap();
        let d = s.draws();
        assert_eq!(d.len(), 128);
        assert_eq!(s.run_name(0), "A-001");
        assert_eq!(s.run_name(3), "AB2-001");
        assert_eq!(s.run_name(127), "AB2-032");
        for e in 0..32 {
            let (a, b, ab1, ab2) = (&d[4 * e], &d[4 * e + 1], &d[4 * e + 2], &d[4 * e + 3]);
            assert_eq!((ab1[0], ab1[1]), (b[0], a[1]));
            assert_eq!((ab2[0], ab2[1]), (a[0], b[1]));
        }
    }

    /// Too few base points for Sobol indices are refused, naming the least; from it the
    /// design is accepted.
    #[test]
    fn a_saltelli_design_of_too_few_eyes_is_refused() {
        let text = |eyes: usize| {
            format!("eyes = {eyes}\ndesign = \"saltelli\"\nseed = 2\n[keys]\n\"growth.eta0\" = {{ dist = \"uniform\", low = 0, high = 1 }}\n")
        };
        for eyes in [2, 4, MIN_SALTELLI_EYES - 1] {
            let e = sample(&text(eyes)).unwrap_err().to_string();
            assert!(
                e.contains(&format!(
                    "eyes = {eyes}: the saltelli design needs at least 32 base points"
                )),
                "{e}"
            );
        }
        assert!(sample(&text(MIN_SALTELLI_EYES)).is_ok());
        // Other designs keep their least, 2.
        assert!(sample("eyes = 2\nseed = 2\n[keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 0, high = 1 }\n").is_ok());
    }
}
