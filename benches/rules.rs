//! The growth rules' cost (docs/MODEL.md §6, "Growth rules"; docs/guide/hypotheses.md): one
//! growth run per iteration of scenes/myopia/single-vision.toml (computed optics, a -2 D
//! spectacle, t from 8 to 11 years) under the paper's rule `blue-surface`, the local rules
//! `defocus` and `chromatic`, and `defocus` over the integrated region. Run with
//!   cargo bench --bench rules
//! Before timing, each run's work (IDA steps, residual evaluations, Newton iterations) is
//! printed: a rule that grows a different eye takes a different number of steps, so a
//! run's ratio to the paper's is (cost per residual) × (residuals per run), and the counts
//! say which part is which. The bound: a local rule at most 1.2× the paper's per
//! run, an integrated one at most 2×.

use criterion::{criterion_group, criterion_main, Criterion};
use eyeshell::model::rule::{BlueSurface, Drive, GrowthRule, Reads, RuleError, RuleKeys, Seen};
use eyeshell::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The rules timed: the name and the `--set`s that choose it.
const RULES: [(&str, &[&str]); 4] = [
    ("blue_surface", &["stimulus.rule=blue-surface"]),
    ("defocus", &["stimulus.rule=defocus"]),
    ("chromatic", &["stimulus.rule=chromatic"]),
    (
        "defocus_integrated",
        &["stimulus.rule=defocus", "stimulus.region=integrated"],
    ),
];

fn read(sets: &[&str]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/myopia/single-vision.toml");
    let mut all = vec!["output.history_points=0".to_string()];
    all.extend(sets.iter().map(|s| s.to_string()));
    Scene::from_file(&path, &all).expect("scenes/myopia/single-vision.toml")
}

/// Every rule under IDA (its own steps), then under fixed-step Euler: 200 steps whatever the
/// rule grows (equal steps; each step's elastic Newton iterations still follow how far the
/// eye grew), then each local rule evaluated along the paper's own run (equal work).
fn rules(c: &mut Criterion) {
    timed(c, "rules_single_vision_8_to_11", &[]);
    timed(
        c,
        "rules_equal_work_euler_200",
        &["solver.integrator=euler", "solver.steps=200"],
    );
    along_the_papers_run(c);
}

/// A rule evaluated but not obeyed: at every call it computes `timed`'s drive (and the view
/// it reads: the red surface, the defocus) and then returns the paper's, so the run is the
/// paper's run, step for step, plus the rule's own cost. A rule that grows a different eye
/// takes different steps and different elastic iterations; this separates what the rule
/// costs from what the eye it grows costs.
#[derive(Debug)]
struct Shadow {
    timed: Arc<dyn GrowthRule>,
    scratch: std::sync::Mutex<Vec<Drive>>,
}

impl GrowthRule for Shadow {
    fn name(&self) -> &str {
        "shadow"
    }

    fn reads(&self) -> Reads {
        self.timed.reads()
    }

    fn drive(&self, seen: &[Seen], partials: bool, out: &mut [Drive]) -> Result<(), RuleError> {
        let mut scratch = self.scratch.lock().expect("one growth run at a time");
        scratch.resize(out.len(), Drive::default());
        self.timed.drive(seen, partials, &mut scratch)?;
        black_box(&*scratch);
        BlueSurface.drive(seen, partials, out)
    }
}

/// The local rules' own cost per run: each rule (with the scene's keys) shadowing the paper's
/// rule over the paper's run of the scene (IDA, its own 46 steps), against that run itself.
fn along_the_papers_run(c: &mut Criterion) {
    let keys = |rule: usize| RuleKeys {
        rule,
        baseline: 0.05,
        hyperopic_gain: 0.37,
        myopic_gain: 0.01,
        ..RuleKeys::default()
    };
    let papers = read(&["stimulus.rule=blue-surface"]);
    let reference = papers.grow(&mut ()).expect("the paper's run");
    let mut group = c.benchmark_group("rules_along_the_papers_run");
    group.sample_size(10);
    group.bench_function("blue_surface", |b| {
        b.iter(|| black_box(papers.grow(&mut ()).unwrap().series.len()))
    });
    for (name, rule) in [("defocus", 1), ("chromatic", 2)] {
        let mut scene = papers.clone();
        let shadow = Shadow {
            timed: keys(rule).build(),
            scratch: Default::default(),
        };
        scene.set_rule(Arc::new(shadow)).expect("a growing scene");
        let run = scene.grow(&mut ()).expect("the shadowed run");
        // The same run: the same steps and the same eye, so the time is the rule's alone.
        assert_eq!(run.stats.steps, reference.stats.steps, "{name}");
        assert_eq!(
            run.series.last().map(|r| r.axial_length),
            reference.series.last().map(|r| r.axial_length),
            "{name}"
        );
        eprintln!(
            "{name} along the paper's run: {} steps, {} residual evaluations",
            run.stats.steps, run.stats.residual_evaluations
        );
        group.bench_function(name, |b| {
            b.iter(|| black_box(scene.grow(&mut ()).unwrap().series.len()))
        });
    }
    group.finish();
}

fn timed(c: &mut Criterion, group_name: &str, integrator: &[&str]) {
    let mut group = c.benchmark_group(group_name);
    group.sample_size(10);
    for (name, sets) in RULES {
        let all: Vec<&str> = sets.iter().chain(integrator).copied().collect();
        let scene = read(&all);
        let run = scene
            .grow(&mut ())
            .expect("the scene grows under every rule");
        let s = &run.stats;
        eprintln!(
            "{name}: {} steps, {} residual evaluations, {} Newton iterations, axial length {:.6} mm",
            s.steps,
            s.residual_evaluations,
            s.nonlinear_iterations,
            run.series.last().map_or(f64::NAN, |r| r.axial_length),
        );
        group.bench_function(name, |b| {
            b.iter(|| black_box(scene.grow(&mut ()).unwrap().series.len()))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().measurement_time(Duration::from_secs(20));
    targets = rules
}
criterion_main!(benches);
