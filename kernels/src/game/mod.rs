//! The game on top of the simulation core (paper sections 4, 5 and 7). A game step runs, in
//! order:
//!
//! 1. [`master::master`]: the master thread: the step's input (the player's, or the one the
//!    autopilot left), ship, shots, and how many enemies to spawn; then [`master::births`]
//!    brings them to life;
//! 2. the broad phase (`crate::sim::broad`);
//! 3. the narrow phase (`crate::sim::narrow`): contacts, damage (in small worlds without
//!    rectangles, with the machines and the integrator in one launch:
//!    [`ai::collide_think_integrate`]);
//! 4. [`ai::think`], once per enemy kind: perception through the grid, the finite-state
//!    machine ([`fsm`]), the steering force;
//! 5. integration; then [`autopilot::autopilot`] (the next step's input, from this step's
//!    grid) beside the free lists (`crate::sim`), which mark the deaths, then
//!    [`effects::burst_and_fade`] (a scene's explosions) beside [`master::tally`]: score,
//!    FPS meter, game over.
//!
//! [`control`] holds the two structs that cross between CPU and GPU; [`rules`] the scene's
//! constants.

pub mod ai;
pub mod autopilot;
pub mod control;
pub mod effects;
pub mod fsm;
pub mod master;
pub mod rules;

use control::{Input, Status};
use rules::{Brain, Wave};

crate::device_data! {
    /// The game's own buffers: the scene's tables, what crosses between host and device, and
    /// the spawn counters.
    pub struct GameData(kinds, waves, burst_slots): GameDataAccess {
        /// Each kind's brain (machine 0 for kinds that have none).
        brains: [Brain; kinds],
        /// The spawn schedule.
        waves: [Wave; waves],
        /// The game's state as the last step left it: score, events, game over (what the
        /// step posts to the host through the [`control::Mailbox`]).
        status: [Status; 1],
        /// Steps tallied so far, modulo 2³²: which slot of the mailbox the step under way
        /// uses.
        tallied: [u32; 1],
        /// The ship's input the step uses: the player's, or the autopilot's.
        input: [Input; 1],
        /// The autopilot's input for the next step, which the step leaves.
        steered: [Input; 1],
        /// Enemies spawned so far, per kind.
        spawned: [u32; kinds],
        /// Enemies the master ordered born this step, per kind.
        births: [u32; kinds],
        /// The speed they are born with, per kind.
        birth_speed: [f32; kinds],
        /// Each kind's free slots as the step began (see [`master::MasterArgs::free_before`]).
        free_before: [u32; kinds],
        /// Deaths of each kind in the step's physics (see [`crate::sim::Deaths::per_kind`]).
        deaths: [u32; kinds],
        /// Deaths of each slot so far where kills burst into particles (`burst_slots`: the
        /// world's slots in games with explosions, else none; see
        /// [`crate::sim::Deaths::per_slot`]).
        slot_deaths: [u32; burst_slots],
    }
}
