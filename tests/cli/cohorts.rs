//! Sampled sweeps (`[sweep.sample]`, virtual cohorts): population statistics against the
//! exact inflated sphere, Sobol indices of a key that matters and one that does not, the
//! same seed giving the same bytes, a killed sweep resumed to the same result, shards
//! merged to the same result, and draws outside a key's range refused.

use std::path::Path;

use crate::support::*;

/// The exact sphere of docs/MODEL.md §7 on 21 nodes (4e-6 mm from the exact axial length).
const SPHERE: &str = "name = \"sphere\"\n[pressure]\ndP = 2.0\n[material]\nC = 100.0\nbending = 18.0\nthickness = \"uniform\"\nH0 = 0.65\n[fibres]\nD = 0.0\n[cornea]\nC = 100.0\nH = 0.65\nR0 = 10.0\n[geometry]\nR0 = 10.0\nfraction = 0.8\n[solver]\nnodes = 21\n";

/// A small growth scene (N = 21, CVODE rtol 1e-3, two output times) and a cohort of it.
const GROWING: &str = "name = \"small\"\n[fibres]\nD = 0.0\n[growth]\neta0 = 70.0\nt_end = 0.2\n[solver]\nnodes = 21\nrtol = 1e-3\n[output]\ntimes = [0.1, 0.2]\nhistory_points = 10\n[sweep.sample]\ndesign = \"latin-hypercube\"\nseed = 11\n[sweep.sample.keys]\n\"growth.eta0\" = { dist = \"normal\", mean = 70.0, sd = 5.0 }\n\"growth.Gamma\" = { dist = \"uniform\", low = 6.0, high = 10.0 }\n";

fn population(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("population.json")).unwrap()).unwrap()
}

/// The exact sphere's axial length at pressure dP: the retina's z at the posterior pole,
/// 2αR0 − h/2 with the inflated thickness h = H0/α² (MODEL.md §6, §7), α the cornea's
/// stretch (its closed form, solved to double precision by the library).
fn exact_axial_length(dp: f64) -> f64 {
    let cornea = eyeshell::model::params::CorneaParams {
        c: 100.0,
        h: 0.65,
        r0: 10.0,
    };
    let a = eyeshell::model::cornea::stretch(&cornea, dp).unwrap();
    2.0 * a * 10.0 - 0.65 / (2.0 * a * a)
}

/// Right statistics: ΔP ~ N(2, 0.2²) over 400 eyes of the exact sphere. The population's
/// mean and sd of the axial length are those of the closed form over the normal density
/// (by quadrature, 1e-12), within 3 of their reported Monte Carlo standard errors; the
/// table's values are the runs' own; and each run's drawn ΔP is its sweep.csv column.
#[test]
fn a_cohorts_mean_and_sd_match_the_exact_sphere() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        format!("{SPHERE}[sweep.sample]\neyes = 400\nseed = 3\n[sweep.sample.keys]\n\"pressure.dP\" = {{ dist = \"normal\", mean = 2.0, sd = 0.2 }}\n"),
    )
    .unwrap();
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "--quiet"]);
    succeeded(&run, "sampled sweep");
    let out = dir.path().join("out");
    // Quadrature of the closed form against the normal density on ±8 sd.
    let (mut m0, mut m1, mut m2) = (0.0, 0.0, 0.0);
    let steps = 4000;
    for i in 0..=steps {
        let z = -8.0 + 16.0 * i as f64 / steps as f64;
        let w = if i == 0 || i == steps { 0.5 } else { 1.0 } * (-0.5 * z * z).exp();
        let l = exact_axial_length(2.0 + 0.2 * z);
        m0 += w;
        m1 += w * l;
        m2 += w * l * l;
    }
    let mean = m1 / m0;
    let sd = (m2 / m0 - mean * mean).sqrt();
    let p = population(&out);
    let a = &p["final"]["axial_length"];
    let got = |k: &str| a[k].as_f64().unwrap();
    assert_eq!(a["n"], 400);
    assert!(
        (got("mean") - mean).abs() < 3.0 * got("mean_se"),
        "mean {} vs exact {mean} (se {})",
        got("mean"),
        got("mean_se")
    );
    assert!(
        (got("sd") - sd).abs() < 3.0 * got("sd_se"),
        "sd {} vs exact {sd} (se {})",
        got("sd"),
        got("sd_se")
    );
    // The standard error is the sd over √n, and sd is about 0.02 mm (dL/dΔP ≈ 0.1 mm/kPa).
    assert!((got("mean_se") - got("sd") / 20.0).abs() < 1e-15);
    assert!(sd > 0.01 && sd < 0.03, "{sd}");
    // Each run: its drawn ΔP in the table, and its axial length the closed form's.
    let (header, rows) = csv_cells(&out.join("sweep.csv"));
    assert_eq!(&header[..3], ["run", "status", "pressure.dP"]);
    let col = header.iter().position(|h| h == "axial_length").unwrap();
    let lengths: Vec<f64> = rows.iter().map(|r| r[col].parse().unwrap()).collect();
    for r in &rows {
        let dp: f64 = r[2].parse().unwrap();
        let l: f64 = r[col].parse().unwrap();
        assert!((l - exact_axial_length(dp)).abs() < 1e-5, "{r:?}");
    }
    assert_eq!(rows[0][0], "eye-001");
    let n = lengths.len() as f64;
    let sample_mean = lengths.iter().sum::<f64>() / n;
    assert!((got("mean") - sample_mean).abs() < 1e-12);
    let table = std::fs::read_to_string(out.join("population.csv")).unwrap();
    assert!(table.starts_with("t,output,n,mean,sd,q0.05,"), "{table}");
    assert!(table.contains("\nfinal,axial_length,400,"), "{table}");
    assert!(
        table.contains("\nfinal,class=hyperopic,400,1.0,"),
        "{table}"
    );
}

