//! `master`: the master before the physics: the step's input (the player's, or the one the
//! autopilot left), ship, shots, score, spawns ordered; one launch of one warp.

use gpuwars_kernels::{Kernel, KernelArgs, registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// Bytes a master warp moves, by our count: a few status words and a kind's counters a
/// lane.
const BYTES: u64 = 128 * warp::WARP as u64;

/// The master on one warp, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    on_one_warp(registry::MASTER, |b| world.master_args(b))
}

/// `kernel` (the master before or after the physics) on one warp with the arguments `args`
/// makes, in games.
pub(super) fn on_one_warp<A: KernelArgs>(
    kernel: Kernel<A>,
    args: impl FnOnce(&mut Binder) -> Option<A>,
) -> Vec<Op> {
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let Some(args) = args(&mut b) else {
        return Vec::new();
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe { threads(kernel, warp::WARP, args, b, BYTES) }]
}
