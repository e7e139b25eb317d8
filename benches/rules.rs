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
use eyeshell::scene::Scene;
use std::hint::black_box;
use std::path::Path;
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
/// rule grows, so the second group's ratios are the rule's cost at equal work.
fn rules(c: &mut Criterion) {
    timed(c, "rules_single_vision_8_to_11", &[]);
    timed(
        c,
        "rules_equal_work_euler_200",
        &["solver.integrator=euler", "solver.steps=200"],
    );
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