/// Which spread matters: a Saltelli design over ΔP (which sets the sphere's size) and
/// solver.newton_tol (which does not change the converged shell beyond round-off): ΔP's
/// first-order and total indices are 1 and newton_tol's 0, each inside its bootstrap
/// interval.
#[test]
fn sobol_indices_name_the_key_that_matters() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        format!("{SPHERE}[sweep.sample]\neyes = 64\ndesign = \"saltelli\"\nseed = 5\n[sweep.sample.keys]\n\"pressure.dP\" = {{ dist = \"uniform\", low = 1.5, high = 2.5 }}\n\"solver.newton_tol\" = {{ dist = \"lognormal\", mean = 1e-9, sd = 5e-10 }}\n"),
    )
    .unwrap();
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out"]);
    succeeded(&run, "saltelli sweep");
    assert!(run.stdout.contains("sobol indices"), "{}", run.stdout);
    let out = dir.path().join("out");
    let (_, rows) = csv_cells(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 64 * 4);
    assert_eq!(
        [&rows[0][0], &rows[1][0], &rows[2][0], &rows[3][0]],
        ["A-001", "B-001", "AB1-001", "AB2-001"]
    );
    let p = population(&out);
    assert_eq!(p["eyes"], 128, "A and B rows are the cohort");
    let s = &p["sobol"]["axial_length"];
    let f = |key: &str, what: &str| s[key][what].as_f64().unwrap();
    let ci = |key: &str, what: &str| {
        let c = &s[key][format!("{what}_ci")];
        (c[0].as_f64().unwrap(), c[1].as_f64().unwrap())
    };
    assert!((f("pressure.dP", "first") - 1.0).abs() < 0.05, "{s}");
    assert!((f("pressure.dP", "total") - 1.0).abs() < 0.05, "{s}");
    assert!(f("solver.newton_tol", "first").abs() < 1e-3, "{s}");
    assert!(f("solver.newton_tol", "total").abs() < 1e-3, "{s}");
    let (lo, hi) = ci("pressure.dP", "total");
    assert!(lo < 1.0 + 1e-9 && hi > 0.9, "{s}");
    let table = std::fs::read_to_string(out.join("sobol.csv")).unwrap();
    assert!(table.starts_with("output,key,first,first_low,first_high,total,total_low,total_high\n"));
    assert!(table.contains("\naxial_length,pressure.dP,"), "{table}");
}

