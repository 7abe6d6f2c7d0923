//! The master thread (paper section 5): the game's sequential logic, run by one dedicated
//! thread in one-thread launches, [`master`] before the physics of each step and [`tally`]
//! after it, and the parallel [`births`] it orders.
//!
//! Why its own launch: everything it decides (slot allocation, spawn counts, score, game
//! over) must be made in one fixed order to stay deterministic, and every other kernel of the
//! step reads what it wrote. A launch boundary is the only barrier the design allows, so the
//! master thread gets a launch of its own, before the broad phase, rather than being thread 0
//! of a block whose other threads would have to wait for it.
//!
//! Its work is small on purpose: it moves the ship, fires at most one shot, writes how many
//! enemies of each kind to spawn ([`births`] brings them to life in parallel, each from its
//! own slot's generator), and, once the step's physics is done, counts.

use glam::Vec2;

use super::control::{DESTROYED, Events, Input, PLAYING, Status, TOO_SLOW};
use super::rules::{Rules, Wave};
use crate::sim::free_list::FreeSlots;
use crate::sim::scatter::{Place, birth, random_place};
use crate::sim::{Bodies, Contacts, KindInfo, SlotRange, Space};
use crate::{DevSlice, KernelArgs, Thread};

/// Arguments of [`master`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct MasterArgs {
    /// The bodies (the ship and new shots are written).
    pub bodies: Bodies,
    /// Kind table.
    pub kinds: DevSlice<KindInfo>,
    /// Slot range of each kind.
    pub ranges: DevSlice<SlotRange>,
    /// Free slots after the previous step.
    pub free: FreeSlots,
    /// This step's contacts (the ship's hits, for [`tally`]).
    pub contacts: Contacts,
    /// The game's state: read, advanced, written back (one element).
    pub status: DevSlice<Status>,
    /// This step's input (one element).
    pub input: DevSlice<Input>,
    /// Enemies spawned so far, per kind.
    pub spawned: DevSlice<u32>,
    /// Output: enemies to spawn this step, per kind (for [`births`]).
    pub births: DevSlice<u32>,
    /// Output: birth velocity deviation per kind, from the last due wave of the kind.
    pub birth_speed: DevSlice<f32>,
    /// The spawn schedule.
    pub waves: DevSlice<Wave>,
    /// The world.
    pub space: Space,
    /// The scene's rules.
    pub rules: Rules,
    /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
    pub reserved: u32,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for MasterArgs {}

/// The master thread before the physics (thread 0 only):
/// 1. at step 0, the ship is born in the middle of the world;
/// 2. the ship takes the input's movement as its velocity, and recovers energy;
/// 3. a shot leaves the ship along the aim if the fire key is held and the gun is ready,
///    in the shot kind's first free slot;
/// 4. the schedule's due waves claim free slots, in wave order, for [`births`].
///
/// After game over nothing moves, fires or spawns, and the status is left as it is.
#[inline(always)]
pub fn master(t: Thread, args: &MasterArgs) {
    if t.global() != 0 {
        return;
    }
    let (b, rules) = (&args.bodies, &args.rules);
    let mut st = args.status.get(0);
    for k in 0..args.births.len() {
        args.births.set(k, 0);
    }
    if st.is_over() {
        // The status stays as the last step left it, however many steps follow.
        return;
    }
    let input = args.input.get(0);
    st.events = Events::default();
    st.input = input;
    let step = st.step;
    let ship = rules.ship.start;
    if step == 0 {
        let place = Place {
            pos: args.space.size * 0.5,
            vel: Vec2::ZERO,
            facing: Vec2::X,
        };
        birth(b, &args.space, ship, place, rules.ship_energy);
    }
    if b.is_alive(ship) {
        fly_ship(args, &input, step);
        st.cooldown = st.cooldown.saturating_sub(1);
        if input.firing() && st.cooldown == 0 && args.free.count.get(rules.shot_kind) > 0 {
            fire(args, &input);
            st.cooldown = rules.fire_period;
            st.events.shots_fired = 1;
        }
    }
    // Spawns: each due wave takes what its kind has left.
    for w in 0..args.waves.len() {
        let wave = args.waves.get(w);
        if wave.due(step) {
            let k = wave.kind;
            let asked = args.births.get(k);
            let room = args.free.count.get(k) - asked;
            args.births.set(k, asked + wave.count.min(room));
            args.birth_speed.set(k, wave.speed);
            st.events.waves += u32::from(wave.count.min(room) > 0);
        }
    }
    for k in 0..args.births.len() {
        let n = args.births.get(k);
        // Saturates rather than wraps (after 4,294,967,295 spawns of one kind), so that the
        // dead counted from it never drop to 0.
        args.spawned.set(k, args.spawned.get(k).saturating_add(n));
        // At most the world's slots (2^24): no overflow.
        st.events.spawned += n;
    }
    args.status.set(0, st);
}

