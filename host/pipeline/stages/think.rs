//! `think`: every enemy's machine, in one launch over the enemy kinds' slots.

use gpuwars_kernels::game::ai::ThinkArgs;
use gpuwars_kernels::registry;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// A team of threads a slot of the kinds with a machine, in games with enemies.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let (Some(game), Some(teams)) = (&world.game, world.config.think_teams) else {
        return Vec::new();
    };
    let slots = u64::from(teams.end_slot - teams.first_slot);
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = ThinkArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        space: world.space,
        grid: world.cells(&mut b),
        contacts: world.scratch.contacts(&mut b),
        brains: b.view(&game.data.brains),
        ranges: b.view(&world.state.tables.ranges),
        teams,
        ship: game.config.rules.ship.start,
        shot_kind: game.config.rules.shot_kind,
    };
    let threads_needed = u32::try_from(teams.threads(&world.layout.ranges))
        .expect("at most 32 threads a slot of at most 2^24 slots");
    let kernel = if teams.single() {
        registry::THINK
    } else {
        registry::THINK_IN_TEAMS
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe { threads(kernel, threads_needed, args, b, 56 * slots) }]
}
