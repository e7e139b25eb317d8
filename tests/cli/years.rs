//! Growth in years (time.*, growth.schedule*): bad clocks, schedules and ages are refused in
//! one line before any run; a schedule is the constant-rate run on another clock.

use crate::support::*;

fn grow_fails(scene: &str, needle: &str) {
    fails("grow", scene, &[], needle, "scene.toml: ");
}

const YEARS: &str = "[growth]\neta0 = 3.5\n[time]\nunit = \"years\"\nstart = 0\nend = 20\n";

#[test]
fn bad_clocks_and_schedules_are_refused_in_one_line() {
    grow_fails(
        "[growth]\neta0 = 70\n[time]\nunit = \"years\"\n",
        "time.start and time.end must both be given",
    );
    grow_fails(
        "[growth]\neta0 = 70\n[time]\nunit = \"days\"\nstart = 3\n",
        "time.unit",
    );
    grow_fails(
        "[growth]\neta0 = 70\n[time]\nunit = \"years\"\nstart = 5\nend = 1\n",
        "time.end = 1 must come after time.start = 5 (the ages are out of order)",
    );
    let table = |times: &str, factors: &str| {
        format!("[growth]\neta0 = 70\nschedule = \"table\"\nschedule_times = {times}\nschedule_factors = {factors}\n[time]\nunit = \"years\"\nstart = 0\nend = 20\n")
    };
    grow_fails(
        &table("[0, 4, 2]", "[1, 1, 1]"),
        "growth.schedule_times = [0, 4, 2] must be strictly increasing (the ages are out of order): 2 (item 3) follows 4",
    );
    grow_fails(
        &table("[0, 2, 4]", "[1, -0.5, 1]"),
        "item 2 is -0.5: a factor on growth.eta0 must be finite, at least 0",
    );
    grow_fails(
        &table("[0, 2, 4]", "[1, nan, 1]"),
        "growth.schedule_factors",
    );
    grow_fails(&table("[0, 2, 4]", "[1, 1e300, 1]"), "at most 1000000");
    grow_fails(&table("[0, 2]", "[1, 1, 1]"), "holds 3 factors for 2 times");
    grow_fails(
        "[growth]\nschedule = \"exponential\"\nschedule_tau = -1\n",
        "growth.schedule_tau = -1 must be positive",
    );
    grow_fails(
        "[growth]\nschedule = \"logistic\"\nschedule_width = 0\n",
        "growth.schedule_width = 0 must be positive",
    );
}

/// One clock: with time.unit the rates are per year, so the single-vision child of
/// scenes/myopia/ grown from 8 to 14 years has, at 11, the axial length of the same child
/// grown from 8 to 11 (to 1e-6 mm at a tolerance that leaves the integrators' difference
/// below it; 2.5e-8 mm measured), and its snapshots are at the ages written.
#[test]
fn a_longer_window_keeps_the_growth_per_year() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo().join("scenes/myopia/single-vision.toml");
    let grow = |out: &str, sets: &[&str]| {
        let mut args = vec!["grow", s(&scene), "--out", out, "--quiet"];
        for set in ["solver.rtol=1e-9", "solver.atol=1e-11"].iter().chain(sets) {
            args.extend(["--set", set]);
        }
        succeeded(&eyeshell_in(d, &args), out);
        let series = d.join(out).join("series.csv");
        let ages = numbers(&series, "age");
        let lengths = numbers(&series, "axial_length");
        (ages, lengths, numbers(&series, "t"))
    };
    let (ages, short, t) = grow("short", &[]);
    assert_eq!(ages, [8.0, 9.0, 10.0, 11.0]);
    assert_eq!(t, [0.0, 1.0, 2.0, 3.0]);
    let (ages, long, _) = grow("long", &["time.end=14", "output.times=[9, 10, 11, 14]"]);
    assert_eq!(ages, [8.0, 9.0, 10.0, 11.0, 14.0]);
    for (a, b) in short.iter().zip(&long) {
        assert!((a - b).abs() < 1e-6, "{short:?} against {long:?}");
    }
    // The growth goes on after 11, and is the same child's: 3 years more, less than 1.5×
    // the first 3 years' (the growth slows as the retina nears the surface).
    let (first, more) = (long[3] - long[0], long[4] - long[3]);
    assert!(more > 0.2 && more < first * 1.5, "{long:?}");
}

