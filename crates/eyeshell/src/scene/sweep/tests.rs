use super::spec::shorten;
use super::*;

const BASE: &str = "name = \"fib\"\n[fibres]\nD = 100.0\n[growth]\neta0 = 70.0\n";

fn sweep(extra: &str) -> Result<Sweep, SceneError> {
    Sweep::from_toml_str(&format!("{BASE}{extra}"), "s.toml", &[])
}

#[test]
fn a_grid_is_every_combination_last_key_fastest() {
    let s =
        sweep("[sweep.grid]\n\"growth.Gamma\" = [4, 8, 12]\n\"growth.delta\" = [2, 6]\n").unwrap();
    let names: Vec<_> = s.runs.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "Gamma=4_delta=2",
            "Gamma=4_delta=6",
            "Gamma=8_delta=2",
            "Gamma=8_delta=6",
            "Gamma=12_delta=2",
            "Gamma=12_delta=6"
        ]
    );
    let g = s.runs[5].scene.growth.as_ref().unwrap();
    assert_eq!((g.gamma, g.delta), (12.0, 6.0));
    assert_eq!(s.runs[5].scene.params.d, 100.0);
    assert_eq!(s.keys, ["growth.Gamma", "growth.delta"]);
    assert_eq!(s.runs[2].shown("growth.Gamma"), "8");
    assert_eq!(s.runs[0].scene.name.as_deref(), Some("fib/Gamma=4_delta=2"));
}

/// A grid of 24 keys with 3 values each (2.8e11 runs) is refused by counting, before
/// anything is expanded (expanding it would take 8 GB and abort).
#[test]
fn a_huge_grid_is_counted_not_expanded() {
    let keys = [
        "pressure.dP",
        "material.C",
        "material.bending",
        "material.H0",
        "fibres.D",
        "cornea.C",
        "cornea.H",
        "cornea.R0",
        "geometry.R0",
        "geometry.fraction",
        "solver.epsilon",
        "solver.newton_tol",
        "growth.eta0",
        "growth.Gamma",
        "growth.delta",
        "growth.t_end",
        "solver.rtol",
        "solver.atol",
        "stimulus.blue.P1",
        "stimulus.blue.P2",
        "stimulus.blue.P3",
        "stimulus.blue.z_B",
        "stimulus.red.offset",
        "growth.kink_width",
    ];
    let grid: String = keys
        .iter()
        .map(|k| format!("\"{k}\" = [1, 2, 3]\n"))
        .collect();
    let start = std::time::Instant::now();
    let e = sweep(&format!("[sweep.grid]\n{grid}"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("282429536481 runs, more than the 10000000 allowed"),
        "{e}"
    );
    assert!(start.elapsed().as_secs() < 5, "counted, not expanded");
    // A list of named runs counts as its length.
    let grid: String = (0..64)
        .map(|k| format!("[[sweep.runs]]\nname = \"r{k}\"\n"))
        .collect::<String>();
    assert!(sweep(&grid).is_ok());
}

/// Generated names stay legal file names: long ones are cut and hashed, stably.
#[test]
fn long_run_names_are_shortened_stably() {
    let long = "x".repeat(300);
    let keys = [
        "material.bending",
        "fibres.D",
        "growth.t_end",
        "solver.epsilon",
        "growth.Gamma",
        "growth.delta",
        "growth.eta0",
    ];
    let grid: String = keys
        .iter()
        .map(|k| format!("\"{k}\" = [1.2345678901234567]\n"))
        .collect();
    let text = format!("[sweep.grid]\n{grid}");
    let s = sweep(&text).unwrap();
    let name = &s.runs[0].name;
    assert_eq!(name.len(), 80 + 1 + 16, "{name}");
    assert!(
        // The grid's keys in the order written.
        name.starts_with("bending=1.2345678901234567_D=1.2345678901234567_"),
        "{name}"
    );
    assert_eq!(
        name,
        &sweep(&text).unwrap().runs[0].name,
        "the same every time"
    );
    assert_eq!(shorten(long.clone()).len(), 80 + 1 + 16);
    assert_ne!(shorten(long.clone()), shorten(format!("{long}y")));
    assert_eq!(shorten("Gamma=4".into()), "Gamma=4");
}

#[test]
fn nested_grid_keys_are_dotted_keys() {
    let s = sweep("[sweep.grid.fibres]\nD = [0, 400]\n").unwrap();
    assert_eq!(
        s.runs.iter().map(|r| r.scene.params.d).collect::<Vec<_>>(),
        [0.0, 400.0]
    );
}

#[test]
fn a_list_names_its_runs_and_crosses_the_grid() {
    let s = sweep(
        "[[sweep.runs]]\nname = \"const\"\n\"material.thickness\" = \"uniform\"\n[[sweep.runs]]\nname = \"thick\"\n\"material.thickness\" = \"nonuniform\"\n[sweep.grid]\n\"fibres.D\" = [0, 200]\n",
    )
    .unwrap();
    let names: Vec<_> = s.runs.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        ["const_D=0", "const_D=200", "thick_D=0", "thick_D=200"]
    );
    assert_eq!(s.keys, ["material.thickness", "fibres.D"]);
    assert_eq!(
        s.runs[3].scene.params.thickness,
        crate::model::params::Thickness::NonUniform
    );
}

