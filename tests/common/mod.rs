//! Shared test support: one device per backend, the macro that makes a CPU and a GPU variant of
//! each test, and plain host references that the kernels are checked against.
#![allow(dead_code)] // each test binary uses its own part of this module

pub mod game;
pub mod sim;

use std::io::Write;
use std::sync::OnceLock;

use gpuwars::{Device, Error};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// The edge sizes every primitive is checked at, besides random ones.
pub const EDGE_SIZES: &[usize] = &[0, 1, 31, 32, 33, 1000, (1 << 20) + 7];

/// The CPU emulation, shared by the tests of one binary.
pub fn cpu() -> &'static Device {
    static CPU: OnceLock<Device> = OnceLock::new();
    CPU.get_or_init(|| Device::cpu(None, "tests").expect("the CPU emulation starts"))
}

/// The GPU, or `None` (with the reason printed) where there is none. A GPU that is present but
/// fails to open is a test failure, not a skip.
pub fn gpu() -> Option<&'static Device> {
    static GPU: OnceLock<Result<Device, String>> = OnceLock::new();
    let gpu = GPU.get_or_init(|| match Device::cuda("tests") {
        Ok(device) => Ok(device),
        Err(Error::CudaUnavailable(why)) => Err(why),
        Err(other) => panic!("a GPU is present but cannot be used: {other}"),
    });
    match gpu {
        Ok(device) => Some(device),
        Err(why) => {
            // Straight to stderr: the test harness captures only the print macros, and a skip
            // must be visible.
            let name = std::thread::current().name().unwrap_or("test").to_string();
            let _ = writeln!(std::io::stderr(), "{name}: skipped: no GPU ({why})");
            None
        }
    }
}

/// Makes `cpu::NAME` and `gpu::NAME` tests of each function `NAME(&Device)`.
#[macro_export]
macro_rules! on_both_backends {
    ($($name:ident),* $(,)?) => {
        mod cpu {
            $(#[test] fn $name() { super::$name($crate::common::cpu()); })*
        }
        mod gpu {
            $(#[test] fn $name() {
                if let Some(device) = $crate::common::gpu() { super::$name(device); }
            })*
        }
    };
}

/// A generator seeded from the test's name and a size, so every failure is reproducible.
pub fn rng_for(test: &str, n: usize) -> StdRng {
    let seed = test.bytes().fold(n as u64 ^ 0x9e37_79b9_7f4a_7c15, |h, b| {
        h.rotate_left(5) ^ b as u64
    });
    StdRng::seed_from_u64(seed)
}

/// `n` random u32 values below `bound`.
pub fn random_below(rng: &mut StdRng, n: usize, bound: u32) -> Vec<u32> {
    (0..n).map(|_| rng.random_range(0..bound)).collect()
}

/// Reference exclusive prefix sum, wrapping like the kernel.
pub fn exclusive_scan(input: &[u32]) -> Vec<u32> {
    let mut sum = 0u32;
    input
        .iter()
        .map(|&v| {
            let before = sum;
            sum = sum.wrapping_add(v);
            before
        })
        .collect()
}

/// Reference histogram: keys not below `bins` are not counted.
pub fn histogram(keys: &[u32], bins: usize) -> Vec<u32> {
    let mut counts = vec![0u32; bins];
    for &k in keys {
        if let Some(c) = counts.get_mut(k as usize) {
            *c += 1;
        }
    }
    counts
}

/// Reference sort of (key, index) pairs: the standard library's sort of the pairs themselves,
/// so equal keys are ordered by index.
pub fn sort_pairs(keys: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = keys
        .iter()
        .enumerate()
        .map(|(i, &k)| (k, i as u32))
        .collect();
    pairs.sort_unstable();
    pairs.into_iter().unzip()
}

/// A histogram of the first `n` of `keys` into `counts`, on `grid` blocks of `block` threads,
/// as an op that holds both buffers.
pub fn histogram_op(
    keys: &gpuwars::Buffer<u32>,
    counts: &gpuwars::Buffer<u32>,
    n: u32,
    grid: u32,
    block: u32,
) -> gpuwars::Op {
    use gpuwars::backend::{Binder, Launch};
    use gpuwars::kernels::{primitives::histogram::HistogramArgs, registry};
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = HistogramArgs {
        keys: b.view(keys),
        counts: b.view(counts),
        n,
        reserved: 0,
    };
    let kernel = registry::HISTOGRAM;
    // SAFETY: two buffers of this binder; a wrong `n` is caught by the bounds checks.
    unsafe {
        gpuwars::Op::launch(
            Launch {
                kernel,
                grid,
                block,
                args,
            },
            b,
            0,
        )
    }
}