/// The other times a user writes with time.unit are ages too: `optics --at` takes one in
/// [time.start, time.end], and `check` shows the window's t_end and default output times as
/// comments that follow the ages (read back, the scene is the same).
#[test]
fn optics_at_takes_an_age_and_check_shows_the_derived_times() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo().join("scenes/myopia/single-vision.toml");
    let optics = |at: &str| {
        let sets = ["optics.max_field=10", "--at", at, "--out", "o", "--quiet"];
        let mut args = vec!["optics", s(&scene), "--set"];
        args.extend(sets);
        eyeshell_in(d, &args)
    };
    assert_bad(
        &optics("5"),
        "--at 5: the eye's age must lie in [8, 11] years (time.start, time.end)",
        "--at before time.start",
    );
    assert!(!d.join("o").exists());
    succeeded(&optics("11"), "--at 11");
    std::fs::write(
        d.join("window.toml"),
        "[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 8\nend = 11\n",
    )
    .unwrap();
    let r = eyeshell_in(d, &["check", "window.toml"]);
    succeeded(&r, "check");
    for line in [
        "# growth.t_end = 3.0  (follows time.start and time.end)",
        "# output.times = [8.3, 8.6, 9.2, 11.0]  (follows time.start and time.end)",
    ] {
        assert!(r.stdout.contains(line), "{line}: {}", r.stdout);
    }
}

/// Ages in a fit's data: outside [time.start, time.end], or without a clock in the scene.
#[test]
fn ages_outside_the_clock_or_without_one_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("years.toml"),
        format!("{YEARS}[solver]\nnodes = 21\n"),
    )
    .unwrap();
    std::fs::write(
        d.join("t.toml"),
        "[growth]\neta0 = 70\n[solver]\nnodes = 21\n",
    )
    .unwrap();
    std::fs::write(d.join("late.csv"), "age,axial_length\n1,20\n2,21\n25,23\n").unwrap();
    std::fs::write(d.join("ages.csv"), "age,axial_length\n1,20\n2,21\n5,23\n").unwrap();
    let fit = |scene: &str, data: &str| {
        eyeshell_in(
            d,
            &[
                "fit",
                scene,
                "--data",
                data,
                "--fit",
                "growth.eta0",
                "--out",
                "out",
            ],
        )
    };
    let r = fit("years.toml", "late.csv");
    refused(
        &r,
        "late.csv: observation 3 (age 25 years) lies outside the scene's ages [time.start, time.end] = [0, 20] years",
        "age after time.end",
    );
    let r = fit("t.toml", "ages.csv");
    refused(
        &r,
        "the data give ages (an age column), but the scene counts no ages",
        "ages without time.unit",
    );
    assert!(!d.join("out").exists());
}

/// A table schedule of 2 everywhere is η0 doubled: the same run on a clock twice as fast.
#[test]
fn a_factor_of_two_is_eta0_doubled() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("double.toml"),
        "[growth]\neta0 = 70\nschedule = \"table\"\nschedule_times = [0, 1]\nschedule_factors = [2, 2]\n[solver]\nnodes = 21\n",
    )
    .unwrap();
    std::fs::write(
        d.join("fast.toml"),
        "[growth]\neta0 = 140\n[solver]\nnodes = 21\n",
    )
    .unwrap();
    for name in ["double", "fast"] {
        succeeded(
            &eyeshell_in(
                d,
                &["grow", &format!("{name}.toml"), "--out", name, "--quiet"],
            ),
            name,
        );
    }
    let lengths = |name: &str| -> Vec<f64> {
        let (h, rows) = csv_cells(&d.join(name).join("series.csv"));
        let j = h.iter().position(|c| c == "axial_length").unwrap();
        rows.iter().map(|r| r[j].parse().unwrap()).collect()
    };
    let (a, b) = (lengths("double"), lengths("fast"));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-9 * y, "{x} against {y}");
    }
    assert!(a[a.len() - 1] - a[0] > 1.0, "{a:?}");
}