/// The columns of sweep.csv that do not measure time or say whether a run was reused:
/// the names, the draws and the results.
fn table_without_timings(path: &Path) -> Vec<Vec<String>> {
    let (header, rows) = csv_cells(path);
    let wall = header.iter().position(|h| h == "wall_seconds").unwrap();
    rows.into_iter()
        .map(|mut r| {
            r.remove(wall);
            r.remove(1);
            r
        })
        .collect()
}

/// Reproducible: the same seed draws the same cohort and writes the same population files,
/// byte for byte; another seed draws another cohort.
#[test]
fn the_same_seed_gives_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        GROWING.replace("[sweep.sample.keys]", "eyes = 6\n[sweep.sample.keys]"),
    )
    .unwrap();
    for out in ["a", "b"] {
        succeeded(
            &eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", out, "--quiet"]),
            out,
        );
    }
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    assert_eq!(
        table_without_timings(&a.join("sweep.csv")),
        table_without_timings(&b.join("sweep.csv"))
    );
    for f in ["population.json", "population.csv"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
    // Per output time: t = 0 and both output times, each with every output.
    let p = population(&a);
    let times: Vec<f64> = p["times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["t"].as_f64().unwrap())
        .collect();
    assert_eq!(times, [0.0, 0.1, 0.2]);
    assert_eq!(
        p["times"][2]["outputs"]["axial_length"],
        p["final"]["axial_length"]
    );
    let text = std::fs::read_to_string(dir.path().join("s.toml")).unwrap();
    std::fs::write(
        dir.path().join("s2.toml"),
        text.replace("seed = 11", "seed = 12"),
    )
    .unwrap();
    succeeded(
        &eyeshell_in(dir.path(), &["sweep", "s2.toml", "--out", "d", "--quiet"]),
        "d",
    );
    let (_, ra) = csv_cells(&a.join("sweep.csv"));
    let (_, rd) = csv_cells(&dir.path().join("d/sweep.csv"));
    assert_ne!(ra[0][2], rd[0][2], "another seed, other draws");
}

/// A sampled sweep killed (SIGKILL, as a lost node) and resumed writes the population
/// files an uninterrupted sweep writes, byte for byte; the killed one wrote none. Run as
/// two shards and merged, the same again.
#[test]
fn a_killed_cohort_resumed_and_a_sharded_one_equal_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let eyes = 40;
    std::fs::write(
        dir.path().join("s.toml"),
        GROWING.replace(
            "[sweep.sample.keys]",
            &format!("eyes = {eyes}\n[sweep.sample.keys]"),
        ),
    )
    .unwrap();
    succeeded(
        &eyeshell_in(
            dir.path(),
            &["sweep", "s.toml", "--out", "whole", "--quiet"],
        ),
        "whole",
    );
    let (mut child, _stderr, _) = spawn_in_own_group(
        dir.path(),
        &["sweep", "s.toml", "--out", "killed", "--jobs", "1"],
        "eyeshell: [1/40] eye-",
    );
    let killed = std::process::Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .status()
        .unwrap();
    assert!(killed.success());
    let _ = child.wait();
    let killed = dir.path().join("killed");
    assert!(
        !killed.join("population.json").exists(),
        "no population of a killed sweep"
    );
    let run = eyeshell_in(
        dir.path(),
        &["sweep", "s.toml", "--out", "killed", "--resume"],
    );
    succeeded(&run, "resume");
    assert!(run.stdout.contains("reused"), "{}", run.stdout);
    for shard in ["1/2", "2/2"] {
        succeeded(
            &eyeshell_in(
                dir.path(),
                &[
                    "sweep", "s.toml", "--out", "sharded", "--shard", shard, "--quiet",
                ],
            ),
            shard,
        );
    }
    let merged = eyeshell_in(dir.path(), &["sweep", "merge", "sharded"]);
    succeeded(&merged, "merge");
    assert!(
        merged.stdout.contains("population.json"),
        "{}",
        merged.stdout
    );
    let whole = dir.path().join("whole");
    for other in [killed, dir.path().join("sharded")] {
        for f in ["population.json", "population.csv"] {
            assert_eq!(
                std::fs::read(whole.join(f)).unwrap(),
                std::fs::read(other.join(f)).unwrap(),
                "{f} of {}",
                other.display()
            );
        }
        assert_eq!(
            table_without_timings(&whole.join("sweep.csv")),
            table_without_timings(&other.join("sweep.csv"))
        );
    }
}

