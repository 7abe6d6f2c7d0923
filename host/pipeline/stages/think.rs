//! `think`: every enemy's machine, in one launch over the enemy kinds' slots.

use gpuwars_kernels::game::ai::ThinkArgs;
use gpuwars_kernels::registry;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// A thread a slot of the kinds with a machine, in games with enemies.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(game) = &world.game else {
        return Vec::new();
    };
    let Some((first_slot, end_slot)) = game.config.mind_slots(&world.layout) else {
        return Vec::new();
    };
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = ThinkArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        space: world.space,
        grid: world.cells(&mut b),
        contacts: world.scratch.contacts(&mut b),
        brains: b.view(&game.data.brains),
        first_slot,
        end_slot,
        ship: game.config.rules.ship.start,
        shot_kind: game.config.rules.shot_kind,
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads(
            registry::THINK,
            end_slot - first_slot,
            args,
            b,
            56 * u64::from(end_slot - first_slot),
        )
    }]
}
