//! Optics with age (docs/guide/optics.md): the const scene grown with computed surfaces whose
//! eye changes over t (scenes/optics-age.toml: the cornea flattens and the anterior chamber
//! deepens, five table times) against the same eye fixed at its t = 1 values. Run with
//!   cargo bench --bench optics_age
//! Two timings each: the growth alone (the scene read, its surfaces traced, beforehand: what
//! a step costs) and the scene read and grown (the tracing at every table time included).
//! The brief's bound: the changing eye costs at most twice the fixed one.

use criterion::{criterion_group, criterion_main, Criterion};
use eyeshell::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// N = 201 keeps a run near a second on the shared machine.
const NODES: &str = "solver.nodes=201";

fn read(changing: bool) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/optics-age.toml");
    let mut sets = vec![NODES.to_string(), "output.history_points=0".to_string()];
    if !changing {
        // The same eye at its t = 1 values throughout.
        sets.push("optics.surfaces=[{}, {}]".to_string());
    }
    Scene::from_file(&path, &sets).expect("scenes/optics-age.toml")
}

fn optics_age(c: &mut Criterion) {
    let mut group = c.benchmark_group("optics_age_n201_to_t1");
    group.sample_size(10);
    for (name, changing) in [("fixed_eye", false), ("flattening_cornea", true)] {
        let scene = read(changing);
        group.bench_function(format!("grow_{name}"), |b| {
            b.iter(|| black_box(scene.grow(&mut ()).unwrap().series.len()))
        });
        group.bench_function(format!("read_and_grow_{name}"), |b| {
            b.iter(|| black_box(read(changing).grow(&mut ()).unwrap().series.len()))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().measurement_time(Duration::from_secs(20));
    targets = optics_age
}
criterion_main!(benches);
