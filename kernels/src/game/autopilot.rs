//! The autopilot: a deterministic bot that writes the ship's [`Input`] on the device, for the
//! headless demo, the benchmarks and the tests. It runs in its own one-thread launch before
//! the master thread every step, and passes the player's input through when the host's
//! [`Command`] says the player flies. It looks around the ship through the previous step's
//! grid (buckets of slots; positions as they are now), so a bot-played step needs no
//! read-back.
//!
//! It flies away from the enemies near it (each weighted by closeness, those heading for it
//! more), keeps off the world's edges when they clamp, drifts back to the middle when nothing
//! is near, and shoots at the nearest enemy, leading it.

use glam::Vec2;

use super::control::{Command, Input};
use super::rules::Rules;
use crate::sim::broad::{CellIndex, kind_bit};
use crate::sim::{Bodies, KindInfo, Space};
use crate::{DevSlice, KernelArgs, Thread};

/// Arguments of [`autopilot`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct AutopilotArgs {
    /// The bodies (read only).
    pub bodies: Bodies,
    /// Kind table (which kinds are enemies).
    pub kinds: DevSlice<KindInfo>,
    /// The world.
    pub space: Space,
    /// The previous step's grid.
    pub grid: CellIndex,
    /// The host's command for this step (one element).
    pub command: DevSlice<Command>,
    /// Output: the input for this step (one element).
    pub input: DevSlice<Input>,
    /// The scene's rules.
    pub rules: Rules,
    /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
    pub reserved: u32,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for AutopilotArgs {}

/// Fraction of the sight within which an edge of a clamping world pushes the ship back.
pub const EDGE_MARGIN: f32 = 1.0;

/// Thread 0 writes the input for this step: the command's, or the autopilot's if it flies.
#[inline(always)]
pub fn autopilot(t: Thread, args: &AutopilotArgs) {
    if t.global() != 0 {
        return;
    }
    let command = args.command.get(0);
    if command.autopilot == 0 {
        args.input.set(0, command.input);
        return;
    }
    let (b, rules, space) = (&args.bodies, &args.rules, &args.space);
    let ship = rules.ship.start;
    if !b.is_alive(ship) {
        args.input.set(0, Input::default());
        return;
    }
    let pos = b.pos.get(ship);
    let sight = rules.autopilot_sight;
    let mut flee = Vec2::ZERO;
    let mut target: Option<(f32, Vec2, Vec2)> = None;
    // The enemies: the kinds driven by a machine.
    let mut enemies = 0u32;
    for k in 0..args.kinds.len() {
        if !args.kinds.get(k).dies_at_zero_energy() {
            enemies |= kind_bit(k);
        }
    }
    // The grid is the previous step's; the enemies have moved since: their places now.
    args.grid.for_each_near(space, pos, enemies, |other, _, _| {
        if !b.is_alive(other) {
            return;
        }
        let d = space.offset(pos, b.pos.get(other));
        let dist2 = d.length_squared();
        if dist2 > sight * sight || dist2 <= 0.0 {
            return;
        }
        let vel = b.vel.get(other);
        let dist = libm::sqrtf(dist2);
        // Closer enemies, and those coming at the ship, weigh more.
        let coming = (-d.dot(vel) / dist).max(0.0) / rules.ship_speed;
        let weight = (1.0 + coming) * (sight / dist - 1.0);
        flee -= d / dist * weight;
        if target.is_none_or(|(best, _, _)| dist2 < best) {
            target = Some((dist2, d, vel));
        }
    });
    if !space.wraps() {
        flee += edge_push(pos, space.size, sight * EDGE_MARGIN) * 4.0;
    }
    let wish = if flee.length_squared() > 0.0 {
        flee
    } else {
        // Nothing near: drift back to the middle, slowly, to keep room on every side.
        (space.size * 0.5 - pos) / (space.size.x.max(space.size.y))
    };
    let (move_x, move_y) = Input::move_towards(wish.clamp_length_max(1.0));
    let (aim, fire) = match target {
        Some((dist2, d, vel)) => {
            let lead = libm::sqrtf(dist2) / rules.shot_speed;
            (Input::aim_towards(d + (vel - b.vel.get(ship)) * lead), 1)
        }
        None => (0, 0),
    };
    args.input.set(
        0,
        Input {
            move_x,
            move_y,
            aim,
            fire,
        },
    );
}

/// A push away from each edge closer than `margin`, growing to 1 at the edge.
#[inline(always)]
fn edge_push(pos: Vec2, size: Vec2, margin: f32) -> Vec2 {
    let near = |x: f32, side: f32| {
        let low = (1.0 - x / margin).max(0.0);
        let high = (1.0 - (side - x) / margin).max(0.0);
        low - high
    };
    Vec2::new(near(pos.x, size.x), near(pos.y, size.y))
}
