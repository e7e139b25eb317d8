//! Unit tests of the eye's surfaces: a custom eye, overrides, tables over time.

use super::*;

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
