//! Unit tests of scene parsing, overrides and validation.

use super::*;
use crate::bvp::settings::{LinearSolverKind, Scheme};
use crate::model::params::Thickness;

mod growth;
mod optics;
mod size;
mod surfaces;

use super::suggest::levenshtein;

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_toml_str(text, "x.toml", &[])
}

fn parse_set(text: &str, sets: &[&str]) -> Result<Scene, SceneError> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, "x.toml", &sets)
}

/// The error's one line, checked to be one line, to start with the origin and to name `key`.
fn err(r: Result<Scene, SceneError>, origin: &str, key: &str) -> String {
    let e = r.expect_err("expected an error").to_string();
    assert!(!e.contains('\n'), "not one line: {e:?}");
    assert!(
        e.starts_with(&format!("{origin}: ")),
        "origin {origin:?} not first: {e}"
    );
    assert!(e.contains(key), "key {key:?} not named: {e}");
    e
}

#[test]
fn empty_scene_is_the_defaults() {
    let s = parse("").unwrap();
    assert_eq!(s.params, Params::default());
    assert_eq!(s.solver, SolverSettings::default());
    assert_eq!(s.name, None);
    assert_eq!(s.display_name(), "x");
}

#[test]
fn every_key_is_read() {
    let s = parse(
        r#"
        name = "all"
        description = "every key"
        [pressure]
        dP = 3
        [material]
        C = 120.5
        bending = 20
        thickness = "nonuniform"
        H0 = 0.7
        [fibres]
        D = 200
        [cornea]
        C = 90
        H = 0.6
        R0 = 9
        [geometry]
        R0 = 11
        fraction = 0.75
        [solver]
        nodes = 101
        epsilon = 2e-3
        scheme = "trapezoid"
        linear = "klu"
        newton_tol = 1e-9
        max_newton = 20
        pole_grading = false
        "#,
    )
    .unwrap();
    let p = s.params;
    assert_eq!(
        (p.dp, p.c, p.e_b, p.thickness, p.h0, p.d),
        (3.0, 120.5, 20.0, Thickness::NonUniform, 0.7, 200.0)
    );
    assert_eq!(
        (p.cornea.c, p.cornea.h, p.cornea.r0, p.r0, p.fraction),
        (90.0, 0.6, 9.0, 11.0, 0.75)
    );
    let v = s.solver;
    assert_eq!(
        (v.nodes, v.epsilon, v.scheme, v.linear),
        (101, 2e-3, Scheme::Trapezoid, LinearSolverKind::Klu)
    );
    assert_eq!(
        (v.newton_tol, v.max_newton, v.pole_grading),
        (1e-9, 20, false)
    );
    assert_eq!(s.name.as_deref(), Some("all"));
    assert_eq!(s.display_name(), "all");
    assert_eq!(s.description.as_deref(), Some("every key"));
}

#[test]
fn dotted_keys_work_at_top_level() {
    let s = parse("pressure.dP = 1.5\nsolver.nodes = 11").unwrap();
    assert_eq!(s.params.dp, 1.5);
    assert_eq!(s.solver.nodes, 11);
}

#[test]
fn keys_are_unique_and_defaults_are_valid() {
    for (i, a) in KEYS.iter().enumerate() {
        for b in &KEYS[i + 1..] {
            assert_ne!(a.key, b.key);
        }
    }
    Scene::default().validate().unwrap();
}

#[test]
fn to_toml_reads_back() {
    let s = parse_set(
        "name = \"r\"\n[material]\nthickness = \"nonuniform\"",
        &["fibres.D=123.456789012345", "solver.scheme=trapezoid"],
    )
    .unwrap();
    let t = s.to_toml();
    let back = Scene::from_toml_str(&t, "x.toml", &[]).unwrap();
    assert_eq!(back.params, s.params);
    assert_eq!(back.solver, s.solver);
    assert_eq!(back.name, s.name);
}

#[test]
fn syntax_error_is_one_line_with_position() {
    let e = err(parse("[material]\nC = = 3\n"), "x.toml", "line 2");
    assert!(e.contains("invalid TOML"), "{e}");
}