/// Column `name` of a CSV file whose other columns may be text (series.csv's class).
fn numbers(path: &std::path::Path, name: &str) -> Vec<f64> {
    let (h, rows) = csv_cells(path);
    let j = h.iter().position(|c| c == name).unwrap();
    rows.iter().map(|r| r[j].parse().unwrap()).collect()
}

/// A scene in years carries the age beside t everywhere: series.csv, history.csv,
/// sensitivities.csv, peripheral.csv and the snapshots end in an `age` column, the snapshot files are named by age, `plot`
/// draws against age, and `fit` (data by age) reports, tabulates and draws by age.
#[test]
fn a_scene_in_years_has_ages_in_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Ages 2 to 12 years: t = age − 2, and η0 per year.
    std::fs::write(
        d.join("years.toml"),
        "[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 2\nend = 12\n[output]\nhistory_points = 4\n[solver]\nnodes = 21\n",
    )
    .unwrap();
    succeeded(
        &eyeshell_in(
            d,
            &[
                "grow",
                "years.toml",
                "--out",
                "run",
                "--sensitivities",
                "growth.eta0",
                "--quiet",
            ],
        ),
        "grow in years",
    );
    let run = d.join("run");
    for file in [
        "series.csv",
        "history.csv",
        "sensitivities.csv",
        "peripheral.csv",
    ] {
        let path = run.join(file);
        let (h, _) = csv_cells(&path);
        assert_eq!(h.last().map(String::as_str), Some("age"), "{file}: {h:?}");
        let (t, age) = (numbers(&path, "t"), numbers(&path, "age"));
        assert!(t.len() >= 5, "{file}: {t:?}");
        for (t, a) in t.iter().zip(&age) {
            assert!((a - (2.0 + t)).abs() <= 1e-12, "{file}: t {t}, age {a}");
        }
    }
    let names: Vec<String> = snapshots(&run)
        .iter()
        .map(|(p, _)| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [
            "snapshot_00000_age2.000000.csv",
            "snapshot_00001_age3.000000.csv",
            "snapshot_00002_age4.000000.csv",
            "snapshot_00003_age6.000000.csv",
            "snapshot_00004_age12.000000.csv"
        ]
    );
    // Each snapshot ends in its age, the same on every node: the age of its name.
    for ((p, _), want) in snapshots(&run).iter().zip([2.0, 3.0, 4.0, 6.0, 12.0]) {
        let (h, _) = csv_cells(p);
        assert_eq!(
            h.last().map(String::as_str),
            Some("age"),
            "{}: {h:?}",
            p.display()
        );
        let age = numbers(p, "age");
        assert!(age.len() > 10, "{}: {age:?}", p.display());
        for a in age {
            assert!(
                (a - want).abs() <= 1e-12,
                "{}: age {a}, want {want}",
                p.display()
            );
        }
    }
    // plot: the timeline and the sensitivities against age.
    succeeded(
        &eyeshell_in(d, &["plot", "run", "--out", "figs", "-q"]),
        "plot",
    );
    for f in ["timeline", "sensitivities", "profiles"] {
        let svg = std::fs::read_to_string(d.join(format!("figs/{f}.svg"))).unwrap();
        assert!(
            svg.contains("age (years)") || svg.contains("years"),
            "{f}.svg has no age"
        );
    }
    let svg = std::fs::read_to_string(d.join("figs/timeline.svg")).unwrap();
    assert!(svg.contains("age (years)"), "timeline.svg: no age axis");
    // fit by age: the series' own lengths at its ages, η0 started 10 % off.
    let (ages, lengths) = (
        numbers(&run.join("series.csv"), "age"),
        numbers(&run.join("series.csv"), "axial_length"),
    );
    let mut data = String::from("age,axial_length,sigma\n");
    for (a, l) in ages.iter().zip(&lengths).skip(1) {
        data.push_str(&format!("{a},{l},0.05\n"));
    }
    std::fs::write(d.join("ages.csv"), data).unwrap();
    let r = eyeshell_in(
        d,
        &[
            "fit",
            "years.toml",
            "--data",
            "ages.csv",
            "--fit",
            "growth.eta0",
            "--set",
            "growth.eta0=6.3",
            "--out",
            "fit",
        ],
    );
    succeeded(&r, "fit by age");
    assert!(
        r.stdout.contains("residuals        age (years)"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("      12.0000"), "{}", r.stdout);
    let residuals = d.join("fit/residuals.csv");
    let (h, _) = csv_cells(&residuals);
    assert_eq!(h.last().map(String::as_str), Some("age"), "{h:?}");
    assert_eq!(column(&residuals, "age"), ages[1..].to_vec());
    let curve = d.join("fit/curve.csv");
    for (t, a) in column(&curve, "t").iter().zip(column(&curve, "age")) {
        assert!((a - (2.0 + t)).abs() <= 1e-12, "curve.csv: t {t}, age {a}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("fit/fit.json")).unwrap()).unwrap();
    assert_eq!(json["residuals"][0]["age"].as_f64(), Some(ages[1]));
    let estimate = json["parameters"][0]["estimate"].as_f64().unwrap();
    assert!((estimate - 7.0).abs() < 0.005, "η0 = {estimate}");
    let svg = std::fs::read_to_string(d.join("fit/fit.svg")).unwrap();
    assert!(svg.contains("age (years)"), "fit.svg: no age axis");
}

/// What a run would find only once it started is refused before it starts: a schedule whose
/// integral over the window is 0 (check says so too, exit 2, nothing written), a
/// growth.t_end that is not the window of the scene's ages, and sensitivities or a fit
/// to a schedule's parameter the scene's schedule does not have.
#[test]
fn a_run_that_cannot_grow_is_refused_before_it_starts() {
    let zero = "[growth]\neta0 = 70\nschedule = \"table\"\nschedule_times = [0, 1]\nschedule_factors = [0, 0]\n";
    let needle = "growth.schedule_factors = [0, 0] makes the schedule grow nothing that can be integrated: ∫ s dt over the growth window is 0";
    grow_fails(zero, needle);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("zero.toml"), zero).unwrap();
    let r = eyeshell_in(dir.path(), &["check", "zero.toml"]);
    assert_bad(&r, needle, "check of a schedule of zeros");
    // A window of 10 years written beside growth.t_end = 1: the clock is one, so the two
    // must agree, and the message says how to convert the rate.
    grow_fails(
        "[growth]\neta0 = 70\nt_end = 1\n[time]\nunit = \"years\"\nstart = 2\nend = 12\n",
        "growth.t_end = 1 is not the window of the ages: with time.unit = \"years\" the run lasts time.end − time.start = 10 years; leave growth.t_end out and give growth.eta0 per year (η per unit of t over t_end = T is η·T/(time.end − time.start) per year)",
    );
    let constant = "[growth]\neta0 = 70\n[solver]\nnodes = 21\n";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), constant).unwrap();
    std::fs::write(
        dir.path().join("data.csv"),
        "t,axial_length\n0.5,22\n1,23\n",
    )
    .unwrap();
    for args in [
        vec![
            "grow",
            "scene.toml",
            "--sensitivities",
            "growth.schedule_tau",
            "--out",
            "out",
        ],
        vec![
            "fit",
            "scene.toml",
            "--data",
            "data.csv",
            "--fit",
            "growth.schedule_tau",
            "--out",
            "out",
        ],
    ] {
        let r = eyeshell_in(dir.path(), &args);
        assert_bad(
            &r,
            "growth.schedule_tau needs growth.schedule = \"exponential\" (scene.toml has \"constant\")",
            &format!("{args:?}"),
        );
        assert!(
            !dir.path().join("out").exists(),
            "{args:?}: out/ was written"
        );
    }
}

