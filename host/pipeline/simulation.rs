//! The simulation-only configuration of the pipeline: a world of bodies without a game.

use super::{Lanes, Persistent, Pipeline};
use crate::sim::WorldSpec;
use crate::{Device, Error};

/// A world on a device stepped by the pipeline's physics stages only (broad phase, narrow
/// phase, integration, free lists); a scene's game adds the rest (`crate::game::Game`).
/// It is a [`Pipeline`] without a game: its `step` queues a step, its reads wait for the
/// steps queued.
pub type Simulation<'d> = Pipeline<'d>;

impl<'d> Pipeline<'d> {
    /// An empty world (every slot free) for `spec` without a game, its generators seeded
    /// from `seed`; the step replays as a CUDA graph on the GPU.
    pub fn new(device: &'d Device, spec: &WorldSpec, seed: u32) -> Result<Self, Error> {
        Pipeline::configured(
            device,
            spec,
            seed,
            None,
            (true, Lanes::Auto, Persistent::Auto),
        )
    }
}
