//! `tally`: the master after the physics: kills, score, status for the host; beside the
//! free lists' rebuild.

use gpuwars_kernels::registry;

use super::master;
use crate::Op;
use crate::pipeline::world::World;

/// The tally on one warp, beside the stages after it, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    // SAFETY: the stage after it (the free lists) writes the flags, lists and counts of
    // free slots, none of which the tally reads (it counts from the free slots the master
    // found, its births and the physics' deaths), and reads the bodies' kinds and liveness, which the tally does
    // not write (the status, the mailbox, the deaths it clears and the frozen flag).
    master::on_one_warp(world, registry::TALLY)
        .into_iter()
        .map(|op| unsafe { op.beside() })
        .collect()
}
