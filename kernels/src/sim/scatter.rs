//! Bringing bodies to life at random places, drawn from each slot's own generator.

use glam::Vec2;

use super::bodies::{Bodies, BodiesAccess};
use super::space::Space;
use crate::access::Write;
use crate::data::View;
use crate::math::try_normalize;
use crate::{DevSlice, Thread, kernel_args};

kernel_args! {
    /// Arguments of [`scatter`].
    pub struct ScatterArgs {
        /// The bodies; the chosen slots are (re)initialised.
        pub bodies: Bodies,
        /// The slots to fill: `count` distinct free slots (a prefix of a free list).
        pub slots: DevSlice<u32>,
        /// The world (size and boundary rule).
        pub space: Space,
        /// Standard deviation of each velocity component.
        pub speed: f32,
        /// Initial energy.
        pub energy: i32,
    }
}

/// Thread `t` brings slot `slots[t]` to life at a uniformly random place (see
/// [`random_place`]), velocity normal with deviation `speed` per axis, with the given energy.
#[inline(always)]
pub fn scatter(t: Thread, args: &ScatterArgs) {
    let i = t.global();
    if i >= args.slots.len() {
        return;
    }
    let b = &args.bodies;
    let slot = args.slots.get(i);
    let place = random_place(b, slot, &args.space, args.speed);
    birth(b, &args.space, slot, place, args.energy);
}

/// Where and how a body comes to life.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Place {
    /// Position.
    pub pos: Vec2,
    /// Velocity.
    pub vel: Vec2,
    /// The way it faces if it is born at rest (a unit vector).
    pub facing: Vec2,
}

/// A uniformly random position in the world (two draws) and a normal velocity of deviation
/// `speed` per axis (two more, Box–Muller), from `slot`'s own generator. The same normal
/// pair gives a uniformly random facing for a body born at rest: bodies that all faced `+x`
/// would all wander that way, since wandering turns only a little from the way a body faces.
#[inline(always)]
pub fn random_place(b: &Bodies, slot: u32, space: &Space, speed: f32) -> Place {
    let mut rng = b.rng.open(slot);
    let u = Vec2::new(rng.next_f32(), rng.next_f32());
    let (nx, ny) = rng.next_normal_pair();
    let normal = Vec2::new(nx, ny);
    Place {
        pos: u * space.size,
        vel: normal * speed,
        facing: try_normalize(normal).unwrap_or(Vec2::X),
    }
}

/// Brings `slot` to life at `place`, kept inside the world: no force, `energy`, age 0, its
/// machine's initial state, facing its velocity (or the place's facing at rest). Writes
/// what a birth sets, and nothing else of the bodies (`M` allows that much).
#[inline(always)]
pub fn birth<M>(b: &Bodies<View, M>, space: &Space, slot: u32, place: Place, energy: i32)
where
    M: BodiesAccess<
            pos = Write,
            prev = Write,
            vel = Write,
            force = Write,
            dir = Write,
            energy = Write,
            state = Write,
            age = Write,
            alive = Write,
        >,
{
    let (pos, vel) = space.confine(place.pos, place.vel);
    b.pos.set(slot, pos);
    if b.traces() {
        // A newborn has not moved yet: its first path starts where it is born.
        b.prev.set(slot, pos);
    }
    b.vel.set(slot, vel);
    b.force.set(slot, Vec2::ZERO);
    b.dir.set(slot, try_normalize(vel).unwrap_or(place.facing));
    b.energy.set(slot, energy);
    b.state.set(slot, 0);
    b.age.set(slot, 0);
    b.alive.set(slot, 1);
}
