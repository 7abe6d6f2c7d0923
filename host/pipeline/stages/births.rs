//! `births`: the enemies the master ordered come alive.

use gpuwars_kernels::game::master::BirthArgs;
use gpuwars_kernels::registry;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// Threads enough for a large wave at once, and no more: each takes every `BIRTH_THREADS`-th
/// birth, so a step that orders none costs a short launch at any size.
const BIRTH_THREADS: u32 = 65_536;

/// Up to [`BIRTH_THREADS`] threads (no more than the slots), in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(game) = &world.game else {
        return Vec::new();
    };
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = BirthArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        ranges: b.view(&world.state.tables.ranges),
        free: world.state.free(&mut b),
        births: b.view(&game.data.births),
        birth_speed: b.view(&game.data.birth_speed),
        space: world.space,
        rules: game.config.rules,
        reserved: 0,
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads(
            registry::BIRTHS,
            world.layout.slots.min(BIRTH_THREADS),
            args,
            b,
            8 * u64::from(world.layout.slots),
        )
    }]
}
