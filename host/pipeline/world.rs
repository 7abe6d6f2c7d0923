//! The simulation-only configuration of the pipeline: a world of bodies without a game.

use std::ops::{Deref, DerefMut};

use super::Pipeline;
use crate::sim::{Snapshot, WorldSpec};
use crate::{Device, Error};

/// A world on a device, stepped by the pipeline's physics stages only (broad phase, narrow
/// phase, integration, free lists); a scene's game adds the rest (`crate::game::Game`).
pub struct Simulation<'d> {
    pipeline: Pipeline<'d>,
}

impl<'d> Simulation<'d> {
    /// An empty world (every slot free) for `spec`, its generators seeded from `seed`; the
    /// step replays as a CUDA graph on the GPU.
    pub fn new(device: &'d Device, spec: &WorldSpec, seed: u32) -> Result<Self, Error> {
        Ok(Simulation {
            pipeline: Pipeline::new(device, spec, seed, None, true)?,
        })
    }

    /// Advances the world by one time step and waits for it.
    pub fn step(&mut self) -> Result<(), Error> {
        self.pipeline.step()?;
        self.pipeline.device().synchronize()
    }

    /// A copy of the whole state, read back from the device.
    pub fn snapshot(&self) -> Result<Snapshot, Error> {
        self.pipeline.snapshot_at(self.pipeline.steps())
    }

    /// The state hash after the steps so far (see [`Snapshot::state_hash`]).
    pub fn state_hash(&self) -> Result<u64, Error> {
        Ok(self.snapshot()?.state_hash())
    }
}

impl<'d> Deref for Simulation<'d> {
    type Target = Pipeline<'d>;

    fn deref(&self) -> &Self::Target {
        &self.pipeline
    }
}

impl DerefMut for Simulation<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.pipeline
    }
}
