//! Explosions' particles on screen: each shown particle a small disc in its kind's colour,
//! faded towards the background as it ages, under every body.
//!
//! [`splat_particles`] draws them into the kernel renderer's keys (an atomic maximum, as
//! the bodies: order-free); [`write_particle_vertices`] writes the same discs for the GL
//! renderer, after the bodies' vertices in its vertex buffer.

use glam::Vec2;

use super::{
    BodyVertex, Framing, Shown, VERTEX_ALIVE, VERTEX_LEVEL_SHIFT, VERTEX_PARTICLE, cover,
    particle_key,
};
use crate::access::{Read, Unused};
use crate::data::View;
use crate::game::effects::{Particles, ParticlesAccess, fade_level};
use crate::{DevSlice, Thread, access, kernel_args};

access! {
    /// What the renderers read of the particles: where each is, how long it has left, and
    /// whose kind it shows.
    pub struct Glowing: ParticlesAccess {
        pos: Read, vel: Unused, life: Read, kind: Read, seen: Unused,
    }
}

/// The particles as the renderers read them.
pub type DrawnParticles = Particles<View, Glowing>;

/// A particle's radius in world units (times the view's scale: its radius in pixels).
pub const SIZE: f32 = 1.5;
/// Largest radius of a particle, in pixels.
pub const MAX_RADIUS_PX: f32 = 3.0;

/// Where particle `p` is drawn in `view`, if shown: its image position and radius in
/// pixels ([`SIZE`] at the view's scale, at most [`MAX_RADIUS_PX`]; the pixel under its
/// centre is drawn however small).
#[inline(always)]
pub fn disc(particles: &DrawnParticles, view: &Framing, p: u32) -> Option<(Vec2, f32)> {
    if particles.life.get(p) == 0 {
        return None;
    }
    let radius = (SIZE * view.scale).min(MAX_RADIUS_PX);
    Some((view.to_image(particles.pos.get(p)), radius))
}

/// Fade level of particle `p` (see [`fade_level`]), of at most `lifetime` steps.
#[inline(always)]
fn level(particles: &DrawnParticles, lifetime: u32, p: u32) -> u32 {
    fade_level(particles.life.get(p), lifetime, super::PARTICLE_LEVELS)
}

kernel_args! {
    /// Arguments of [`splat_particles`].
    pub struct ParticleSplatArgs {
        /// The particles (read only).
        pub particles: DrawnParticles,
        /// What the image shows (one element, from the camera).
        pub shown: DevSlice<Shown>,
        /// One key per pixel, row-major (see `splat_bodies`).
        pub keys: DevSlice<u32>,
        /// Steps a particle lives at most: how its age becomes a fade level.
        pub lifetime: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `p` draws particle `p`, if shown: every pixel whose centre lies in its disc, and
/// the pixel under its centre, keyed by [`particle_key`] (under every body).
#[inline(always)]
pub fn splat_particles(t: Thread, args: &ParticleSplatArgs) {
    let p = t.global();
    let parts = &args.particles;
    if p >= parts.len() {
        return;
    }
    let view = args.shown.get(0).view;
    let Some((centre, radius)) = disc(parts, &view, p) else {
        return;
    };
    let key = particle_key(None, parts.kind.get(p), level(parts, args.lifetime, p));
    cover(&view, centre, Vec2::splat(radius), |pixel, d, under| {
        if under || d.length_squared() <= radius * radius {
            args.keys.atomic_max(pixel, key);
        }
    });
}

kernel_args! {
    /// Arguments of [`write_particle_vertices`].
    pub struct ParticleVertexArgs {
        /// The particles (read only).
        pub particles: DrawnParticles,
        /// What the image shows (one element, from the camera).
        pub shown: DevSlice<Shown>,
        /// Output: one vertex per particle (after the bodies' in the GL vertex buffer).
        pub vertices: DevSlice<BodyVertex>,
        /// Steps a particle lives at most.
        pub lifetime: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `p` writes particle `p`'s vertex: a disc of its kind, flagged
/// [`VERTEX_PARTICLE`] with its fade level (flags 0 when it is not shown).
#[inline(always)]
pub fn write_particle_vertices(t: Thread, args: &ParticleVertexArgs) {
    let p = t.global();
    let parts = &args.particles;
    if p >= parts.len() || p >= args.vertices.len() {
        return;
    }
    let view = args.shown.get(0).view;
    let vertex = match disc(parts, &view, p) {
        Some((centre, radius)) => BodyVertex {
            centre,
            facing: Vec2::X,
            half: Vec2::splat(radius),
            radius,
            bound: radius,
            kind: parts.kind.get(p),
            flags: VERTEX_ALIVE
                | VERTEX_PARTICLE
                | (level(parts, args.lifetime, p) << VERTEX_LEVEL_SHIFT),
        },
        None => BodyVertex::default(),
    };
    args.vertices.set(p, vertex);
}
