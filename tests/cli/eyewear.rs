//! Eyewear and refraction in dioptres: refraction_D in a run's files, consistent with the
//! optics it comes from, and bad lenses refused in one line naming the item, nothing written.

use crate::support::*;

/// The paper's const scene (101 nodes) starts hyperopic in dioptres too, and ends with a
/// refraction whose sign its class agrees with (emmetropic: within ±0.5 D); the refraction at
/// t = 0, worn as a spectacle lens, brings the default eye's best focus onto the retina
/// (`eyeshell optics` traces it, lens on) to 0.01 D.
#[test]
fn the_const_scene_refraction_is_consistent() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("const");
    ok(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=101",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let (header, rows) = csv_cells(&out.join("series.csv"));
    assert_eq!(header[6], "refraction_D");
    let num = |r: &Vec<String>, i: usize| r[i].parse::<f64>().unwrap();
    let (first, last) = (&rows[0], rows.last().unwrap());
    let (length0, rx0) = (num(first, 1), num(first, 6));
    assert_eq!(first[5], "hyperopic");
    // 19.956 mm against the Atchison 2006 eye's 555 nm focus near 23.5 mm: about +10.5 D.
    assert!(rx0 > 9.0 && rx0 < 12.0, "{rx0}");
    let rx1 = num(last, 6);
    assert_eq!(last[5], "emmetropic");
    assert!(rx1.abs() <= 0.5, "{rx1}");
    let (_, history) = csv_cells(&out.join("history.csv"));
    assert!(history
        .iter()
        .all(|r| r[6].parse::<f64>().unwrap().is_finite()));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["final"]["refraction_D"].as_f64().unwrap(), rx1);

    // peripheral.csv: every output time at every 5° to optics.max_field (40°); field 0 is
    // the pole, whose refraction (from a 2.5 D table) is series.csv's (from a 1 D table).
    let (header, peripheral) = csv_cells(&out.join("peripheral.csv"));
    assert_eq!(header, ["t", "field_deg", "refraction_D", "relative_D"]);
    assert_eq!(peripheral.len(), rows.len() * 9);
    for (k, row) in rows.iter().enumerate() {
        let at = &peripheral[9 * k..9 * (k + 1)];
        let fields: Vec<f64> = at.iter().map(|p| num(p, 1)).collect();
        assert_eq!(fields, [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0]);
        assert!(at.iter().all(|p| p[0] == row[0]));
        assert!(
            (num(&at[0], 2) - num(row, 6)).abs() < 1e-3,
            "{at:?} {row:?}"
        );
        assert_eq!(num(&at[0], 3), 0.0);
        // To 30° every time has a refraction; at 35° and 40° the +10 D eye of t = 0 has none
        // (the foci there fail for the strongest plus lenses, which the cubic around that
        // refraction needs): NaN in both columns.
        for (k, p) in at.iter().enumerate() {
            assert!(k > 6 || num(p, 2).is_finite(), "{p:?}");
            let relative = num(p, 2) - num(&at[0], 2);
            assert!(
                (num(p, 3) - relative).abs() < 1e-12 || (relative.is_nan() && num(p, 3).is_nan()),
                "{p:?}"
            );
        }
    }

    // The refraction worn: the 555 nm on-axis best focus with the lens on.
    let eye = dir.path().join("eye");
    ok(&[
        "optics",
        "scenes/const.toml",
        "--set",
        "stimulus.source=optics",
        "--set",
        "optics.wavelengths=[555, 600]",
        "--set",
        &format!("optics.lenses=[{{ kind = \"spectacle\", vertex = 12, power = {rx0:?} }}]"),
        "--set",
        "optics.max_field=5",
        "--out",
        s(&eye),
        "--quiet",
    ]);
    let (_, foci) = csv_cells(&eye.join("surfaces.csv"));
    let focus = num(&foci[0], 2);
    // About 2.3 D per mm of focus at this refraction: 0.01 D is 0.0043 mm.
    assert!(
        (focus - length0).abs() < 0.0043,
        "focus {focus} vs retina {length0}"
    );
}

