//! `integrate`: Euler, the boundary rule, deaths.

use gpuwars_kernels::registry;
use gpuwars_kernels::sim::free_list::Marks;
use gpuwars_kernels::sim::integrate::IntegrateArgs;

use crate::Op;
use crate::backend::Binder;
use crate::pipeline::world::World;
use crate::primitives::threads;

/// The integrator of substep `substep`, a thread a slot (in the first substep, unless the
/// bodies take their step in one launch: see `Config::one_launch`). Where `marking` (a
/// game's step that does not renumber) and the world's config says so
/// (`Config::marks_in_integrate`), its first substep marks the slots whose freedom it
/// changes for the free lists.
pub(in crate::pipeline) fn ops(world: &World, substep: u32, marking: bool) -> Vec<Op> {
    if substep == 0 && world.config.one_launch {
        return Vec::new();
    }
    let (spec, physics) = (&world.spec, &world.spec.physics);
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let marks = marking && substep == 0 && world.config.marks_in_integrate;
    let args = IntegrateArgs {
        bodies: world.state.bodies(&mut b),
        kinds: b.view(&world.state.tables.info),
        contacts: world.scratch.contacts(&mut b),
        space: world.space,
        field: spec.field,
        dt: step_dt(world),
        integrator: physics.integrator.code(),
        deaths: world.deaths(&mut b),
        substep,
        from_the_end: u32::from(substep == 0 && world.config.integrate_from_the_end),
        marks: match marks {
            true => {
                let m = &world.scratch.marks;
                Marks {
                    ranges: b.view(&world.state.tables.ranges),
                    flags: b.view(&m.flags),
                    tiles: b.view(&m.tiles),
                    sums: b.view(&m.sums),
                }
            }
            false => Marks::NONE,
        },
    };
    // SAFETY: the world's buffers, sized as the kernel asks (see `World`).
    let op = unsafe {
        threads(
            registry::INTEGRATE,
            world.layout.slots,
            args,
            b,
            (BYTES_A_SLOT + 4 * u64::from(marks)) * u64::from(world.layout.slots),
        )
    };
    // The autopilot's branch, where it reads the bodies' velocities, ends before they first
    // move.
    match substep {
        0 => vec![op.after_branches()],
        _ => vec![op],
    }
}

/// The time step of each substep.
pub(super) fn step_dt(world: &World) -> f32 {
    world.spec.dt / world.spec.physics.substeps as f32
}

/// Bytes the integrator moves a slot, by our count: what a body reads of itself and its
/// contacts, and its new place and velocity.
pub(super) const BYTES_A_SLOT: u64 = 88;
