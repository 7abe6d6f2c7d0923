//! The world held still for a frame drawn beside the next step: a copy of what the
//! renderers read ([`Drawing`](super::Drawing), [`Glowing`](super::particles::Glowing) and
//! the last input), made in one launch between two steps, so that the frame's launches
//! read the copy while the next step writes the world.

use super::DrawnBodies;
use super::particles::DrawnParticles;
use crate::access::{Read, Unused, Write};
use crate::data::View;
use crate::game::control::Input;
use crate::game::effects::{Particles, ParticlesAccess};
use crate::sim::{Bodies, BodiesAccess};
use crate::{DevSlice, Thread, access, kernel_args};

access! {
    /// The still's bodies as [`keep_still`] writes them: each array the renderers read
    /// ([`Drawing`](super::Drawing)).
    pub struct KeepingBodies: BodiesAccess {
        pos: Write, vel: Unused, force: Unused, dir: Write, kind: Write, energy: Write,
        mass: Unused, alive: Write, state: Unused, age: Unused, prev: Unused, frozen: Unused,
        rng: Unused,
    }
}

access! {
    /// The still's particles as [`keep_still`] writes them: each array the renderers read
    /// ([`Glowing`](super::particles::Glowing)).
    pub struct KeepingParticles: ParticlesAccess {
        pos: Write, vel: Unused, life: Write, kind: Write, seen: Unused,
    }
}

kernel_args! {
    /// Arguments of [`keep_still`].
    pub struct StillArgs {
        /// The world's bodies.
        pub bodies: DrawnBodies,
        /// The world's particles (none in a world without explosions).
        pub particles: DrawnParticles,
        /// The world's last input (one element; none in a world without a game).
        pub input: DevSlice<Input, Read>,
        /// Output: the still's bodies, as many slots as the world's.
        pub still: Bodies<View, KeepingBodies>,
        /// Output: the still's particles, as many as the world's.
        pub still_particles: Particles<View, KeepingParticles>,
        /// Output: the still's input, as long as the world's.
        pub still_input: DevSlice<Input>,
    }
}

/// Threads [`keep_still`] needs: one an element of the longest array it copies.
#[inline]
pub fn still_threads(slots: u32, particles: u32) -> u32 {
    slots.max(particles).max(1)
}

/// Thread `i` copies slot `i`'s drawn arrays, particle `i`'s, and (thread 0) the input.
#[inline(always)]
pub fn keep_still(t: Thread, args: &StillArgs) {
    let i = t.global();
    let (from, to) = (&args.bodies, &args.still);
    if i < from.slots() {
        to.pos.set(i, from.pos.get(i));
        to.dir.set(i, from.dir.get(i));
        to.kind.set(i, from.kind.get(i));
        to.energy.set(i, from.energy.get(i));
        to.alive.set(i, from.alive.get(i));
    }
    let (from, to) = (&args.particles, &args.still_particles);
    if i < from.len() {
        to.pos.set(i, from.pos.get(i));
        to.life.set(i, from.life.get(i));
        to.kind.set(i, from.kind.get(i));
    }
    if i < args.input.len() {
        args.still_input.set(i, args.input.get(i));
    }
}
