//! The autopilot: a deterministic bot that writes the ship's [`Input`] on the device, for the
//! headless demo, the benchmarks and the tests. Each step, once the bodies have moved, it
//! looks around the ship through the step's grid (buckets of slots; positions as they are
//! now) and leaves its input for the next step, whose master takes it unless the host's
//! [`Command`](super::control::Command) says the player flies; so a bot-played step needs
//! no read-back, and the search runs beside the end of the step (free lists, effects,
//! tally), off the chain of launches that a step waits for.
//!
//! It flies away from the enemies near it (each weighted by closeness, those heading for it
//! more), keeps off the world's edges when they clamp, drifts back to the middle when nothing
//! is near, and shoots at the nearest enemy, leading it.

use glam::Vec2;

use super::control::Input;
use super::rules::Rules;
use crate::sim::broad::{CellIndex, Near, kind_bit};
use crate::sim::{Bodies, KindInfo, Space};
use crate::{DevSlice, Thread, kernel_args, warp};

kernel_args! {
    /// Arguments of [`autopilot`].
    pub struct AutopilotArgs {
        /// The bodies (read only).
        pub bodies: Bodies,
        /// Kind table (which kinds are enemies).
        pub kinds: DevSlice<KindInfo>,
        /// The world.
        pub space: Space,
        /// The step's grid.
        pub grid: CellIndex,
        /// Output: the autopilot's input for the next step (one element).
        pub steered: DevSlice<Input>,
        /// The scene's rules.
        pub rules: Rules,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Fraction of the sight within which an edge of a clamping world pushes the ship back.
pub const EDGE_MARGIN: f32 = 1.0;

/// What one lane finds among its runs of the grid, or a warp among all of its lanes'.
#[derive(Clone, Copy)]
struct Sighting {
    /// The push away from the enemies seen.
    flee: Vec2,
    /// The nearest enemy: its squared distance's bits over its visiting order (smaller is
    /// nearer, then earlier), or `u64::MAX` for none.
    nearest: u64,
    /// The nearest enemy's slot.
    slot: u32,
    /// Entries visited (before the cap).
    entries: u32,
}

impl Sighting {
    const NONE: Sighting = Sighting {
        flee: Vec2::ZERO,
        nearest: u64::MAX,
        slot: 0,
        entries: 0,
    };

    /// Both lanes' findings: commutative, as a warp reduction needs (the visiting orders in
    /// `nearest` are distinct, so one of two keys is strictly smaller).
    #[inline(always)]
    fn merge(self, other: Sighting) -> Sighting {
        let (nearest, slot) = if other.nearest < self.nearest {
            (other.nearest, other.slot)
        } else {
            (self.nearest, self.slot)
        };
        Sighting {
            flee: self.flee + other.flee,
            nearest,
            slot,
            entries: self.entries.wrapping_add(other.entries),
        }
    }
}

impl warp::Lanes for Sighting {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        Sighting {
            flee: self.flee.shuffle_xor(mask),
            nearest: self.nearest.shuffle_xor(mask),
            slot: self.slot.shuffle_xor(mask),
            entries: self.entries.shuffle_xor(mask),
        }
    }
}

/// The first warp writes the autopilot's input for the next step (no input without a live
/// ship). The warp looks around the ship together: each lane takes one run of the grid's
/// entries at a time (a kind's cells in one row of the 3×3 block), and the lanes' findings
/// are reduced in a fixed tree, so the result is the same on every backend and schedule.
#[inline(always)]
pub fn autopilot(t: Thread, args: &AutopilotArgs) {
    let lane = t.lane();
    // Only lane 0 writes.
    if t.global() >= warp::WARP || warp::is_copy_of_lane0(lane) {
        return;
    }
    let (b, rules, space) = (&args.bodies, &args.rules, &args.space);
    let ship = rules.ship.start;
    if !b.is_alive(ship) {
        if lane == 0 {
            args.steered.set(0, Input::default());
        }
        return;
    }
    let pos = b.pos.get(ship);
    let sight = rules.autopilot_sight;
    // The enemies: the kinds driven by a machine.
    let kinds = args.kinds.len();
    let enemies = warp::reduce(
        lane,
        |l| {
            let mut mask = 0u32;
            let mut k = l;
            while k < kinds {
                if !args.kinds.get(k).dies_at_zero_energy() {
                    mask |= kind_bit(k);
                }
                k += warp::WARP;
            }
            mask
        },
        |a, c| a | c,
    );
    // The grid is the step's; the enemies have moved since: their places now, so the whole
    // block (a body may have left a cell that its old place put out of reach).
    let grid = &args.grid;
    let near = grid.near_runs(
        space,
        Near {
            pos,
            reach: None,
            mask: enemies,
        },
    );
    let cap = if grid.cap == 0 { u32::MAX } else { grid.cap };
    let mut found = Sighting::NONE;
    // Runs in chunks of one a lane; `seen` entries came before the chunk.
    let (mut chunk, mut seen) = (0, 0u32);
    while chunk < near.count() && seen < cap {
        let run = |l: u32| near.get(grid, space, chunk + l);
        let lane_sighting = |l: u32| {
            let (_, start, end) = run(l);
            let before = seen.saturating_add(warp::exclusive_sum_u32(l, |j| {
                let (_, start, end) = run(j);
                end - start
            }));
            let allowed = (end - start).min(cap.saturating_sub(before));
            let mut mine = Sighting {
                entries: end - start,
                ..Sighting::NONE
            };
            for entry in start..start + allowed {
                let other = grid.slots.get(entry);
                if !b.is_alive(other) {
                    continue;
                }
                let d = space.offset(pos, b.pos.get(other));
                let dist2 = d.length_squared();
                if dist2 > sight * sight || dist2 <= 0.0 {
                    continue;
                }
                let vel = b.vel.get(other);
                let dist = libm::sqrtf(dist2);
                // Closer enemies, and those coming at the ship, weigh more.
                let coming = (-d.dot(vel) / dist).max(0.0) / rules.ship_speed;
                let weight = (1.0 + coming) * (sight / dist - 1.0);
                mine.flee -= d / dist * weight;
                let order = before + (entry - start);
                let key = u64::from(dist2.to_bits()) << 32 | u64::from(order);
                if key < mine.nearest {
                    (mine.nearest, mine.slot) = (key, other);
                }
            }
            mine
        };
        let chunk_found = warp::reduce(lane, lane_sighting, Sighting::merge);
        found.flee += chunk_found.flee;
        if chunk_found.nearest < found.nearest {
            (found.nearest, found.slot) = (chunk_found.nearest, chunk_found.slot);
        }
        seen = seen.saturating_add(chunk_found.entries);
        chunk += warp::WARP;
    }
    if lane != 0 {
        return;
    }
    let mut flee = found.flee;
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
    let (aim, fire) = if found.nearest != u64::MAX {
        let d = space.offset(pos, b.pos.get(found.slot));
        let vel = b.vel.get(found.slot);
        let lead = libm::sqrtf(d.length_squared()) / rules.shot_speed;
        (Input::aim_towards(d + (vel - b.vel.get(ship)) * lead), 1)
    } else {
        (0, 0)
    };
    args.steered.set(
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