#[test]
fn unknown_key_suggests_the_closest() {
    let e = err(parse("[material]\nc = 3"), "x.toml", "material.c");
    assert!(e.contains("did you mean 'material.C'"), "{e}");
    let e = err(parse("[pressure]\ndp = 3"), "x.toml", "pressure.dp");
    assert!(e.contains("'pressure.dP'"), "{e}");
    let e = err(parse("[solver]\nnode = 3"), "x.toml", "solver.node");
    assert!(e.contains("'solver.nodes'"), "{e}");
    let e = err(
        parse("[geometry]\nepsilon = 1e-3"),
        "x.toml",
        "geometry.epsilon",
    );
    assert!(e.contains("'solver.epsilon'"), "{e}");
    let e = err(parse("[material]\nwibble = 3"), "x.toml", "material.wibble");
    assert!(!e.contains("did you mean"), "{e}");
}

#[test]
fn unknown_section_suggests_the_closest() {
    let e = err(parse("[materail]\nC = 3"), "x.toml", "materail");
    assert!(
        e.contains("unknown section") && e.contains("[material]"),
        "{e}"
    );
    let e = err(parse("[groth]\neta0 = 70"), "x.toml", "groth");
    assert!(e.contains("unknown section"), "{e}");
}

#[test]
fn section_given_as_a_value_is_a_type_error() {
    let e = err(parse("material = 3"), "x.toml", "material");
    assert!(e.contains("must be a table"), "{e}");
}

#[test]
fn wrong_types() {
    let e = err(parse("[material]\nC = \"stiff\""), "x.toml", "material.C");
    assert!(
        e.contains("must be a number, found string \"stiff\""),
        "{e}"
    );
    let e = err(parse("[solver]\nnodes = 5.5"), "x.toml", "solver.nodes");
    assert!(e.contains("must be an integer"), "{e}");
    let e = err(
        parse("[solver]\npole_grading = 1"),
        "x.toml",
        "solver.pole_grading",
    );
    assert!(e.contains("true or false"), "{e}");
    let e = err(parse("[solver]\nscheme = 4"), "x.toml", "solver.scheme");
    assert!(e.contains("\"hermite-simpson\""), "{e}");
    let e = err(
        parse("[solver]\nscheme = \"rk4\""),
        "x.toml",
        "solver.scheme",
    );
    assert!(e.contains("must be one of"), "{e}");
    let e = err(
        parse("[material]\nthickness = \"thick\""),
        "x.toml",
        "material.thickness",
    );
    assert!(e.contains("\"uniform\", \"nonuniform\""), "{e}");
    let e = err(parse("name = 3"), "x.toml", "name");
    assert!(e.contains("must be a string"), "{e}");
    err(parse("[material]\nC = [1, 2]"), "x.toml", "material.C");
    err(parse("[material.C]\nx = 1"), "x.toml", "material.C");
}

#[test]
fn integers_are_accepted_for_floats() {
    let s = parse("[pressure]\ndP = 2\n[geometry]\nR0 = 12").unwrap();
    assert_eq!(s.params.dp, 2.0);
    assert_eq!(s.params.r0, 12.0);
}

#[test]
fn non_positive_moduli_and_lengths() {
    for key in [
        "material.C",
        "material.H0",
        "material.bending",
        "geometry.R0",
        "cornea.C",
        "cornea.H",
        "cornea.R0",
    ] {
        for v in ["0", "-1", "-0.0"] {
            let e = err(parse(&format!("{key} = {v}")), "x.toml", key);
            assert!(e.contains("must be positive"), "{e}");
        }
    }
    let e = err(parse("[material]\nC = -1"), "x.toml", "material.C");
    assert_eq!(e, "x.toml: material.C = -1 must be positive");
}

#[test]
fn negative_fibres_and_pressure() {
    let e = err(parse("fibres.D = -1"), "x.toml", "fibres.D");
    assert!(e.contains("must be non-negative"), "{e}");
    parse("fibres.D = 0").unwrap();
    let e = err(parse("pressure.dP = -0.5"), "x.toml", "pressure.dP");
    assert!(e.contains("must be non-negative"), "{e}");
    parse("pressure.dP = 0").unwrap();
}

