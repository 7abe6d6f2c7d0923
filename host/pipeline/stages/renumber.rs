//! `renumber`: every few steps in large worlds, the bodies move to the slots of their kinds'
//! ranges in the grid's order (gather, then settle).

use gpuwars_kernels::registry;
use gpuwars_kernels::sim::renumber::RenumberArgs;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;
use crate::sim::state::made;

/// Both launches, a thread a slot each, in worlds that renumber.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(moved) = world.scratch.moved.as_ref() else {
        return Vec::new();
    };
    let (slots, state, scratch) = (world.layout.slots, &world.state, &world.scratch);
    [
        (registry::GATHER_IN_CELL_ORDER, 92),
        (registry::SETTLE_IN_CELL_ORDER, 100),
    ]
    .into_iter()
    .map(|(kernel, bytes)| {
        // SAFETY: the views go into this op only.
        let mut b = unsafe { Binder::new() };
        let args = RenumberArgs {
            bodies: state.bodies(&mut b),
            ranges: b.view(&state.tables.ranges),
            start: b.view(&scratch.grid.start),
            entries: b.view(&scratch.grid.slots),
            moved: made(moved.convert(&mut b)),
            cells: scratch.cells,
            reserved: 0,
        };
        // SAFETY: the world's buffers, sized as the kernels ask (see `World`).
        unsafe { threads(kernel, slots, args, b, bytes * u64::from(slots)) }
    })
    .collect()
}
