//! The integrator (paper 6.3) with the world's force field, then the boundary rule.
//!
//! The paper's Euler updates the velocity from the force, then the position from the new
//! velocity: semi-implicit (symplectic) Euler, the default. Explicit Euler and velocity
//! Verlet are the measured alternatives (`gpuwars tradeoff`). A step may be split into
//! substeps: the physics stages run once per substep with `dt / substeps`, while ageing and
//! deaths happen once per step, in the first substep.

use glam::Vec2;

use super::bodies::{Bodies, BodiesAccess, Contacts, Deaths};
use super::free_list::Marks;
use super::kinds::KindInfo;
use super::narrow::inverse_mass;
use super::space::Space;
use crate::access::{Read, Write};
use crate::data::View;
use crate::math::{self, sqrt};
use crate::{DevSlice, Thread, access, kernel_args};

/// The paper's order, velocity then position: semi-implicit (symplectic) Euler.
pub const SEMI_IMPLICIT_EULER: u32 = 0;
/// Position from the old velocity, then the velocity: explicit (forward) Euler.
pub const EXPLICIT_EULER: u32 = 1;
/// Velocity Verlet: the field's acceleration at the start and at the end of the step.
pub const VELOCITY_VERLET: u32 = 2;

/// A force field every body feels, as accelerations: a uniform one (gravity) and a central
/// one towards `centre` of strength `strength / r²` (an orbit's attracting mass).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Field {
    /// Uniform acceleration.
    pub gravity: Vec2,
    /// Centre of the central acceleration.
    pub centre: Vec2,
    /// `G·M` of the central acceleration (0: none).
    pub strength: f32,
    /// Keeps the struct free of implicit padding.
    pub reserved: u32,
}

impl Field {
    /// Whether the field is zero everywhere (the game's worlds).
    #[inline(always)]
    pub fn is_none(&self) -> bool {
        self.gravity == Vec2::ZERO && self.strength == 0.0
    }

    /// The field's acceleration at `pos`; zero at the centre itself.
    #[inline(always)]
    pub fn accel(&self, pos: Vec2) -> Vec2 {
        let r = self.centre - pos;
        let r2 = r.length_squared();
        if self.strength == 0.0 || r2 <= 0.0 {
            self.gravity
        } else {
            self.gravity + r * (self.strength / (r2 * sqrt(r2)))
        }
    }
}

access! {
    /// What the integrator does with the bodies: moves them, ages them, and lets those
    /// whose time or place is up die.
    pub struct Moving: BodiesAccess {
        pos: Write, vel: Write, force: Read, dir: Write, kind: Read, energy: Read, mass: Read,
        alive: Write, state: Read, age: Write, prev: Write, frozen: Read, rng: Read,
    }
}

kernel_args! {
    /// Arguments of [`integrate`].
    pub struct IntegrateArgs {
        /// The bodies, advanced in place.
        pub bodies: Bodies<View, Moving>,
        /// Kind table (speed limits).
        pub kinds: DevSlice<KindInfo, Read>,
        /// The narrow phase's response for each slot.
        pub contacts: Contacts<View, Read>,
        /// The world (size, boundary rule).
        pub space: Space,
        /// The force field.
        pub field: Field,
        /// Time step of this substep.
        pub dt: f32,
        /// One of [`SEMI_IMPLICIT_EULER`], [`EXPLICIT_EULER`], [`VELOCITY_VERLET`].
        pub integrator: u32,
        /// Where the deaths are counted.
        pub deaths: Deaths,
        /// Which substep of the step this is: bodies age and die in substep 0 only.
        pub substep: u32,
        /// Nonzero: the launch takes its blocks from the last (see
        /// [`Thread::from_last_block`]).
        pub from_the_end: u32,
        /// Where the slots whose freedom this launch changes are marked for the free lists
        /// ([`Marks::NONE`] where the free lists' own launch marks every slot).
        pub marks: Marks,
    }
}

/// One semi-implicit Euler step of a body with acceleration `accel`: `v' = v + a dt`,
/// limited to `max_speed`, then `x' = x + v' dt` (the velocity updated first, as the paper
/// describes). Returns the new position and velocity; a non-finite velocity becomes zero.
#[inline(always)]
pub fn euler(pos: Vec2, vel: Vec2, accel: Vec2, dt: f32, max_speed: f32) -> (Vec2, Vec2) {
    let vel = finite(limit_speed(vel + accel * dt, max_speed));
    (pos + vel * dt, vel)
}

/// One explicit Euler step: `x' = x + v dt`, then `v' = v + a dt` limited to `max_speed`.
#[inline(always)]
pub fn explicit_euler(pos: Vec2, vel: Vec2, accel: Vec2, dt: f32, max_speed: f32) -> (Vec2, Vec2) {
    let vel = finite(vel);
    (
        pos + vel * dt,
        finite(limit_speed(vel + accel * dt, max_speed)),
    )
}