#[test]
fn pressure_beyond_the_cornea_limit_names_the_limit() {
    let max = crate::model::cornea::max_pressure(&Params::default().cornea);
    parse(&format!("pressure.dP = {max:?}")).unwrap();
    let e = err(parse("pressure.dP = 30"), "x.toml", "pressure.dP");
    assert!(
        e.contains(&format!("{max:.6}")) && e.contains("cornea's limit"),
        "{e}"
    );
    // A weaker cornea lowers the limit: the limit follows the cornea keys.
    let e = err(
        parse_set("", &["cornea.C=10"]),
        "--set cornea.C=10",
        "pressure.dP",
    );
    let weak = crate::model::cornea::max_pressure(&crate::model::params::CorneaParams {
        c: 10.0,
        ..Params::default().cornea
    });
    assert!(e.contains(&format!("{weak:.6}")), "{e}");
}

#[test]
fn too_few_nodes() {
    let e = err(parse("solver.nodes = 4"), "x.toml", "solver.nodes");
    assert!(e.contains("between 5 and 1000000"), "{e}");
    let e = err(parse("solver.nodes = -3"), "x.toml", "solver.nodes");
    assert!(e.contains("between 5 and 1000000"), "{e}");
    parse("solver.nodes = 5").unwrap();
}

#[test]
fn epsilon_out_of_range() {
    for v in ["0", "-1e-3"] {
        let e = err(
            parse(&format!("solver.epsilon = {v}")),
            "x.toml",
            "solver.epsilon",
        );
        assert!(e.contains("must be positive"), "{e}");
    }
    let l = Params::default().length();
    for v in [l, 30.0] {
        let e = err(
            parse(&format!("solver.epsilon = {v:?}")),
            "x.toml",
            "solver.epsilon",
        );
        assert!(e.contains("must be below the shell's length L"), "{e}");
    }
    // L depends on R0 and fraction: ε = 1 is fine for the defaults but not for R0 = 1, f = 0.1.
    parse("solver.epsilon = 1").unwrap();
    err(
        parse("solver.epsilon = 1\ngeometry.R0 = 1\ngeometry.fraction = 0.1"),
        "x.toml",
        "solver.epsilon",
    );
}

#[test]
fn fraction_outside_the_unit_interval() {
    for v in ["0", "1", "1.5", "-0.2"] {
        let e = err(
            parse(&format!("geometry.fraction = {v}")),
            "x.toml",
            "geometry.fraction",
        );
        assert!(e.contains("strictly between 0 and 1"), "{e}");
    }
}

#[test]
fn nan_and_inf_are_rejected_from_file_and_set() {
    for v in ["nan", "inf", "-inf", "+inf", "-nan"] {
        for key in [
            "material.C",
            "pressure.dP",
            "fibres.D",
            "solver.epsilon",
            "solver.newton_tol",
            "geometry.fraction",
        ] {
            let e = err(parse(&format!("{key} = {v}")), "x.toml", key);
            assert!(e.contains("must be a finite number"), "{e}");
            let set = format!("{key}={v}");
            let e = err(parse_set("", &[&set]), &format!("--set {set}"), key);
            assert!(e.contains("must be a finite number"), "{e}");
        }
    }
}

#[test]
fn newton_settings() {
    for v in ["0", "-1e-10"] {
        let e = err(
            parse(&format!("solver.newton_tol = {v}")),
            "x.toml",
            "solver.newton_tol",
        );
        assert!(e.contains("must be positive"), "{e}");
    }
    let e = err(
        parse("solver.max_newton = 0"),
        "x.toml",
        "solver.max_newton",
    );
    assert!(e.contains("between 1 and 10000"), "{e}");
}

#[test]
fn overrides_win_over_the_file_and_later_overrides_win() {
    let file = "[pressure]\ndP = 3\n[solver]\nscheme = \"hermite-simpson\"";
    let s = parse_set(file, &["pressure.dP=4"]).unwrap();
    assert_eq!(s.params.dp, 4.0);
    let s = parse_set(file, &["pressure.dP=4", "pressure.dP = 1.25"]).unwrap();
    assert_eq!(s.params.dp, 1.25);
    assert_eq!(
        s.overrides,
        vec![
            "pressure.dP=4".to_string(),
            "pressure.dP = 1.25".to_string()
        ]
    );
    // Unquoted strings, quoted strings, booleans, integers.
    let s = parse_set(
        file,
        &[
            "solver.scheme=trapezoid",
            "solver.linear=\"klu\"",
            "solver.pole_grading=false",
            "solver.nodes=21",
        ],
    )
    .unwrap();
    assert_eq!(s.solver.scheme, Scheme::Trapezoid);
    assert_eq!(s.solver.linear, LinearSolverKind::Klu);
    assert!(!s.solver.pole_grading);
    assert_eq!(s.solver.nodes, 21);
    // The file is untouched by a key the overrides do not give.
    assert_eq!(s.params.dp, 3.0);
}

