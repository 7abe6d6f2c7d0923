//! The arithmetic the GPU does its own faster way, checked bit for bit against the correctly
//! rounded operations it stands for, over every input it is used on.

mod common;

use gpuwars::Device;
use gpuwars::backend::{Binder, Launch, Op};
use gpuwars::kernels::math::{
    PLAIN_SQUARES, RECIP_SQRT_CHECKS_PER_THREAD, RecipSqrtCheckArgs, recip_sqrt,
};
use gpuwars::kernels::registry;

/// How many of the `count` patterns from `first` give a `recip_sqrt` other than `1.0 /
/// sqrt(x)` on `device`, and the largest of them.
fn recip_sqrt_mismatches(device: &Device, first: u32, count: u32) -> [u32; 2] {
    let found = device.alloc_zeroed::<u32>(2).unwrap();
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let args = RecipSqrtCheckArgs {
        first,
        count,
        found: b.view(&found),
    };
    let threads = count.div_ceil(RECIP_SQRT_CHECKS_PER_THREAD);
    let launch = Launch {
        kernel: registry::CHECK_RECIP_SQRT,
        grid: threads.div_ceil(256),
        block: 256,
        args,
    };
    // SAFETY: one buffer of two counters, changed by atomics only.
    device.launch(unsafe { Op::launch(launch, b, 0) }).unwrap();
    let found = device.download(&found).unwrap();
    [found[0], found[1]]
}

/// Every `f32` from 2⁻¹⁰⁰ to 2¹⁰⁰ (about 1.7 billion of them) on the GPU, whose
/// `recip_sqrt` runs the instructions of `sqrt.rn` and `rcp.rn` without their range checks,
/// against those correctly rounded instructions, in launches of at most 2^28 patterns. A
/// mismatch names the first pattern in hexadecimal. (On the CPU `recip_sqrt` is the division
/// itself: the test below checks it against f64.)
#[test]
fn recip_sqrt_on_the_gpu_is_the_rounded_reciprocal_of_the_rounded_root() {
    let Some(device) = common::gpu() else { return };
    let (low, high) = (
        PLAIN_SQUARES.start().to_bits(),
        PLAIN_SQUARES.end().to_bits(),
    );
    let all = high - low + 1;
    for k in 0..all.div_ceil(1 << 28) {
        let (first, count) = (low + (k << 28), (all - (k << 28)).min(1 << 28));
        let [mismatches, largest] = recip_sqrt_mismatches(device, first, count);
        assert_eq!(
            mismatches,
            0,
            "{mismatches} of the {count} patterns from {first:#010x} differ, up to {largest:#010x} ({})",
            f32::from_bits(largest)
        );
    }
}

/// `1 / sqrt(x)` with each step rounded to f32, from f64 arithmetic: a square root or a
/// quotient computed in f64 and rounded to f32 is the correctly rounded f32 one (f64 has more
/// than twice f32's precision and two bits more), so this is an independent reference.
fn recip_sqrt_in_f64(x: f32) -> f32 {
    let root = f64::from(x).sqrt() as f32;
    (1.0 / f64::from(root)) as f32
}

/// The CPU's `recip_sqrt` (the one the emulator runs) against the f64 reference, over every
/// 997th pattern of the range, its ends and the powers of two; and the emulator's launch of
/// the check kernel over a run of patterns finds no mismatch either.
#[test]
fn recip_sqrt_on_the_cpu_matches_a_reference_in_f64() {
    let (low, high) = (
        PLAIN_SQUARES.start().to_bits(),
        PLAIN_SQUARES.end().to_bits(),
    );
    let sampled = (low..=high).step_by(997);
    let powers = (-100..=100).map(|e| 2f32.powi(e).to_bits());
    for bits in sampled.chain([low, high]).chain(powers) {
        let x = f32::from_bits(bits);
        assert_eq!(
            recip_sqrt(x).to_bits(),
            recip_sqrt_in_f64(x).to_bits(),
            "{x:e} ({bits:#010x})"
        );
    }
    assert_eq!(recip_sqrt_mismatches(common::cpu(), low, 1_000), [0, 0]);
}

/// The range the fast path is taken for: its ends are 2⁻¹⁰⁰ and 2¹⁰⁰ exactly, whose square
/// roots and their reciprocals are normal numbers far from the GPU's special cases.
#[test]
fn the_plain_squares_are_the_powers_of_two_they_say() {
    assert_eq!(*PLAIN_SQUARES.start(), 2f32.powi(-100));
    assert_eq!(*PLAIN_SQUARES.end(), 2f32.powi(100));
}
