//! The autopilot: a deterministic bot that writes the ship's [`Input`] on the device, for the
//! headless demo, the benchmarks and the tests. Each step it looks around the ship through
//! the step's grid, as the grid was built (the places and velocities its entries hold, before
//! the step's physics moves anything), and leaves its input for the next step, whose master
//! takes it unless the host's [`Order`](super::control::Order) says the player flies; so
//! a bot-played step needs no read-back, and, reading nothing the physics writes, the search
//! runs beside the rest of the step (the physics, free lists, effects, tally), off the chain
//! of launches that a step waits for.
//!
//! It flies away from the enemies near it (each weighted by closeness, those heading for it
//! more), keeps off the world's edges when they clamp, drifts back to the middle when nothing
//! is near, and shoots at the nearest enemy, leading it.

use glam::Vec2;

use super::control::Input;
use super::rules::Rules;
use crate::access::Read;
use crate::math;
use crate::sim::broad::{CellIndex, NO_BUCKET, Near, kind_bit};
use crate::sim::{KindInfo, Space};
use crate::{DevSlice, Thread, asked, kernel_args, warp};

kernel_args! {
    /// Arguments of [`autopilot`].
    pub struct AutopilotArgs {
        /// The bodies' velocities, read where the grid keeps none of its entries' (see
        /// [`CellIndex::vel`]); nothing before the autopilot has changed them since the grid
        /// was built then.
        pub vel: DevSlice<Vec2, Read>,
        /// Each slot's bucket in the grid (see `Grid::keys`): the ship's tells its entry.
        pub keys: DevSlice<u32, Read>,
        /// Kind table (which kinds are enemies).
        pub kinds: DevSlice<KindInfo, Read>,
        /// The world.
        pub space: Space,
        /// The step's grid (its first, in worlds with substeps).
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
    /// The nearest enemy's entry in the grid.
    entry: u32,
    /// Entries visited (before the cap).
    entries: u32,
}

impl Sighting {
    const NONE: Sighting = Sighting {
        flee: Vec2::ZERO,
        nearest: u64::MAX,
        entry: 0,
        entries: 0,
    };

    /// Both lanes' findings: commutative, as a warp reduction needs (the visiting orders in
    /// `nearest` are distinct, so one of two keys is strictly smaller).
    #[inline(always)]
    fn merge(self, other: Sighting) -> Sighting {
        let (nearest, entry) = if other.nearest < self.nearest {
            (other.nearest, other.entry)
        } else {
            (self.nearest, self.entry)
        };
        Sighting {
            flee: self.flee + other.flee,
            nearest,
            entry,
            entries: self.entries.wrapping_add(other.entries),
        }
    }
}

impl warp::Exchanged for Sighting {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        Sighting {
            flee: self.flee.shuffle_xor(mask),
            nearest: self.nearest.shuffle_xor(mask),
            entry: self.entry.shuffle_xor(mask),
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
    let (grid, rules, space) = (&args.grid, &args.rules, &args.space);
    let Some(ship) = ship_entry(args) else {
        if lane == 0 {
            args.steered.set(0, Input::default());
        }
        return;
    };
    // Entry `entry`'s velocity as the grid was built.
    let vel_of = |entry: u32| match grid.vel.is_empty() {
        true => args.vel.get(grid.slots.get(entry)),
        false => grid.vel.get(entry),
    };
    let pos = grid.pos.get(ship);
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
            let stop = start + allowed;
            let mut first = start;
            while first < stop {
                // Four entries at a time, their places and velocities asked for at once
                // (past the run's end, the run's last entry again, unused).
                let at = |k: u32| (first + k).min(stop - 1);
                let places = asked([0, 1, 2, 3].map(|k| grid.pos.get(at(k))));
                let vels = asked([0, 1, 2, 3].map(|k| vel_of(at(k))));
                for k in 0..4 {
                    let entry = first + k as u32;
                    if entry >= stop {
                        continue;
                    }
                    let d = space.offset(pos, places[k]);
                    let dist2 = d.length_squared();
                    if dist2 > sight * sight || dist2 <= 0.0 {
                        continue;
                    }
                    let (vel, dist) = (vels[k], math::sqrt(dist2));
                    // Closer enemies, and those coming at the ship, weigh more.
                    let coming = (-d.dot(vel) / dist).max(0.0) / rules.ship_speed;
                    let weight = (1.0 + coming) * (sight / dist - 1.0);
                    mine.flee -= d / dist * weight;
                    let order = before + (entry - start);
                    let key = u64::from(dist2.to_bits()) << 32 | u64::from(order);
                    if key < mine.nearest {
                        (mine.nearest, mine.entry) = (key, entry);
                    }
                }
                first += 4;
            }
            mine
        };
        let chunk_found = warp::reduce(lane, lane_sighting, Sighting::merge);
        found.flee += chunk_found.flee;
        if chunk_found.nearest < found.nearest {
            (found.nearest, found.entry) = (chunk_found.nearest, chunk_found.entry);
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
    let (move_x, move_y) = Input::move_towards(math::clamp_length_max(wish, 1.0));
    let (aim, fire) = if found.nearest != u64::MAX {
        let d = space.offset(pos, grid.pos.get(found.entry));
        let vel = vel_of(found.entry);
        let lead = math::length(d) / rules.shot_speed;
        let ship_vel = vel_of(ship);
        (Input::aim_towards(d + (vel - ship_vel) * lead), 1)
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

/// The ship's entry in the grid, if it was alive as the grid was built: the entry of its
/// slot in the bucket its key names (a bucket of the ship's kind). Before the first grid
/// (every key and bucket start zero) the bucket is empty.
#[inline(always)]
fn ship_entry(args: &AutopilotArgs) -> Option<u32> {
    let (grid, ship) = (&args.grid, args.rules.ship.start);
    let key = args.keys.get(ship);
    if key == NO_BUCKET || key / grid.cells != args.rules.ship_kind {
        return None;
    }
    let (start, end) = (grid.start.get(key), grid.start.get(key + 1));
    (start..end).find(|&entry| grid.slots.get(entry) == ship)
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
