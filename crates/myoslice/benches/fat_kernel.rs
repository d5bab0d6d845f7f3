//! The fat kernel (one shape-matching iteration) on blocks of 840, 20 000 and 200 000
//! hexahedra, on one and two threads; throughput is in elements, so criterion's
//! "elem/s" converts to ns per element-iteration (1e9 / throughput).

mod common;

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use myoslice::tissue::FatSolver;

/// Shape-matching iterations per tissue update (the default): each run of the kernel
/// starts again from the bent shape after this many, as each update starts from its guess.
const ITERATIONS: u64 = 6;

fn bent(nx: usize, ny: usize, nz: usize) -> FatSolver {
    let mut s = FatSolver::grid(nx, ny, nz, 0.01);
    // A bend, so rotations and goals are not trivial.
    for p in &mut s.x {
        p.z += 0.02 * (p.x * 10.0).sin();
    }
    s
}

fn fat(c: &mut Criterion) {
    for (name, dims) in [
        ("840", (20, 7, 6)),
        ("20k", (40, 25, 20)),
        ("200k", (100, 50, 40)),
    ] {
        let mut g = c.benchmark_group(format!("fat_kernel_{name}"));
        g.sample_size(20).measurement_time(Duration::from_secs(5));
        let base = bent(dims.0, dims.1, dims.2);
        g.throughput(Throughput::Elements(base.len() as u64));
        for threads in [1, 2] {
            let pool = common::pool(threads);
            let mut s = base.clone();
            // Whole batches inside the pool: no thread hand-over per iteration.
            g.bench_function(format!("{threads}_threads"), |b| {
                b.iter_custom(|iters| {
                    pool.install(|| {
                        let mut spent = Duration::ZERO;
                        let mut done = 0;
                        while done < iters {
                            // From the bent shape again every update's worth of
                            // iterations, as the tissue does.
                            s.x.clone_from(&base.x);
                            s.rot.clone_from(&base.rot);
                            let n = ITERATIONS.min(iters - done);
                            let t = Instant::now();
                            for _ in 0..n {
                                s.iterate(black_box(0.5));
                            }
                            spent += t.elapsed();
                            done += n;
                        }
                        spent
                    })
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, fat);
criterion_main!(benches);
