//! Hand-made worlds for tests and scenarios: bodies brought to life, placed or pushed
//! outside a step.

use gpuwars_kernels::registry;
use gpuwars_kernels::sim::scatter::ScatterArgs;

use super::{Pipeline, Stage};
use crate::Error;
use crate::backend::Binder;
use crate::primitives::threads;

/// Hand-made worlds for tests and scenarios: bodies brought to life outside a step.
impl Pipeline<'_> {
    /// Number of free slots of each kind.
    pub fn free_counts(&self) -> Result<Vec<u32>, Error> {
        self.device.download(&self.world.state.free.count)
    }

    /// Brings `count` bodies of kind `kind` to life in its lowest free slots, at uniformly
    /// random positions with normal velocities of deviation `speed` per axis, drawn from
    /// each slot's own generator.
    pub fn scatter(&mut self, kind: usize, count: u32, speed: f32) -> Result<(), Error> {
        let world = &self.world;
        let Some(spec) = world.spec.kinds.get(kind) else {
            return Err(Error::Invalid(format!(
                "kind {kind} does not exist (the world has {})",
                world.spec.kinds.len()
            )));
        };
        if !speed.is_finite() || speed < 0.0 {
            return Err(Error::Invalid(format!(
                "scatter speed {speed} (allowed: finite, at least 0)"
            )));
        }
        let free = self.free_counts()?[kind];
        if count > free {
            return Err(Error::Invalid(format!(
                "cannot scatter {count} bodies of kind `{}`: {free} of its {} slots are free",
                spec.name, spec.capacity
            )));
        }
        let start = world.layout.ranges[kind].start;
        // SAFETY: the views go into this op only.
        let mut b = unsafe { Binder::new() };
        let args = ScatterArgs {
            bodies: world.state.bodies(&mut b),
            slots: b.view(&world.state.free.list).range(start, count),
            space: world.space,
            speed,
            energy: spec.energy,
        };
        // SAFETY: the world's buffers; `count` free slots listed from `start` (checked).
        self.device
            .launch(unsafe { threads(registry::SCATTER, count, args, b, 0) })?;
        self.run_stage(Stage::Free)
    }

    /// Brings bodies to life at exact places: `bodies` lists `(slot, position, velocity)`,
    /// and those slots come alive with their kind's energy, no force, and state 0, not yet
    /// moved.
    pub fn place(&mut self, bodies: &[(u32, glam::Vec2, glam::Vec2)]) -> Result<(), Error> {
        let snapshot = self.snapshot()?;
        let mut all = snapshot.bodies;
        for &(slot, pos, vel) in bodies {
            let Some(kind) = all.kind.get(slot as usize).copied() else {
                return Err(Error::Invalid(format!(
                    "slot {slot} does not exist (the world has {})",
                    self.world.layout.slots
                )));
            };
            let range = self.world.layout.ranges[kind as usize];
            if slot >= range.end() {
                return Err(Error::Invalid(format!(
                    "slot {slot} is padding, not a usable slot"
                )));
            }
            let s = slot as usize;
            all.pos[s] = pos;
            all.vel[s] = vel;
            all.force[s] = glam::Vec2::ZERO;
            all.dir[s] = vel.try_normalize().unwrap_or(glam::Vec2::X);
            all.energy[s] = self.world.spec.kinds[kind as usize].energy;
            all.alive[s] = 1;
            all.state[s] = 0;
            all.age[s] = 0;
            // Born here: its first path starts here (where the world keeps paths).
            if let Some(prev) = all.prev.get_mut(s) {
                *prev = pos;
            }
        }
        let (d, b) = (self.device, &mut self.world.state.bodies);
        d.write(&mut b.pos, &all.pos)?;
        d.write(&mut b.vel, &all.vel)?;
        d.write(&mut b.force, &all.force)?;
        d.write(&mut b.dir, &all.dir)?;
        d.write(&mut b.energy, &all.energy)?;
        d.write(&mut b.alive, &all.alive)?;
        d.write(&mut b.state, &all.state)?;
        d.write(&mut b.age, &all.age)?;
        d.write(&mut b.prev, &all.prev)?;
        self.run_stage(Stage::Free)
    }

    /// Sets the force on each listed slot: `(slot, force)`.
    pub fn set_forces(&mut self, forces: &[(u32, glam::Vec2)]) -> Result<(), Error> {
        let mut all = self.device.download(&self.world.state.bodies.force)?;
        for &(slot, force) in forces {
            let Some(f) = all.get_mut(slot as usize) else {
                return Err(Error::Invalid(format!("slot {slot} does not exist")));
            };
            *f = force;
        }
        self.device.write(&mut self.world.state.bodies.force, &all)
    }
}
