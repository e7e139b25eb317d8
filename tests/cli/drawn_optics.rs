//! Optics keys drawn and swept as any other (`optics.surfaces[i].key`, `optics.lenses[i].key`,
//! `optics.pupil` in `[sweep.sample.keys]` and `[sweep.grid]`), and a lens prescribed for
//! its own eye (`power = "prescribe"`): each eye's values are its own, its results follow
//! them, the prescription corrects the eye it is worn by (traced again by `eyeshell optics`
//! with the number), and bad keys are refused in one line with nothing written.

use std::path::Path;

use crate::support::*;

/// The overrides that make scenes/myopia/*.toml quick: 51 nodes (4e-5 mm from 201), a
/// quarter of a year, one output time.
const QUICK: [&str; 4] = [
    "solver.nodes=51",
    "time.end=8.25",
    "output.times=[8.25]",
    "output.history_points=0",
];

/// The single-vision myope of scenes/myopia/ with `lens` in place of its −2 D lens's power
/// line, then `sweep` (a `[sweep]` table).
fn myope(lens: &str, sweep: &str) -> String {
    let text = std::fs::read_to_string(repo().join("scenes/myopia/single-vision.toml")).unwrap();
    assert!(text.contains("\npower = -2.0\n"));
    format!(
        "{}\n{sweep}",
        text.replace("\npower = -2.0\n", &format!("\n{lens}\n"))
    )
}

/// `eyeshell sweep s.toml` of `scene` with the quick overrides, in `dir`; its sweep.csv.
fn sweep(dir: &Path, scene: &str) -> (Vec<String>, Vec<Vec<String>>) {
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let mut args = vec!["sweep", "s.toml", "--out", "out", "--quiet"];
    for set in QUICK {
        args.extend(["--set", set]);
    }
    succeeded(&eyeshell_in(dir, &args), "sweep");
    csv_cells(&dir.join("out/sweep.csv"))
}

