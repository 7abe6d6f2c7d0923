//! `narrow`: contacts and their response (`collide_circles` without rectangles).

use gpuwars_kernels::sim::narrow::{CollideArgs, Relaxation};

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::{TeamWarps, World};
use crate::primitives::{UNEVEN_BLOCK, threads_in};

/// The narrow phase of substep `substep`, a team of threads a slot, if anything collides
/// (and, in the first substep, the bodies do not take their step in one launch: see
/// `Config::one_launch`).
pub(in crate::pipeline) fn ops(world: &World, substep: u32) -> Vec<Op> {
    let Some(kernel) = world.config.collide else {
        return Vec::new();
    };
    if substep == 0 && world.config.one_launch {
        return Vec::new();
    }
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = CollideArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        warps: TeamWarps::view(&mut b, &world.warps.narrow),
        teams: world.config.narrow_teams,
        space: world.space,
        grid: world.cells(&mut b),
        contacts: world.scratch.contacts(&mut b),
        relax: relaxation(world),
        substep,
        budget: world.spec.physics.contact_budget,
    };
    let threads_needed = u32::try_from(args.teams.threads(&world.layout.ranges))
        .expect("at most 32 threads a slot of at most 2^24 slots");
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    vec![unsafe {
        threads_in(
            kernel,
            threads_needed,
            UNEVEN_BLOCK,
            args,
            b,
            BYTES_A_SLOT * u64::from(world.layout.slots),
        )
    }]
}

/// Bytes the narrow phase moves a slot, by our count: what a body reads of itself and
/// writes of its contacts.
pub(super) const BYTES_A_SLOT: u64 = 52;

/// How the world's physics combines a body's pushes.
pub(super) fn relaxation(world: &World) -> Relaxation {
    let physics = &world.spec.physics;
    Relaxation {
        fraction: physics.relaxation,
        averaged: u32::from(physics.averaged),
    }
}
