//! The broad phase (paper 6.1): a uniform grid rebuilt every step. The same grid answers the
//! narrow phase's "who is near me" and the enemies' vision.
//!
//! The grid is bucketed by (kind, cell): bucket `kind · cells + cell` holds the live bodies of
//! that kind in that cell, in increasing slot order, so that a query reads only the kinds it
//! cares about (an enemy's contacts are with the ship and the shots, not with the thousands
//! of enemies around it). Kinds own contiguous slot ranges in kind order, so reading a cell's
//! buckets in kind order visits its bodies in plain slot order. Buckets are kind-major, so
//! the cells of one row of a query's 3×3 block are one run of entries per kind.
//!
//! Build, with no sort and work that grows with the live bodies:
//! 1. [`count_cells`]: each live body adds itself to its bucket's count with an atomic add,
//!    which hands out ranks in whatever order threads arrive (the counts do not depend on it);
//! 2. the exclusive prefix sum of the counts: each bucket's first entry;
//! 3. [`place_in_cells`]: each body writes its slot at its bucket's start plus its rank, a
//!    scheduling-dependent order inside the bucket (in a small bucket, with its rank and the
//!    bucket's size beside it), and the counts go back to zero for the next build (so no
//!    clear runs between the step's launches);
//! 4. [`order_cells`]: each entry counts the smaller slots in its bucket and moves its slot to
//!    that rank, which makes every bucket canonical (increasing slots) before anything reads
//!    it.
//!
//! Query: [`CellIndex::for_each_near`].

use glam::Vec2;

use super::bodies::Bodies;
use super::space::{Space, Span};
use crate::access::{Read, Readable};
use crate::exec::follow_previous_launch;
use crate::warp::{Handed, Team};
use crate::{DevSlice, Thread, asked, device_data, kernel_args};

device_data! {
    /// The grid's arrays: what the broad phase builds each step and [`CellIndex`] queries.
    pub struct Grid(slots, buckets, moving, traced, kind_rows): GridAccess {
        /// Each slot's bucket, or [`NO_BUCKET`].
        keys: [u32; slots],
        /// Each slot's arrival rank in its bucket; the merge passes' runs afterwards.
        ranks: [u32; slots],
        /// Bodies per bucket while the grid is built, zero between builds; one more element
        /// (always zero) for the total.
        counts: [u32; buckets],
        /// Each bucket's first entry (the counts' exclusive prefix sums); the last element is
        /// the number of entries.
        start: [u32; buckets],
        /// Slots by bucket, in arrival order (with their places in small buckets: see
        /// [`place_in_cells`]); the merge passes' runs afterwards.
        unordered: [u32; slots],
        /// Slots by bucket, in slot order.
        slots: [u32; slots],
        /// Each entry's position.
        pos: [Vec2; slots],
        /// Each entry's velocity, in worlds whose bodies move in the launch that queries
        /// the grid (`moving` = slots; else none): see [`CellIndex::vel`].
        vel: [Vec2; moving],
        /// Each entry's last path's start ([`Bodies::prev`]), in worlds that trace paths and
        /// whose bodies move in the launch that queries the grid (`traced` = slots; else
        /// none): see [`CellIndex::prev_at`].
        prev: [Vec2; traced],
        /// Each kind's first and last row holding one of its bodies (`2k`, `2k + 1`), where
        /// it has any (`kind_rows` = twice the kinds; see [`CellIndex::rows`]).
        rows: [u32; kind_rows],
    }
}

/// The key of a slot without a live body: in no bucket.
pub const NO_BUCKET: u32 = u32::MAX;

kernel_args! {
    /// Arguments of [`count_cells`].
    pub struct CountArgs {
        /// The bodies (positions, kinds and liveness are read).
        pub bodies: Bodies,
        /// The world and its grid.
        pub space: Space,
        /// Output: each slot's bucket, or [`NO_BUCKET`].
        pub keys: DevSlice<u32>,
        /// Output: each live slot's arrival rank inside its bucket.
        pub ranks: DevSlice<u32>,
        /// Bodies per bucket, zero before (as [`place_in_cells`] leaves them); `kinds ·
        /// cells` buckets.
        pub counts: DevSlice<u32>,
    }
}

/// Thread `i` keys slot `i` by its bucket and counts it there.
#[inline(always)]
pub fn count_cells(t: Thread, args: &CountArgs) {
    let b = &args.bodies;
    let slot = t.global();
    if slot >= args.keys.len() {
        return;
    }
    // Asked for at once, before the branch: the thread waits for memory once.
    let [alive, kind] = asked([b.alive.get(slot), b.kind.get(slot)]);
    let pos = asked(b.pos.get(slot));
    count_slot(args, slot, (alive != 0, kind, pos));
}

/// [`count_cells`]' work for slot `slot` (below the keys' length), whose body is `alive`, of
/// kind `kind` at `pos` (as read, or as just born).
#[inline(always)]
pub fn count_slot(args: &CountArgs, slot: u32, (alive, kind, pos): (bool, u32, Vec2)) {
    if !alive {
        args.keys.set(slot, NO_BUCKET);
        return;
    }
    let key = kind * args.space.cells() + args.space.cell_of(pos);
    args.keys.set(slot, key);
    args.ranks.set(slot, args.counts.atomic_add(key, 1));
}

