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
    assert!(sample(
        "eyes = 2\nseed = 2\n[keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 0, high = 1 }\n"
    )
    .is_ok());
}
