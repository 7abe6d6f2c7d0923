//! Where a frame's launches read the world from: the world itself, or a still of what the
//! renderers read of it (`gpuwars_kernels::render::still`), kept for a frame drawn beside
//! the next step (see `super::beside`).

use gpuwars_kernels::DevSlice;
use gpuwars_kernels::access::Read;
use gpuwars_kernels::game::control::Input;
use gpuwars_kernels::game::effects::Particles;
use gpuwars_kernels::render::particles::{DrawnParticles, Glowing};
use gpuwars_kernels::render::{Drawing, DrawnBodies};
use gpuwars_kernels::sim::Bodies;

use super::Pipeline;
use super::world::World;
use crate::backend::{Binder, Buffers};
use crate::sim::state::made;
use crate::{Buffer, Device, Error};

/// What a frame beside the next step reads instead of the world: the arrays of the bodies
/// and the particles that the renderers read, and the last input.
pub(super) struct Still {
    /// The bodies' arrays the renderers read, as many slots as the world's.
    pub(super) bodies: Bodies<Buffers, Drawing>,
    /// As many as the world's (none in a world without explosions), and their lifetime.
    pub(super) particles: (Particles<Buffers, Glowing>, u32),
    /// As long as the world's (empty in a world without a game).
    pub(super) input: Buffer<Input>,
}

impl Still {
    /// A still of `world`'s size, zeroed, of the arrays the renderers read only.
    pub(super) fn new(device: &Device, world: &World) -> Result<Still, Error> {
        let slots = world.layout.slots as usize;
        let game = world.game.as_ref();
        let effects = game.and_then(|g| g.effects.as_ref());
        let (count, lifetime) = effects.map_or((0, 0), |(p, burst)| (p.life.len(), burst.lifetime));
        Ok(Still {
            bodies: Bodies::build(&mut device.zeroed_used(), slots, 0)?,
            particles: (
                Particles::build(&mut device.zeroed_used(), count)?,
                lifetime,
            ),
            input: device.alloc_zeroed(game.map_or(0, |g| g.data.input.len()))?,
        })
    }
}

/// Where a frame's launches read the world from.
#[derive(Clone, Copy)]
pub(super) enum Source<'a> {
    /// The world itself: a frame drawn between two steps.
    World,
    /// A still of it: a frame drawn beside the next step.
    Still(&'a Still),
}

impl Pipeline<'_> {
    /// The bodies as the renderers read them from `source`, made by `b`.
    pub(super) fn drawn_bodies(&self, source: Source, b: &mut Binder) -> DrawnBodies {
        match source {
            Source::World => self.world.state.bodies(b),
            Source::Still(still) => made(still.bodies.convert(b)),
        }
    }

    /// The particles as the renderers read them from `source`, made by `b`, and their
    /// lifetime in steps, if the world has any.
    pub(super) fn drawn_particles(
        &self,
        source: Source,
        b: &mut Binder,
    ) -> Option<(DrawnParticles, u32)> {
        match source {
            Source::World => self.world.particles(b),
            Source::Still(Still {
                particles: (particles, lifetime),
                ..
            }) => (!particles.life.is_empty()).then(|| (made(particles.convert(b)), *lifetime)),
        }
    }

    /// The last input as the renderers read it from `source`, made by `b` (empty in a
    /// world without a game).
    pub(super) fn drawn_input(&self, source: Source, b: &mut Binder) -> DevSlice<Input, Read> {
        match source {
            Source::World => {
                (self.world.game.as_ref()).map_or(DevSlice::EMPTY, |g| b.view(&g.data.input))
            }
            Source::Still(still) => b.view(&still.input),
        }
    }
}