/// The fit report's residuals by age stay short whatever σ is: with σ = 1e-140 mm the
/// weighted residuals are about 5e139 σ, printed as `+5.68e139 σ`, not 140 digits on a
/// 227-character line.
#[test]
fn residuals_by_age_are_short_with_a_tiny_sigma() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("years.toml"),
        "[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 2\nend = 12\n[output]\nhistory_points = 4\n[solver]\nnodes = 21\n",
    )
    .unwrap();
    std::fs::write(
        d.join("tiny.csv"),
        "age,axial_length,sigma\n3,20,1e-140\n5,21,1e-140\n8,23,1e-140\n",
    )
    .unwrap();
    let r = eyeshell_in(
        d,
        &[
            "fit",
            "years.toml",
            "--data",
            "tiny.csv",
            "--fit",
            "growth.eta0",
            "--out",
            "fit",
        ],
    );
    succeeded(&r, "fit with a tiny sigma");
    let rows: Vec<&str> = r.stdout.lines().filter(|l| l.ends_with(" σ)")).collect();
    assert_eq!(rows.len(), 3, "{}", r.stdout);
    for line in &rows {
        assert!(
            line.chars().count() <= 100,
            "{} characters: {line}",
            line.chars().count()
        );
        assert!(line.contains("e139 σ)"), "{line}");
    }
    for line in r.stdout.lines() {
        assert!(line.chars().count() <= 130, "{line}");
    }
}