kernel_args! {
    /// Arguments of [`place_in_cells`].
    pub struct PlaceArgs {
        /// Each slot's bucket (from [`count_cells`]).
        pub keys: DevSlice<u32>,
        /// Each live slot's rank inside its bucket (from [`count_cells`]).
        pub ranks: DevSlice<u32>,
        /// Each bucket's first entry: the exclusive prefix sums of the counts.
        pub start: DevSlice<u32>,
        /// Output: the slots grouped by bucket, in arrival order inside a bucket, each with
        /// its place in a small bucket (see [`place_in_cells`]).
        pub unordered: DevSlice<u32>,
        /// The counts that were scanned into `start`: set back to zero.
        pub counts: DevSlice<u32>,
        /// Output: each kind's first and last row holding one of its bodies (see
        /// [`CellIndex::rows`]).
        pub rows: DevSlice<u32>,
        /// The world's grid (its rows and columns).
        pub space: Space,
    }
}

/// The bits of an arrival-ordered entry that hold its slot (slots are below 2²⁴).
const SLOT_BITS: u32 = 24;

/// The bits of an arrival-ordered entry that hold its rank, and then its bucket's size,
/// above its slot (see [`placed`]).
const PLACE_BITS: u32 = 4;

/// The largest bucket whose entries carry their place in it (see [`placed`]).
const SMALL_BUCKET: u32 = (1 << PLACE_BITS) - 1;

/// Slot `slot`'s arrival-ordered entry, with its `rank` in a bucket of `size` entries
/// where the bucket has at most [`SMALL_BUCKET`] (size in the top four bits, rank in the
/// four below them; a size of 0 says the bucket is larger): so that the ordering finds its
/// bucket's entries without first waiting for the slot's key and the bucket's bounds.
#[inline(always)]
fn placed(slot: u32, rank: u32, size: u32) -> u32 {
    match size <= SMALL_BUCKET {
        true => slot | rank << SLOT_BITS | size << (SLOT_BITS + PLACE_BITS),
        false => slot,
    }
}

/// The slot of an arrival-ordered entry (see [`placed`]).
#[inline(always)]
fn slot_of(entry: u32) -> u32 {
    entry & ((1 << SLOT_BITS) - 1)
}

/// Thread `i` writes slot `i` into its bucket: each entry has exactly one writer, since the
/// ranks of a bucket are distinct. In a bucket of at most `SMALL_BUCKET` entries the entry
/// also holds the bucket's size and its rank in the bits above the slot (see `placed`),
/// so that [`order_cells`] finds the bucket's entries without waiting for the key. The
/// thread of a bucket's first arrival writes the bucket's row as its kind's first or last
/// row with a body (see [`CellIndex::rows`]) where the bucket is its kind's first or last
/// that is not empty: one writer each. The threads also zero the counts, every
/// `threads`-th bucket each, for the next build: nothing in this launch reads them.
#[inline(always)]
pub fn place_in_cells(t: Thread, args: &PlaceArgs) {
    let slot = t.global();
    let threads = t.block_dim * t.grid_dim;
    // The keys and ranks are the count's, which the scan's launches separate from this one
    // (at least one more than the launch before): read before the wait (see
    // `follow_previous_launch`), with the rank beside the key (a dead slot's is stale, and
    // unused). After the wait only the bucket's start is waited for.
    let [key, rank] = match slot < args.keys.len() {
        true => asked([args.keys.get(slot), args.ranks.get(slot)]),
        false => [NO_BUCKET, 0],
    };
    follow_previous_launch();
    let mut bucket = slot;
    while bucket < args.counts.len() {
        args.counts.set(bucket, 0);
        bucket += threads;
    }
    if key == NO_BUCKET {
        return;
    }
    let [first, end] = asked([args.start.get(key), args.start.get(key + 1)]);
    args.unordered
        .set(first + rank, placed(slot, rank, end - first));
    if rank == 0 {
        let cells = args.space.cells();
        let kind = key / cells;
        let row = key % cells / args.space.cols;
        let [kind_first, kind_end] = asked([
            args.start.get(kind * cells),
            args.start.get((kind + 1) * cells),
        ]);
        if first == kind_first {
            args.rows.set(2 * kind, row);
        }
        if end == kind_end {
            args.rows.set(2 * kind + 1, row);
        }
    }
}