/// Bad samples: one line, exit 2, nothing written. A draw outside its key's range is named
/// and counted, not clipped.
#[test]
fn bad_samples_are_refused_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "[sweep.sample]\neyes = 200\nseed = 1\n[sweep.sample.keys]\n\"material.C\" = { dist = \"normal\", mean = 20.0, sd = 10.0 }\n",
            "of 200 drawn values lie outside their key's range and are not clipped",
        ),
        (
            "[sweep.sample]\neyes = 20\nseed = 1\ndesign = \"sobal\"\n[sweep.sample.keys]\n\"material.C\" = { dist = \"uniform\", low = 90.0, high = 110.0 }\n",
            "did you mean 'sobol'",
        ),
        (
            "[sweep.sample]\neyes = 20\nseed = 1\n[sweep.sample.keys]\n\"material.C\" = { dist = \"uniform\", low = 90.0, high = 110.0 }\n[sweep.grid]\n\"fibres.D\" = [0, 1]\n",
            "has no [sweep.grid] or [[sweep.runs]]",
        ),
        (
            "[sweep.sample]\neyes = 20\n[sweep.sample.keys]\n\"material.C\" = { dist = \"uniform\", low = 90.0, high = 110.0 }\n",
            "give seed",
        ),
        // Sobol indices of 4 base points came out as 1.41 [1.25, 1.77] without a word.
        (
            "[sweep.sample]\neyes = 4\nseed = 1\ndesign = \"saltelli\"\n[sweep.sample.keys]\n\"pressure.dP\" = { dist = \"uniform\", low = 1.5, high = 2.5 }\n",
            "eyes = 4: the saltelli design needs at least 32 base points",
        ),
    ];
    for (sample, needle) in cases {
        std::fs::write(dir.path().join("s.toml"), format!("{SPHERE}{sample}")).unwrap();
        let run = bounded(dir.path(), &["sweep", "s.toml", "--out", "out"]);
        refused(&run, needle, sample);
        assert!(!dir.path().join("out").exists(), "{sample}");
    }
    // A sampled key set with --set would be ambiguous.
    std::fs::write(
        dir.path().join("s.toml"),
        format!("{SPHERE}[sweep.sample]\neyes = 20\nseed = 1\n[sweep.sample.keys]\n\"material.C\" = {{ dist = \"uniform\", low = 90.0, high = 110.0 }}\n"),
    )
    .unwrap();
    let run = bounded(
        dir.path(),
        &["sweep", "s.toml", "--out", "out", "--set", "material.C=5"],
    );
    refused(&run, "sweeps material.C", "--set on a sampled key");
}