/// A sampled cohort in years carries the age beside t in every table it writes, in either
/// form: sweep.csv and population.csv (after t), population.json (each time's and the
/// final age, and the unit), the table cohort's series.csv (last), and population.png is
/// drawn against age.
#[test]
fn a_cohort_in_years_has_ages_in_every_table() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for per_run in ["directory", "table"] {
        // Ages 2 to 12 years over t in [0, 1]: age = 2 + 10 t.
        std::fs::write(
            d.join(format!("{per_run}.toml")),
            format!(
                "[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 2\nend = 12\n[output]\ntimes = [3, 7, 12]\nhistory_points = 0\n[solver]\nnodes = 21\n[sweep.sample]\neyes = 3\nseed = 2\nper_run = \"{per_run}\"\n[sweep.sample.keys]\n\"growth.eta0\" = {{ dist = \"uniform\", low = 6, high = 8 }}\n"
            ),
        )
        .unwrap();
        let out = d.join(per_run);
        succeeded(
            &eyeshell_in(
                d,
                &["sweep", &format!("{per_run}.toml"), "--out", per_run, "-q"],
            ),
            per_run,
        );
        let sweep = out.join("sweep.csv");
        let (h, _) = csv_cells(&sweep);
        let t_at = h.iter().position(|c| c == "t").unwrap();
        assert_eq!(h[t_at + 1], "age", "{per_run} sweep.csv: {h:?}");
        assert_eq!(numbers(&sweep, "age"), vec![12.0; 3], "{per_run}");
        let population = out.join("population.csv");
        let (h, rows) = csv_cells(&population);
        assert_eq!(&h[..3], ["t", "age", "output"], "{per_run}: {h:?}");
        for r in &rows {
            let age: f64 = r[1].parse().unwrap();
            let expected = match r[0].as_str() {
                "final" => 12.0,
                t => 2.0 + t.parse::<f64>().unwrap(),
            };
            assert!((age - expected).abs() <= 1e-12, "{per_run}: {r:?}");
        }
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("population.json")).unwrap())
                .unwrap();
        assert_eq!(json["age_unit"], "years", "{per_run}");
        assert_eq!(json["final_age"].as_f64(), Some(12.0), "{per_run}");
        let ages: Vec<f64> = json["times"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t["age"].as_f64().unwrap())
            .collect();
        assert_eq!(ages.len(), 4, "{per_run}: {ages:?}");
        assert!((ages[2] - 7.0).abs() <= 1e-12, "{per_run}: {ages:?}");
        let svg = std::fs::read_to_string(out.join("population.svg")).unwrap();
        assert!(
            svg.contains("age (years)"),
            "{per_run}: population.svg has no age axis"
        );
    }
    let series = d.join("table/series.csv");
    let (h, _) = csv_cells(&series);
    assert_eq!(h.last().map(String::as_str), Some("age"), "{h:?}");
    for (t, a) in numbers(&series, "t").iter().zip(numbers(&series, "age")) {
        assert!((a - (2.0 + t)).abs() <= 1e-12, "series.csv: t {t}, age {a}");
    }
}