kernel_args! {
    /// Arguments of [`order_cells`].
    pub struct OrderArgs {
        /// The bodies' positions.
        pub pos: DevSlice<Vec2>,
        /// The bodies' velocities (read only where `entry_vel` is not empty).
        pub vel: DevSlice<Vec2>,
        /// The bodies' last paths' starts (read only where `entry_prev` is not empty).
        pub prev: DevSlice<Vec2>,
        /// Each slot's bucket.
        pub keys: DevSlice<u32>,
        /// Each bucket's first entry; the last element is the number of live bodies.
        pub start: DevSlice<u32>,
        /// The slots of each bucket in arrival order (from [`place_in_cells`]).
        pub unordered: DevSlice<u32>,
        /// Output: the same slots in increasing order inside each bucket.
        pub slots: DevSlice<u32>,
        /// Output: each entry's position, so that a query reads its neighbours' places in a
        /// row instead of one scattered load per neighbour.
        pub entry_pos: DevSlice<Vec2>,
        /// Output: each entry's velocity, or empty (see [`CellIndex::vel`]).
        pub entry_vel: DevSlice<Vec2>,
        /// Output: each entry's last path's start, or empty (see [`CellIndex::prev`]).
        pub entry_prev: DevSlice<Vec2>,
        /// Output when `bounded`: the entries of buckets larger than [`RUN`], each run of
        /// [`RUN`] entries in slot order, for [`merge_runs`] to merge.
        pub runs: DevSlice<u32>,
        /// Non-zero: buckets larger than [`RUN`] are ordered run by run (then merged), so that
        /// a crowded cell costs `O(n log n)`, not `O(n²)`.
        pub bounded: u32,
        /// Keeps the struct free of implicit padding.
        pub reserved: u32,
    }
}

/// Entries of a bucket [`order_cells`] orders by counting when the order is bounded; larger
/// buckets are ordered in runs of this many and merged by [`merge_runs`].
pub const RUN: u32 = 64;

/// In the merge buffers: an entry whose bucket is already in the grid's slots, so that
/// later passes skip it at the cost of one load (slots are below 2²⁴).
pub const DONE: u32 = u32::MAX;

/// Thread `j` takes entry `j`: its slot's rank among its bucket's slots is the number of
/// smaller slots there, and it moves there. The ranks of a bucket are a permutation (slots
/// are distinct), so each output entry has one writer, whatever order the entries arrived in.
/// An entry of a small bucket carries its place in it (see [`place_in_cells`]); only a larger
/// bucket's entries wait for their slot's key, then their bucket's bounds.
#[inline(always)]
pub fn order_cells(t: Thread, args: &OrderArgs) {
    let j = t.global();
    if j >= args.unordered.len() {
        return;
    }
    // Each wait asks for all it can: the entry with the count of entries (past it, a stale
    // entry, unused), then its slot's place (and a large bucket's bounds).
    let [live, entry] = asked([args.start.get(args.start.len() - 1), args.unordered.get(j)]);
    if j >= live {
        return;
    }
    let slot = slot_of(entry);
    let pos = asked(args.pos.get(slot));
    let keeps_vel = !args.entry_vel.is_empty();
    let vel = asked(if keeps_vel {
        args.vel.get(slot)
    } else {
        Vec2::ZERO
    });
    let keeps_prev = !args.entry_prev.is_empty();
    let prev = asked(if keeps_prev {
        args.prev.get(slot)
    } else {
        Vec2::ZERO
    });
    let size = entry >> (SLOT_BITS + PLACE_BITS);
    let [first, end] = if size != 0 {
        let first = j - (entry >> SLOT_BITS & SMALL_BUCKET);
        [first, first + size]
    } else {
        let key = args.keys.get(slot);
        asked([args.start.get(key), args.start.get(key + 1)])
    };
    if args.bounded != 0 {
        if end - first > RUN {
            // A large bucket: order this entry's run only.
            let run = first + (j - first) / RUN * RUN;
            let mut rank = 0;
            args.unordered
                .for_each_in::<4>(run, end.min(run + RUN), |_, other| {
                    rank += u32::from(slot_of(other) < slot);
                });
            args.runs.set(run + rank, slot);
            return;
        }
        args.runs.set(j, DONE);
    }
    let mut rank = 0;
    args.unordered.for_each_in::<4>(first, end, |_, other| {
        rank += u32::from(slot_of(other) < slot);
    });
    args.slots.set(first + rank, slot);
    args.entry_pos.set(first + rank, pos);
    if keeps_vel {
        args.entry_vel.set(first + rank, vel);
    }
    if keeps_prev {
        args.entry_prev.set(first + rank, prev);
    }
}

kernel_args! {
    /// Arguments of [`merge_runs`].
    pub struct MergeArgs {
        /// The bodies' positions.
        pub pos: DevSlice<Vec2>,
        /// The bodies' velocities (read only where `entry_vel` is not empty).
        pub vel: DevSlice<Vec2>,
        /// The bodies' last paths' starts (read only where `entry_prev` is not empty).
        pub prev: DevSlice<Vec2>,
        /// Each bucket's first entry; the last element is the number of live bodies.
        pub start: DevSlice<u32>,
        /// The large buckets' entries, in sorted runs of `run`.
        pub src: DevSlice<u32>,
        /// Output: the same, in sorted runs of `2 · run`, and [`DONE`] for the entries of
        /// buckets that are finished.
        pub dst: DevSlice<u32>,
        /// Output: the grid's slots, for the buckets this pass finishes.
        pub slots: DevSlice<u32>,
        /// Output: the grid's entry positions, likewise.
        pub entry_pos: DevSlice<Vec2>,
        /// Output: each entry's velocity, or empty (see [`CellIndex::vel`]).
        pub entry_vel: DevSlice<Vec2>,
        /// Output: each entry's last path's start, or empty (see [`CellIndex::prev`]).
        pub entry_prev: DevSlice<Vec2>,
        /// Length of the sorted runs in `src`.
        pub run: u32,
        /// Keeps the struct free of implicit padding.
        pub reserved: u32,
    }
}

