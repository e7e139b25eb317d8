//! Sweeps and figures (scenes, sweeps and the paper's figures). Run with
//!   cargo bench --bench figures
//! Figures go in BENCHMARKS.md. The whole `eyeshell figures` (twelve runs and six figures)
//! is timed with `time eyeshell figures --out /tmp/figures` instead: one sample is seconds.

use std::sync::atomic::AtomicBool;

use criterion::{criterion_group, criterion_main, Criterion};
use eyeshell::scene::sweep::Sweep;
use eyeshell::sweep::{run_sweep, SweepOptions};
use eyeshell_cli::charts::{paper_figures, PaperRuns};
use eyeshell_cli::study::figures::SCENES;

/// The binary's allocator (src/main.rs), so that the figures are what `eyeshell` gets.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn scene(name: &str) -> Sweep {
    let (_, file, text) = SCENES
        .iter()
        .find(|s| s.0 == name)
        .expect("a built-in scene");
    Sweep::from_toml_str(text, file, &[]).expect("the built-in scene is valid")
}

/// The fibre sweep (four growth runs, N = 501, to t = 1) on one thread and on two: what
/// running the runs in parallel buys on a 2-core machine.
fn fibre_sweep(c: &mut Criterion) {
    let sweep = scene("fibre");
    let dir = tempfile::tempdir().expect("a temporary directory");
    let cancel = AtomicBool::new(false);
    let mut group = c.benchmark_group("fibre_sweep_4_runs");
    group.sample_size(10);
    for jobs in [1, 2] {
        let options = SweepOptions {
            jobs,
            resume: false,
            cancel: &cancel,
            runner: &eyeshell::sweep::InProcess,
            inputs: &[],
        };
        group.bench_function(format!("jobs_{jobs}"), |b| {
            b.iter(|| {
                run_sweep(&sweep, &dir.path().join("fibre"), &options, &|_, _, _| {})
                    .expect("the sweep runs")
            })
        });
    }
    group.finish();
}

/// Drawing figures (a)–(f) (PNG and SVG) from runs already on disk: `eyeshell figures --replot`.
fn draw(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let data = dir.path().join("data");
    let cancel = AtomicBool::new(false);
    let options = SweepOptions {
        jobs: 0,
        resume: false,
        cancel: &cancel,
        runner: &eyeshell::sweep::InProcess,
        inputs: &[],
    };
    for (name, _, _) in SCENES {
        run_sweep(&scene(name), &data.join(name), &options, &|_, _, _| {}).expect("the scene runs");
    }
    let runs = PaperRuns::read(&data).expect("the runs read back");
    let mut group = c.benchmark_group("figures");
    group.sample_size(10);
    group.bench_function("read_runs", |b| {
        b.iter(|| PaperRuns::read(&data).expect("the runs read back"))
    });
    group.bench_function("draw_a_to_f", |b| {
        b.iter(|| paper_figures(&runs, dir.path()).expect("the figures draw"))
    });
    group.finish();
}

criterion_group!(benches, fibre_sweep, draw);
criterion_main!(benches);
