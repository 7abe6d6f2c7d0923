//! `master`: the step's input (the autopilot's, or the player's passed through), then the
//! master before the physics: ship, shots, score, spawns ordered; one launch of one warp.

use gpuwars_kernels::game::autopilot::AutopilotArgs;
use gpuwars_kernels::game::master::{MasterArgs, PilotMasterArgs};
use gpuwars_kernels::{Kernel, registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// Bytes a master warp moves, by our count: a few status words and a kind's counters a
/// lane (the autopilot reads about half as much).
const BYTES: u64 = 128 * warp::WARP as u64;

/// The input and the master on one warp, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(game) = &world.game else {
        return Vec::new();
    };
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let Some(master) = world.master_args(&mut b) else {
        return Vec::new();
    };
    let pilot = AutopilotArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        space: world.space,
        grid: world.cells(&mut b),
        mailbox: master.mailbox,
        input: b.view(&game.data.input),
        rules: game.config.rules,
        reserved: 0,
    };
    let args = PilotMasterArgs { pilot, master };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads(
            registry::PILOT_THEN_MASTER,
            warp::WARP,
            args,
            b,
            BYTES * 3 / 2,
        )
    }]
}

/// `kernel`, the master after the physics, on one warp with the master's arguments, in
/// games.
pub(super) fn on_one_warp(world: &World, kernel: Kernel<MasterArgs>) -> Vec<Op> {
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let Some(args) = world.master_args(&mut b) else {
        return Vec::new();
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe { threads(kernel, warp::WARP, args, b, BYTES) }]
}