/// `per_run = "table"`: a cohort without a directory per eye. Its population files are the
/// per-eye output's, byte for byte; its series.csv holds each eye's series.csv rows (a run
/// column first) and its sweep.csv the same rows. Killed (SIGKILL) and resumed, with the
/// checkpoint's last line cut short as a kill mid-write leaves it, it writes the same
/// population, series and table as an uninterrupted one. Shards refuse it (they need run
/// directories); a misspelt per_run is refused.
#[test]
fn a_cohort_kept_as_a_table_equals_the_per_eye_output_and_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let eyes = 40;
    let per_eye = GROWING.replace(
        "[sweep.sample.keys]",
        &format!("eyes = {eyes}\n[sweep.sample.keys]"),
    );
    let table = per_eye.replace(
        "[sweep.sample.keys]",
        "per_run = \"table\"\n[sweep.sample.keys]",
    );
    std::fs::write(dir.path().join("d.toml"), &per_eye).unwrap();
    std::fs::write(dir.path().join("t.toml"), &table).unwrap();
    for (scene, out) in [("d.toml", "dirs"), ("t.toml", "table")] {
        succeeded(
            &eyeshell_in(dir.path(), &["sweep", scene, "--out", out, "--quiet"]),
            out,
        );
    }
    let (dirs, whole) = (dir.path().join("dirs"), dir.path().join("table"));
    assert!(!whole.join("runs").exists(), "no run directories");
    for f in ["population.json", "population.csv"] {
        assert_eq!(
            std::fs::read(dirs.join(f)).unwrap(),
            std::fs::read(whole.join(f)).unwrap(),
            "{f}"
        );
    }
    assert_eq!(
        table_without_timings(&dirs.join("sweep.csv")),
        table_without_timings(&whole.join("sweep.csv"))
    );
    let series = std::fs::read_to_string(whole.join("series.csv")).unwrap();
    let mut lines = series.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    for k in 1..=eyes {
        let name = format!("eye-{k:03}");
        let own =
            std::fs::read_to_string(dirs.join("runs").join(&name).join("series.csv")).unwrap();
        let mut own = own.lines();
        assert_eq!(header, format!("run,{}", own.next().unwrap()));
        let prefix = format!("{name},");
        let mine: Vec<&str> = rows
            .iter()
            .filter_map(|r| r.strip_prefix(prefix.as_str()))
            .collect();
        assert_eq!(mine, own.collect::<Vec<_>>(), "{name}");
        assert_eq!(mine.len(), 3, "t = 0, 0.1, 0.2");
    }

    let (mut child, _stderr, _) = spawn_in_own_group(
        dir.path(),
        &["sweep", "t.toml", "--out", "killed", "--jobs", "1"],
        "eyeshell: [1/40] eye-",
    );
    let status = std::process::Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .status()
        .unwrap();
    assert!(status.success());
    let _ = child.wait();
    let killed = dir.path().join("killed");
    assert!(!killed.join("population.json").exists());
    let checkpoint = killed.join("eyes.jsonl");
    let kept = std::fs::read_to_string(&checkpoint)
        .unwrap()
        .matches('\n')
        .count();
    assert!((1..eyes).contains(&kept), "{kept} eyes checkpointed");
    let mut torn = std::fs::read(&checkpoint).unwrap();
    torn.extend_from_slice(b"{\"run\":\"eye-040\",\"scene\":\"01");
    std::fs::write(&checkpoint, torn).unwrap();
    let run = eyeshell_in(
        dir.path(),
        &["sweep", "t.toml", "--out", "killed", "--resume"],
    );
    succeeded(&run, "resume");
    assert!(
        run.stdout
            .contains(&format!("({kept} reused from the earlier sweep)")),
        "{}",
        run.stdout
    );
    for f in ["population.json", "population.csv", "series.csv"] {
        assert_eq!(
            std::fs::read(whole.join(f)).unwrap(),
            std::fs::read(killed.join(f)).unwrap(),
            "{f}"
        );
    }
    assert_eq!(
        table_without_timings(&whole.join("sweep.csv")),
        table_without_timings(&killed.join("sweep.csv"))
    );
    assert_eq!(
        std::fs::read_to_string(&checkpoint)
            .unwrap()
            .lines()
            .count(),
        eyes,
        "the torn line dropped, every eye checkpointed once"
    );

    let run = bounded(
        dir.path(),
        &["sweep", "t.toml", "--out", "sh", "--shard", "1/2"],
    );
    refused(
        &run,
        "per_run = \"table\" in [sweep.sample] runs the cohort in one process",
        "shard",
    );
    assert!(!dir.path().join("sh").exists());
    std::fs::write(
        dir.path().join("bad.toml"),
        table.replace("per_run = \"table\"", "per_run = \"tables\""),
    )
    .unwrap();
    let run = bounded(dir.path(), &["sweep", "bad.toml", "--out", "bad"]);
    refused(
        &run,
        "per_run must be \"directory\" (a run directory per eye) or \"table\"",
        "per_run",
    );
}

