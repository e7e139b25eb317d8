//! Unit tests of scene parsing, overrides and validation.

use super::*;
use crate::bvp::settings::{LinearSolverKind, Scheme};
use crate::model::params::Thickness;

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
        include_str!("../../../../scenes/default.toml"),
        "default.toml",
        &[],
    )
    .unwrap();
    assert_eq!(d.params, Params::default());
    assert_eq!(d.solver, SolverSettings::default());
    let f = Scene::from_toml_str(
        include_str!("../../../../scenes/fibres-nonuniform.toml"),
        "f.toml",
        &[],
    )
    .unwrap();
    assert_eq!(f.params.thickness, Thickness::NonUniform);
    assert_eq!(f.params.d, 200.0);
    let e = Scene::from_toml_str(
        include_str!("../../../../scenes/exact-sphere.toml"),
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

// ---- Growth keys -------------------------------------------------------------------------

use crate::growth::{GrowthParams, GrowthSettings, Integrator, ThicknessLaw};
use crate::model::stimulus::{Surface, RED_OFFSET};

#[test]
fn a_scene_without_growth_keys_is_elastic() {
    let s = parse("[pressure]\ndP = 2").unwrap();
    assert_eq!(s.growth, None);
    assert_eq!(s.growth_settings, GrowthSettings::default());
    // Growth numerics and surfaces alone do not turn growth on.
    let s = parse_set(
        "[solver]\nrtol = 1e-4\nintegrator = \"euler\"\n[output]\ntimes = [0.5]\n[stimulus.blue]\nP3 = 24",
        &["solver.steps=10"],
    )
    .unwrap();
    assert_eq!(s.growth, None);
    assert_eq!(s.growth_settings.rtol, 1e-4);
    assert_eq!(s.growth_settings.steps, 10);
    assert_eq!(s.stimulus.blue.p3, 24.0);
    // ... and are not shown, written or summarised.
    for (k, _) in s.entries() {
        assert!(!crate::scene::keys::find(k).unwrap().growth, "{k}");
    }
    assert!(!s.to_toml().contains("solver.rtol"));
    assert!(!s.to_toml().contains("growth."));
    assert!(s.parameters_json().get("growth.eta0").is_none());
    assert!(s.parameters_json().get("output.times").is_none());
}

#[test]
fn any_growth_key_turns_growth_on_with_defaults() {
    for text in [
        "[growth]\neta0 = 70",
        "growth.Gamma = 8",
        "[growth]\nthickness_law = \"none\"",
        "growth.t_end = 1",
    ] {
        let s = parse(text).unwrap();
        assert_eq!(s.growth, Some(GrowthParams::default()), "{text}");
    }
    let s = parse_set("", &["growth.delta=2"]).unwrap();
    assert_eq!(
        s.growth,
        Some(GrowthParams {
            delta: 2.0,
            ..GrowthParams::default()
        })
    );
    assert!(s.to_toml().contains("growth.delta = 2.0"));
    assert_eq!(s.parameters_json()["growth.delta"], 2.0);
    assert_eq!(
        s.parameters_json()["output.times"],
        serde_json::json!([0.1, 0.2, 0.4, 1.0])
    );
    assert_eq!(s.parameters_json()["stimulus.red.offset"], RED_OFFSET);
}

#[test]
fn every_growth_key_is_read() {
    let s = parse(
        r#"
        [growth]
        eta0 = 50
        Gamma = -3.5
        delta = 2
        t_end = 2.5
        thickness_law = "mass"
        [solver]
        integrator = "euler"
        rtol = 1e-5
        atol = 1e-9
        steps = 400
        [output]
        times = [0.5, 1, 2.5]
        [stimulus.blue]
        P1 = -4
        P2 = -8
        P3 = 23
        z_B = -0.5
        phi_max = 0.6
        [stimulus.red]
        P1 = -4.5
        P2 = -8.5
        P3 = 23.5
        z_B = -0.4
        phi_max = 0.55
        offset = 0.7
        "#,
    )
    .unwrap();
    let g = s.growth.clone().unwrap();
    assert_eq!(
        (g.eta0, g.gamma, g.delta, g.t_end, g.thickness_law),
        (50.0, -3.5, 2.0, 2.5, ThicknessLaw::Mass)
    );
    let blue = Surface {
        p1: -4.0,
        p2: -8.0,
        p3: 23.0,
        z_b: -0.5,
        phi_max: 0.6,
        offset: 0.0,
    };
    let red = Surface {
        p1: -4.5,
        p2: -8.5,
        p3: 23.5,
        z_b: -0.4,
        phi_max: 0.55,
        offset: 0.7,
    };
    assert_eq!((g.blue, g.red), (blue, red));
    let v = &s.growth_settings;
    assert_eq!(
        (v.integrator, v.rtol, v.atol, v.steps),
        (Integrator::Euler, 1e-5, 1e-9, 400)
    );
    assert_eq!(v.output_times, vec![0.5, 1.0, 2.5]);
    // The effective scene reads back whole.
    let back = Scene::from_toml_str(&s.to_toml(), "b.toml", &[]).unwrap();
    assert_eq!(back.growth, s.growth);
    assert_eq!(back.growth_settings, s.growth_settings);
}

#[test]
fn growth_overrides() {
    let s = parse_set(
        "",
        &[
            "growth.eta0=0",
            "growth.thickness_law=mass",
            "solver.integrator=euler",
            "solver.steps=7",
            "output.times=[0.25, 1]",
            "stimulus.red.offset=0.5",
        ],
    )
    .unwrap();
    let g = s.growth.clone().unwrap();
    assert_eq!((g.eta0, g.thickness_law), (0.0, ThicknessLaw::Mass));
    assert_eq!(s.growth_settings.integrator, Integrator::Euler);
    assert_eq!(s.growth_settings.steps, 7);
    assert_eq!(s.growth_settings.output_times, vec![0.25, 1.0]);
    assert_eq!(
        g.red,
        Surface {
            offset: 0.5,
            ..Surface::default_red()
        }
    );
    // A single number is a list of one.
    let s = parse_set("growth.t_end = 2", &["output.times=2"]).unwrap();
    assert_eq!(s.growth_settings.output_times, vec![2.0]);
}

#[test]
fn red_follows_blue_unless_given() {
    // Blue alone: red is the new blue pushed back by 0.655.
    let s = parse("growth.eta0 = 70\n[stimulus.blue]\nP3 = 25\nphi_max = 0.5").unwrap();
    let g = s.growth.unwrap();
    assert_eq!(g.blue.p3, 25.0);
    assert_eq!(
        g.red,
        Surface {
            offset: RED_OFFSET,
            ..g.blue
        }
    );
    // The effective scene reads back with red still following blue, and no red key in it.
    let s = parse("growth.eta0 = 70\n[stimulus.blue]\nP3 = 25").unwrap();
    let text = s.to_toml();
    assert!(
        text.lines()
            .filter(|l| l.contains("stimulus.red."))
            .all(|l| l.starts_with("# ") && l.ends_with("(follows blue)")),
        "{text}"
    );
    assert!(
        text.contains("# stimulus.red.offset = 0.655  (follows blue)\n"),
        "{text}"
    );
    let mut back = Scene::from_toml_str(&s.to_toml(), "b.toml", &[]).unwrap();
    assert_eq!(back.stimulus, s.stimulus);
    assert_eq!(back.growth, s.growth);
    back.set("stimulus.blue.P3", 24).unwrap();
    assert_eq!(back.red().p3, 24.0, "red follows the new blue");
    // A given red surface is written and read back as given.
    let s = parse_set("growth.eta0 = 70", &["stimulus.red.P1=-5"]).unwrap();
    let back = Scene::from_toml_str(&s.to_toml(), "b.toml", &[]).unwrap();
    assert_eq!((back.stimulus, back.growth), (s.stimulus, s.growth));
    // Any red key: red starts from its own default, in any order of the keys.
    for sets in [
        ["stimulus.blue.P3=25", "stimulus.red.P1=-5"],
        ["stimulus.red.P1=-5", "stimulus.blue.P3=25"],
    ] {
        let s = parse_set("growth.eta0 = 70", &sets).unwrap();
        let g = s.growth.unwrap();
        assert_eq!(g.blue.p3, 25.0);
        assert_eq!(
            g.red,
            Surface {
                p1: -5.0,
                ..Surface::default_red()
            },
            "{sets:?}"
        );
    }
    // Surfaces given before growth is turned on are kept when it is.
    let s = parse_set("[stimulus.blue]\nP3 = 25", &["growth.eta0=1"]).unwrap();
    assert_eq!(s.growth.unwrap().red.p3, 25.0);
    // The defaults are the published blue surface and its red shadow.
    let g = parse("growth.eta0 = 70").unwrap().growth.unwrap();
    assert_eq!((g.blue, g.red), (Surface::blue(), Surface::default_red()));
}

#[test]
fn bad_growth_values_name_the_key() {
    for (text, key, problem) in [
        ("growth.eta0 = -1", "growth.eta0", "must be non-negative"),
        ("growth.delta = 0", "growth.delta", "must be positive"),
        ("growth.delta = -2", "growth.delta", "must be positive"),
        (
            "growth.t_end = 0",
            "growth.t_end",
            "must be at least 1e-100",
        ),
        (
            "growth.t_end = -1",
            "growth.t_end",
            "must be at least 1e-100",
        ),
        (
            "growth.t_end = 1e-200",
            "growth.t_end",
            "must be at least 1e-100",
        ),
        (
            "growth.t_end = 5e-324",
            "growth.t_end",
            "must be at least 1e-100",
        ),
        (
            "growth.Gamma = nan",
            "growth.Gamma",
            "must be a finite number",
        ),
        (
            "growth.Gamma = inf",
            "growth.Gamma",
            "must be a finite number",
        ),
        (
            "growth.eta0 = inf",
            "growth.eta0",
            "must be a finite number",
        ),
        ("solver.rtol = 0", "solver.rtol", "strictly between 0 and 1"),
        ("solver.rtol = 1", "solver.rtol", "strictly between 0 and 1"),
        (
            "solver.rtol = -1e-6",
            "solver.rtol",
            "strictly between 0 and 1",
        ),
        ("solver.atol = 0", "solver.atol", "must be positive"),
        (
            "solver.atol = nan",
            "solver.atol",
            "must be a finite number",
        ),
        ("solver.steps = 0", "solver.steps", "between 1 and 1000000"),
        ("solver.steps = -5", "solver.steps", "between 1 and 1000000"),
        ("output.times = []", "output.times", "at least one time"),
        ("output.times = [0, 0.5]", "output.times", "positive"),
        ("output.times = [-0.1]", "output.times", "positive"),
        (
            "output.times = [0.5, 0.2]",
            "output.times",
            "strictly increasing",
        ),
        (
            "output.times = [0.5, 0.5]",
            "output.times",
            "strictly increasing",
        ),
        ("output.times = [0.5, nan]", "output.times", "finite"),
        ("output.times = [inf]", "output.times", "finite"),
        (
            "stimulus.blue.phi_max = 0",
            "stimulus.blue.phi_max",
            "between 0 and π",
        ),
        (
            "stimulus.blue.phi_max = 3.2",
            "stimulus.blue.phi_max",
            "between 0 and π",
        ),
        (
            "stimulus.red.phi_max = -0.1",
            "stimulus.red.phi_max",
            "between 0 and π",
        ),
        ("stimulus.red.offset = nan", "stimulus.red.offset", "finite"),
        ("stimulus.blue.P1 = inf", "stimulus.blue.P1", "finite"),
        ("stimulus.red.z_B = -inf", "stimulus.red.z_B", "finite"),
    ] {
        let text = format!("growth.thickness_law = \"none\"\n{text}");
        let e = err(parse(&text), "x.toml", key);
        assert!(e.contains(problem), "{text}: {e}");
        // The same through --set names the --set text.
        let set = text.lines().nth(1).unwrap().replace(" = ", "=");
        let e = err(
            parse_set("growth.thickness_law = \"none\"", &[&set]),
            &format!("--set {set}"),
            key,
        );
        assert!(e.contains(problem), "{set}: {e}");
    }
}

#[test]
fn output_times_must_end_by_t_end() {
    let e = err(
        parse("growth.t_end = 1\noutput.times = [0.5, 1.5]"),
        "x.toml",
        "output.times",
    );
    assert!(e.contains("growth.t_end = 1") && e.contains("1.5"), "{e}");
    // The error names whichever of the two was set last.
    err(
        parse_set("output.times = [0.5, 1]", &["growth.t_end=0.8"]),
        "--set growth.t_end=0.8",
        "output.times",
    );
    parse("growth.t_end = 1\noutput.times = [0.5, 1]").unwrap();
    // Without growth, t_end is not in force.
    parse("output.times = [5]").unwrap();
}

#[test]
fn growth_wrong_types() {
    let e = err(
        parse("output.times = \"0.1,0.2\""),
        "x.toml",
        "output.times",
    );
    assert!(e.contains("a list of numbers"), "{e}");
    let e = err(
        parse("output.times = [0.1, \"x\"]"),
        "x.toml",
        "output.times[2]",
    );
    assert!(e.contains("must be a number"), "{e}");
    err(
        parse_set("", &["output.times=0.1,0.2"]),
        "--set output.times=0.1,0.2",
        "output.times",
    );
    let e = err(
        parse("[growth]\nthickness_law = \"volume\""),
        "x.toml",
        "growth.thickness_law",
    );
    assert!(e.contains("\"none\", \"mass\""), "{e}");
    let e = err(
        parse("[solver]\nintegrator = \"rk45\""),
        "x.toml",
        "solver.integrator",
    );
    assert!(e.contains("\"cvode\", \"euler\""), "{e}");
    err(parse("growth.eta0 = \"fast\""), "x.toml", "growth.eta0");
    err(parse("solver.steps = 2.5"), "x.toml", "solver.steps");
    let e = err(parse("[growth]\ngamma = 8"), "x.toml", "growth.gamma");
    assert!(e.contains("did you mean 'growth.Gamma'"), "{e}");
    let e = err(parse("[stimulus.bleu]\nP1 = 1"), "x.toml", "stimulus.bleu");
    assert!(e.contains("did you mean [stimulus.blue]"), "{e}");
    err(
        parse("[stimulus.blue]\noffset = 1"),
        "x.toml",
        "stimulus.blue.offset",
    );
}

#[test]
fn shipped_const_scene_grows_with_the_defaults() {
    let s = Scene::from_toml_str(
        include_str!("../../../../scenes/const.toml"),
        "const.toml",
        &[],
    )
    .unwrap();
    assert_eq!(s.growth, Some(GrowthParams::default()));
    // The defaults, with the axial-length history its figure draws.
    assert_eq!(
        s.growth_settings,
        GrowthSettings {
            history_points: 100,
            ..GrowthSettings::default()
        }
    );
    assert_eq!(s.params.thickness, Thickness::Uniform);
    assert_eq!(s.params.d, 0.0);
    assert_eq!(s.solver.nodes, 501);
    assert_eq!(s.growth_settings.output_times, vec![0.1, 0.2, 0.4, 1.0]);
    // The elastic scenes stay elastic.
    for text in [
        include_str!("../../../../scenes/default.toml"),
        include_str!("../../../../scenes/fibres-nonuniform.toml"),
        include_str!("../../../../scenes/exact-sphere.toml"),
    ] {
        assert_eq!(
            Scene::from_toml_str(text, "s.toml", &[]).unwrap().growth,
            None
        );
    }
}

/// Counts that size an allocation or a loop are bounded, and every derived size of the
/// mesh is checked before anything is allocated (TESTING.md, family 1).
#[test]
fn absurd_sizes_are_refused_before_allocation() {
    for (text, key, problem) in [
        (
            "solver.nodes = 100000000000",
            "solver.nodes",
            "between 5 and 1000000",
        ),
        (
            "solver.max_newton = 99999999999",
            "solver.max_newton",
            "between 1 and 10000",
        ),
        ("geometry.R0 = 1e308", "geometry.R0", "not finite"),
        (
            "material.bending = 1e-300",
            "material.bending",
            "thinner than double precision",
        ),
        (
            "material.bending = 5e-324",
            "material.bending",
            "raise material.bending",
        ),
        (
            "solver.nodes = 1000000\nsolver.epsilon = 1e-300",
            "solver.nodes",
            "more than the 1000000 allowed",
        ),
    ] {
        let e = err(parse(text), "x.toml", key);
        assert!(e.contains(problem), "{text}: {e}");
        assert!(e.len() < 400, "one short line: {e}");
    }
    for text in [
        "growth.eta0 = 70\noutput.history_points = 100000000",
        "growth.eta0 = 70\nsolver.steps = 100000000",
    ] {
        let e = parse(text).unwrap_err().to_string();
        assert!(e.contains("between"), "{text}: {e}");
    }
    // Numbers in messages are short: no 300-digit renderings of 1e-300.
    let e = parse("geometry.R0 = 1e-300").unwrap_err().to_string();
    assert!(e.contains("geometry.R0 = 1e-300") && e.len() < 300, "{e}");
    // Without the cornea's grading the thin layer is not laid, so the scene is accepted.
    assert!(parse("material.bending = 1e-300\nsolver.cornea_grading = false").is_ok());
}

// ---- The stimulus computed from the eye's optics ----------------------------------------

use crate::model::optics::Source;

/// The default source is the published polynomial: no optics key is in effect or
/// summarised, and nothing is traced; the effective TOML shows an optics key only when the
/// scene gives it another value than its default (so that the text reads back to the same
/// scene). With `stimulus.source = "optics"` the keys are in effect and the surfaces are
/// traced once, as the scene is read.
#[test]
fn the_optics_keys_apply_to_the_optics_source_only() {
    let s = parse("growth.eta0 = 70\noptics.pupil = 2").unwrap();
    let g = s.growth.as_ref().unwrap();
    assert_eq!(
        (g.source, g.optics.pupil, g.computed.is_none()),
        (Source::Polynomial, 2.0, true)
    );
    let params = s.parameters_json();
    assert!(params.get("stimulus.source").is_none() && params.get("optics.pupil").is_none());
    let text = s.to_toml();
    assert!(text.contains("optics.pupil = 2.0\n"), "{text}");
    assert_eq!(text.matches("optics.").count(), 1, "{text}");
    assert_eq!(parse(&text).unwrap(), s);
    assert!(!parse("growth.eta0 = 70")
        .unwrap()
        .to_toml()
        .contains("optics"));
    let s = parse(
        "growth.eta0 = 70\nstimulus.source = \"optics\"\n[optics]\npupil = 1.5\nfocus = \"sagittal\"\nmax_field = 30\nwavelengths = [450, 650]",
    )
    .unwrap();
    let params = s.parameters_json();
    assert_eq!(params["stimulus.source"], "optics");
    assert_eq!(params["optics.eye"], "atchison-2006");
    assert_eq!(params["optics.pupil"], 1.5);
    assert_eq!(params["optics.focus"], "sagittal");
    let g = s.growth.as_ref().unwrap();
    let c = g.computed.as_ref().expect("traced as the scene is read");
    assert_eq!(c.surfaces.surfaces.len(), 2);
    assert_eq!(c.surfaces.surfaces[0].points.len(), 31);
    assert_eq!(c.surfaces.surfaces[1].wavelength_nm, 650.0);
    assert_eq!(c.z_c, g.blue.z_b);
    assert!(matches!(
        g.blue_focal(),
        crate::model::stimulus::Focal::Computed(_)
    ));
    // Resolving again traces nothing: the same shared surfaces.
    let again = g.resolved().unwrap();
    assert!(std::sync::Arc::ptr_eq(again.computed.as_ref().unwrap(), c));
    // The scene reads back, surfaces and all.
    let back = parse(&s.to_toml()).unwrap();
    assert_eq!(back, s);
}

/// Bad optics keys are refused as the scene is read, in one line naming the key, from the
/// file or from --set: an unknown eye, a pupil wider than the eye admits, wavelengths the
/// dispersion laws do not cover or too few of them, a largest field that cannot be traced.
#[test]
fn bad_optics_keys_are_refused_naming_the_key() {
    let base = "growth.eta0 = 70\nstimulus.source = \"optics\"";
    for (set, key, problem) in [
        (
            "optics.eye=gullstrand",
            "optics.eye",
            "must be one of \"atchison-2006\"",
        ),
        ("optics.pupil=12", "optics.pupil", "must lie in (0, 10] mm"),
        ("optics.pupil=0", "optics.pupil", "positive"),
        ("optics.pupil=nan", "optics.pupil", "finite"),
        (
            "optics.wavelengths=[400, 5000]",
            "optics.wavelengths",
            "(5000 does not)",
        ),
        (
            "optics.wavelengths=[400]",
            "optics.wavelengths",
            "at least two",
        ),
        (
            "optics.wavelengths=[nan, 600]",
            "optics.wavelengths",
            "finite",
        ),
        (
            "optics.max_field=85",
            "optics.max_field",
            "must lie in [5, 80] degrees",
        ),
        ("optics.focus=best", "optics.focus", "must be one of"),
        (
            "stimulus.source=zemax",
            "stimulus.source",
            "\"polynomial\", \"optics\"",
        ),
    ] {
        let e = err(parse_set(base, &[set]), &format!("--set {set}"), key);
        assert!(e.contains(problem), "{set}: {e}");
    }
    // Traced and failing: at 80° with an 8 mm pupil a ray misses the posterior lens; the
    // error names the field, the wavelength and the surface, and blames the largest field.
    let e = err(
        parse_set(base, &["optics.pupil=8", "optics.max_field=80"]),
        "--set optics.max_field=80",
        "optics.max_field",
    );
    assert!(
        e.contains("cannot be traced in the atchison-2006 eye")
            && e.contains("at 80° and 400 nm fails at 'posterior lens'"),
        "{e}"
    );
    // From the file, the file is named.
    let e = err(
        parse(&format!("{base}\noptics.pupil = 11")),
        "x.toml",
        "optics.pupil",
    );
    assert!(e.contains("11"), "{e}");
    // A polynomial scene does not check (or trace) optics keys it does not use.
    assert!(parse_set("growth.eta0 = 70", &["optics.pupil=12"]).is_ok());
}

/// Every parameter round-trips through its scene key, `set` and `value` touch the
/// field the key names (as the scene's own key does), and the refusals name the key.
#[test]
fn sensitivity_parameters_and_their_keys() {
    for param in crate::growth::dae::SensParam::ALL {
        assert_eq!(super::keys::sensitivity_param(param.key()), Ok(param));
        let mut scene = Scene::default_scene();
        scene.params.d = 200.0;
        let mut g = crate::growth::GrowthParams::default();
        param.set(&mut scene.params, &mut g, 0.75);
        assert_eq!(param.value(&scene.params, &g), 0.75, "{}", param.key());
        scene.growth = Some(crate::growth::GrowthParams::default());
        scene.set(param.key(), 0.75).unwrap();
        let ours = (scene.params, scene.growth.clone().unwrap());
        assert_eq!(param.value(&ours.0, &ours.1), 0.75, "{}", param.key());
        assert!(crate::growth::dae::SensParam::SUPPORTED.contains(param.key()));
    }
    let why = super::keys::sensitivity_param("stimulus.red.offset").unwrap_err();
    assert!(why.contains("only affects the classification"), "{why}");
    let why = crate::growth::dae::SensParam::FibreStiffness
        .check(&crate::model::params::Params::default())
        .unwrap_err();
    assert!(
        why.starts_with("fibres.D = 0: the scene has no fibres"),
        "{why}"
    );
    assert!(crate::growth::dae::SensParam::Modulus
        .check(&crate::model::params::Params::default())
        .is_ok());
}

// ---- The eye's surfaces: a custom eye, overrides, tables over time ----------------------

/// A custom four-surface eye, as `[[optics.surfaces]]`.
const CUSTOM_EYE: &str = "growth.eta0 = 70\nstimulus.source = \"optics\"\n[optics]\neye = \"custom\"\npupil = 0.5\npupil_position = 3.6\nmax_field = 10\n\
[[optics.surfaces]]\nradius = 7.8\nconic = -0.25\nthickness = 0.55\nindex = 1.376\n\
[[optics.surfaces]]\nradius = 6.5\nthickness = 3.05\ncauchy = [1.3237, 0.0043]\n\
[[optics.surfaces]]\nradius = 10.2\nconic = -3\nthickness = 4\nindex = 1.42\n\
[[optics.surfaces]]\nradius = -6\nconic = -1\nthickness = 16.4\nindex = 1.336\n";

/// The surfaces read back from the scene's own TOML, one key set alone by --set, and a
/// built-in eye's surfaces changed by overrides (the rest the source's; the pupil on the
/// lens's front vertex, which moves with the anterior chamber).
#[test]
fn the_eyes_surfaces_are_read_written_and_overridden() {
    let s = parse(CUSTOM_EYE).unwrap();
    let system = s.optics().system().unwrap();
    assert_eq!(system.elements.len(), 4);
    assert_eq!(system.elements[2].surface.conic, -3.0);
    assert_eq!(
        s.parameters_json()["optics.surfaces"][1]["cauchy"][1],
        0.0043
    );
    let back = parse(&s.to_toml()).unwrap();
    assert_eq!(back, s);
    // A plane's radius in summary.json (JSON has no inf) reads back as a plane.
    let planar = parse_set(CUSTOM_EYE, &["optics.surfaces[1].radius=inf"]).unwrap();
    let json = planar.parameters_json();
    assert_eq!(json["optics.surfaces"][1]["radius"], "inf");
    let text = format!("{CUSTOM_EYE}\n");
    let again = parse_set(&text, &["optics.surfaces[1].radius=\"inf\""]).unwrap();
    assert_eq!(again.optics().surfaces, planar.optics().surfaces);
    // No surface tables: no value, shown or summarised.
    let builtin = parse("growth.eta0 = 70\nstimulus.source = \"optics\"").unwrap();
    assert!(builtin.parameters_json().get("optics.surfaces").is_none());
    assert!(!builtin.to_toml().contains("optics.surfaces"));
    let s = parse_set(CUSTOM_EYE, &["optics.surfaces[2].radius=11"]).unwrap();
    assert_eq!(
        s.optics().system().unwrap().elements[2].surface.radius,
        11.0
    );
    // Overrides of the Atchison eye: a flatter cornea and a deeper anterior chamber.
    let s = parse_set(
        "growth.eta0 = 70\nstimulus.source = \"optics\"",
        &[
            "optics.surfaces[0].radius=7.9",
            "optics.surfaces[1].thickness=3.35",
        ],
    )
    .unwrap();
    let eye = s.optics().system().unwrap();
    let source = eyeshell_optics::eyes::atchison_2006();
    assert_eq!(eye.elements[0].surface.radius, 7.9);
    assert_eq!(
        eye.elements[0].surface.conic,
        source.elements[0].surface.conic
    );
    assert_eq!(eye.elements[1].thickness, 3.35);
    assert_eq!(eye.elements[4], source.elements[4]);
    assert!((eye.pupil_position.unwrap() - 3.90).abs() < 1e-12);
}

/// Bad surface keys are refused as the scene is read, one line naming the surface's key and
/// the origin that gave it (the file, or the --set).
#[test]
fn bad_surface_keys_are_refused_naming_the_surface() {
    for (set, key, problem) in [
        (
            "optics.surfaces[2].radius=0.01",
            "optics.surfaces[2].radius",
            "between 0.5 and 10000 mm",
        ),
        (
            "optics.surfaces[2].radius=nan",
            "optics.surfaces[2].radius",
            "(not nan)",
        ),
        (
            "optics.surfaces[1].index=0.5",
            "optics.surfaces[1].index",
            "between 1 and 3",
        ),
        (
            "optics.surfaces[3].thickness=-1",
            "optics.surfaces[3].thickness",
            "positive",
        ),
        (
            "optics.surfaces[3].thickness=1e300",
            "optics.surfaces[3].thickness",
            "at most 100 mm",
        ),
        (
            "optics.surfaces[2].conic=1e6",
            "optics.surfaces[2].conic",
            "between −100 and 100",
        ),
        (
            "optics.surfaces[1].colour=3",
            "optics.surfaces[1].colour",
            "is not a key of a surface",
        ),
        (
            "optics.surfaces[x].radius=3",
            "optics.surfaces[x].radius",
            "i from 0 to 15",
        ),
        (
            "optics.surfaces[99].radius=3",
            "optics.surfaces[99].radius",
            "i from 0 to 15",
        ),
        (
            "optics.surfaces[5].radius=7",
            "optics.surfaces[4].radius",
            "must be given for a custom eye",
        ),
        (
            "optics.surfaces[1].cauchy=[1.4, 0.5]",
            "optics.surfaces[1].cauchy",
            "at 400 nm, not a physical one",
        ),
        (
            "optics.surfaces[1].cauchy=[]",
            "optics.surfaces[1].cauchy",
            "one to four",
        ),
        (
            "optics.surfaces[0].aspheric=[1, nan]",
            "optics.surfaces[0].aspheric",
            "finite",
        ),
        (
            "optics.surfaces[0].sellmeier={ b = [1] }",
            "optics.surfaces[0].sellmeier",
            "must be a table",
        ),
        (
            "optics.pupil_position=30",
            "optics.pupil_position",
            "not behind the last one (at 7.6 mm)",
        ),
        (
            "optics.pupil_position=-1",
            "optics.pupil_position",
            "positive",
        ),
        (
            "optics.surfaces[0].radius={ t = [0, 1], value = [7.8] }",
            "optics.surfaces[0].radius",
            "as many values as times",
        ),
        (
            "optics.surfaces[0].radius={ t = [1, 0], value = [7.8, 7.7] }",
            "optics.surfaces[0].radius",
            "strictly increasing",
        ),
        (
            "optics.surfaces[0].radius={ t = [-1, 1], value = [7.8, 7.7] }",
            "optics.surfaces[0].radius",
            "from 0 on",
        ),
        (
            "optics.surfaces[0].radius={ t = [0, 1], value = [7.8, -7.7] }",
            "optics.surfaces[0].radius",
            "keep one sign",
        ),
        (
            "optics.surfaces[0].radius={ t = [0, 1], v = [7.8, 7.7] }",
            "optics.surfaces[0].radius",
            "unknown key 'v'",
        ),
        (
            "optics.surfaces[0].aspheric={ t = [0, 1], value = [0, 1] }",
            "optics.surfaces[0].aspheric",
            "list of numbers",
        ),
    ] {
        let e = err(parse_set(CUSTOM_EYE, &[set]), &format!("--set {set}"), key);
        assert!(e.contains(problem), "{set}: {e}");
    }
    // From the file, the file is named.
    let text = CUSTOM_EYE.replace("radius = 10.2", "radius = 0");
    let e = err(parse(&text), "x.toml", "optics.surfaces[2].radius");
    assert!(e.contains("(not 0)"), "{e}");
    let text = CUSTOM_EYE.replace("index = 1.42", "index = 1.42\ncauchy = [1.4]");
    let e = err(parse(&text), "x.toml", "optics.surfaces[2]");
    assert!(e.contains("gives its medium twice"), "{e}");
    // A custom eye needs its stop, two surfaces or more, and each surface's numbers.
    let text = CUSTOM_EYE.replace("pupil_position = 3.6\n", "");
    let e = err(parse(&text), "x.toml", "optics.pupil_position");
    assert!(
        e.contains("must be given for optics.eye = \"custom\""),
        "{e}"
    );
    let text = CUSTOM_EYE.replace("thickness = 3.05\n", "");
    let e = err(parse(&text), "x.toml", "optics.surfaces[1].thickness");
    assert!(e.contains("must be given"), "{e}");
    // A built-in eye has so many surfaces, and its GRIN lens is the source's.
    let base = "growth.eta0 = 70\nstimulus.source = \"optics\"";
    let e = err(
        parse_set(base, &["optics.surfaces[5].radius=7"]),
        "--set optics.surfaces[5].radius=7",
        "optics.surfaces[5]",
    );
    assert!(
        e.contains("beyond the atchison-2006 eye's 5 surfaces"),
        "{e}"
    );
    let e = err(
        parse_set(base, &["optics.surfaces[2].index=1.4"]),
        "--set optics.surfaces[2].index=1.4",
        "optics.surfaces[2].index",
    );
    assert!(e.contains("gradient-index medium"), "{e}");
}

/// An error found by tracing names the key it blames from where that key was given: a
/// largest field given by --set is the --set's, whichever key came last.
#[test]
fn a_traced_error_names_the_origin_of_its_key() {
    let base = "growth.eta0 = 70\nstimulus.source = \"optics\"\noptics.pupil = 8";
    let e = err(
        parse_set(base, &["optics.max_field=80"]),
        "--set optics.max_field=80",
        "optics.max_field",
    );
    assert!(e.contains("fails at 'posterior lens'"), "{e}");
    // The same error after the scene was read (as `eyeshell optics` meets it).
    let mut s = parse_set(
        "growth.eta0 = 70",
        &["optics.pupil=8", "optics.max_field=80"],
    )
    .unwrap();
    s.set_stimulus_source(Source::Optics);
    let e = s.resolve_optics().unwrap_err().to_string();
    assert!(
        e.starts_with("--set optics.max_field=80: optics.max_field = 80"),
        "{e}"
    );
}
