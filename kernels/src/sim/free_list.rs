//! The free list of each kind's slot range (paper section 5: "a list with the values to
//! indicate available positions for individuals creation"), rebuilt after every step by
//! stream compaction so that it needs neither atomics nor a sequential scan:
//!
//! 1. [`mark_free`]: `flags[i]` has [`FREE`] where slot `i` is a usable slot without a live
//!    body, and each warp's count of its 32 slots' free ones (a tile: ranges are aligned to
//!    warps);
//! 2. the exclusive prefix sum of the tiles' counts, 32 times shorter than the slots;
//! 3. [`gather_free`]: each free slot writes itself into its range's list at its rank (its
//!    tile's offset and the free slots before it in the tile, a warp scan), and the last slot
//!    of each range writes the range's count.
//!
//! Lists come out in increasing slot order; the master thread takes slots from the front.
//! Each free slot's flag also holds its rank in its list ([`free_rank`]), so that a slot
//! can tell by itself whether the births ordered from the front of its list take it.
//!
//! Where every range is small ([`ONE_LAUNCH_RANGE`]), [`mark_and_gather_free`] does all three
//! in one launch: each warp counts the free slots of its range before it itself.
//!
//! In a game's step a kind whose bodies neither died nor were born keeps its list, flags
//! and tile counts as the last rebuild left them ([`Changes`]): its warps return at once,
//! and the scan adds up the counts they kept. A million enemies that seldom die then cost
//! the launches and the scan, not a pass over every slot.
//!
//! In a game's step where the integrator's launch is the step's last to bring bodies to life
//! or death, it marks the slots whose freedom it changed itself ([`Marks::note`]), with an
//! atomic add of each change to its tile's count and to the sum of the tiles' counts a
//! thousand at a time ([`FreeMarks::sums`], the scan's first level, which a whole rebuild
//! writes): the step's rebuild is then the scan's last launch
//! ([`crate::primitives::scan::scan_tiles_after_sums`]) and [`gather_free`] alone.

use super::bodies::{Bodies, BodiesAccess};
use super::kinds::SlotRange;
use crate::access::{Read, Unused};
use crate::data::View;
use crate::exec::follow_previous_launch;
use crate::primitives::scan::{self, TILE};
use crate::warp::{self, WARP};
use crate::{DevSlice, Thread, access, asked, device_data, kernel_args};

device_data! {
    /// Each kind's free slots, as the free-list rebuild leaves them.
    pub struct FreeSlots(slots, kinds): FreeSlotsAccess {
        /// Kind `k`'s free slots in order, from its range's start.
        list: [u32; slots],
        /// Free slots per kind.
        count: [u32; kinds],
    }
}

device_data! {
    /// The rebuild's own arrays, remade every step for the kinds that changed.
    pub struct FreeMarks(slots, tiles, groups): FreeMarksAccess {
        /// [`FREE`] for a free usable slot, with its rank in its kind's list above
        /// [`RANK_SHIFT`]; else 0 (written by [`mark_free`], the ranks by [`gather_free`]).
        flags: [u32; slots],
        /// The free slots of each tile of 32 slots, and a last element, 0, for the total
        /// (see [`FreeMarks::tiles_for`]).
        tiles: [u32; tiles],
        /// The exclusive prefix sums of the tiles' counts, and their total.
        offsets: [u32; tiles],
        /// The wrapping sum of each [`TILE`] tiles' counts (see [`FreeMarks::groups_for`]):
        /// written by a whole rebuild's scan, changed by each change of a count it sums
        /// in a game's step (see [`Marks`]).
        sums: [u32; groups],
    }
}

kernel_args! {
    /// Which kinds' free lists a rebuild remakes: every kind, or in a game's step those
    /// whose bodies died or were born (the others' lists, flags and tile counts stay as the
    /// rebuild before left them, which must have been whole).
    pub struct Changes {
        /// Each kind's deaths this step (see [`crate::sim::Deaths`]); empty: every kind
        /// changed.
        pub deaths: DevSlice<u32, Read>,
        /// Each kind's births the master ordered this step.
        pub births: DevSlice<u32, Read>,
        /// Kinds that change in any step (bit `k`: kind `k`): those the master brings to
        /// life itself, the ship's and its shots'.
        pub always: u32,
        /// Keeps the struct free of implicit padding.
        pub reserved: u32,
    }
}

