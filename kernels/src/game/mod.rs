//! The game on top of the simulation core (paper sections 4, 5 and 7). A game step runs, in
//! order:
//!
//! 1. [`autopilot::autopilot`] (when the bot plays): the ship's input, from the previous
//!    step's grid;
//! 2. [`master::master`]: the master thread: ship, shots, score, FPS meter, game over, and
//!    how many enemies to spawn; then [`master::births`] brings them to life;
//! 3. the broad phase (`crate::sim::broad`);
//! 4. the narrow phase (`crate::sim::narrow`): contacts, damage;
//! 5. [`ai::think`], once per enemy kind: perception through the grid, the finite-state
//!    machine ([`fsm`]), the steering force;
//! 6. integration, [`effects::burst_and_fade`] (a scene's explosions), and the free lists
//!    (`crate::sim`).
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
