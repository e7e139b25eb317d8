//! The refraction without growing: `eyeshell optics` writes the refraction of the loaded,
//! ungrown retina (refraction.csv, peripheral.csv), naked and through the lenses, at t = 0
//! and at each table time of an eye that changes with age; `eyeshell solve` reports
//! `refraction_D`. The naked eye's values are a growth run's first row.

use std::path::{Path, PathBuf};

use crate::support::*;

/// The small mesh every run here uses.
const NODES: &str = "solver.nodes=101";

/// `eyeshell optics SCENE` (on the small mesh, with `sets`) into `dir/name`.
fn optics(dir: &Path, name: &str, scene: &str, sets: &[&str]) -> (PathBuf, Run) {
    let out = dir.join(name);
    let mut args = vec!["optics", scene, "--set", NODES];
    for s in sets {
        args.extend_from_slice(&["--set", s]);
    }
    args.extend_from_slice(&["--out", s(&out)]);
    let run = ok(&args);
    (out, run)
}

/// The first output of a growth run of `scene` that barely grows (t_end = 1e-6): its
/// series.csv row at t = 0 and its peripheral.csv rows at t = 0.
fn first_row(dir: &Path, scene: &str) -> (Vec<String>, Vec<f64>, Vec<Vec<f64>>) {
    let out = dir.join("grown");
    let _ = std::fs::remove_dir_all(&out);
    ok(&[
        "grow",
        scene,
        "--set",
        NODES,
        "--set",
        "growth.t_end=1e-6",
        "--set",
        "output.times=[1e-6]",
        "--set",
        "output.history_points=0",
        "--out",
        s(&out),
        "--quiet",
    ]);
    // The class is a word: NaN among the numbers.
    let (header, rows) = csv_cells(&out.join("series.csv"));
    let first = rows[0]
        .iter()
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    // A scene with lenses adds the rows through them: the naked eye's are `naked`.
    let peripheral = match csv_cells(&out.join("peripheral.csv")).0.len() {
        4 => csv(&out.join("peripheral.csv")).1,
        _ => rows_of(&out.join("peripheral.csv"), "naked", 0),
    };
    let at0 = peripheral.into_iter().filter(|r| r[0] == 0.0).collect();
    (header, first, at0)
}

/// The rows of a refraction file (refraction.csv or peripheral.csv) through `through`
/// (`naked`, `lenses`), image `image`: its numeric cells before `through`.
fn rows_of(path: &Path, through: &str, image: usize) -> Vec<Vec<f64>> {
    let (header, rows) = csv_cells(path);
    let k = header.iter().position(|c| c == "through").unwrap();
    rows.iter()
        .filter(|r| r[k] == through && r[k + 1] == image.to_string())
        .map(|r| r[..k].iter().map(|v| v.parse().unwrap()).collect())
        .collect()
}