/// The bucket holding entry `j`: the last bucket whose first entry is at most `j` (empty
/// buckets share their first entry with the next).
#[inline(always)]
fn bucket_of(start: &DevSlice<u32>, j: u32) -> u32 {
    let (mut low, mut high) = (0, start.len() - 1);
    // Invariant: start[low] <= j < start[high].
    while high - low > 1 {
        let mid = low + (high - low) / 2;
        if start.get(mid) <= j {
            low = mid;
        } else {
            high = mid;
        }
    }
    low
}

/// Thread `j` takes entry `j` of a bucket larger than `run`: it finds its value's rank in
/// the partner run by binary search, and so its place in the merged run of `2 · run`. A
/// bucket this pass finishes goes to the grid's slots, with positions, and is marked
/// [`DONE`] for the next pass; finished entries pass their mark on. Slots are distinct, so
/// each output has one writer.
#[inline(always)]
pub fn merge_runs(t: Thread, args: &MergeArgs) {
    let j = t.global();
    let live = args.start.get(args.start.len() - 1);
    if j >= live {
        return;
    }
    let x = args.src.get(j);
    if x == DONE {
        args.dst.set(j, DONE);
        return;
    }
    let bucket = bucket_of(&args.start, j);
    let (first, end) = (args.start.get(bucket), args.start.get(bucket + 1));
    let run = args.run;
    let i = j - first;
    let r = i / run;
    // The partner run (possibly short or empty at the bucket's end).
    let other = first + (r ^ 1) * run;
    let (mut low, mut high) = (other.min(end), (other + run).min(end));
    while low < high {
        let mid = low + (high - low) / 2;
        if args.src.get(mid) < x {
            low = mid + 1;
        } else {
            high = mid;
        }
    }
    let rank = low - other.min(end);
    let at = first + (r & !1) * run + (i - r * run) + rank;
    if end - first <= 2 * run {
        args.slots.set(at, x);
        args.entry_pos.set(at, args.pos.get(x));
        if !args.entry_vel.is_empty() {
            args.entry_vel.set(at, args.vel.get(x));
        }
        if !args.entry_prev.is_empty() {
            args.entry_prev.set(at, args.prev.get(x));
        }
        args.dst.set(at, DONE);
    } else {
        args.dst.set(at, x);
    }
}

/// The grid: the live slots bucketed by (kind, cell), each bucket in increasing slot order.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct CellIndex {
    /// Slots by bucket, then by slot.
    pub slots: DevSlice<u32, Read>,
    /// The position of each entry's body when the grid was built: inside its bucket's
    /// cell.
    pub pos: DevSlice<Vec2, Read>,
    /// The velocity of each entry's body when the grid was built, in worlds whose bodies
    /// move in the launch that queries the grid (whose own velocities then change under the
    /// queries); empty elsewhere, where the bodies' own are read (see [`CellIndex::vel_at`]).
    pub vel: DevSlice<Vec2, Read>,
    /// Where each entry's body was when its last (sub)step moved it ([`Bodies::prev`]), in
    /// worlds that trace paths and whose bodies move in the launch that queries the grid;
    /// empty elsewhere, where the bodies' own are read (see [`CellIndex::prev_at`]).
    pub prev: DevSlice<Vec2, Read>,
    /// First entry of each bucket in `slots`, and one more element: the number of entries.
    /// Bucket `b` is `slots[start[b] .. start[b + 1]]`.
    pub start: DevSlice<u32, Read>,
    /// Each kind's first and last row holding one of its bodies (elements `2k` and
    /// `2k + 1`), as the grid's ordering wrote them: meaningful only for a kind with
    /// entries.
    pub rows: DevSlice<u32, Read>,
    /// Number of kinds.
    pub kinds: u32,
    /// Number of cells (buckets per kind).
    pub cells: u32,
    /// The most entries one query examines (its own body included), in its visiting order;
    /// 0 for no limit. A cap bounds the cost of a crowded cell at the price of contacts and
    /// sightings missed past it.
    pub cap: u32,
    /// Keeps the struct free of implicit padding.
    pub reserved: u32,
}

/// What a neighbour query looks for: the bodies of the kinds in `mask` (bit `k`: kind `k`)
/// in the 3×3 cells around `pos`, or only in those that can hold a body within `reach` of
/// it along each axis if given (see [`Space::neighbourhood_within`]).
#[derive(Clone, Copy, Debug)]
pub struct Near {
    /// Where the query looks from.
    pub pos: Vec2,
    /// How far along either axis a body it wants can be; `None` for the whole block.
    pub reach: Option<f32>,
    /// The kinds it wants.
    pub mask: u32,
}

