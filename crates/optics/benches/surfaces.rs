//! Two wavelengths × 41 field angles with the Strehl criterion through the Atchison 2006 eye:
//! the cost of a run's optics (computed once per run).

use criterion::{criterion_group, criterion_main, Criterion};
use eyeshell_optics::{eyes, Criterion as Focus, Pupil, SurfaceSettings, Surfaces};

fn surfaces(c: &mut Criterion) {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 3.0,
        position: eye.pupil_position.unwrap_or(3.7),
    };
    let settings = SurfaceSettings::default();
    c.bench_function("atchison_2006 strehl 2x41", |b| {
        b.iter(|| {
            Surfaces::compute(&eye, &[400.0, 600.0], &pupil, Focus::Strehl, &settings).unwrap()
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = surfaces
}
criterion_main!(benches);