/// Column `name` of a table's header.
fn at(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// The first row (t = 0) of a run's series.csv: (axial length, refraction_D, defocus_D).
fn start(run: &Path) -> (f64, f64, f64) {
    let (header, rows) = csv_cells(&run.join("series.csv"));
    let cell = |name: &str| rows[0][at(&header, name)].parse::<f64>().unwrap();
    assert_eq!(cell("t"), 0.0);
    (
        cell("axial_length"),
        cell("refraction_D"),
        cell("defocus_D"),
    )
}

/// A thin lens's vergence at the cornea from its power `p` at 12 mm (D).
fn at_cornea(p: f64) -> f64 {
    p / (1.0 - 0.012 * p)
}

/// The on-axis best focus (mm from the corneal apex) of the single-vision myope's eye with
/// the cornea's radius `radius` wearing `lens` (an inline TOML table), traced by
/// `eyeshell optics` at 555 nm (its first wavelength, the refraction's) into `out`.
fn worn_focus(out: &Path, radius: f64, lens: &str) -> f64 {
    ok(&[
        "optics",
        "scenes/myopia/single-vision.toml",
        "--set",
        &format!("optics.surfaces[0].radius={radius:?}"),
        "--set",
        &format!("optics.lenses=[{lens}]"),
        "--set",
        "optics.max_field=5",
        "--out",
        s(out),
        "--quiet",
    ]);
    let (header, rows) = csv_cells(&out.join("surfaces.csv"));
    assert_eq!(header[2], "z", "{header:?}");
    rows[0][2].parse().unwrap()
}

/// A cohort of 6 drawing the cornea's radius, the lens's power and the pupil: sweep.csv and
/// each eye's summary.json hold its own drawn values; its refraction at t = 0 follows its
/// cornea (a flatter cornea has less power: the eye is less myopic, by about the change of
/// the front surface's power), and its defocus through its own lens at t = 0 is the lens's
/// vergence against the eye's at the cornea; the eyes grow apart.
#[test]
fn a_sample_draws_each_eyes_cornea_lens_and_pupil() {
    let dir = tempfile::tempdir().unwrap();
    let keys = [
        "optics.surfaces[0].radius",
        "optics.lenses[0].power",
        "optics.pupil",
    ];
    let scene = myope(
        "power = -2.0",
        "[sweep.sample]\neyes = 6\ndesign = \"latin-hypercube\"\nseed = 4\n[sweep.sample.keys]\n\
         \"optics.surfaces[0].radius\" = { dist = \"uniform\", low = 7.4, high = 8.1 }\n\
         \"optics.lenses[0].power\" = { dist = \"uniform\", low = -3.0, high = -1.0 }\n\
         [sweep.sample.keys.optics]\npupil = { dist = \"uniform\", low = 2.5, high = 4.0 }\n",
    );
    let (header, rows) = sweep(dir.path(), &scene);
    assert_eq!(rows.len(), 6);
    let mut eyes = Vec::new();
    for row in &rows {
        let drawn: Vec<f64> = keys
            .iter()
            .map(|k| row[at(&header, k)].parse().unwrap())
            .collect();
        let run = dir.path().join("out/runs").join(&row[0]);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap())
                .unwrap();
        let p = &summary["parameters"];
        assert_eq!(p["optics.surfaces"][0]["radius"].as_f64(), Some(drawn[0]));
        assert_eq!(p["optics.lenses"][0]["power"].as_f64(), Some(drawn[1]));
        assert_eq!(p["optics.pupil"].as_f64(), Some(drawn[2]));
        let (length, refraction, defocus) = start(&run);
        // The defocus through the lens: its vergence at the cornea against the one the eye
        // needs (positive when the image lies behind the retina), converted by the eye's
        // paraxial vergence (0.0017 D from this at 0.5 D).
        let expected = at_cornea(refraction) - at_cornea(drawn[1]);
        assert!(
            (defocus - expected).abs() < 0.01 + 0.01 * expected.abs(),
            "{}: defocus {defocus} D, expected {expected} D",
            row[0]
        );
        let final_length: f64 = row[at(&header, "axial_length")].parse().unwrap();
        eyes.push((drawn, length, refraction, final_length));
    }
    for k in 0..3 {
        let mut values: Vec<f64> = eyes.iter().map(|e| e.0[k]).collect();
        values.sort_by(f64::total_cmp);
        values.dedup();
        assert_eq!(values.len(), 6, "{}: each eye its own", keys[k]);
    }
    // One shell: the same retina at t = 0, each cornea its own refraction.
    assert!(eyes.iter().all(|e| e.1 == eyes[0].1));
    eyes.sort_by(|a, b| a.0[0].total_cmp(&b.0[0]));
    // A flatter cornea, a less myopic eye, wherever the radii differ by more than the
    // pupils' aberrations move the focus (0.1 mm of radius is about 0.6 D).
    for pair in eyes.windows(2).filter(|p| p[1].0[0] - p[0].0[0] > 0.1) {
        assert!(pair[1].2 > pair[0].2, "{:?} then {:?}", pair[0], pair[1]);
    }
    // The front surface's power (n − 1)/r, n = 1.376 (the Atchison 2006 cornea): from the
    // steepest to the flattest cornea the vergence at the cornea moves by its change, to
    // 5 % (2.2 % here: the pupils' aberrations and the back surface's share are not in it).
    let (a, b) = (&eyes[0], &eyes[5]);
    let change = 376.0 * (1.0 / a.0[0] - 1.0 / b.0[0]);
    let moved = at_cornea(b.2) - at_cornea(a.2);
    eprintln!(
        "radius {} → {} mm: {moved} D at the cornea, the surface {change} D",
        a.0[0], b.0[0]
    );
    assert!(
        (moved - change).abs() < 0.05 * change,
        "radius {} → {}: refraction {} → {} D ({moved} D at the cornea, the surface {change} D)",
        a.0[0],
        b.0[0],
        a.2,
        b.2
    );
    let mut finals: Vec<f64> = eyes.iter().map(|e| e.3).collect();
    finals.sort_by(f64::total_cmp);
    finals.dedup();
    assert_eq!(finals.len(), 6, "each eye grows as its own: {finals:?}");
}