/// How much of a crowd a query takes (an enemy's look, a body's contacts): of each run of
/// cells it reads (a row of its 3×3 block, one kind; two runs where the block wraps around
/// the field's edge), at most `⌈budget / 3⌉` entries (0: all), evenly: a run of `n` entries
/// gets a stride of `⌈n / ⌈budget / 3⌉⌉`, the query takes every stride-th entry from
/// `phase` (modulo the stride) on, and hands each with the stride as its weight, so that
/// sums weighted by it estimate the whole run's. A query so takes at most `budget` entries
/// of a kind (twice that where the block wraps), decided from the bounds of each run, which
/// it loads anyway; where no run exceeds its share it is the plain query, bit for bit. It
/// depends on the grid and the phase alone, so it is deterministic.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// The most entries of one kind taken from the block's three rows; 0 for all.
    pub budget: u32,
    /// Which entries of a stride are taken (bodies that look from the same block with
    /// different phases see different shares of the crowd).
    pub phase: u32,
}

impl Sample {
    /// Every entry, each of weight 1: the plain query.
    pub const ALL: Sample = Sample {
        budget: 0,
        phase: 0,
    };

    /// The stride and the first entry taken of a run of `len` entries: `(1, 0)` within its
    /// share, `⌈budget / 3⌉` entries.
    #[inline(always)]
    fn of_run(&self, len: u32) -> (u32, u32) {
        let share = self.budget.div_ceil(3);
        if self.budget == 0 || len <= share {
            return (1, 0);
        }
        let every = len.div_ceil(share);
        (every, self.phase % every)
    }
}

impl CellIndex {
    /// The velocity, when the grid was built, of the body at entry `entry` (slot `slot`):
    /// with `MOVING` (bodies move in the launch that queries), the grid's copy, else the
    /// body's own, `vel[slot]`, which has not changed since.
    #[inline(always)]
    pub fn vel_at<const MOVING: bool>(
        &self,
        entry: u32,
        slot: u32,
        vel: &DevSlice<Vec2, impl Readable>,
    ) -> Vec2 {
        if MOVING {
            self.vel.get(entry)
        } else {
            vel.get(slot)
        }
    }

    /// Where the body at entry `entry` (slot `slot`) was when its last (sub)step moved it:
    /// with `MOVING`, the grid's copy, else the body's own, `prev[slot]`, which has not
    /// changed since the grid was built.
    #[inline(always)]
    pub fn prev_at<const MOVING: bool>(
        &self,
        entry: u32,
        slot: u32,
        prev: &DevSlice<Vec2, impl Readable>,
    ) -> Vec2 {
        if MOVING {
            self.prev.get(entry)
        } else {
            prev.get(slot)
        }
    }

    /// Calls `visit(slot, kind, position, entry)` for every body `near` asks for, with its
    /// position when the grid was built and the index of its entry. Each body once, in a
    /// fixed order: kind by kind in increasing order, then row by row of the block, each
    /// row's cells from left to right (as the block wraps), by increasing slot inside a
    /// cell. Since buckets are kind-major, the cells of a row that are neighbours
    /// in the grid too are one run of entries: three runs per kind, not nine. With a
    /// [`CellIndex::cap`], the query stops after that many entries, and reads the whole
    /// block whatever the reach, so that a cap counts the same entries at every reach.
    #[inline(always)]
    pub fn for_each_near(
        &self,
        space: &Space,
        near: Near,
        mut visit: impl FnMut(u32, u32, Vec2, u32),
    ) {
        self.for_each_taken(space, (near, Sample::ALL), |_, slot, kind, at, entry| {
            visit(slot, kind, at, entry)
        });
    }

    /// [`CellIndex::for_each_near`] under `sample`: `visit(weight, slot, kind, position,
    /// entry)` for every entry the sample takes, with its run's stride as the weight, one
    /// thread walking them all.
    #[inline(always)]
    fn for_each_taken(
        &self,
        space: &Space,
        (near, sample): (Near, Sample),
        mut visit: impl FnMut(u32, u32, u32, Vec2, u32),
    ) {
        self.for_each_run(space, (near, true), |kind, start, end| {
            let (every, skip) = sample.of_run(end - start);
            // Each entry is asked for while the one before is visited. (Bounds checked an
            // entry: the contacts' runs are short, and a run's views cost the narrow phase
            // more registers than their checks save, 730 -> 762 µs at 16.76M on an H200.)
            let mut entry = start + skip;
            let mut ahead = self.entry(entry, end);
            while entry < end {
                let (slot, at) = ahead;
                ahead = self.entry(entry + every, end);
                visit(every, slot, kind, at, entry);
                entry += every;
            }
        });
    }

    /// Whether a body of a kind of `mask` lies in a row of the whole 3×3 block around `pos`:
    /// where none does (an enemy far from the ship and its shots), a query reads nothing and
    /// needs no block.
    #[inline(always)]
    fn any_around(&self, space: &Space, pos: Vec2, mask: u32) -> bool {
        let around = space.neighbourhood(pos).0;
        let mut rest = mask;
        let mut any = false;
        while rest != 0 {
            let kind = rest.trailing_zeros();
            rest &= rest - 1;
            if let Some((low, high)) = self.rows_of(kind) {
                any |= (0..around.count).any(|k| (low..=high).contains(&around.at(k)));
            }
        }
        any
    }

