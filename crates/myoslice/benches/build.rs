//! The whole build, label volume to lattice (issue: goal under 0.5 s on one core).

mod common;

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use myoslice::prelude::*;

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    let one = common::pool(1);
    if let Some((v, l)) = common::vh_paths() {
        g.bench_function("visible_human_read_and_build_1_thread", |b| {
            b.iter(|| {
                one.install(|| {
                    let vol = read_nifti(&v).unwrap_or_else(|e| panic!("{e}"));
                    let table = LabelTable::from_path(&l).unwrap_or_else(|e| panic!("{e}"));
                    black_box(Lattice::build(&vol, &table, &BuildOptions::default()))
                })
            })
        });
    }
    let (vol, table) = Phantom::default()
        .generate()
        .unwrap_or_else(|e| panic!("{e}"));
    g.bench_function("phantom_build_1_thread", |b| {
        b.iter(|| one.install(|| black_box(Lattice::build(&vol, &table, &BuildOptions::default()))))
    });
    g.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
