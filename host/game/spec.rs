//! A scene's game rules, as the host describes them: the ship and its gun, the FPS meter, the
//! spawn schedule and the enemies' behaviours. With a [`WorldSpec`] they make a [`Scene`].

pub use gpuwars_kernels::game::fsm::Machine;

use crate::sim::WorldSpec;
use crate::sim::spec::{KindSpec, MAX_SIDE, SpecError, check_range, error};

/// The ship and its gun (a scene's `[ship]` table).
#[derive(Clone, Debug, PartialEq)]
pub struct ShipSpec {
    /// Name of the ship's kind (capacity 1, no behaviour).
    pub kind: String,
    /// Speed at full stick (> 0).
    pub speed: f32,
    /// Shots per second (> 0).
    pub fire_rate: f32,
    /// Name of the shots' kind (no behaviour).
    pub shot: String,
    /// Speed of a shot (> 0).
    pub shot_speed: f32,
    /// How far the autopilot looks (> 0); the grid cells are made at least this large.
    pub autopilot_sight: f32,
}

/// The FPS meter: the paper's measure of the ship's health (a scene's `[fps]` table).
#[derive(Clone, Debug, PartialEq)]
pub struct FpsSpec {
    /// The meter at full energy (> 0).
    pub start: f32,
    /// Game over below this (0 to `start`).
    pub min: f32,
    /// FPS recovered per second (≥ 0).
    pub recovery: f32,
}

/// One entry of the spawn schedule.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveSpec {
    /// Name of the kind spawned (not the ship's nor the shots').
    pub kind: String,
    /// Seconds from the start of the first spawn (≥ 0).
    pub at: f32,
    /// Bodies per spawn (≥ 1; fewer if the kind has fewer free slots).
    pub count: u32,
    /// Seconds between spawns (> 0), if it repeats.
    pub every: Option<f32>,
    /// Number of spawns (≥ 1; exactly 1 if it does not repeat).
    pub times: u32,
    /// Standard deviation of each velocity component at birth (≥ 0).
    pub speed: f32,
}

/// Explosions: what a kill bursts into (a scene's `[effects]` table).
#[derive(Clone, Debug, PartialEq)]
pub struct EffectsSpec {
    /// Particles per kill (1 to 64).
    pub particles: u32,
    /// Seconds a particle lives at most (above 0 to 10; at least one step).
    pub lifetime: f32,
    /// Fastest speed a particle leaves the kill with (≥ 0).
    pub speed: f32,
    /// Fraction of its speed a particle still has after a second (above 0 to 1; 1: no drag).
    pub speed_kept: f32,
}

impl Default for EffectsSpec {
    fn default() -> Self {
        EffectsSpec {
            particles: 12,
            lifetime: 0.7,
            speed: 260.0,
            speed_kept: 0.1,
        }
    }
}

/// When and how enemies appear.
#[derive(Clone, Debug, PartialEq)]
pub struct SpawnSpec {
    /// Enemies appear at least this far from the ship when a few random tries allow (≥ 0).
    pub distance: f32,
    /// The schedule.
    pub waves: Vec<WaveSpec>,
}

/// How an enemy kind behaves (paper section 7): its machine and the numbers that set it
/// apart from the other kinds of the same machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Behaviour {
    /// Kamikaze, group or tricky.
    pub machine: Machine,
    /// Vision radius (> 0); the grid cells are made at least this large.
    pub vision: f32,
    /// Speed when attacking, escaping or dodging (> 0, at most the kind's `max_speed`).
    pub speed: f32,
    /// Whether it perceives and avoids shots (group and tricky only).
    pub avoid_bullets: bool,
    /// Energy at or below which a tricky enemy escapes (0 to below its birth energy).
    pub low_energy: i32,
    /// Energy a tricky enemy recovers per second while escaping (≥ 0).
    pub recovery: f32,
}

impl Behaviour {
    /// Checks the behaviour of `kind` (valid in its world); `at` names a field.
    pub(crate) fn validate(
        &self,
        kind: &KindSpec,
        at: impl Fn(&str) -> String,
    ) -> Result<(), SpecError> {
        if self.machine == Machine::None {
            return Err(error(at("machine"), "must be kamikaze, group or tricky"));
        }
        check_range(at("vision"), self.vision, (0.0, false), MAX_SIDE)?;
        check_range(
            at("speed"),
            self.speed,
            (0.0, false),
            kind.max_speed.min(MAX_SIDE),
        )?;
        if !kind.mass.is_finite() {
            return Err(error(
                at("machine"),
                "an enemy with a machine must have a finite mass (it steers by force)",
            ));
        }
        if self.low_energy < 0 || self.low_energy >= kind.energy {
            return Err(error(
                at("low_energy"),
                format!(
                    "{} is out of range (allowed 0 to {}, below the birth energy)",
                    self.low_energy,
                    kind.energy - 1
                ),
            ));
        }
        check_range(at("recovery"), self.recovery, (0.0, true), MAX_SIDE)
    }
}

/// The rules on top of the world.
#[derive(Clone, Debug, PartialEq)]
pub struct GameSpec {
    /// The ship.
    pub ship: ShipSpec,
    /// The FPS meter.
    pub fps: FpsSpec,
    /// The spawn schedule.
    pub spawn: SpawnSpec,
    /// Each kind's behaviour, indexed like the world's kinds: exactly the kinds the world
    /// marks `controlled` have one.
    pub behaviours: Vec<Option<Behaviour>>,
    /// Explosions, if the scene has any (without, the step launches nothing for them).
    pub effects: Option<EffectsSpec>,
}

/// A playable scene: the world, its rules, and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Short name (`paper`, …).
    pub name: String,
    /// One line saying what it shows.
    pub description: String,
    /// The world and its kinds of body.
    pub world: WorldSpec,
    /// The game's rules.
    pub game: GameSpec,
    /// The TOML text it was read from (replays carry it).
    pub source: String,
}
