//! The bodies as a structure of arrays (paper section 5), one element per slot.

use glam::Vec2;

use crate::rng::RngStreams;
use crate::{DevSlice, device_data};

device_data! {
    /// Every per-body array, one element per slot. Slots of dead bodies keep their kind, mass
    /// and generator; only [`Bodies::alive`] says whether the rest means anything.
    pub struct Bodies(slots, traced) {
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
        rng: RngStreams(slots),
    }
}

impl Bodies {
    /// Number of slots.
    #[inline(always)]
    pub fn slots(&self) -> u32 {
        self.alive.len()
    }

    /// Whether the world is frozen (see [`Bodies::frozen`]).
    #[inline(always)]
    pub fn is_frozen(&self) -> bool {
        self.frozen.get(0) != 0
    }

    /// Whether the world keeps each body's last path (see [`Bodies::prev`]).
    #[inline(always)]
    pub fn traces(&self) -> bool {
        !self.prev.is_empty()
    }

    /// Whether `slot` holds a live body.
    #[inline(always)]
    pub fn is_alive(&self, slot: u32) -> bool {
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
    /// What the narrow phase tells the integrator about each slot.
    pub struct Contacts(slots) {
        /// Displacement that separates the body from those it overlaps.
        push: [Vec2; slots],
        /// Velocity change from the collision impulses.
        kick: [Vec2; slots],
        /// Number of bodies it touched this step.
        count: [u32; slots],
        /// Energy it lost to those contacts this step.
        damage: [i32; slots],
    }
}
