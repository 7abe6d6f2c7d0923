//! The AI step (paper section 7): each enemy looks around through the broad-phase grid,
//! moves its finite-state machine ([`super::fsm`]) one step, and acts: a steering force for
//! the integrator, and, for the tricky kind, energy recovered while escaping.
//!
//! One launch for every enemy kind, over the slots from the first enemy kind's to the last's:
//! kinds own ranges aligned to 32 slots, so a warp runs one kind's machine (the paper's
//! grouped warps), and the kinds' machines run side by side rather than one launch after
//! another. Threads in slot order keep each body's own reads and writes coalesced; in large
//! worlds the bodies are renumbered in the grid's order every few steps
//! ([`crate::sim::renumber`]), so that neighbouring threads also look at neighbouring places
//! (running threads in grid order without moving the bodies was slower: 6.6 ms against
//! 4.6 ms at 16 million bodies on the H200, each body's own state then read out of order).
//! In a small world the kinds that expect many neighbours get a team of lanes a body
//! ([`crate::sim::teams`]), which looks around together and leaves the machine to its first
//! lane. It runs after the narrow phase, so that a hit is seen in the step it happens. Where
//! the kinds that walk their neighbours lie at the end of its slots, the launch takes its
//! blocks from the last ([`ThinkArgs::from_the_end`]), so that its longest warps start first
//! rather than leave the GPU to a few of them at its end.

use glam::Vec2;

use super::control::Status;
use super::fsm::{Machine, Percept, State, next_state};
use super::rules::Brain;
use crate::access::{Read, Write};
use crate::data::{Restrict, View};
use crate::elementary;
use crate::exec::{follow_previous_launch, unseen};
use crate::math::{self, trunc_i32};
use crate::rng::Drawing;
use crate::sim::broad::{CellIndex, Near, Sample, kind_bit};
use crate::sim::free_list::Marks;
use crate::sim::integrate::{Field, IntegrateArgs, integrate_slot};
use crate::sim::narrow::{CollideArgs, Relaxation, collide_slot};
use crate::sim::teams::Teams;
use crate::sim::{Bodies, BodiesAccess, Contacts, Deaths, KindInfo, SlotKind, Space};
use crate::warp::{Handed, Team};
use crate::{DevSlice, Thread, access, asked, kernel_args};

/// Seconds a steering force takes to bring the velocity to the wanted one.
pub const STEER_TIME: f32 = 0.25;
/// A shot is a threat if it will pass closer than this many of the body's radii.
pub const DANGER_RADII: f32 = 3.0;
/// ... within this many seconds.
pub const DANGER_TIME: f32 = 1.0;
/// Wandering bodies cruise at this fraction of their speed.
pub const WANDER_SPEED: f32 = 0.5;
/// Standard deviation of a wandering body's turn, in radians per step.
pub const WANDER_TURN: f32 = 0.2;
/// Bodies of a group keep this many radii apart.
pub const PERSONAL_SPACE_RADII: f32 = 3.0;

access! {
    /// What the machines do with the bodies: set their states, forces and energies, let
    /// them die, and draw from their generators.
    pub struct Thinking: BodiesAccess {
        pos: Read, vel: Read, force: Write, dir: Read, kind: Read, energy: Write, mass: Read,
        alive: Write, state: Write, age: Read, prev: Read, frozen: Read, rng: Drawing,
    }
}

access! {
    /// What a body's whole step in one launch does with the bodies: what the narrow phase
    /// ([`Colliding`](crate::sim::narrow::Colliding)), the machines ([`Thinking`]) and the
    /// integrator ([`Moving`](crate::sim::integrate::Moving)) do.
    pub struct Stepping: BodiesAccess {
        pos: Write, vel: Write, force: Write, dir: Write, kind: Read, energy: Write,
        mass: Read, alive: Write, state: Write, age: Write, prev: Write, frozen: Read,
        rng: Drawing,
    }
}

