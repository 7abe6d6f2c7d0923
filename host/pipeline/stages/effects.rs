//! `effects`: kills burst into particles, the others move and fade (before `free` rebuilds
//! the flags it reads).

use gpuwars_kernels::game::effects::EffectsArgs;
use gpuwars_kernels::registry;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;
use crate::sim::state::made;

/// A thread a particle, in games with explosions.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(game) = &world.game else {
        return Vec::new();
    };
    let Some((particles, burst)) = game.effects.as_ref().filter(|(_, b)| b.particles() > 0) else {
        return Vec::new();
    };
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = EffectsArgs {
        bodies: world.state.bodies(&mut b),
        ranges: b.view(&world.state.tables.ranges),
        brains: b.view(&game.data.brains),
        was_free: b.view(&world.scratch.marks.flags),
        particles: made(particles.convert(&mut b)),
        burst: *burst,
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads(
            registry::BURST_AND_FADE,
            burst.particles(),
            args,
            b,
            28 * u64::from(burst.particles()),
        )
    }]
}