/// With time.unit the optics' tables are over ages too: scenes/optics-age.toml (t ∈ [0, 1]
/// is 0.25 to 6.5 years, η0 = 70 per unit of t) written in years (tables over
/// age = 0.25 + 6.25 t, η0 = 70/6.25 = 11.2 per year, output ages 0.25 + 6.25 tᵢ) grows the
/// same eye: the growth is p' = η0 f(p, optics(t)), unchanged by the affine change of clock,
/// and the tables' splines are cubics in either time. `check` writes the tables over age and
/// its scene grows alike again; a table over t in a scene of ages, or over age in one without,
/// is refused in one line.
#[test]
fn optics_tables_are_over_ages_in_a_scene_of_ages() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo().join("scenes/optics-age.toml");
    let tight = ["solver.rtol=1e-9", "solver.atol=1e-11", "solver.nodes=201"];
    let in_years = [
        "time.unit=\"years\"",
        "time.start=0.25",
        "time.end=6.5",
        "growth.eta0=11.2",
        "output.times=[0.875, 1.5, 2.75, 6.5]",
        "optics.surfaces=[{ radius = { age = [0.25, 0.75, 1.5, 3.0, 6.5], value = [7.472, 7.682, 7.731, 7.761, 7.77] } }, { thickness = { age = [0.25, 0.75, 1.5, 3.0, 6.5], value = [2.512, 2.598, 2.697, 2.842, 3.15] } }]",
    ];
    let grow = |scene: &std::path::Path, out: &str, sets: &[&str]| {
        let mut args = vec!["grow", s(scene), "--out", out, "--quiet"];
        for set in tight.iter().chain(sets) {
            args.extend(["--set", set]);
        }
        succeeded(&eyeshell_in(d, &args), out);
        numbers(&d.join(out).join("series.csv"), "axial_length")
    };
    let in_t = grow(&scene, "t", &[]);
    let years = grow(&scene, "years", &in_years);
    assert_eq!(in_t.len(), 5);
    for (a, b) in in_t.iter().zip(&years) {
        assert!((a - b).abs() < 1e-6, "{in_t:?} against {years:?}");
    }
    assert!(in_t[4] - in_t[0] > 0.1, "{in_t:?}");
    assert_eq!(
        numbers(&d.join("years/series.csv"), "age"),
        [0.25, 0.875, 1.5, 2.75, 6.5]
    );
    // The scene as `check` writes it: the tables over age, read back to the same growth.
    let mut args = vec!["check", s(&scene)];
    for set in &in_years {
        args.extend(["--set", set]);
    }
    let r = eyeshell_in(d, &args);
    succeeded(&r, "check");
    assert!(
        r.stdout.contains("age = [0.25, 0.75, 1.5, 3.0, 6.5]") && !r.stdout.contains("{ t = ["),
        "{}",
        r.stdout
    );
    std::fs::write(d.join("written.toml"), &r.stdout).unwrap();
    let again = grow(&d.join("written.toml"), "again", &[]);
    for (a, b) in again.iter().zip(&years) {
        assert!((a - b).abs() < 1e-12, "{again:?} against {years:?}");
    }
    // One surface's key set alone in ages, after the clock, moves with the others.
    let one = grow(
        &scene,
        "one",
        &[
            in_years[0], in_years[1], in_years[2], in_years[3], in_years[4], in_years[5],
            "optics.surfaces[0].radius={ age = [0.25, 0.75, 1.5, 3.0, 6.5], value = [7.472, 7.682, 7.731, 7.761, 7.77] }",
        ],
    );
    assert_eq!(one, years);
    // Times under the wrong name for the scene's clock.
    let years_scene = "[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 8\nend = 11\n[stimulus]\nsource = \"optics\"\n[[optics.surfaces]]\nradius = { t = [0, 3], value = [7.7, 7.8] }\n";
    grow_fails(
        years_scene,
        "gives a table over t, but the scene counts in ages (time.unit)",
    );
    grow_fails(
        "[growth]\neta0 = 70\n[stimulus]\nsource = \"optics\"\n[[optics.surfaces]]\nradius = { age = [0, 1], value = [7.7, 7.8] }\n",
        "gives a table over age, but the scene counts no ages",
    );
    grow_fails(
        "[growth]\neta0 = 70\n[stimulus]\nsource = \"optics\"\n[[optics.surfaces]]\nradius = { t = [0, 1], age = [0, 1], value = [7.7, 7.8] }\n",
        "gives both t and age",
    );
}

