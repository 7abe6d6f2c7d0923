//! Time per call of each parallel primitive next to a device-to-device copy of the same data,
//! on the backend `GPUWARS_BACKEND` names (default: auto).
//!
//! ```text
//! cargo bench --bench primitives                          # auto: the GPU when present
//! GPUWARS_BACKEND=cpu cargo bench --bench primitives -- prefix_sum
//! ```
//! Every timed iteration ends with a synchronise, so GPU times are whole calls, not queueing.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use gpuwars::Device;
use gpuwars::primitives::{CountingSort, PrefixSum, histogram};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

mod common;
use common::device;

/// 2^20 and the 2^24 of the recorded GPU figures.
const SIZES: &[usize] = &[1 << 20, 1 << 24];
/// Bins of the histogram and key bound of the sort: a 64×64 grid of cells (three sort passes).
const CELLS: u32 = 4096;

fn random_keys(n: usize, bound: u32) -> Vec<u32> {
    let mut rng = StdRng::seed_from_u64(n as u64);
    (0..n).map(|_| rng.random_range(0..bound)).collect()
}

fn primitives(c: &mut Criterion) {
    let device = device();
    let backend = device.kind();
    if let Some(gpu) = device.gpu_properties() {
        eprintln!(
            "benchmarking on {} (compute capability {})",
            gpu.name, gpu.compute_capability
        );
    }
    for &n in SIZES {
        let keys = random_keys(n, CELLS);
        let src = device.upload(&keys).unwrap();
        let mut dst = device.alloc_zeroed::<u32>(n).unwrap();
        let id = BenchmarkId::new(backend.to_string(), n);

        let elements = Throughput::Elements(n as u64);
        // Bytes read plus bytes written.
        let copy_bytes = Throughput::Bytes(2 * 4 * n as u64);
        time_calls(c, &device, "copy_dtod", &id, copy_bytes, 20, || {
            device.copy(&src, &mut dst)
        });
        let mut scan = PrefixSum::new(&device, n).unwrap();
        time_calls(c, &device, "prefix_sum", &id, elements.clone(), 20, || {
            scan.run(&device, &src, &mut dst, black_box(n))
        });
        let mut counts = device.alloc_zeroed::<u32>(CELLS as usize).unwrap();
        time_calls(c, &device, "histogram", &id, elements.clone(), 20, || {
            histogram(&device, &src, black_box(n), &mut counts)
        });
        let mut sort = CountingSort::new(&device, n).unwrap();
        let mut indices = device.alloc_zeroed::<u32>(n).unwrap();
        time_calls(c, &device, "counting_sort", &id, elements, 10, || {
            sort.run(&device, &src, black_box(n), CELLS, &mut dst, &mut indices)
        });
    }
}

/// Times `call` followed by a synchronise, so that GPU times are whole calls, not queueing.
fn time_calls(
    c: &mut Criterion,
    device: &Device,
    group: &str,
    id: &BenchmarkId,
    throughput: Throughput,
    samples: usize,
    mut call: impl FnMut() -> Result<(), gpuwars::Error>,
) {
    let mut group = c.benchmark_group(group);
    group.sample_size(samples).throughput(throughput);
    group.bench_function(id.clone(), |b| {
        b.iter(|| {
            call().unwrap();
            device.synchronize().unwrap();
        })
    });
    group.finish();
}

criterion_group!(benches, primitives);
criterion_main!(benches);