/// With stimulus.classify = "dioptres" the class follows refraction_D's thresholds.
#[test]
fn the_class_follows_dioptres_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    ok(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=101",
        "--set",
        "stimulus.classify=dioptres",
        "--set",
        "stimulus.hyperopia_D=2.5",
        "--set",
        "output.history_points=0",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let (_, rows) = csv_cells(&out.join("series.csv"));
    for r in &rows {
        let rx: f64 = r[6].parse().unwrap();
        let expect = if rx > 2.5 {
            "hyperopic"
        } else if rx < -0.5 {
            "myopic"
        } else {
            "emmetropic"
        };
        assert_eq!(r[5], expect, "{r:?}");
    }
    // t = 0.2 is +2.1 D: emmetropic by these thresholds, hyperopic by the surfaces.
    assert_eq!(rows[2][5], "emmetropic");
}

/// Bad eyewear: one line naming the item, exit 2, nothing written.
#[test]
fn bad_lenses_are_refused_and_nothing_is_written() {
    let scene = "growth.eta0 = 70\nstimulus.source = \"optics\"\n";
    let lens = |body: &str| format!("{scene}[[optics.lenses]]\n{body}\n");
    // A lens whose edge the rays pass.
    fails(
        "grow",
        &lens("zones = [{ radius = 2, power = -2 }, { radius = 6, power = 0.5 }]"),
        &[],
        "optics.lenses[0].zones[1].radius = 6 is the lens's edge",
        "scene.toml",
    );
    // Zones out of order, in the second lens.
    fails(
        "grow",
        &format!(
            "{}[[optics.lenses]]\nkind = \"contact\"\nzones = [{{ radius = 3, power = -2 }}, {{ radius = 2, power = 0 }}]\n",
            lens("power = -1")
        ),
        &[],
        "optics.lenses[1].zones[1].radius = 2 must be larger than the previous zone's radius (3 mm)",
        "scene.toml",
    );
    fails(
        "grow",
        &lens("vertex = -3\npower = -2"),
        &[],
        "optics.lenses[0].vertex = -3 must lie in (0, 50] mm",
        "scene.toml",
    );
    // A ball-like lens focuses the light 5 mm behind it: the eye receives it diverging at
    // about −140 D and forms no image.
    fails(
        "grow",
        &lens("front_radius = 5\nback_radius = -5\nthickness = 3\nindex = 1.5"),
        &["optics.max_field=5"],
        "form no image in the atchison-2006 eye",
        "scene.toml",
    );
    fails(
        "grow",
        &lens("power = 1e9"),
        &[],
        "optics.lenses[0].power = 1000000000 must lie in [-100, 100] D",
        "scene.toml",
    );
    fails(
        "grow",
        &lens("power = -2\nzones = [{ radius = 4, power = 1 }]"),
        &[],
        "optics.lenses[0] = (this lens) must give exactly one of power, zones, table",
        "scene.toml",
    );
    // Lenses change computed surfaces only.
    fails(
        "grow",
        "growth.eta0 = 70\n[[optics.lenses]]\npower = -2\n",
        &[],
        "need stimulus.source = \"optics\"",
        "scene.toml",
    );
    fails(
        "grow",
        scene,
        &["stimulus.myopia_D=3"],
        "stimulus.myopia_D = 3 must lie in [-25, 0] D",
        "--set stimulus.myopia_D=3",
    );
}