    /// The first and the last row that hold a body of `kind`, if any does (see
    /// [`CellIndex::rows`]), in one wait for memory. The same for every query, so a warp's
    /// lanes load them together; a kind of few bodies close together (the ship, its shots)
    /// so costs the queries far from them one test a row, not the loads of the row's
    /// bounds.
    #[inline(always)]
    fn rows_of(&self, kind: u32) -> Option<(u32, u32)> {
        let [first, end, low, high] = asked([
            self.start.get(kind * self.cells),
            self.start.get((kind + 1) * self.cells),
            self.rows.get(2 * kind),
            self.rows.get(2 * kind + 1),
        ]);
        (first < end).then_some((low, high))
    }

    /// The block a query reads: the whole 3×3 block without a reach or under a cap.
    #[inline(always)]
    fn block(&self, space: &Space, near: Near) -> NearBlock {
        let (rows, cols) = match near.reach {
            Some(reach) if self.cap == 0 => space.neighbourhood_within(near.pos, reach),
            _ => space.neighbourhood(near.pos),
        };
        NearBlock { rows, cols }
    }

    /// Entry `entry`'s slot and position, or the last entry's past `end` (`0 < end`, and
    /// entries `.. end` lie in the grid), asked for now (see [`Run::ahead`]).
    #[inline(always)]
    fn entry(&self, entry: u32, end: u32) -> (u32, Vec2) {
        let at = entry.min(end - 1);
        (asked(self.slots.get(at)), asked(self.pos.get(at)))
    }

    /// Entries `start .. end` (`start < end`) of a one-thread walk of the looks, their
    /// bounds checked once for the run rather than once an entry: a look's runs are long.
    #[inline(always)]
    fn run(&self, start: u32, end: u32) -> Run {
        Run {
            start,
            pos: self.pos.range(start, end - start),
        }
    }

    /// [`CellIndex::for_each_near`] under `sample` (see [`Sample`]) shared by a `team` of
    /// lanes: the lanes load the bounds of the runs of entries side by side, each lane
    /// `test`s every team-width-th entry the sample takes of a run (`Some` for the bodies
    /// that count), and every lane `fold`s the results, each with its run's stride as the
    /// weight, in the order of the one-thread query, so the fold ends the same bit for bit
    /// as one thread walking the sample with `test` and `fold` in one closure would. Every
    /// lane of the team must call it with the same `near` and `sample`.
    #[inline(always)]
    pub fn for_each_near_in<R: Handed + Default>(
        &self,
        team: Team,
        space: &Space,
        (near, sample): (Near, Sample),
        test: impl Fn(u32, u32, Vec2, u32) -> Option<R>,
        mut fold: impl FnMut(R, u32),
    ) {
        let (lane, width) = team.stride();
        if width == 1 {
            self.for_each_taken(space, (near, sample), |weight, slot, kind, at, entry| {
                if let Some(found) = test(slot, kind, at, entry) {
                    fold(found, weight);
                }
            });
            return;
        }
        self.walk_runs_in(team, space, near, |kind, start, end| {
            let (every, skip) = sample.of_run(end - start);
            let mut first = start + skip;
            while first < end {
                let entry = first + lane * every;
                let found = if entry < end {
                    test(self.slots.get(entry), kind, self.pos.get(entry), entry)
                } else {
                    None
                };
                team.fold_found(found, |found| fold(found, every));
                first += width * every;
            }
        });
    }

    /// [`CellIndex::for_each_near`] under `sample` (see [`Sample`]) shared by a `team` of
    /// lanes for a result that does not depend on the order in which the bodies come: each
    /// lane `add`s every team-width-th entry the sample takes of each run to its own value
    /// (from `init`), with the run's stride as the weight, `add(value, weight, kind,
    /// position, entry)`: the walk reads each entry's position, and leaves its slot to `add`
    /// (`slots[entry]`), which reads it only for the entries whose place does not decide
    /// (a look reads 8 bytes an entry of its own kind, not 12). The lanes' values are merged
    /// across the team (see [`Team::merge`]). Where `add` and `merge` are free of order
    /// (exact integer sums, least keys), every lane gets what one thread adding every entry
    /// taken gets, bit for bit, without handing each body found to every lane. Every lane
    /// of the team must call it with the same `near` and `sample`. On the GPU one thread
    /// walks the runs of kind `own` in a loop of their own, which hands `add` that kind as
    /// `own` itself, so that what `add` does by kind is decided once, not at each entry.
    #[inline(always)]
    pub fn merge_near_in<A: Handed>(
        &self,
        team: Team,
        space: &Space,
        (near, sample, own): (Near, Sample, u32),
        init: A,
        add: impl Fn(A, u32, u32, Vec2, u32) -> A,
        merge: impl Fn(A, A) -> A,
    ) -> A {
        let (lane, width) = team.stride();
        let mut value = init;
        if width == 1 {
            // `for_each_taken`'s walk written out: through its closure the looks of `paper`
            // took 7% longer on the CPU emulation (470 against 440 µs a step).
            self.for_each_run(space, (near, false), |kind, start, end| {
                let (every, skip) = sample.of_run(end - start);
                let run = self.run(start, end);
                let of_run = |value, weight, at, entry| add(value, weight, kind, at, entry);
                // On the GPU a run of kind `own` taken whole (every run, where there is no
                // budget) is walked with a weight known to be 1 and its kind known, so that
                // `add`'s weighted sums multiply nothing and its test of the kind folds away
                // (a third copy of `add`, for the other kinds' whole runs, was left out of
                // line). Natively the second copy of `add` made the emulated looks slower
                // (`paper` 434 -> 594 µs a step): one walk there.
                value = match every {
                    1 if cfg!(target_arch = "nvptx64") && kind == own => {
                        run.fold(start, 1, value, |value, weight, at, entry| {
                            add(value, weight, own, at, entry)
                        })
                    }
                    _ => run.fold(start + skip, every, value, of_run),
                };
            });
            return value;
        }
        // Each lane's share of a run: every team-width-th entry the sample takes.
        self.walk_runs_in(team, space, near, |kind, start, end| {
            let (every, skip) = sample.of_run(end - start);
            let mut entry = start + skip + lane * every;
            while entry < end {
                value = add(value, every, kind, self.pos.get(entry), entry);
                entry += width * every;
            }
        });
        team.merge(value, merge)
    }

