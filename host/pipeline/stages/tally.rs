//! `tally`: the master after the physics: kills, score, status for the host; beside the
//! free lists' rebuild.

use gpuwars_kernels::registry;

use super::master;
use crate::Op;
use crate::pipeline::world::World;

/// The tally on one warp, beside the stages after it, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    // It counts from the free slots the master found, its births and the physics' deaths,
    // not from the free lists the stage beside it rebuilds.
    master::on_one_warp(registry::TALLY, |b| world.tally_args(b))
        .into_iter()
        .map(Op::beside)
        .collect()
}