/// A table lens is worn (spectacle, contact, and a flat table of two points, which is the
/// uniform lens of its power), and so is a ring design whose outer rings lie beyond what the
/// pupil sees: every real lens is wider than what the eye looks through. optics.json says
/// how far the rays reach and which zones none crosses.
#[test]
fn table_lenses_and_rings_beyond_the_pupil_are_worn() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        "growth.eta0 = 70\nstimulus.source = \"optics\"\n[optics]\npupil = 1.0\nmax_field = 10\n",
    )
    .unwrap();
    let grow = |name: &str, lenses: &str| -> f64 {
        let out = dir.path().join(name);
        let set = format!("optics.lenses={lenses}");
        let r = eyeshell_in(
            dir.path(),
            &[
                "grow",
                s(&scene),
                "--set",
                "solver.nodes=101",
                "--set",
                &set,
                "--out",
                s(&out),
                "--quiet",
            ],
        );
        assert_eq!(r.code, Some(0), "{name}: {}", r.stderr);
        let (header, rows) = csv_cells(&out.join("series.csv"));
        let last = |c: &str| -> f64 {
            let j = header.iter().position(|h| h == c).unwrap();
            rows.last().unwrap()[j].parse().unwrap()
        };
        assert!(last("refraction_D").is_finite(), "{name}");
        last("axial_length")
    };
    let uniform = grow("uniform", "[{ power = -2 }]");
    let flat = grow(
        "flat",
        "[{ table = [{ radius = 0, power = -2 }, { radius = 20, power = -2 }] }]",
    );
    // The same lens but for its edge and its phase, integrated (Gauss–Legendre) where the
    // uniform lens's is exact, and the ray count chosen for each: the same eye to within the
    // runs' focus tolerance (1e-5 mm, measured 2.5e-6 mm).
    assert!((flat - uniform).abs() < 1e-5, "{flat} vs {uniform}");
    let table = grow(
        "table",
        "[{ table = [{ radius = 0, power = -2 }, { radius = 3, power = -1.5 }, { radius = 20, power = 0.5 }] }]",
    );
    assert!(
        table.is_finite() && (table - uniform).abs() > 1e-3,
        "{table} vs {uniform}"
    );
    let contact = grow(
        "contact",
        "[{ kind = \"contact\", table = [{ radius = 0, power = -2 }, { radius = 7, power = -1 }] }]",
    );
    assert!(contact.is_finite());
    // Rings out to 30 mm at 12 mm in front of a 1 mm pupil seen to 10°: the rays cross the
    // lens within about 2.5 mm of its axis, so the rings from 5 mm on are never looked through
    // and the run is the single-vision lens's (to the runs' focus tolerance: the rings' lens
    // has an edge, the uniform one none).
    let rings = grow(
        "rings",
        "[{ zones = [{ radius = 5, power = -2 }, { radius = 10, power = 0.5 }, { radius = 30, power = 1 }] }]",
    );
    assert!((rings - uniform).abs() < 1e-5, "{rings} vs {uniform}");
    let out = dir.path().join("optics");
    let r = eyeshell_in(
        dir.path(),
        &[
            "optics",
            s(&scene),
            "--set",
            "optics.lenses=[{ zones = [{ radius = 5, power = -2 }, { radius = 10, power = 0.5 }, { radius = 30, power = 1 }] }]",
            "--out",
            s(&out),
            "--quiet",
        ],
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("optics.json")).unwrap()).unwrap();
    let lens = &json["lenses"][0];
    let reach = lens["rays_reach_mm"].as_f64().unwrap();
    assert!(reach > 0.5 && reach < 5.0, "{lens}");
    let unseen: Vec<&str> = lens["zones_no_ray_crosses"]
        .as_array()
        .unwrap()
        .iter()
        .map(|z| z["zone"].as_str().unwrap())
        .collect();
    assert_eq!(
        unseen,
        ["optics.lenses[0].zones[1]", "optics.lenses[0].zones[2]"]
    );
}

