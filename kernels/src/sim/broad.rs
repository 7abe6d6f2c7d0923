//! The broad phase (paper 6.1): a uniform grid rebuilt every step by sorting the bodies by
//! cell, as in NVIDIA's particles sample. The same grid answers the narrow phase's "who is
//! near me" and, later, the enemies' vision.
//!
//! Build: [`assign_cells`] keys each slot by its cell, the counting sort orders the
//! (key, slot) pairs (stable, so slots stay in increasing order inside a cell), and
//! [`cell_bounds`] records each cell's run in the sorted order. Query:
//! [`CellIndex::for_each_near`].

use glam::Vec2;

use super::Space;
use super::bodies::Bodies;
use crate::{DevSlice, KernelArgs, Thread};

/// Arguments of [`assign_cells`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AssignArgs {
    /// The bodies (positions and liveness are read).
    pub bodies: Bodies,
    /// The world and its grid.
    pub space: Space,
    /// Output: one sort key per slot.
    pub keys: DevSlice<u32>,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for AssignArgs {}

/// Thread `i` writes `keys[i]`: the cell of slot `i`'s body, or `space.cells()` (past every
/// cell, so it sorts last and is never visited) for a free slot.
#[inline(always)]
pub fn assign_cells(t: Thread, args: &AssignArgs) {
    let slot = t.global();
    if slot >= args.keys.len() {
        return;
    }
    let key = if args.bodies.is_alive(slot) {
        args.space.cell_of(args.bodies.pos.get(slot))
    } else {
        args.space.cells()
    };
    args.keys.set(slot, key);
}

/// The sorted grid: slots ordered by cell, and each cell's run in that order.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CellIndex {
    /// Slots sorted by cell, then by slot.
    pub slots: DevSlice<u32>,
    /// The cell of each entry of `slots` (the sorted keys).
    pub keys: DevSlice<u32>,
    /// First entry of each cell in `slots` (stale for an empty cell).
    pub start: DevSlice<u32>,
    /// One past the last entry of each cell (0 for an empty cell, so its run is empty).
    pub end: DevSlice<u32>,
}

impl CellIndex {
    /// Calls `visit(slot)` for every live body in the 3×3 cells around `pos`: each body once,
    /// cell by cell in row order, by increasing slot inside a cell.
    #[inline(always)]
    pub fn for_each_near(&self, space: &Space, pos: Vec2, mut visit: impl FnMut(u32)) {
        space.for_each_neighbour_cell(pos, |cell| {
            let (start, end) = (self.start.get(cell), self.end.get(cell));
            for entry in start..end {
                visit(self.slots.get(entry));
            }
        });
    }
}

/// Arguments of [`cell_bounds`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct BoundsArgs {
    /// The sorted grid; `start` and `end` are the outputs, and `end` must be zeroed before.
    pub grid: CellIndex,
    /// Number of cells; keys not below it (free slots) are skipped.
    pub cells: u32,
    /// Keeps the struct free of implicit padding.
    pub reserved: u32,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for BoundsArgs {}

/// Thread `j` looks at sorted entry `j`: the first entry of a cell writes the cell's start,
/// the last writes its end. Each cell's bounds have exactly one writer.
#[inline(always)]
pub fn cell_bounds(t: Thread, args: &BoundsArgs) {
    let keys = &args.grid.keys;
    let j = t.global();
    if j >= keys.len() {
        return;
    }
    let key = keys.get(j);
    if key >= args.cells {
        return;
    }
    if j == 0 || keys.get(j - 1) != key {
        args.grid.start.set(key, j);
    }
    if j + 1 == keys.len() || keys.get(j + 1) != key {
        args.grid.end.set(key, j + 1);
    }
}