kernel_args! {
    /// Arguments of [`think`].
    pub struct ThinkArgs {
        /// The bodies (force, state, energy and liveness of the enemies are written).
        pub bodies: Bodies<View, Thinking>,
        /// Kind table.
        pub kinds: DevSlice<KindInfo, Read>,
        /// The world and its grid.
        pub space: Space,
        /// This step's grid.
        pub grid: CellIndex,
        /// This step's narrow-phase results (the hits).
        pub contacts: Contacts<View, Read>,
        /// Each kind's brain (machine 0 for kinds without one).
        pub brains: DevSlice<Brain, Read>,
        /// Each warp's first slot and team width ([`Teams::warp_table`]; empty where every
        /// body gets one thread).
        pub warps: DevSlice<u32, Read>,
        /// How many threads each kind's bodies get, from the first kind with a machine to
        /// the last.
        pub teams: Teams,
        /// The game's state: where the ship is as this step's grid was built (its
        /// [`Status::ship`], one element).
        pub status: DevSlice<Status, Read>,
        /// The ship's slot.
        pub ship: u32,
        /// The kind of the ship's shots.
        pub shot_kind: u32,
        /// Nonzero: the launch takes its blocks from the last (see [`Thread::from_last_block`]),
        /// so that the kinds at the end of its slots start first.
        pub from_the_end: u32,
        /// Keeps the struct free of implicit padding.
        pub reserved: u32,
        /// Where the deaths are counted.
        pub deaths: Deaths,
    }
}

/// What a body sees within its vision radius.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sight {
    /// Offset to the ship, if seen.
    pub ship: Option<Vec2>,
    /// Mean offset to the visible bodies of its own kind, if any.
    pub group: Option<Vec2>,
    /// Sum of unit offsets away from own-kind bodies inside its personal space.
    pub crowd: Vec2,
    /// Which way to step out of the most imminent shot's path, if one is coming.
    pub dodge: Option<Vec2>,
}

/// Where a shot at offset `d` with velocity `rel` relative to a body of radius `radius` will
/// pass: the unit direction to step away from its path, if it comes within
/// [`DANGER_RADII`] radii in less than [`DANGER_TIME`], with the time it takes.
#[inline(always)]
pub fn threat(d: Vec2, rel: Vec2, radius: f32) -> Option<(f32, Vec2)> {
    let closing = d.dot(rel);
    let speed2 = rel.length_squared();
    if closing >= 0.0 || speed2 <= 0.0 {
        return None;
    }
    let time = -closing / speed2;
    let miss = d + rel * time;
    let danger = DANGER_RADII * radius;
    if time >= DANGER_TIME || miss.length_squared() >= danger * danger {
        return None;
    }
    // Step away from the point of closest approach; dead-on, step to the shot's left.
    let away = math::try_normalize(-miss).unwrap_or(math::normalize_or_zero(rel.perp()));
    Some((time, away))
}

/// What a lane has seen of a body's surroundings, as sums that come out the same in any
/// order (so that a team's lanes can each look at a share of the bodies and merge): the
/// offsets in fixed point, whose integer sums are exact, and the soonest threat as the
/// least key. The ship's offset and the threat's way out are worked out again once the
/// look is over, from the same positions, so that the walk keeps fewer registers (the
/// one-thread `think` spills at its 56).
#[derive(Clone, Copy)]
struct Seen {
    /// The ship's grid entry plus one once it is seen, else 0.
    ship_seen: u32,
    /// Bodies of its own kind seen, each of a crowd's sample counted as many as it stands
    /// for (its weight).
    similar: u32,
    /// The sum of the offsets to them, weighted likewise, in units of `1 / scale` (see
    /// [`fixed_scale`]).
    sum: [i64; 2],
    /// The sum of the unit offsets to those inside its personal space, weighted likewise,
    /// in units of [`UNIT_SCALE`]`⁻¹`.
    crowd: [i64; 2],
    /// The soonest threat's seconds to its closest approach (as bits) above its slot;
    /// `u64::MAX` for none. Ties go to the lower slot.
    threat: u64,
    /// The soonest threat's grid entry (kept where bodies move in the launch that looks:
    /// see [`CellIndex::vel`]).
    threat_entry: u32,
}

impl Seen {
    /// Nothing seen.
    const NONE: Seen = Seen {
        ship_seen: 0,
        similar: 0,
        sum: [0; 2],
        crowd: [0; 2],
        threat: u64::MAX,
        threat_entry: 0,
    };

