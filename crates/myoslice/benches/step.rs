//! Stepping: the muscle + skeleton step alone (Hill, 1 ms; rigid tendons, and compliant
//! ones on the phantom) and the whole leg with its tissue at the default rate (and, on
//! the phantom, at a third of it). Each sample runs 0.1 s of simulated time from the same state,
//! a flexion under way, so the real-time factor is 0.1 s over the time shown.

mod common;

use std::time::Duration;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use myoslice::muscle::MuscleCatalogue;
use myoslice::prelude::*;
use myoslice::tissue::TissueConfig;

const SPAN_S: f64 = 0.1;

fn flexing(lattice: Lattice, tissue: bool) -> Simulation {
    flexing_with(lattice, tissue, TendonModel::Rigid)
}

fn flexing_with(lattice: Lattice, tissue: bool, tendon: TendonModel) -> Simulation {
    flexing_at(lattice, tissue, tendon, TissueConfig::default().rate_hz)
}

fn flexing_at(lattice: Lattice, tissue: bool, tendon: TendonModel, rate_hz: f64) -> Simulation {
    let mut cfg = SimulationConfig {
        tendon,
        ..SimulationConfig::default()
    };
    cfg.tissue.enabled = tissue;
    cfg.tissue.rate_hz = rate_hz;
    let mut sim = Simulation::new(lattice, cfg, &MuscleCatalogue::default())
        .unwrap_or_else(|e| panic!("{e}"));
    common::excite_flexors(&mut sim, 0.6);
    // Into the motion: the knee is turning when the samples start.
    sim.step(0.2).unwrap_or_else(|e| panic!("{e}"));
    sim
}

fn bench_span(c: &mut Criterion, group: &str, name: &str, sim: &Simulation, threads: usize) {
    let pool = common::pool(threads);
    let mut g = c.benchmark_group(group);
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    g.bench_function(format!("{name}_{threads}_threads"), |b| {
        b.iter_batched(
            || sim.clone(),
            |mut s| pool.install(|| s.step(SPAN_S).map(|_| s)),
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

fn steps(c: &mut Criterion) {
    let phantom = common::phantom_lattice();
    let vh = common::vh_lattice();
    bench_span(
        c,
        "muscle_step_0.1s",
        "phantom",
        &flexing(phantom.clone(), false),
        1,
    );
    if let Some(l) = &vh {
        bench_span(
            c,
            "muscle_step_0.1s",
            "visible_human",
            &flexing(l.clone(), false),
            1,
        );
    }
    // The same with the compliant tendons' per-step solve.
    bench_span(
        c,
        "muscle_step_0.1s",
        "phantom_compliant",
        &flexing_with(phantom.clone(), false, TendonModel::Compliant),
        1,
    );
    for threads in [1, 2] {
        bench_span(
            c,
            "whole_leg_0.1s",
            "phantom",
            &flexing(phantom.clone(), true),
            threads,
        );
        if let Some(l) = &vh {
            bench_span(
                c,
                "whole_leg_0.1s",
                "visible_human",
                &flexing(l.clone(), true),
                threads,
            );
        }
    }
    // The tissue at a third of its default rate: what that buys (the README's table of
    // rates; a 0.1 s span then holds one update, nothing beside its guard).
    bench_span(
        c,
        "whole_leg_0.1s",
        "phantom_tissue_third_rate",
        &flexing_at(
            phantom.clone(),
            true,
            TendonModel::Rigid,
            TissueConfig::default().rate_hz / 3.0,
        ),
        2,
    );
}

criterion_group!(benches, steps);
criterion_main!(benches);