#[test]
fn override_can_repair_a_file_value_and_errors_name_the_last_origin() {
    // Validation is on the effective values: a good override repairs a bad file value.
    let s = parse_set("material.C = -1", &["material.C=50"]).unwrap();
    assert_eq!(s.params.c, 50.0);
    // ... and a bad override breaks a good file, named by its --set text.
    let e = err(
        parse_set("material.C = 50", &["material.C=-1"]),
        "--set material.C=-1",
        "material.C",
    );
    assert_eq!(e, "--set material.C=-1: material.C = -1 must be positive");
    // A cross-key error names whichever involved key was set last.
    let e = err(
        parse_set("solver.epsilon = 5", &["geometry.R0=1"]),
        "--set geometry.R0=1",
        "solver.epsilon",
    );
    assert!(e.contains("L = π·fraction·R0"), "{e}");
}

#[test]
fn bad_overrides() {
    let e = err(
        parse_set("", &["pressure.dP"]),
        "--set pressure.dP",
        "key=value",
    );
    assert!(e.contains("form key=value"), "{e}");
    err(parse_set("", &["=3"]), "--set =3", "key");
    let e = err(
        parse_set("", &["material.c=3"]),
        "--set material.c=3",
        "material.c",
    );
    assert!(e.contains("did you mean 'material.C'"), "{e}");
    let e = err(
        parse_set("", &["material.C=abc"]),
        "--set material.C=abc",
        "material.C",
    );
    assert!(e.contains("must be a number, found string \"abc\""), "{e}");
    let e = err(
        parse_set("", &["solver.scheme=rk4"]),
        "--set solver.scheme=rk4",
        "solver.scheme",
    );
    assert!(e.contains("must be one of"), "{e}");
    // Control characters never break the one line.
    let e = err(
        parse_set("", &["material.C=a\nb"]),
        "--set material.C=a\\nb",
        "material.C",
    );
    assert!(!e.contains('\n'));
}

#[test]
fn missing_file_is_one_line() {
    let e = Scene::from_file(Path::new("/nonexistent/dir/x.toml"), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("/nonexistent/dir/x.toml: cannot read the scene"),
        "{e}"
    );
    assert!(!e.contains('\n'));
}

#[test]
fn shipped_scenes_are_valid() {
    let d = Scene::from_toml_str(
        include_str!("../../../../../scenes/default.toml"),
        "default.toml",
        &[],
    )
    .unwrap();
    // default.toml gives cornea.R0, which then no longer follows geometry.R0.
    let given = Params {
        cornea_follows_radius: false,
        ..Params::default()
    };
    assert_eq!(d.params, given);
    assert_eq!(d.solver, SolverSettings::default());
    let f = Scene::from_toml_str(
        include_str!("../../../../../scenes/fibres-nonuniform.toml"),
        "f.toml",
        &[],
    )
    .unwrap();
    assert_eq!(f.params.thickness, Thickness::NonUniform);
    assert_eq!(f.params.d, 200.0);
    let e = Scene::from_toml_str(
        include_str!("../../../../../scenes/exact-sphere.toml"),
        "e.toml",
        &[],
    )
    .unwrap();
    assert_eq!(e.params, e.params.exact_sphere());
}

#[test]
fn closest_and_levenshtein() {
    assert_eq!(levenshtein("kitten", "sitting"), 3);
    assert_eq!(levenshtein("", "abc"), 3);
    assert_eq!(
        closest("SOLVER.NODES", KEYS.iter().map(|k| k.key)),
        Some("solver.nodes")
    );
    assert_eq!(closest("zzzzzz", KEYS.iter().map(|k| k.key)), None);
}