    /// What `self` and `other` saw together: the same whichever is which.
    #[inline(always)]
    fn merge(self, other: Seen) -> Seen {
        Seen {
            ship_seen: self.ship_seen.max(other.ship_seen),
            similar: self.similar.wrapping_add(other.similar),
            sum: add_fixed(self.sum, other.sum),
            crowd: add_fixed(self.crowd, other.crowd),
            threat: self.threat.min(other.threat),
            // The keys' slots are distinct: the same entry whichever is which.
            threat_entry: match other.threat < self.threat {
                true => other.threat_entry,
                false => self.threat_entry,
            },
        }
    }
}

impl Handed for Seen {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        let pair = |v: [i64; 2]| {
            [
                v[0].shuffle_from(source, members),
                v[1].shuffle_from(source, members),
            ]
        };
        Seen {
            ship_seen: self.ship_seen.shuffle_from(source, members),
            similar: self.similar.shuffle_from(source, members),
            sum: pair(self.sum),
            crowd: pair(self.crowd),
            threat: self.threat.shuffle_from(source, members),
            threat_entry: self.threat_entry.shuffle_from(source, members),
        }
    }
}

/// The fixed-point scale of unit vectors' components: 2³⁰.
const UNIT_SCALE: f32 = (1u32 << 30) as f32;

/// The power of two that scales a component of at most `bound` in magnitude to below
/// 2³⁰, so that 2³² of them sum exactly in an `i64` (the finest such scale: `bound`'s
/// resolution is kept down to 2⁻²⁹ of it).
#[inline(always)]
pub fn fixed_scale(bound: f32) -> f32 {
    // `bound` lies in [2^(e - 1), 2^e) for a normal number.
    let e = ((bound.to_bits() >> 23) & 0xff) as i32 - 126;
    let exponent = (30 - e).clamp(-126, 127);
    f32::from_bits(((exponent + 127) as u32) << 23)
}

/// `v` in fixed point at `scale` (truncated, saturated, NaN to 0: see
/// [`crate::math::trunc_i32`]). A component below 2³⁰ at `scale` fits an `i32`, whose
/// conversion the GPU does at full rate (to an `i64` it costs several times more).
#[inline(always)]
fn fixed(v: Vec2, scale: f32) -> [i64; 2] {
    [
        i64::from(trunc_i32(v.x * scale)),
        i64::from(trunc_i32(v.y * scale)),
    ]
}

/// The sum of two fixed-point vectors (wrapping, so exact in any order).
#[inline(always)]
fn add_fixed(a: [i64; 2], b: [i64; 2]) -> [i64; 2] {
    [a[0].wrapping_add(b[0]), a[1].wrapping_add(b[1])]
}

/// `v` counted `weight` times (exact: a component below 2³⁰ times a weight below 2³² fits);
/// a weight of 1, every body outside a crowd, needs no product.
#[inline(always)]
fn weighted(v: [i64; 2], weight: u32) -> [i64; 2] {
    if weight == 1 {
        return v;
    }
    let w = i64::from(weight);
    [v[0].wrapping_mul(w), v[1].wrapping_mul(w)]
}

/// `v` back from fixed point at `scale`.
#[inline(always)]
fn unfixed(v: [i64; 2], scale: f32) -> Vec2 {
    Vec2::new(v[0] as f32, v[1] as f32) * (1.0 / scale)
}

/// The kinds a `machine` body driven by `brain` looks for (bit `k`: kind `k`): the ship's,
/// and unless it is a kamikaze its own kind and, if it avoids bullets, the shots'.
#[inline(always)]
pub fn sight_mask(brain: &Brain, machine: Machine, ship_kind: u32, shot_kind: u32) -> u32 {
    kind_bit(ship_kind) | others_mask(brain, machine, shot_kind)
}

/// The kinds of [`sight_mask`] but the ship's: those a body finds by walking the grid where
/// it looks at the ship directly (see [`look`]).
#[inline(always)]
pub fn others_mask(brain: &Brain, machine: Machine, shot_kind: u32) -> u32 {
    let mut mask = 0;
    if machine != Machine::Kamikaze {
        mask |= kind_bit(brain.kind);
        if brain.avoid_bullets != 0 {
            mask |= kind_bit(shot_kind);
        }
    }
    mask
}

/// A body about to look around: what [`think`] reads of it before it does.
#[derive(Clone, Copy, Debug)]
pub struct Looker {
    /// Its slot.
    pub slot: u32,
    /// Where it is.
    pub pos: Vec2,
    /// Its velocity.
    pub vel: Vec2,
    /// Its kind's radius.
    pub radius: f32,
    /// The ship's kind.
    pub ship_kind: u32,
}

