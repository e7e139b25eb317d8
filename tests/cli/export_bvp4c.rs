//! The elastic export is bvp4c's: on the non-uniform fibre shell, `yp` is
//! f(x, y) of docs/MODEL.md §3 at every point of x (checked against the equations written
//! out here from the export's own fields, not from eyeshell's code), each interface of the
//! material data (a, b, Σ_e) is in x twice with its one-sided values, and deval's cubic
//! Hermite on (x, y, yp) reproduces `eyeshell solve --at` at the quarter points of every
//! interval (a difference of the node values as yp would miss r′ − α_s cos θ by about 1e-7
//! at N = 201).

use crate::support::*;
use eyeshell::interop::npz;
use std::f64::consts::PI;
use std::path::Path;

/// (x, y rows, yp rows, named extra rows) of the .npz export of a fibres-nonuniform solve
/// at `nodes`, with `--at` written at `at` when given.
struct Export {
    x: Vec<f64>,
    y: Vec<Vec<f64>>,
    yp: Vec<Vec<f64>>,
    arrays: Vec<(String, npz::NpyArray)>,
}

impl Export {
    fn extra(&self, name: &str) -> &[f64] {
        &self.arrays.iter().find(|(n, _)| n == name).unwrap().1.data
    }
}

fn solve_and_export(dir: &Path, nodes: usize, at: Option<&str>) -> Export {
    let run = dir.join(format!("solve{nodes}"));
    let n = format!("solver.nodes={nodes}");
    let mut args = vec![
        "solve",
        "scenes/fibres-nonuniform.toml",
        "--set",
        &n,
        "--out",
        s(&run),
        "--quiet",
    ];
    if let Some(at) = at {
        args.extend(["--at", at]);
    }
    ok(&args);
    let file = dir.join(format!("solve{nodes}.npz"));
    ok(&["export", s(&run), "--npz", s(&file), "--quiet"]);
    let arrays = npz::read(&file).unwrap();
    let get = |name: &str| arrays.iter().find(|(n, _)| n == name).unwrap().1.clone();
    let x = get("x").data;
    let m = x.len();
    let rows = |a: npz::NpyArray| {
        assert_eq!(a.shape, vec![5, m]);
        a.data.chunks(m).map(<[f64]>::to_vec).collect::<Vec<_>>()
    };
    Export {
        x,
        y: rows(get("y")),
        yp: rows(get("yp")),
        arrays,
    }
}

#[test]
fn yp_is_f_and_the_interfaces_are_repeated() {
    let dir = tempfile::tempdir().unwrap();
    let e = solve_and_export(dir.path(), 201, None);
    let (eb, dp) = (18.0, 2.0); // the scene's material.bending and pressure.dP
    let (t_s, t_phi) = (e.extra("t_s"), e.extra("t_phi"));
    let mut worst = [0.0f64; 4];
    for k in 0..e.x.len() {
        let [kappa, a, r, th, q] = std::array::from_fn(|i| e.y[i][k]);
        // docs/MODEL.md §3 in σ = Σ (the ungrown shell).
        let f = [
            a * ((th.sin() / r - kappa) * th.cos() / r - q / (r * eb)),
            a * th.cos(),
            a * kappa,
            a * (r * dp - kappa * r * t_s[k] - th.sin() * t_phi[k]),
        ];
        for (w, (i, fi)) in worst
            .iter_mut()
            .zip([(0, f[0]), (2, f[1]), (3, f[2]), (4, f[3])])
        {
            *w = w.max((e.yp[i][k] - fi).abs() / fi.abs().max(1.0));
        }
    }
    assert!(
        worst[1] <= 1e-10 && worst[2] <= 1e-10,
        "r′, θ′ − f: {worst:?}"
    );
    assert!(
        worst[0] <= 1e-9 && worst[3] <= 1e-9,
        "κ′, Q′ − f: {worst:?}"
    );

    // a, b, Σ_e twice each, and nothing else repeated.
    let se = PI * 10.0 / 2.0;
    let repeated: Vec<f64> =
        e.x.windows(2)
            .filter(|w| w[0] == w[1])
            .map(|w| w[0])
            .collect();
    assert_eq!(repeated.len(), 3, "{repeated:?}");
    for (got, want) in repeated.iter().zip([se / 20.0, se / 4.0, se]) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
    // At Σ_e the thickness jumps: α_s (and h) differ between the two copies, t_s does not.
    let k = e.x.iter().position(|&x| x == repeated[2]).unwrap();
    assert_ne!(e.y[1][k], e.y[1][k + 1], "α_s from below and above at Σ_e");
    assert_eq!(t_s[k], t_s[k + 1]);
    assert_ne!(e.extra("h")[k], e.extra("h")[k + 1]);
    assert!(e.x.windows(2).all(|w| w[0] <= w[1]));
}

#[test]
fn deval_on_the_export_reproduces_solve_at() {
    let dir = tempfile::tempdir().unwrap();
    let first = solve_and_export(dir.path(), 801, None);
    let x = &first.x;
    // The quarter points of every interval (not of a repeated interface's empty one).
    let mut pts = Vec::new();
    for w in x.windows(2).filter(|w| w[1] > w[0]) {
        pts.extend([0.25, 0.5, 0.75].map(|t| w[0] + t * (w[1] - w[0])));
    }
    let list: Vec<String> = pts.iter().map(|p| format!("{p:?}")).collect();
    let e = solve_and_export(&dir.path().join("at"), 801, Some(&list.join(",")));
    assert_eq!(&e.x, x);
    let at = dir.path().join("at/solve801/at.csv");
    let names = ["kappa", "alpha_s", "r", "theta", "Q"];
    for (row, name) in names.iter().enumerate() {
        let want = column(&at, name);
        assert_eq!(want.len(), pts.len());
        let mut worst = (0.0f64, 0.0);
        for (p, w) in pts.iter().zip(&want) {
            // deval: the interval [x_i, x_{i+1}] with x_i ≤ p < x_{i+1}.
            let i = x.partition_point(|&v| v <= *p) - 1;
            let h = x[i + 1] - x[i];
            let t = (p - x[i]) / h;
            let (y, yp) = (&e.y[row], &e.yp[row]);
            let v = (2.0 * t.powi(3) - 3.0 * t * t + 1.0) * y[i]
                + (t.powi(3) - 2.0 * t * t + t) * h * yp[i]
                + (-2.0 * t.powi(3) + 3.0 * t * t) * y[i + 1]
                + (t.powi(3) - t * t) * h * yp[i + 1];
            if (v - w).abs() > worst.0 {
                worst = ((v - w).abs(), *p);
            }
        }
        // On κ, r, θ deval's cubic is --at's own (the same node values and slopes f); on
        // α_s and Q, which --at takes from the interpolated t_s and r q_s, both are O(h⁴).
        let tol = if matches!(*name, "alpha_s" | "Q") {
            1e-8
        } else {
            1e-12
        };
        assert!(
            worst.0 <= tol,
            "{name}: deval − --at = {:.2e} at Σ = {}",
            worst.0,
            worst.1
        );
    }
}