/// A quantity that cannot be computed is NaN with a note, never another rule's answer, and
/// never dropped from a summary. Eyes of 14.9–15.6 mm, classed by dioptres: those beyond
/// +25 D (refraction_D NaN, from geometry.R0 below about 5.7 mm) are "unknown", not the
/// surfaces' "hyperopic"; refraction_D stays in population.json's final with its n, the
/// eyes that have it, and notes say how many have none and could not be classed.
#[test]
fn an_eye_the_dioptre_rule_cannot_class_is_unknown_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let scene = "name = \"small\"\n[fibres]\nD = 0.0\n[growth]\neta0 = 70.0\nt_end = 0.1\n[solver]\nnodes = 21\nrtol = 1e-3\n[output]\ntimes = [0.05, 0.1]\nhistory_points = 5\n[stimulus]\nclassify = \"dioptres\"\n[cornea]\nR0 = 5.5\n[sweep.sample]\neyes = 6\ndesign = \"latin-hypercube\"\nseed = 1\n[sweep.sample.keys]\n\"geometry.R0\" = { dist = \"uniform\", low = 5.3, high = 6.0 }\n";
    std::fs::write(dir.path().join("s.toml"), scene).unwrap();
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out"]);
    succeeded(&run, "cohort");
    let out = dir.path().join("out");
    let (header, rows) = csv_cells(&out.join("sweep.csv"));
    let at = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (class, refraction) = (at("class"), at("refraction_D"));
    let nan = rows.iter().filter(|r| r[refraction] == "NaN").count();
    assert!((1..rows.len() - 1).contains(&nan), "{rows:?}");
    for r in &rows {
        let d: f64 = r[refraction].parse().unwrap();
        let expected = if d.is_nan() { "unknown" } else { "hyperopic" };
        assert_eq!(r[class], expected, "{r:?}");
    }
    let p = population(&out);
    let have = rows.len() - nan;
    assert_eq!(p["final"]["refraction_D"]["n"], have, "{}", p["final"]);
    let finite: Vec<f64> = rows
        .iter()
        .filter_map(|r| r[refraction].parse::<f64>().ok().filter(|d| d.is_finite()))
        .collect();
    let mean = finite.iter().sum::<f64>() / finite.len() as f64;
    let got = p["final"]["refraction_D"]["mean"].as_f64().unwrap();
    assert!((got - mean).abs() < 1e-12 * mean.abs(), "{got} vs {mean}");
    let unknown = p["classes"]["unknown"]["share"].as_f64().unwrap();
    assert!((unknown - nan as f64 / rows.len() as f64).abs() < 1e-15);
    let notes: Vec<&str> = p["notes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let counted = format!("{nan} of {} eyes", rows.len());
    assert!(
        notes.iter().any(|n| n.starts_with(&format!(
            "refraction_D at the final time: {counted} have no value"
        ))),
        "{notes:?}"
    );
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with(&format!("{counted} could not be classed"))),
        "{notes:?}"
    );
    // The notes are on the summary as well, and population.csv has the row.
    assert!(
        run.stdout
            .contains(&format!("  note            {counted} could not be classed")),
        "{}",
        run.stdout
    );
    let table = std::fs::read_to_string(out.join("population.csv")).unwrap();
    assert!(
        table.contains(&format!("\nfinal,refraction_D,{have},")),
        "{table}"
    );
    assert!(table.contains("\nfinal,class=unknown,"), "{table}");
}

