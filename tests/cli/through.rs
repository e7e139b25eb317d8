//! The refraction through the worn lens in a growth run's peripheral.csv (docs/guide/outputs.md,
//! docs/guide/eyewear.md): for a scene whose eye wears lenses, after the naked eye's rows, the
//! rows through each image of the lenses with its share of the light, at every output time for
//! the retina at that time; at t = 0 the rows `eyeshell optics` writes; at every time and field
//! the spectacle power that puts the field's focus on the retina, to 0.01 D of a direct trace.

use std::path::{Path, PathBuf};

use eyeshell_optics::lens::{wear, Lens};
use eyeshell_optics::{best_focus_with, Criterion};

use crate::support::*;

/// `eyeshell grow` of the scene file `scene` with `sets` into `dir/name`, without history.
fn grow(dir: &Path, name: &str, scene: &str, sets: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec!["grow", scene, "--set", "output.history_points=0"];
    for s in sets {
        args.extend_from_slice(&["--set", s]);
    }
    args.extend_from_slice(&["--out", s(&out), "--quiet"]);
    ok(&args);
    out
}

/// The rows of a peripheral.csv at time `t` (its first cell parsed).
fn rows_at(path: &Path, t: f64) -> (Vec<String>, Vec<Vec<String>>) {
    let (header, rows) = csv_cells(path);
    let rows = (rows.into_iter())
        .filter(|r| r[0].parse::<f64>().unwrap() == t)
        .collect();
    (header, rows)
}

/// At t = 0 a growth run's peripheral.csv is `eyeshell optics`'s, row for row: the same
/// columns, the naked eye's rows and then each image's through the lenses, the same words
/// and shares, and every number within 1e-9 D: through a −2 D spectacle lens (one image)
/// and a dual-focus contact lens (two, whose shares sum to 1 at every field). Without a lens
/// the growth run keeps its four columns.
#[test]
fn at_the_start_a_growth_runs_peripheral_rows_are_eyeshell_optics() {
    let dir = tempfile::tempdir().unwrap();
    let quick = [
        "solver.nodes=101",
        "growth.t_end=1e-6",
        "output.times=[1e-6]",
    ];
    for (scene, images) in [
        ("scenes/eyewear/single-vision.toml", 1),
        ("scenes/eyewear/dual-focus.toml", 2),
    ] {
        let grown = grow(dir.path(), "grown", scene, &quick);
        let optics = dir.path().join("optics");
        ok(&[
            "optics",
            scene,
            "--set",
            "solver.nodes=101",
            "--out",
            s(&optics),
        ]);
        let (gh, g) = rows_at(&grown.join("peripheral.csv"), 0.0);
        let (oh, o) = rows_at(&optics.join("peripheral.csv"), 0.0);
        assert_eq!(gh, oh, "{scene}");
        assert_eq!(
            gh,
            [
                "t",
                "field_deg",
                "refraction_D",
                "relative_D",
                "through",
                "image",
                "image_power_D",
                "share"
            ]
        );
        assert_eq!(g.len(), 9 * (1 + images), "{scene}");
        assert_eq!(g.len(), o.len(), "{scene}");
        for (a, b) in g.iter().zip(&o) {
            assert_eq!(a[4..], b[4..], "{scene}: {a:?} {b:?}");
            for k in 0..4 {
                let (x, y): (f64, f64) = (a[k].parse().unwrap(), b[k].parse().unwrap());
                assert!(
                    x.is_finite() && (x - y).abs() < 1e-9,
                    "{scene}: {a:?} {b:?}"
                );
            }
        }
        let lenses: Vec<_> = g.iter().filter(|r| r[4] == "lenses").collect();
        assert_eq!(lenses.len(), 9 * images, "{scene}");
        for field in (0..=40).step_by(5) {
            let of_field = lenses.iter().filter(|r| r[1] == format!("{field}.0"));
            let sum: f64 = of_field.map(|r| r[7].parse::<f64>().unwrap()).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{scene} at {field}°: {sum}");
        }
    }
    let bare = grow(dir.path(), "bare", "scenes/eyewear/none.toml", &quick);
    let (header, rows) = csv_cells(&bare.join("peripheral.csv"));
    assert_eq!(header, ["t", "field_deg", "refraction_D", "relative_D"]);
    assert_eq!(rows.len(), 2 * 9);
}