impl Changes {
    /// Every kind changed: a whole rebuild.
    pub const ALL: Changes = Changes {
        deaths: DevSlice::EMPTY,
        births: DevSlice::EMPTY,
        always: 0,
        reserved: 0,
    };

    /// Whether kind `kind`'s bodies may have died or been born.
    #[inline(always)]
    pub fn changed(&self, kind: u32) -> bool {
        self.deaths.is_empty()
            || self.always & super::broad::kind_bit(kind) != 0
            || self.deaths.get(kind) != 0
            || self.births.get(kind) != 0
    }
}

impl FreeMarks {
    /// Elements of [`FreeMarks::tiles`] for `slots` slots (a multiple of [`WARP`]).
    pub const fn tiles_for(slots: u32) -> u32 {
        slots / WARP + 1
    }

    /// Elements of [`FreeMarks::sums`] for `slots` slots: one per [`TILE`] tiles.
    pub const fn groups_for(slots: u32) -> u32 {
        scan::tiles(Self::tiles_for(slots))
    }
}

kernel_args! {
    /// Where the integrator marks the slots whose freedom it changes (see [`Marks::note`]):
    /// empty slices where it marks none.
    pub struct Marks {
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange, Read>,
        /// The flags (see [`FreeMarks::flags`]).
        pub flags: DevSlice<u32>,
        /// The free slots of each tile of 32 slots.
        pub tiles: DevSlice<u32>,
        /// The tiles' counts summed [`TILE`] at a time.
        pub sums: DevSlice<u32>,
    }
}

impl Marks {
    /// No marks.
    pub const NONE: Marks = Marks {
        ranges: DevSlice::EMPTY,
        flags: DevSlice::EMPTY,
        tiles: DevSlice::EMPTY,
        sums: DevSlice::EMPTY,
    };

    /// What [`Marks::note`] needs of slot `slot` of kind `kind`: its flag and its kind's
    /// range, asked for with the slot's other reads (`None` without marks).
    #[inline(always)]
    pub fn read(&self, slot: u32, kind: u32) -> Option<(u32, SlotRange)> {
        (!self.flags.is_empty()).then(|| (self.flags.get(slot), self.ranges.get(kind)))
    }

    /// Slot `slot`, whose flag and kind's range are `read` ([`Marks::read`]) and whose body
    /// is `alive` now: if that changed whether the slot is free, its flag says so (rank 0,
    /// until [`gather_free`] ranks its kind) and its tile's count and the count's sum go up
    /// or down by one, atomically. A slot changes only where a body died or was born, so
    /// the kind is one the rebuild remakes.
    #[inline(always)]
    pub fn note(&self, slot: u32, read: Option<(u32, SlotRange)>, alive: bool) {
        let Some((flag, range)) = read else {
            return;
        };
        let free = !alive && usable(slot, range);
        if free == (flag & FREE != 0) {
            return;
        }
        self.flags.set(slot, self::flag(free, 0));
        // Plus or minus one, wrapping: the sums are exact whatever the order of the adds.
        let change = if free { 1 } else { u32::MAX };
        let tile = slot / WARP;
        self.tiles.atomic_add(tile, change);
        self.sums.atomic_add(tile / TILE, change);
    }
}

/// A flag's bit: the slot is usable and holds no live body.
pub const FREE: u32 = 1;

/// Where a free slot's flag holds its rank in its kind's list (ranks are below the
/// world's 2²⁴ slots).
pub const RANK_SHIFT: u32 = 1;

/// The rank in its kind's free list of the free slot flagged `flag`.
#[inline(always)]
pub fn free_rank(flag: u32) -> u32 {
    flag >> RANK_SHIFT
}

/// The flag of a slot that is `free` now, `rank`-th in its kind's list.
#[inline(always)]
fn flag(free: bool, rank: u32) -> u32 {
    match free {
        false => 0,
        true => FREE | rank << RANK_SHIFT,
    }
}

access! {
    /// What the free lists read of the bodies: each slot's kind and liveness.
    pub struct Marking: BodiesAccess {
        pos: Unused, vel: Unused, force: Unused, dir: Unused, kind: Read, energy: Unused,
        mass: Unused, alive: Read, state: Unused, age: Unused, prev: Unused, frozen: Unused,
        rng: Unused,
    }
}