/// What `looker`, a `machine` body driven by `brain`, finds in the grid, for
/// [`Glance::sight`] to finish: only bodies within its vision,
/// found through the grid's 3×3 neighbourhood by its `team` (every lane gets the same). A
/// kamikaze looks only for the ship. With `MOVING` (bodies move in the launch that looks),
/// the others' places and velocities come from the grid's entries.
///
/// `DIRECT`: the walk has no cap (`args.grid.cap == 0`). Then the ship is not walked for:
/// it is looked at where the status says it was as the grid was built. The grid's cells
/// are no narrower than the widest vision, so a ship in sight lies in the block the walk
/// reads: the walk would find it exactly when this check does (it is in the grid whenever
/// a body thinks, since a step without a live ship is frozen), and a kamikaze walks
/// nothing at all. And the looker counts its own entry among its kind's by place alone,
/// and takes it off after the walk ([`CellIndex::own_weight`]): a living body is in the
/// step's grid, at the very place it looks from (nothing revives or moves a body between
/// the grid's build and its look). Under a cap, which may stop the walk before the
/// looker's entry, its entry is told apart by its slot as the walk meets it.
#[inline(always)]
pub fn look<const MOVING: bool, const DIRECT: bool>(
    args: &ThinkArgs,
    brain: &Brain,
    machine: Machine,
    looker: &Looker,
    team: Team,
) -> Glance {
    let b = &args.bodies;
    let Looker {
        slot,
        pos,
        vel,
        radius,
        ship_kind,
    } = *looker;
    let vision2 = brain.vision * brain.vision;
    let personal = PERSONAL_SPACE_RADII * radius;
    let social = machine != Machine::Kamikaze;
    let dodges = social && brain.avoid_bullets != 0;
    let scale = fixed_scale(brain.vision);
    let direct = DIRECT;
    debug_assert_eq!(direct, args.grid.cap == 0);
    let mask = match direct {
        true => others_mask(brain, machine, args.shot_kind),
        false => sight_mask(brain, machine, ship_kind, args.shot_kind),
    };
    // A body looked at by one thread reads only the rows and columns its vision reaches,
    // since every body it counts lies within it; a team reads the whole block (reading
    // less made `think` slower for teams: `paper` 14.8 -> 17.2 µs on an H200). The sight
    // budget samples the whole block's runs, so a look under one keeps them all.
    let alone = team.width() == 1;
    let near = Near {
        pos,
        reach: (alone && brain.sight_budget == 0).then_some(brain.vision),
        mask,
    };
    // A crowd within the budget, each body taking a share that depends on its slot.
    let sample = Sample {
        budget: brain.sight_budget,
        phase: slot,
    };
    // The walk's closure takes its values by copy: borrowed, the CPU emulation read each
    // through a reference at every entry (`scale-1m` 3% slower there; the PTX is the same).
    let grid = &args.grid;
    let mut seen = grid.merge_near_in(
        team,
        &args.space,
        (near, sample, brain.kind),
        Seen::NONE,
        move |mut seen, weight, kind, at, entry| {
            let offset = args.space.offset(pos, at);
            let dist2 = offset.length_squared();
            if dist2 > vision2 {
                return seen;
            }
            // A body of its own kind (never the ship's, which has no machine) counts, the
            // looker itself too where the walk has no cap: it is taken off after the walk
            // (its slot read only where the offset is zero, a wait for memory a few lanes
            // of a warp at a time, cost `scale-1m` 1% on an H100). Under a cap it is left
            // out here, its slot read only where the offset is zero (or not a number), as
            // the looker's own is.
            if social && kind == brain.kind {
                // Zero or not a number, the looker's own offset: not greater than zero.
                #[allow(clippy::neg_cmp_op_on_partial_ord)]
                if !direct && !(dist2 > 0.0) && grid.slots.get(entry) == slot {
                    return seen;
                }
                // A neighbour of a crowd's sample stands for `weight` of them.
                seen.similar = seen.similar.wrapping_add(weight);
                seen.sum = add_fixed(seen.sum, weighted(fixed(offset, scale), weight));
                // (An offset of zero, the looker's own, would add nothing.)
                if dist2 > 0.0 && dist2 < personal * personal {
                    let away = fixed(math::normalize_or_zero(offset), UNIT_SCALE);
                    seen.crowd = add_fixed(seen.crowd, weighted(away, weight));
                }
                return seen;
            }
            let other = grid.slots.get(entry);
            if other == slot {
                return seen;
            }
            if other == args.ship {
                seen.ship_seen = entry + 1;
            } else if dodges
                && kind == args.shot_kind
                && let Some((time, _)) = threat(
                    offset,
                    args.grid.vel_at::<MOVING>(entry, other, &b.vel) - vel,
                    radius,
                )
                && time >= 0.0
            {
                // Seconds ahead are positive, so their bits order as they do (NaN, never).
                let key = u64::from(time.to_bits()) << 32 | u64::from(other);
                if key < seen.threat {
                    seen.threat = key;
                    seen.threat_entry = entry;
                }
            }
            seen
        },
        Seen::merge,
    );
    // The looker counted itself among its own kind (its offset: zero, adding nothing to
    // the sums), as often as the sample took its entry.
    if direct && social {
        let own = grid.own_weight(&args.space, (near, sample), brain.kind, slot);
        seen.similar = seen.similar.wrapping_sub(own);
    }
    Glance { seen, direct }
}