/// The retina of a snapshot file: its nodes' (z, r), pole first.
fn retina(path: &Path) -> Vec<(f64, f64)> {
    let (h, rows) = csv(path);
    let z = h.iter().position(|c| c == "z_retina").unwrap();
    let r = h.iter().position(|c| c == "r_retina").unwrap();
    rows.iter().map(|row| (row[z], row[r])).collect()
}

/// How far the point (z, y) lies behind `retina` along the ray from the axis point `z_c`:
/// its distance from z_c less the retina's there, the retina's distance interpolated
/// linearly in the polar angle between its nodes (the first node's before it).
fn behind(retina: &[(f64, f64)], z_c: f64, (z, y): (f64, f64)) -> f64 {
    let polar = |(z, r): (f64, f64)| (r.abs().atan2(z - z_c), r.hypot(z - z_c));
    let (phi, rho) = polar((z, y));
    let nodes: Vec<(f64, f64)> = retina.iter().map(|&p| polar(p)).collect();
    if phi <= nodes[0].0 {
        return rho - nodes[0].1;
    }
    for w in nodes.windows(2) {
        let ((p0, r0), (p1, r1)) = (w[0], w[1]);
        if p0 <= phi && phi <= p1 {
            return rho - (r0 + (phi - p0) / (p1 - p0) * (r1 - r0));
        }
    }
    panic!("the retina does not reach φ = {phi}");
}

/// The spectacle power at 12 mm that puts the mean-sphere focus of `field` on `retina`,
/// each power traced directly: the focus is placed from the sagittal and tangential foci
/// the exact tracer finds along the chief ray (the mean of their vergences), and the power
/// found by the secant method, bracketed, to 1e-8 D. `worn(F)` is the eye with the trial
/// lens of power F, `pupil` the naked eye's stop; `guess` starts the bracket.
fn exact_refraction(
    worn: &dyn Fn(f64) -> eyeshell_optics::OpticalSystem,
    spec: &eyeshell::model::optics::OpticsSpec,
    pupil: &eyeshell_optics::Pupil,
    field: f64,
    retina: &[(f64, f64)],
    z_c: f64,
    guess: f64,
) -> f64 {
    let g = |f: f64| {
        let focus = best_focus_with(
            &worn(f),
            spec.refraction_wavelength,
            field,
            pupil,
            spec.criterion(),
            &spec.focus_settings(),
        )
        .unwrap();
        let s = 2.0 / (1.0 / focus.sagittal + 1.0 / focus.tangential);
        let (q, d) = (focus.chief_exit, focus.chief_direction);
        behind(retina, z_c, (q.0 + s * d.0, q.1 + s * d.1))
    };
    let (mut a, mut b) = (guess - 0.25, guess + 0.25);
    let (mut ga, mut gb) = (g(a), g(b));
    assert!(ga > 0.0 && gb < 0.0, "no bracket at {field}°: {ga} {gb}");
    for _ in 0..60 {
        // Illinois: the secant within the bracket, halving a stuck end's weight.
        let m = b - gb * (b - a) / (gb - ga);
        let gm = g(m);
        if (gm > 0.0) == (ga > 0.0) {
            a = m;
            ga = gm;
            gb *= 0.5;
        } else {
            b = m;
            gb = gm;
            ga *= 0.5;
        }
        if (b - a).abs() < 1e-8 || gm == 0.0 {
            return m;
        }
    }
    0.5 * (a + b)
}

/// The growth run of the built-in eye `eye` through a −2 D spectacle lens (scenes/eyewear/
/// single-vision.toml of that eye, few nodes, three output times) into `dir`: its output
/// directory and the scene.
fn run_of(dir: &Path, eye: &str) -> (PathBuf, eyeshell::Scene) {
    let text = std::fs::read_to_string("scenes/eyewear/single-vision.toml")
        .unwrap()
        .replace("eye = \"atchison-2006\"", &format!("eye = \"{eye}\""));
    let scene_path = dir.join(format!("{eye}.toml"));
    std::fs::write(&scene_path, &text).unwrap();
    let sets = ["solver.nodes=101", "output.times=[0.25, 0.5, 1.0]"];
    let out = grow(dir, eye, s(&scene_path), &sets);
    (out, eyeshell::Scene::from_path(&scene_path).unwrap())
}

