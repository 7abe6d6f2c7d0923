//! `broad`: the grid: bucket counts, their prefix sum into starts, placement (which zeroes
//! the counts for the next build), canonical order.

use gpuwars_kernels::game::master::BirthCountArgs;
use gpuwars_kernels::registry;
use gpuwars_kernels::sim::broad::{self, CountArgs, MergeArgs, OrderArgs, PlaceArgs};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::{LIGHT_BLOCK, threads, threads_in};

/// The broad phase's launches of substep `substep`, a thread a slot each, if the world has
/// a grid; in the first substep of a game whose births are in the count
/// (`Config::births_in_count`), the count brings the enemies the master ordered to life
/// first (`births_and_count`).
pub(in crate::pipeline) fn ops(world: &World, substep: u32) -> Vec<Op> {
    if !world.config.grid {
        return Vec::new();
    }
    let slots = world.layout.slots;
    let (g, pos, vel) = (
        &world.scratch.grid,
        &world.state.bodies.pos,
        &world.state.bodies.vel,
    );
    // The entries' velocities, where the bodies move in the launch that queries the grid.
    let moving = world.config.one_launch;
    // SAFETY (every binder below): the views go into the op made with it.
    let mut b = unsafe { Binder::new() };
    let count = CountArgs {
        bodies: world.state.bodies(&mut b),
        space: world.space,
        keys: b.view(&g.keys),
        ranks: b.view(&g.ranks),
        counts: b.view(&g.counts),
    };
    // SAFETY (every op below): the world's buffers, sized as the kernels ask (see `World`);
    // the counts are zero before the first build (allocated zeroed) and after every other
    // (`place_in_cells` zeroes them).
    let births = match substep {
        0 if world.config.births_in_count => world.birth_args(&mut b),
        _ => None,
    };
    let mut ops = vec![match births {
        Some(births) => {
            let args = BirthCountArgs { births, count };
            let bytes = 32 * u64::from(slots);
            unsafe { threads(registry::BIRTHS_AND_COUNT, slots, args, b, bytes) }
        }
        None => unsafe {
            threads(
                registry::COUNT_CELLS,
                slots,
                count,
                b,
                28 * u64::from(slots),
            )
        },
    }];
    ops.extend(
        world
            .scratch
            .grid_scan
            .ops(&g.counts, &g.start, g.start.len() as u32)
            .expect("the scan was made for the buckets"),
    );
    let mut b = unsafe { Binder::new() };
    let place = PlaceArgs {
        keys: b.view(&g.keys),
        ranks: b.view(&g.ranks),
        start: b.view(&g.start),
        unordered: b.view(&g.unordered),
        counts: b.view(&g.counts),
        rows: b.view(&g.rows),
        space: world.space,
    };
    let buckets = g.counts.len() as u64;
    ops.push(unsafe {
        threads_in(
            registry::PLACE_IN_CELLS,
            slots,
            LIGHT_BLOCK,
            place,
            b,
            16 * u64::from(slots) + 4 * buckets,
        )
    });
    // With a cap or a contact budget (the settings that ask for bounded crowds), crowded
    // buckets are ordered in runs and merged, so that their cost stays O(n log n): the
    // passes a bucket of the largest kind's capacity needs.
    let physics = &world.spec.physics;
    let bounded = physics.neighbour_cap != 0 || physics.contact_budget != 0;
    let mut b = unsafe { Binder::new() };
    let order = OrderArgs {
        pos: b.view(pos),
        vel: b.view(vel),
        keys: b.view(&g.keys),
        start: b.view(&g.start),
        unordered: b.view(&g.unordered),
        slots: b.view(&g.slots),
        entry_pos: b.view(&g.pos),
        entry_vel: world.scratch.entry_velocities(&mut b, moving),
        prev: b.view(&world.state.bodies.prev),
        entry_prev: b.view(&g.prev),
        runs: b.view(&g.ranks),
        bounded: u32::from(bounded),
        reserved: 0,
    };
    ops.push(unsafe {
        threads(
            registry::ORDER_CELLS,
            slots,
            order,
            b,
            36 * u64::from(slots),
        )
    });
    let largest = world.layout.ranges.iter().map(|r| r.capacity).max();
    let merges = match largest {
        Some(largest) if bounded => largest
            .div_ceil(broad::RUN)
            .next_power_of_two()
            .trailing_zeros(),
        _ => 0,
    };
    // The runs go back and forth between the ranks (free after placement) and the
    // arrival-ordered slots (free after ordering).
    let (mut src, mut dst) = (&g.ranks, &g.unordered);
    for pass in 0..merges {
        let mut b = unsafe { Binder::new() };
        let merge = MergeArgs {
            pos: b.view(pos),
            vel: b.view(vel),
            start: b.view(&g.start),
            src: b.view(src),
            dst: b.view(dst),
            slots: b.view(&g.slots),
            entry_pos: b.view(&g.pos),
            entry_vel: world.scratch.entry_velocities(&mut b, moving),
            prev: b.view(&world.state.bodies.prev),
            entry_prev: b.view(&g.prev),
            run: broad::RUN << pass,
            reserved: 0,
        };
        ops.push(unsafe { threads(registry::MERGE_RUNS, slots, merge, b, 24 * u64::from(slots)) });
        (src, dst) = (dst, src);
    }
    ops
}
