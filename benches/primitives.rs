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
use gpuwars::primitives::{CountingSort, PrefixSum, histogram};
use gpuwars::{BackendRequest, Device};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// 2^20 and the 2^24 of the recorded GPU figures.
const SIZES: &[usize] = &[1 << 20, 1 << 24];
/// Bins of the histogram and key bound of the sort: a 64×64 grid of cells (three sort passes).
const CELLS: u32 = 4096;

fn device() -> Device {
    let request = match std::env::var("GPUWARS_BACKEND").as_deref() {
        Ok("cpu") => BackendRequest::Cpu,
        Ok("cuda") => BackendRequest::Cuda,
        _ => BackendRequest::Auto,
    };
    Device::select(request, None).expect("the backend opens")
}

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

        let mut group = c.benchmark_group("copy_dtod");
        group.sample_size(20);
        // Bytes read plus bytes written.
        group.throughput(Throughput::Bytes(2 * 4 * n as u64));
        group.bench_function(id.clone(), |b| {
            b.iter(|| {
                device.copy(&src, &mut dst).unwrap();
                device.synchronize().unwrap();
            })
        });
        group.finish();

        let mut group = c.benchmark_group("prefix_sum");
        group.sample_size(20);
        group.throughput(Throughput::Elements(n as u64));
        let mut scan = PrefixSum::new(&device, n).unwrap();
        group.bench_function(id.clone(), |b| {
            b.iter(|| {
                scan.run(&device, &src, &mut dst, black_box(n)).unwrap();
                device.synchronize().unwrap();
            })
        });
        group.finish();

        let mut group = c.benchmark_group("histogram");
        group.sample_size(20);
        group.throughput(Throughput::Elements(n as u64));
        let mut counts = device.alloc_zeroed::<u32>(CELLS as usize).unwrap();
        group.bench_function(id.clone(), |b| {
            b.iter(|| {
                histogram(&device, &src, black_box(n), &mut counts).unwrap();
                device.synchronize().unwrap();
            })
        });
        group.finish();

        let mut group = c.benchmark_group("counting_sort");
        group.sample_size(10);
        group.throughput(Throughput::Elements(n as u64));
        let mut sort = CountingSort::new(&device, n).unwrap();
        let mut indices = device.alloc_zeroed::<u32>(n).unwrap();
        group.bench_function(id, |b| {
            b.iter(|| {
                sort.run(&device, &src, black_box(n), CELLS, &mut dst, &mut indices)
                    .unwrap();
                device.synchronize().unwrap();
            })
        });
        group.finish();
    }
}

criterion_group!(benches, primitives);
criterion_main!(benches);