    /// Hands `run(kind, start, end)` every nonempty run of entries of `near` in visiting
    /// order, cut at the cap, one after another (the one-thread walk). Where its kinds are
    /// `sparse` (the contacts': the ship and its shots), a query first asks whether any of
    /// their bodies is around ([`CellIndex::any_around`]); the looks, whose own kind is all
    /// around, skip the question (asked, `paper` lost 3% on an H200).
    #[inline(always)]
    fn for_each_run(
        &self,
        space: &Space,
        (near, sparse): (Near, bool),
        mut run: impl FnMut(u32, u32, u32),
    ) {
        let mask = near.mask & kinds_mask(self.kinds);
        if sparse && !self.any_around(space, near.pos, mask) {
            return;
        }
        let block = self.block(space, near);
        let count = block.rows.count * block.cols.runs();
        let mut rest = mask;
        // Entries the cap still allows.
        let mut left = if self.cap == 0 { u32::MAX } else { self.cap };
        while rest != 0 {
            let kind = rest.trailing_zeros();
            rest &= rest - 1;
            // Rows without a body of the kind have empty runs: not read.
            let Some((low, high)) = self.rows_of(kind) else {
                continue;
            };
            // The bounds of the kind's `j`-th run of the block.
            let bounds = |j: u32| {
                let (row, first, last) = block.run(j);
                if !(low..=high).contains(&row) {
                    return [0, 0];
                }
                let row = kind * self.cells + row * space.cols;
                asked([self.start.get(row + first), self.start.get(row + last + 1)])
            };
            // A look asks for each run's bounds before it walks the run before, so that it
            // waits for them once, not once a run (the contacts, whose runs are short and
            // whose registers are few, read them as they go: `paper` lost 1.4% on an H200).
            let ahead = !sparse;
            let mut next = if ahead { bounds(0) } else { [0, 0] };
            for j in 0..count {
                let [start, end] = if ahead { next } else { bounds(j) };
                if ahead && j + 1 < count {
                    next = bounds(j + 1);
                }
                let end = end.min(start.saturating_add(left));
                if start < end {
                    run(kind, start, end);
                }
                left -= end.saturating_sub(start);
                if left == 0 {
                    return;
                }
            }
        }
    }

    /// Hands `run(kind, start, end)` every run of entries of `near` in visiting order, cut
    /// at the cap, in every lane of `team` (wider than one lane): the lanes load the runs'
    /// bounds side by side, so the team waits for memory once for up to a team width of
    /// runs, not once a run.
    #[inline(always)]
    fn walk_runs_in(
        &self,
        team: Team,
        space: &Space,
        near: Near,
        mut run: impl FnMut(u32, u32, u32),
    ) {
        let (lane, width) = team.stride();
        let runs = self.near_runs(space, near);
        let count = runs.count();
        let mut left = if self.cap == 0 { u32::MAX } else { self.cap };
        let mut base = 0;
        while base < count {
            let (kind, start, end) = runs.get(self, space, base + lane);
            for j in 0..width.min(count - base) {
                let kind = team.share(kind, j);
                let start = team.share(start, j);
                let end = team.share(end, j).min(start.saturating_add(left));
                run(kind, start, end);
                left -= end.saturating_sub(start);
                if left == 0 {
                    return;
                }
            }
            base += width;
        }
    }

    /// The weight [`CellIndex::merge_near_in`] under `sample` gives the entry of slot
    /// `slot`, a body of kind `kind` at `near.pos` that is in the grid: its run's stride
    /// where the sample takes it, else 0. Without a cap, so that a walk may count a body
    /// among its neighbours by place alone and take itself off after (rather than read the
    /// slot of every entry at offset zero: a wait for memory a few lanes at a time). Only
    /// a run beyond its share looks for the entry (in its cell's bucket, by slot).
    #[inline(always)]
    pub fn own_weight(
        &self,
        space: &Space,
        (near, sample): (Near, Sample),
        kind: u32,
        slot: u32,
    ) -> u32 {
        if sample.budget == 0 {
            return 1;
        }
        // The block's run of columns that holds the body's own cell, in its own row.
        let cols = self.block(space, near).cols;
        let (col, row) = space.cell_coords(near.pos);
        let (first, last) = match cols.run(0) {
            (first, last) if (first..=last).contains(&col) => (first, last),
            _ => cols.run(1),
        };
        let base = kind * self.cells + row * space.cols;
        let [start, end] = asked([
            self.start.get(base + first),
            self.start.get(base + last + 1),
        ]);
        let (every, skip) = sample.of_run(end - start);
        if every == 1 {
            return 1;
        }
        let [mut low, mut high] =
            asked([self.start.get(base + col), self.start.get(base + col + 1)]);
        // A bucket is in increasing slot order.
        while low < high {
            let mid = low + (high - low) / 2;
            match self.slots.get(mid) {
                s if s < slot => low = mid + 1,
                s if s > slot => high = mid,
                _ => {
                    return if (mid - start) % every == skip {
                        every
                    } else {
                        0
                    };
                }
            }
        }
        0
    }

