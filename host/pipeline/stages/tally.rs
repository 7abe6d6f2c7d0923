//! `tally`: the master after the physics: kills, score, status for the host.

use gpuwars_kernels::{registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// The tally on one warp, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let Some(args) = world.master_args(&mut b) else {
        return Vec::new();
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads(
            registry::TALLY,
            warp::WARP,
            args,
            b,
            128 * u64::from(warp::WARP),
        )
    }]
}