/// What a [`look`] found in its walk, before the reads that finish it ([`Glance::sight`]):
/// apart, so that a body asks for its own state before it waits for those.
#[derive(Clone, Copy)]
pub struct Glance {
    seen: Seen,
    /// Whether the walk had no cap (`DIRECT` in [`look`]).
    direct: bool,
}

impl Glance {
    /// What `looker`, driven by `brain`, sees, from what its look found (`MOVING` as in
    /// [`look`]): the ship where the walk had no cap (the status read now, not held across
    /// the walk), and the soonest threat's place and velocity.
    #[inline(always)]
    pub fn sight<const MOVING: bool>(
        &self,
        args: &ThinkArgs,
        brain: &Brain,
        looker: &Looker,
    ) -> Sight {
        let (b, grid, seen) = (&args.bodies, &args.grid, &self.seen);
        // From the brain, so that the glance carries only what the walk found.
        let (vision2, scale) = (brain.vision * brain.vision, fixed_scale(brain.vision));
        let Looker {
            slot,
            pos,
            vel,
            radius,
            ..
        } = *looker;
        // Where the bodies move in this launch, from the grid's entries, as the look measured;
        // else from the bodies, which have not moved since the grid was built.
        // (A branch, not a closure: LLVM left such a closure out of line, its captures in
        // local memory, once `look` grew.)
        let dodge = if seen.threat != u64::MAX {
            let (entry, other) = (seen.threat_entry, seen.threat as u32);
            let at = if MOVING {
                grid.pos.get(entry)
            } else {
                b.pos.get(other)
            };
            let offset = args.space.offset(pos, at);
            let rel = grid.vel_at::<MOVING>(entry, other, &b.vel) - vel;
            Some(threat(offset, rel, radius).map_or(Vec2::ZERO, |(_, away)| away))
        } else {
            None
        };
        let ship = if self.direct {
            let offset = args.space.offset(pos, args.status.get(0).ship);
            (slot != args.ship && offset.length_squared() <= vision2).then_some(offset)
        } else {
            let at = |entry: u32| match MOVING {
                true => grid.pos.get(entry),
                false => b.pos.get(args.ship),
            };
            (seen.ship_seen != 0).then(|| args.space.offset(pos, at(seen.ship_seen - 1)))
        };
        Sight {
            ship,
            group: (seen.similar > 0).then(|| unfixed(seen.sum, scale) / seen.similar as f32),
            crowd: -unfixed(seen.crowd, UNIT_SCALE),
            dodge,
        }
    }
}

