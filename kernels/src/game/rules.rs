//! The rules of a scene as the kernels see them: the ship and its gun, the FPS meter, the
//! spawn schedule, and each enemy kind's brain.

use crate::sim::SlotRange;

/// The game's constants (one per scene, passed by value to the master thread).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Rules {
    /// The ship's kind (capacity 1: its slot is its range's start).
    pub ship_kind: u32,
    /// The kind of the ship's shots.
    pub shot_kind: u32,
    /// The ship's slot.
    pub ship: SlotRange,
    /// The shots' slots: known to the master at once, so that its reads of the shots' free
    /// list and of their hits need not wait for the range first.
    pub shots: SlotRange,
    /// Speed of the ship at full stick.
    pub ship_speed: f32,
    /// Speed of a shot.
    pub shot_speed: f32,
    /// Steps between two shots.
    pub fire_period: u32,
    /// Steps per energy point the ship recovers (0: none).
    pub recover_every: u32,
    /// The ship's energy at birth (the FPS meter at full).
    pub ship_energy: i32,
    /// The FPS meter at full energy.
    pub fps_start: f32,
    /// Game over below this.
    pub fps_min: f32,
    /// Spawned enemies appear at least this far from the ship (when a few tries allow).
    pub spawn_distance: f32,
    /// How far the autopilot looks (at most the grid cell).
    pub autopilot_sight: f32,
}

impl Rules {
    /// The FPS meter for a ship with `energy` left.
    #[inline(always)]
    pub fn fps_meter(&self, energy: i32) -> f32 {
        self.fps_start * energy.max(0) as f32 / self.ship_energy as f32
    }
}

/// One entry of the spawn schedule: `count` bodies of `kind` at step `first`, then every
/// `every` steps up to step `last` (inclusive), as free slots allow.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Wave {
    /// Kind spawned.
    pub kind: u32,
    /// Bodies per spawn.
    pub count: u32,
    /// Step of the first spawn.
    pub first: u32,
    /// Steps between spawns (0: once).
    pub every: u32,
    /// Step of the last spawn.
    pub last: u32,
    /// Standard deviation of each velocity component at birth.
    pub speed: f32,
}

impl Wave {
    /// Whether this wave spawns at `step`.
    #[inline(always)]
    pub fn due(&self, step: u32) -> bool {
        // Without branches (`&`, `|`), so that the master reads each wave in one load.
        let since = step.wrapping_sub(self.first);
        let on_beat = since.is_multiple_of(self.every.max(1)) & ((self.every != 0) | (since == 0));
        (step >= self.first) & (step <= self.last) & on_beat
    }
}

/// What drives one enemy kind: its machine and the numbers that make the seven types.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Brain {
    /// `fsm::Machine` as u32.
    pub machine: u32,
    /// The kind these bodies are.
    pub kind: u32,
    /// Vision radius (at most the grid cell).
    pub vision: f32,
    /// Cruising speed when attacking, escaping or dodging.
    pub speed: f32,
    /// Energy at or below which a tricky enemy escapes.
    pub low_energy: i32,
    /// Steps per energy point recovered while escaping (0: none).
    pub recover_every: u32,
    /// 1: shots coming its way are perceived and avoided; 0: ignored.
    pub avoid_bullets: u32,
    /// The most bodies of one kind a look examines, a third from each row of its block,
    /// taken evenly from a crowd (see [`crate::sim::broad::Sample`]); 0 for all.
    pub sight_budget: u32,
}
