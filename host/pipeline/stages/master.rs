//! `master`: the master before the physics: the step's input (the player's, or the one the
//! autopilot left), ship, shots, score, spawns ordered; one launch of one warp.

use gpuwars_kernels::game::master::MasterArgs;
use gpuwars_kernels::{Kernel, registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// Bytes a master warp moves, by our count: a few status words and a kind's counters a
/// lane.
const BYTES: u64 = 128 * warp::WARP as u64;

/// The master on one warp, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    on_one_warp(world, registry::MASTER, None)
}

/// `kernel` (the master before or after the physics) on one warp with the master's
/// arguments, in games; where `declared`, writing only the buffers it names first and
/// leaving alone those it names second (see `Binder::writing`), else writing all.
pub(super) fn on_one_warp(
    world: &World,
    kernel: Kernel<MasterArgs>,
    declared: Option<(&[&'static str], &[&'static str])>,
) -> Vec<Op> {
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = match declared {
        Some((written, ignored)) => {
            b.writing(written, |b| b.ignoring(ignored, |b| world.master_args(b)))
        }
        None => world.master_args(&mut b),
    };
    let Some(args) = args else {
        return Vec::new();
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe { threads(kernel, warp::WARP, args, b, BYTES) }]
}
