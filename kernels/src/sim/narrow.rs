//! The narrow phase and collision response (paper 6.2).
//!
//! Each live body tests the bodies its grid neighbourhood holds and sums its own side of every
//! contact: a push that separates the pair in proportion to the inverse masses, an impulse
//! that removes (1 + restitution) of the approaching normal velocity, and the energy the
//! other body's kind takes per step of contact. Both threads of a pair see the same contact
//! (see [`super::contact`]) and the same pre-step state, so their responses are equal and
//! opposite without either writing the other's slot.

use glam::Vec2;

use super::bodies::{Bodies, BodiesAccess, Contacts, Touched};
use super::broad::{CellIndex, Near, Sample};
use super::contact::{Swept, contact, first_overlap, tie_break};
use super::kinds::{Bound, KindInfo};
use super::space::Space;
use super::teams::Teams;
use crate::access::{Read, Write};
use crate::data::View;
use crate::warp::{Handed, Team};
use crate::{DevSlice, Thread, access, asked, kernel_args};

access! {
    /// What the narrow phase does with the bodies: their energy is lost in contacts.
    pub struct Colliding: BodiesAccess {
        pos: Read, vel: Read, force: Read, dir: Read, kind: Read, energy: Write, mass: Read,
        alive: Read, state: Read, age: Read, prev: Read, frozen: Read, rng: Read,
    }
}

kernel_args! {
    /// Arguments of [`collide`].
    pub struct CollideArgs {
        /// The bodies; energy is updated in place, the rest is read.
        pub bodies: Bodies<View, Colliding>,
        /// Kind table.
        pub kinds: DevSlice<KindInfo, Read>,
        /// Each warp's first slot and team width ([`Teams::warp_table`]; empty where every
        /// body gets one thread).
        pub warps: DevSlice<u32, Read>,
        /// How many threads each kind's bodies get (every kind's).
        pub teams: Teams,
        /// The world and its grid.
        pub space: Space,
        /// The sorted grid of this step.
        pub grid: CellIndex,
        /// Output: each slot's response (zero for free slots).
        pub contacts: Contacts,
        /// How much of the summed push is applied.
        pub relax: Relaxation,
        /// Which substep of the step this is: energy is lost, and contacts and damage are
        /// counted, in substep 0 only (contact damage is per step).
        pub substep: u32,
        /// The most bodies of one kind a body's contacts are sought among, taken evenly from
        /// a crowd beyond that, each contact found standing for the stride's worth (see
        /// [`Sample`]); 0 for all.
        pub budget: u32,
    }
}

/// How a body's pushes are combined: today's full sum by default. Every pair of a crowd is
/// resolved from the same pre-step state, so a body on a spot shared with `n` others gets
/// `n` pushes; averaging them (Jacobi relaxation) and resolving only a `fraction` of the
/// depth per step keep a crowd from exploding.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Relaxation {
    /// Fraction of the (summed or averaged) push applied per step, in `(0, 1]`.
    pub fraction: f32,
    /// Non-zero: the pushes are averaged over the body's contacts instead of summed.
    pub averaged: u32,
}

impl Relaxation {
    /// Every contact resolved fully and the pushes summed (the paper's game).
    pub const FULL: Relaxation = Relaxation {
        fraction: 1.0,
        averaged: 0,
    };

    /// The push applied for `sum`, the sum of `count` contacts' pushes.
    #[inline(always)]
    pub fn apply(&self, sum: Vec2, count: u32) -> Vec2 {
        let push = if self.averaged != 0 && count > 1 {
            sum / count as f32
        } else {
            sum
        };
        push * self.fraction
    }
}

/// `1 / mass`; zero for an immovable (infinitely heavy) body.
#[inline(always)]
pub fn inverse_mass(mass: f32) -> f32 {
    1.0 / mass
}

/// The response of body `a` to one contact with body `b`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Response {
    /// Displacement of `a`.
    pub push: Vec2,
    /// Velocity change of `a`.
    pub kick: Vec2,
}