/// `power = "prescribe"` on a grid of two corneas × spectacle or contact lens × `over` of 0
/// or −0.5 D: the spectacle lens's power is the eye's own refraction_D at t = 0, the
/// contact lens's its vertex conversion; worn, each puts the 555 nm focus on the retina
/// (traced again by `eyeshell optics` with the number: 0.0043 mm is 0.01 D here) and the
/// run's defocus at t = 0 is 0 within 0.01 D; `over` adds to the power, and the eye
/// over-corrected by −0.5 D sees that much hyperopic defocus (its vergence at the cornea).
#[test]
fn a_prescribed_lens_corrects_its_own_eye_at_the_start() {
    let dir = tempfile::tempdir().unwrap();
    let scene = myope(
        "power = \"prescribe\"",
        "[sweep.grid]\n\"optics.surfaces[0].radius\" = [7.6, 7.9]\n\
         \"optics.lenses[0].kind\" = [\"spectacle\", \"contact\"]\n\
         \"optics.lenses[0].over\" = [0.0, -0.5]\n",
    );
    let (header, rows) = sweep(dir.path(), &scene);
    assert_eq!(rows.len(), 8);
    let power = at(&header, "optics.lenses[0].power");
    let mut runs = std::collections::BTreeMap::new();
    for row in &rows {
        let radius: f64 = row[at(&header, "optics.surfaces[0].radius")]
            .parse()
            .unwrap();
        let kind = row[at(&header, "optics.lenses[0].kind")].clone();
        let over: f64 = row[at(&header, "optics.lenses[0].over")].parse().unwrap();
        let p: f64 = row[power].parse().unwrap();
        let run = dir.path().join("out/runs").join(&row[0]);
        let scene_toml = std::fs::read_to_string(run.join("scene.toml")).unwrap();
        assert!(scene_toml.contains("power = \"prescribe\""), "{scene_toml}");
        runs.insert((radius.to_bits(), kind, over.to_bits()), (p, start(&run)));
    }
    let get = |radius: f64, kind: &str, over: f64| {
        runs[&(radius.to_bits(), kind.to_string(), over.to_bits())]
    };
    for radius in [7.6, 7.9] {
        let (spectacle, (length, refraction, defocus)) = get(radius, "spectacle", 0.0);
        assert!(
            (spectacle - refraction).abs() < 1e-9,
            "{spectacle} vs {refraction}"
        );
        assert!(defocus.abs() < 0.01, "{defocus}");
        let (contact, (_, _, contact_defocus)) = get(radius, "contact", 0.0);
        assert!((contact - at_cornea(refraction)).abs() < 1e-12);
        assert!(contact_defocus.abs() < 0.01, "{contact_defocus}");
        for (name, lens) in [
            (
                "spectacle",
                format!("{{ kind = \"spectacle\", vertex = 12, power = {spectacle:?} }}"),
            ),
            (
                "contact",
                format!("{{ kind = \"contact\", power = {contact:?} }}"),
            ),
        ] {
            let out = dir.path().join(format!("optics-{radius}-{name}"));
            let focus = worn_focus(&out, radius, &lens);
            assert!(
                (focus - length).abs() < 0.0043,
                "{lens}: focus {focus} mm, retina {length} mm"
            );
        }
        for kind in ["spectacle", "contact"] {
            let (p, _) = get(radius, kind, 0.0);
            let (q, (_, _, d)) = get(radius, kind, -0.5);
            assert!((q - (p - 0.5)).abs() < 1e-12, "{kind}: {q} vs {p} − 0.5");
            let expected = at_cornea(p) - at_cornea(q);
            let expected = if kind == "contact" { 0.5 } else { expected };
            assert!(
                (d - expected).abs() < 0.01,
                "{kind}: defocus {d}, expected {expected}"
            );
        }
    }
    // The steeper cornea is the more myopic eye: its prescription more minus, by over 1 D.
    assert!(get(7.6, "spectacle", 0.0).0 < get(7.9, "spectacle", 0.0).0 - 1.0);
}