#[test]
fn a_plain_scene_is_a_sweep_of_one() {
    let s = Sweep::from_toml_str(BASE, "s.toml", &[]).unwrap();
    assert_eq!(s.runs.len(), 1);
    assert_eq!(s.runs[0].name, "run");
}

#[test]
fn bad_sweeps_are_one_line_errors() {
    let cases = [
        ("[sweep]\n", "is empty"),
        ("[sweep]\ngird = {}\n", "did you mean 'grid'"),
        (
            "[sweep.grid]\n\"fibres.DD\" = [1]\n",
            "unknown key 'fibres.DD'",
        ),
        ("[sweep.grid]\n\"fibres.D\" = 3\n", "must be a list"),
        ("[sweep.grid]\n\"fibres.D\" = []\n", "empty list"),
        ("[sweep.grid]\n\"fibres.D\" = [-1]\n", "fibres.D"),
        ("[sweep.grid]\n\"fibres.D\" = [\"x\"]\n", "must be a number"),
        ("[[sweep.runs]]\nname = \"a/b\"\n", "directory name"),
        (
            "[[sweep.runs]]\n\"fibres.D\" = 1\n[sweep.grid]\n\"fibres.D\" = [2]\n",
            "both in the grid and in the runs",
        ),
    ];
    for (extra, expect) in cases {
        let e = sweep(extra).expect_err(extra).to_string();
        assert!(e.contains(expect), "{extra:?}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    let e = Sweep::from_toml_str(&format!("sweep = 3\n{BASE}"), "s.toml", &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("must be a table"), "{e}");
    // An invalid value names the run.
    let e = sweep("[sweep.grid]\n\"fibres.D\" = [1, -1]\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("run D=-1"), "{e}");
}

#[test]
fn set_may_not_touch_a_swept_key() {
    let text = format!("{BASE}[sweep.grid]\n\"fibres.D\" = [0, 1]\n");
    let e = Sweep::from_toml_str(&text, "s.toml", &["fibres.D=3".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("sweeps fibres.D"), "{e}");
    let s = Sweep::from_toml_str(&text, "s.toml", &["material.C=50".into()]).unwrap();
    assert!(s.runs.iter().all(|r| r.scene.params.c == 50.0));
}

#[test]
fn a_scene_with_a_sweep_is_refused_by_the_single_loader() {
    let e = Scene::from_toml_str(
        &format!("{BASE}[sweep.grid]\n\"fibres.D\" = [0]\n"),
        "s.toml",
        &[],
    )
    .unwrap_err();
    assert!(e.to_string().contains("eyeshell sweep"), "{e}");
}

/// Names made from the index alone ([`SweepPlan::direct_names`]) are the names made
/// unique in sweep order, and read back to their runs; a plan whose names could
/// collide lists them instead, with the same result.
#[test]
fn names_from_the_index_are_the_names_made_in_order() {
    let cases = [
        // (sweep, names are direct)
        ("[sweep.grid]\n\"growth.Gamma\" = [4, 8, 12]\n\"growth.delta\" = [2, 6]\n", true),
        ("[sweep.grid]\n\"solver.newton_tol\" = [1e-9, 1e-10]\n\"growth.t_end\" = [1, 2]\n", true),
        ("[[sweep.runs]]\nname = \"a_b\"\n[[sweep.runs]]\n\"fibres.D\" = 3\n[[sweep.runs]]\n[sweep.grid]\n\"growth.t_end\" = [1, 2]\n", true),
        ("[[sweep.runs]]\nname = \"run\"\n[[sweep.runs]]\n\"fibres.D\" = 3\n", true),
        // 1 and 1.0 both show as D=1.
        ("[sweep.grid]\n\"fibres.D\" = [1, 1.0, 2]\n", false),
        // An entry of no values is named "run", as the first one is.
        ("[[sweep.runs]]\nname = \"run\"\n[[sweep.runs]]\n", false),
        ("[[sweep.runs]]\nname = \"D=1\"\n[[sweep.runs]]\n\"fibres.D\" = 1\n[sweep.grid]\n\"growth.Gamma\" = [4, 8]\n", false),
    ];
    for (extra, direct) in cases {
        let plan = SweepPlan::from_toml_str(&format!("{BASE}{extra}"), "s.toml", &[]).unwrap();
        assert_eq!(plan.direct.is_some(), direct, "{extra}");
        let listed = plan.unique_names();
        for (i, name) in listed.iter().enumerate() {
            assert_eq!(&plan.run_name(i), name, "{extra}");
            assert!(plan.has_name(name), "{name} in {extra}");
            assert_eq!(plan.run(i).unwrap().name, *name);
        }
        for other in [
            "",
            "run-2",
            "Gamma=4",
            "Gamma=4_delta=2_x",
            "x_Gamma=4_delta=2",
            "_Gamma=4_delta=2",
        ] {
            assert_eq!(
                plan.has_name(other),
                listed.iter().any(|n| n == other),
                "{other} in {extra}"
            );
        }
    }
    let long: String = (0..7)
        .map(|k| {
            format!(
                "\"{}\" = [1.2345678901234567]\n",
                [
                    "material.bending",
                    "fibres.D",
                    "growth.t_end",
                    "solver.epsilon",
                    "growth.Gamma",
                    "growth.delta",
                    "growth.eta0"
                ][k]
            )
        })
        .collect();
    let plan =
        SweepPlan::from_toml_str(&format!("{BASE}[sweep.grid]\n{long}"), "s.toml", &[]).unwrap();
    assert!(plan.direct.is_none(), "shortened names are listed");
    assert!(plan.has_name(&plan.run_name(0)));
}

/// A plan counts its runs before it names any: a sweep of 10⁷ runs is refused as too
/// large for one process at once.
#[test]
fn a_plan_names_no_run_until_asked() {
    let values: Vec<String> = (0..100)
        .map(|i| format!("{}", 1.0 + i as f64 / 100.0))
        .collect();
    let axis = format!("[{}]", values.join(", "));
    let text = format!(
        "{BASE}[sweep.grid]\n\"pressure.dP\" = {axis}\n\"material.C\" = [{}]\n\"fibres.D\" = {axis}\n\"solver.newton_tol\" = [1e-9, 2e-9, 3e-9, 4e-9, 5e-9, 6e-9, 7e-9, 8e-9, 9e-9, 1e-8]\n",
        (50..150).map(|c| c.to_string()).collect::<Vec<_>>().join(", ")
    );
    let start = std::time::Instant::now();
    let plan = SweepPlan::from_toml_str(&text, "s.toml", &[]).unwrap();
    assert_eq!(plan.len(), 10_000_000);
    assert!(plan.direct.is_some());
    assert!(plan.names.get().is_none(), "no run named yet");
    let last = plan.run_name(plan.len() - 1);
    assert_eq!(last, "dP=1.99_C=149_D=1.99_newton_tol=1e-8");
    assert!(plan.has_name(&last));
    assert_eq!(plan.index_of(&last), Some(plan.len() - 1));
    let e = Sweep::from_plan(plan).unwrap_err().to_string();
    assert!(
        e.contains("declares 10000000 runs, more than the 10000 allowed"),
        "{e}"
    );
    assert!(start.elapsed().as_secs_f64() < 1.0, "{:?}", start.elapsed());
}

#[test]
fn duplicate_generated_names_are_made_unique() {
    let s =
        sweep("[[sweep.runs]]\n\"fibres.D\" = 1\n[[sweep.runs]]\n\"fibres.D\" = 1.0\n").unwrap();
    assert_eq!(s.runs[0].name, "D=1");
    assert_eq!(s.runs[1].name, "D=1-2");
}

/// A name the user gave is never taken by another run's de-duplication, whatever the
/// order: `a`, `a`, `a-2` keep `a` and `a-2` and the second `a` becomes `a-3`.
#[test]
fn deduplication_never_takes_a_name_a_run_was_given() {
    let runs = |names: &[&str]| {
        let text: String = names
            .iter()
            .enumerate()
            .map(|(i, n)| format!("[[sweep.runs]]\nname = \"{n}\"\n\"fibres.D\" = {}\n", i + 1))
            .collect();
        let s = sweep(&text).unwrap();
        let got: Vec<(String, f64)> = s
            .runs
            .iter()
            .map(|r| (r.name.clone(), r.scene.params.d))
            .collect();
        let unique: std::collections::HashSet<&String> = got.iter().map(|(n, _)| n).collect();
        assert_eq!(unique.len(), got.len(), "{got:?}");
        got
    };
    let got = runs(&["a", "a", "a-2"]);
    assert_eq!(got[0], ("a".into(), 1.0));
    assert_eq!(got[1], ("a-3".into(), 2.0));
    assert_eq!(got[2], ("a-2".into(), 3.0), "the user's a-2 keeps its name");
    let got = runs(&["a-2", "a", "a", "a", "a-3"]);
    let names: Vec<&str> = got.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["a-2", "a", "a-4", "a-5", "a-3"]);
}