/// SIGTERM (what Slurm sends at a time limit) ends a run as Ctrl-C does: a cohort kept as
/// a table stops starting eyes, says "interrupted" in summary.json with its finished eyes
/// "ok" in sweep.csv (not "running" with every row "not run"), exits 1 with one line on how
/// to resume, and `--resume` gives the bytes of an uninterrupted cohort.
#[test]
fn sigterm_interrupts_a_cohort_as_ctrl_c_does() {
    let dir = tempfile::tempdir().unwrap();
    let eyes = 40;
    let scene = GROWING.replace(
        "[sweep.sample.keys]",
        &format!("eyes = {eyes}\nper_run = \"table\"\n[sweep.sample.keys]"),
    );
    std::fs::write(dir.path().join("t.toml"), &scene).unwrap();
    succeeded(
        &eyeshell_in(
            dir.path(),
            &["sweep", "t.toml", "--out", "whole", "--quiet"],
        ),
        "whole",
    );
    let (mut child, mut stderr, _) = spawn_in_own_group(
        dir.path(),
        &["sweep", "t.toml", "--out", "out", "--jobs", "1"],
        "eyeshell: [1/40] eye-",
    );
    let sent = std::process::Command::new("kill")
        .args(["-TERM", "--", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(1), "{rest}");
    let last = rest.lines().last().unwrap();
    assert!(
        last.starts_with("eyeshell: error: sweep interrupted: ") && last.contains("--resume"),
        "{last}"
    );
    let out = dir.path().join("out");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"interrupted\""), "{summary}");
    let (_, rows) = csv_cells(&out.join("sweep.csv"));
    let ok = rows.iter().filter(|r| r[1] == "ok").count();
    let not_run = rows.iter().filter(|r| r[1] == "not run").count();
    assert!((1..eyes).contains(&ok) && ok + not_run == eyes, "{rows:?}");
    let run = eyeshell_in(dir.path(), &["sweep", "t.toml", "--out", "out", "--resume"]);
    succeeded(&run, "resume");
    for f in ["population.json", "population.csv", "series.csv"] {
        assert_eq!(
            std::fs::read(dir.path().join("whole").join(f)).unwrap(),
            std::fs::read(out.join(f)).unwrap(),
            "{f}"
        );
    }
}

/// Over 10,000 eyes kept as a table: the refusal's advice is what works. Shards refuse a
/// table cohort, so it says so and advises per_run = "directory" with shards, whose script
/// is then written.
#[test]
fn a_table_cohort_too_large_for_one_process_is_advised_what_works() {
    let dir = tempfile::tempdir().unwrap();
    let cohort = |per_run: &str| {
        format!("{SPHERE}[sweep.sample]\neyes = 10001\nseed = 1\nper_run = \"{per_run}\"\n[sweep.sample.keys]\n\"pressure.dP\" = {{ dist = \"uniform\", low = 1.5, high = 2.5 }}\n")
    };
    std::fs::write(dir.path().join("t.toml"), cohort("table")).unwrap();
    std::fs::write(dir.path().join("d.toml"), cohort("directory")).unwrap();
    let run = bounded(dir.path(), &["sweep", "t.toml", "--out", "out"]);
    refused(
        &run,
        "a cohort kept as a table (per_run = \"table\") runs in one process and cannot be sharded: give at most 10000 eyes, or set per_run = \"directory\" and run it in shards",
        "table cohort of 10001",
    );
    assert!(!dir.path().join("out").exists());
    let shard = bounded(
        dir.path(),
        &["sweep", "t.toml", "--out", "out", "--shard", "1/2"],
    );
    refused(&shard, "per_run = \"table\"", "shard of a table cohort");
    // The advice followed: the directory form's shards are planned.
    let script = bounded(
        dir.path(),
        &["sweep", "d.toml", "--out", "out", "--slurm-script"],
    );
    succeeded(&script, "slurm script of the directory form");
    assert!(
        script.stdout.contains("#SBATCH --array"),
        "{}",
        script.stdout
    );
}

/// `plot` of a cohort kept as a table says what there is to draw (its population figure,
/// named), not that a run "points outside the sweep's runs", as if it were damaged.
#[test]
fn plot_of_a_table_cohort_names_its_population_figure() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("t.toml"),
        format!("{SPHERE}[sweep.sample]\neyes = 4\nseed = 1\nper_run = \"table\"\n[sweep.sample.keys]\n\"pressure.dP\" = {{ dist = \"uniform\", low = 1.5, high = 2.5 }}\n"),
    )
    .unwrap();
    succeeded(
        &eyeshell_in(dir.path(), &["sweep", "t.toml", "--out", "out", "--quiet"]),
        "table cohort",
    );
    let run = bounded(dir.path(), &["plot", "out", "--out", "p"]);
    refused(
        &run,
        "out: a cohort kept as a table (per_run = \"table\") has no run directories to draw",
        "plot of a table cohort",
    );
    assert!(
        run.stderr.contains("its figure is out/population.png"),
        "{}",
        run.stderr
    );
    assert!(!dir.path().join("p").exists());
}
