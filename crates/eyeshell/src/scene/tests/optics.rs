//! Unit tests of the stimulus computed from the eye's optics.

use super::*;
use crate::model::eyewear::ProfileSpec;
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
        let key = super::names::sensitivity_key(param);
        assert_eq!(super::sensitivity::sensitivity_param(key), Ok(param));
        let mut scene = Scene::default_scene();
        scene.params.d = 200.0;
        let mut g = crate::growth::GrowthParams::default();
        param.set(&mut scene.params, &mut g, 0.75);
        assert_eq!(param.value(&scene.params, &g), 0.75, "{}", param.key());
        scene.growth = Some(crate::growth::GrowthParams::default());
        scene.set(param.key(), 0.75).unwrap();
        let ours = (scene.params, scene.growth.clone().unwrap());
        assert_eq!(param.value(&ours.0, &ours.1), 0.75, "{}", param.key());
        assert!(super::names::supported_sensitivities().contains(param.key()));
    }
    let why = super::sensitivity::sensitivity_param("stimulus.red.offset")
        .unwrap_err()
        .to_string();
    assert!(why.contains("only affects the classification"), "{why}");
    let why = crate::growth::dae::SensParam::FibreStiffness
        .check(&crate::model::params::Params::default())
        .unwrap_err()
        .to_string();
    assert!(
        why.starts_with("fibres.D = 0: the scene has no fibres"),
        "{why}"
    );
    assert!(crate::growth::dae::SensParam::Modulus
        .check(&crate::model::params::Params::default())
        .is_ok());
}

/// Every eye of the optics crate's registry is selectable from a scene by its name, traces,
/// and has the registry's wavelength range; `custom` is the last name `optics.eye` takes. An
/// eye added to the registry needs no other list to be selectable.
#[test]
fn every_registered_eye_is_selectable_from_a_scene() {
    use eyeshell_optics::eyes::REGISTRY;
    let names = crate::model::optics::EYES;
    assert_eq!(names.len(), REGISTRY.len() + 1);
    assert_eq!(names[REGISTRY.len()], crate::model::optics::CUSTOM);
    let base =
        "growth.eta0 = 70\nstimulus.source = \"optics\"\n[optics]\npupil = 1\nmax_field = 10\n";
    for eye in REGISTRY {
        let s = parse(&format!("{base}eye = \"{}\"\n", eye.name)).unwrap();
        let spec = s.optics();
        assert_eq!(spec.eye_name(), eye.name);
        let system = spec.system().unwrap();
        assert_eq!(
            system.elements.len(),
            (eye.build)().elements.len(),
            "{}",
            eye.name
        );
        let (lo, hi, why) = spec.wavelength_range();
        assert_eq!(
            (lo, hi),
            (eye.wavelengths.lo, eye.wavelengths.hi),
            "{}",
            eye.name
        );
        assert!(why.contains(eye.wavelengths.source), "{why}");
        let g = s.growth.as_ref().unwrap();
        assert!(
            g.computed.is_some(),
            "{} traced as the scene is read",
            eye.name
        );
        for alias in eye.aliases {
            assert_eq!(
                eyeshell_optics::eyes::builtin(alias).map(|e| e.elements.len()),
                Some(system.elements.len())
            );
        }
    }
}

/// One key of one lens (`optics.lenses[i].key`): the lens's other keys kept, a lens added
/// after the last, a contact lens made from a spectacle lens without its vertex; a
/// prescribed lens (`power = "prescribe"`, `over`) written back as prescribed and read to
/// the same scene, its power its eye's refraction at t = 0 (the prescription itself is
/// tested in the core and by tests/cli/drawn_optics.rs).
#[test]
fn one_lens_key_is_set_alone_and_a_prescription_reads_back() {
    // The shell of scenes/myopia/ (about −2 D at t = 0).
    let base = "geometry.R0 = 12.07\ncornea.R0 = 12.07\ngrowth.eta0 = 70\nstimulus.source = \"optics\"\n[[optics.lenses]]\nvertex = 14.0\npower = -2.0\n";
    let s = parse_set(base, &["optics.lenses[0].power=-3"]).unwrap();
    let lens = &s.optics().lenses[0];
    assert_eq!(
        (lens.vertex, &lens.profile),
        (14.0, &ProfileSpec::Power(-3.0))
    );
    let s = parse_set(
        base,
        &[
            "optics.lenses[1].kind=contact",
            "optics.lenses[1].power=1.5",
        ],
    );
    // A lens added with its kind alone has no power yet: the first key is refused.
    let e = s.unwrap_err().to_string();
    assert!(
        e.contains("optics.lenses[1]") && e.contains("must give exactly one of power"),
        "{e}"
    );
    let s = parse_set(
        base,
        &[
            "optics.lenses[1].power=1.5",
            "optics.lenses[1].kind=contact",
        ],
    )
    .unwrap();
    let added = &s.optics().lenses[1];
    assert_eq!((added.kind, &added.profile), (1, &ProfileSpec::Power(1.5)));
    let s = parse_set(base, &["optics.lenses[0].kind=contact"]).unwrap();
    assert_eq!(s.optics().lenses[0].kind, 1);
    let e = err(
        parse_set(base, &["optics.lenses[2].power=1"]),
        "--set optics.lenses[2].power=1",
        "optics.lenses[2].power",
    );
    assert!(e.contains("it wears 1 lens"), "{e}");

    let prescribed = parse_set(
        base,
        &[
            "optics.lenses[0].power=prescribe",
            "optics.lenses[0].over=-0.25",
        ],
    )
    .unwrap();
    let lens = &prescribed.optics().lenses[0];
    assert_eq!(lens.prescribe, Some(-0.25));
    let ProfileSpec::Power(p) = lens.profile else {
        panic!("{lens:?}")
    };
    let text = prescribed.to_toml();
    assert!(
        text.contains("power = \"prescribe\", over = -0.25"),
        "{text}"
    );
    let back = parse(&text).unwrap();
    assert_eq!(back.optics(), prescribed.optics());
    // The eye is about −2 D at t = 0: its correction at 14 mm, 0.25 D more minus.
    assert!(p > -2.6 && p < -1.9, "{p}");
    let e = err(
        parse_set(base, &["optics.lenses[0].over=1"]),
        "--set optics.lenses[0].over=1",
        "optics.lenses[0].over",
    );
    assert!(e.contains("is the offset of a prescribed lens"), "{e}");
}