/// Two contact lenses are refused in words (the cornea holds one), naming the second; a
/// lens list many rings long is never echoed whole: the line stays short.
#[test]
fn two_contact_lenses_are_refused_in_words() {
    let scene = "growth.eta0 = 70\nstimulus.source = \"optics\"\n";
    fails(
        "grow",
        scene,
        &["optics.lenses=[{ kind = \"contact\", power = -1 }, { kind = \"contact\", power = 1 }]"],
        "optics.lenses[1].kind = \"contact\" is a second contact lens (optics.lenses[0] is one): two contact lenses cannot be worn at once",
        "--set optics.lenses=",
    );
    let rings: Vec<String> = (1..=20)
        .map(|k| {
            format!(
                "{{ radius = {}, power = {} }}",
                k as f64 * 0.2,
                if k % 2 == 0 { -2 } else { 0 }
            )
        })
        .collect();
    let set = format!("optics.lenses=[{{ zones = [{}] }}]", rings.join(", "));
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    let r = eyeshell_in(
        dir.path(),
        &["grow", "scene.toml", "--set", &set, "--out", "out"],
    );
    assert_bad(
        &r,
        "optics.lenses[0].zones[19].radius = 4 is the lens's edge",
        "20 rings",
    );
    assert!(
        r.stderr.len() <= 300,
        "{} characters: {}",
        r.stderr.len(),
        r.stderr
    );
    assert!(!dir.path().join("out").exists());
}

/// Bad lenslet and zone input, in `eyeshell optics`: one line of at most 300 characters
/// naming the lens and its key, exit 2, nothing written.
#[test]
fn bad_multifocal_lenses_are_refused_in_one_short_line() {
    let scene = "stimulus.source = \"optics\"\n[optics]\nmax_field = 20\n";
    let lens = |zones: &str| format!("{scene}[[optics.lenses]]\nzones = [{zones}]\n");
    let cases = [
        (
            "{ radius = 4.7, power = -2 }, { radius = 16.5, power = -2, lenslets = { power = 1.5, fill = 1.5 } }",
            "optics.lenses[0].zones[1].lenslets.fill = 1.5 must lie in [0, 1]",
        ),
        (
            "{ radius = 4.7, power = -2 }, { radius = 16.5, power = -2, lenslets = { power = 1.5, fill = -0.1 } }",
            "optics.lenses[0].zones[1].lenslets.fill = -0.1 must lie in [0, 1]",
        ),
        // +90 D segments focus the light 11 mm behind the lens, in front of the eye.
        (
            "{ radius = 4.7, power = -2 }, { radius = 25, power = -2, lenslets = { power = 90, fill = 0.5 } }",
            "optics.lenses[0].zones[1].lenslets.power = 90 forms no image in the atchison-2006 eye",
        ),
        // Overlapping (the second zone ends inside the first) and unordered zones.
        (
            "{ radius = 4.7, power = -2 }, { radius = 4.7, power = 0 }, { radius = 25, power = -2 }",
            "optics.lenses[0].zones[1].radius = 4.7 must be larger than the previous zone's radius (4.7 mm)",
        ),
        (
            "{ radius = 8, power = -2 }, { radius = 3, power = 0 }, { radius = 25, power = -2 }",
            "optics.lenses[0].zones[1].radius = 3 must be larger than the previous zone's radius (8 mm)",
        ),
        (
            "{ radius = 4.7, power = -2, lenslets = { power = 1.5 } }, { radius = 25, power = -2 }",
            "optics.lenses[0].zones[0].lenslets.fill = (missing) must be given",
        ),
    ];
    for (zones, needle) in cases {
        let text = lens(zones);
        fails("optics", &text, &[], needle, "scene.toml");
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scene.toml"), &text).unwrap();
        let run = eyeshell_in(dir.path(), &["optics", "scene.toml", "--out", "out"]);
        assert!(run.stderr.chars().count() <= 300, "{}", run.stderr);
    }
}

/// The foci (z, r) and shares of each image at 400 nm from `eyeshell optics`'s surfaces.csv:
/// `[image][field]`.
fn images_at_400(out: &std::path::Path) -> Vec<Vec<(f64, f64, f64)>> {
    let (header, rows) = csv_cells(&out.join("surfaces.csv"));
    assert_eq!(&header[6..], ["image", "share"]);
    let mut images: Vec<Vec<(f64, f64, f64)>> = Vec::new();
    for r in rows.iter().filter(|r| r[0] == "400.0") {
        let k: usize = r[6].parse().unwrap();
        if images.len() <= k {
            images.push(Vec::new());
        }
        let n = |i: usize| r[i].parse::<f64>().unwrap();
        images[k].push((n(2), n(3), n(7)));
    }
    images
}