/// Body `a`'s share of resolving a contact whose `normal` points from `a` to `b`: inverse
/// masses `inv_a`, `inv_b`, velocities `vel_a`, `vel_b`, restitution `e`.
#[inline(always)]
pub fn respond(
    normal: Vec2,
    depth: f32,
    (inv_a, inv_b): (f32, f32),
    (vel_a, vel_b): (Vec2, Vec2),
    e: f32,
) -> Response {
    let weight = inv_a + inv_b;
    if weight <= 0.0 || weight.is_nan() {
        // Two immovable bodies: nothing gives way.
        return Response::default();
    }
    let share = inv_a / weight;
    let push = normal * (-depth * share);
    // Normal component of b's velocity relative to a: negative while they approach.
    let approach = (vel_b - vel_a).dot(normal);
    let kick = if approach < 0.0 {
        let impulse = -(1.0 + e) * approach / weight;
        normal * (-impulse * inv_a)
    } else {
        Vec2::ZERO
    };
    Response { push, kick }
}

/// Each slot's team of threads (see [`Teams`]) sums the responses of the slot to every body
/// it overlaps, and its first lane writes them and applies the energy losses to that slot
/// only. Any mix of circles and rectangles.
#[inline(always)]
pub fn collide(t: Thread, args: &CollideArgs) {
    collide_bounds::<true, false, false>(t, args);
}

/// [`collide`] for worlds without rectangles: the rectangle tests are compiled out.
#[inline(always)]
pub fn collide_circles(t: Thread, args: &CollideArgs) {
    collide_bounds::<false, false, false>(t, args);
}

/// [`collide`] for worlds with swept pairs (see [`KindInfo::swept_kinds`]): a world without
/// any runs the kernels above, which have no swept code at all.
#[inline(always)]
pub fn collide_swept(t: Thread, args: &CollideArgs) {
    collide_bounds::<true, true, false>(t, args);
}

/// [`collide_circles`] for worlds with swept pairs.
#[inline(always)]
pub fn collide_circles_swept(t: Thread, args: &CollideArgs) {
    collide_bounds::<false, true, false>(t, args);
}

/// [`collide`] that also logs every contact it counts (see [`Contacts::log`]): audit runs
/// only, so that the kernels above carry no log's code.
#[inline(always)]
pub fn collide_logged(t: Thread, args: &CollideArgs) {
    collide_bounds::<true, false, true>(t, args);
}

/// [`collide_circles`] that logs its contacts.
#[inline(always)]
pub fn collide_circles_logged(t: Thread, args: &CollideArgs) {
    collide_bounds::<false, false, true>(t, args);
}

/// [`collide_swept`] that logs its contacts.
#[inline(always)]
pub fn collide_swept_logged(t: Thread, args: &CollideArgs) {
    collide_bounds::<true, true, true>(t, args);
}

/// [`collide_circles_swept`] that logs its contacts.
#[inline(always)]
pub fn collide_circles_swept_logged(t: Thread, args: &CollideArgs) {
    collide_bounds::<false, true, true>(t, args);
}

/// The bound of a kind; with `RECTS` false every kind is taken as its circle, which is exact
/// when the world has no rectangles and lets the compiler drop the rectangle tests.
#[inline(always)]
fn bound<const RECTS: bool>(info: &KindInfo) -> Bound {
    if RECTS {
        info.bound()
    } else {
        Bound::Circle(info.reach)
    }
}

/// The swept contact of bounds `a` and `b` whose offset went from `d0` to `d` over the
/// motion, if they were apart at `d0` (see [`first_overlap`]). Inlined: as a call (which the few
/// pairs close enough to have met would make) it cost `paper` 4% more on an H200 and the
/// narrow phase at a million enemies twice its time.
#[inline(always)]
fn began((a, b): (Bound, Bound), d0: Vec2, d: Vec2, tie: Vec2) -> Option<Swept> {
    match contact(a, b, d0, tie) {
        Some(_) => None,
        None => first_overlap(a, b, d0, d),
    }
}

