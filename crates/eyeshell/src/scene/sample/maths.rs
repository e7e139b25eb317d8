//! The sampling mathematics: the Gaussian copula, the normal distribution's CDF and
//! quantile, and the generator of the bootstrap's resamples.

/// `u` through the Gaussian copula of Cholesky factor `l`.
pub(super) fn copula(l: &[Vec<f64>], u: &[f64]) -> Vec<f64> {
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
pub(super) struct SplitMix64(u64);

impl SplitMix64 {
    pub(super) fn new(seed: u64, stream: u64, tag: u64) -> SplitMix64 {
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
    pub(super) fn unit(&mut self) -> f64 {
        ((self.next() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Uniform in 0..n (n ≥ 1), by rejection: no modulo bias.
    pub(super) fn below(&mut self, n: usize) -> usize {
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
