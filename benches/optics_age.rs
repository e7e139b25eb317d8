//! Optics with age (docs/guide/optics.md): the const scene grown with computed surfaces whose
//! eye changes over t (scenes/optics-age.toml: the cornea flattens and the anterior chamber
//! deepens, five table times) against the same eye fixed at its t = 1 values. Run with
//!   cargo bench --bench optics_age
//! Three timings each: the growth alone (the scene read, its surfaces traced, beforehand: what
//! a step costs), the scene read and grown (the surfaces traced at every table time; the
//! refraction tables are traced once per process and kept, so after the first iteration they
//! are not in it), and the whole command `eyeshell grow` as a process at N = 201 and 501
//! (everything: read, trace, refraction tables, growth, files). The bound: the changing eye
//! costs at most twice the fixed one. Beside them, the growth alone with the schedule of
//! scenes/optics-age-schedule.toml (s = exp(−t/0.5) on η0, the surfaces read at t = S⁻¹(τ)),
//! for the fixed and the changing eye: the changing eye with the schedule costs at most
//! twice the fixed eye without one.

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
    read_scene("scenes/optics-age.toml", changing)
}

fn read_scene(file: &str, changing: bool) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let mut sets = vec![NODES.to_string(), "output.history_points=0".to_string()];
    if !changing {
        // The same eye at its t = 1 values throughout.
        sets.push("optics.surfaces=[{}, {}]".to_string());
    }
    Scene::from_file(&path, &sets).expect(file)
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
    for (name, changing) in [("fixed_eye", false), ("flattening_cornea", true)] {
        let scene = read_scene("scenes/optics-age-schedule.toml", changing);
        group.bench_function(format!("grow_scheduled_{name}"), |b| {
            b.iter(|| black_box(scene.grow(&mut ()).unwrap().series.len()))
        });
    }
    group.finish();
    let mut group = c.benchmark_group("optics_age_process_to_t1");
    group.sample_size(10);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/optics-age.toml");
    let out = std::env::temp_dir().join(format!("eyeshell-optics-age-{}", std::process::id()));
    for nodes in ["201", "501"] {
        for (name, changing) in [("fixed_eye", false), ("flattening_cornea", true)] {
            group.bench_function(format!("eyeshell_grow_n{nodes}_{name}"), |b| {
                b.iter(|| {
                    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_eyeshell"));
                    cmd.arg("grow")
                        .arg(&scene)
                        .arg("-q")
                        .args(["--set", &format!("solver.nodes={nodes}")])
                        .args(["--set", "output.history_points=0"]);
                    if !changing {
                        cmd.args(["--set", "optics.surfaces=[{}, {}]"]);
                    }
                    let status = cmd.arg("--out").arg(&out).status().unwrap();
                    assert!(status.success());
                })
            });
        }
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&out);
}

criterion_group! {
    name = benches;
    config = Criterion::default().measurement_time(Duration::from_secs(20));
    targets = optics_age
}
criterion_main!(benches);