/// The naked eye's refraction of `eyeshell optics` equals a growth run's first row to 1e-6 D,
/// at the pole and at every field, for the eye without a lens, with a −2 D spectacle lens and
/// with a dual-focus contact lens (a growth run's refraction is the naked eye's whatever it
/// wears). Through the spectacle lens at 12 mm, the trial lens held in contact with it, the
/// refraction is the naked eye's plus 2 D to the tables' error (1e-5 D at the pole, 0.005 D
/// at every field); through the
/// MiSight-like contact lens each image has its own, the 0 D rings' the naked eye's, and the
/// shares of the two images sum to 1 at every field.
#[test]
fn optics_gives_a_growth_runs_first_refraction_naked_and_through_the_lenses() {
    let dir = tempfile::tempdir().unwrap();
    for scene in [
        "scenes/eyewear/none.toml",
        "scenes/eyewear/single-vision.toml",
        "scenes/eyewear/misight.toml",
    ] {
        let (out, run) = optics(dir.path(), "eye", scene, &[]);
        assert!(
            run.stdout
                .contains("refraction at the pole at t = 0: +10.462 D naked"),
            "{scene}: {}",
            run.stdout
        );
        let (header, series, peripheral) = first_row(dir.path(), scene);
        let j = header.iter().position(|c| c == "refraction_D").unwrap();
        let pole = rows_of(&out.join("refraction.csv"), "naked", 0);
        assert_eq!(pole.len(), 1, "{scene}");
        // t, axial_length, refraction_D: the growth run's t = 0 retina and its refraction.
        assert_eq!(pole[0][0], 0.0);
        assert!(
            (pole[0][1] - series[1]).abs() < 1e-9,
            "{scene}: {pole:?} {series:?}"
        );
        assert!(
            (pole[0][2] - series[j]).abs() < 1e-6,
            "{scene}: {pole:?} {series:?}"
        );
        let naked = rows_of(&out.join("peripheral.csv"), "naked", 0);
        assert_eq!(naked.len(), 9, "{scene}");
        assert_eq!(naked.len(), peripheral.len(), "{scene}");
        for (a, b) in naked.iter().zip(&peripheral) {
            // t, field_deg, refraction_D, relative_D, as the growth run's columns.
            assert_eq!(a[..2], b[..2], "{scene}");
            assert!(
                (a[2] - b[2]).abs() < 1e-6 && (a[3] - b[3]).abs() < 1e-6,
                "{scene}: {a:?} {b:?}"
            );
        }
        let through = rows_of(&out.join("refraction.csv"), "lenses", 0);
        match scene {
            "scenes/eyewear/none.toml" => assert!(through.is_empty()),
            "scenes/eyewear/single-vision.toml" => {
                assert!(
                    (through[0][2] - pole[0][2] - 2.0).abs() < 1e-5,
                    "{through:?} {pole:?}"
                );
                let worn = rows_of(&out.join("peripheral.csv"), "lenses", 0);
                assert_eq!(worn.len(), 9);
                assert!((worn[0][2] - through[0][2]).abs() < 1e-3, "{worn:?}");
                // At every field the trial lens and the −2 D lens at 12 mm are one thin lens:
                // the naked eye's + 2 D, to the two tables' error (each within 1e-3 mm of
                // its traced foci, about 0.0025 D).
                for (w, n) in worn.iter().zip(&naked) {
                    assert!((w[2] - n[2] - 2.0).abs() < 0.005, "{w:?} {n:?}");
                }
            }
            _ => {
                let other = rows_of(&out.join("refraction.csv"), "lenses", 1);
                // The −2 D centre: 1.4 to 2 D more plus (a contact lens at the cornea is
                // weaker at 12 mm, and its pencil is 0.98 of the pupil); the 0 D rings: the naked eye's.
                assert!(
                    through[0][2] > pole[0][2] + 1.4 && through[0][2] < pole[0][2] + 2.0,
                    "{through:?}"
                );
                assert!(
                    (other[0][2] - pole[0][2]).abs() < 1e-5,
                    "{other:?} {pole:?}"
                );
                let (header, rows) = csv_cells(&out.join("peripheral.csv"));
                let share = header.iter().position(|c| c == "share").unwrap();
                let image = share - 2;
                assert_eq!(header[image + 1], "image_power_D");
                for field in (0..=40).step_by(5) {
                    let sum: f64 = rows
                        .iter()
                        .filter(|r| {
                            r[1].parse::<f64>().unwrap() == field as f64 && r[image - 1] == "lenses"
                        })
                        .map(|r| r[share].parse::<f64>().unwrap())
                        .sum();
                    assert!((sum - 1.0).abs() < 1e-12, "{field}°: {sum}");
                }
            }
        }
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("optics.json")).unwrap())
                .unwrap();
        assert_eq!(
            j["refraction"]["at"][0]["refraction_D"].as_f64(),
            Some(pole[0][2])
        );
        assert_eq!(
            j["refraction"]["axial_length_mm"].as_f64(),
            Some(pole[0][1])
        );
    }
}

/// An eye that changes with age is refracted at each of its table times, the retina the
/// ungrown one throughout: at t = 0 as the growth run's first row, at t = 1 as the same eye
/// with its t = 1 values fixed, and more hyperopic as the cornea flattens.
#[test]
fn an_eye_that_changes_with_age_is_refracted_at_each_table_time() {
    let dir = tempfile::tempdir().unwrap();
    let scene = "scenes/optics-age.toml";
    let quick = "optics.max_field=10";
    let (out, run) = optics(dir.path(), "age", scene, &[quick]);
    assert!(
        run.stdout.contains("(and at 4 more table times)"),
        "{}",
        run.stdout
    );
    let pole = rows_of(&out.join("refraction.csv"), "naked", 0);
    let times: Vec<f64> = pole.iter().map(|r| r[0]).collect();
    assert_eq!(times, [0.0, 0.08, 0.2, 0.44, 1.0]);
    assert!(pole.iter().all(|r| r[1] == pole[0][1]), "{pole:?}");
    assert!(pole.windows(2).all(|w| w[1][2] > w[0][2]), "{pole:?}");
    assert!(pole[4][2] > pole[0][2] + 2.0, "{pole:?}");
    let (header, series, _) = first_row(dir.path(), scene);
    let j = header.iter().position(|c| c == "refraction_D").unwrap();
    assert!((pole[0][2] - series[j]).abs() < 1e-6, "{pole:?} {series:?}");
    let fixed = "optics.surfaces=[{ radius = 7.77 }, { thickness = 3.15 }]";
    let (out1, _) = optics(dir.path(), "fixed", scene, &[quick, fixed]);
    let pole1 = rows_of(&out1.join("refraction.csv"), "naked", 0);
    assert_eq!(pole1.len(), 1);
    assert!(
        (pole1[0][2] - pole[4][2]).abs() < 1e-6,
        "{pole1:?} {pole:?}"
    );
    let peripheral = rows_of(&out.join("peripheral.csv"), "naked", 0);
    let peripheral1 = rows_of(&out1.join("peripheral.csv"), "naked", 0);
    assert_eq!(peripheral.len(), 5 * 3);
    for (a, b) in peripheral[12..].iter().zip(&peripheral1) {
        assert!((a[2] - b[2]).abs() < 1e-6, "{a:?} {b:?}");
    }
}

