//! geometry.R0 is the eye's size as a whole: the cornea's radius follows it unless
//! cornea.R0 is given (docs/MODEL.md §1, §3).

use super::*;

/// The pressurised eye's axial length at the start of the paper's const scene, with `sets`.
fn axial_length(sets: &[&str]) -> f64 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/const.toml");
    let mut all: Vec<String> = [
        "growth.t_end=1e-6",
        "output.times=[1e-6]",
        "output.history_points=0",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    all.extend(sets.iter().map(|s| s.to_string()));
    let scene = Scene::from_file(&path, &all).unwrap();
    scene.grow(&mut ()).unwrap().series[0].axial_length
}

/// A shell 10 % larger at the start is an eye 8–12 % longer, its cornea with it; on the
/// paper's 10 mm cornea the same shell is pulled into a shorter eye, whichever key comes first.
#[test]
fn a_larger_eye_at_the_start_is_a_longer_eye() {
    let paper = axial_length(&[]);
    assert!((paper - 19.9561).abs() < 1e-3, "{paper}");
    let larger = axial_length(&["geometry.R0=11"]);
    let ratio = larger / paper;
    assert!(
        (1.08..=1.12).contains(&ratio),
        "{larger} / {paper} = {ratio}"
    );
    let on_the_papers_cornea = axial_length(&["geometry.R0=11", "cornea.R0=10"]);
    assert!(
        on_the_papers_cornea < paper,
        "{on_the_papers_cornea} vs {paper}"
    );
    assert_eq!(
        axial_length(&["cornea.R0=10", "geometry.R0=11"]),
        on_the_papers_cornea
    );
}

/// The cornea follows until cornea.R0 is given; the effective scene's TOML keeps which, and
/// reads back to the same scene either way.
#[test]
fn the_cornea_follows_geometry_r0_until_given() {
    let follows = parse("[geometry]\nR0 = 12").unwrap();
    assert_eq!(follows.params.cornea.r0, 12.0);
    assert!(follows.params.cornea_follows_radius);
    let text = follows.to_toml();
    assert!(
        text.contains("# cornea.R0 = 12.0  (follows geometry.R0)"),
        "{text}"
    );
    assert_eq!(parse(&text).unwrap(), follows);

    for given in [
        "[cornea]\nR0 = 10\n[geometry]\nR0 = 12",
        "[geometry]\nR0 = 12\n[cornea]\nR0 = 10",
    ] {
        let s = parse(given).unwrap();
        assert_eq!((s.params.r0, s.params.cornea.r0), (12.0, 10.0), "{given}");
        assert!(!s.params.cornea_follows_radius);
        let text = s.to_toml();
        assert!(text.contains("\ncornea.R0 = 10.0\n"), "{text}");
        assert_eq!(parse(&text).unwrap(), s);
    }
    // A --set of geometry.R0 moves a following cornea, not a given one.
    let s = parse_set("", &["geometry.R0=9"]).unwrap();
    assert_eq!(s.params.cornea.r0, 9.0);
    let s = parse_set("[cornea]\nR0 = 10", &["geometry.R0=9"]).unwrap();
    assert_eq!(s.params.cornea.r0, 10.0);
}