/// A table over ages is checked in ages: its times from time.start on, and its spline over
/// the window, each problem said with the ages the scene writes.
#[test]
fn optics_tables_over_ages_are_checked_in_ages() {
    let scene = |radius: &str| {
        format!("[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 8\nend = 11\n[stimulus]\nsource = \"optics\"\n[[optics.surfaces]]\nradius = {radius}\n")
    };
    grow_fails(
        &scene("{ age = [5, 9], value = [7.7, 7.8] }"),
        "optics.surfaces[0].radius = { age = [5, 9], value = [7.7, 7.8] } must list finite ages from time.start = 8 on, not 5",
    );
    grow_fails(
        &scene("{ age = [10, 9], value = [7.7, 7.8] }"),
        "strictly increasing times (they are not sorted for you): 9 follows 10",
    );
    grow_fails(
        &scene("{ age = [10.9, 11], value = [-6, -100] }"),
        "optics.surfaces[0].radius = { age = [10.9, 11], value = [-6, -100] } reaches 2720 at age 8 (its spline between or beyond its points): it must stay between 0.5 and 10000 mm in magnitude, of one sign for all ages in [8, 11]",
    );
}

/// The two age effects on one clock: scenes/optics-age-schedule.toml (a schedule
/// s = exp(−t/0.5) beside optics tables over t ∈ [0, 1]) written in years from 0.25 to 6.5
/// (tables over age = 0.25 + 6.25 t, τ = 0.5 · 6.25 = 3.125 years, η0 = 70/6.25 per year)
/// grows the same eye (3e-13 mm measured; 1e-9 asserted).
#[test]
fn a_schedule_in_years_beside_optics_over_ages_is_the_same_growth() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ages = "[0.25, 0.75, 1.5, 3.0, 6.5]";
    std::fs::write(
        d.join("years.toml"),
        format!(
            "[growth]\neta0 = 11.2\nschedule = \"exponential\"\nschedule_tau = 3.125\n\
             [time]\nunit = \"years\"\nstart = 0.25\nend = 6.5\n\
             [stimulus]\nsource = \"optics\"\n\
             [optics]\neye = \"atchison-2006\"\nfocus = \"sagittal\"\npupil = 1.0\n\
             [[optics.surfaces]]\nradius = {{ age = {ages}, value = [7.472, 7.682, 7.731, 7.761, 7.77] }}\n\
             [[optics.surfaces]]\nthickness = {{ age = {ages}, value = [2.512, 2.598, 2.697, 2.842, 3.15] }}\n"
        ),
    )
    .unwrap();
    let grow = |scene: &std::path::Path, out: &str| {
        let args = [
            "grow",
            s(scene),
            "--set",
            "solver.nodes=201",
            "--out",
            out,
            "--quiet",
        ];
        succeeded(&eyeshell_in(d, &args), out);
        numbers(&d.join(out).join("series.csv"), "axial_length")
    };
    let in_t = grow(&repo().join("scenes/optics-age-schedule.toml"), "t");
    let years = grow(&d.join("years.toml"), "years");
    assert_eq!(in_t.len(), 5);
    for (a, b) in in_t.iter().zip(&years) {
        assert!((a - b).abs() < 1e-9, "{in_t:?} against {years:?}");
    }
    // The schedule slows the growth: the unscheduled eye is longer at the end.
    assert!(in_t[4] < 23.2 && in_t[4] - in_t[0] > 3.0, "{in_t:?}");
}

/// The ages a scene writes stay its ages when its clock moves after them: the tables of a
/// scene of ages, with time.start then set later, are shown over the same ages by `check`.
#[test]
fn optics_tables_over_ages_keep_their_ages_when_the_clock_moves() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("s.toml"),
        "[growth]\neta0 = 7\n[time]\nunit = \"years\"\nstart = 8\nend = 11\n[stimulus]\nsource = \"optics\"\n[[optics.surfaces]]\nradius = { age = [9, 11], value = [7.7, 7.8] }\n",
    )
    .unwrap();
    for start in ["8.5", "9"] {
        let set = format!("time.start={start}");
        let r = eyeshell_in(d, &["check", "s.toml", "--set", &set]);
        succeeded(&r, &set);
        assert!(
            r.stdout
                .contains("radius = { age = [9.0, 11.0], value = [7.7, 7.8] }"),
            "{set}: {}",
            r.stdout
        );
    }
}
