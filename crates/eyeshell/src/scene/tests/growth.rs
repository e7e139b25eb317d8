//! Unit tests of the growth keys.

use super::*;
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
        include_str!("../../../../../scenes/const.toml"),
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
        include_str!("../../../../../scenes/default.toml"),
        include_str!("../../../../../scenes/fibres-nonuniform.toml"),
        include_str!("../../../../../scenes/exact-sphere.toml"),
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