/// The velocity a body in `state` wants, and the wandering heading it keeps (its slot's
/// generator at `position` if read already: see
/// [`crate::rng::streams::RngStreams::position`]).
#[inline(always)]
fn wanted_velocity(
    args: &ThinkArgs,
    brain: &Brain,
    (slot, position): (u32, Option<u32>),
    state: State,
    sight: &Sight,
) -> Vec2 {
    let b = &args.bodies;
    let speed = brain.speed;
    let toward = |d: Option<Vec2>| d.and_then(math::try_normalize);
    match state {
        State::Attacking => toward(sight.ship).unwrap_or(Vec2::ZERO) * speed,
        State::AvoidingBullets => sight.dodge.unwrap_or(Vec2::ZERO) * speed,
        State::Grouping => {
            let to_group = toward(sight.group).unwrap_or(Vec2::ZERO);
            math::normalize_or_zero(to_group + sight.crowd) * (WANDER_SPEED * speed)
        }
        State::Escaping => {
            let away = toward(sight.ship.map(|d| -d)).unwrap_or(b.dir.get(slot));
            away * speed
        }
        State::CheckingEnergy | State::Dead => b.vel.get(slot),
        State::Wandering => {
            // Asked for with the generator's position, not after its words are written back
            // (which the load could not then pass): one wait for memory, not two.
            let dir = asked(b.dir.get(slot));
            let turn = match position {
                Some(position) => b.rng.open_at(slot, position).next_normal(),
                None => b.rng.open(slot).next_normal(),
            };
            let (sin, cos) = elementary::sin_cos(turn * WANDER_TURN);
            let rotation = Vec2::new(cos, sin);
            let heading = rotation.rotate(dir);
            heading * (WANDER_SPEED * speed)
        }
    }
}

/// Each slot of the kinds with a machine gets its team of threads (see [`Teams`]) and, if a
/// body of a kind with a machine lives there, runs that machine on it: perceive (the team),
/// transition and act (its first lane).
#[inline(always)]
pub fn think(t: Thread, args: &ThinkArgs) {
    think_with::<false>(t, args);
}

/// [`think`] for teams wider than one thread: a kernel of its own, so that the one-thread
/// kernel carries none of the teams' code (and registers).
#[inline(always)]
pub fn think_in_teams(t: Thread, args: &ThinkArgs) {
    think_with::<true>(t, args);
}

#[inline(always)]
fn think_with<const TEAMS: bool>(t: Thread, args: &ThinkArgs) {
    let t = match args.from_the_end {
        0 => t,
        _ => t.from_last_block(),
    };
    if let Some((slot, team)) = args.teams.member(t, &args.warps) {
        think_slot::<TEAMS, false>(args, slot, team, None);
    }
}

/// What a slot's machine reads of the world's own tables, which no step writes: its kind
/// with the kind's entry and brain (read before a launch waits for the one before it).
#[derive(Clone, Copy)]
struct Known {
    kind: SlotKind,
    brain: Brain,
}

impl Known {
    /// Slot `slot`'s.
    #[inline(always)]
    fn read(args: &ThinkArgs, slot: u32) -> Known {
        let kind = SlotKind::read(&args.bodies, &args.kinds, slot);
        Known {
            kind,
            brain: asked(args.brains.get(kind.kind)),
        }
    }
}

kernel_args! {
    /// Arguments of [`collide_think_integrate`].
    pub struct BodyStepArgs {
        /// The machines' arguments; their teams span every kind (a kind with a machine
        /// keeps its machine's width, the others take their narrow phase's), and their grid
        /// keeps its entries' velocities ([`CellIndex::vel`]).
        pub think: ThinkArgs,
        /// The bodies, as the whole step uses them (the narrow phase's and the integrator's
        /// views of them are these, narrowed).
        pub bodies: Bodies<View, Stepping>,
        /// The contacts, which the narrow phase writes and the machines and the integrator
        /// read.
        pub contacts: Contacts,
        /// How the narrow phase combines a body's pushes.
        pub relax: Relaxation,
        /// The force field.
        pub field: Field,
        /// The time step of the step's first substep.
        pub dt: f32,
        /// The integrator (see [`crate::sim::integrate`]).
        pub integrator: u32,
        /// The narrow phase's budget (see [`CollideArgs::budget`]).
        pub contact_budget: u32,
        /// Keeps the struct free of implicit padding.
        pub reserved: u32,
    }
}