/// One velocity Verlet step: `x' = x + v dt + a dt²/2`, then `v' = v + (a + a') dt / 2` with
/// `a'` the acceleration at `x'` (`accel_at(x')`), limited to `max_speed`.
#[inline(always)]
pub fn velocity_verlet(
    pos: Vec2,
    vel: Vec2,
    accel: Vec2,
    accel_at: impl Fn(Vec2) -> Vec2,
    dt: f32,
    max_speed: f32,
) -> (Vec2, Vec2) {
    let vel = finite(vel);
    let next = pos + vel * dt + accel * (0.5 * dt * dt);
    let vel = vel + (accel + accel_at(next)) * (0.5 * dt);
    (next, finite(limit_speed(vel, max_speed)))
}

/// `vel`, or zero if it is not finite.
#[inline(always)]
fn finite(vel: Vec2) -> Vec2 {
    if vel.is_finite() { vel } else { Vec2::ZERO }
}

/// `vel` scaled down to `max_speed` if it is faster.
#[inline(always)]
pub fn limit_speed(vel: Vec2, max_speed: f32) -> Vec2 {
    let speed2 = vel.length_squared();
    if speed2 > max_speed * max_speed {
        vel * (max_speed / sqrt(speed2))
    } else {
        vel
    }
}

/// Thread `i` advances slot `i`: in substep 0 a body dies if the narrow phase left it
/// without energy (for kinds without a machine, see [`KindInfo::dies_at_zero_energy`]) or it
/// reaches its kind's lifetime; otherwise the collision kick changes its velocity, the
/// integrator moves it under its force and the field, the collision push moves it, and the
/// boundary rule keeps it in the world.
#[inline(always)]
pub fn integrate(t: Thread, args: &IntegrateArgs) {
    let t = match args.from_the_end {
        0 => t,
        _ => t.from_last_block(),
    };
    let slot = t.global();
    if slot < args.bodies.slots() {
        integrate_slot(args, slot);
    }
}

/// Slot `slot`'s share of [`integrate`] (a slot of the world).
#[inline(always)]
pub fn integrate_slot(args: &IntegrateArgs, slot: u32) {
    let bodies = &args.bodies;
    // Every load of the slot, then its kind's entry, before anything waits on them, and
    // the new place and velocity stored whether the body moves or not (a body that does not
    // move gets its own back): with no branch between the loads and the stores, the
    // compiler keeps the loads together, and a live body waits for memory twice, not once
    // a branch.
    let (frozen, alive, kind) = (
        bodies.is_frozen(),
        bodies.is_alive(slot),
        bodies.kind.get(slot),
    );
    let (age, energy) = (bodies.age.get(slot), bodies.energy.get(slot));
    let (pos, vel, kick) = (
        bodies.pos.get(slot),
        bodies.vel.get(slot),
        args.contacts.kick.get(slot),
    );
    let (force, mass) = (bodies.force.get(slot), bodies.mass.get(slot));
    let push = args.contacts.push.get(slot);
    let info = args.kinds.get(kind);
    let marked = args.marks.read(slot, kind);
    let live = alive && !frozen;
    // Bodies age and die in substep 0 only.
    let aging = args.substep == 0;
    let aged = age.saturating_add(1);
    let dies = aging && ((energy <= 0 && info.dies_at_zero_energy()) || info.expired(aged));
    if live && dies {
        bodies.alive.set(slot, 0);
        args.deaths.count(slot, kind);
    }
    // In the substep that brings bodies to death, the last launch of the step that does.
    if aging {
        args.marks.note(slot, marked, alive && !(live && dies));
    }
    let moves = live && !dies;
    if moves && aging {
        bodies.age.set(slot, aged);
    }
    let (old_pos, old_vel) = (pos, vel);
    let vel = vel + kick;
    let pushed = force * inverse_mass(mass);
    let field = &args.field;
    // The game's worlds have no field: no field term at all then, so that no bit (not even a
    // zero's sign) differs from the paper's.
    let none = field.is_none();
    let accel_at = |p: Vec2| {
        if none {
            pushed
        } else {
            pushed + field.accel(p)
        }
    };
    let (dt, max_speed) = (args.dt, info.max_speed);
    let accel = accel_at(pos);
    let (pos, vel) = match args.integrator {
        EXPLICIT_EULER => explicit_euler(pos, vel, accel, dt, max_speed),
        VELOCITY_VERLET => velocity_verlet(pos, vel, accel, accel_at, dt, max_speed),
        _ => euler(pos, vel, accel, dt, max_speed),
    };
    let (pos, vel) = args.space.confine(pos + push, vel);
    bodies.pos.set(slot, if moves { pos } else { old_pos });
    if bodies.traces() {
        // The path starts where the contacts' push left the body (for a swept contact,
        // where it began): the push resolves what the step found, the path is what the body
        // moved through afterwards.
        bodies
            .prev
            .set(slot, if moves { old_pos + push } else { old_pos });
    }
    bodies.vel.set(slot, if moves { vel } else { old_vel });
    if let Some(dir) = math::try_normalize(vel).filter(|_| moves) {
        bodies.dir.set(slot, dir);
    }
}