/// One contact's share of a body's response, as the lane that found it hands it on; the
/// swept contact's time and partner are handed on only where `SWEPT` (elsewhere they are
/// constants, and the lanes exchange no more than before swept contacts existed).
#[derive(Clone, Copy, Default)]
struct Share<const SWEPT: bool> {
    push: Vec2,
    kick: Vec2,
    damage: i32,
    /// For a swept contact ([`super::contact::first_overlap`]), when it began as a fraction of the
    /// motion (below 1); 1 for a contact at the motion's end.
    time: f32,
    /// The other body's slot.
    other: u32,
}

impl<const SWEPT: bool> Share<SWEPT> {
    /// Whether this contact began during the motion rather than at its end.
    #[inline(always)]
    fn swept(&self) -> bool {
        SWEPT && self.time < 1.0
    }

    /// Whether this swept contact comes before `than` in the fixed order: time, then slot.
    #[inline(always)]
    fn before(&self, than: &Earliest) -> bool {
        self.time < than.time || (self.time == than.time && self.other < than.other)
    }
}

/// The earliest swept contact of a body so far: when it began, with whom, and its kick
/// (all a body keeps of it, so that the narrow phase holds few registers more).
#[derive(Clone, Copy)]
struct Earliest {
    time: f32,
    other: u32,
    kick: Vec2,
}

impl<const SWEPT: bool> Handed for Share<SWEPT> {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_from(self, source: u32, members: u32) -> Self {
        let (time, other) = match SWEPT {
            true => (
                self.time.shuffle_from(source, members),
                self.other.shuffle_from(source, members),
            ),
            false => (self.time, self.other),
        };
        Share {
            push: self.push.shuffle_from(source, members),
            kick: self.kick.shuffle_from(source, members),
            damage: self.damage.shuffle_from(source, members),
            time,
            other,
        }
    }
}

#[inline(always)]
fn collide_bounds<const RECTS: bool, const SWEPT: bool, const LOGGED: bool>(
    t: Thread,
    args: &CollideArgs,
) {
    if let Some((slot, team)) = args.teams.member(t, &args.warps) {
        collide_slot::<RECTS, false, SWEPT, LOGGED>(args, slot, team, |kind| args.kinds.get(kind));
    }
}

/// Slot `slot`'s share of [`collide`], by its `team`, with `info_of` giving its kind's entry:
/// the team sums the slot's responses to
/// the bodies it overlaps, and its first lane writes them and the slot's energy loss (with
/// `RECTS` false, every kind taken as its circle; with `MOVING`, the others' velocities
/// read from the grid's entries: see [`CellIndex::vel_at`]; with `SWEPT`, the swept pairs'
/// contacts found over the last motion, where the world traces paths; with `LOGGED`, every
/// contact counted in the step's first substep logged: see [`Contacts::record`]).
#[inline(always)]
pub fn collide_slot<
    const RECTS: bool,
    const MOVING: bool,
    const SWEPT: bool,
    const LOGGED: bool,