/// Every body's step but the grid in one launch, for worlds without rectangles: each slot
/// of every kind gets its team, which finds the slot's contacts and their response
/// ([`collide_slot`]), runs the machine of a body of a kind with one, and moves the body
/// ([`integrate_slot`], its first lane). The results are those of the three launches one
/// after the other, bit for bit: a team reads of its own body what it has itself just
/// written (hits, energy, force), and of the others only what nothing in the launch writes
/// (masses, kinds, the grid's entries with their places and velocities as the grid was
/// built), never the places and velocities that their own teams change meanwhile.
#[inline(always)]
pub fn collide_think_integrate(t: Thread, args: &BodyStepArgs) {
    body_step::<false, false>(t, args);
}

/// [`collide_think_integrate`] for worlds with swept pairs (see
/// [`crate::sim::KindInfo::swept_kinds`]).
#[inline(always)]
pub fn collide_think_integrate_swept(t: Thread, args: &BodyStepArgs) {
    body_step::<true, false>(t, args);
}

/// [`collide_think_integrate`] that logs every contact it counts (audit runs only: see
/// [`crate::sim::Contacts::log`]).
#[inline(always)]
pub fn collide_think_integrate_logged(t: Thread, args: &BodyStepArgs) {
    body_step::<false, true>(t, args);
}

/// [`collide_think_integrate_swept`] that logs its contacts.
#[inline(always)]
pub fn collide_think_integrate_swept_logged(t: Thread, args: &BodyStepArgs) {
    body_step::<true, true>(t, args);
}

/// [`collide_think_integrate`], its narrow phase with swept pairs if `SWEPT`, logging its
/// contacts if `LOGGED`.
#[inline(always)]
fn body_step<const SWEPT: bool, const LOGGED: bool>(t: Thread, args: &BodyStepArgs) {
    let think = &args.think;
    // The thread's slot and its kind's tables are the world's: read while the grid's last
    // launch ends.
    let member = think.teams.member(t, &think.warps);
    let known = member.map(|(slot, _)| Known::read(think, slot));
    follow_previous_launch();
    let (Some((slot, team)), Some(known)) = (member, known) else {
        return;
    };
    let collide = CollideArgs {
        bodies: args.bodies.restrict(),
        kinds: think.kinds,
        warps: think.warps,
        teams: think.teams,
        space: think.space,
        grid: think.grid,
        contacts: args.contacts,
        relax: args.relax,
        substep: 0,
        budget: args.contact_budget,
    };
    collide_slot::<false, true, SWEPT, LOGGED>(&collide, slot, team, |_| known.kind.info);
    think_slot::<true, true>(think, slot, team, Some(known));
    if team.leads() && slot < think.bodies.slots() {
        let integrate = IntegrateArgs {
            bodies: args.bodies.restrict(),
            kinds: think.kinds,
            contacts: args.contacts.restrict(),
            space: think.space,
            field: args.field,
            dt: args.dt,
            integrator: args.integrator,
            deaths: think.deaths,
            substep: 0,
            from_the_end: 0,
            marks: Marks::NONE,
        };
        integrate_slot(&integrate, slot);
    }
}

/// `glance` and, where the bodies move in the launch that looks (`MOVING`), the sight it
/// makes for `looker`, driven by `brain`, at once (see [`think_as`]).
#[inline(always)]
fn sight_first<const MOVING: bool>(
    glance: Glance,
    args: &ThinkArgs,
    brain: &Brain,
    looker: &Looker,
) -> (Glance, Option<Sight>) {
    let sight = match MOVING {
        true => Some(glance.sight::<MOVING>(args, brain, looker)),
        false => None,
    };
    (glance, sight)
}