kernel_args! {
    /// Arguments of [`mark_free`].
    pub struct MarkArgs {
        /// The bodies (kinds and liveness are read).
        pub bodies: Bodies<View, Marking>,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange, Read>,
        /// Output: the flags (see [`FreeMarks::flags`]), one per slot.
        pub flags: DevSlice<u32>,
        /// Output: the free slots of each tile of 32 slots.
        pub tiles: DevSlice<u32>,
        /// The kinds to remake.
        pub changes: Changes,
    }
}

/// Whether `slot`, of kind `range`, is usable (not padding).
#[inline(always)]
fn usable(slot: u32, range: SlotRange) -> bool {
    slot >= range.start && slot < range.end()
}

/// Thread `i` writes `flags[i]`; lane 0 of each warp writes its tile's count. The slots
/// come in whole warps (a multiple of [`WARP`]), of one kind each, so a warp returns early
/// whole: past the slots, or where its kind did not change.
#[inline(always)]
pub fn mark_free(t: Thread, args: &MarkArgs) {
    let slot = t.global();
    if slot >= args.flags.len() {
        return;
    }
    let b = &args.bodies;
    let kind = b.kind.get(slot);
    if !args.changes.changed(kind) {
        return;
    }
    let free = |s: u32| usable(s, args.ranges.get(b.kind.get(s))) && !b.is_alive(s);
    let mine = free(slot);
    // The rank comes in `gather_free`.
    args.flags.set(slot, flag(mine, 0));
    let (lane, first) = (t.lane(), slot - t.lane());
    let theirs = |l: u32| free(first + l) as u32;
    let count = warp::sum_u32_in_lane0(lane, warp::own_or(lane, mine as u32, theirs));
    if lane == 0 {
        args.tiles.set(slot / WARP, count);
    }
}

kernel_args! {
    /// Arguments of [`gather_free`].
    pub struct GatherArgs {
        /// Kind of each slot.
        pub kind: DevSlice<u32, Read>,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange, Read>,
        /// The flags of [`mark_free`]: each free slot's rank in its list is added.
        pub flags: DevSlice<u32>,
        /// The exclusive prefix sums of the tiles' counts of free slots, and their total.
        pub offsets: DevSlice<u32, Read>,
        /// Output: the free slots of kind `k` at `list[start_k ..][.. count_k]`; one per slot.
        pub list: DevSlice<u32>,
        /// Output: the number of free slots of each kind. A kind without slots has no writer: its
        /// count stays the 0 it was allocated with.
        pub count: DevSlice<u32>,
        /// The kinds to remake (as [`mark_free`]'s).
        pub changes: Changes,
    }
}

/// Thread `i`: a free slot writes itself at its rank inside its range's list, and thread `k`
/// writes kind `k`'s count, the free slots of its tiles. Every element has one writer. A
/// warp returns at once where its tile has no free slot (most, in a full world), or where
/// its kind did not change.
#[inline(always)]
pub fn gather_free(t: Thread, args: &GatherArgs) {
    let slot = t.global();
    let offsets = &args.offsets;
    // A range starts a tile and its padding, never free, ends one: its count is its tiles'.
    if slot < args.count.len() && args.changes.changed(slot) {
        let range = args.ranges.get(slot);
        if range.capacity > 0 {
            let (first, last) = (range.start / WARP, (range.end() - 1) / WARP);
            let count = offsets.get(last + 1).wrapping_sub(offsets.get(first));
            args.count.set(slot, count);
        }
    }
    if slot >= args.flags.len() {
        return;
    }
    let (lane, tile) = (t.lane(), slot / WARP);
    // Warp-uniform, as the kind is: the tile's slots are of one range.
    let [offset, next] = asked([offsets.get(tile), offsets.get(tile + 1)]);
    if next == offset {
        return;
    }
    let kind = args.kind.get(slot);
    if !args.changes.changed(kind) {
        return;
    }
    let before = warp::exclusive_sum_u32(lane, |l| args.flags.get(tile * WARP + l) & FREE);
    let range = args.ranges.get(kind);
    let flag = args.flags.get(slot);
    if flag & FREE == 0 || !usable(slot, range) {
        return;
    }
    // A range starts a tile: the free slots before it are its first tile's offset. Only the
    // rank's bits change (a rank left by an earlier rebuild is replaced): the other lanes'
    // reads of the flag's `FREE` above (on the CPU, where a lane reads its warp's flags) get
    // the same bit either way.
    let rank = offset + before - offsets.get(range.start / WARP);
    args.flags.set(slot, FREE | rank << RANK_SHIFT);
    args.list.set(range.start + rank, slot);
}