/// `eyeshell solve` reports the pole's refraction (summary.json's `refraction_D`, and its
/// summary line): a growth run's first for a growing scene; for a scene that does not grow,
/// through its own optics with `stimulus.source = "optics"`, and none without (neither key
/// nor line: an elastic scene of the shell alone has no eye to refract through).
#[test]
fn solve_reports_the_refraction_or_why_there_is_none() {
    let dir = tempfile::tempdir().unwrap();
    let solve = |name: &str, scene: &str, sets: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["solve", scene, "--set", NODES];
        for s in sets {
            args.extend_from_slice(&["--set", s]);
        }
        args.extend_from_slice(&["--out", s(&out)]);
        let run = ok(&args);
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        (run.stdout, j)
    };
    let scene = "scenes/eyewear/single-vision.toml";
    let (stdout, j) = solve("grows", scene, &[]);
    let (header, series, _) = first_row(dir.path(), scene);
    let k = header.iter().position(|c| c == "refraction_D").unwrap();
    assert!(
        (j["refraction_D"].as_f64().unwrap() - series[k]).abs() < 1e-6,
        "{j}"
    );
    assert!(
        stdout.contains("refraction_D    +10.462 D (at the pole, naked eye)"),
        "{stdout}"
    );
    let (stdout, j) = solve("none", "scenes/default.toml", &[]);
    assert!(j.get("refraction_D").is_none(), "{j}");
    assert!(!stdout.contains("refraction"), "{stdout}");
    // The four-surface eye's own refraction of the default shell (19.96 mm long against
    // the eye's 24 mm): strongly hyperopic.
    let (_, j) = solve(
        "own",
        "scenes/four-surfaces.toml",
        &["stimulus.source=optics"],
    );
    let d = j["refraction_D"].as_f64().unwrap();
    assert!(d > 5.0 && d < 25.0, "{d}");
}

/// Bad input: a real spectacle lens across the spectacle plane leaves the trial lens of the
/// refraction through the lenses nowhere: one line naming the lens's vertex, exit 2, nothing
/// written.
#[test]
fn a_lens_across_the_spectacle_plane_is_refused_naming_its_vertex() {
    let scene = "growth.eta0 = 70\nsolver.nodes = 51\nstimulus.source = \"optics\"\n";
    fails(
        "optics",
        scene,
        &["optics.lenses=[{ front_radius = 100, back_radius = 80, thickness = 2, index = 1.5 }]"],
        "optics.lenses[0].vertex = 12 puts a real lens across the spectacle plane (12 mm)",
        "--set optics.lenses=",
    );
}

/// A scene that counts in years ends each row in the age, as a growth run's files do: the
/// corrected myope of scenes/myopia/single-vision.toml at 8 years, −2 D naked and corrected
/// through its −2 D spectacle lens (the naked eye's + 2 D, to the tables' 1e-5 D).
#[test]
fn a_scene_in_years_ends_its_rows_in_the_age() {
    let dir = tempfile::tempdir().unwrap();
    let (out, _) = optics(dir.path(), "years", "scenes/myopia/single-vision.toml", &[]);
    for file in ["refraction.csv", "peripheral.csv"] {
        let (header, rows) = csv_cells(&out.join(file));
        assert_eq!(header.last().unwrap(), "age", "{file}");
        assert!(rows.iter().all(|r| r.last().unwrap() == "8.0"), "{file}");
    }
    let naked = rows_of(&out.join("refraction.csv"), "naked", 0)[0][2];
    let through = rows_of(&out.join("refraction.csv"), "lenses", 0)[0][2];
    assert!((naked + 1.98).abs() < 0.01, "{naked}");
    assert!((through - naked - 2.0).abs() < 1e-5, "{through} {naked}");
}