/// The master thread after the physics (thread 0 only), from the rebuilt free lists:
/// 1. counts and score: an enemy kind's dead are those spawned minus those alive, each
///    worth its birth energy; the kills and the score saturate at `u32::MAX` instead of
///    wrapping, and never go back (a saturated spawn count would undercount the dead);
/// 2. the ship's hits this step, the shots that struck an enemy (those that took damage:
///    obstacles such as crates do none), and where the ship is;
/// 3. the FPS meter from the ship's energy; game over below the minimum, or without a ship,
///    and then the world is frozen (see [`Bodies::frozen`]).
#[inline(always)]
pub fn tally(t: Thread, args: &MasterArgs) {
    if t.global() != 0 {
        return;
    }
    let (b, rules) = (&args.bodies, &args.rules);
    let mut st = args.status.get(0);
    if st.is_over() {
        return;
    }
    let (mut alive, mut killed, mut score) = (0u32, 0u32, 0u32);
    for k in 0..args.kinds.len() {
        let info = args.kinds.get(k);
        if info.dies_at_zero_energy() {
            continue;
        }
        let now = args.ranges.get(k).capacity - args.free.count.get(k);
        let dead = args.spawned.get(k).saturating_sub(now);
        // At most the world's slots (2^24): no overflow.
        alive += now;
        killed = killed.saturating_add(dead);
        // Birth energies are at least 1.
        score = score.saturating_add(dead.saturating_mul(info.energy as u32));
    }
    let killed = killed.max(st.enemies_killed);
    st.events.kills = killed - st.enemies_killed;
    st.enemies_alive = alive;
    st.enemies_killed = killed;
    st.score = score.max(st.score);
    let shots = args.ranges.get(rules.shot_kind);
    st.shots_alive = shots.capacity - args.free.count.get(rules.shot_kind);
    // Summed in slot order over the kind's range (a few dozen slots): the same on every
    // schedule.
    st.events.shot_hits = (shots.start..shots.start + shots.capacity)
        .map(|slot| u32::from(args.contacts.damage.get(slot) > 0))
        .sum();
    let ship = rules.ship.start;
    let ship_alive = b.is_alive(ship);
    st.events.ship_hits = if ship_alive {
        args.contacts.count.get(ship)
    } else {
        0
    };
    if ship_alive {
        st.ship = b.pos.get(ship);
    }
    let energy = if ship_alive { b.energy.get(ship) } else { 0 };
    st.fps_meter = rules.fps_meter(energy);
    st.game_over = if !ship_alive {
        DESTROYED
    } else if st.fps_meter < rules.fps_min {
        TOO_SLOW
    } else {
        PLAYING
    };
    st.step = st.step.saturating_add(1);
    args.status.set(0, st);
    if st.is_over() {
        b.frozen.set(0, 1);
    }
}

/// The ship goes where the stick points, at the scene's speed, and recovers energy.
#[inline(always)]
fn fly_ship(args: &MasterArgs, input: &Input, step: u32) {
    let (b, rules) = (&args.bodies, &args.rules);
    let ship = rules.ship.start;
    b.vel.set(ship, input.movement() * rules.ship_speed);
    b.force.set(ship, Vec2::ZERO);
    if rules.recover_every != 0 && step.is_multiple_of(rules.recover_every) {
        // A ship at the largest energy allowed (i32::MAX) stays there, rather than wrapping
        // to the most negative and dying.
        let energy = b.energy.get(ship);
        b.energy
            .set(ship, energy.saturating_add(1).min(rules.ship_energy));
    }
}

/// A shot in the first free slot of the shot kind, just outside the ship along the aim.
#[inline(always)]
fn fire(args: &MasterArgs, input: &Input) {
    let (b, rules) = (&args.bodies, &args.rules);
    let ship = rules.ship.start;
    let shot = args.kinds.get(rules.shot_kind);
    let slot = args.free.list.get(args.ranges.get(rules.shot_kind).start);
    let aim = input.aim_dir();
    let gap = args.kinds.get(rules.ship_kind).radius + shot.radius;
    let pos = b.pos.get(ship) + aim * (gap * 1.01);
    let place = Place {
        pos,
        vel: aim * rules.shot_speed,
        facing: aim,
    };
    birth(b, &args.space, slot, place, shot.energy);
}

/// Arguments of [`births`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct BirthArgs {
    /// The bodies.
    pub bodies: Bodies,
    /// Kind table (birth energies).
    pub kinds: DevSlice<KindInfo>,
    /// Slot range of each kind.
    pub ranges: DevSlice<SlotRange>,
    /// The free lists the master thread counted from.
    pub free: FreeSlots,
    /// Bodies to spawn per kind (from [`master`]).
    pub births: DevSlice<u32>,
    /// Birth velocity deviation per kind (from [`master`]).
    pub birth_speed: DevSlice<f32>,
    /// The world.
    pub space: Space,
    /// The ship's slot and the spawn distance.
    pub rules: Rules,
    /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
    pub reserved: u32,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for BirthArgs {}

/// Tries at a position far enough from the ship before the last one is taken as it is.
pub const PLACE_TRIES: u32 = 8;

/// Thread `j` looks at free-list entry `j`: it lies in some kind's range, and if it is among
/// the first `births[kind]` entries there, that slot comes alive at a random place at least
/// the spawn distance from the ship (up to [`PLACE_TRIES`] draws from the slot's generator).
#[inline(always)]
pub fn births(t: Thread, args: &BirthArgs) {
    let b = &args.bodies;
    let j = t.global();
    if j >= b.slots() {
        return;
    }
    let kind = b.kind.get(j);
    let range = args.ranges.get(kind);
    if j < range.start || j - range.start >= args.births.get(kind) {
        return;
    }
    let slot = args.free.list.get(j);
    let ship = args.rules.ship.start;
    let ship_pos = b.pos.get(ship);
    let far = args.rules.spawn_distance * args.rules.spawn_distance;
    let speed = args.birth_speed.get(kind);
    let mut place = random_place(b, slot, &args.space, speed);
    let mut tries = 1;
    while tries < PLACE_TRIES
        && b.is_alive(ship)
        && args.space.offset(ship_pos, place.pos).length_squared() < far
    {
        place = random_place(b, slot, &args.space, speed);
        tries += 1;
    }
    birth(b, &args.space, slot, place, args.kinds.get(kind).energy);
}