/// The lenslet spectacle (scenes/eyewear/lenslets.toml) and a 20-ring design that steps back
/// to the base power, out to 30 mm, each form two images, and no image's surface jumps from
/// one field to the next by more than the naked eye's surface does plus the two powers' own
/// foci's difference (the one-wavefront trace of such lenses spiked at a zone's edge, or
/// found no chief ray). Inside the lenslet ring the segments carry exactly their fill.
#[test]
fn lenslet_and_ring_designs_form_two_smooth_images() {
    let dir = tempfile::tempdir().unwrap();
    let rings: Vec<String> = (0..20)
        .map(|k| {
            let power = if k % 2 == 0 { -2.0 } else { 0.0 };
            format!("{{ radius = {}, power = {power:?} }}", 1.5 * (k + 1) as f64)
        })
        .collect();
    let ring_lens = format!(
        "optics.lenses=[{{ kind = \"spectacle\", vertex = 12, zones = [{}] }}]",
        rings.join(", ")
    );
    let none = dir.path().join("none");
    ok(&[
        "optics",
        "scenes/eyewear/none.toml",
        "--out",
        s(&none),
        "--quiet",
    ]);
    let naked = &images_at_400(&none)[0];
    for (name, sets) in [
        ("lenslets", vec![]),
        ("rings", vec!["--set", ring_lens.as_str()]),
    ] {
        let out = dir.path().join(name);
        let scene = if name == "lenslets" {
            "scenes/eyewear/lenslets.toml"
        } else {
            "scenes/eyewear/single-vision.toml"
        };
        let mut args = vec!["optics", scene, "--out", s(&out), "--quiet"];
        args.extend(sets);
        ok(&args);
        let images = images_at_400(&out);
        assert_eq!(images.len(), 2, "{name}");
        for j in 0..naked.len() {
            let sum: f64 = images.iter().map(|im| im[j].2).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{name} at {j}°: {sum}");
            if j > 0 {
                let gap = (images[0][j].0 - images[1][j].0).abs();
                let step = |p: &[(f64, f64, f64)]| (p[j].0 - p[j - 1].0).hypot(p[j].1 - p[j - 1].1);
                for (k, im) in images.iter().enumerate() {
                    assert!(
                        step(im) <= step(naked) + gap,
                        "{name}: image {k} jumps {} mm at {j}° (naked {}, gap {gap})",
                        step(im),
                        step(naked)
                    );
                }
            }
        }
        if name == "lenslets" {
            // On the axis the pencil is inside the 9.4 mm centre; from 25° it is inside the
            // ring, where half the light goes through the segments.
            assert_eq!(images[0][0].2, 1.0);
            for j in 25..=40 {
                assert!(
                    (images[1][j].2 - 0.5).abs() < 1e-9,
                    "{j}°: {}",
                    images[1][j].2
                );
            }
        }
    }
}

/// A lens of two images on an eye that changes with age is refused naming the lens: the
/// blend over t is of one surface per wavelength.
#[test]
fn a_multifocal_lens_on_an_eye_that_changes_with_age_is_refused() {
    let age = std::fs::read_to_string(repo().join("scenes/optics-age.toml")).unwrap();
    fails(
        "optics",
        &format!(
            "{age}\n[[optics.lenses]]\nzones = [{{ radius = 4.7, power = -2 }}, {{ radius = 25, power = 0.5 }}]\n"
        ),
        &[],
        "optics.lenses[0] = (spectacle lens at 12 mm, 2 zones) forms 2 images, but the eye changes with age",
        "scene.toml",
    );
}
