//! Renumbering: every few steps in large worlds, the live bodies of each kind move to the
//! front of the kind's slot range in the grid's order (cell by cell, slots in increasing
//! order inside a cell), and the free slots follow them. Threads run in slot order, so after
//! it a warp's 32 bodies are neighbours in the field: their neighbour queries read the same
//! buckets and cache lines, while each body's own reads and writes stay coalesced and warps
//! stay grouped by kind.
//!
//! It runs right after the broad phase, whose buckets list each kind's live bodies in that
//! order, in two launches (the arrays are permuted, which no single launch can do in place):
//! 1. [`gather_in_cell_order`]: slot `i` copies the state of the body that moves there into
//!    [`Moved`];
//! 2. [`settle_in_cell_order`]: slot `i` takes it back, and the grid's entries name the new
//!    slots.
//!
//! What moves is what a body carries from step to step: place, velocity, force, facing,
//! energy, state, age, and the last path's start where the world traces paths. Kind and
//! mass are those of the range; each slot keeps its generator, so a body draws from the
//! generator of the slot it holds, as a body born there would. The grid's buckets keep their order (a bucket's bodies get
//! increasing slots in the order they were listed), so every query folds its neighbours in
//! the same order as before.

use glam::Vec2;

use super::bodies::Bodies;
use super::kinds::SlotRange;
use crate::{DevSlice, Thread, device_data, kernel_args};

device_data! {
    /// The bodies' state on its way to their new slots, one element per (new) slot.
    pub struct Moved(slots, traced): MovedAccess {
        /// Position.
        pos: [Vec2; slots],
        /// Velocity.
        vel: [Vec2; slots],
        /// Force.
        force: [Vec2; slots],
        /// Facing.
        dir: [Vec2; slots],
        /// Energy.
        energy: [i32; slots],
        /// Machine state.
        state: [u32; slots],
        /// Age.
        age: [u32; slots],
        /// Where the last (sub)step moved it from, in worlds that trace paths.
        prev: [Vec2; traced],
    }
}

kernel_args! {
    /// Arguments of [`gather_in_cell_order`] and [`settle_in_cell_order`].
    pub struct RenumberArgs {
        /// The bodies, moved.
        pub bodies: Bodies,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange>,
        /// The grid's bucket starts (bucket `kind · cells + cell`, one more for the total).
        pub start: DevSlice<u32>,
        /// The grid's entries: the slots of each bucket; renamed to the new slots.
        pub entries: DevSlice<u32>,
        /// The state between the two launches.
        pub moved: Moved,
        /// Cells of the grid.
        pub cells: u32,
        /// Keeps the struct free of implicit padding.
        pub reserved: u32,
    }
}

/// Copies what a body carries from step to step (every array [`Moved`] holds but the free
/// flag, which lives outside the bodies) from element `$from` of `$src` to element `$to` of
/// `$dst`: the same fields in [`Bodies`] and in [`Moved`], named once.
macro_rules! carry {
    ($dst:expr, $to:expr, $src:expr, $from:expr) => {{
        let (dst, src) = (&$dst, &$src);
        dst.pos.set($to, src.pos.get($from));
        dst.vel.set($to, src.vel.get($from));
        dst.force.set($to, src.force.get($from));
        dst.dir.set($to, src.dir.get($from));
        dst.energy.set($to, src.energy.get($from));
        dst.state.set($to, src.state.get($from));
        dst.age.set($to, src.age.get($from));
        if !dst.prev.is_empty() {
            dst.prev.set($to, src.prev.get($from));
        }
    }};
}

/// What the renumbering gives a slot of a kind's range.
enum Destination {
    /// The body at this grid entry: the kind's `r`-th live body in grid order goes to the
    /// range's `r`-th slot.
    Body(u32),
    /// Nothing: the slot ends up free.
    Free,
}

/// Slot `i`'s destination; `None` for a slot the renumbering leaves alone (padding, or every
/// slot of a frozen world).
#[inline(always)]
fn destination(args: &RenumberArgs, i: u32) -> Option<Destination> {
    let b = &args.bodies;
    if i >= b.slots() || b.is_frozen() {
        return None;
    }
    let kind = b.kind.get(i);
    let range = args.ranges.get(kind);
    if i < range.start || i >= range.end() {
        return None;
    }
    let first = args.start.get(kind * args.cells);
    let live = args.start.get((kind + 1) * args.cells) - first;
    let rank = i - range.start;
    Some(if rank < live {
        Destination::Body(first + rank)
    } else {
        Destination::Free
    })
}

/// Thread `i`: if slot `i` receives a body, its state is copied into [`Moved`].
#[inline(always)]
pub fn gather_in_cell_order(t: Thread, args: &RenumberArgs) {
    let i = t.global();
    let Some(Destination::Body(entry)) = destination(args, i) else {
        return;
    };
    let from = args.entries.get(entry);
    carry!(args.moved, i, args.bodies, from);
}

/// Thread `i`: slot `i` takes the body [`gather_in_cell_order`] copied for it, and its grid
/// entry names it; or the slot is free (its other elements mean nothing until a birth
/// writes them all).
#[inline(always)]
pub fn settle_in_cell_order(t: Thread, args: &RenumberArgs) {
    let i = t.global();
    let b = &args.bodies;
    let entry = match destination(args, i) {
        None => return,
        Some(Destination::Free) => {
            b.alive.set(i, 0);
            return;
        }
        Some(Destination::Body(entry)) => entry,
    };
    carry!(args.bodies, i, args.moved, i);
    b.alive.set(i, 1);
    args.entries.set(entry, i);
}
