//! Explosions: every enemy that dies bursts into particles of its kind, born on the device
//! from the kill. Particles only move and fade: no collisions, no machine, no effect on the
//! game, so the state hash of a game does not cover them.
//!
//! One launch a step, after the physics (which counts each slot's deaths, see
//! [`Deaths`](crate::sim::Deaths)), beside the free lists and the tally, one thread a
//! particle. The enemy slots `first_slot .. end_slot` each own [`Burst::per_kill`]
//! consecutive particles, so a burst needs no allocation and no ordering: thread `p` looks at
//! its owner's slot, and if that slot's deaths changed since the particle last looked (its
//! enemy died this step) the particle is born at the enemy's place; otherwise a live
//! particle moves, slows and ages. Every particle has one writer, so the result is the same
//! on every schedule and backend.

use core::f32::consts::TAU;

use glam::Vec2;

use super::rules::Brain;
use crate::access::{Read, Readable, Unused};
use crate::data::View;
use crate::math::Divisor;
use crate::sim::{Bodies, BodiesAccess};
use crate::{DevSlice, Thread, access, device_data, kernel_args};

/// Most particles one kill makes.
pub const MAX_PER_KILL: u32 = 64;
/// Most particles a world has.
pub const MAX_PARTICLES: u32 = 1 << 24;

device_data! {
    /// The particles, structure of arrays, one element each.
    pub struct Particles(count): ParticlesAccess {
        /// World position.
        pos: [Vec2; count],
        /// Velocity, in units per second.
        vel: [Vec2; count],
        /// Steps left to live; 0 for a particle that is not shown.
        life: [u32; count],
        /// Kind of the enemy whose death made it (its colour).
        kind: [u32; count],
        /// Its owner slot's deaths (see [`Deaths::per_slot`](crate::sim::Deaths)) as it
        /// last saw them.
        seen: [u32; count],
    }
}

impl<M: ParticlesAccess> Particles<View, M>
where
    M::life: Readable,
{
    /// Number of particles.
    #[inline(always)]
    pub fn len(&self) -> u32 {
        self.life.len()
    }

    /// Whether there are none.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// How kills burst, in the kernels' terms (steps, per-step factors).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Burst {
    /// Particles per kill, 1 to [`MAX_PER_KILL`] (each particle's thread divides its index
    /// by it).
    pub per_kill: Divisor,
    /// Steps a particle lives at most (at least 1).
    pub lifetime: u32,
    /// Fastest speed a particle leaves with, relative to the enemy, in units per second.
    pub speed: f32,
    /// Factor a particle's velocity keeps each step (drag), in `(0, 1]`.
    pub keep: f32,
    /// Time step, in seconds.
    pub dt: f32,
    /// First enemy slot owning particles.
    pub first_slot: u32,
    /// One past the last enemy slot owning particles.
    pub end_slot: u32,
}

impl Burst {
    /// Particles the owners `first_slot .. end_slot` need.
    #[inline(always)]
    pub fn particles(&self) -> u32 {
        (self.end_slot - self.first_slot) * self.per_kill.get()
    }
}

access! {
    /// What the explosions read of the bodies: where a kill was, how fast, and of what kind.
    pub struct Bursting: BodiesAccess {
        pos: Read, vel: Read, force: Unused, dir: Unused, kind: Read, energy: Unused,
        mass: Unused, alive: Unused, state: Unused, age: Unused, prev: Unused, frozen: Unused,
        rng: Unused,
    }
}

kernel_args! {
    /// Arguments of [`burst_and_fade`].
    pub struct EffectsArgs {
        /// The bodies (read only).
        pub bodies: Bodies<View, Bursting>,
        /// Each kind's brain: only kinds with a machine burst.
        pub brains: DevSlice<Brain, Read>,
        /// Each slot's deaths so far (see [`Deaths::per_slot`](crate::sim::Deaths)).
        pub deaths: DevSlice<u32, Read>,
        /// The particles: born, moved and aged.
        pub particles: Particles,
        /// How kills burst.
        pub burst: Burst,
    }
}

/// Whether particle `p`, of the owner slot `slot`, sees a kill to burst from: its slot's
/// deaths changed since it last looked (which it notes), and of an enemy (a kind with a
/// machine).
#[inline(always)]
fn sees_a_kill(args: &EffectsArgs, p: u32, slot: u32) -> bool {
    let (deaths, seen) = (args.deaths.get(slot), args.particles.seen.get(p));
    if deaths == seen {
        return false;
    }
    args.particles.seen.set(p, deaths);
    args.brains.get(args.bodies.kind.get(slot)).machine != 0
}

/// A well-mixed 32-bit hash (a murmur-style finaliser): the particles' only randomness,
/// the same on every backend.
#[inline(always)]
pub fn mix(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// A number in `[0, 1)` from the top 24 bits of `h`.
#[inline(always)]
fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Thread `p`: particle `p` is born from its owner's death this step, or moves and fades.
///
/// A burst spreads its particles evenly around the circle (each jittered within its share),
/// at speeds from a third of [`Burst::speed`] to all of it, on top of a quarter of the
/// enemy's velocity; each lives from two thirds of [`Burst::lifetime`] to all of it.
#[inline(always)]
pub fn burst_and_fade(t: Thread, args: &EffectsArgs) {
    let p = t.global();
    let parts = &args.particles;
    if p >= parts.len() {
        return;
    }
    let burst = &args.burst;
    let slot = burst.first_slot + burst.per_kill.quotient(p);
    if slot < burst.end_slot && sees_a_kill(args, p, slot) {
        let b = &args.bodies;
        let pos = b.pos.get(slot);
        // Different for every particle and every death (the place of death varies).
        let seed = mix(p ^ mix(pos.x.to_bits() ^ mix(pos.y.to_bits())));
        let (h1, h2, h3) = (mix(seed ^ 1), mix(seed ^ 2), mix(seed ^ 3));
        let share = burst.per_kill.remainder(p) as f32 + unit(h1);
        let angle = share * (TAU / burst.per_kill.get() as f32);
        let speed = burst.speed * (1.0 + 2.0 * unit(h2)) * (1.0 / 3.0);
        let dir = Vec2::new(libm::cosf(angle), libm::sinf(angle));
        let life = burst.lifetime - (unit(h3) * (burst.lifetime / 3) as f32) as u32;
        parts.pos.set(p, pos);
        parts.vel.set(p, b.vel.get(slot) * 0.25 + dir * speed);
        parts.life.set(p, life.max(1));
        parts.kind.set(p, b.kind.get(slot));
        return;
    }
    let life = parts.life.get(p);
    if life == 0 {
        return;
    }
    let vel = parts.vel.get(p);
    parts.pos.set(p, parts.pos.get(p) + vel * burst.dt);
    parts.vel.set(p, vel * burst.keep);
    parts.life.set(p, life - 1);
}

/// How faded a particle with `life` steps left of at most `lifetime` is, from 0 (just born)
/// to `levels - 1` (about to go), in whole levels.
#[inline(always)]
pub fn fade_level(life: u32, lifetime: u32, levels: u32) -> u32 {
    let gone = lifetime.saturating_sub(life) as u64;
    ((gone * levels as u64) / lifetime.max(1) as u64).min(levels as u64 - 1) as u32
}