/// scenes/myopia/cohort.toml with 8 of its 200 children: each child's lens is its own, its
/// power that child's refraction_D at t = 0, and every run says "prescribe".
#[test]
fn the_myopia_cohort_gives_each_child_its_own_lens() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo().join("scenes/myopia/cohort.toml")).unwrap();
    assert!(text.contains("\neyes = 200\n"));
    let (header, rows) = sweep(dir.path(), &text.replace("\neyes = 200\n", "\neyes = 8\n"));
    assert_eq!(rows.len(), 8);
    let mut powers = Vec::new();
    for row in &rows {
        assert_eq!(row[1], "ok");
        let p: f64 = row[at(&header, "optics.lenses[0].power")].parse().unwrap();
        let (_, refraction, defocus) = start(&dir.path().join("out/runs").join(&row[0]));
        assert!(
            (p - refraction).abs() < 1e-9,
            "{}: {p} vs {refraction}",
            row[0]
        );
        assert!(defocus.abs() < 0.01, "{}: {defocus}", row[0]);
        powers.push(p);
    }
    powers.sort_by(f64::total_cmp);
    powers.dedup();
    assert_eq!(powers.len(), 8, "{powers:?}");
    assert!(powers[7] - powers[0] > 1.0, "{powers:?}");
}

/// Bad indexed keys and prescriptions: one line naming the key, exit 2, nothing written.
#[test]
fn bad_indexed_keys_are_refused_and_nothing_is_written() {
    let sample = |key: &str| {
        myope(
            "power = -2.0",
            &format!("[sweep.sample]\neyes = 4\nseed = 1\n[sweep.sample.keys]\n\"{key}\" = {{ dist = \"uniform\", low = 1.0, high = 2.0 }}\n"),
        )
    };
    let grid =
        |lens: &str, key: &str| myope(lens, &format!("[sweep.grid]\n\"{key}\" = [-1.0, -2.0]\n"));
    for (scene, sets, needle) in [
        (sample("optics.surfaces[16].radius"), vec![], "optics.surfaces[16].radius = { dist"),
        (sample("optics.lenses[0].kind"), vec![], "optics.lenses[0].kind is not a real-valued key"),
        (grid("power = -2.0", "optics.lenses[0].powr"), vec![], "optics.lenses[0].powr = [-1.0, -2.0] is not a lens's key"),
        (grid("power = -2.0", "optics.lenses[2].power"), vec![], "optics.lenses[2].power = float -1 is not a lens of the scene: it wears 1 lens"),
        (grid("power = -2.0", "optics.lenses[0].over"), vec![], "optics.lenses[0].over = -1 is the offset of a prescribed lens"),
        (grid("power = \"prescribd\"", "optics.pupil"), vec![], "optics.lenses[0].power = \"prescribd\" must be a number (D) or \"prescribe\""),
        (grid("power = -2.0", "optics.lenses[0].power"), vec!["optics.lenses=[{ power = -1 }]"], "sweeps optics.lenses[0].power: remove `--set optics.lenses=[{ power = -1 }]`"),
        (myope("power = -2.0", ""), vec!["optics.lenses[4].power=1"], "optics.lenses[4].power = integer 1 is not a lens's key: write optics.lenses[i].key with i from 0 to 3"),
    ] {
        let cmd = if scene.contains("[sweep") { "sweep" } else { "grow" };
        let origin = if needle.starts_with("sweeps") || sets.is_empty() { "scene.toml" } else { "--set" };
        fails(cmd, &scene, &sets, needle, origin);
    }
}