/// Usable slot `slot` of kind `kind`'s `range`, with `rank` free slots of the range before
/// it: written at its rank into the kind's list if it is free (`free` 1), and, as the
/// range's last, the kind's count of free slots.
#[inline(always)]
fn place_in_list(
    (list, count): (&DevSlice<u32>, &DevSlice<u32>),
    (slot, kind, range): (u32, u32, SlotRange),
    rank: u32,
    free: u32,
) {
    if free != 0 {
        list.set(range.start + rank, slot);
    }
    if slot + 1 == range.end() {
        count.set(kind, rank + free);
    }
}

/// The largest kind range whose free list [`mark_and_gather_free`] rebuilds: its last warp
/// reads the liveness of every slot of the range before it, `ONE_LAUNCH_RANGE / 32 / 16`
/// rounds of 16 loads a lane (see [`crate::exec::RUNS_IN_FLIGHT`]).
pub const ONE_LAUNCH_RANGE: u32 = 4096;

kernel_args! {
    /// Arguments of [`mark_and_gather_free`].
    pub struct MarkGatherArgs {
        /// The bodies (kinds and liveness are read).
        pub bodies: Bodies<View, Marking>,
        /// Slot range of each kind, none larger than [`ONE_LAUNCH_RANGE`] slots.
        pub ranges: DevSlice<SlotRange, Read>,
        /// Output: the flags (see [`FreeMarks::flags`]), one per slot.
        pub flags: DevSlice<u32>,
        /// Output: as [`GatherArgs::list`].
        pub list: DevSlice<u32>,
        /// Output: as [`GatherArgs::count`].
        pub count: DevSlice<u32>,
        /// The kinds to remake (as [`mark_free`]'s).
        pub changes: Changes,
    }
}

/// [`mark_free`], the scan and [`gather_free`] in one launch, with the same flags, lists and
/// counts: thread `i` flags slot `i`, and its warp counts the free slots of its range before
/// it (each lane every 32nd, then a warp sum) instead of reading a prefix sum of the tiles.
/// A warp's slots are of one range (ranges start on warps, and padding belongs to the range
/// before it), all usable from the range's start up to the warp. The work of the last warp
/// of a range grows with the range: for ranges of at most [`ONE_LAUNCH_RANGE`] slots.
#[inline(always)]
pub fn mark_and_gather_free(t: Thread, args: &MarkGatherArgs) {
    let slot = t.global();
    // Whole warps: the slots are a multiple of 32.
    if slot >= args.flags.len() {
        return;
    }
    let (b, lane) = (&args.bodies, t.lane());
    let first = slot - lane;
    // The slot's kind and range are the world's: read while the launch before ends.
    let kind = b.kind.get(slot);
    let range = args.ranges.get(kind);
    follow_previous_launch();
    if !args.changes.changed(kind) {
        return;
    }
    let free = |s: u32| usable(s, range) && !b.is_alive(s);
    let mine = free(slot) as u32;
    // Each lane reads runs of four slots, every `4 · WARP`-th: the range's start and the
    // warp's first slot are multiples of 32.
    let before = warp::sum_u32(lane, |l| {
        let dead = |n: u32, [a, b, c, d]: [u32; 4]| {
            n + u32::from(a == 0) + u32::from(b == 0) + u32::from(c == 0) + u32::from(d == 0)
        };
        b.alive
            .fold_runs((range.start + 4 * l, first, 4 * WARP), 0, dead)
    });
    let within =
        warp::exclusive_sum_u32(lane, warp::own_or(lane, mine, |l| free(first + l) as u32));
    args.flags.set(slot, flag(mine != 0, before + within));
    if !usable(slot, range) {
        return;
    }
    place_in_list(
        (&args.list, &args.count),
        (slot, kind, range),
        before + within,
        mine,
    );
}
