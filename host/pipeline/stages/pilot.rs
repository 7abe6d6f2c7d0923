//! `pilot`: the autopilot's input for the next step, from the grid and the bodies as the
//! step leaves them, beside the step's last stages.

use gpuwars_kernels::game::autopilot::AutopilotArgs;
use gpuwars_kernels::{registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// The autopilot on one warp, beside the stages after it, in games.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(game) = &world.game else {
        return Vec::new();
    };
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = AutopilotArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        space: world.space,
        grid: world.cells(&mut b),
        steered: b.view(&game.data.steered),
        rules: game.config.rules,
        reserved: 0,
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    let op = unsafe {
        threads(
            registry::AUTOPILOT,
            warp::WARP,
            args,
            b,
            64 * u64::from(warp::WARP),
        )
    };
    // SAFETY: the stages after it (free lists, effects, tally) write the free lists,
    // particles, the status, the mailbox and the frozen flag, none of which the autopilot reads
    // (it reads bodies' liveness, places and velocities, the kinds and the grid), and none
    // of them touches the input it writes, which the next step's master reads.
    vec![unsafe { op.beside() }]
}
