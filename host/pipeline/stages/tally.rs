//! `tally`: the master after the physics: kills, score, status for the host.

use gpuwars_kernels::registry;

use super::master;
use crate::Op;
use crate::pipeline::world::World;

/// The tally on one warp, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    master::on_one_warp(world, registry::TALLY)
}