const NAVARRO: &str = "escudero-sanz-navarro-1999";

/// The Navarro eye's growth run through a −2 D spectacle lens gives a refraction at every
/// output time and every field to 40°, naked and through the lens: 4 × 18 rows, none NaN
/// (where a strong trial lens forms no focus at a wide field, the table's interval is read
/// from the traced powers on its other side).
#[test]
fn the_navarro_eyes_peripheral_refraction_has_no_nan() {
    let dir = tempfile::tempdir().unwrap();
    let (out, _) = run_of(dir.path(), NAVARRO);
    let (header, rows) = csv_cells(&out.join("peripheral.csv"));
    assert_eq!(header[4], "through");
    assert_eq!(rows.len(), 4 * 18);
    for row in &rows {
        let d: f64 = row[2].parse().unwrap();
        assert!(d.is_finite(), "{row:?}");
    }
}

/// The must-show: the Navarro eye's growth run through a −2 D spectacle lens, at every
/// output time and every field to 40°, naked and through the lens, within 0.01 D of a
/// direct trace of the same eye onto that time's retina (the trial lens held in contact with
/// the spectacle lens: one thin lens of their summed power). The worst row is 9.0e-4 D (40°
/// at t = 0.25, naked). What holds the wide fields is the table's halved intervals: on its
/// 2.5 D grid alone, where the focus runs steeply forward with plus power, the cubic misses
/// by 0.17 D at 40°. The default Atchison eye, whose naked rows read the kept tables, holds
/// the same bound (on the grid alone it misses by 0.11 D at 40° at t = 0).
#[test]
fn the_peripheral_refraction_is_a_direct_traces_to_a_hundredth_dioptre() {
    let dir = tempfile::tempdir().unwrap();
    for eye in [NAVARRO, "atchison-2006"] {
        let (worst, at) = worst_against_direct_trace(dir.path(), eye);
        eprintln!("{eye}: worst {worst:.2e} D at {at}");
        assert!(worst < 0.01, "{eye}: worst {worst} D at {at}");
    }
}

/// The largest difference (D) of the peripheral.csv of `eye`'s run ([`run_of`]) from a
/// direct trace ([`exact_refraction`]) over every output time, field and eye, and where.
fn worst_against_direct_trace(dir: &Path, eye_name: &str) -> (f64, String) {
    let (out, scene) = run_of(dir, eye_name);
    let spec = scene.optics().clone();
    assert_eq!(spec.criterion(), Criterion::MeanSphere);
    assert!(spec.times().is_empty());
    let z_c = scene.blue().z_b;
    let eye = spec.system().unwrap();
    let pupil = spec.pupil_stop(&eye);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let snapshots = summary["snapshots"].as_array().unwrap();
    assert_eq!(snapshots.len(), 4);
    let mut worst = (0.0_f64, String::new());
    for snap in snapshots {
        let t = snap["t"].as_f64().unwrap();
        let retina = retina(&out.join(snap["file"].as_str().unwrap()));
        let (_, rows) = rows_at(&out.join("peripheral.csv"), t);
        assert_eq!(rows.len(), 18, "t {t}");
        for row in &rows {
            let field: f64 = row[1].parse().unwrap();
            let d: f64 = row[2].parse().unwrap();
            assert!(d.is_finite(), "t {t}: {row:?}");
            let worn = |f: f64| {
                let lens = match row[4].as_str() {
                    "naked" => Lens::spectacle(f, 12.0),
                    _ => Lens::spectacle(f - 2.0, 12.0),
                };
                wear(&eye, &[lens]).unwrap()
            };
            let exact = exact_refraction(&worn, &spec, &pupil, field, &retina, z_c, d);
            let error = (d - exact).abs();
            if error > worst.0 {
                worst = (error, format!("t {t}, {field}°, {}", row[4]));
            }
        }
    }
    worst
}