    /// The runs of entries that [`CellIndex::for_each_near`] visits for `near`, to be taken
    /// by index (a warp's lanes take one each). The cap is not applied: the caller counts
    /// entries against [`CellIndex::cap`] in visiting order.
    #[inline(always)]
    pub fn near_runs(&self, space: &Space, near: Near) -> NearRuns {
        let mask = near.mask & kinds_mask(self.kinds);
        NearRuns {
            block: self.block(space, near),
            mask,
            kinds: mask.count_ones(),
        }
    }
}

/// A run of a grid's entries that one thread's look walks (see [`CellIndex::merge_near_in`]).
#[derive(Clone, Copy)]
struct Run {
    /// The first entry's index in the grid.
    start: u32,
    /// The run's positions.
    pos: DevSlice<Vec2, Read>,
}

impl Run {
    /// Entry `entry`'s position, or the run's last entry's past its end, asked for now (see
    /// [`asked`]): the one-thread walk reads one entry ahead of the one it visits, so that
    /// it waits for the entries' memory about once, not once an entry. (Teams of lanes
    /// gained nothing from it: `paper` −1.5% on an H200.)
    #[inline(always)]
    fn ahead(&self, entry: u32) -> Vec2 {
        asked(self.pos.get((entry - self.start).min(self.pos.len() - 1)))
    }

    /// `add(value, every, position, entry)` over every `every`-th entry from `first` on, in
    /// order, each entry asked for while the one before is visited.
    #[inline(always)]
    fn fold<A>(&self, first: u32, every: u32, init: A, add: impl Fn(A, u32, Vec2, u32) -> A) -> A {
        let end = self.start + self.pos.len();
        let mut value = init;
        let mut entry = first;
        let mut ahead = self.ahead(entry);
        while entry < end {
            let at = ahead;
            ahead = self.ahead(entry + every);
            value = add(value, every, at, entry);
            entry += every;
        }
        value
    }
}

/// The rows of a query's block, and its columns (taken as runs of consecutive columns),
/// in visiting order.
#[derive(Clone, Copy, Debug)]
pub struct NearBlock {
    rows: Span,
    cols: Span,
}

impl NearBlock {
    /// The row, first and last column of the block's `j`-th run, row by row, run by run
    /// (`j` below the rows times the columns' runs).
    #[inline(always)]
    fn run(&self, j: u32) -> (u32, u32, u32) {
        // Columns wrap into a second run only on a torus: one run a row, without dividing.
        let (k, r) = match self.cols.runs() {
            1 => (j, 0),
            _ => (j / 2, j % 2),
        };
        let (first, last) = self.cols.run(r);
        (self.rows.at(k), first, last)
    }
}

/// The runs of one query of the grid in visiting order: kind by kind, row by row, run by
/// run (see [`CellIndex::near_runs`]).
#[derive(Clone, Copy, Debug)]
pub struct NearRuns {
    block: NearBlock,
    mask: u32,
    kinds: u32,
}

impl NearRuns {
    /// Number of runs.
    #[inline(always)]
    pub fn count(&self) -> u32 {
        self.kinds * self.block.rows.count * self.block.cols.runs()
    }

    /// Run `r`'s kind and entries `start .. end` of `grid`; `(0, 0, 0)` past the last run.
    #[inline(always)]
    pub fn get(&self, grid: &CellIndex, space: &Space, r: u32) -> (u32, u32, u32) {
        if r >= self.count() {
            return (0, 0, 0);
        }
        let runs = self.block.cols.runs();
        let per_kind = self.block.rows.count * runs;
        // The kind: the (r / per_kind)-th kind of the mask.
        let mut rest = self.mask;
        for _ in 0..r / per_kind {
            rest &= rest - 1;
        }
        let kind = rest.trailing_zeros();
        let (row, first, last) = self.block.run(r % per_kind);
        let row = kind * grid.cells + row * space.cols;
        (
            kind,
            grid.start.get(row + first),
            grid.start.get(row + last + 1),
        )
    }
}

/// The mask bit of kind `kind` (none past the 32 kinds a mask can hold).
#[inline(always)]
pub fn kind_bit(kind: u32) -> u32 {
    1u32.checked_shl(kind).unwrap_or(0)
}

/// The mask of every kind of a world with `kinds` kinds.
#[inline(always)]
pub fn kinds_mask(kinds: u32) -> u32 {
    if kinds >= u32::BITS {
        u32::MAX
    } else {
        (1u32 << kinds) - 1
    }
}