/// Slot `slot`'s share of [`think`], by its `team` (given what it reads of the world's
/// tables, if read already: `known`): if a body of a kind with a machine lives there,
/// perceive (the team), transition and act (its first lane); `MOVING` as in [`look`].
#[inline(always)]
fn think_slot<const TEAMS: bool, const MOVING: bool>(
    args: &ThinkArgs,
    slot: u32,
    team: Team,
    known: Option<Known>,
) {
    // Without teams the width is known to be 1, and the teams' code compiles out.
    let team = if TEAMS { team } else { Team::ALONE };
    let b = &args.bodies;
    // Asked for at once, before the branches they decide: the thread waits for memory
    // once, not once a branch (and once more for its kind's tables, unless known).
    let [alive, kind, frozen, ship_kind] = asked([
        b.alive.get(slot),
        b.kind.get(slot),
        b.frozen.get(0),
        b.kind.get(args.ship),
    ]);
    let [pos, vel] = asked([b.pos.get(slot), b.vel.get(slot)]);
    if alive == 0 || frozen != 0 {
        return;
    }
    // A kind's brain is the kind's (`brain.kind == kind`).
    let (info, brain) = match known {
        Some(known) => (known.kind.info, known.brain),
        None => (args.kinds.get(kind), asked(args.brains.get(kind))),
    };
    let radius = asked(info.reach);
    let looker = Looker {
        slot,
        pos,
        vel,
        radius,
        ship_kind,
    };
    match Machine::from_u32(brain.machine) {
        Machine::Kamikaze => {
            think_as::<{ Machine::Kamikaze as u32 }, MOVING>(args, &brain, &looker, team)
        }
        Machine::Group => {
            think_as::<{ Machine::Group as u32 }, MOVING>(args, &brain, &looker, team)
        }
        Machine::Tricky => {
            think_as::<{ Machine::Tricky as u32 }, MOVING>(args, &brain, &looker, team)
        }
        Machine::None => {}
    }
}

/// One body, `looker`, of a `MACHINE` kind driven by `brain`: perceive, transition, act.
#[inline(always)]
fn think_as<const MACHINE: u32, const MOVING: bool>(
    args: &ThinkArgs,
    brain: &Brain,
    looker: &Looker,
    team: Team,
) {
    let b = &args.bodies;
    let machine = Machine::from_u32(MACHINE);
    // Without a cap, a walk of its own (see `look`). Where the sight comes first (see
    // below), each walk's is finished in its own arm, where the cap is known: finished
    // once after the two, `paper` ran 1.1% slower on an H200.
    let (glance, sight_first) = match args.grid.cap {
        0 => sight_first::<MOVING>(
            look::<MOVING, true>(args, brain, machine, looker, team),
            args,
            brain,
            looker,
        ),
        _ => sight_first::<MOVING>(
            look::<MOVING, false>(args, brain, machine, looker, team),
            args,
            brain,
            looker,
        ),
    };
    if !team.leads() {
        return;
    }
    let slot = looker.slot;
    // The kind's brain and birth energy read again, asked for with the body's state: those
    // read before the look were held across the walk, which spilled them at 56 registers.
    // Where the bodies move in the launch that looks (a small world, whose step waits on
    // latency), the sight is finished before the body's state is asked for; else the state
    // and the generator's position are asked for first, so that a wandering body waits for
    // them with the ship's place and the threat's, and for its generator's words after,
    // not for each in turn (1M +1.1% on an H200; a small world's `paper` lost 1.4% so).
    let kind = unseen(brain.kind);
    let brain = &asked(args.brains.get(kind));
    let full = asked(args.kinds.get(kind).energy);
    // The mass is asked for with the state, not after the state and the generator are
    // written back (which its load could not then pass): one wait for memory, not two.
    let [energy, damage] = asked([b.energy.get(slot), args.contacts.damage.get(slot)]);
    let state = asked(b.state.get(slot));
    let mass = asked(b.mass.get(slot));
    let position = match MOVING {
        true => None,
        false => Some(asked(b.rng.position(slot))),
    };
    let sight = match sight_first {
        Some(sight) => sight,
        None => glance.sight::<MOVING>(args, brain, looker),
    };
    let percept = Percept {
        hit: damage > 0,
        out_of_energy: energy <= 0,
        low_energy: energy <= brain.low_energy,
        full_energy: energy >= full,
        sees_ship: sight.ship.is_some(),
        sees_similar: sight.group.is_some(),
        sees_bullet: sight.dodge.is_some(),
    };
    let state = next_state(machine, State::from_u32(state), &percept);
    b.state.set(slot, state as u32);
    if state == State::Dead {
        b.alive.set(slot, 0);
        args.deaths.count(slot, brain.kind);
        return;
    }
    if state == State::Escaping
        && brain.recover_every != 0
        && b.age.get(slot).is_multiple_of(brain.recover_every)
    {
        // Saturates at the largest birth energy allowed (i32::MAX) rather than wrapping.
        b.energy.set(slot, energy.saturating_add(1).min(full));
    }
    let want = wanted_velocity(args, brain, (slot, position), state, &sight);
    let force = (want - looker.vel) * (mass / STEER_TIME);
    b.force.set(slot, force);
}
