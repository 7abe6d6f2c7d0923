//! The bodies as a structure of arrays (paper section 5), one element per slot.

use glam::Vec2;

use crate::access::Readable;
use crate::data::View;
use crate::rng::{RngStreams, RngStreamsAccess};
use crate::{DevSlice, device_data};

device_data! {
    /// Every per-body array, one element per slot. Slots of dead bodies keep their kind, mass
    /// and generator; only [`Bodies::alive`] says whether the rest means anything.
    pub struct Bodies(slots, traced): BodiesAccess {
        /// Position.
        pos: [Vec2; slots],
        /// Velocity.
        vel: [Vec2; slots],
        /// Force applied during the next integration (set by the AI and the master thread).
        force: [Vec2; slots],
        /// Unit direction the body faces: that of its velocity while it moves.
        dir: [Vec2; slots],
        /// Kind index (fixed per slot range).
        kind: [u32; slots],
        /// Energy; the body dies when it reaches zero.
        energy: [i32; slots],
        /// Mass; `f32::INFINITY` makes a body immovable.
        mass: [f32; slots],
        /// 1 for a live body, 0 for a free slot.
        alive: [u32; slots],
        /// State of the body's finite-state machine (0 at birth).
        state: [u32; slots],
        /// Steps lived since birth (bodies of kinds with a lifetime die when it is reached).
        age: [u32; slots],
        /// Where the body's last (sub)step moved it from, once that step's contacts had
        /// pushed it: its path since is the segment from here to [`Bodies::pos`] (where it
        /// was born, until it first moves).
        /// One element a slot in worlds that trace paths (a kind sweeps its contacts, or an
        /// audit reads them: `traced` = slots), none elsewhere.
        prev: [Vec2; traced],
        /// One element, non-zero once the world is frozen (the game is over): from then on
        /// the kernels that advance bodies leave every one as it is, so that steps the host
        /// queued before it learnt of the end change nothing.
        frozen: [u32; 1],
    } nested {
        /// The slot's random number generator.
        rng: RngStreams(slots): RngStreamsAccess,
    }
}

impl<M: BodiesAccess> Bodies<View, M> {
    /// Number of slots.
    #[inline(always)]
    pub fn slots(&self) -> u32
    where
        M::alive: Readable,
    {
        self.alive.len()
    }

    /// Whether the world is frozen (see [`Bodies::frozen`]).
    #[inline(always)]
    pub fn is_frozen(&self) -> bool
    where
        M::frozen: Readable,
    {
        self.frozen.get(0) != 0
    }

    /// Whether the world keeps each body's last path (see [`Bodies::prev`]).
    #[inline(always)]
    pub fn traces(&self) -> bool
    where
        M::prev: Readable,
    {
        !self.prev.is_empty()
    }

    /// Whether `slot` holds a live body.
    #[inline(always)]
    pub fn is_alive(&self, slot: u32) -> bool
    where
        M::alive: Readable,
    {
        self.alive.get(slot) != 0
    }
}

/// Where the step's physics counts the deaths it causes, for a game's tally and explosions,
/// which then need not wait for the free lists (empty views, counting nothing, elsewhere).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct Deaths {
    /// Each kind's deaths this step, added to atomically (their sum does not depend on the
    /// order); the tally and the free lists' rebuild read them, the next step's master sets
    /// them back to zero.
    pub per_kind: DevSlice<u32>,
    /// Each slot's deaths so far, modulo 2³², where kills burst into particles: a
    /// particle that sees its slot's count change bursts.
    pub per_slot: DevSlice<u32>,
}

impl Deaths {
    /// Counting nothing.
    pub const NONE: Deaths = Deaths {
        per_kind: DevSlice::EMPTY,
        per_slot: DevSlice::EMPTY,
    };

    /// Counts the death of the body of kind `kind` in slot `slot`: a body dies at most once
    /// a step, and only its own thread counts it in its slot.
    #[inline(always)]
    pub fn count(&self, slot: u32, kind: u32) {
        if !self.per_kind.is_empty() {
            self.per_kind.atomic_add(kind, 1);
        }
        if !self.per_slot.is_empty() {
            self.per_slot
                .set(slot, self.per_slot.get(slot).wrapping_add(1));
        }
    }
}

device_data! {
    /// What the narrow phase tells the integrator about each slot, and in audit runs every
    /// contact it counted.
    pub struct Contacts(slots, logged, logging): ContactsAccess {
        /// Displacement that separates the body from those it overlaps.
        push: [Vec2; slots],
        /// Velocity change from the collision impulses.
        kick: [Vec2; slots],
        /// Number of bodies it touched this step.
        count: [u32; slots],
        /// Energy it lost to those contacts this step.
        damage: [i32; slots],
        /// Audit runs only (`logged`, a power of two, elsewhere 0): every contact the narrow
        /// phase counted, from each side, in a ring that [`Contacts::cursor`] goes round.
        /// The order of a step's records depends on the schedule; the host sorts them.
        log: [Touched; logged],
        /// Audit runs only (`logging` = 1, elsewhere 0): the records ever written, modulo
        /// 2³²; the host reads a step's records between its values before and after.
        cursor: [u32; logging],
    }
}

/// One contact the narrow phase counted (see [`Contacts::log`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Touched {
    /// The slot that counted it.
    pub slot: u32,
    /// The other body's slot.
    pub other: u32,
    /// When it began as a fraction of the motion, in `[0, 1)`, for a swept contact; 1 for a
    /// contact found at the motion's end. (Under a contact budget, the contacts found among
    /// the sample are logged, each once: see `crate::sim::broad::Sample`.)
    pub time: f32,
}

impl Contacts {
    /// Logs `touched` where the run audits its contacts (a ring of records); does nothing
    /// where the world keeps no log (a logged kernel's launch over a world without one,
    /// which the host never makes, writes nowhere).
    #[inline(always)]
    pub fn record(&self, touched: Touched) {
        if self.cursor.is_empty() {
            return;
        }
        // The cursor's value is unique to this record whatever the order; the ring's length
        // is a power of two, so it wraps with the cursor.
        let at = self.cursor.atomic_add(0, 1);
        self.log.set(at & (self.log.len() - 1), touched);
    }
}
