//! `pilot`: the autopilot's input for the next step, from the step's grid as it was built,
//! beside the rest of the step where that leaves what it reads alone.

use gpuwars_kernels::game::autopilot::AutopilotArgs;
use gpuwars_kernels::{DevSlice, registry, warp};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// The autopilot on one warp, in games, beside the stages after it: to the step's end where
/// the grid keeps its entries' velocities, else until the integrator (which joins it
/// before it moves the bodies); in order where the step's end would be after a substep's
/// new grid.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let Some(game) = &world.game else {
        return Vec::new();
    };
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = {
        let grid = world.cells(&mut b);
        AutopilotArgs {
            // Read only where the grid keeps no velocities of its own.
            vel: match grid.vel.is_empty() {
                true => b.view(&world.state.bodies.vel),
                false => DevSlice::EMPTY,
            },
            keys: b.view(&world.scratch.grid.keys),
            kinds: b.view(&world.state.tables.info),
            space: world.space,
            grid,
            steered: b.view(&game.data.steered),
            rules: game.config.rules,
            reserved: 0,
        }
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
    let to_the_end = !args.grid.vel.is_empty();
    if to_the_end && world.spec.physics.substeps > 1 {
        // The next substep's grid would replace the one it reads.
        return vec![op];
    }
    vec![op.beside()]
}
