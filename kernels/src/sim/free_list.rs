//! The free list of each kind's slot range (paper section 5: "a list with the values to
//! indicate available positions for individuals creation"), rebuilt after every step by
//! stream compaction so that it needs neither atomics nor a sequential scan:
//!
//! 1. [`mark_free`]: `flags[i]` = 1 where slot `i` is a usable slot without a live body, a
//!    tile of [`TILE`] slots a thread, which also writes its tile's count: the first pass of
//!    the prefix sum;
//! 2. the host's prefix sum of the flags goes on from those tile sums;
//! 3. [`gather_free`]: each free slot writes itself into its range's list at its rank, and
//!    the last slot of each range writes the range's count.
//!
//! Lists come out in increasing slot order; the master thread takes slots from the front.

use super::bodies::Bodies;
use super::kinds::SlotRange;
use crate::primitives::scan::{TILE, tiles};
use crate::{DevSlice, KernelArgs, Thread};

/// Each kind's free slots, as the free-list rebuild leaves them.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct FreeSlots {
    /// Kind `k`'s free slots in order, from its range's start.
    pub list: DevSlice<u32>,
    /// Free slots per kind.
    pub count: DevSlice<u32>,
}

/// Arguments of [`mark_free`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct MarkArgs {
    /// The bodies (kinds and liveness are read).
    pub bodies: Bodies,
    /// Slot range of each kind.
    pub ranges: DevSlice<SlotRange>,
    /// Output: 1 for a free usable slot, else 0; one per slot.
    pub flags: DevSlice<u32>,
    /// Output: the number of free usable slots in each tile of [`TILE`] slots (the first
    /// level of the flags' prefix sum, `tiles(slots)` elements; empty for a single tile).
    pub tile_counts: DevSlice<u32>,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for MarkArgs {}

/// Whether `slot`, of kind `range`, is usable (not padding).
#[inline(always)]
fn usable(slot: u32, range: SlotRange) -> bool {
    slot >= range.start && slot < range.end()
}

/// Thread `t` writes the flags of tile `t` (slots `t·TILE ..`) and their count. Ranges
/// start at multiples of 32 slots and own the padding up to the next one, and a world's slots
/// are a multiple of 32, so a tile is whole and lies in one kind's range.
#[inline(always)]
pub fn mark_free(t: Thread, args: &MarkArgs) {
    let tile = t.global();
    if tile >= tiles(args.flags.len()) {
        return;
    }
    let start = tile * TILE;
    let b = &args.bodies;
    let range = args.ranges.get(b.kind.get(start));
    let alive: [u32; TILE as usize] = b.alive.get_run(start);
    let mut count = 0u32;
    let flags: [u32; TILE as usize] = core::array::from_fn(|i| {
        let slot = start + i as u32;
        let free = usable(slot, range) && alive[i] == 0;
        count += free as u32;
        free as u32
    });
    args.flags.set_run(start, flags);
    // A world of one tile needs no sums.
    if !args.tile_counts.is_empty() {
        args.tile_counts.set(tile, count);
    }
}

/// Arguments of [`gather_free`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
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
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for GatherArgs {}

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
