//! The smallest kernel that does work: one read-modify-write a thread. The host replays a
//! chain of these over one array, as many as a step launches, to measure the launch floor a
//! step is compared with (`gpuwars demo --profile`, `gpuwars bench scale`); and the same
//! chain as rounds of one block with a barrier between them, the floor of a step that would
//! run in one block.

use crate::{DevSlice, Thread, kernel_args};

kernel_args! {
    /// Arguments of [`touch`].
    pub struct TouchArgs {
        /// One element a thread.
        pub data: DevSlice<u32>,
    }
}

/// Thread `i` adds one to `data[i]` (wrapping). Each element has one writer.
#[inline(always)]
pub fn touch(t: Thread, args: &TouchArgs) {
    let i = t.global();
    if i < args.data.len() {
        args.data.set(i, args.data.get(i).wrapping_add(1));
    }
}

kernel_args! {
    /// Arguments of [`touch_rounds`].
    pub struct TouchRoundsArgs {
        /// The elements touched each round.
        pub data: DevSlice<u32>,
        /// Rounds, one a stage of the step it stands for.
        pub rounds: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// `rounds` times: every thread adds one to each of the elements `global, global + threads,
/// ...` of `data` (wrapping), then the block waits at a barrier. Launched as one block, it is
/// a step's chain of launches run as one block with a barrier between stages.
///
/// Each element has one writer, which is also its only reader, so the barrier orders nothing
/// the result depends on: the emulator, which runs a block's threads one after the other,
/// skips it and gets the same counts.
#[inline(always)]
pub fn touch_rounds(t: Thread, args: &TouchRoundsArgs) {
    let stride = t.block_dim * t.grid_dim;
    for _ in 0..args.rounds {
        let mut i = t.global();
        while i < args.data.len() {
            args.data.set(i, args.data.get(i).wrapping_add(1));
            i += stride;
        }
        barrier();
    }
}

/// Waits until every thread of the block has arrived. `barrier.sync`, not `bar.sync` (which
/// is `.aligned`): the compiler may give threads that skip the loop's body a copy of the
/// barrier of their own, and only the unaligned form lets them meet at different copies.
#[inline(always)]
fn barrier() {
    // SAFETY: every thread of the block reaches it the same number of times (the loop count
    // is the launch's argument, the same for all); it only waits.
    #[cfg(target_arch = "nvptx64")]
    unsafe {
        core::arch::asm!("barrier.sync 0;", options(nostack));
    }
}
