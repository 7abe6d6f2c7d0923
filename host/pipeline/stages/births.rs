//! `births`: the enemies the master ordered come alive, in a launch of their own (large games).

use gpuwars_kernels::registry;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// Threads enough for a large wave at once, and no more: each takes every `BIRTH_THREADS`-th
/// birth, so a step that orders none costs a short launch at any size.
const BIRTH_THREADS: u32 = 65_536;

/// Up to [`BIRTH_THREADS`] threads (no more than the slots), in games whose births are not
/// in the grid's count (see `Config::births_in_count`).
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    if world.config.births_in_count {
        return Vec::new();
    }
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let Some(args) = world.birth_args(&mut b) else {
        return Vec::new();
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
