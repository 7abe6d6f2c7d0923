//! What every body of a kind shares: its bound, whom it collides with, what a contact does.

use glam::Vec2;

use super::bodies::{Bodies, BodiesAccess};
use crate::access::Readable;
use crate::data::View;
use crate::{DevSlice, asked};

/// [`KindInfo::shape`] of a kind bounded by a circle.
pub const SHAPE_CIRCLE: u32 = 0;
/// [`KindInfo::shape`] of a kind bounded by an axis-aligned rectangle.
pub const SHAPE_RECT: u32 = 1;

/// The narrow-phase bound of a body (paper 6.2): a circle wherever possible, else an
/// axis-aligned rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// A circle of this radius around the position.
    Circle(f32),
    /// A rectangle with these half extents, centred on the position.
    Rect(Vec2),
}

impl Bound {
    /// The bound of shape `shape` ([`SHAPE_RECT`]: a rectangle of half extents `half`; any
    /// other: a circle of radius `radius`).
    #[inline(always)]
    pub fn of_shape(shape: u32, half: Vec2, radius: f32) -> Bound {
        if shape == SHAPE_RECT {
            Bound::Rect(half)
        } else {
            Bound::Circle(radius)
        }
    }
}

/// A [`Bound`] as plain data, for device arrays.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PlainBound {
    /// Half extents of a rectangle (zero for a circle).
    pub half: Vec2,
    /// Radius of a circle (zero for a rectangle).
    pub radius: f32,
    /// [`SHAPE_CIRCLE`] or [`SHAPE_RECT`].
    pub shape: u32,
}

impl PlainBound {
    /// The bound it holds.
    #[inline(always)]
    pub fn bound(&self) -> Bound {
        Bound::of_shape(self.shape, self.half, self.radius)
    }
}

impl From<Bound> for PlainBound {
    fn from(bound: Bound) -> PlainBound {
        match bound {
            Bound::Circle(radius) => PlainBound {
                half: Vec2::ZERO,
                radius,
                shape: SHAPE_CIRCLE,
            },
            Bound::Rect(half) => PlainBound {
                half,
                radius: 0.0,
                shape: SHAPE_RECT,
            },
        }
    }
}

/// One kind of body, as the kernels see it (one entry per kind, indexed by [`Bodies::kind`]).
///
/// [`Bodies::kind`]: crate::sim::Bodies::kind
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct KindInfo {
    /// Half extents of a rectangle; `(reach, reach)` for a circle.
    pub half: Vec2,
    /// How far the body reaches from its position: a circle's radius; for a rectangle, the
    /// radius of the circle around it (the broad phase's and the sweep's bound).
    pub reach: f32,
    /// [`SHAPE_CIRCLE`] or [`SHAPE_RECT`].
    pub shape: u32,
    /// Bit `k` set: bodies of this kind collide with bodies of kind `k` (symmetric).
    pub collides_with: u32,
    /// Energy a body touching one of this kind loses per step of contact.
    pub damage: i32,
    /// Coefficient of restitution in `[0, 1]`; a pair uses the larger of its two.
    pub restitution: f32,
    /// Speed limit (`f32::INFINITY` for none).
    pub max_speed: f32,
    /// Energy at birth.
    pub energy: i32,
    /// Steps a body lives (0: no limit).
    pub lifetime: u32,
    /// Nonzero if a controller (the game's finite-state machines) drives this kind: its
    /// bodies die when the controller says so, not when their energy runs out, so that the
    /// machine's "checking energy" and "dead" states see it happen.
    pub controlled: u32,
    /// The farthest apart, along either axis, that a body of this kind and one of a kind it
    /// collides with can be and still touch: its [`KindInfo::reach`] plus the largest of
    /// theirs (0 if it collides with nothing), plus, for pairs that are swept, the farthest
    /// both can travel in a (sub)step. The narrow phase's query reaches no farther.
    pub contact_reach: f32,
    /// Bit `k` set: contacts with bodies of kind `k` are swept over each step's motion, so
    /// that neither can pass through the other between two steps (symmetric; only in worlds
    /// that trace paths, see [`crate::sim::Bodies::prev`]).
    pub swept_kinds: u32,
    /// The farthest a swept test follows a body of this kind in a (sub)step: a little more
    /// than its top speed times the (sub)step (0 where the speed is unknown). A swept pair
    /// farther apart at the motion's end than their circles and both travels cannot have
    /// met.
    pub travel: f32,
}

impl KindInfo {
    /// The narrow-phase bound of this kind's bodies.
    #[inline(always)]
    pub fn bound(&self) -> Bound {
        Bound::of_shape(self.shape, self.half, self.reach)
    }

    /// Whether this kind's bodies die as soon as their energy runs out (no controller decides).
    #[inline(always)]
    pub fn dies_at_zero_energy(&self) -> bool {
        self.controlled == 0
    }

    /// Whether a body of this kind that has lived `age` steps has reached its lifetime.
    #[inline(always)]
    pub fn expired(&self, age: u32) -> bool {
        self.lifetime != 0 && age >= self.lifetime
    }

    /// Whether contacts with bodies of kind `other` are swept.
    #[inline(always)]
    pub fn swept_with(&self, other: u32) -> bool {
        other < u32::BITS && self.swept_kinds & (1 << other) != 0
    }

    /// Whether bodies of this kind collide with bodies of kind `other`.
    #[inline(always)]
    pub fn collides_with(&self, other: u32) -> bool {
        other < u32::BITS && self.collides_with & (1 << other) != 0
    }
}

/// The slots of one kind: `capacity` slots from `start`, which is a multiple of 32 so that
/// a warp runs one kind's code (the paper's grouped warps). The slots between
/// `start + capacity` and the next range's start are padding and never live.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SlotRange {
    /// First slot.
    pub start: u32,
    /// Number of usable slots.
    pub capacity: u32,
}

impl SlotRange {
    /// One past the last usable slot.
    #[inline(always)]
    pub fn end(&self) -> u32 {
        self.start + self.capacity
    }

    /// Slots the range takes, its padding included: the capacity rounded up to a warp.
    #[inline(always)]
    pub fn span(&self) -> u32 {
        self.capacity.next_multiple_of(crate::warp::WARP)
    }

    /// One past the range's last slot, padding included (the next range's start).
    #[inline(always)]
    pub fn padded_end(&self) -> u32 {
        self.start + self.span()
    }
}

crate::device_data! {
    /// The kind tables every stage reads: one element per kind.
    pub struct KindTables(kinds): KindTablesAccess {
        /// What the bodies of each kind share.
        info: [KindInfo; kinds],
        /// Each kind's slots.
        ranges: [SlotRange; kinds],
    }
}

/// A slot's kind and the kind's entry: the world's own, which no step writes, so that a
/// launch reads them before it waits for the one before it (see
/// [`crate::exec::follow_previous_launch`]).
#[derive(Clone, Copy, Debug)]
pub struct SlotKind {
    /// The slot's kind.
    pub kind: u32,
    /// The kind's entry.
    pub info: KindInfo,
}

impl SlotKind {
    /// Slot `slot`'s kind (of `bodies`) and its entry of `kinds`.
    #[inline(always)]
    pub fn read<M: BodiesAccess<kind: Readable>>(
        bodies: &Bodies<View, M>,
        kinds: &DevSlice<KindInfo, impl Readable>,
        slot: u32,
    ) -> Self {
        let kind = bodies.kind.get(slot);
        SlotKind {
            kind,
            info: asked(kinds.get(kind)),
        }
    }
}
