//! `think`: every enemy's machine, in one launch over the enemy kinds' slots; in small
//! worlds of circles, the narrow phase's and the integrator's launches too.

use gpuwars_kernels::game::ai::{BodyStepArgs, ThinkArgs};
use gpuwars_kernels::registry;

use super::integrate::{self, step_dt};
use super::narrow::{self, relaxation};
use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::{TeamWarps, World};
use crate::primitives::threads;

/// A team of threads a slot of the kinds with a machine, in games with enemies; where the
/// bodies take their step in one launch (`Config::one_launch`), a team a slot of every
/// kind.
pub(in crate::pipeline) fn ops(world: &World) -> Vec<Op> {
    let (Some(game), Some(teams)) = (&world.game, world.config.think_teams) else {
        return Vec::new();
    };
    let slots = u64::from(teams.end_slot - teams.first_slot);
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = ThinkArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        space: world.space,
        grid: world.cells(&mut b),
        contacts: world.scratch.contacts(&mut b),
        brains: b.view(&game.data.brains),
        warps: TeamWarps::view(&mut b, &world.warps.think),
        teams,
        status: b.view(&game.data.status),
        ship: game.config.rules.ship.start,
        shot_kind: game.config.rules.shot_kind,
        from_the_end: u32::from(world.config.think_from_the_end),
        reserved: 0,
        deaths: world.deaths(&mut b),
    };
    let threads_needed = u32::try_from(teams.threads(&world.layout.ranges))
        .expect("at most 32 threads a slot of at most 2^24 slots");
    // SAFETY (each op below): the world's buffers, sized as the kernels ask (see `World`).
    let op = if world.config.one_launch {
        // In one launch the narrow phase, the machines and the integrator write theirs.
        let args = BodyStepArgs {
            think: args,
            bodies: world.state.bodies(&mut b),
            contacts: world.scratch.contacts(&mut b),
            relax: relaxation(world),
            field: world.spec.field,
            dt: step_dt(world),
            integrator: world.spec.physics.integrator.code(),
            contact_budget: world.spec.physics.contact_budget,
            reserved: 0,
        };
        // The narrow phase's bytes, the machines' and the integrator's.
        unsafe {
            threads(
                match (world.config.swept, world.config.logged) {
                    (false, false) => registry::COLLIDE_THINK_INTEGRATE,
                    (true, false) => registry::COLLIDE_THINK_INTEGRATE_SWEPT,
                    (false, true) => registry::COLLIDE_THINK_INTEGRATE_LOGGED,
                    (true, true) => registry::COLLIDE_THINK_INTEGRATE_SWEPT_LOGGED,
                },
                threads_needed,
                args,
                b,
                (narrow::BYTES_A_SLOT + BYTES_A_SLOT + integrate::BYTES_A_SLOT) * slots,
            )
        }
    } else if teams.single() {
        unsafe {
            threads(
                registry::THINK,
                threads_needed,
                args,
                b,
                BYTES_A_SLOT * slots,
            )
        }
    } else {
        unsafe {
            threads(
                registry::THINK_IN_TEAMS,
                threads_needed,
                args,
                b,
                BYTES_A_SLOT * slots,
            )
        }
    };
    vec![op]
}

/// Bytes a body's machine moves, by our count, as a wandering body moves them (a body in
/// another state moves fewer; DRAM moved more in ncu's count at a million enemies, 146
/// bytes a body, its generator's words scattered over their arrays: docs/benchmarks.md):
/// - of its own slot, its liveness, kind, place, velocity, energy, hits, state and mass
///   read (40 bytes), its state and force written (12), and its heading read (8);
/// - of its generator, the parameters (12) and position (4) read and the position written
///   (4), and the two draws' five words read and two written (28).
///
/// The grid's entries and cells it looks through are not counted: its neighbours read the
/// same ones, mostly from the caches.
pub(super) const BYTES_A_SLOT: u64 = 40 + 12 + 8 + (12 + 4 + 4 + 28);
