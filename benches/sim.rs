//! Time per simulation step of the 10,000-body world of the determinism tests, on the
//! backend `GPUWARS_BACKEND` names (default: auto).
//!
//! ```text
//! cargo bench --bench sim                 # auto: the GPU when present
//! GPUWARS_BACKEND=cpu cargo bench --bench sim
//! ```
//! Every timed step ends with a synchronise.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gpuwars::pipeline::Simulation;

mod common;
use common::device;

#[path = "../tests/common/sim.rs"]
#[allow(dead_code)]
mod worlds;

fn step(c: &mut Criterion) {
    let device = device();
    let (spec, scatter) = worlds::ten_thousand();
    let mut sim = Simulation::new(&device, &spec, 1).unwrap();
    let mut bodies = 0;
    for (kind, count, speed) in scatter {
        sim.scatter(kind, count, speed).unwrap();
        bodies += u64::from(count);
    }
    let mut group = c.benchmark_group("sim_step");
    group.throughput(Throughput::Elements(bodies));
    group.bench_function(format!("{}/10k_bodies", device.kind()), |b| {
        b.iter(|| {
            sim.step().unwrap();
            device.synchronize().unwrap();
        })
    });
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
