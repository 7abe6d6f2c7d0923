//! The free list of each kind's slot range (paper section 5: "a list with the values to
//! indicate available positions for individuals creation"), rebuilt after every step by
//! stream compaction so that it needs neither atomics nor a sequential scan:
//!
//! 1. [`mark_free`]: `flags[i]` = 1 where slot `i` is a usable slot without a live body;
//! 2. the host takes the exclusive prefix sum of the flags;
//! 3. [`gather_free`]: each free slot writes itself into its range's list at its rank, and
//!    the last slot of each range writes the range's count.
//!
//! Lists come out in increasing slot order; the master thread takes slots from the front.

use super::bodies::Bodies;
use super::kinds::SlotRange;
use crate::{DevSlice, Thread, device_data, kernel_args};

device_data! {
    /// Each kind's free slots, as the free-list rebuild leaves them.
    pub struct FreeSlots(slots, kinds) {
        /// Kind `k`'s free slots in order, from its range's start.
        list: [u32; slots],
        /// Free slots per kind.
        count: [u32; kinds],
    }
}

device_data! {
    /// The rebuild's own arrays, remade every step.
    pub struct FreeMarks(slots) {
        /// 1 for a free usable slot, else 0 (written by [`mark_free`]).
        flags: [u32; slots],
        /// The flags' exclusive prefix sums.
        ranks: [u32; slots],
    }
}

kernel_args! {
    /// Arguments of [`mark_free`].
    pub struct MarkArgs {
        /// The bodies (kinds and liveness are read).
        pub bodies: Bodies,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange>,
        /// Output: 1 for a free usable slot, else 0; one per slot.
        pub flags: DevSlice<u32>,
    }
}

/// Whether `slot`, of kind `range`, is usable (not padding).
#[inline(always)]
fn usable(slot: u32, range: SlotRange) -> bool {
    slot >= range.start && slot < range.end()
}

/// Thread `i` writes `flags[i]`.
#[inline(always)]
pub fn mark_free(t: Thread, args: &MarkArgs) {
    let slot = t.global();
    if slot >= args.flags.len() {
        return;
    }
    let range = args.ranges.get(args.bodies.kind.get(slot));
    let free = usable(slot, range) && !args.bodies.is_alive(slot);
    args.flags.set(slot, free as u32);
}

kernel_args! {
    /// Arguments of [`gather_free`].
    pub struct GatherArgs {
        /// Kind of each slot.
        pub kind: DevSlice<u32>,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange>,
        /// The flags of [`mark_free`].
        pub flags: DevSlice<u32>,
        /// Their exclusive prefix sums.
        pub ranks: DevSlice<u32>,
        /// Output: the free slots of kind `k` at `list[start_k ..][.. count_k]`; one per slot.
        pub list: DevSlice<u32>,
        /// Output: the number of free slots of each kind. A kind without slots has no writer: its
        /// count stays the 0 it was allocated with.
        pub count: DevSlice<u32>,
    }
}

/// Thread `i`: a free slot writes itself at its rank inside its range's list; the last usable
/// slot of a range writes the range's count. Every element has one writer.
#[inline(always)]
pub fn gather_free(t: Thread, args: &GatherArgs) {
    let slot = t.global();
    if slot >= args.flags.len() {
        return;
    }
    let kind = args.kind.get(slot);
    let range = args.ranges.get(kind);
    if !usable(slot, range) {
        return;
    }
    let first = args.ranks.get(range.start);
    let rank = args.ranks.get(slot) - first;
    let flag = args.flags.get(slot);
    if flag != 0 {
        args.list.set(range.start + rank, slot);
    }
    if slot + 1 == range.end() {
        args.count.set(kind, rank + flag);
    }
}
