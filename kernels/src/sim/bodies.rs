//! The bodies as a structure of arrays (paper section 5), one element per slot.

use glam::Vec2;

use crate::DevSlice;
use crate::rng::RngStreams;

/// Every per-body array, as one kernel argument. Slots of dead bodies keep their kind, mass
/// and generator; only [`Bodies::alive`] says whether the rest means anything.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct Bodies {
    /// Position.
    pub pos: DevSlice<Vec2>,
    /// Velocity.
    pub vel: DevSlice<Vec2>,
    /// Force applied during the next integration (set by the AI and the master thread).
    pub force: DevSlice<Vec2>,
    /// Unit direction the body faces: that of its velocity while it moves.
    pub dir: DevSlice<Vec2>,
    /// Kind index (fixed per slot range).
    pub kind: DevSlice<u32>,
    /// Energy; the body dies when it reaches zero.
    pub energy: DevSlice<i32>,
    /// Mass; `f32::INFINITY` makes a body immovable.
    pub mass: DevSlice<f32>,
    /// 1 for a live body, 0 for a free slot.
    pub alive: DevSlice<u32>,
    /// State of the body's finite-state machine (0 at birth).
    pub state: DevSlice<u32>,
    /// Steps lived since birth (bodies of kinds with a lifetime die when it is reached).
    pub age: DevSlice<u32>,
    /// The slot's random number generator.
    pub rng: RngStreams,
    /// One element, non-zero once the world is frozen (the game is over): from then on the
    /// kernels that advance bodies leave every one as it is, so that steps the host queued
    /// before it learnt of the end change nothing.
    pub frozen: DevSlice<u32>,
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

    /// Whether `slot` holds a live body.
    #[inline(always)]
    pub fn is_alive(&self, slot: u32) -> bool {
        self.alive.get(slot) != 0
    }
}

/// What the narrow phase tells the integrator about each slot.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct Contacts {
    /// Displacement that separates the body from those it overlaps.
    pub push: DevSlice<Vec2>,
    /// Velocity change from the collision impulses.
    pub kick: DevSlice<Vec2>,
    /// Number of bodies it touched this step.
    pub count: DevSlice<u32>,
    /// Energy it lost to those contacts this step.
    pub damage: DevSlice<i32>,
}
