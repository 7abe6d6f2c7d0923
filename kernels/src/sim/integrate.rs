//! The integrator (paper 6.3): explicit Euler in the paper's order, force → velocity →
//! position, with a fixed time step, then the world's boundary rule.

use glam::Vec2;

use super::bodies::{Bodies, Contacts};
use super::kinds::KindInfo;
use super::narrow::inverse_mass;
use super::space::Space;
use crate::{DevSlice, KernelArgs, Thread};

/// Arguments of [`integrate`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct IntegrateArgs {
    /// The bodies, advanced in place.
    pub bodies: Bodies,
    /// Kind table (speed limits).
    pub kinds: DevSlice<KindInfo>,
    /// The narrow phase's response for each slot.
    pub contacts: Contacts,
    /// The world (size, boundary rule).
    pub space: Space,
    /// Time step.
    pub dt: f32,
    /// Keeps the struct free of implicit padding.
    pub reserved: u32,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for IntegrateArgs {}

/// One Euler step of a body with acceleration `accel`: `v' = v + a dt`, limited to
/// `max_speed`, then `x' = x + v' dt` (the velocity updated first, as the paper describes).
/// Returns the new position and velocity; a non-finite velocity becomes zero.
#[inline(always)]
pub fn euler(pos: Vec2, vel: Vec2, accel: Vec2, dt: f32, max_speed: f32) -> (Vec2, Vec2) {
    let vel = limit_speed(vel + accel * dt, max_speed);
    let vel = if vel.is_finite() { vel } else { Vec2::ZERO };
    (pos + vel * dt, vel)
}

/// `vel` scaled down to `max_speed` if it is faster.
#[inline(always)]
pub fn limit_speed(vel: Vec2, max_speed: f32) -> Vec2 {
    let speed2 = vel.length_squared();
    if speed2 > max_speed * max_speed {
        vel * (max_speed / libm::sqrtf(speed2))
    } else {
        vel
    }
}

/// Thread `i` advances slot `i`: a body dies if the narrow phase left it without energy (for
/// kinds without a machine, see [`KindInfo::dies_at_zero_energy`]) or it reaches its kind's
/// lifetime; otherwise the collision kick and the force change its velocity, its velocity and
/// the collision push move it, and the boundary rule keeps it in the world.
#[inline(always)]
pub fn integrate(t: Thread, args: &IntegrateArgs) {
    let bodies = &args.bodies;
    let slot = t.global();
    if slot >= bodies.slots() || bodies.is_frozen() || !bodies.is_alive(slot) {
        return;
    }
    let info = args.kinds.get(bodies.kind.get(slot));
    let age = bodies.age.get(slot).saturating_add(1);
    if (bodies.energy.get(slot) <= 0 && info.dies_at_zero_energy()) || info.expired(age) {
        bodies.alive.set(slot, 0);
        return;
    }
    bodies.age.set(slot, age);
    let accel = bodies.force.get(slot) * inverse_mass(bodies.mass.get(slot));
    let (pos, vel) = euler(
        bodies.pos.get(slot),
        bodies.vel.get(slot) + args.contacts.kick.get(slot),
        accel,
        args.dt,
        info.max_speed,
    );
    let (pos, vel) = args.space.confine(pos + args.contacts.push.get(slot), vel);
    bodies.pos.set(slot, pos);
    bodies.vel.set(slot, vel);
    if let Some(dir) = vel.try_normalize() {
        bodies.dir.set(slot, dir);
    }
}
