//! The stages of a step, typed: [`Stage`] names each, in step order, and makes its ops for
//! a world (one file per stage under `stages/`).

use serde::Serialize;

use super::stages;
use super::world::World;
use crate::{Op, Plan};

/// A stage of the step. [`Stage::ALL`] is the step's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    /// The master before the physics: the step's input (the player's, or the one the
    /// autopilot left), ship, shots, spawns (one warp); games.
    Master,
    /// The enemies the master ordered come alive; games of more than 2¹⁸ slots (in smaller
    /// ones, in the broad phase's first launch).
    Births,
    /// The grid: bucket counts (in games of at most 2¹⁸ slots, after the births in the same
    /// launch), their prefix sum, placement, canonical order; games, and worlds where
    /// something collides.
    Broad,
    /// The bodies move to slots in the grid's order within their kinds' ranges (gather,
    /// settle); every few steps, in worlds that renumber.
    Renumber,
    /// The autopilot's input for the next step (one warp), from the step's grid; beside
    /// the stages after it where they leave the grid as it is (no substeps) and the grid
    /// keeps its entries' velocities; games.
    Pilot,
    /// Contacts and their response; worlds where something collides.
    Narrow,
    /// Every enemy's machine, in one launch over the enemy kinds' slots; games with enemies.
    Think,
    /// Euler, the boundary rule, deaths; always.
    Integrate,
    /// Broad, narrow and integrate again for each further substep; worlds with substeps.
    Substeps,
    /// Kills burst into particles, the others move and fade, beside the stages after it;
    /// games with explosions.
    Effects,
    /// The master after the physics (one warp), beside the free lists; games.
    Tally,
    /// The free lists: flags, their prefix sum, gather; always.
    Free,
}

impl Stage {
    /// Every stage, in the order a step runs them.
    pub const ALL: [Stage; 12] = [
        Stage::Master,
        Stage::Births,
        Stage::Broad,
        Stage::Renumber,
        Stage::Pilot,
        Stage::Narrow,
        Stage::Think,
        Stage::Integrate,
        Stage::Substeps,
        Stage::Effects,
        Stage::Tally,
        Stage::Free,
    ];

    /// The stage's name, as profiles and the documentation spell it.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Master => "master",
            Stage::Births => "births",
            Stage::Broad => "broad",
            Stage::Renumber => "renumber",
            Stage::Pilot => "pilot",
            Stage::Narrow => "narrow",
            Stage::Think => "think",
            Stage::Integrate => "integrate",
            Stage::Substeps => "substeps",
            Stage::Effects => "effects",
            Stage::Tally => "tally",
            Stage::Free => "free",
        }
    }

    /// The stage's ops for `world` (none where the world has no such stage).
    pub(super) fn ops(self, world: &World) -> Vec<Op> {
        match self {
            Stage::Master => stages::master::ops(world),
            Stage::Births => stages::births::ops(world),
            Stage::Broad => stages::broad::ops(world, 0),
            Stage::Renumber => stages::renumber::ops(world),
            Stage::Pilot => stages::pilot::ops(world),
            Stage::Narrow => stages::narrow::ops(world, 0),
            Stage::Think => stages::think::ops(world),
            Stage::Integrate => stages::integrate::ops(world, 0, false),
            Stage::Substeps => stages::substeps::ops(world),
            Stage::Effects => stages::effects::ops(world),
            Stage::Tally => stages::tally::ops(world),
            Stage::Free => stages::free::ops(world, false),
        }
    }
}

/// A stage of a world's step and its plans.
pub struct StagePlan {
    /// Which stage.
    pub stage: Stage,
    /// The stage as a step that renumbers runs it, and as a world's first free lists and
    /// those after bodies are placed need it (every kind remade).
    pub(super) plan: Plan,
    /// The stage as a step that does not renumber runs it, where that differs (the
    /// integrator's marks and the free lists of the kinds that changed: see `free::ops`).
    pub(super) tracked: Option<Plan>,
}

impl StagePlan {
    /// The plan a step runs for this stage: the tracked one, unless the step renumbers.
    pub(super) fn in_step(&self, renumbers: bool) -> &Plan {
        match (&self.tracked, renumbers) {
            (Some(tracked), false) => tracked,
            _ => &self.plan,
        }
    }

    /// Kernel launches per step (of a step that does not renumber).
    pub fn launches(&self) -> usize {
        self.in_step(false).launches()
    }

    /// Bytes the stage moves per step (of a step that does not renumber), by our count.
    pub fn bytes(&self) -> u64 {
        self.in_step(false).bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::Stage;

    /// The table of stages in the pipeline's documentation lists the enum's, in order.
    #[test]
    fn documentation_lists_every_stage_in_order() {
        let doc = include_str!("mod.rs");
        let listed: Vec<&str> = doc
            .lines()
            .take_while(|l| l.starts_with("//!"))
            .filter_map(|l| l.strip_prefix("//! | `"))
            .filter_map(|l| l.split('`').next())
            .collect();
        let names: Vec<&str> = Stage::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(listed, names);
    }
}