>(
    args: &CollideArgs,
    slot: u32,
    team: Team,
    info_of: impl Fn(u32) -> KindInfo,
) {
    let bodies = &args.bodies;
    let out = &args.contacts;
    if slot >= bodies.slots() {
        return;
    }
    // Asked for at once, before the branches they decide: the thread waits for memory
    // once, not once a branch (and once more for its kind's entry, unless `info_of` holds
    // it already).
    let [frozen, alive, kind] = asked([
        bodies.frozen.get(0),
        bodies.alive.get(slot),
        bodies.kind.get(slot),
    ]);
    let [pos, vel] = asked([bodies.pos.get(slot), bodies.vel.get(slot)]);
    let mass = asked(bodies.mass.get(slot));
    if frozen != 0 {
        return;
    }
    let mut push = Vec2::ZERO;
    let mut kick = Vec2::ZERO;
    let mut count = 0u32;
    let mut at_end = 0u32;
    let mut damage = 0i32;
    // The earliest swept contact that kicks the body, in the fixed order (time, then slot):
    // the body goes back to where it was then, and only that contact kicks it. A swept
    // contact with no kick (a path that closes in on the other body only by f32's rounding
    // of a tangent, while the velocities do not approach) is counted but moves nothing:
    // going back for it would put the body where it began, step after step, frozen.
    let mut first = Earliest {
        time: 1.0,
        other: 0,
        kick: Vec2::ZERO,
    };
    // Whether the world keeps each body's last path (see `Bodies::prev`).
    let traced = SWEPT && bodies.traces();
    if alive != 0 {
        let info = info_of(kind);
        let inv = inverse_mass(mass);
        // Only the kinds it collides with: the grid's buckets skip the others unread.
        let near = Near {
            pos,
            reach: Some(info.contact_reach),
            mask: info.collides_with,
        };
        // A crowd within the budget, each body taking a share that depends on its slot.
        let sample = Sample {
            budget: args.budget,
            phase: slot,
        };
        args.grid.for_each_near_in(
            team,
            &args.space,
            (near, sample),
            |other, other_kind, at, entry| {
                if other == slot {
                    return None;
                }
                let other_info = args.kinds.get(other_kind);
                let (a, b) = (bound::<RECTS>(&info), bound::<RECTS>(&other_info));
                let d = args.space.offset(pos, at);
                let tie = tie_break(slot, other);
                // A contact at the motion's end; for a swept pair apart where the motion
                // began (its start was the last step's end, whose contacts that step
                // counted), the moment it began instead, whether or not the pair still
                // overlaps at the end (it may have passed through, or past the middle).
                // A pair farther apart than their circles and the farthest both can travel
                // cannot have met: most of a query's bodies, whose paths' starts are then
                // never read (nor this body's, if none is near).
                let ended = contact(a, b, d, tie);
                let near = (info.reach + other_info.reach) + (info.travel + other_info.travel);
                let swept =
                    traced && info.swept_with(other_kind) && d.length_squared() < near * near;
                let began = match swept {
                    true => {
                        let other_prev = args.grid.prev_at::<MOVING>(entry, other, &bodies.prev);
                        let d0 = args.space.offset(bodies.prev.get(slot), other_prev);
                        began((a, b), args.space.image_near(d0, d), d, tie)
                    }
                    false => None,
                };
                let (normal, depth, time) = match (began, ended) {
                    (Some(s), _) => (s.normal, 0.0, s.time),
                    (None, Some(c)) => (c.normal, c.depth, 1.0),
                    (None, None) => return None,
                };
                // Only in the logged kernels: elsewhere the log's branch and atomic took
                // the narrow phase 8 more registers (`collide_circles` 78 -> 86).
                if LOGGED && args.substep == 0 {
                    out.record(Touched { slot, other, time });
                }
                let r = respond(
                    normal,
                    depth,
                    (inv, inverse_mass(bodies.mass.get(other))),
                    (vel, args.grid.vel_at::<MOVING>(entry, other, &bodies.vel)),
                    info.restitution.max(other_info.restitution),
                );
                Some(Share::<SWEPT> {
                    push: r.push,
                    kick: r.kick,
                    damage: other_info.damage,
                    time,
                    other,
                })
            },
            |touch, weight| {
                // A contact of a crowd's sample stands for `weight` of them (1 elsewhere,
                // where the products are the contact's own bits).
                let times = weight as f32;
                count += weight;
                damage = damage.saturating_add(touch.damage.saturating_mul(weight as i32));
                if !touch.swept() {
                    push += touch.push * times;
                    kick += touch.kick * times;
                    at_end += weight;
                } else if touch.kick != Vec2::ZERO && touch.before(&first) {
                    first = Earliest {
                        time: touch.time,
                        other: touch.other,
                        kick: touch.kick,
                    };
                }
            },
        );
    }
    if !team.leads() {
        return;
    }
    // Damage comes from contacts only, so only a live body has any.
    if damage != 0 && args.substep == 0 {
        let energy = bodies.energy.get(slot);
        bodies.energy.set(slot, energy.saturating_sub(damage));
    }
    let mut push = args.relax.apply(push, at_end);
    if SWEPT && first.time < 1.0 {
        // Back along the last motion to where the earliest swept contact began.
        push -= args.space.offset(bodies.prev.get(slot), pos) * (1.0 - first.time);
        kick += first.kick;
    }
    out.push.set(slot, push);
    out.kick.set(slot, kick);
    if args.substep == 0 {
        out.count.set(slot, count);
        out.damage.set(slot, damage);
    }
}
