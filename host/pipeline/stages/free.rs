//! `free`: the free lists: flags and each tile's count of them, the tiles' prefix sum, the
//! lists and counts (each kind's last slot writes its count, so they need no clearing); on
//! the GPU in worlds of small ranges, all of it in one launch.

use gpuwars_kernels::registry;
use gpuwars_kernels::sim::broad::kind_bit;
use gpuwars_kernels::sim::free_list::{Changes, FreeMarks, GatherArgs, MarkArgs, MarkGatherArgs};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::{LIGHT_BLOCK, threads, threads_in};

/// Mark and gather, a thread a slot each, with the scan of the tiles' counts between them;
/// or both in one launch where the world's ranges allow (see `Config::free_in_one_launch`).
/// Where `tracked` (a game's step that does not renumber), only the kinds whose bodies died
/// or were born are remade, and the marks are the integrator's where it makes them
/// (`Config::marks_in_integrate`); elsewhere every kind (the lists a world starts from,
/// those after bodies are placed or renumbered).
pub(in crate::pipeline) fn ops(world: &World, tracked: bool) -> Vec<Op> {
    let (slots, state, marks) = (world.layout.slots, &world.state, &world.scratch.marks);
    let changes = |b: &mut Binder| match (&world.game, tracked) {
        (Some(game), true) => {
            let rules = &game.config.rules;
            Changes {
                deaths: b.view(&game.data.deaths),
                births: b.view(&game.data.births),
                always: kind_bit(rules.ship_kind) | kind_bit(rules.shot_kind),
                reserved: 0,
            }
        }
        _ => Changes::ALL,
    };
    if world.config.free_in_one_launch {
        // SAFETY: the views go into the op made with the binder.
        let mut b = unsafe { Binder::new() };
        let args = MarkGatherArgs {
            bodies: state.bodies(&mut b),
            ranges: b.view(&state.tables.ranges),
            flags: b.view(&marks.flags),
            list: b.view(&state.free.list),
            count: b.view(&state.free.count),
            changes: changes(&mut b),
        };
        // SAFETY: the world's buffers, sized as the kernel asks (see `World`); the config
        // holds it only where every range is small enough.
        let op = unsafe {
            threads(
                registry::MARK_AND_GATHER_FREE,
                slots,
                args,
                b,
                16 * u64::from(slots),
            )
        };
        return vec![op];
    }
    let mut ops = Vec::new();
    // In a game's step the integrator may have marked the slots that changed already.
    let marked = tracked && world.config.marks_in_integrate;
    if !marked {
        // SAFETY: the views go into the op made with the binder.
        let mut b = unsafe { Binder::new() };
        let mark = MarkArgs {
            bodies: state.bodies(&mut b),
            ranges: b.view(&state.tables.ranges),
            flags: b.view(&marks.flags),
            tiles: b.view(&marks.tiles),
            changes: changes(&mut b),
        };
        // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
        ops.push(unsafe {
            threads_in(
                registry::MARK_FREE,
                slots,
                LIGHT_BLOCK,
                mark,
                b,
                12 * u64::from(slots),
            )
        });
    }
    // Over one more element than the tiles, whose sum is the total; not in place, since
    // the kinds that keep their lists keep their tiles' counts. The counts' sums, which the
    // integrator's marks keep, are worked out again where the marks were the free lists'.
    ops.extend(
        world
            .scratch
            .marks_scan
            .ops_with_sums(
                &marks.tiles,
                &marks.offsets,
                FreeMarks::tiles_for(slots),
                (&marks.sums, marked),
            )
            .expect("the scan was made for the tiles"),
    );
    // SAFETY: the views go into the op made with the binder.
    let mut b = unsafe { Binder::new() };
    let gather = GatherArgs {
        kind: b.view(&state.bodies.kind),
        ranges: b.view(&state.tables.ranges),
        flags: b.view(&marks.flags),
        offsets: b.view(&marks.offsets),
        list: b.view(&state.free.list),
        count: b.view(&state.free.count),
        changes: changes(&mut b),
    };
    // SAFETY: as above.
    ops.push(unsafe {
        threads_in(
            registry::GATHER_FREE,
            slots,
            LIGHT_BLOCK,
            gather,
            b,
            12 * u64::from(slots),
        )
    });
    ops
}
