//! `pilot`: the ship's input for the step, the autopilot's or the player's passed through.

use gpuwars_kernels::game::autopilot::AutopilotArgs;
use gpuwars_kernels::{registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// The autopilot on one warp, in games.
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
        command: b.view(&game.data.command),
        input: b.view(&game.data.input),
        rules: game.config.rules,
        reserved: 0,
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads(
            registry::AUTOPILOT,
            warp::WARP,
            args,
            b,
            64 * u64::from(warp::WARP),
        )
    }]
}
