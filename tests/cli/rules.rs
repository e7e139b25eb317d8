//! Growth rules (docs/MODEL.md §6, "Growth rules"; docs/guide/hypotheses.md): every rule of
//! the catalogue in the key table and the model's account, bad rule keys refused in one
//! line, and the myopia scenes' must-shows.

use super::support::{csv_cells, eyeshell, repo, s};

/// Each built-in rule is named by `stimulus.rule`'s description and has its row in
/// docs/MODEL.md's table and in the guide's: a rule added to the catalogue alone fails here.
#[test]
fn every_rule_is_in_the_key_table_and_the_model() {
    let keys = eyeshell(&["keys"]);
    assert_eq!(keys.code, Some(0), "{}", keys.stderr);
    let rule_line = keys
        .stdout
        .lines()
        .find(|l| l.starts_with("stimulus.rule "))
        .expect("stimulus.rule in `eyeshell keys`");
    let model = std::fs::read_to_string(repo().join("docs/MODEL.md")).unwrap();
    let guide = std::fs::read_to_string(repo().join("docs/guide/hypotheses.md")).unwrap();
    for rule in eyeshell::model::rule::CATALOGUE {
        assert!(
            rule_line.contains(&format!("\"{rule}\"")),
            "{rule} not a choice: {rule_line}"
        );
        let row = format!("| `{rule}`");
        assert!(model.contains(&row), "docs/MODEL.md has no row {row}");
        assert!(
            guide.contains(&row),
            "docs/guide/hypotheses.md has no row {row}"
        );
    }
    assert_eq!(eyeshell::model::rule::CATALOGUE.len(), 3);
}

/// An unknown rule, a gain that is negative or not finite, a region beyond the surface:
/// one line naming the key, exit 2, nothing written.
#[test]
fn bad_rule_keys_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (set, says) in [
        ("stimulus.rule=\"myopic-drift\"", "stimulus.rule"),
        ("stimulus.myopic_gain=-0.1", "stimulus.myopic_gain"),
        ("stimulus.hyperopic_gain=nan", "stimulus.hyperopic_gain"),
        ("stimulus.chromatic_gain=-1", "stimulus.chromatic_gain"),
        ("stimulus.region=\"everywhere\"", "stimulus.region"),
        ("stimulus.max_field=0", "stimulus.max_field"),
    ] {
        let out = dir.path().join("out");
        let run = eyeshell(&["grow", "scenes/const.toml", "--set", set, "--out", s(&out)]);
        assert_eq!(run.code, Some(2), "{set}: {}", run.stderr);
        assert_eq!(
            run.stderr.trim().lines().count(),
            1,
            "{set}: {}",
            run.stderr
        );
        assert!(run.stderr.contains(says), "{set}: {}", run.stderr);
        assert!(!out.exists(), "{set}: wrote {}", out.display());
    }
    // Beyond the published surface's φ_max (33.6°): the run says where the surface ends.
    let out = dir.path().join("beyond");
    let run = eyeshell(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "stimulus.region=\"integrated\"",
        "--set",
        "stimulus.max_field=40",
        "--out",
        s(&out),
    ]);
    assert_ne!(run.code, Some(0));
    assert!(run.stderr.contains("φ_max = 33.63"), "{}", run.stderr);
}

/// The axial lengths (mm) of a myopia scene at ages 8 to 11, with overrides.
fn lengths(scene: &str, sets: &[&str]) -> Vec<f64> {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut args = vec!["grow", scene, "--out", s(&out), "--quiet"];
    for set in sets {
        args.extend(["--set", set]);
    }
    let run = eyeshell(&args);
    assert_eq!(run.code, Some(0), "{scene}: {}", run.stderr);
    let (header, rows) = csv_cells(&out.join("series.csv"));
    let j = header.iter().position(|h| h == "axial_length").unwrap();
    rows.iter().map(|r| r[j].parse().unwrap()).collect()
}

/// The corrected myope progresses under the defocus rule (0.2–0.6 mm a year over 8–11, the
/// scene's η0 fitted to the single-vision arm's 0.62 mm in 3 years) and not under the
/// paper's (under 0.05 mm a year); both two-image lenses grow less than single vision.
#[test]
fn the_corrected_myope_progresses_and_the_lenses_slow_it() {
    let sv = lengths("scenes/myopia/single-vision.toml", &[]);
    assert_eq!(sv.len(), 4);
    let per_year = (sv[3] - sv[0]) / 3.0;
    assert!((0.2..0.6).contains(&per_year), "{sv:?}");
    assert!(
        (sv[3] - sv[0] - 0.62).abs() < 0.02,
        "the fit to 0.62 mm: {sv:?}"
    );
    let paper = lengths(
        "scenes/myopia/single-vision.toml",
        &["stimulus.rule=\"blue-surface\""],
    );
    for w in paper.windows(2) {
        assert!((0.0..0.05).contains(&(w[1] - w[0])), "{paper:?}");
    }
    for lens in ["dual-focus", "lenslets"] {
        let l = lengths(&format!("scenes/myopia/{lens}.toml"), &[]);
        assert!(
            l[3] - l[0] < sv[3] - sv[0] - 0.03,
            "{lens}: {l:?} against {sv:?}"
        );
    }
}
