//! The arithmetic the GPU does its own faster way, checked bit for bit against the correctly
//! rounded operations it stands for, over every input it is used on.

mod common;

use gpuwars::backend::{Binder, Launch, Op};
use gpuwars::kernels::math::{PLAIN_SQUARES, RECIP_SQRT_CHECKS_PER_THREAD, RecipSqrtCheckArgs};
use gpuwars::kernels::registry;
use gpuwars::{BackendKind, Device};

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
/// `recip_sqrt` runs the instructions of `sqrt.rn` and `rcp.rn` without their range checks;
/// a spread sample of them on the CPU emulation, whose `recip_sqrt` is the division itself
/// (the check of the check). A mismatch names the first pattern in hexadecimal.
fn recip_sqrt_is_the_rounded_reciprocal_of_the_rounded_root(device: &Device) {
    let (low, high) = (
        PLAIN_SQUARES.start().to_bits(),
        PLAIN_SQUARES.end().to_bits(),
    );
    let all = high - low + 1;
    let chunks: Vec<(u32, u32)> = match device.kind() {
        // In launches of at most 2^28 patterns.
        BackendKind::Cuda => (0..all.div_ceil(1 << 28))
            .map(|k| (low + (k << 28), (all - (k << 28)).min(1 << 28)))
            .collect(),
        // 64 spread runs of 1,000, the range's ends among them.
        BackendKind::Cpu => (0..64u32)
            .map(|k| (low + (all - 1_000) / 63 * k, 1_000))
            .collect(),
    };
    for (first, count) in chunks {
        let [mismatches, largest] = recip_sqrt_mismatches(device, first, count);
        assert_eq!(
            mismatches,
            0,
            "{mismatches} of the {count} patterns from {first:#010x} differ, up to {largest:#010x} ({})",
            f32::from_bits(largest)
        );
    }
}

/// The range the fast path is taken for: its ends are 2⁻¹⁰⁰ and 2¹⁰⁰ exactly, whose square
/// roots and their reciprocals are normal numbers far from the GPU's special cases.
#[test]
fn the_plain_squares_are_the_powers_of_two_they_say() {
    assert_eq!(*PLAIN_SQUARES.start(), 2f32.powi(-100));
    assert_eq!(*PLAIN_SQUARES.end(), 2f32.powi(100));
}

on_both_backends!(recip_sqrt_is_the_rounded_reciprocal_of_the_rounded_root);
